"""A logger gap inside the capture: the frames on each side estimated apart, those in it named.

A 1 kHz consumer-MEMS flight whose log drops 77 ms over two of its six frames
(``gaps_in_capture``; the command carries ``--max-gap``), five targets, the flight
controller's attitude in the log. One estimate over the record fitted the frames
inside the gap to an interpolated motion and carried the gap into every frame
after it: up to 6.1 deg of angle error before the gap and 7.4 deg after it. Each
run between gaps is now its own record, with one clock and positions carried
from run to run (:mod:`raysim.pipeline.gap_segments`): 0.099 deg before, 0.091
after. A log without the controller's attitude, the ground in view (the parking
lot's clutter): each run restarts level with roll and pitch from the ground and
the heading carried on by the log's rates; estimated whole the frames scored
0.29-0.49 deg before the gap and 0.88 deg after it, now 0.055-0.063 and 0.089.
"""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np

from raysim.cli import main
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import write_flight
from raysim.pipeline.flight_truth import score_flight

#: Bounds of the frames outside the gap: angle [deg], pseudo-velocity [bin], leakage [dB].
ANGLE_DEG, PSEUDO_VELOCITY_BINS, LEAKAGE_DB = 0.2, 0.05, -35.0


def test_frames_on_each_side_of_a_gap_are_compensated_apart(tmp_path):
    flight = write_flight(tmp_path / "f", targets="default5", seed=119, frames=6,
                          time_offset=-0.0041, clock_drift_ppm=30.0, board="IWR6843ISK",
                          log_gaps=2, gaps_in_capture=True)
    out = tmp_path / "c.zarr"
    err, said = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(said), contextlib.redirect_stderr(err):
        assert main(flight.calibrating_command(out, "--range-m", "4.0:9.3", "--el-deg",
                                               "-6:6:1", "--autofocus", "off",
                                               attitude="log")) == 0
    gap = [ln for ln in err.getvalue().splitlines() if "lie in a filled gap" in ln]
    assert len(gap) == 1, err.getvalue()
    inside = [int(k) for k in gap[0].split("frame(s) ")[1].split(" lie")[0].split(", ")]
    assert 0 < min(inside) and max(inside) < 5           # frames on both sides of it
    scores = np.asarray(score_flight(tmp_path / "f", out)["targets"])   # [target, frame, 3]
    outside = [k for k in range(6) if k not in inside]
    worst = np.abs(scores[:, outside]).max(axis=(0, 1))
    assert worst[0] <= ANGLE_DEG and worst[1] <= PSEUDO_VELOCITY_BINS, worst
    assert scores[:, outside, 2].max() <= LEAKAGE_DB, scores[:, outside, 2]
    parts = json.loads(open_store(out).attrs["self_calibration"])["segments"]
    assert [p["frames"] for p in parts if p["in_gap"]] == [inside]
    assert sorted(k for p in parts for k in p["frames"]) == list(range(6))
    assert "estimated in 3 parts split at the log's filled gaps" in err.getvalue()


def test_without_the_controllers_attitude_each_side_restarts_from_the_ground(tmp_path):
    flight = write_flight(tmp_path / "f", targets="default5", seed=127, frames=6,
                          time_offset=-0.00412, clock_drift_ppm=30.0, board="IWR6843ISK",
                          log_gaps=2, gaps_in_capture=True, attitude=False,
                          clutter_scene="parking_lot", clutter_max_scatterers=60)
    out = tmp_path / "c.zarr"
    err, said = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(said), contextlib.redirect_stderr(err):
        assert main(flight.calibrating_command(out, "--range-m", "4.0:9.3", "--el-deg",
                                               "-6:6:1", attitude="log")) == 0
    assert "each from its own frames and restarting level, roll and pitch from the ground, " \
        "its heading carried on from the part before" in err.getvalue() + said.getvalue()
    parts = json.loads(open_store(out).attrs["self_calibration"])["segments"]
    inside = [k for p in parts if p["in_gap"] for k in p["frames"]]
    outside = [k for k in range(6) if k not in inside]
    assert inside and min(inside) > 0 and max(inside) < 5
    scores = np.asarray(score_flight(tmp_path / "f", out)["targets"])   # [target, frame, 3]
    worst = np.abs(scores[:, outside]).max(axis=(0, 1))
    assert worst[0] <= ANGLE_DEG and worst[1] <= PSEUDO_VELOCITY_BINS, worst
    assert scores[:, outside, 2].max() <= LEAKAGE_DB, scores[:, outside, 2]
