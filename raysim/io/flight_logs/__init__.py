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
``.ulg`` (PX4)         :mod:`.ulog`                ``timestamp`` / ``timestamp_sample``:
                                                   microseconds since boot (some
                                                   logs: since the Unix epoch)
``.bin`` (ArduPilot)   :mod:`.dataflash`           ``TimeUS`` (``TimeMS`` in 2014-15
                                                   firmware): since boot
ROS 2 bag (folder,     :mod:`.rosbag`              ``header.stamp`` (sec + nanosec),
``.mcap``, ``.db3``);                              the publisher's clock (ROS time)
ROS 1 ``.bag``
=====================  ==========================  ================================

Sources inside a log: each reader lists the IMU sources the file holds (PX4
topics ``sensor_gyro_fifo`` + ``sensor_accel_fifo``, ``vehicle_imu``,
``sensor_combined`` and their instances; ArduPilot ``ISBH``/``ISBD`` batches,
``GYR`` + ``ACC``, ``IMU``), reads the complete ones (gyro and accelerometer
over the same time) and returns the one with the highest sample rate unless
``topic`` / ``instance`` choose. The choice (topic, instance, rate, time base)
is written into :attr:`ImuSamples.source <raysim.platform.imu.ImuSamples>`.

Time base: :func:`time_base` tells time since boot from Unix-epoch stamps
(a first stamp between 2000-01-01 and 2100-01-01 in seconds is taken for
epoch time: no flight controller runs for 30 years). Either way the times are
returned as they are stored; the clock offset to the radar
(``--time-offset``) is then of the size of the stamps (docs/recordings.md).

Frames: PX4 and ArduPilot log in FRD already; ROS uses FLU (REP 103), turned
into FRD by :func:`flu_to_frd` (and ENU world into NED by :data:`ENU_TO_NED`).

Attitude: :func:`raysim.io.flight_logs.attitude.read_attitude_log` reads the
flight controller's attitude estimate the same file holds (PX4
``vehicle_attitude``, ArduPilot ``ATT`` / ``AHRS2``, ROS orientation), on
the same clock as its IMU samples.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from raysim.platform.imu import ImuSamples

__all__ = ["FLIGHT_LOG_SUFFIXES", "ROS_BAG_SUFFIXES", "ENU_TO_NED", "flu_to_frd", "read_imu_log",
           "time_base", "choose_source"]

#: Unix time [s] of 2000-01-01 and 2100-01-01: a first stamp between them is epoch time.
EPOCH_RANGE_S = (946_684_800.0, 4_102_444_800.0)

#: File suffixes recognised by :func:`read_imu_log` (a ROS 2 bag may also be a folder).
FLIGHT_LOG_SUFFIXES = (".csv", ".ulg", ".bin", ".mcap", ".db3", ".bag")
#: Suffixes of ROS bag files (a rosbag2 folder is given as the folder).
ROS_BAG_SUFFIXES = (".mcap", ".db3", ".bag")

#: FLU -> FRD: a rotation of 180 deg about the common x axis, diag(1, -1, -1).
_FLU_TO_FRD = np.diag([1.0, -1.0, -1.0])
#: ENU -> NED for world vectors (swap x and y, negate z); its own inverse.
ENU_TO_NED = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


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


def time_base(time: np.ndarray) -> str:
    """``"unix epoch"`` or ``"time since boot"`` for stamps ``[sample]`` [s] (module docstring)."""
    t0 = float(np.asarray(time, dtype=float).ravel()[0]) if np.size(time) else 0.0
    return "unix epoch" if EPOCH_RANGE_S[0] <= t0 <= EPOCH_RANGE_S[1] else "time since boot"


def median_rate(time: np.ndarray) -> float:
    """Sample rate [Hz] from the median interval of stamps ``[sample]`` [s] (0 if < 2)."""
    t = np.asarray(time, dtype=float)
    if t.size < 2:
        return 0.0
    d = float(np.median(np.diff(t)))
    return 1.0 / d if d > 0 else 0.0


def choose_source(where: str, candidates: list, topic: str | None, instance: int | None,
                  unusable: dict) -> tuple:
    """The candidate with the highest rate among those ``topic`` / ``instance`` allow.

    Parameters
    ----------
    where : str
        The file, for messages.
    candidates : list of (str, int, float, object)
        ``(topic, instance, rate [Hz], payload)`` of each complete source.
    topic, instance : optional
        The user's choice (None: any).
    unusable : dict
        ``"topic[instance]" -> reason`` of the sources present but incomplete.

    Raises
    ------
    ValueError
        Nothing matches; the message lists the sources present with their
        rates and the unusable ones with their reasons.
    """
    ok = [c for c in candidates if (topic is None or c[0] == topic)
          and (instance is None or c[1] == instance)]
    if not ok:
        present = [f"{c[0]}[{c[1]}] at {c[2]:.4g} Hz" for c in candidates]
        asked = ", ".join(x for x in (f"topic={topic!r}" if topic is not None else "",
                                      f"instance={instance!r}" if instance is not None
                                      else "") if x) or "any source"
        raise ValueError(f"{where}: no IMU source matches {asked}; complete sources present: "
                         f"{present or 'none'}"
                         + (f"; present but unusable: {unusable}" if unusable else ""))
    return max(ok, key=lambda c: c[2])


def read_imu_log(path: str | os.PathLike, **kwargs) -> ImuSamples:
    """Read an IMU log of any supported source, dispatched on the file suffix.

    Parameters
    ----------
    path : str or path-like
        ``.csv`` (:func:`raysim.io.imu_log.read_imu_csv`), ``.ulg`` (PX4 ULog,
        :func:`.ulog.read_px4_ulog`), ``.bin`` (ArduPilot DataFlash,
        :func:`.dataflash.read_dataflash_imu`; needs ``raysim[ardupilot]``), or a
        ROS 2 bag: its folder, or a ``.mcap`` / ``.db3`` file inside one, or a
        ROS 1 ``.bag`` (:func:`.rosbag.read_ros_imu`).
    **kwargs
        Passed to the source's reader: ``topic=`` (PX4 topic, ArduPilot
        message, ROS topic) and ``instance=`` (PX4 / ArduPilot); None values
        are dropped (the reader's choice: the best source present).

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
    kwargs = {k: v for k, v in kwargs.items() if v is not None}
    p = Path(path)
    if not p.exists():
        raise ValueError(f"IMU log {str(p)!r} does not exist")
    suffix = p.suffix.lower()
    if p.is_dir() or suffix in ROS_BAG_SUFFIXES:
        from raysim.io.flight_logs.rosbag import read_ros_imu

        if "instance" in kwargs:
            raise ValueError(f"IMU log {str(p)!r}: a ROS 2 bag has topics, not instances; got "
                             f"instance={kwargs['instance']!r} (choose with topic=)")
        return read_ros_imu(p, **kwargs)
    if suffix == ".csv":
        from raysim.io.imu_log import PX4_EXPORT, csv_header, export_layout, read_imu_csv

        if kwargs:
            raise ValueError(f"IMU CSV {str(p)!r}: no reader options expected, got "
                             f"{sorted(kwargs)}")
        if export_layout(csv_header(p)[0]) == PX4_EXPORT:
            from raysim.io.flight_logs.ulog import read_px4_csv_export

            return read_px4_csv_export(p)
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
                         f"sample is at {float(t[0]):.6f} s")
    stamps = np.rint(t * 1e6).astype(np.int64)
    check_increasing(stamps.astype(float), f"{writer} (times rounded to 1 us)")
    return stamps
