"""A record whose IMU log has filled gaps among its frames, estimated run by run.

Across a filled gap the log's motion is interpolated, not measured
(:func:`compensation.ingestion.gap_segments`): one estimate over the whole
record fits the frames inside the gap to a motion the platform did not make and
carries what the gap left unmeasured into every frame after it. On a 1 kHz
flight with a 95 ms logger gap over frames 3 and 4 of six, one estimate left
0.26-0.49 deg of angle error in frames 0-2, before the gap, and 0.8 deg after
it; frames 0-2 and frame 5 compensated apart (``--frames``) gave 0.063 and
0.041 deg. So each run between gaps is estimated as a record of its own, from
its frames and the attitude at its first ramp: the log's, where it holds one;
else level, roll and pitch from the ground, and the heading carried on from the
run before by the log's rates (:func:`heading_step`; where a later run's ground
gives no roll and pitch the record stays whole). The frames inside a gap form
their own run, their motion still interpolated (warned). The clock is one: the
largest run outside a gap is estimated first and its offset given to the others
(a single frame after the gap found its own 0.1 ms off, 1.5 of its spreads).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

__all__ = ["body_turn", "frame_subset", "heading_step", "motions_by_segment", "turned",
           "GROUND_ROLE"]

#: The report's ``ground_plane.role`` where the ground gave a run its roll and pitch.
GROUND_ROLE = "initial roll and pitch"


def frame_subset(inp, idx):
    """The compensate input restricted to its selected frames ``idx`` (indices, in order)."""
    idx = [int(i) for i in idx]
    return replace(inp, frames=[inp.frames[i] for i in idx], slot_times=inp.slot_times[idx],
                   read=lambda k: inp.read(idx[k]))


def _part(inp, idx, in_gap: bool, report: dict) -> dict:
    """One run's figures for the report's ``segments``."""
    keys = ("time_offset_s", "time_offset_sigma_s", "initial_velocity_mps",
            "initial_velocity_sigma_mps")
    return {"frames": [int(inp.frames[i]) for i in idx], "in_gap": bool(in_gap),
            **{k: report.get(k) for k in keys}}


def body_turn(imu, t0: float, t1: float, offset: float) -> np.ndarray:
    """The body's rotation ``R_WB(t0)^T R_WB(t1)`` ``[3, 3]`` from radar-clock time ``t0``
    to ``t1`` [s] by the gyro of ``imu`` (``[sample, 7]``, :func:`motions_by_segment`)
    read at clock offset ``offset`` [s]."""
    from compensation.strapdown import integrate_imu

    att = integrate_imu(imu[:, 0], imu[:, 1:4], imu[:, 4:7], [t0, t1],
                        time_offset=offset).attitude
    return att[0].T @ att[1]


def heading_step(end, start, turn) -> float:
    """Turn [rad] about W's vertical that gives ``start``'s first chirp the heading of
    ``end``'s last chirp carried on by the log's rates between the two
    (:class:`compensation.strapdown.PlatformMotion` both; ``turn`` the body's rotation
    ``[3, 3]`` over that interval). Across a filled gap those rates are interpolated:
    the heading is the one an estimate over the whole record would carry, and what the
    platform turned inside the gap beyond them stays unknown (warned with the gap)."""
    from compensation.geometry import euler_zyx

    d = euler_zyx(end.attitude[-1] @ turn)[0] - euler_zyx(start.attitude[0])[0]
    return float(np.angle(np.exp(1j * d)))


def turned(motions, angle: float) -> list:
    """``motions`` (PlatformMotion) turned by ``angle`` [rad] about W's vertical (down):
    attitude, position and velocity. A hover estimate that starts level is the same
    estimate at any heading (gravity and the ground are vertical), so this is its start
    at that heading."""
    from compensation.geometry import yaw_matrices

    rz = yaw_matrices(angle)[0]
    return [replace(m, attitude=rz @ m.attitude, position=m.position @ rz.T,
                    velocity=m.velocity @ rz.T) for m in motions]


def motions_by_segment(inp, segments, estimate, attitude_of, imu, rcs: list, notes: list):
    """Per-frame motions, the report and the offset applied, each run estimated apart.

    Parameters
    ----------
    inp : raysim.io.compensate_io.CompensateInput
    segments : list of (list of int, bool)
        Runs of frame indices and whether each lies in a gap
        (:func:`raysim.pipeline.imu_inputs.imu_window`).
    estimate : callable
        ``estimate(inp, rcs, attitude, track, offset) -> (motions, report, offset)``: one
        record's self-calibrated motion (``rcs`` receives its range-compressed frames;
        ``offset`` [s] the clock offset to use, None: the caller's).
    attitude_of : callable
        ``attitude_of(inp, first, offset) -> (attitude, track)``: the initial attitude of
        a run (``first``: the record's first run, where a given attitude applies; the log
        read at ``offset`` [s], None: the caller's).
    imu : ndarray, shape ``[sample, 7]``
        The log over the window used, gaps filled: time [s, IMU clock], gyro [rad/s],
        specific force [m/s^2]; its rates carry the heading from run to run where it
        holds no attitude (:func:`body_turn`).
    rcs : list
        Receives the range-compressed frames of every run, in frame order.
    notes : list
        Receives a note naming the runs.

    Returns
    -------
    (list of PlatformMotion, dict, float)
        The motions of every frame in order; the report of the largest run outside a
        gap (estimated first; the other runs take its clock offset: one clock) with
        ``segments`` (each run's frames, clock offset and initial velocity) and every
        run's warnings; that run's offset [s].
    """
    def whole(why: str):
        apart = " and ".join(f"--frames {inp.frames[i[0]]}:{inp.frames[i[-1]] + 1}"
                             for i, gap in segments if not gap)
        notes.append(f"imu gaps: {why}; the record is estimated whole, across them ({apart} "
                     f"compensate the frames outside the gaps apart, each from its own start)")
        return estimate(inp, rcs, *attitude_of(inp, True, None), None)
    if len(segments) < 2:
        return estimate(inp, rcs, *attitude_of(inp, True, None), None)
    # without the log's attitude each run restarts level with heading 0: roll and pitch
    # from the ground, the heading carried from run to run (below)
    carry = attitude_of(frame_subset(inp, segments[-1][0]), False, None)[1] is None
    # the largest run outside a gap first: its clock offset is the others' (one clock)
    main = max(range(len(segments)), key=lambda j: (not segments[j][1], len(segments[j][0]), -j))
    parts: dict = {}
    # the runs' warnings wait: where the record falls back to one estimate, that one's
    # speak for it, not those of the runs it replaced
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        for j in [main, *(j for j in range(len(segments)) if j != main)]:
            idx, in_gap = segments[j]
            sub, sub_rcs = frame_subset(inp, idx), []
            clock = None if j == main else parts[main][4]
            lo, hi = inp.frames[idx[0]], inp.frames[idx[-1]]
            try:
                m, report, offset = estimate(sub, sub_rcs, *attitude_of(sub, j == 0, clock),
                                             clock)
            except ValueError as exc:   # a run too short for its own estimate: whole
                why = (f"{f'frame {lo}' if lo == hi else f'frames {lo}-{hi}'} between its "
                       f"gaps could not be estimated alone ({exc})")
                break
            if carry and j > 0 and report.get("ground_plane", {}).get("role") != GROUND_ROLE:
                # a level restart would drop the tilt the gyro carried to it
                why = (f"the log holds no attitude and the ground gave no roll and pitch to "
                       f"restart from at frame {lo}")
                break
            parts[j] = (idx, in_gap, report, m, offset, sub_rcs)
        else:
            why = None
    if why is not None:
        return whole(why)
    for w in said:
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno, source=w.source)
    motions = []
    for j in range(len(segments)):
        ms = parts[j][3]
        if motions and carry:   # heading: the last run's, turned on by the log's gyro
            ms = turned(ms, heading_step(motions[-1], ms[0], body_turn(
                imu, motions[-1].time[-1], ms[0].time[0], parts[main][4])))
        if motions:        # positions from the record's start: the last run's, extrapolated
            end, start = motions[-1], ms[0]
            d = (end.position[-1] + end.velocity[-1] * (start.time[0] - end.time[-1])
                 - start.position[0])
            ms = [replace(m, position=m.position + d) for m in ms]
        motions.extend(ms)
        rcs.extend(parts[j][5])
    parts = [parts[j] for j in range(len(segments))]
    report = dict(parts[main][2])
    report["segments"] = [_part(inp, idx, gap, r) for idx, gap, r, *_ in parts]
    found: list = []
    for _, _, r, *_ in parts:
        found.extend(w for w in r.get("warnings", ()) if w not in found)
    report["warnings"] = found

    def name(idx, gap):
        lo, hi = inp.frames[idx[0]], inp.frames[idx[-1]]
        return (f"{lo}" if lo == hi else f"{lo}-{hi}") + (" (in the gap)" if gap else "")
    start = ("restarting level, roll and pitch from the ground, its heading carried on from "
             "the part before" if carry else "the attitude at its first ramp")
    notes.append(f"imu gaps: the record is estimated in {len(parts)} parts split at the log's "
                 f"filled gaps (frames {', '.join(name(i, g) for i, g, *_ in parts)}), each "
                 f"from its own frames and {start}, with the clock offset of frames "
                 f"{name(parts[main][0], parts[main][1])}, whose figures are printed; the "
                 f"report's 'segments' holds each part's")
    return motions, report, parts[main][4]
