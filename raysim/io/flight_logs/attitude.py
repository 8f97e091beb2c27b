"""The flight controller's attitude estimate in a log, beside its IMU samples.

:func:`read_attitude_log` reads the attitude a log holds, on the same clock
and with the same time base as the IMU samples of
:func:`raysim.io.flight_logs.read_imu_log` (stamps returned as stored: time
since boot, or Unix epoch; see :func:`raysim.io.flight_logs.time_base`):

=====================  =============================================  =================
source                 fields                                         frames
=====================  =============================================  =================
PX4 ULog               ``vehicle_attitude``: ``timestamp`` [us],      body FRD to NED
                       ``q[4]`` (Hamilton ``w, x, y, z``)
ArduPilot DataFlash    ``ATT`` (else ``AHRS2``): ``TimeUS``           body FRD to NED
                       (``TimeMS``), ``Roll``, ``Pitch``, ``Yaw``
                       [deg], Z-Y-X Euler angles
ROS 2 bag              ``sensor_msgs/msg/Imu.orientation`` (else      body FLU to ENU
                       ``nav_msgs/msg/Odometry.pose.pose.orientation``) (REP 103), turned
                       ``x, y, z, w``, ``header.stamp``               into FRD to NED
=====================  =============================================  =================

An IMU message whose ``orientation_covariance[0]`` is -1 (REP 145: no
orientation) or whose quaternion is all zero carries no attitude. A log
without any attitude gives None: the compensate stage then assumes the
platform level at the first ramp and says so.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from raysim.io.flight_logs import (
    ENU_TO_NED,
    ROS_BAG_SUFFIXES,
    check_increasing,
    median_rate,
    time_base,
)

__all__ = ["AttitudeLog", "read_attitude_log"]

#: FLU <-> FRD (its own inverse).
_FLU_TO_FRD = np.diag([1.0, -1.0, -1.0])


@dataclass(frozen=True, eq=False)
class AttitudeLog:
    """A log's attitude estimate ``R_WB`` (body FRD to world NED) over time.

    Attributes
    ----------
    time : ndarray, shape ``[sample]``
        Stamps on the log's clock [s] (the IMU's clock).
    rotation : scipy.spatial.transform.Rotation, ``[sample]``
        ``R_WB`` at each stamp.
    source : str
        File, message or topic, rate and time base.
    """

    time: np.ndarray
    rotation: Rotation
    source: str

    @property
    def rate(self) -> float:
        """Median sample rate [Hz]."""
        return median_rate(self.time)

    def at(self, t: float) -> Rotation:
        """``R_WB`` at log time ``t`` [s], spherical interpolation between the stamps.

        Raises
        ------
        ValueError
            ``t`` is outside the logged attitude's time span.
        """
        t = float(t)
        if not (self.time[0] <= t <= self.time[-1]):
            raise ValueError(f"the attitude of {self.source} spans {self.time[0]:.6f} .. "
                             f"{self.time[-1]:.6f} s, not {t:.6f} s (the first ramp on the "
                             f"log's clock); give --initial-attitude-deg")
        return Slerp(self.time, self.rotation)([t])[0]

    def euler_deg(self, t: float) -> tuple[float, float, float]:
        """``(yaw, pitch, roll)`` [deg] (Z-Y-X) at log time ``t`` [s]."""
        return tuple(float(v) for v in self.at(t).as_euler("ZYX", degrees=True))


def _make(time, rotation: Rotation, where: str, what: str) -> AttitudeLog:
    t = np.asarray(time, dtype=float)
    order = np.argsort(t, kind="stable")
    t, rotation = t[order], rotation[order]
    keep = np.concatenate([[True], np.diff(t) > 0]) if t.size else np.zeros(0, bool)
    t, rotation = t[keep], rotation[keep]
    check_increasing(t, f"{where} ({what})")
    return AttitudeLog(t, rotation, f"{where} ({what}, {median_rate(t):.4g} Hz, "
                                    f"{time_base(t)})")


def _unit_quats(q: np.ndarray) -> np.ndarray:
    """Rows of ``q [sample, 4]`` that are finite and of non-zero norm (mask)."""
    n = np.linalg.norm(q, axis=1)
    return np.isfinite(n) & (n > 0.5)


def _ulog(path: Path) -> AttitudeLog | None:
    from pyulog import ULog

    try:
        log = ULog(str(path), ["vehicle_attitude"])
    except Exception as exc:  # pyulog raises bare Exceptions on corrupt files
        raise ValueError(f"{str(path)!r}: cannot parse ULog file: {exc}") from None
    data = [d for d in log.data_list if d.name == "vehicle_attitude"]
    if not data:
        return None
    d = min(data, key=lambda x: x.multi_id).data
    q = np.column_stack([np.asarray(d[f"q[{i}]"], dtype=float) for i in range(4)])
    ok = _unit_quats(q)
    if ok.sum() < 2:
        return None
    t = np.asarray(d["timestamp"], dtype=np.uint64).astype(float)[ok] * 1e-6
    rot = Rotation.from_quat(q[ok][:, [1, 2, 3, 0]])        # PX4 w,x,y,z -> scipy x,y,z,w
    return _make(t, rot, str(path), "PX4 ULog vehicle_attitude")


def _dataflash(path: Path) -> AttitudeLog | None:
    from raysim.io.flight_logs.dataflash import _dfreader, _stamp

    log = _dfreader().DFReader_binary(str(path))
    rows: dict = {"ATT": [], "AHRS2": []}
    try:
        while True:
            msg = log.recv_match(type=list(rows))
            if msg is None:
                break
            fields = msg.get_fieldnames()
            rows[msg.get_type()].append((_stamp(msg, fields), msg.Yaw, msg.Pitch, msg.Roll))
    finally:
        log.close()
    for name, r in rows.items():
        if len(r) >= 2:
            a = np.asarray(r, dtype=float)
            rot = Rotation.from_euler("ZYX", a[:, 1:], degrees=True)
            return _make(a[:, 0], rot, str(path), f"ArduPilot DataFlash {name}")
    return None


def _ros(path: Path, topic: str | None) -> AttitudeLog | None:
    from raysim.io.flight_logs.rosbag import IMU_MSGTYPE, open_bag

    odom = "nav_msgs/msg/Odometry"
    reader = open_bag(path)
    try:
        found = {}
        for kind in (IMU_MSGTYPE, odom):
            conns = [c for c in reader.connections if c.msgtype == kind
                     and (topic is None or kind == odom or c.topic == topic)]
            if not conns:            # no connections would read every message
                continue
            stamps, quats = [], []
            for conn, _, raw in reader.messages(connections=conns):
                msg = reader.deserialize(raw, conn.msgtype)
                if kind == IMU_MSGTYPE:
                    if float(msg.orientation_covariance[0]) == -1.0:
                        continue
                    o = msg.orientation
                else:
                    o = msg.pose.pose.orientation
                stamps.append(int(msg.header.stamp.sec) * 1_000_000_000
                              + int(msg.header.stamp.nanosec))
                quats.append((o.x, o.y, o.z, o.w))
            q = np.asarray(quats, dtype=float).reshape(-1, 4)
            ok = _unit_quats(q)
            if ok.sum() >= 2:
                found[kind] = (np.asarray(stamps, dtype=np.int64)[ok] * 1e-9, q[ok],
                               sorted({c.topic for c in conns}))
                break
    finally:
        reader.close()
    if not found:
        return None
    kind, (t, q, topics) = next(iter(found.items()))
    r_enu_flu = Rotation.from_quat(q).as_matrix()
    r_ned_frd = ENU_TO_NED @ r_enu_flu @ _FLU_TO_FRD       # R_WB in NED / FRD
    return _make(t, Rotation.from_matrix(r_ned_frd), str(path),
                 f"{'ROS 1' if path.suffix.lower() == '.bag' else 'ROS 2'} {kind} "
                 f"{', '.join(topics)} orientation, ENU/FLU turned into NED/FRD")


def read_attitude_log(path: str | os.PathLike, topic: str | None = None) -> AttitudeLog | None:
    """The attitude estimate of a flight log, or None when it holds none (module docstring).

    Parameters
    ----------
    path : str or path-like
        ``.ulg``, ``.bin``, a ROS 2 bag (folder, ``.mcap``, ``.db3``), a ROS 1
        ``.bag`` or ``.csv``
        (the project's IMU CSV holds no attitude: None).
    topic : str, optional
        ROS 2: the ``sensor_msgs/msg/Imu`` topic whose orientation to read
        (the IMU topic); ignored for the other sources.

    Returns
    -------
    AttitudeLog or None
    """
    p = Path(path)
    suffix = p.suffix.lower()
    if p.is_dir() or suffix in ROS_BAG_SUFFIXES:
        return _ros(p, topic)
    if suffix == ".ulg":
        return _ulog(p)
    if suffix == ".bin":
        return _dataflash(p)
    return None
