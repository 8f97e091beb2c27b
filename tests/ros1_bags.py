"""ROS 1 bags as a ROS 1 IMU driver (mavros, a VectorNav or Xsens node) records them.

The project reads ROS 1 bags but writes none; the tests write theirs with
``rosbags``'s ROS 1 writer and Noetic's message definitions: ``sensor_msgs/Imu``
in FLU (REP 103), the orientation body FLU to ENU, ``header.seq`` counting.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from raysim.io.flight_logs import ENU_TO_NED, flu_to_frd

IMU = "sensor_msgs/msg/Imu"


def write_ros1_imu(path, samples, topics=("/mavros/imu/data",), orientation=None,
                   epoch_ns: int = 0) -> Path:
    """Write ``samples`` (FRD, SI) to each topic of a new ROS 1 bag ``path``.

    ``orientation``: ``R_WB`` (FRD to NED) per sample, or None (REP 145: unknown).
    """
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS1_NOETIC)
    t = ts.types
    stamps = np.rint(np.asarray(samples.time) * 1e9).astype(np.int64) + epoch_ns
    gyro, accel = flu_to_frd(samples.gyro), flu_to_frd(samples.accel)     # FRD -> FLU
    cov = np.zeros(9)
    quat = np.tile([0.0, 0.0, 0.0, 1.0], (stamps.size, 1))
    if orientation is None:
        cov[0] = -1.0
    else:
        flu = np.diag([1.0, -1.0, -1.0])
        quat = Rotation.from_matrix(ENU_TO_NED @ orientation.as_matrix() @ flu).as_quat()
    path = Path(path)
    with Writer(path) as writer:
        conns = [writer.add_connection(topic, IMU, typestore=ts) for topic in topics]
        for k, ns in enumerate(stamps):
            sec, nsec = divmod(int(ns), 1_000_000_000)
            vec = t["geometry_msgs/msg/Vector3"]
            msg = t[IMU](
                header=t["std_msgs/msg/Header"](
                    seq=k, stamp=t["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec),
                    frame_id="base_link"),
                orientation=t["geometry_msgs/msg/Quaternion"](*quat[k]),
                orientation_covariance=cov,
                angular_velocity=vec(*gyro[k]), angular_velocity_covariance=np.zeros(9),
                linear_acceleration=vec(*accel[k]),
                linear_acceleration_covariance=np.zeros(9))
            for conn in conns:
                writer.write(conn, int(ns), ts.serialize_ros1(msg, IMU))
    return path
