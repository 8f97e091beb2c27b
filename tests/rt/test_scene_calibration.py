"""Self-calibration on a traced scene honours the settings' ground clutter."""

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
