"""Scene measurement (raysim.measure.scene, raysim.measure.ridge): definitions and bad input."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.measure.ridge import RIDGE_HALF_WIDTH_BINS, ridge_bins, ridge_leakage_db
from raysim.measure.scene import (
    SCENE_MAPS,
    SCENE_METRICS,
    angle_grid,
    channel_taper,
    measure_scene,
    range_compressed,
    scene_metric,
)
from raysim.vocabulary import MAPS, REFERENCE, metric_unit


def test_ridge_leakage_closed_form():
    """A quarter of the power off the ridge is -6.02 dB; all on the ridge is far below."""
    rd = np.zeros((3, 16))
    on = ridge_bins(16)
    assert (on.start, on.stop) == (8 - RIDGE_HALF_WIDTH_BINS, 8 + RIDGE_HALF_WIDTH_BINS + 1)
    rd[:, 8] = 3.0
    assert ridge_leakage_db(rd) < -1000
    rd[:, 2] = 1.0
    assert ridge_leakage_db(rd) == pytest.approx(10 * np.log10(0.25))
    with pytest.raises(ValueError, match="non-negative"):
        ridge_leakage_db(-rd)
    with pytest.raises(ValueError, match="no power"):
        ridge_leakage_db(np.zeros((2, 8)))
    with pytest.raises(ValueError, match="num_doppler"):
        ridge_bins(3)


def test_scene_metric_names_are_vocabulary_names():
    """Every scene metric has a unit and is named apart from the point metrics."""
    for m in SCENE_MAPS:
        assert m in MAPS
        assert scene_metric(m) == SCENE_METRICS[m] == f"scene_entropy_{m}_nats"
        assert metric_unit(scene_metric(m)) == "nats"
    assert metric_unit("ridge_leakage_db") == "dB"
    with pytest.raises(ValueError, match="'re'"):
        scene_metric("re")
    with pytest.raises(ValueError, match="entropy_ra_nats"):
        metric_unit("entropy_ra_nats")              # the old scene name is gone


def test_grid_and_taper():
    az, el = angle_grid(60.0, 6.0)
    assert az.size == 21 and np.allclose(np.rad2deg(az[[0, -1]]), [-60, 60])
    with pytest.raises(ValueError, match="grid_step_deg"):
        angle_grid(60.0, 0.0)
    from raysim.radar.arrays import ti_3tx4rx, upa

    w = channel_taper(upa(6, 4, wavelength=3.9e-3))
    assert w.shape == (24,) and w.mean() == pytest.approx(1.0)
    assert np.all(channel_taper(ti_3tx4rx(3.9e-3)) == 1.0)        # no grid: uniform
    with pytest.raises(ValueError, match="spatial_window"):
        channel_taper(upa(4, 4, wavelength=3.9e-3), "hamming")
    with pytest.raises(ValueError, match="taper"):
        range_compressed(np.zeros((4, 3, 8), np.complex64), np.ones(5))


def test_a_still_point_target_stays_on_the_ridge():
    """The oracle's static target, stationary radar: maps of the vocabulary, all RD power
    on the zero-Doppler ridge, the target detected where it is; a compensated chain
    without motion is refused."""
    from raysim.echoes.oracle import PointTarget, simulate_point_targets
    from raysim.platform.motion import stationary
    from raysim.radar.arrays import upa
    from raysim.radar.config import RadarConfig

    cfg = RadarConfig(num_chirps=16)
    arr = upa(4, 4, wavelength=cfg.wavelength)
    target = PointTarget.at(15.0, np.deg2rad(12.0), 0.0)
    frame = simulate_point_targets(cfg, arr, [target], stationary())
    rc = range_compressed(frame.data, channel_taper(arr))
    az, el = angle_grid(60.0, 6.0)
    kw = dict(config=cfg, array=arr, azimuth=az, elevation=el, range_window=(12.0, 18.0),
              lever_arm=(0.0, 0.0, 0.0))
    res = measure_scene(REFERENCE, rc, None, **kw)
    assert res.key == REFERENCE
    assert {m: res.maps[m].dims for m in SCENE_MAPS} == {m: MAPS[m] for m in SCENE_MAPS}
    assert res.ridge_leakage_db < -100
    assert set(res.metrics()) == set(SCENE_METRICS.values()) | {"ridge_leakage_db"}
    best = res.detections[0]
    assert best["range_m"] == pytest.approx(15.0, abs=cfg.range_resolution)
    assert best["az_deg"] == pytest.approx(12.0, abs=6.0)
    with pytest.raises(ValueError, match="needs motion"):
        measure_scene("exact", rc, None, **kw)
    with pytest.raises(ValueError, match="range_window"):
        measure_scene("none", rc, None, **dict(kw, range_window=(200.0, 300.0)))
