"""Runs of frames between the IMU log's gaps, estimated apart: order, clock, positions, report."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.strapdown import STANDARD_GRAVITY, PlatformMotion
from raysim.pipeline.gap_segments import GROUND_ROLE, motions_by_segment

#: The stand-in estimates each say which frames they estimated (checked where it matters).
pytestmark = pytest.mark.filterwarnings("ignore:estimated frames")

#: Chirps per frame of the stand-in motions, frame period [s] and chirp interval [s].
CHIRPS, PERIOD, DT = 4, 0.05, 1e-3
#: Yaw rate of the turning stand-in [rad/s] (the 5.7 deg/s of a slowly yawing hover).
YAW_RATE = np.deg2rad(5.7)
#: Heading carried from run to run against the record's own [rad]: a constant rate is
#: integrated exactly, so what is left is the integrator's rounding.
HEADING_TOL = 1e-9


@dataclass
class _Input:
    frames: list
    slot_times: np.ndarray
    read: object = None


def _input():
    t = 0.5 + PERIOD * np.arange(6)[:, None, None] + DT * np.arange(CHIRPS)[None, :, None]
    return _Input(frames=list(range(6)), slot_times=t)


def _log(yaw_rate=0.0):
    """A level log turning at ``yaw_rate`` about the vertical, 1 kHz, ``[sample, 7]``, on
    the radar clock (offset 0)."""
    t = np.arange(0.4, 0.9, 1e-3)
    gyro, accel = np.zeros((t.size, 3)), np.zeros((t.size, 3))
    gyro[:, 2], accel[:, 2] = yaw_rate, -STANDARD_GRAVITY
    return np.column_stack([t, gyro, accel])


def _motion(t, v, yaw_rate=0.0):
    """A run's frame as its own estimate has it: level, heading 0 at the run's start
    ``t0`` (``t`` its times on from there), body velocity ``v`` in W."""
    n = t.size
    yaw = yaw_rate * (t - t[0])
    return PlatformMotion(time=t, attitude=Rotation.from_euler("z", yaw[:, None]).as_matrix(),
                          position=(t - t[0])[:, None] * v, velocity=np.tile(v, (n, 1)),
                          angular_rate=np.tile([0.0, 0.0, yaw_rate], (n, 1)),
                          lever_arm=np.zeros(3))


def _runner(calls, track=True, yaw_rate=0.0, ground=()):
    def estimate(sub, sub_rcs, attitude, trk, clock):
        calls.append((list(sub.frames), clock))
        warnings.warn(f"estimated frames {sub.frames}", UserWarning, stacklevel=2)
        v = np.array([0.1 * (1 + sub.frames[0]), 0.0, 0.0])
        # each run's positions start at 0 and its heading at 0: the segmenting carries
        # them on
        ms, t0 = [], sub.slot_times[0, 0, 0]
        for k in range(len(sub.frames)):
            t = sub.slot_times[k, :, 0]
            m = _motion(t, v, yaw_rate)
            rz = Rotation.from_euler("z", yaw_rate * (t[0] - t0)).as_matrix()
            ms.append(m if not ms else PlatformMotion(
                m.time, rz @ m.attitude, m.position + ms[-1].position[-1]
                + v * (m.time[0] - ms[-1].time[-1]), m.velocity, m.angular_rate, m.lever_arm))
        sub_rcs.extend(f"rc{k}" for k in sub.frames)
        own = 1e-3 * (1 + sub.frames[0])
        report = {"time_offset_s": own, "warnings": ["w", f"w{len(calls)}"]}
        if sub.frames[0] in ground:
            report["ground_plane"] = {"role": GROUND_ROLE}
        return ms, report, own if clock is None else clock

    def attitude_of(sub, first, clock):
        return (0.0, 0.0, 0.0), ("track" if track else None)
    return estimate, attitude_of


def test_the_largest_run_outside_a_gap_first_and_its_clock_for_the_others():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls)
    segments = [([0], False), ([1, 2], True), ([3, 4, 5], False)]
    motions, report, offset = motions_by_segment(_input(), segments, estimate, attitude_of,
                                                 _log(), rcs, notes)
    assert calls == [([3, 4, 5], None), ([0], 4e-3), ([1, 2], 4e-3)]
    assert offset == 4e-3 and report["time_offset_s"] == 4e-3
    assert rcs == [f"rc{k}" for k in range(6)] and len(motions) == 6
    assert [p["frames"] for p in report["segments"]] == [[0], [1, 2], [3, 4, 5]]
    assert [p["in_gap"] for p in report["segments"]] == [False, True, False]
    assert report["warnings"] == ["w", "w2", "w3", "w1"]     # runs in frame order, each once
    assert "estimated in 3 parts" in notes[0] and "frames 0, 1-2 (in the gap), 3-5" in notes[0]
    # positions run on from run to run: each run's first chirp where the last run's
    # motion, extrapolated at its velocity, puts it
    for a, b in zip(motions[:-1], motions[1:], strict=True):
        expect = a.position[-1] + a.velocity[-1] * (b.time[0] - a.time[-1])
        np.testing.assert_allclose(b.position[0], expect, atol=1e-12)


def test_without_an_attitude_each_run_takes_the_heading_the_log_carried_to_it():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls, track=False, yaw_rate=YAW_RATE, ground=(0, 1, 3))
    segments = [([0], False), ([1, 2], True), ([3, 4, 5], False)]
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        motions, report, _ = motions_by_segment(_input(), segments, estimate, attitude_of,
                                                _log(YAW_RATE), rcs, notes)
    assert [c[0] for c in calls] == [[3, 4, 5], [0], [1, 2]]
    assert [str(w.message) for w in said] == [f"estimated frames {f}" for f in
                                              ([3, 4, 5], [0], [1, 2])]   # each run's, once
    t0 = motions[0].time[0]
    for k, m in enumerate(motions):   # every chirp at the heading turned since the start
        yaw = Rotation.from_matrix(m.attitude).as_euler("ZYX")[:, 0]
        np.testing.assert_allclose(yaw, YAW_RATE * (m.time - t0), rtol=0, atol=HEADING_TOL)
        # the velocity turned with it: each run's along the heading at the run's start
        start = motions[{0: 0, 1: 1, 2: 1}.get(k, 3)].time[0]
        assert abs(np.arctan2(m.velocity[0, 1], m.velocity[0, 0])
                   - YAW_RATE * (start - t0)) <= HEADING_TOL
    assert "restarting level, roll and pitch from the ground, its heading carried on" \
        in notes[0] and len(report["segments"]) == 3
    # without the turn, run 3-5 would start at heading 0: 0.15 s of 5.7 deg/s off
    assert Rotation.from_matrix(motions[3].attitude[0]).as_euler("ZYX")[0] > 0.8 * np.deg2rad(
        5.7 * 0.15)


def test_without_an_attitude_or_the_ground_after_a_gap_the_record_is_estimated_whole():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls, track=False, ground=(0,))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        motions, report, _ = motions_by_segment(
            _input(), [([0, 1], False), ([2, 3, 4, 5], False)], estimate, attitude_of, _log(),
            rcs, notes)
    assert calls[-1] == ([0, 1, 2, 3, 4, 5], None) and "segments" not in report
    # the runs given up say nothing: the one estimate over the record speaks for it
    assert [str(w.message) for w in said] == ["estimated frames [0, 1, 2, 3, 4, 5]"]
    assert "holds no attitude and the ground gave no roll and pitch to restart from at " \
        "frame 2" in notes[0]
    assert "(--frames 0:2 and --frames 2:6 compensate the frames outside the gaps apart" \
        in notes[0]
    assert len(motions) == 6 and rcs == [f"rc{k}" for k in range(6)]


def test_one_run_is_the_record_itself():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls)
    motions_by_segment(_input(), [(list(range(6)), False)], estimate, attitude_of, _log(), rcs,
                       notes)
    assert calls == [([0, 1, 2, 3, 4, 5], None)] and notes == []


def test_a_run_that_cannot_be_estimated_alone_leaves_the_record_whole():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls)

    def picky(sub, sub_rcs, attitude, trk, clock):
        if len(sub.frames) == 1:
            raise ValueError("scatterers: none given and none detected")
        return estimate(sub, sub_rcs, attitude, trk, clock)
    motions, report, _ = motions_by_segment(
        _input(), [(list(range(5)), False), ([5], False)], picky, attitude_of, _log(), rcs,
        notes)
    assert [c[0] for c in calls] == [[0, 1, 2, 3, 4], [0, 1, 2, 3, 4, 5]]
    assert len(motions) == 6 and rcs == [f"rc{k}" for k in range(6)]
    assert "frame 5 between its gaps could not be estimated alone (scatterers: none" \
        in notes[0] and "segments" not in report
