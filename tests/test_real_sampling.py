"""Real-sampled radars (``complex_sampling = false``, common on TI parts): a real IF."""

from __future__ import annotations

import json

import numpy as np
import pytest

from raysim.cli import main
from raysim.echoes.oracle import PointTarget, add_noise, noise_power, simulate_point_targets
from raysim.processing.maps import range_compress
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig
from raysim.synthesis.frame import adc_samples

#: Relative tolerance of a noise-power estimate from 2e6 samples (5 sigma of a chi^2).
NOISE_RTOL = 5 * np.sqrt(2 / 2e6)
#: Amplitude agreement of real and complex processing of the same tone: the real
#: tone's negative-frequency image leaks into the positive half through the Hann
#: sidelobes (below -50 dB at a beat of 100 bins).
AMPLITUDE_RTOL = 1e-2
#: A small frame whose real-sampled band (f_s / 2) still reaches the 15 m target.
SMALL = ["--set", "radar.num_chirps=32", "--set", "array.nx=4", "--set", "array.ny=4"]


@pytest.fixture(scope="module")
def pair():
    cfg = RadarConfig(num_chirps=16)
    arr = upa(4, 4, wavelength=cfg.wavelength)
    targets = [PointTarget.at(15.0, np.deg2rad(20.0), np.deg2rad(-5.0))]
    iq = simulate_point_targets(cfg, arr, targets)
    real = simulate_point_targets(cfg.with_(complex_sampling=False), arr, targets)
    return iq, real


def test_real_adc_is_the_in_phase_channel(pair):
    iq, real = pair
    assert real.data.dtype == np.float32 and iq.data.dtype == np.complex64
    np.testing.assert_array_equal(real.data, iq.data.real)


def test_real_range_profile_matches_the_complex_one(pair):
    """Positive beat half, doubled: the same peak bin and amplitude as the IQ receiver."""
    iq, real = pair
    rc_iq, rc_real = range_compress(iq.data), range_compress(real.data)
    n = real.config.num_samples
    assert rc_real.shape[-1] == n // 2 == real.config.range_axis().size
    p_iq = np.abs(rc_iq[0, 0, : n // 2])
    p_real = np.abs(rc_real[0, 0])
    k = int(np.argmax(p_iq))
    assert int(np.argmax(p_real)) == k
    assert p_real[k] == pytest.approx(p_iq[k], rel=AMPLITUDE_RTOL)
    np.testing.assert_allclose(rc_real[:, :, k], rc_iq[:, :, k], rtol=AMPLITUDE_RTOL)


def test_real_noise_has_half_the_power():
    """A real ADC digitises one channel: noise power k T0 F f_s / 2 per sample."""
    cfg = RadarConfig(num_chirps=64, complex_sampling=False)
    cube = np.zeros((cfg.num_chirps, 64, cfg.num_samples), dtype=np.complex64)
    add_noise(cube, cfg, seed=3)
    data = adc_samples(cube, cfg)
    measured = float(np.mean(data.astype(np.float64) ** 2))
    assert data.size > 2e6
    assert measured == pytest.approx(noise_power(cfg) / 2.0, rel=NOISE_RTOL)


def test_target_beyond_the_real_band_is_refused(capsys):
    """Real sampling halves the unambiguous range: 12.8 us chirps reach 9.6 m only."""
    code = main(["simulate", "--case", "stationary", "--json", *SMALL, "--set",
                 "radar.chirp_duration_s=12.8e-6", "--set", "radar.complex_sampling=false"])
    assert code == 2 and "range" in capsys.readouterr().err


def test_simulate_a_real_sampled_radar(capsys):
    code = main(["simulate", "--case", "stationary", "--json", *SMALL])
    iq = json.loads(capsys.readouterr().out)
    code_real = main(["simulate", "--case", "stationary", "--json", *SMALL,
                      "--set", "radar.complex_sampling=false"])
    real = json.loads(capsys.readouterr().out)
    assert code == code_real == 0
    for chain, m in real["chains"].items():
        ref = iq["chains"][chain]
        assert m["range_m"] == pytest.approx(ref["range_m"], abs=1e-3)
        assert m["angle_error_deg"] == pytest.approx(ref["angle_error_deg"], abs=1e-2)
        assert m["peak_power_db"] == pytest.approx(ref["peak_power_db"], abs=0.05)


def test_report_of_a_real_sampled_radar(tmp_path):
    out = tmp_path / "r.html"
    assert main(["report", "--case", "stationary", *SMALL, "--set",
                 "radar.complex_sampling=false", "--out", str(out)]) == 0
    assert out.stat().st_size > 0


def test_real_sampled_store_round_trip(tmp_path):
    from raysim.io import storage
    from raysim.pipeline.run import render
    from raysim.pipeline.sources import render_frames
    from raysim.scenario import scenario_from_case

    scen = scenario_from_case("stationary").with_values(
        {"radar.num_chirps": 16, "array.nx": 2, "array.ny": 2, "frames": 2,
         "radar.complex_sampling": False})
    render(scen, tmp_path / "r.zarr")
    ds = storage.open_store(tmp_path / "r.zarr")
    fr = storage.frame_from_dataset(ds, 1)
    assert fr.data.dtype == np.float32 and not fr.config.complex_sampling
    np.testing.assert_array_equal(fr.data, render_frames(scen)[1].data)
    storage.export_netcdf(ds, tmp_path / "r.nc")
    assert storage.read_netcdf(tmp_path / "r.nc")["if_data"].dtype == np.float32
    out = tmp_path / "r.html"
    assert main(["report", str(tmp_path / "r.zarr"), "--out", str(out)]) == 0
