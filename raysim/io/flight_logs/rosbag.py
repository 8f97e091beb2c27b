"""ROS bags: ``sensor_msgs/msg/Imu`` messages, read (ROS 1, ROS 2) and written (ROS 2).

Both with ``rosbags``.

Fields used: ``header.stamp`` (``sec`` + ``nanosec``), ``angular_velocity``
[rad/s] and ``linear_acceleration`` [m/s^2] (``geometry_msgs/Vector3``).
REP 145 asks IMU drivers to publish the specific force (gravity included,
``+9.81`` on z when level), which is what raysim calls ``accel``.

Time base: ``header.stamp``, the time the driver assigned to the sample on the
publisher's clock (ROS time: usually Unix time, or ``/clock`` in simulation),
not the bag's receive time. It is returned in seconds relative to
``epoch_ns`` (default 0): integer nanoseconds are subtracted before the
conversion to float64, so a Unix-time stamp keeps sub-microsecond resolution
only when ``epoch_ns`` is close to it.

Frame: REP 103 body axes are FLU (x forward, y left, z up); the vectors are
turned into FRD by :func:`raysim.io.flight_logs.flu_to_frd`, ``(x, -y, -z)``.
A ``frame_id`` other than the body frame is not rotated (no TF lookup).

Bags: a rosbag2 folder (``metadata.yaml`` with a ``.db3`` SQLite3 or ``.mcap``
file), one of its storage files, a standalone ``.mcap`` file (an MCAP file
carries its own schemas and channels, so no ``metadata.yaml`` is needed; a
``.db3`` file without its folder's ``metadata.yaml`` is refused with a message
saying so), or a ROS 1 ``.bag`` file (its connections carry their message
definitions; ``sensor_msgs/Imu`` has the same fields, its ``time`` stamps are
read as ``sec`` + ``nanosec``). The result's ``source`` names the topic, the rate and the time base
(:func:`raysim.io.flight_logs.time_base`: ROS time is usually Unix time).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from raysim.io.flight_logs import (
    ENU_TO_NED,
    check_increasing,
    flu_to_frd,
    median_rate,
    time_base,
)
from raysim.platform.imu import ImuSamples

__all__ = ["IMU_MSGTYPE", "open_bag", "read_ros_imu", "write_ros2_imu"]

#: Message type of IMU samples (``rosbags`` names ROS 1's ``sensor_msgs/Imu`` the same).
IMU_MSGTYPE = "sensor_msgs/msg/Imu"


def _typestore():
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_HUMBLE)


def open_bag(path: Path):
    """An open ``rosbags`` ``AnyReader`` of a bag given as in the module docstring.

    Raises
    ------
    ValueError
        A ``.db3`` file without its folder, or a file ``rosbags`` cannot read.
    """
    from rosbags.highlevel import AnyReader

    bag = path if path.is_dir() else path.parent
    if not path.is_dir() and not (path.parent / "metadata.yaml").is_file():
        if path.suffix.lower() not in (".mcap", ".bag"):
            raise ValueError(f"{str(path)!r}: a rosbag2 {path.suffix} storage file needs its "
                             f"bag folder's metadata.yaml beside it (none in "
                             f"{str(path.parent)!r}); give the bag folder, or record to MCAP")
        bag = path            # an MCAP file or a ROS 1 bag holds its own message definitions
    try:
        reader = AnyReader([bag], default_typestore=_typestore())
        reader.open()
    except Exception as exc:  # rosbags raises its own error types per storage
        raise ValueError(f"{str(path)!r} is not a readable ROS bag: {exc}") from None
    return reader


def read_ros_imu(path: str | os.PathLike, topic: str | None = None,
                 epoch_ns: int = 0) -> ImuSamples:
    """Read the ``sensor_msgs/msg/Imu`` messages of one topic of a ROS 1 or ROS 2 bag.

    Parameters
    ----------
    path : str or path-like
        ROS 2 bag folder, a ``.mcap`` / ``.db3`` file inside one, a standalone
        ``.mcap`` file, or a ROS 1 ``.bag`` file.
    topic : str or None
        IMU topic; None takes the only ``sensor_msgs/msg/Imu`` topic.
    epoch_ns : int
        Subtracted from the header stamps [ns] before conversion to seconds.

    Returns
    -------
    ImuSamples
        ``time [sample]`` [s, header stamps minus ``epoch_ns``],
        ``gyro [sample, 3]`` [rad/s], ``accel [sample, 3]`` [m/s^2], FRD.

    Raises
    ------
    ValueError
        Not a bag, no IMU topic or several without ``topic``, an unknown
        topic, or header stamps that do not increase.
    """
    path = Path(path)
    reader = open_bag(path)
    ros = "ROS 1" if path.suffix.lower() == ".bag" else "ROS 2"
    try:
        imu_topics = sorted({c.topic for c in reader.connections if c.msgtype == IMU_MSGTYPE})
        if topic is None:
            if len(imu_topics) != 1:
                raise ValueError(f"{str(path)!r}: expected exactly one {IMU_MSGTYPE} topic "
                                 f"when topic is not given, found {imu_topics}")
            topic = imu_topics[0]
        elif topic not in imu_topics:
            raise ValueError(f"{str(path)!r}: topic={topic!r} is not a {IMU_MSGTYPE} topic; "
                             f"IMU topics are {imu_topics}")
        conns = [c for c in reader.connections if c.topic == topic]
        stamps, gyro, accel = [], [], []
        for conn, _, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            stamps.append(int(msg.header.stamp.sec) * 1_000_000_000
                          + int(msg.header.stamp.nanosec))
            w, a = msg.angular_velocity, msg.linear_acceleration
            gyro.append((w.x, w.y, w.z))
            accel.append((a.x, a.y, a.z))
    finally:
        reader.close()
    time = (np.asarray(stamps, dtype=np.int64) - int(epoch_ns)) * 1e-9
    check_increasing(time, f"{str(path)!r} topic {topic!r} (header.stamp)")
    gyro_frd = flu_to_frd(np.asarray(gyro, dtype=float).reshape(-1, 3))
    accel_frd = flu_to_frd(np.asarray(accel, dtype=float).reshape(-1, 3))
    rate = median_rate(time)
    return ImuSamples(time, gyro_frd, accel_frd, spec=None, truth=None,
                      source=f"{path} ({ros} {topic}, {rate:.4g} Hz, "
                      f"{time_base(time + epoch_ns * 1e-9)})", rate=rate)


def write_ros2_imu(path: str | os.PathLike, samples: ImuSamples, topic: str = "/imu",
                   storage: str = "sqlite3", frame_id: str = "base_link",
                   epoch_ns: int = 0, orientation=None) -> Path:
    """Write IMU samples as ``sensor_msgs/msg/Imu`` messages of a new ROS 2 bag.

    Parameters
    ----------
    path : str or path-like
        Bag folder to create (must not exist).
    samples : ImuSamples
        ``time [sample]`` [s], ``gyro``/``accel [sample, 3]`` in FRD
        [rad/s, m/s^2]; written in FLU (REP 103).
    topic : str
        Topic name.
    storage : {"sqlite3", "mcap"}
        rosbag2 storage plugin.
    frame_id : str
        ``header.frame_id``.
    epoch_ns : int
        Added to the times [ns] for the header stamps (which must be >= 0).
    orientation : scipy.spatial.transform.Rotation, optional
        ``R_WB`` (body FRD to NED) at every sample, written as the REP 103
        orientation (body FLU to ENU); default none (REP 145:
        ``orientation_covariance[0] = -1``).

    Returns
    -------
    pathlib.Path
        The bag folder.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer
    from scipy.spatial.transform import Rotation

    if not isinstance(samples, ImuSamples):
        raise ValueError(f"samples must be ImuSamples, got {type(samples).__name__}")
    plugins = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}
    if storage not in plugins:
        raise ValueError(f"storage must be one of {list(plugins)}, got {storage!r}")
    path = Path(path)
    if path.exists():
        raise ValueError(f"bag folder {str(path)!r} already exists")
    stamps = np.rint(np.asarray(samples.time, dtype=float) * 1e9).astype(np.int64) + epoch_ns
    if stamps[0] < 0:
        raise ValueError(f"header stamps must be >= 0 ns, the first is {int(stamps[0])}")
    ts = _typestore()
    imu_t = ts.types[IMU_MSGTYPE]
    hdr_t, time_t = ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    vec_t, quat_t = ts.types["geometry_msgs/msg/Vector3"], ts.types["geometry_msgs/msg/Quaternion"]
    gyro, accel = flu_to_frd(samples.gyro), flu_to_frd(samples.accel)   # FRD -> FLU: same map
    unknown = np.zeros(9)
    unknown[0] = -1.0   # REP 145: orientation not provided
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (stamps.size, 1))
    if orientation is not None:
        if len(orientation) != stamps.size:
            raise ValueError(f"orientation has {len(orientation)} rotations, expected one per "
                             f"sample ({stamps.size})")
        flu = np.diag([1.0, -1.0, -1.0])
        quat = Rotation.from_matrix(ENU_TO_NED @ orientation.as_matrix() @ flu).as_quat()
        unknown = np.zeros(9)
    with Writer(path, version=9, storage_plugin=plugins[storage]) as writer:
        conn = writer.add_connection(topic, IMU_MSGTYPE, typestore=ts)
        for k, ns in enumerate(stamps):
            sec, nsec = divmod(int(ns), 1_000_000_000)
            msg = imu_t(header=hdr_t(stamp=time_t(sec=sec, nanosec=nsec), frame_id=frame_id),
                        orientation=quat_t(x=quat[k, 0], y=quat[k, 1], z=quat[k, 2],
                                           w=quat[k, 3]),
                        orientation_covariance=unknown,
                        angular_velocity=vec_t(x=gyro[k, 0], y=gyro[k, 1], z=gyro[k, 2]),
                        angular_velocity_covariance=np.zeros(9),
                        linear_acceleration=vec_t(x=accel[k, 0], y=accel[k, 1], z=accel[k, 2]),
                        linear_acceleration_covariance=np.zeros(9))
            writer.write(conn, int(ns), ts.serialize_cdr(msg, IMU_MSGTYPE))
    return path
