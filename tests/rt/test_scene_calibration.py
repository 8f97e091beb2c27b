"""Self-calibration on a traced scene honours the settings' ground clutter and mounting."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.studies import scene_report as sr
from raysim.studies.scene_calibration import scene_calibration

pytestmark = pytest.mark.sionna

#: A small QUICK: few chirps, a 4 x 4 array, a sparse trace.
TINY = sr.QUICK.with_values(num_chirps=16, array_size=4, samples_per_src=2000,
                            grid_step_deg=12.0, range_window=(14.0, 20.0))


def test_clutter_field_is_traced(warm_kernels):
    """clutter="field" traces the persistent clutter field (its scatterers are reported);
    "sionna" keeps Sionna's diffuse paths, a different scene."""
    field = scene_calibration(settings=TINY, frames=2)
    assert TINY.clutter == "field"
    assert field.clutter["num_scatterers"] > 0
    sionna = scene_calibration(settings=TINY.with_values(clutter="sionna"), frames=2)
    assert sionna.clutter == {}
    assert not np.array_equal(field.leakage_true_db, sionna.leakage_true_db)
    for r in (field, sionna):
        assert np.all(np.isfinite(r.leakage_estimated_db)) and r.scatterers >= 1


def test_mover_is_refused():
    with pytest.raises(ValueError, match="mover_speed: got 5.0"):
        scene_calibration(settings=TINY.with_values(mover_speed=5.0), frames=2)


#: Height agreement of a scatterer with the ground [m]: the range resolution c / (2 B)
#: (0.15 m at 1 GHz), which ``z = r sin(el)`` inherits.
HEIGHT_TOL_M = 0.15


def test_forward_radar_finds_its_scatterers_on_the_ground_ahead(warm_kernels):
    """A forward-mounted radar (``radar.mounting_deg = "forward"``) is traced, synthesised
    and calibrated as mounted: its elevation axis is vertical, so a ground point at slant
    range ``r`` lies at elevation ``asin(h / r)`` whatever its azimuth, and every scatterer
    it finds, placed at ``r`` along ``R_BA u(az, el)``, lies on the ground ahead (+x)."""
    from raysim.echoes.ground.surface import GroundSurface
    from raysim.echoes.rt.scenes import load_scene

    base = TINY.with_values(range_window=(18.0, 30.0))
    fwd = base.with_values(scenario=base.scenario.with_values(
        {"radar.mounting_deg": "forward"}))
    r = scene_calibration(settings=fwd, frames=2)
    p = r.scatterer_positions_m
    assert p.shape == (r.scatterers, 3) and r.scatterers >= 3
    _, ground_z = GroundSurface.from_scene(load_scene("flat_reflectors")).locate(p)
    assert np.max(np.abs(p[:, 2] - ground_z)) < HEIGHT_TOL_M
    assert np.all(p[:, 0] > 0.0)
    slant = np.linalg.norm(p - np.asarray(fwd.lever_arm), axis=1)
    assert np.all((slant >= 18.0 - HEIGHT_TOL_M) & (slant <= 30.0 + HEIGHT_TOL_M))
    assert np.all(np.isfinite(r.leakage_estimated_db)) and np.all(np.isfinite(r.leakage_true_db))
