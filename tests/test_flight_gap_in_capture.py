"""A logger gap inside the capture: the frames on each side estimated apart, those in it named.

A 1 kHz consumer-MEMS flight whose log drops 77 ms over two of its six frames
(``gaps_in_capture``; the command carries ``--max-gap``), five targets, the flight
controller's attitude in the log. One estimate over the record fitted the frames
inside the gap to an interpolated motion and carried the gap into every frame
after it: up to 6.1 deg of angle error before the gap and 7.4 deg after it. Each
run between gaps is now its own record, with one clock and positions carried
from run to run (:mod:`raysim.pipeline.gap_segments`): 0.099 deg before, 0.091
after.
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
