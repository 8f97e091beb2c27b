"""Flight-controller IMU logs: PX4 ULog, ROS 2 bags, ArduPilot DataFlash and the IMU CSV.

The same simulated motion is written in every format and read back through the
one reader :func:`raysim.io.read_imu_log`; each format must return the samples
within its own storage precision, in the body frame FRD.
"""

from __future__ import annotations

import struct
import sys

import numpy as np
import pytest

from raysim.io import read_imu_csv, read_imu_log, write_imu_csv
from raysim.io.flight_logs import flu_to_frd
from raysim.io.flight_logs.dataflash import write_dataflash_imu
from raysim.io.flight_logs.rosbag import IMU_MSGTYPE, write_ros2_imu
from raysim.io.flight_logs.ulog import read_px4_ulog, write_px4_ulog
from raysim.platform.imu import ImuSamples, simulate_imu
from raysim.platform.motion import sinusoid

#: Unit roundoff of IEEE float32 (round to nearest): |fl(x) - x| <= u |x| with
#: u = 2^-24 (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed.,
#: Theorem 2.2). ULog and DataFlash store the IMU values as float32.
FLOAT32_UNIT_ROUNDOFF = 2.0 ** -24
#: ULog / DataFlash stamps are whole microseconds: at most half a step away [s].
MICROSECOND_ROUNDING_S = 0.5e-6
#: ROS stamps are whole nanoseconds [s].
NANOSECOND_ROUNDING_S = 0.5e-9
#: float64 spacing allowance for times of order 1 s and their 1e-6 / 1e-9 scaling.
TIME_FLOAT64_S = 1e-15


def _motion(start: float = 0.0) -> ImuSamples:
    """Consumer-MEMS IMU on a yaw sinusoid (noise, bias: every digit matters), 1 kHz, 60 ms."""
    traj = sinusoid("yaw", np.deg2rad(4), 7.0)
    return simulate_imu(traj, "consumer_mems", rate=1000.0, start=start, end=start + 0.06,
                        seed=3)


def _within_float32(back: np.ndarray, ref: np.ndarray) -> bool:
    return bool(np.all(np.abs(back - ref) <= FLOAT32_UNIT_ROUNDOFF * np.abs(ref)))


def _write_all(tmp_path, s: ImuSamples) -> dict:
    paths = {"csv": write_imu_csv(tmp_path / "imu.csv", s),
             "ulog": write_px4_ulog(tmp_path / "imu.ulg", s),
             "bag_sqlite3": write_ros2_imu(tmp_path / "bag_db3", s, storage="sqlite3"),
             "bag_mcap": write_ros2_imu(tmp_path / "bag_mcap", s, storage="mcap"),
             "dataflash": write_dataflash_imu(tmp_path / "imu.bin", s)}
    return paths


def test_same_motion_in_every_format_reads_back_the_same(tmp_path):
    s = _motion()
    paths = _write_all(tmp_path, s)
    back = {}
    for fmt, path in paths.items():
        if fmt == "dataflash" and not _have_pymavlink():
            continue
        back[fmt] = read_imu_log(path)
    # CSV: shortest round-trip decimals, exact
    np.testing.assert_array_equal(back["csv"].time, s.time)
    np.testing.assert_array_equal(back["csv"].gyro, s.gyro)
    np.testing.assert_array_equal(back["csv"].accel, s.accel)
    # ROS 2 bags: float64 fields, nanosecond stamps; FLU -> FRD is an exact sign flip
    for fmt in ("bag_sqlite3", "bag_mcap"):
        b = back[fmt]
        assert np.max(np.abs(b.time - s.time)) <= NANOSECOND_ROUNDING_S + TIME_FLOAT64_S, fmt
        np.testing.assert_array_equal(b.gyro, s.gyro)
        np.testing.assert_array_equal(b.accel, s.accel)
    # ULog and DataFlash: float32 values, microsecond stamps
    for fmt in ("ulog", "dataflash"):
        if fmt not in back:
            continue
        b = back[fmt]
        assert np.max(np.abs(b.time - s.time)) <= MICROSECOND_ROUNDING_S + TIME_FLOAT64_S, fmt
        assert _within_float32(b.gyro, s.gyro), fmt
        assert _within_float32(b.accel, s.accel), fmt
        assert not np.array_equal(b.gyro, s.gyro)   # float32 storage really happened
    for b in back.values():
        assert b.rate == pytest.approx(1000.0) or b.rate is None


def _have_pymavlink() -> bool:
    try:
        import pymavlink  # noqa: F401
    except ImportError:
        return False
    return True


def test_ulog_is_read_by_pyulog_as_px4_sensor_combined(tmp_path):
    """The ULog writer follows the spec: pyulog itself sees the PX4 topic and fields."""
    from pyulog import ULog

    s = _motion(start=2.5)   # 2.5 s after boot
    path = write_px4_ulog(tmp_path / "f.ulg", s)
    raw = path.read_bytes()
    assert raw[:7] == b"ULog\x01\x12\x35"
    assert struct.unpack("<Q", raw[8:16])[0] == 2_500_000   # log start [us since boot]
    log = ULog(str(path))
    (d,) = log.data_list
    assert d.name == "sensor_combined"
    np.testing.assert_array_equal(d.data["timestamp"], np.rint(s.time * 1e6).astype(np.uint64))
    np.testing.assert_array_equal(d.data["gyro_rad[2]"], s.gyro[:, 2].astype(np.float32))
    np.testing.assert_array_equal(d.data["accelerometer_m_s2[2]"],
                                  s.accel[:, 2].astype(np.float32))
    np.testing.assert_array_equal(d.data["gyro_integral_dt"], 0)      # instantaneous samples
    (d,) = ULog(str(write_px4_ulog(tmp_path / "b.ulg", s, averaged=True))).data_list
    np.testing.assert_array_equal(d.data["gyro_integral_dt"], 1000)   # 1 kHz averages
    np.testing.assert_array_equal(d.data["accelerometer_integral_dt"], 1000)


#: A stamp read back: whole microseconds plus float64 spacing [s].
STAMP_TOL_S = MICROSECOND_ROUNDING_S + TIME_FLOAT64_S
#: A float32 value and its linear interpolation, relative (a few roundings).
FLOAT32_RTOL = 4 * FLOAT32_UNIT_ROUNDOFF


def test_ulog_averages_are_read_at_their_intervals_middle(tmp_path):
    """A boxcar average over the interval ending at its stamp equals a linear signal at the
    interval's middle (exactly): the reader returns it there, the 250 Hz log's 2 ms delay
    is not left to the clock offset; an instantaneous sample stays at its stamp."""
    rate, slope = 250.0, 3.0                       # [Hz], [rad/s^2 and m/s^3]
    stamps = 1.0 + np.arange(1, 40) / rate         # the intervals' ends [s]
    mid = stamps - 0.5 / rate
    sig = np.column_stack([slope * mid, np.zeros(mid.size), np.full(mid.size, -9.8)])
    s = ImuSamples(stamps, sig, sig.copy())
    back = read_px4_ulog(write_px4_ulog(tmp_path / "m.ulg", s, averaged=True))
    np.testing.assert_allclose(back.time, mid, rtol=0, atol=STAMP_TOL_S)
    np.testing.assert_allclose(back.gyro[:, 0], slope * back.time, rtol=FLOAT32_RTOL)
    np.testing.assert_allclose(back.accel[:, 0], slope * back.time, rtol=FLOAT32_RTOL)
    inst = read_px4_ulog(write_px4_ulog(tmp_path / "i.ulg", s))
    np.testing.assert_allclose(inst.time, stamps, rtol=0, atol=STAMP_TOL_S)
    # the averaging interval travels with the samples (the clock fit compares over it)
    assert back.interval == pytest.approx(1 / rate, abs=1e-6) and inst.interval == 0.0


def test_ulog_accelerometer_relative_stamp_is_interpolated(tmp_path):
    """accel taken 500 us after the gyro stamp: read back at the gyro stamp."""
    from pyulog import ULog

    t = np.arange(20) * 1e-3 + 1.0
    offset_us = 500
    slope = 2.0   # accel_x = slope * t_acc [m/s^2]: linear, so interpolation is exact
    accel = np.column_stack([slope * (t + offset_us * 1e-6), np.zeros(20), np.full(20, -9.8)])
    s = ImuSamples(t, np.zeros((20, 3)), accel)
    path = write_px4_ulog(tmp_path / "a.ulg", s)
    log = ULog(str(path))
    log.data_list[0].data["accelerometer_timestamp_relative"][:] = offset_us
    log.write_ulog(str(tmp_path / "b.ulg"))
    back = read_px4_ulog(tmp_path / "b.ulg")
    inner = slice(1, None)   # the first gyro stamp precedes every accel sample: held, skipped
    expected = slope * t[inner]
    assert np.all(np.abs(back.accel[inner, 0] - expected)
                  <= 4 * FLOAT32_UNIT_ROUNDOFF * np.abs(expected))


def test_ros_flu_positive_yaw_rate_is_negative_frd_yaw_rate(tmp_path):
    """REP 103: +z up. A left turn (+yaw about z-up) is -yaw about FRD z-down;
    gravity reaction +9.81 on ROS z-up is -9.81 on FRD z-down (level at rest)."""
    from rosbags.rosbag2 import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    t = ts.types
    bag = tmp_path / "left_turn"
    with Writer(bag, version=9) as w:
        conn = w.add_connection("/mavros/imu/data", IMU_MSGTYPE, typestore=ts)
        for k in range(5):
            stamp_ns = 1_700_000_000_000_000_000 + k * 5_000_000   # Unix time, 200 Hz
            sec, nsec = divmod(stamp_ns, 1_000_000_000)
            msg = t[IMU_MSGTYPE](
                header=t["std_msgs/msg/Header"](
                    stamp=t["builtin_interfaces/msg/Time"](sec=sec, nanosec=nsec),
                    frame_id="base_link"),
                orientation=t["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                orientation_covariance=np.zeros(9),
                angular_velocity=t["geometry_msgs/msg/Vector3"](x=0.1, y=0.2, z=0.5),
                angular_velocity_covariance=np.zeros(9),
                linear_acceleration=t["geometry_msgs/msg/Vector3"](x=0.3, y=0.4, z=9.81),
                linear_acceleration_covariance=np.zeros(9))
            w.write(conn, stamp_ns + 123, ts.serialize_cdr(msg, IMU_MSGTYPE))
    s = read_imu_log(bag, epoch_ns=1_700_000_000_000_000_000)
    np.testing.assert_array_equal(s.gyro, np.tile([0.1, -0.2, -0.5], (5, 1)))
    np.testing.assert_array_equal(s.accel, np.tile([0.3, -0.4, -9.81], (5, 1)))
    # header stamps, not the bag's receive time (123 ns later), after the integer epoch shift
    assert np.max(np.abs(s.time - np.arange(5) * 5e-3)) <= TIME_FLOAT64_S


def test_simulated_right_turn_is_written_as_negative_ros_yaw_rate(tmp_path):
    """FRD yaw rate > 0 at t = 0 of a yaw sinusoid (a right turn) -> ROS z rate < 0."""
    from rosbags.highlevel import AnyReader

    s = simulate_imu(sinusoid("yaw", np.deg2rad(4), 7.0), "ideal", rate=1000.0, start=0.0,
                     end=0.01)
    assert s.gyro[0, 2] > 0
    bag = write_ros2_imu(tmp_path / "b", s, storage="mcap")
    with AnyReader([bag]) as reader:
        first = next(reader.messages())
        msg = reader.deserialize(first[2], first[0].msgtype)
    assert msg.angular_velocity.z == -s.gyro[0, 2]
    assert msg.linear_acceleration.z == -s.accel[0, 2] > 0   # gravity reaction up in FLU


def test_flu_to_frd_is_its_own_inverse_and_checks_shape():
    v = np.array([[1.0, 2.0, 3.0]])
    np.testing.assert_array_equal(flu_to_frd(v), [[1.0, -2.0, -3.0]])
    np.testing.assert_array_equal(flu_to_frd(flu_to_frd(v)), v)
    with pytest.raises(ValueError, match=r"\[\.\.\., 3\]"):
        flu_to_frd(np.zeros((2, 2)))


def test_legacy_compensate_header_and_write_imu_csv_are_one_format(tmp_path):
    """The header `raysim compensate` took before (time_s,gyro_x,...: SI) and the
    unit-suffixed header of write_imu_csv read to the same samples."""
    s = _motion()
    legacy = tmp_path / "legacy.csv"
    np.savetxt(legacy, np.column_stack([s.time, s.gyro, s.accel]), delimiter=",",
               header="time_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z", comments="",
               fmt="%.17g")
    new = write_imu_csv(tmp_path / "new.csv", s, time_unit="ms", gyro_unit="deg_s",
                        accel_unit="g")
    a, b = read_imu_csv(legacy), read_imu_log(new)
    np.testing.assert_array_equal(a.gyro, s.gyro)
    np.testing.assert_allclose(b.gyro, a.gyro, rtol=1e-14, atol=0)
    np.testing.assert_allclose(b.accel, a.accel, rtol=1e-14, atol=0)
    np.testing.assert_allclose(b.time, a.time, rtol=1e-14, atol=1e-18)


def test_dataflash_file_is_read_with_pymavlink(tmp_path):
    pytest.importorskip("pymavlink", reason="optional extra raysim[ardupilot] not installed")
    s = _motion(start=0.25)
    write_dataflash_imu(tmp_path / "i0.bin", s, instance=1)
    back = read_imu_log(tmp_path / "i0.bin", instance=1)
    np.testing.assert_array_equal(back.time, np.rint(s.time * 1e6) * 1e-6)
    assert _within_float32(back.gyro, s.gyro)
    with pytest.raises(ValueError, match=r"instance=0.*present: \[.IMU\[1\] at 1000 Hz.\]"):
        read_imu_log(tmp_path / "i0.bin", instance=0)


def test_dataflash_reading_closes_the_log(tmp_path, monkeypatch):
    """pymavlink's reader holds the file and a memory map until closed: both readers close
    it (an open map keeps the file locked on Windows and warns at exit elsewhere)."""
    pytest.importorskip("pymavlink", reason="optional extra raysim[ardupilot] not installed")
    from pymavlink import DFReader

    from raysim.io.flight_logs.attitude import read_attitude_log

    path = write_dataflash_imu(tmp_path / "c.bin", _motion())
    opened, closed = [], []
    init, close = DFReader.DFReader_binary.__init__, DFReader.DFReader_binary.close
    monkeypatch.setattr(DFReader.DFReader_binary, "__init__",
                        lambda self, *a, **k: (opened.append(self), init(self, *a, **k))[1])
    monkeypatch.setattr(DFReader.DFReader_binary, "close",
                        lambda self: (closed.append(self), close(self))[1])
    read_imu_log(path)
    read_attitude_log(path)
    assert len(opened) == 2 and closed == opened


def test_dataflash_without_pymavlink_names_the_extra(tmp_path, monkeypatch):
    path = write_dataflash_imu(tmp_path / "x.bin", _motion())
    monkeypatch.setitem(sys.modules, "pymavlink", None)   # import fails as if not installed
    with pytest.raises(ImportError, match=r"pip install raysim\[ardupilot\]"):
        read_imu_log(path)


@pytest.mark.parametrize("name, body, match", [
    ("x.txt", b"1,2,3", r"unknown suffix '\.txt'"),
    ("x.ulg", b"not a ulog", "not a ULog file"),
    ("x.bin", b"\x00\x01", "not an ArduPilot DataFlash log"),
])
def test_bad_flight_logs_raise_value_errors(tmp_path, name, body, match):
    (tmp_path / name).write_bytes(body)
    with pytest.raises(ValueError, match=match):
        read_imu_log(tmp_path / name)


def test_missing_log_topic_and_stamps_are_named(tmp_path):
    with pytest.raises(ValueError, match="does not exist"):
        read_imu_log(tmp_path / "none.ulg")
    s = _motion()
    bag = write_ros2_imu(tmp_path / "bag", s, topic="/imu/data")
    with pytest.raises(ValueError, match=r"topic='/imu'.*\['/imu/data'\]"):
        read_imu_log(bag, topic="/imu")
    with pytest.raises(ValueError, match="must be >= 0"):
        write_px4_ulog(tmp_path / "neg.ulg", _motion(start=-0.01))
    too_fine = ImuSamples(np.array([1.0, 1.0 + 0.2e-6]), s.gyro[:2], s.accel[:2])
    with pytest.raises(ValueError, match=r"rounded to 1 us.*strictly increasing"):
        write_px4_ulog(tmp_path / "fine.ulg", too_fine)


# --------------------------------------------------------------------------- real-log behaviour

def test_time_base_tells_epoch_from_boot(tmp_path):
    from raysim.io.flight_logs import time_base

    assert time_base(np.array([12.5, 12.6])) == "time since boot"
    assert time_base(np.array([1.7e9, 1.7e9 + 0.004])) == "unix epoch"
    s = _motion()
    epoch = ImuSamples(s.time + 1_700_000_000.0, s.gyro, s.accel)
    back = read_imu_log(write_px4_ulog(tmp_path / "e.ulg", epoch))
    assert "unix epoch" in back.source and back.time[0] == pytest.approx(1.7e9, abs=1e-3)
    assert "time since boot" in read_imu_log(write_px4_ulog(tmp_path / "b.ulg", s)).source


def test_standalone_mcap_is_read_and_lone_db3_refused(tmp_path):
    import shutil

    s = _motion()
    bag = write_ros2_imu(tmp_path / "bag", s, storage="mcap")
    alone = tmp_path / "alone" / "flight.mcap"
    alone.parent.mkdir()
    shutil.copy(next(bag.glob("*.mcap")), alone)
    back = read_imu_log(alone)
    assert np.allclose(back.time, s.time, atol=NANOSECOND_ROUNDING_S + TIME_FLOAT64_S)
    assert np.allclose(back.gyro, s.gyro) and "1000 Hz" in back.source
    db = write_ros2_imu(tmp_path / "bag_db3", s, storage="sqlite3")
    lone = tmp_path / "lone" / "flight.db3"
    lone.parent.mkdir()
    shutil.copy(next(db.glob("*.db3")), lone)
    with pytest.raises(ValueError, match="needs its bag folder's metadata.yaml"):
        read_imu_log(lone)
    with pytest.raises(ValueError, match="topics, not instances"):
        read_imu_log(bag, instance=0)


def test_ulog_source_choice_and_instances(tmp_path):
    s = _motion()
    path = write_px4_ulog(tmp_path / "s.ulg", s)
    back = read_imu_log(path, topic="sensor_combined", instance=0)
    assert "sensor_combined instance 0, 1000 Hz" in back.source and back.rate == pytest.approx(
        1000.0)
    with pytest.raises(ValueError, match=r"topic='vehicle_imu'.*sensor_combined\[0\] at 1000"):
        read_imu_log(path, topic="vehicle_imu")
    with pytest.raises(ValueError, match=r"topic='imu'.*expected one of"):
        read_imu_log(path, topic="imu")
    with pytest.raises(ValueError, match="no reader options"):
        read_imu_log(write_imu_csv(tmp_path / "s.csv", s), topic="x")


def test_window_judgement_cuts_far_gaps_fills_short_ones_and_refuses_long_ones():
    from compensation.ingestion import fill_imu_gaps, judge_imu_window

    t = np.arange(0.0, 10.0, 0.004)                   # 250 Hz
    far = (t > 2.0) & (t < 2.5)                       # 0.5 s gap, 3.5 s before the window
    short = (t > 6.50) & (t < 6.54)                   # 44 ms gap inside the window
    keep_t = t[~far & ~short]
    keep, fill, notes = judge_imu_window(keep_t, (6.0, 6.6))
    assert keep_t[keep[0]] >= 2.5                     # cut after the far gap
    assert [n.split(":")[0] for n in notes] == ["imu window", "imu gaps filled"]
    assert "0.5 s at 2 s" in notes[0] and "0.04 s at 6.5 s" in notes[1]
    tt, v = fill_imu_gaps(keep_t, np.column_stack([keep_t, 2 * keep_t]), keep, fill)
    assert np.max(np.diff(tt)) < 0.0045 and np.allclose(v[:, 1], 2 * tt)
    long = keep_t[(keep_t < 6.3) | (keep_t > 6.45)]    # 150 ms gap inside
    with pytest.raises(ValueError, match=r"gap of 0.15.*inside the window.*--max-gap"):
        judge_imu_window(long, (6.0, 6.6))
    keep, fill, notes = judge_imu_window(long, (6.0, 6.6), max_gap=0.2)
    assert fill.size == 38 + 9 and notes[-1].startswith("imu gaps filled: 2 gap(s)")
    with pytest.raises(ValueError, match=r"does not cover the capture: the log spans 0\.0+ \.\. "
                                         r"9\.99"):
        judge_imu_window(t, (9.9, 10.5))
    with pytest.raises(ValueError, match="max_gap must be a finite positive"):
        judge_imu_window(t, (1.0, 2.0), max_gap=-1.0)


def _cube_and_imu(tmp_path):
    """A 4 x 4 array cube (.npz) on a pitch sinusoid and its ideal 250 Hz IMU over -5..1 s."""
    from raysim.echoes.oracle import PointTarget, simulate_point_targets
    from raysim.radar.arrays import upa
    from raysim.radar.config import RadarConfig

    cfg = RadarConfig(num_chirps=32, sample_rate=2.5e6)
    arr = upa(4, 4, wavelength=cfg.wavelength)
    traj = sinusoid("pitch", np.deg2rad(3), 10.0)
    fr = simulate_point_targets(cfg, arr, [PointTarget.at(12.0, 0.2, 0.0)], traj)
    np.savez(tmp_path / "c.npz", data=fr.data, chirp_times=fr.chirp_times,
             element_positions=arr.virtual_positions, carrier_frequency=cfg.carrier_frequency,
             bandwidth=cfg.bandwidth, chirp_duration=cfg.chirp_duration,
             sample_rate=cfg.sample_rate, grid_shape=np.array(arr.grid_shape))
    return tmp_path / "c.npz", simulate_imu(traj, "ideal", rate=250.0, start=-5.0, end=1.0)


def _drop(s, lo, hi):
    keep = (s.time < lo) | (s.time > hi)
    return ImuSamples(s.time[keep], s.gyro[keep], s.accel[keep])


def test_compensate_judges_gaps_over_the_capture_and_says_so(tmp_path, capsys):
    from raysim.cli import main
    from raysim.pipeline.compensate import compensate

    cube, s = _cube_and_imu(tmp_path)
    opts = dict(range_m=(11, 13), azimuth_deg=[11.0], elevation_deg=[0.0])
    far = write_imu_csv(tmp_path / "far.csv", _drop(s, -3.9, -3.5))   # 3.5 s before
    with pytest.warns(UserWarning, match="imu window"):
        res = compensate(cube, far, out=tmp_path / "a.npz", **opts)
    assert any(w.startswith("imu window") for w in res.warnings)
    assert res.imu_source == str(far)
    near = write_imu_csv(tmp_path / "near.csv", _drop(s, 0.001, 0.04))   # 40 ms at the chirps
    with pytest.warns(UserWarning, match="imu gaps filled"):
        res = compensate(cube, near, out=tmp_path / "b.npz", **opts)
    assert any(w.startswith("imu gaps filled") for w in res.warnings)
    wide = write_imu_csv(tmp_path / "wide.csv", _drop(s, 0.001, 0.2))
    with pytest.raises(ValueError, match="--max-gap"):
        compensate(cube, wide, out=tmp_path / "x.npz", **opts)
    assert not (tmp_path / "x.npz").exists()
    args = ["compensate", str(cube), "--imu", str(wide), "--range-m", "11:13", "--az-deg",
            "11:11:1", "--el-deg", "0:0:1"]
    assert main(args + ["--out", str(tmp_path / "d.npz")]) == 2
    assert "--max-gap" in capsys.readouterr().err
    assert main(args + ["--max-gap", "0.25", "--out", str(tmp_path / "d.npz")]) == 0
    cap = capsys.readouterr()
    assert f"IMU log: {wide}" in cap.out
    # said once, with its chain, and not again as a Python warning with its source line
    said = [ln for ln in cap.err.splitlines() if "imu gaps filled" in ln]
    assert len(said) == 1 and said[0].startswith("warning: exact: imu gaps filled"), said
    assert "Warning:" not in cap.err and "compensate(" not in cap.err
    late = write_imu_csv(tmp_path / "late.csv", _drop(s, -9.0, 0.5))
    with pytest.raises(ValueError, match="does not cover"):
        compensate(cube, late, out=tmp_path / "e.npz", **opts)
    with pytest.raises(ValueError, match="--imu-topic / --imu-instance"):
        compensate(cube, np.column_stack([s.time, s.gyro, s.accel]), out=tmp_path / "f.npz",
                   imu_topic="x", **opts)


def _ulog_with_fifo(path, s: ImuSamples, combined_every: int = 4) -> None:
    """A ULog with ``sensor_gyro_fifo`` / ``sensor_accel_fifo`` (8 samples a message, int16
    with a scale) and a decimated ``sensor_combined``, per the ULog file format."""
    from raysim.io.flight_logs.ulog import _FORMAT, _MAGIC, _RECORD, _message

    fifo = ("{}:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;"
            "float scale;uint8_t samples;int16_t[32] x;int16_t[32] y;int16_t[32] z;")
    rec = struct.Struct("<QQIffB32h32h32h")
    us = np.rint(s.time * 1e6).astype(np.int64)
    body = bytearray(_MAGIC + b"\x01" + struct.pack("<Q", int(us[0])))
    body += _message(b"B", bytes(40))
    body += _message(b"F", _FORMAT.encode())
    body += _message(b"F", fifo.format("sensor_gyro_fifo").encode())
    body += _message(b"F", fifo.format("sensor_accel_fifo").encode())
    for mid, name in enumerate(("sensor_combined", "sensor_gyro_fifo", "sensor_accel_fifo")):
        body += _message(b"A", struct.pack("<BH", 0, mid) + name.encode())
    dt = float(us[1] - us[0])
    scales = {1: 1e-4, 2: 1e-3}                       # rad/s and m/s^2 per count
    for a in range(0, us.size - 7, 8):
        for mid, v in ((1, s.gyro), (2, s.accel)):
            q = np.rint(v[a:a + 8] / scales[mid]).astype(int)
            pad = np.zeros((32, 3), int)
            pad[:8] = q
            body += _message(b"D", struct.pack("<H", mid) + rec.pack(
                int(us[a + 7]), int(us[a + 7]), 1, dt, scales[mid], 8, *pad[:, 0], *pad[:, 1],
                *pad[:, 2]))
        for k in range(a, a + 8):
            if k % combined_every == 0:
                body += _message(b"D", struct.pack("<H", 0) + _RECORD.pack(
                    int(us[k]), *map(float, s.gyro[k]), int(dt * combined_every), 0,
                    *map(float, s.accel[k]), int(dt * combined_every), 0, 0, 0, 0))
    path.write_bytes(bytes(body))


def test_ulog_fifo_topics_are_preferred_over_sensor_combined(tmp_path):
    s = _motion()
    _ulog_with_fifo(tmp_path / "f.ulg", s)
    back = read_imu_log(tmp_path / "f.ulg")
    assert "sensor_gyro_fifo instance 0, 1000 Hz" in back.source
    assert "also present: sensor_combined[0] 250 Hz" in back.source
    n = back.time.size
    np.testing.assert_allclose(back.time, np.rint(s.time[:n] * 1e6) * 1e-6, atol=1e-9)
    assert np.max(np.abs(back.gyro - s.gyro[:n])) <= 0.5e-4 + 1e-12      # half a count
    assert np.max(np.abs(back.accel - s.accel[:n])) <= 0.5e-3 + 1e-12
    low = read_imu_log(tmp_path / "f.ulg", topic="sensor_combined")
    assert low.rate == pytest.approx(250.0) and "sensor_combined instance 0" in low.source


def test_dataflash_raw_gyr_acc_preferred_over_filtered_imu(tmp_path):
    """``GYR``/``ACC`` at the sensor rate beat ``IMU`` at the loop rate; ``SampleUS`` is the
    sample time."""
    pytest.importorskip("pymavlink")
    s = _motion()
    head, rec = b"\xa3\x95", struct.Struct("<QBQfff")

    def fmt(kind, name, cols):
        return head + bytes([0x80]) + struct.pack("<BB4s16s64s", kind, 3 + rec.size,
                                                  name.encode(), b"QBQfff", cols.encode())

    body = bytearray(fmt(0x90, "GYR", "TimeUS,I,SampleUS,GyrX,GyrY,GyrZ")
                     + fmt(0x91, "ACC", "TimeUS,I,SampleUS,AccX,AccY,AccZ"))
    us = np.rint(s.time * 1e6).astype(np.int64) + 1000
    for k in range(us.size):
        body += head + bytes([0x90]) + rec.pack(int(us[k]) + 300, 0, int(us[k]),
                                                *map(float, s.gyro[k]))
        body += head + bytes([0x91]) + rec.pack(int(us[k]) + 300, 0, int(us[k]),
                                                *map(float, s.accel[k]))
    path = tmp_path / "raw.bin"
    path.write_bytes(bytes(body))
    back = read_imu_log(path)
    assert "GYR instance 0, 1000 Hz, SampleUS" in back.source
    np.testing.assert_allclose(back.time, us * 1e-6, atol=1e-12)
    assert _within_float32(back.gyro, s.gyro) and _within_float32(back.accel, s.accel)
    with pytest.raises(ValueError, match=r"topic='IMU'.*GYR\[0\] at 1000 Hz"):
        read_imu_log(path, topic="IMU")
