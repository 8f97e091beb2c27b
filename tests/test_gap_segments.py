"""Runs of frames between the IMU log's gaps, estimated apart: order, clock, positions, report."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from compensation.strapdown import PlatformMotion
from raysim.pipeline.gap_segments import motions_by_segment

#: Chirps per frame of the stand-in motions, frame period [s] and chirp interval [s].
CHIRPS, PERIOD, DT = 4, 0.05, 1e-3


@dataclass
class _Input:
    frames: list
    slot_times: np.ndarray
    read: object = None


def _input():
    t = 0.5 + PERIOD * np.arange(6)[:, None, None] + DT * np.arange(CHIRPS)[None, :, None]
    return _Input(frames=list(range(6)), slot_times=t)


def _motion(t, v):
    n = t.size
    return PlatformMotion(time=t, attitude=np.repeat(np.eye(3)[None], n, 0),
                          position=(t - t[0])[:, None] * v, velocity=np.tile(v, (n, 1)),
                          angular_rate=np.zeros((n, 3)), lever_arm=np.zeros(3))


def _runner(calls, track=True):
    def estimate(sub, sub_rcs, attitude, trk, clock):
        calls.append((list(sub.frames), clock))
        v = np.array([0.1 * (1 + sub.frames[0]), 0.0, 0.0])
        # each run's positions start at 0: the segmenting carries them on
        ms = []
        for k in range(len(sub.frames)):
            m = _motion(sub.slot_times[k, :, 0], v)
            ms.append(m if not ms else PlatformMotion(
                m.time, m.attitude, m.position + ms[-1].position[-1]
                + v * (m.time[0] - ms[-1].time[-1]), m.velocity, m.angular_rate, m.lever_arm))
        sub_rcs.extend(f"rc{k}" for k in sub.frames)
        own = 1e-3 * (1 + sub.frames[0])
        report = {"time_offset_s": own, "warnings": ["w", f"w{len(calls)}"]}
        return ms, report, own if clock is None else clock

    def attitude_of(sub, first, clock):
        return (0.0, 0.0, 0.0), ("track" if track else None)
    return estimate, attitude_of


def test_the_largest_run_outside_a_gap_first_and_its_clock_for_the_others():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls)
    segments = [([0], False), ([1, 2], True), ([3, 4, 5], False)]
    motions, report, offset = motions_by_segment(_input(), segments, estimate, attitude_of,
                                                 rcs, notes)
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


def test_without_an_attitude_in_the_log_the_record_is_estimated_whole():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls, track=False)
    motions, report, _ = motions_by_segment(
        _input(), [([0, 1], False), ([2, 3, 4, 5], False)], estimate, attitude_of, rcs, notes)
    assert calls == [([0, 1, 2, 3, 4, 5], None)] and "segments" not in report
    assert "holds no attitude to restart the estimate" in notes[0]
    assert "(--frames 0:2 and --frames 2:6 compensate the frames outside the gaps apart" \
        in notes[0]


def test_one_run_is_the_record_itself():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls)
    motions_by_segment(_input(), [(list(range(6)), False)], estimate, attitude_of, rcs, notes)
    assert calls == [([0, 1, 2, 3, 4, 5], None)] and notes == []


def test_a_run_that_cannot_be_estimated_alone_leaves_the_record_whole():
    calls, rcs, notes = [], [], []
    estimate, attitude_of = _runner(calls)

    def picky(sub, sub_rcs, attitude, trk, clock):
        if len(sub.frames) == 1:
            raise ValueError("scatterers: none given and none detected")
        return estimate(sub, sub_rcs, attitude, trk, clock)
    motions, report, _ = motions_by_segment(
        _input(), [(list(range(5)), False), ([5], False)], picky, attitude_of, rcs, notes)
    assert [c[0] for c in calls] == [[0, 1, 2, 3, 4], [0, 1, 2, 3, 4, 5]]
    assert len(motions) == 6 and rcs == [f"rc{k}" for k in range(6)]
    assert "frame 5 between its gaps could not be estimated alone (scatterers: none" \
        in notes[0] and "segments" not in report
