"""PX4 ULog (``.ulg``): the IMU topics, read with ``pyulog``; the best present chosen.

Topics read (PX4 ``msg/*.msg``), from the highest rate a log usually holds:

``sensor_gyro_fifo`` + ``sensor_accel_fifo``
    ``timestamp_sample`` [us], ``dt`` [us], ``scale``, ``samples``,
    ``x/y/z[32]`` (int16; value = x * scale, rad/s and m/s^2): the raw sensor
    samples (1-8 kHz), band up to the sensor's own anti-alias filter.
``vehicle_imu``
    ``timestamp_sample`` [us], ``delta_angle[3]`` [rad], ``delta_velocity[3]``
    [m/s], ``delta_angle_dt`` / ``delta_velocity_dt`` [us]: integrals over the
    logged interval (a boxcar of that length).
``sensor_combined``
    ``timestamp`` [us], ``gyro_rad[3]`` [rad/s], ``accelerometer_m_s2[3]``
    [m/s^2], ``accelerometer_timestamp_relative`` [us]: 200-250 Hz in real
    logs, each sample a 4-5 ms boxcar average.

Every instance (PX4 multi-id: one per IMU) of every topic present is read;
the complete source (gyro and accelerometer) with the highest median sample
rate is returned unless ``topic`` / ``instance`` choose. A FIFO sample ``i``
of a message of ``n`` samples is placed at ``timestamp_sample - (n - 1 - i)
dt`` (the last sample at ``timestamp_sample``); the FIFO accelerometer is
interpolated onto the FIFO gyro times. ``vehicle_imu`` rates are the deltas
over their intervals, placed at the interval's middle, ``timestamp_sample -
delta_angle_dt / 2`` (the accelerometer at ``timestamp_sample -
delta_velocity_dt / 2``, interpolated onto the gyro times).

What each source can see: an average over ``T`` seconds is a boxcar filter
(first null at ``1/T``) and a log at ``f_s`` folds everything above ``f_s/2``:
a 200-250 Hz ``sensor_combined`` (``T`` = 4-5 ms) cannot resolve a 100-200 Hz
rotor band; only the FIFO topics can (docs/recordings.md).

Time base: the returned ``time`` is the stamp times 1e-6 [s], as stored (less
half an averaging interval, below):
microseconds since boot (PX4 ``hrt_absolute_time``) in most logs, since the
Unix epoch in some (:func:`raysim.io.flight_logs.time_base` tells them apart
and the result's ``source`` says which). ``sensor_combined`` publishes the gyro
and accelerometer averaged over their ``*_integral_dt`` intervals ending at the
stamp; each average is returned as a sample at its interval's middle, ``timestamp
- gyro_integral_dt / 2`` (the accelerometer at ``timestamp +
accelerometer_timestamp_relative - accelerometer_integral_dt / 2``, interpolated
linearly onto the gyro times, held constant before its first and after its last
sample): a boxcar average equals the signal at its middle to second order (for a
signal linear over the interval, exactly), so the clock offset estimated from such a
log is the IMU-radar offset itself, not the offset plus half the interval. An
``*_integral_dt`` of 0 (or absent) is an instantaneous sample, kept at its stamp.
Frames: ``sensor_combined`` and ``vehicle_imu`` are in
the body frame FRD (board rotation and calibration applied); the FIFO topics
are in the sensor board's frame (FRD for the usual mounting, before
``SENS_BOARD_ROT`` and the calibration). No axis conversion is made. Values are
float32 in the file.

:func:`write_px4_ulog` writes a minimal ULog file (header, flag bits, one
format, one subscription, data messages) per the published ULog specification
(docs.px4.io, "ULog File Format"), e.g. to hand a simulated flight to tools
that read PX4 logs.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path

import numpy as np

from raysim.io.flight_logs import (
    check_increasing,
    choose_source,
    median_rate,
    microsecond_stamps,
    time_base,
)
from raysim.platform.imu import ImuSamples

__all__ = ["ULOG_TOPIC", "ULOG_IMU_TOPICS", "ATTITUDE_TOPIC", "read_px4_ulog", "write_px4_ulog"]

#: The PX4 topic the writer uses (and the usual IMU topic of a log).
ULOG_TOPIC = "sensor_combined"
#: IMU topics read (``sensor_gyro_fifo`` stands for the FIFO pair).
ULOG_IMU_TOPICS = ("sensor_gyro_fifo", "vehicle_imu", "sensor_combined")
_FIFO_ACCEL = "sensor_accel_fifo"

_MAGIC = b"ULog\x01\x12\x35"
_FORMAT = ("sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
           "int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;"
           "uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;"
           "uint8_t gyro_clipping;uint8_t accel_calibration_count;"
           "uint8_t gyro_calibration_count;")
_RECORD = struct.Struct("<Q3fIi3fIBBBB")
#: The attitude topic the writer adds (PX4 ``vehicle_attitude``: ``q`` body FRD to NED).
ATTITUDE_TOPIC = "vehicle_attitude"
_ATT_FORMAT = ("vehicle_attitude:uint64_t timestamp;float[4] q;float[4] delta_q_reset;"
               "uint8_t quat_reset_counter;")
_ATT_RECORD = struct.Struct("<Q4f4fB")


def _increasing(time: np.ndarray, *arrays) -> tuple:
    """Drop samples whose stamp does not increase (repeated FIFO reads), keep the rest."""
    keep = np.concatenate([[True], np.diff(time) > 0]) if time.size else np.zeros(0, bool)
    while time.size and not np.all(np.diff(time[keep]) > 0):
        t = time[keep]
        bad = np.flatnonzero(np.diff(t) <= 0) + 1
        idx = np.flatnonzero(keep)[bad]
        keep[idx] = False
    return (time[keep],) + tuple(a[keep] for a in arrays)


def _fifo(d: dict) -> tuple[np.ndarray, np.ndarray]:
    """Samples of a ``sensor_*_fifo`` topic: time ``[sample]`` [s], values ``[sample, 3]``."""
    n = np.asarray(d["samples"], dtype=int)
    dt = np.asarray(d["dt"], dtype=float)
    scale = np.asarray(d["scale"], dtype=float)
    ts = np.asarray(d.get("timestamp_sample", d["timestamp"]), dtype=float)
    width = max(int(n.max()) if n.size else 0, 1)
    i = np.arange(width)
    valid = i[None, :] < n[:, None]
    t = (ts[:, None] - (n[:, None] - 1 - i[None, :]) * dt[:, None]) * 1e-6
    xyz = [np.column_stack([np.asarray(d[f"{a}[{j}]"], dtype=float) for j in range(width)])
           * scale[:, None] for a in "xyz"]
    vals = np.stack([x[valid] for x in xyz], axis=-1)
    time, vals = _increasing(t[valid], vals)
    return time, vals


def _interval(d: dict, field: str, n: int) -> np.ndarray:
    """``*_integral_dt`` [us] of each sample, ``[sample]``; 0 (an instantaneous sample)
    where the field is absent. Older PX4 firmware logs it as float32 seconds (0.004 at
    250 Hz), newer as integer microseconds: a float field whose median is below one
    (no IMU averages over less than a microsecond) is read as seconds."""
    raw = np.asarray(d.get(field, np.zeros(n)))
    dt = raw.astype(float)
    if np.any(dt < 0) or not np.all(np.isfinite(dt)):
        raise ValueError(f"{field} negative or not finite")
    if np.issubdtype(raw.dtype, np.floating) and dt.size and 0 < np.median(dt) < 1.0:
        dt = dt * 1e6
    return dt


def sensor_combined_samples(d: dict, where: str) -> tuple:
    """``(time [sample], gyro [sample, 3], accel [sample, 3], interval)`` of PX4
    ``sensor_combined`` fields ``d`` (a ULog's, or its ``ulog2csv`` export's columns):
    each sample at the middle of its averaging interval [s], the accelerometer
    interpolated to the gyro's times, ``interval`` the median averaging interval [s]."""
    stamp = np.asarray(d["timestamp"], dtype=np.uint64).astype(float) * 1e-6
    gyro = np.column_stack([d[f"gyro_rad[{i}]"] for i in range(3)]).astype(float)
    accel = np.column_stack([d[f"accelerometer_m_s2[{i}]"] for i in range(3)]).astype(float)
    rel = np.asarray(d.get("accelerometer_timestamp_relative", np.zeros(stamp.size)),
                     dtype=float)
    dt = _interval(d, "gyro_integral_dt", stamp.size)
    time = stamp - 0.5e-6 * dt
    t_acc = stamp + rel * 1e-6 - 0.5e-6 * _interval(d, "accelerometer_integral_dt", stamp.size)
    if np.any(t_acc != time):
        check_increasing(t_acc, f"{where} accelerometer")
        accel = np.column_stack([np.interp(time, t_acc, accel[:, i]) for i in range(3)])
    return time, gyro, accel, 1e-6 * float(np.median(dt)) if dt.size else 0.0


def read_px4_csv_export(path: str | os.PathLike) -> ImuSamples:
    """PX4 ``sensor_combined`` rows of pyulog's ``ulog2csv`` export, read as from the ULog
    (:func:`sensor_combined_samples`: each sample at its averaging interval's middle).

    Raises
    ------
    ValueError
        A row that is not numbers, a field count that is not the header's, or time
        stamps that do not increase (the line named).
    """
    import csv

    from raysim.io.imu_log import PX4_EXPORT, csv_header

    path = Path(path)
    header, header_line = csv_header(path)
    names = [h.strip() for h in header]
    rows = []
    with path.open(newline="") as fh:
        for k, fields in enumerate(csv.reader(fh), start=1):
            if k <= header_line or not fields:
                continue
            if len(fields) != len(names):
                raise ValueError(f"{path}: line {k} has {len(fields)} fields, the header has "
                                 f"{len(names)}")
            try:
                rows.append([float(x) for x in fields])
            except ValueError:
                raise ValueError(f"{path}: line {k} is not {len(names)} numbers") from None
    data = np.asarray(rows, dtype=float).reshape(-1, len(names))
    if not data.size or not np.all(np.isfinite(data)):
        raise ValueError(f"{path}: expected rows of finite numbers after the header")
    cols = {n: data[:, i] for i, n in enumerate(names)}
    time, gyro, accel, interval = sensor_combined_samples(cols, str(path))
    check_increasing(time, f"{path} (timestamp)")
    rate = median_rate(time)
    return ImuSamples(time, gyro, accel, spec=None, truth=None, rate=rate, interval=interval,
                      source=f"{path} ({PX4_EXPORT}: FRD, SI, {rate:.4g} Hz, "
                             f"{time_base(time)})")


def _candidates(log) -> tuple[list, dict]:
    """Complete IMU sources of a parsed log: ``(topic, instance, rate, (t, gyro, accel))``."""
    by = {(d.name, d.multi_id): d.data for d in log.data_list}
    out, unusable = [], {}
    for (name, k), d in sorted(by.items()):
        try:
            if name == "sensor_combined":
                time, gyro, accel, _ = sensor_combined_samples(d, f"{name}[{k}]")
            elif name == "vehicle_imu":
                stamp = np.asarray(d.get("timestamp_sample", d["timestamp"]),
                                   dtype=np.uint64).astype(float) * 1e-6
                da = np.asarray(d["delta_angle_dt"], dtype=float) * 1e-6
                dv = np.asarray(d["delta_velocity_dt"], dtype=float) * 1e-6
                if np.any(da <= 0) or np.any(dv <= 0):
                    raise ValueError("delta_angle_dt / delta_velocity_dt not positive")
                gyro = np.column_stack([d[f"delta_angle[{i}]"] for i in range(3)]) / da[:, None]
                accel = np.column_stack([d[f"delta_velocity[{i}]"]
                                         for i in range(3)]) / dv[:, None]
                time, t_acc = stamp - da / 2, stamp - dv / 2      # the intervals' middles
                if np.any(t_acc != time):
                    check_increasing(t_acc, f"{name}[{k}] accelerometer")
                    accel = np.column_stack([np.interp(time, t_acc, accel[:, i])
                                             for i in range(3)])
            elif name == "sensor_gyro_fifo":
                time, gyro = _fifo(d)
                if (_FIFO_ACCEL, k) not in by:
                    raise ValueError(f"no {_FIFO_ACCEL}[{k}] in the log")
                t_acc, acc = _fifo(by[_FIFO_ACCEL, k])
                inside = (time >= t_acc[0]) & (time <= t_acc[-1])
                if inside.sum() < 2:
                    raise ValueError(f"{_FIFO_ACCEL}[{k}] does not overlap the gyro samples")
                time, gyro = time[inside], gyro[inside]
                accel = np.column_stack([np.interp(time, t_acc, acc[:, i]) for i in range(3)])
            else:
                continue
            time = np.asarray(time, dtype=float)
            check_increasing(time, f"{name}[{k}]")     # FIFO repeats are dropped in _fifo
            out.append((name, k, median_rate(time), (time, gyro, accel)))
        except (KeyError, ValueError) as exc:
            unusable[f"{name}[{k}]"] = str(exc)
    return out, unusable


def read_px4_ulog(path: str | os.PathLike, instance: int | None = None,
                  topic: str | None = None) -> ImuSamples:
    """Read the best IMU source of a PX4 ULog file (module docstring).

    Parameters
    ----------
    path : str or path-like
        ``.ulg`` file.
    instance : int, optional
        Multi-instance id of the topic (one per IMU); default the best.
    topic : {"sensor_gyro_fifo", "vehicle_imu", "sensor_combined"}, optional
        Topic to read; default the complete one with the highest rate.

    Returns
    -------
    ImuSamples
        ``time [sample]`` [s, the log's clock], ``gyro [sample, 3]`` [rad/s],
        ``accel [sample, 3]`` [m/s^2], FRD; ``rate`` the median sample rate
        [Hz]; ``source`` names the file, topic, instance, rate and time base.

    Raises
    ------
    ValueError
        Not a ULog file, an unknown topic, no complete IMU source matching
        ``topic`` / ``instance`` (the message lists the sources present with
        their rates), or time stamps that do not increase.
    """
    from pyulog import ULog

    path = Path(path)
    if topic is not None and topic not in ULOG_IMU_TOPICS:
        raise ValueError(f"{str(path)!r}: topic={topic!r} is not an IMU topic read here; "
                         f"expected one of {list(ULOG_IMU_TOPICS)}")
    if instance is not None and (isinstance(instance, bool) or int(instance) != instance
                                 or instance < 0):
        raise ValueError(f"{str(path)!r}: instance must be a non-negative integer, got "
                         f"{instance!r}")
    with path.open("rb") as fh:
        if fh.read(7) != _MAGIC:
            raise ValueError(f"{str(path)!r} is not a ULog file (no 'ULog' header magic)")
    try:
        log = ULog(str(path), list(ULOG_IMU_TOPICS) + [_FIFO_ACCEL])
    except Exception as exc:  # pyulog raises bare Exceptions on corrupt files
        raise ValueError(f"{str(path)!r}: cannot parse ULog file: {exc}") from None
    found, unusable = _candidates(log)
    if not found and not unusable and topic is None and instance is None:
        topics = sorted({f.name for f in log.message_formats.values()})
        raise ValueError(f"{str(path)!r}: no IMU data in the log; expected one of the PX4 "
                         f"topics {list(ULOG_IMU_TOPICS)} (formats present: {topics})")
    name, k, rate, (time, gyro, accel) = choose_source(str(path), found, topic, instance,
                                                       unusable)
    check_increasing(time, f"{str(path)!r} ({name}[{k}])")
    others = ", ".join(f"{c[0]}[{c[1]}] {c[2]:.4g} Hz" for c in found if c[:2] != (name, k))
    source = (f"{path} (PX4 ULog {name} instance {k}, {rate:.4g} Hz, {time_base(time)}"
              + (f"; also present: {others}" if others else "") + ")")
    d = next(x.data for x in log.data_list if (x.name, x.multi_id) == (name, k))
    dt = {"sensor_combined": "gyro_integral_dt", "vehicle_imu": "delta_angle_dt"}.get(name)
    interval = 1e-6 * float(np.median(_interval(d, dt, time.size))) if dt else 0.0
    return ImuSamples(time, gyro, accel, spec=None, truth=None, source=source, rate=rate,
                      interval=interval)


def _message(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def write_px4_ulog(path: str | os.PathLike, samples: ImuSamples, attitude=None, *,
                   averaged: bool = False) -> Path:
    """Write IMU samples as the ``sensor_combined`` topic of a minimal PX4 ULog file.

    With ``attitude`` the file also holds the flight controller's attitude as
    ``vehicle_attitude`` (``q`` = ``w, x, y, z`` of ``R_WB``, body FRD to NED),
    its messages interleaved with the IMU's in time order.

    Parameters
    ----------
    path : str or path-like
        Output ``.ulg`` file (written atomically).
    samples : ImuSamples
        ``time [sample]`` [s, >= 0: time since boot; rounded to whole
        microseconds], ``gyro``/``accel [sample, 3]`` FRD [rad/s, m/s^2]
        (stored as float32).
    attitude : raysim.io.flight_logs.attitude.AttitudeLog, optional
        ``time [sample]`` [s, the IMU's clock, >= 0] and ``rotation`` ``R_WB``.
    averaged : bool
        Each sample is the average over the interval since the previous stamp
        (a flight controller's boxcar output stamped at the interval's end,
        :func:`raysim.platform.imu_output.boxcar_output`): ``*_integral_dt`` is
        that interval [us], the median step (a logger gap is no longer an
        average). False:
        instantaneous samples, ``*_integral_dt`` 0. The reader places each
        sample at its interval's middle (module docstring).

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    ValueError
        ``samples`` is not ImuSamples, a time is negative, or two times round to
        the same microsecond.
    """
    stamps = microsecond_stamps(samples, "write_px4_ulog", "ULog time stamps").astype(np.uint64)
    steps = np.diff(stamps.astype(np.int64))
    # the averaging interval ending at each stamp: the logging step (the median, as a
    # logger gap is no longer average); 0 marks instantaneous samples
    dt_us = np.full(stamps.size, int(np.rint(np.median(steps))) if averaged and steps.size
                    else 0, dtype=np.int64)
    body = bytearray(_MAGIC + b"\x01" + struct.pack("<Q", int(stamps[0])))
    body += _message(b"B", bytes(8) + bytes(8) + bytes(24))   # flag bits: none set
    body += _message(b"F", _FORMAT.encode())
    if attitude is not None:            # every format before the first subscription
        body += _message(b"F", _ATT_FORMAT.encode())
    body += _message(b"A", struct.pack("<BH", 0, 0) + ULOG_TOPIC.encode())
    records = []                                    # (stamp [us], order, data message)
    for k in range(stamps.size):
        g = samples.gyro[k]
        f = samples.accel[k]
        rec = _RECORD.pack(int(stamps[k]), *map(float, g), int(dt_us[k]), 0, *map(float, f),
                           int(dt_us[k]), 0, 0, 0, 0)
        records.append((int(stamps[k]), 0, _message(b"D", struct.pack("<H", 0) + rec)))
    if attitude is not None:
        t_att = np.asarray(attitude.time, dtype=float)
        check_increasing(t_att, "write_px4_ulog attitude")
        if t_att[0] < 0:
            raise ValueError(f"attitude times are microseconds since boot and must be >= 0; "
                             f"the first is at {float(t_att[0]):.6f} s")
        body += _message(b"A", struct.pack("<BH", 0, 1) + ATTITUDE_TOPIC.encode())
        quat = attitude.rotation.as_quat()[:, [3, 0, 1, 2]]       # scipy x,y,z,w -> w,x,y,z
        for t, q in zip(np.rint(t_att * 1e6).astype(np.int64), quat, strict=True):
            rec = _ATT_RECORD.pack(int(t), *map(float, q), 0.0, 0.0, 0.0, 0.0, 0)
            records.append((int(t), 1, _message(b"D", struct.pack("<H", 1) + rec)))
        records.sort(key=lambda r: r[:2])
    for _, _, msg in records:
        body += msg
    from raysim.io.files import atomic_write_bytes

    return atomic_write_bytes(path, bytes(body))
