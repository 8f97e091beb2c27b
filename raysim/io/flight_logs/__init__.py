"""Flight-controller IMU logs: one reader, :func:`read_imu_log`, for every source.

Every reader returns :class:`raysim.platform.imu.ImuSamples` (the in-memory IMU
record of the project): ``time [sample]`` in seconds on the *source's own
clock* (see each module for its time base), ``gyro [sample, 3]`` angular rate
[rad/s] and ``accel [sample, 3]`` specific force [m/s^2], both in the body
frame B = FRD (forward, right, down; ``docs/conventions.md``).

=====================  ==========================  ================================
source                 module                      time base
=====================  ==========================  ================================
``.csv``               :mod:`raysim.io.imu_log`    the file's ``time_<unit>`` column
``.ulg`` (PX4)         :mod:`.ulog`                ``sensor_combined.timestamp``:
                                                   microseconds since boot
``.bin`` (ArduPilot)   :mod:`.dataflash`           ``IMU.TimeUS``: microseconds since
                                                   boot
ROS 2 bag (folder,     :mod:`.rosbag`              ``header.stamp`` (sec + nanosec),
``.mcap``, ``.db3``)                               the publisher's clock (ROS time)
=====================  ==========================  ================================

Frames: PX4 and ArduPilot log in FRD already; ROS uses FLU (REP 103), turned
into FRD by :func:`flu_to_frd`.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from raysim.platform.imu import ImuSamples

__all__ = ["FLIGHT_LOG_SUFFIXES", "flu_to_frd", "read_imu_log"]

#: File suffixes recognised by :func:`read_imu_log` (a ROS 2 bag may also be a folder).
FLIGHT_LOG_SUFFIXES = (".csv", ".ulg", ".bin", ".mcap", ".db3")

#: FLU -> FRD: a rotation of 180 deg about the common x axis, diag(1, -1, -1).
_FLU_TO_FRD = np.diag([1.0, -1.0, -1.0])


def flu_to_frd(vectors: np.ndarray) -> np.ndarray:
    """Body vectors from FLU (ROS REP 103: x forward, y left, z up) to FRD.

    Parameters
    ----------
    vectors : ndarray, shape ``[..., 3]``
        Vectors in FLU (any unit).

    Returns
    -------
    ndarray, shape ``[..., 3]``
        The same vectors in FRD: ``(x, -y, -z)``. A positive yaw rate about
        the ROS z-up axis (turning left) is a negative yaw rate about FRD z-down.
    """
    v = np.asarray(vectors, dtype=float)
    if v.shape[-1:] != (3,):
        raise ValueError(f"vectors must have shape [..., 3], got {v.shape}")
    return v @ _FLU_TO_FRD


def read_imu_log(path: str | os.PathLike, **kwargs) -> ImuSamples:
    """Read an IMU log of any supported source, dispatched on the file suffix.

    Parameters
    ----------
    path : str or path-like
        ``.csv`` (:func:`raysim.io.imu_log.read_imu_csv`), ``.ulg`` (PX4 ULog,
        :func:`.ulog.read_px4_ulog`), ``.bin`` (ArduPilot DataFlash,
        :func:`.dataflash.read_dataflash_imu`; needs ``raysim[ardupilot]``), or a
        ROS 2 bag: its folder, or a ``.mcap`` / ``.db3`` file inside one
        (:func:`.rosbag.read_ros2_imu`).
    **kwargs
        Passed to the source's reader (e.g. ``topic=`` for a bag, ``instance=``
        for ULog / DataFlash).

    Returns
    -------
    ImuSamples
        ``time [sample]`` [s, the source's clock], ``gyro``/``accel [sample, 3]``
        [rad/s, m/s^2] in FRD.

    Raises
    ------
    ValueError
        The path does not exist or its suffix is none of the above.
    """
    p = Path(path)
    if not p.exists():
        raise ValueError(f"IMU log {str(p)!r} does not exist")
    suffix = p.suffix.lower()
    if p.is_dir() or suffix in (".mcap", ".db3"):
        from raysim.io.flight_logs.rosbag import read_ros2_imu

        return read_ros2_imu(p, **kwargs)
    if suffix == ".csv":
        from raysim.io.imu_log import read_imu_csv

        if kwargs:
            raise ValueError(f"IMU CSV {str(p)!r}: no reader options expected, got "
                             f"{sorted(kwargs)}")
        return read_imu_csv(p)
    if suffix == ".ulg":
        from raysim.io.flight_logs.ulog import read_px4_ulog

        return read_px4_ulog(p, **kwargs)
    if suffix == ".bin":
        from raysim.io.flight_logs.dataflash import read_dataflash_imu

        return read_dataflash_imu(p, **kwargs)
    raise ValueError(f"IMU log {str(p)!r}: unknown suffix {p.suffix!r}; expected one of "
                     f"{list(FLIGHT_LOG_SUFFIXES)} or a ROS 2 bag folder")


def check_increasing(time: np.ndarray, where: str) -> None:
    """Raise ValueError unless the time stamps ``[sample]`` are strictly increasing (>= 2)."""
    if time.size < 2:
        raise ValueError(f"{where}: {time.size} IMU sample(s); at least 2 are needed")
    dt = np.diff(time)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise ValueError(f"{where}: IMU time stamp {k} ({time[k]!r} s) is not after stamp "
                         f"{k - 1} ({time[k - 1]!r} s); time stamps must be strictly increasing")


def microsecond_stamps(samples, writer: str, clock: str) -> np.ndarray:
    """Whole-microsecond stamps ``[sample]`` (int64) of IMU samples for a log writer.

    Parameters
    ----------
    samples : raysim.platform.imu.ImuSamples
    writer : str
        Name of the writer, for messages.
    clock : str
        The log's time field, for messages (``"ULog time stamps"``, ``"DataFlash TimeUS"``).

    Raises
    ------
    ValueError
        ``samples`` is not ImuSamples, a time is negative (the logs count from boot) or two
        times round to the same microsecond.
    """
    from raysim.platform.imu import ImuSamples

    if not isinstance(samples, ImuSamples):
        raise ValueError(f"samples must be ImuSamples, got {type(samples).__name__}")
    t = np.asarray(samples.time, dtype=float)
    check_increasing(t, writer)                     # at least 2 samples, increasing
    if t[0] < 0:
        raise ValueError(f"{clock} are microseconds since boot and must be >= 0; the first "
                         f"sample is at {t[0]!r} s")
    stamps = np.rint(t * 1e6).astype(np.int64)
    check_increasing(stamps.astype(float), f"{writer} (times rounded to 1 us)")
    return stamps
