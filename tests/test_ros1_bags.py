"""ROS 1 bags (``.bag``): the IMU and its orientation read as from a ROS 2 bag of the same samples.

Many drone set-ups still log with ROS 1 (mavros on Noetic): ``/mavros/imu/data``
(with the flight controller's orientation) beside ``/mavros/imu/data_raw``.
The bag stores float64 values and nanosecond stamps, as a ROS 2 bag does, so
both must read back the same numbers.
"""

from __future__ import annotations

import numpy as np
import pytest
from ros1_bags import write_ros1_imu
from scipy.spatial.transform import Rotation

from raysim.io import read_imu_log
from raysim.io.flight_logs.attitude import read_attitude_log
from raysim.io.flight_logs.rosbag import write_ros2_imu
from raysim.platform.imu import ImuSamples, simulate_imu
from raysim.platform.motion import sinusoid

#: ROS stamps are whole nanoseconds; Unix-time stamps of 1.7e9 s in float64 keep 0.24 us [s].
EPOCH_STAMP_S = 0.5e-6
#: Two quaternion round trips (FRD/NED -> FLU/ENU -> FRD/NED) in float64 [rad].
ROTATION_RAD = 1e-12


def _samples() -> tuple[ImuSamples, Rotation]:
    traj = sinusoid("roll", np.deg2rad(3), 6.0)
    s = simulate_imu(traj, "consumer_mems", rate=250.0, start=0.0, end=0.2, seed=5)
    s = ImuSamples(s.time + 1_700_000_000.0, s.gyro, s.accel)
    att = Rotation.from_euler("ZYX", np.column_stack([
        np.full(s.time.size, 0.6), 0.02 * np.sin(9.0 * (s.time - s.time[0])),
        np.full(s.time.size, -0.03)]))
    return s, att


def test_ros1_bag_reads_as_a_ros2_bag_of_the_same_samples(tmp_path):
    s, att = _samples()
    ros1 = read_imu_log(write_ros1_imu(tmp_path / "f.bag", s, orientation=att))
    ros2 = read_imu_log(write_ros2_imu(tmp_path / "bag", s, storage="mcap", orientation=att))
    np.testing.assert_allclose(ros1.time, s.time, rtol=0, atol=EPOCH_STAMP_S)
    np.testing.assert_array_equal(ros1.time, ros2.time)
    np.testing.assert_array_equal(ros1.gyro, ros2.gyro)
    np.testing.assert_array_equal(ros1.accel, ros2.accel)
    np.testing.assert_allclose(ros1.gyro, s.gyro, rtol=0, atol=1e-15)
    assert "ROS 1 /mavros/imu/data" in ros1.source and "250 Hz" in ros1.source
    assert "unix epoch" in ros1.source
    a1 = read_attitude_log(tmp_path / "f.bag")
    assert a1 is not None and "ROS 1" in a1.source
    err = (a1.rotation * att.inv()).magnitude()
    assert float(err.max()) < ROTATION_RAD


def test_mavros_topics_are_chosen_by_name(tmp_path):
    s, _ = _samples()
    bag = write_ros1_imu(tmp_path / "m.bag", s,
                         topics=("/mavros/imu/data", "/mavros/imu/data_raw"))
    with pytest.raises(ValueError, match=r"exactly one .*'/mavros/imu/data', "
                                         r"'/mavros/imu/data_raw'"):
        read_imu_log(bag)
    raw = read_imu_log(bag, topic="/mavros/imu/data_raw")
    assert "/mavros/imu/data_raw" in raw.source
    np.testing.assert_allclose(raw.gyro, s.gyro, rtol=0, atol=1e-15)
    assert read_attitude_log(bag) is None          # REP 145: orientation not provided


def test_a_file_that_is_not_a_bag_is_named(tmp_path):
    bad = tmp_path / "flight.bag"
    bad.write_bytes(b"#ROSBAG V1.2\n" + bytes(64))
    with pytest.raises(ValueError, match=r"flight\.bag' is not a readable ROS bag"):
        read_imu_log(bad)
