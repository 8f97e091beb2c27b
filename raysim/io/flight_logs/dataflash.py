"""ArduPilot DataFlash logs (``.bin``): ``IMU`` messages, read with ``pymavlink``.

``pymavlink`` is LGPL-3.0 and therefore an optional extra: install it with
``pip install raysim[ardupilot]``; it is imported only when a ``.bin`` file is
read.

Fields of the ``IMU`` message (ArduPilot ``AP_InertialSensor`` logging):

===========  ===============================================================
``TimeUS``   uint64, microseconds since boot (``AP_HAL::micros64``)
``I``        uint8, IMU instance (older logs: messages ``IMU``, ``IMU2``, ...)
``GyrX..Z``  float32 angular rate [rad/s], body FRD
``AccX..Z``  float32 specific force [m/s^2], body FRD
===========  ===============================================================

Time base: ``time = TimeUS * 1e-6`` [s since boot], the time the sample was
logged (ArduPilot logs the filtered sensor values at the main loop rate; raw
``GYR``/``ACC`` messages at the sensor rate are not read here). ArduPilot's
body frame is FRD, so no axis conversion is made.

:func:`write_dataflash_imu` writes a minimal file (an ``FMT`` message for
``IMU`` then the data messages, each ``0xA3 0x95 <type>`` + payload), the
layout pymavlink's ``DFReader_binary`` parses; it needs no pymavlink.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path

import numpy as np

from raysim.io.flight_logs import check_increasing, microsecond_stamps
from raysim.platform.imu import ImuSamples

__all__ = ["ARDUPILOT_EXTRA", "read_dataflash_imu", "write_dataflash_imu"]

#: The pip extra that installs pymavlink.
ARDUPILOT_EXTRA = "raysim[ardupilot]"

_HEAD = b"\xa3\x95"
_FMT_TYPE = 0x80
_IMU_TYPE = 0x81
_IMU_FORMAT = "QBffffff"
_IMU_COLUMNS = "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ"
_IMU_RECORD = struct.Struct("<QBffffff")


def _dfreader():
    try:
        from pymavlink import DFReader
    except ImportError:
        raise ImportError("reading ArduPilot DataFlash (.bin) logs needs pymavlink, an "
                          f"optional dependency (LGPL): pip install {ARDUPILOT_EXTRA}") from None
    return DFReader


def read_dataflash_imu(path: str | os.PathLike, instance: int = 0) -> ImuSamples:
    """Read the ``IMU`` messages of one IMU instance of an ArduPilot ``.bin`` log.

    Parameters
    ----------
    path : str or path-like
        DataFlash ``.bin`` file.
    instance : int
        IMU instance (field ``I``; in old logs without it, ``IMU`` is 0,
        ``IMU2`` is 1, ``IMU3`` is 2).

    Returns
    -------
    ImuSamples
        ``time [sample]`` [s since boot], ``gyro [sample, 3]`` [rad/s],
        ``accel [sample, 3]`` [m/s^2], FRD.

    Raises
    ------
    ImportError
        pymavlink is not installed (the message names the extra).
    ValueError
        Not a DataFlash file, no ``IMU`` messages of that instance, or time
        stamps that do not increase.
    """
    path = Path(path)
    with path.open("rb") as fh:
        if fh.read(2) != _HEAD:
            raise ValueError(f"{str(path)!r} is not an ArduPilot DataFlash log (no 0xA3 0x95 "
                             f"message header)")
    dfreader = _dfreader()
    log = dfreader.DFReader_binary(str(path))
    names = ["IMU", "IMU2", "IMU3"]
    rows, seen = [], set()
    while True:
        msg = log.recv_match(type=names)
        if msg is None:
            break
        name = msg.get_type()
        fields = msg.get_fieldnames()
        inst = int(msg.I) if "I" in fields else names.index(name)
        seen.add(inst)
        if inst == instance:
            rows.append((int(msg.TimeUS), msg.GyrX, msg.GyrY, msg.GyrZ,
                         msg.AccX, msg.AccY, msg.AccZ))
    if not rows:
        raise ValueError(f"{str(path)!r}: no IMU messages of instance={instance}; instances "
                         f"present: {sorted(seen)}")
    us = np.array([r[0] for r in rows], dtype=np.int64)
    vals = np.array([r[1:] for r in rows], dtype=float)
    time = us * 1e-6
    check_increasing(time, f"{str(path)!r} (IMU.TimeUS)")
    rate = 1.0 / float(np.median(np.diff(time)))
    return ImuSamples(time, vals[:, :3], vals[:, 3:], spec=None, truth=None,
                      source=f"{path} (ArduPilot DataFlash IMU)", rate=rate)


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
