"""The IMU log of a compensation: its table, judged over the window used, and the attitude
it gives at the first ramp.

:func:`raysim.pipeline.compensate.compensate` reads its IMU input through these: a
log file (:func:`raysim.io.flight_logs.read_imu_log`: CSV, PX4 ULog, ArduPilot
DataFlash, ROS 1 or 2 bag), the IMU record of a frame store, or a table; the gaps of the
log are judged over the chirps selected (:mod:`compensation.ingestion`), and the
flight controller's attitude, where the log has one, sets the initial attitude.
"""

from __future__ import annotations

import os

import numpy as np

__all__ = ["imu_table", "imu_window", "log_attitude"]


def imu_table(imu, inp, source: str, topic=None, instance=None) -> tuple[np.ndarray, str, float]:
    """The IMU log as a table ``[sample, 7]`` (time, gyro, accel; SI, FRD), its source and
    the averaging interval of its samples [s] (0: instantaneous or not stated)."""
    from raysim.io.flight_logs import read_imu_log

    if imu is None:
        if inp.imu is None:
            raise ValueError(f"{source!r} holds no IMU log; give an IMU log with --imu FILE")
        if topic is not None or instance is not None:
            raise ValueError("--imu-topic / --imu-instance select a source of an IMU log file; "
                             f"{source!r} carries its own IMU record (give --imu FILE)")
        return inp.imu, f"{source} (IMU log of the store)", 0.0
    if isinstance(imu, (str, os.PathLike)):
        path = os.fspath(imu)
        if not os.path.exists(path):
            raise ValueError(f"IMU file {path!r} does not exist")
        try:
            s = read_imu_log(path, topic=topic, instance=instance)
        except ImportError as exc:   # an optional reader (pymavlink for .bin) is missing
            raise ValueError(f"IMU file {path!r}: {exc}") from None
        return np.column_stack([s.time, s.gyro, s.accel]), s.source, s.interval
    if topic is not None or instance is not None:
        raise ValueError("--imu-topic / --imu-instance select a source of an IMU log file, not "
                         "of a table")
    table = np.asarray(imu, dtype=float)
    if table.ndim != 2 or table.shape[1] != 7:
        raise ValueError(f"imu: got an array of shape {table.shape}, expected a file path or "
                         f"a table [sample, 7] (time, gyro xyz, accel xyz)")
    return table, "table", 0.0


def imu_window(table: np.ndarray, inp, time_offset, max_gap) -> tuple[np.ndarray, tuple, list]:
    """The IMU table judged over the window used (:func:`compensation.ingestion.judge_imu_window`),
    its notes, and the runs of selected frames its filled gaps do not cross
    (:func:`compensation.ingestion.gap_segments`: indices into the selection, in-gap flag).

    The window is every selected chirp and slot on the IMU clock (radar time plus
    the given offset; the first guess 0 of ``"auto"``, whose search stays within
    the margin), plus :data:`compensation.ingestion.WINDOW_MARGIN` on each side.
    The frames in a gap are those :func:`compensation.ingestion.frames_in_gaps` names.
    """
    from compensation.ingestion import (
        fill_imu_gaps,
        frames_in_gaps,
        gap_segments,
        judge_imu_window,
    )

    if max_gap is not None:
        given = max_gap
        try:
            max_gap = float(np.asarray(given, dtype=float).reshape(()))
        except (TypeError, ValueError):
            max_gap = float("nan")
        if not (np.isfinite(max_gap) and max_gap > 0):
            raise ValueError(f"--max-gap: got {given!r}, expected a positive number of "
                             f"seconds")
    t = table[:, 0]
    whole = [(list(range(len(inp.frames))), False)]
    if t.size < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) <= 0):
        return table, (), whole          # the integration names the bad stamps
    slots = np.asarray(inp.slot_times, dtype=float)
    shift = 0.0 if isinstance(time_offset, str) else float(time_offset)
    window = (float(slots.min()) + shift, float(slots.max()) + shift)
    keep, fill, notes = judge_imu_window(t, window, max_gap=max_gap,
                                         what=f"the {len(inp.frames)} frame(s) selected")
    if keep.size == t.size and fill.size == 0:
        return table, notes, whole
    spans, step = [(s.min() + shift, s.max() + shift) for s in slots], float(np.median(np.diff(t)))
    notes = (*notes, *frames_in_gaps(fill, spans, inp.frames, step))
    tt, vals = fill_imu_gaps(t, table[:, 1:], keep, fill)
    return np.column_stack([tt, vals]), notes, gap_segments(fill, spans, step)


def log_attitude(value, imu, inp, time_offset, topic, notes: list):
    """``initial_attitude_deg``: as given, else the IMU log's attitude at the first ramp
    (:mod:`raysim.io.flight_logs.attitude`), else level (0, 0, 0); the choice in ``notes``.
    With it the log's attitude, times [s, IMU clock] and ``R_WB`` ``[sample, 3, 3]`` (None
    when the attitude is given or the log holds none)."""
    if value is not None:
        return value, None
    att = None
    if isinstance(imu, (str, os.PathLike)):
        from raysim.io.flight_logs.attitude import read_attitude_log

        att = read_attitude_log(imu, topic=topic)
    if att is None:
        notes.append("initial attitude: the IMU log holds no attitude; the platform is "
                      "assumed level, heading 0, at the first ramp (--initial-attitude-deg "
                      "0,0,0); --velocity radar measures roll and pitch from the ground "
                      "beyond the range window when in view")
        return None, None             # the nominal attitude, no estimate
    shift = 0.0 if isinstance(time_offset, str) else float(time_offset)
    t = float(np.min(inp.slot_times)) + shift             # the first ramp on the log's clock
    ypr = att.euler_deg(t)
    notes.append(f"initial attitude: yaw, pitch, roll {ypr[0]:.3f}, {ypr[1]:.3f}, "
                 f"{ypr[2]:.3f} deg from {att.source} at {t:.6f} s (the first ramp on the "
                 f"log's clock{', offset 0 taken' if isinstance(time_offset, str) else ''}); "
                 f"--initial-attitude-deg overrides")
    return ypr, (att.time, att.rotation.as_matrix())
