"""The score of a board that resolves elevation does not depend on the elevation grid.

The IWR6843AOP's 4 x 4 grid has a pattern that is not separable in azimuth and
elevation: a beam 0.7 deg off its target's elevation has its azimuth peak up to 0.25 deg
off. A hovering platform moves the targets' apparent elevations off their nominal ones,
so on a -5:5:5 grid the true motion itself scored 0.26 deg. :func:`measure_targets`
interpolates the peak's azimuth between the two elevations about the target's own.
"""

from __future__ import annotations

import numpy as np

import raysim.pipeline.compensate as stage
from compensation import PlatformMotion
from raysim.cli import main
from raysim.pipeline.flight import measure_targets, write_flight
from raysim.platform.motion import hover_jitter

#: The flight's seed: its platform 6.6 cm from the hover point (the targets' elevations
#: move by up to 0.7 deg); targets inside the coarse grid's span.
SEED = 2
TARGETS = [(4.5, -25.0, 0.0), (5.5, 12.0, 3.0), (6.5, -8.0, -3.0), (8.8, 3.0, 2.0)]
#: The coarse and the fine elevation grid, and how closely their scores must agree [deg]
#: (the fine grid's own half step, 0.25 deg, moves the peak by about 0.1 deg).
COARSE, FINE = "-5:5:5", "-4:4:0.5"
AGREE_DEG = 0.06


def test_the_score_on_a_coarse_elevation_grid_matches_a_fine_one(tmp_path, monkeypatch):
    flight = write_flight(tmp_path / "f", frames=1, targets=TARGETS, board="IWR6843AOP",
                          seed=SEED, imu="ideal", progress=False)
    imu = stage._motions

    def truth(inp, table, rcs, **kw):       # the true motion: only the score is tested
        ms, cal, offset = imu(inp, table, rcs, **kw)
        traj = hover_jitter(SEED)
        origin = traj.position(np.array([inp.slot_times[0].ravel()[0]]))[0]
        out = []
        for m in ms:
            pos, rot = traj.pose(m.time)
            out.append(PlatformMotion(m.time, rot.as_matrix(), pos - origin,
                                      traj.velocity(m.time), traj.angular_rate(m.time),
                                      np.asarray(kw["lever_arm"], dtype=float)))
        return out, cal, offset

    monkeypatch.setattr(stage, "_motions", truth)
    scores = {}
    for grid in (COARSE, FINE):
        out = tmp_path / f"{grid}.zarr"
        assert main(flight.command(out, "--range-m", "4:9.3", "--az-deg", "-40:30:0.25",
                                   "--el-deg", grid, "--no-progress")) == 0
        scores[grid] = measure_targets(out, flight)[..., 0]
    assert np.all(np.abs(scores[COARSE] - scores[FINE]) <= AGREE_DEG), scores
