"""RadarConfig: derived quantities against their closed forms, and validation."""

import numpy as np
import pytest

from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

REL = 1e-12


def test_paper_defaults_closed_forms(paper_radar):
    r = paper_radar
    assert r.num_samples == 600
    assert r.chirp_rate == pytest.approx(1e9 / 60e-6, rel=REL)
    # R = c f_b / (2 mu): one FFT bin f_s/K is c / (2 B)
    assert r.range_resolution == pytest.approx(SPEED_OF_LIGHT / (2 * 1e9), rel=REL)
    assert r.max_range == pytest.approx(SPEED_OF_LIGHT * 10e6 / (2 * r.chirp_rate), rel=REL)
    assert r.doppler_resolution == pytest.approx(1 / (256 * 60e-6), rel=REL)
    lam_c = SPEED_OF_LIGHT / (77e9 + 0.5e9)
    assert r.velocity_resolution == pytest.approx(lam_c / (2 * 256 * 60e-6), rel=REL)
    assert r.range_axis()[1] == pytest.approx(r.range_resolution, rel=REL)
    v = r.velocity_axis()
    assert v.size == 256 and v[128] == 0.0
    assert np.diff(v) == pytest.approx(np.full(255, r.velocity_resolution))


def test_real_sampling_halves_band():
    r = RadarConfig(complex_sampling=False)
    assert r.max_range == pytest.approx(RadarConfig().max_range / 2)
    assert r.range_axis().size == 300


def test_tdm_slow_time_period():
    r = RadarConfig(num_tx_slots=3, idle_time=10e-6)
    assert r.slot_interval == pytest.approx(70e-6)
    assert r.chirp_interval == pytest.approx(210e-6)


@pytest.mark.parametrize(
    "kwargs, words",
    [
        ({"sample_rate": 0.0}, "sample_rate"),
        ({"bandwidth": -1e9}, "bandwidth"),
        ({"num_chirps": 0}, "num_chirps"),
        ({"idle_time": -1e-6}, "idle_time"),
        ({"chirp_duration": float("nan")}, "chirp_duration"),
        ({"frame_period": 1e-3}, "frame_period"),
    ],
)
def test_bad_config_names_the_parameter(kwargs, words):
    with pytest.raises(ValueError, match=words):
        RadarConfig(**kwargs)


def test_target_beyond_beat_band_is_refused(paper_radar):
    with pytest.raises(ValueError, match="outside the unambiguous range window"):
        paper_radar.check_range(120.0)
