"""PX4 ULog (``.ulg``): the ``sensor_combined`` topic, read with ``pyulog``.

Topic and fields (PX4 ``msg/SensorCombined.msg``):

=================================  ==========================================
``timestamp``                      uint64, microseconds since boot (PX4
                                   ``hrt_absolute_time``): the gyro sample time
``gyro_rad[3]``                    float32, angular rate [rad/s], FRD
``accelerometer_timestamp_relative``  int32 [us], accel time minus ``timestamp``
``accelerometer_m_s2[3]``          float32, specific force [m/s^2], FRD
=================================  ==========================================

Time base: the returned ``time`` is ``timestamp * 1e-6`` [s since boot]. PX4
publishes the gyro and accelerometer values averaged over their
``*_integral_dt`` interval ending at the stamp; they are returned as samples at
the stamp (a constant delay of half the interval, absorbed by the IMU-radar
clock offset). When ``accelerometer_timestamp_relative`` is not zero the
accelerometer is interpolated linearly onto the gyro stamps (held constant
before its first and after its last sample). PX4's body frame
is FRD, so no axis conversion is made. Values are float32 in the file: about 7
significant digits (relative resolution 2^-24).

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

from raysim.io.flight_logs import check_increasing, microsecond_stamps
from raysim.platform.imu import ImuSamples

__all__ = ["ULOG_TOPIC", "read_px4_ulog", "write_px4_ulog"]

#: The PX4 topic holding the IMU samples.
ULOG_TOPIC = "sensor_combined"

_MAGIC = b"ULog\x01\x12\x35"
_FORMAT = ("sensor_combined:uint64_t timestamp;float[3] gyro_rad;uint32_t gyro_integral_dt;"
           "int32_t accelerometer_timestamp_relative;float[3] accelerometer_m_s2;"
           "uint32_t accelerometer_integral_dt;uint8_t accelerometer_clipping;"
           "uint8_t gyro_clipping;uint8_t accel_calibration_count;"
           "uint8_t gyro_calibration_count;")
_RECORD = struct.Struct("<Q3fIi3fIBBBB")


def read_px4_ulog(path: str | os.PathLike, instance: int = 0) -> ImuSamples:
    """Read the ``sensor_combined`` IMU samples of a PX4 ULog file.

    Parameters
    ----------
    path : str or path-like
        ``.ulg`` file.
    instance : int
        Multi-instance id of the topic (0 for the usual single instance).

    Returns
    -------
    ImuSamples
        ``time [sample]`` [s since boot], ``gyro [sample, 3]`` [rad/s],
        ``accel [sample, 3]`` [m/s^2], FRD (module docstring).

    Raises
    ------
    ValueError
        Not a ULog file, no ``sensor_combined`` topic (the message lists the
        topics present), or time stamps that do not increase.
    """
    from pyulog import ULog

    path = Path(path)
    with path.open("rb") as fh:
        if fh.read(7) != _MAGIC:
            raise ValueError(f"{str(path)!r} is not a ULog file (no 'ULog' header magic)")
    try:
        log = ULog(str(path), [ULOG_TOPIC])
    except Exception as exc:  # pyulog raises bare Exceptions on corrupt files
        raise ValueError(f"{str(path)!r}: cannot parse ULog file: {exc}") from None
    found = [d for d in log.data_list if d.name == ULOG_TOPIC]
    if not found:
        topics = sorted({f.name for f in log.message_formats.values()})
        raise ValueError(f"{str(path)!r}: no {ULOG_TOPIC!r} data in the log; expected the "
                         f"PX4 topic {ULOG_TOPIC!r} (formats present: {topics})")
    ids = sorted(d.multi_id for d in found)
    match = [d for d in found if d.multi_id == instance]
    if not match:
        raise ValueError(f"{str(path)!r}: instance={instance} of {ULOG_TOPIC!r} not present; "
                         f"instances are {ids}")
    d = match[0].data
    stamp_us = np.asarray(d["timestamp"], dtype=np.uint64)
    time = stamp_us.astype(np.float64) * 1e-6
    gyro = np.column_stack([d[f"gyro_rad[{i}]"] for i in range(3)]).astype(float)
    accel = np.column_stack([d[f"accelerometer_m_s2[{i}]"] for i in range(3)]).astype(float)
    where = f"{str(path)!r} ({ULOG_TOPIC})"
    check_increasing(time, where)
    rel = np.asarray(d.get("accelerometer_timestamp_relative", np.zeros(time.size)),
                     dtype=float)
    if np.any(rel != 0):
        t_acc = time + rel * 1e-6
        check_increasing(t_acc, where + " accelerometer")
        accel = np.column_stack([np.interp(time, t_acc, accel[:, i]) for i in range(3)])
    rate = 1.0 / float(np.median(np.diff(time)))
    return ImuSamples(time, gyro, accel, spec=None, truth=None,
                      source=f"{path} (PX4 ULog {ULOG_TOPIC})", rate=rate)


def _message(kind: bytes, payload: bytes) -> bytes:
    return struct.pack("<HB", len(payload), kind[0]) + payload


def write_px4_ulog(path: str | os.PathLike, samples: ImuSamples) -> Path:
    """Write IMU samples as the ``sensor_combined`` topic of a minimal PX4 ULog file.

    Parameters
    ----------
    path : str or path-like
        Output ``.ulg`` file (written atomically).
    samples : ImuSamples
        ``time [sample]`` [s, >= 0: time since boot; rounded to whole
        microseconds], ``gyro``/``accel [sample, 3]`` FRD [rad/s, m/s^2]
        (stored as float32).

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
    dt_us = np.concatenate([steps[:1], steps])   # integral interval ending at each stamp
    body = bytearray(_MAGIC + b"\x01" + struct.pack("<Q", int(stamps[0])))
    body += _message(b"B", bytes(8) + bytes(8) + bytes(24))   # flag bits: none set
    body += _message(b"F", _FORMAT.encode())
    body += _message(b"A", struct.pack("<BH", 0, 0) + ULOG_TOPIC.encode())
    for k in range(stamps.size):
        g = samples.gyro[k]
        f = samples.accel[k]
        rec = _RECORD.pack(int(stamps[k]), *map(float, g), int(dt_us[k]), 0, *map(float, f),
                           int(dt_us[k]), 0, 0, 0, 0)
        body += _message(b"D", struct.pack("<H", 0) + rec)
    from raysim.io.files import atomic_write_bytes

    return atomic_write_bytes(path, bytes(body))
