"""A target past the +-60 deg the boards are specified for, in beams asked for out to 80 deg.

The self-calibration searched its scatterers over +-60 deg only; a target at 70 deg,
strong enough to be detected, then gave the velocity nothing across the others' narrow
spread, and its own angle missed by 0.78 deg. The search now reaches as far as the
beams asked for (``--az-deg``).
"""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np

from raysim.cli import main
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import measure_targets, write_flight
from raysim.pipeline.flight_truth import LIMITS

#: The wide one near (the element pattern leaves it within the detection's range of the
#: others), the others in a 55 deg spread.
TARGETS = [(3.0, 70.0, 0.0), (8.0, -20.0, 0.0), (9.0, 10.0, 5.0), (8.5, -45.0, -5.0)]


def test_a_target_at_70_deg_is_found_and_within_the_bounds(tmp_path):
    flight = write_flight(tmp_path / "f", frames=2, targets=TARGETS, progress=False)
    out = tmp_path / "c.zarr"
    args = flight.calibrating_command(out, "--range-m", "2.5:9.5", "--az-deg", "-80:80:0.5",
                                      "--el-deg", "-5:5:5", "--no-progress")
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(args) == 0
    ds = open_store(out)
    assert json.loads(ds.attrs["self_calibration"])["scatterers"] == len(TARGETS)
    m = measure_targets(ds, flight)                               # [target, frame, 3]
    assert np.all(m[..., 0] <= LIMITS["beam_angle_error_deg"]), m[..., 0]
    assert np.all(np.abs(m[..., 1]) <= LIMITS["beam_pseudo_velocity_bins"]), m[..., 1]
