"""ArduPilot DataFlash logs (``.bin``): the IMU messages, read with ``pymavlink``; the best chosen.

``pymavlink`` is LGPL-3.0 and therefore an optional extra: install it with
``pip install raysim[ardupilot]``; it is imported only when a ``.bin`` file is
read.

Messages read (ArduPilot ``AP_InertialSensor`` logging), from the highest rate
a log usually holds:

=============  ==========================================================  ==================
message        fields used                                                 rate, band
=============  ==========================================================  ==================
``ISBH`` +     ``ISBH``: ``N`` (batch), ``type`` (0 accel, 1 gyro),        raw sensor rate
``ISBD``       ``instance``, ``mul``, ``SampleUS``, ``smp_rate`` [Hz];      (1-8 kHz) in
               ``ISBD``: ``N``, ``seqno``, ``x/y/z[32]`` (int16; value =   bursts
               x / mul, rad/s and m/s^2)
``GYR`` +      ``SampleUS`` (else ``TimeUS``) [us], ``I``, ``GyrX..Z``     sensor rate,
``ACC``        [rad/s] / ``AccX..Z`` [m/s^2]                               before filtering
``IMU``        ``TimeUS`` [us] (``TimeMS`` [ms] in 2014-2015 firmware),    the loop or log
(``IMU2``,     ``I`` (older logs: ``IMU`` is 0, ``IMU2`` 1, ``IMU3`` 2),   rate (25-400 Hz),
``IMU3``)      ``GyrX..Z`` [rad/s], ``AccX..Z`` [m/s^2]                     filtered
=============  ==========================================================  ==================

Every instance of every message present is read; the complete source (gyro
and accelerometer over the same time) with the highest median sample rate is
returned unless ``topic`` (``"ISBD"``, ``"GYR"`` or ``"IMU"``) / ``instance``
choose. Batch sample ``j`` of a batch is placed at ``SampleUS + j /
smp_rate``. The batch sampler records one sensor at a time for vibration
analysis: its gyro and accelerometer batches seldom overlap, and a source
without both over the same time is reported as unusable (with the reason)
rather than read. ``GYR``/``ACC``: the accelerometer is interpolated onto the
gyro times.

Time base: ``time = TimeUS * 1e-6`` (``TimeMS * 1e-3``, a 1 ms resolution) [s
since boot]. ArduPilot's body frame is FRD, so no axis conversion is made.
Each sample stays at its stamp: ArduPilot documents ``IMU`` as the filtered
sensor output at the logging time (a low-pass filter, not an average over a
stated interval, so there is no interval whose middle would be the sample time)
and ``GYR``/``ACC``/``ISBD`` as raw sensor samples; a filter's group delay is
left to the IMU-radar clock offset.

:func:`write_dataflash_imu` writes a minimal file (an ``FMT`` message for
``IMU`` then the data messages, each ``0xA3 0x95 <type>`` + payload), the
layout pymavlink's ``DFReader_binary`` parses; it needs no pymavlink.
"""

from __future__ import annotations

import os
import struct
from collections import defaultdict
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

__all__ = ["ARDUPILOT_EXTRA", "DATAFLASH_IMU_TOPICS", "read_dataflash_imu",
           "write_dataflash_imu"]

#: The pip extra that installs pymavlink.
ARDUPILOT_EXTRA = "raysim[ardupilot]"
#: Sources read (``ISBD`` stands for the ISBH/ISBD batches, ``GYR`` for GYR + ACC).
DATAFLASH_IMU_TOPICS = ("ISBD", "GYR", "IMU")

_HEAD = b"\xa3\x95"
_FMT_TYPE = 0x80
_IMU_TYPE = 0x81
_IMU_FORMAT = "QBffffff"
_IMU_COLUMNS = "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"
_IMU_RECORD = struct.Struct("<QBffffff")
_IMU_NAMES = ("IMU", "IMU2", "IMU3")


def _dfreader():
    try:
        from pymavlink import DFReader
    except ImportError:
        raise ImportError("reading ArduPilot DataFlash (.bin) logs needs pymavlink, an "
                          f"optional dependency (LGPL): pip install {ARDUPILOT_EXTRA}") from None
    return DFReader


def _stamp(msg, fields, prefer_sample: bool = False) -> float:
    """Time of a message [s since boot]: SampleUS, TimeUS or TimeMS."""
    if prefer_sample and "SampleUS" in fields:
        return int(msg.SampleUS) * 1e-6
    if "TimeUS" in fields:
        return int(msg.TimeUS) * 1e-6
    if "TimeMS" in fields:
        return int(msg.TimeMS) * 1e-3
    raise ValueError(f"{msg.get_type()} message has neither TimeUS nor TimeMS "
                     f"(fields {list(fields)})")


def _series(rows) -> tuple[np.ndarray, np.ndarray]:
    """Rows ``(time, x, y, z)`` -> time-sorted, strictly increasing ``t [n]``, ``v [n, 3]``."""
    a = np.asarray(sorted(rows, key=lambda r: r[0]), dtype=float).reshape(-1, 4)
    keep = np.concatenate([[True], np.diff(a[:, 0]) > 0]) if a.size else np.zeros(0, bool)
    return a[keep, 0], a[keep, 1:]


def _pair(t_g, g, t_a, a, what: str) -> tuple:
    """Gyro samples where the accelerometer covers them, the accelerometer interpolated."""
    if t_g.size < 2 or t_a.size < 2:
        raise ValueError(f"{what}: gyro {t_g.size} and accel {t_a.size} sample(s)")
    inside = (t_g >= t_a[0]) & (t_g <= t_a[-1])
    if inside.sum() < 2:
        raise ValueError(f"{what}: the gyro and accelerometer samples do not overlap in time")
    t = t_g[inside]
    return t, g[inside], np.column_stack([np.interp(t, t_a, a[:, i]) for i in range(3)])


def _scan(path: Path) -> tuple[dict, str]:
    """Rows of every IMU source of the log, and the time field of ``IMU`` messages."""
    log = _dfreader().DFReader_binary(str(path))
    try:
        return _scan_messages(log)
    finally:
        log.close()                  # its file and memory map, not left to the collector


def _scan_messages(log) -> tuple[dict, str]:
    imu = defaultdict(list)
    raw = {"GYR": defaultdict(list), "ACC": defaultdict(list)}
    heads, data = {}, defaultdict(list)
    clock = "TimeUS"
    while True:
        msg = log.recv_match(type=list(_IMU_NAMES) + ["GYR", "ACC", "ISBH", "ISBD"])
        if msg is None:
            break
        name, fields = msg.get_type(), msg.get_fieldnames()
        if name in _IMU_NAMES:
            inst = int(msg.I) if "I" in fields else _IMU_NAMES.index(name)
            if "TimeUS" not in fields and "TimeMS" in fields:
                clock = "TimeMS"
            imu[inst].append((_stamp(msg, fields), msg.GyrX, msg.GyrY, msg.GyrZ,
                              msg.AccX, msg.AccY, msg.AccZ))
        elif name in raw:
            inst = int(msg.I) if "I" in fields else 0
            p = "Gyr" if name == "GYR" else "Acc"
            raw[name][inst].append((_stamp(msg, fields, True), getattr(msg, p + "X"),
                                    getattr(msg, p + "Y"), getattr(msg, p + "Z")))
        elif name == "ISBH":
            heads[int(msg.N)] = (int(msg.type), int(msg.instance), float(msg.mul),
                                 int(msg.SampleUS) * 1e-6, float(msg.smp_rate))
        else:
            data[int(msg.N)].append((int(msg.seqno), list(msg.x), list(msg.y), list(msg.z)))
    return dict(imu=imu, raw=raw, heads=heads, data=data), clock


def _candidates(scan: dict, where: str) -> tuple[list, dict]:
    out, unusable = [], {}
    for inst, rows in sorted(scan["imu"].items()):
        a = np.asarray(sorted(rows, key=lambda r: r[0]), dtype=float)
        keep = np.concatenate([[True], np.diff(a[:, 0]) > 0])
        a = a[keep]
        if a.shape[0] < 2:
            unusable[f"IMU[{inst}]"] = f"{a.shape[0]} sample(s)"
            continue
        out.append(("IMU", inst, median_rate(a[:, 0]), (a[:, 0], a[:, 1:4], a[:, 4:7])))
    for inst in sorted(set(scan["raw"]["GYR"]) | set(scan["raw"]["ACC"])):
        try:
            t_g, g = _series(scan["raw"]["GYR"].get(inst, []))
            t_a, f = _series(scan["raw"]["ACC"].get(inst, []))
            t, g, f = _pair(t_g, g, t_a, f, f"GYR/ACC[{inst}]")
            out.append(("GYR", inst, median_rate(t), (t, g, f)))
        except ValueError as exc:
            unusable[f"GYR[{inst}]"] = str(exc)
    series = {0: defaultdict(list), 1: defaultdict(list)}     # type -> instance -> rows
    for n, (kind, inst, mul, t0, rate) in scan["heads"].items():
        for seq, x, y, z in scan["data"].get(n, []):
            for j in range(len(x)):
                series.setdefault(kind, defaultdict(list))[inst].append(
                    (t0 + (seq * len(x) + j) / rate, x[j] / mul, y[j] / mul, z[j] / mul))
    for inst in sorted(set(series[0]) | set(series[1])):
        try:
            t_g, g = _series(series[1].get(inst, []))
            t_a, f = _series(series[0].get(inst, []))
            t, g, f = _pair(t_g, g, t_a, f, f"ISBD[{inst}] (batch sampler)")
            out.append(("ISBD", inst, median_rate(t), (t, g, f)))
        except ValueError as exc:
            unusable[f"ISBD[{inst}]"] = str(exc)
    return out, unusable


def read_dataflash_imu(path: str | os.PathLike, instance: int | None = None,
                       topic: str | None = None) -> ImuSamples:
    """Read the best IMU source of an ArduPilot ``.bin`` log (module docstring).

    Parameters
    ----------
    path : str or path-like
        DataFlash ``.bin`` file.
    instance : int, optional
        IMU instance (field ``I``; in old logs without it, ``IMU`` is 0,
        ``IMU2`` is 1, ``IMU3`` is 2); default the best.
    topic : {"ISBD", "GYR", "IMU"}, optional
        Source; default the complete one with the highest rate.

    Returns
    -------
    ImuSamples
        ``time [sample]`` [s since boot], ``gyro [sample, 3]`` [rad/s],
        ``accel [sample, 3]`` [m/s^2], FRD; ``rate`` the median rate [Hz];
        ``source`` names the file, message, instance, rate and time field.

    Raises
    ------
    ImportError
        pymavlink is not installed (the message names the extra).
    ValueError
        Not a DataFlash file, an unknown topic, no complete source matching
        ``topic`` / ``instance`` (the message lists what is present), or time
        stamps that do not increase.
    """
    path = Path(path)
    if topic is not None and topic not in DATAFLASH_IMU_TOPICS:
        raise ValueError(f"{str(path)!r}: topic={topic!r} is not an IMU source read here; "
                         f"expected one of {list(DATAFLASH_IMU_TOPICS)}")
    with path.open("rb") as fh:
        if fh.read(2) != _HEAD:
            raise ValueError(f"{str(path)!r} is not an ArduPilot DataFlash log (no 0xA3 0x95 "
                             f"message header)")
    scan, clock = _scan(path)
    found, unusable = _candidates(scan, str(path))
    if not found and not unusable:
        raise ValueError(f"{str(path)!r}: no IMU messages ({list(_IMU_NAMES)}, GYR/ACC, "
                         f"ISBH/ISBD) in the log")
    name, k, rate, (time, gyro, accel) = choose_source(str(path), found, topic, instance,
                                                       unusable)
    field = clock if name == "IMU" else "SampleUS"
    check_increasing(time, f"{str(path)!r} ({name}.{field})")
    others = ", ".join(f"{c[0]}[{c[1]}] {c[2]:.4g} Hz" for c in found if c[:2] != (name, k))
    notes = "; ".join(f"{k2}: {v}" for k2, v in unusable.items())
    source = (f"{path} (ArduPilot DataFlash {name} instance {k}, {rate:.4g} Hz, {field}, "
              f"{time_base(time)}" + (f"; also present: {others}" if others else "")
              + (f"; unusable: {notes}" if notes else "") + ")")
    return ImuSamples(time, gyro, accel, spec=None, truth=None, source=source, rate=rate)


def write_dataflash_imu(path: str | os.PathLike, samples: ImuSamples,
                        instance: int = 0) -> Path:
    """Write IMU samples as the ``IMU`` messages of a minimal DataFlash ``.bin`` file.

    Parameters
    ----------
    path : str or path-like
        Output file (written atomically).
    samples : ImuSamples
        ``time [sample]`` [s since boot, >= 0; rounded to whole microseconds],
        ``gyro``/``accel [sample, 3]`` FRD [rad/s, m/s^2] (stored as float32).
    instance : int
        Value of the ``I`` field (0..255).

    Returns
    -------
    pathlib.Path
        The written file.
    """
    if not 0 <= instance <= 255:
        raise ValueError(f"instance must be in 0..255, got {instance}")
    stamps = microsecond_stamps(samples, "write_dataflash_imu", "DataFlash TimeUS")
    fmt = struct.pack("<BB4s16s64s", _IMU_TYPE, 3 + _IMU_RECORD.size, b"IMU",
                      _IMU_FORMAT.encode(), _IMU_COLUMNS.encode())
    body = bytearray(_HEAD + bytes([_FMT_TYPE]) + fmt)
    for k in range(stamps.size):
        body += _HEAD + bytes([_IMU_TYPE]) + _IMU_RECORD.pack(
            int(stamps[k]), instance, *map(float, samples.gyro[k]), *map(float, samples.accel[k]))
    from raysim.io.files import atomic_write_bytes

    return atomic_write_bytes(path, bytes(body))
