"""Flights like real ones: what `raysim flight` writes is read back as written.

The flight's files are read with the project's readers (and pyulog) and compared
with the truth the writer returns: the log's IMU rate, logger gaps and clock, the
flight controller's attitude (``vehicle_attitude``) and its use by the compensate
stage, the board's antenna layout, several targets at their ranges and angles, and a
radar mounted forward or oblique, compensated with its mounting (restored) and with a
wrong one (not restored).
"""

from __future__ import annotations

import numpy as np
import pytest

from raysim.cli import main
from raysim.io import read_imu_log
from raysim.io.flight_logs.attitude import read_attitude_log
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import (
    DEFAULT5_TARGETS,
    _grid,
    measure_targets,
    write_flight,
)
from raysim.pipeline.flight_log import ATTITUDE_RATE, GAP_LENGTH_S

#: Attitude read back against the truth [deg]: float32 quaternions (about 1e-5 deg)
#: and the spherical interpolation between 200 Hz stamps of a slow hover wander.
ATT_TOL_DEG = 2e-3
#: Rate read back, relative (a clock drift of 50 ppm is 5e-5).
RATE_RTOL = 1e-3
#: Compensated with the right mounting (ideal IMU, given velocity and offset): the
#: beam metrics of :mod:`raysim.measure.beams` the estimator work aims at.
MOUNTED_ANGLE_TOL_DEG = 0.05
MOUNTED_PSEUDO_VELOCITY_BINS = 0.05
MOUNTED_LEAKAGE_DB = -35.0
#: With a wrong mounting the rotation is undone about the wrong axes: at least this
#: much pseudo-velocity [bin] or leakage [dB] is left (measured 2.5-3.3 bins, -13..-16 dB).
WRONG_PSEUDO_VELOCITY_BINS = 1.0
WRONG_LEAKAGE_DB = -25.0
#: Uncompensated (chain none) hover jitter of the default flight: the targets' azimuth
#: within this of the truth [deg] (attitude wander of a few tenths of a degree and the
#: rotor vibration's phase smear) and their range within one range cell.
NONE_ANGLE_TOL_DEG = 1.0


def test_flight_log_holds_the_attitude_and_leaves_it_out_when_asked(tmp_path):
    f = write_flight(tmp_path / "a", frames=1)
    att = read_attitude_log(f.imu_log)
    assert "vehicle_attitude" in att.source
    assert abs(att.rate / ATTITUDE_RATE - 1) < RATE_RTOL
    q = att.rotation.as_quat()
    assert np.allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-6)
    got = np.array(att.euler_deg(f.start + f.time_offset))        # the first ramp, IMU clock
    assert np.all(np.abs(got - f.initial_attitude_deg[0]) < ATT_TOL_DEG)
    n = write_flight(tmp_path / "n", frames=1, attitude=False)
    assert read_attitude_log(n.imu_log) is None
    # the attitude is added beside the IMU: capture, cfg and IMU samples unchanged
    assert f.capture.read_bytes() == n.capture.read_bytes()
    assert f.radar_config.read_text() == n.radar_config.read_text()
    a, b = read_imu_log(f.imu_log), read_imu_log(n.imu_log)
    assert np.array_equal(a.time, b.time) and np.array_equal(a.gyro, b.gyro)


def test_boxcar_log_with_gaps_and_drift_read_back(tmp_path):
    drift = 50.0
    f = write_flight(tmp_path / "g", frames=1, imu_rate=250.0, imu_boxcar=True, log_gaps=3,
                     gaps_in_capture=True, clock_drift_ppm=drift, seed=2)
    s = read_imu_log(f.imu_log)
    assert abs(s.rate / (250.0 / (1 + drift * 1e-6)) - 1) < RATE_RTOL
    assert len(f.gaps) == 3
    dt = np.diff(s.time)
    holes = np.flatnonzero(dt > 2.5 / 250.0)
    assert holes.size == 3
    stamp = s.time + 0.5 / 250.0              # read at the middle of each 4 ms average
    for k, (start, length) in zip(holes, f.gaps, strict=True):
        assert stamp[k] < start and stamp[k + 1] >= start + length       # nothing inside
        assert GAP_LENGTH_S[0] <= length <= GAP_LENGTH_S[1]
        assert dt[k] <= length + 2 / 250.0
    capture = (f.start + f.time_offset, f.frame_starts[-1] + 0.05 + f.time_offset)
    inside = [g for g in f.gaps if capture[0] <= g[0] <= capture[1]]
    assert len(inside) == 1                                      # --gaps-in-capture
    att = read_attitude_log(f.imu_log)
    for start, length in f.gaps:                                 # the logger lost both
        assert not np.any((att.time >= start) & (att.time < start + length))


def test_compensate_takes_the_log_attitude_by_default(tmp_path, capsys):
    f = write_flight(tmp_path / "f", frames=1)
    cells = ("--range-m", "10.8:11.8", "--az-deg", "14:26:0.25", "--el-deg", "0:0:1",
             "--no-progress")
    given = f.command(tmp_path / "given.zarr", *cells)
    i = given.index("--initial-attitude-deg")
    assert main(given) == 0
    capsys.readouterr()
    from_log = given[:i] + given[i + 2:]
    from_log[from_log.index("--out") + 1] = str(tmp_path / "log.zarr")
    assert main(from_log) == 0
    err = capsys.readouterr().err
    assert "note: initial attitude" in err and "vehicle_attitude" in err
    a = open_store(tmp_path / "given.zarr")["beams"].values
    b = open_store(tmp_path / "log.zarr")["beams"].values
    assert np.max(np.abs(a - b)) < 1e-3 * np.max(np.abs(a))     # the same attitude
    n = write_flight(tmp_path / "n", frames=1, attitude=False)
    level = n.command(tmp_path / "level.zarr", *cells)
    j = level.index("--initial-attitude-deg")
    assert main(level[:j] + level[j + 2:]) == 0
    assert "assumed level" in capsys.readouterr().err


def test_several_targets_at_their_ranges_and_angles_uncompensated(tmp_path):
    from raysim.pipeline.compensate import compensate

    f = write_flight(tmp_path / "f", frames=1, targets="default5")
    assert f.targets == tuple(DEFAULT5_TARGETS) and len(f.targets) >= 5
    r = [t[0] for t in f.targets]
    assert min(r) >= 4.0 and max(r) <= 9.0
    assert {t[2] for t in f.targets} == {-5.0, 0.0, 5.0}
    out = tmp_path / "none.zarr"
    compensate(f.capture, f.imu_log, out=out, radar_config=f.radar_config, chain="none",
               capture_t0=f.start, range_m=(min(r) - 0.5, max(r) + 0.5),
               azimuth_deg=_grid(-45, 45, 0.25), elevation_deg=(-5.0, 0.0, 5.0))
    m = measure_targets(out, f)                                  # [target, frame, 3]
    assert m.shape == (len(f.targets), 1, 3)
    assert np.all(m[:, 0, 0] <= NONE_ANGLE_TOL_DEG), m[:, 0, 0]
    ds = open_store(out)
    power = (np.abs(ds["beams"].values[0].sum(axis=0)) ** 2).sum(axis=(1, 2))   # [range]
    ranges = ds["range"].values
    cell = float(np.median(np.diff(ranges)))
    for rt in r:       # the strongest cell of the range profile around each target
        near = np.flatnonzero(np.abs(ranges - rt) <= 0.45)
        assert abs(ranges[near[np.argmax(power[near])]] - rt) <= cell


def test_board_layout_written_and_read_back(tmp_path):
    from raysim.io.mmwave_config import read_mmwave_config
    from raysim.pipeline.compensate import compensate

    f = write_flight(tmp_path / "b", frames=1, board="xWR16xx", target=(7.0, -12.0, 0.0))
    assert f.board == "xWR16xx"
    m = read_mmwave_config(f.radar_config, board="xWR16xx")
    assert m.tx_order == (0, 1) and m.board == "xWR16xx"
    x = np.sort(m.array.virtual_positions[:, 0]) / (m.config.center_wavelength / 2)
    assert np.allclose(x, np.arange(8), atol=1e-9)            # eight in a row, lambda/2
    assert np.allclose(m.array.virtual_positions[:, 1:], 0.0)
    out = tmp_path / "none.zarr"
    compensate(f.capture, f.imu_log, out=out, radar_config=f.radar_config, chain="none",
               capture_t0=f.start, range_m=(6.5, 7.5), azimuth_deg=_grid(-40, 20, 0.25),
               elevation_deg=(0.0,), board="xWR16xx")
    assert open_store(out)["beams"].shape[0] == 1
    assert measure_targets(out, f)[0, 0, 0] <= NONE_ANGLE_TOL_DEG
    with pytest.raises(ValueError, match="xWR16xx"):      # the cfg alone does not say it
        compensate(f.capture, f.imu_log, out=tmp_path / "x.zarr",
                   radar_config=f.radar_config, chain="none", capture_t0=f.start)


def _moving():
    from raysim.platform.motion import sinusoid

    return (sinusoid("yaw", np.deg2rad(8.0), 20.0, np.pi / 2)
            + sinusoid("pitch", np.deg2rad(5.0), 13.0) + sinusoid("y", 0.03, 7.0))


@pytest.mark.parametrize("mount, wrong", [("forward", "down"), ("oblique", "down"),
                                          ((0.0, 0.0, 0.0), "forward")])
def test_mounted_radar_restored_with_its_mounting_only(tmp_path, mount, wrong):
    from raysim.pipeline.compensate import compensate

    f = write_flight(tmp_path / "m", trajectory=_moving(), imu="ideal", time_offset=0.0,
                     frames=1, target=(7.0, 10.0, 0.0), mounting_deg=mount)
    opts = dict(radar_config=f.radar_config, capture_t0=f.start, time_offset=0.0,
                velocity="given", initial_velocity=f.initial_velocity[0],
                initial_attitude_deg=tuple(f.initial_attitude_deg[0]), lever_arm=f.lever_arm,
                range_m=(6.5, 7.5), azimuth_deg=_grid(-60, 60, 0.5), elevation_deg=(0.0,))
    compensate(f.capture, f.imu_log, out=tmp_path / "right.zarr", mounting_deg=mount, **opts)
    compensate(f.capture, f.imu_log, out=tmp_path / "wrong.zarr", mounting_deg=wrong, **opts)
    right = measure_targets(tmp_path / "right.zarr", f)[0, 0]
    bad = measure_targets(tmp_path / "wrong.zarr", f)[0, 0]
    assert right[0] <= MOUNTED_ANGLE_TOL_DEG
    assert abs(right[1]) <= MOUNTED_PSEUDO_VELOCITY_BINS and right[2] <= MOUNTED_LEAKAGE_DB
    assert abs(bad[1]) >= WRONG_PSEUDO_VELOCITY_BINS or bad[2] >= WRONG_LEAKAGE_DB


def test_default_mounting_changes_nothing(tmp_path):
    """``down``, ``(0, 0, 0)`` and no mounting give the same bits (the motion is not touched)."""
    from raysim.pipeline.compensate import compensate

    f = write_flight(tmp_path / "f", frames=1)
    opts = dict(radar_config=f.radar_config, capture_t0=f.start, time_offset=f.time_offset,
                velocity="given", initial_velocity=f.initial_velocity[0],
                initial_attitude_deg=tuple(f.initial_attitude_deg[0]), lever_arm=f.lever_arm,
                range_m=(10.8, 11.8), azimuth_deg=_grid(14, 26, 1.0), elevation_deg=(0.0,))
    beams = []
    for k, mount in enumerate((None, "down", (0.0, 0.0, 0.0))):
        compensate(f.capture, f.imu_log, out=tmp_path / f"{k}.zarr", mounting_deg=mount,
                   **opts)
        ds = open_store(tmp_path / f"{k}.zarr")
        assert "mounting_deg" not in ds.attrs
        beams.append(ds["beams"].values)
    assert np.array_equal(beams[0], beams[1]) and np.array_equal(beams[0], beams[2])


@pytest.mark.parametrize("storage", ["sqlite3", "mcap"])
def test_ros2_orientation_read_as_ned_frd(tmp_path, storage):
    """A REP 103 orientation (FLU body to ENU) is read back as ``R_WB`` (FRD to NED)."""
    pytest.importorskip("rosbags")
    from scipy.spatial.transform import Rotation

    from raysim.io.flight_logs.rosbag import write_ros2_imu
    from raysim.platform.imu import ImuSamples

    n = 20
    t = 1.0 + np.arange(n) * 0.01
    ypr = np.column_stack([np.linspace(30, 40, n), np.full(n, 4.0), np.full(n, -6.0)])
    rot = Rotation.from_euler("ZYX", ypr, degrees=True)
    s = ImuSamples(t, np.zeros((n, 3)), np.tile([0.0, 0.0, -9.8], (n, 1)), spec=None,
                   truth=None, source="test", rate=100.0)
    bag = write_ros2_imu(tmp_path / "bag", s, storage=storage, orientation=rot)
    att = read_attitude_log(bag)
    assert "ROS 2" in att.source and np.allclose(att.time, t)
    got = att.rotation.as_euler("ZYX", degrees=True)
    assert np.max(np.abs(got - ypr)) < 1e-9
    # as written (REP 103): a yaw of 30 deg east of north points the FLU x axis 60 deg
    # counter-clockwise from east in ENU, and the pitch up of 4 deg raises it (z up)
    from rosbags.highlevel import AnyReader

    from raysim.io.flight_logs.rosbag import _typestore

    with AnyReader([bag], default_typestore=_typestore()) as reader:
        conn, _, raw = next(iter(reader.messages()))
        o = reader.deserialize(raw, conn.msgtype).orientation
    fwd = Rotation.from_quat([o.x, o.y, o.z, o.w]).apply([1.0, 0.0, 0.0])
    assert np.degrees(np.arctan2(fwd[1], fwd[0])) == pytest.approx(60.0, abs=1e-6)
    assert np.degrees(np.arcsin(fwd[2])) == pytest.approx(4.0, abs=1e-6)
    plain = write_ros2_imu(tmp_path / "plain", s, storage=storage)
    assert read_attitude_log(plain) is None                      # REP 145: none provided


def test_flight_cli_writes_a_realistic_flight_and_names_bad_options(tmp_path, capsys):
    d = tmp_path / "f"
    assert main(["flight", str(d), "--targets", "default5", "--imu-rate", "250",
                 "--imu-boxcar", "--log-gaps", "2", "--gaps-in-capture", "--frames", "1",
                 "--board", "xWR16xx", "--clock-drift-ppm", "20"]) == 0
    out, err = capsys.readouterr()
    assert "--board xWR16xx" in out and "--max-gap" in out and "--range-m 4.0:9.3" in out
    assert "flight: writing about" in err and "logger gaps" in err      # sized, announced
    s = read_imu_log(d / "flight.ulg")
    assert abs(s.rate / 250.0 - 1) < RATE_RTOL
    assert main(["flight", str(tmp_path / "g"), "--mounting-deg", "sideways"]) == 2
    assert "--mounting-deg" in capsys.readouterr().err
    assert main(["flight", str(tmp_path / "h"), "--targets", "default5", "--target",
                 "5,0,0"]) == 2
    assert main(["flight", str(tmp_path / "i"), "--target", "50,0,0"]) == 2
    assert "--target" in capsys.readouterr().err
    assert not (tmp_path / "g").exists() and not (tmp_path / "i").exists()


def test_ros2_odometry_pose_read_when_the_imu_has_no_orientation(tmp_path):
    pytest.importorskip("rosbags")
    from rosbags.rosbag2 import StoragePlugin, Writer
    from scipy.spatial.transform import Rotation

    from raysim.io.flight_logs.rosbag import _typestore

    ts = _typestore()
    odom_t = ts.types["nav_msgs/msg/Odometry"]
    hdr_t, time_t = ts.types["std_msgs/msg/Header"], ts.types["builtin_interfaces/msg/Time"]
    pose_cov_t, pose_t = (ts.types["geometry_msgs/msg/PoseWithCovariance"],
                          ts.types["geometry_msgs/msg/Pose"])
    twist_cov_t, twist_t = (ts.types["geometry_msgs/msg/TwistWithCovariance"],
                            ts.types["geometry_msgs/msg/Twist"])
    vec_t, pt_t = ts.types["geometry_msgs/msg/Vector3"], ts.types["geometry_msgs/msg/Point"]
    quat_t = ts.types["geometry_msgs/msg/Quaternion"]
    heading = np.array([10.0, 20.0, 30.0])                 # ENU, counter-clockwise from east
    with Writer(tmp_path / "bag", version=9, storage_plugin=StoragePlugin.SQLITE3) as w:
        conn = w.add_connection("/odom", "nav_msgs/msg/Odometry", typestore=ts)
        for k, h in enumerate(heading):
            q = Rotation.from_euler("z", h, degrees=True).as_quat()
            msg = odom_t(header=hdr_t(stamp=time_t(sec=5 + k, nanosec=0), frame_id="odom"),
                         child_frame_id="base_link",
                         pose=pose_cov_t(pose=pose_t(position=pt_t(x=0.0, y=0.0, z=0.0),
                                                     orientation=quat_t(x=q[0], y=q[1],
                                                                        z=q[2], w=q[3])),
                                         covariance=np.zeros(36)),
                         twist=twist_cov_t(twist=twist_t(linear=vec_t(x=0.0, y=0.0, z=0.0),
                                                         angular=vec_t(x=0.0, y=0.0, z=0.0)),
                                           covariance=np.zeros(36)))
            w.write(conn, (5 + k) * 1_000_000_000, ts.serialize_cdr(msg, conn.msgtype))
    att = read_attitude_log(tmp_path / "bag")
    assert "nav_msgs/msg/Odometry" in att.source and np.allclose(att.time, [5, 6, 7])
    ypr = att.rotation.as_euler("ZYX", degrees=True)
    assert np.allclose(ypr[:, 0], 90.0 - heading, atol=1e-9)   # yaw from north, clockwise
    assert np.allclose(ypr[:, 1:], 0.0, atol=1e-9)


#: Ground clutter in the flight: its range cells gain at least this much power over the
#: flight without it [dB], the target's cell changes by at most this much [dB].
CLUTTER_GAIN_DB = 20.0
TARGET_CHANGE_DB = 1.0


def test_flight_with_a_scene_ground_clutter(tmp_path):
    from raysim.io.ti_dca1000 import read_dca1000
    from raysim.pipeline.flight_clutter import clutter_points

    altitude = 14.0
    kw = dict(frames=1, target=(8.0, 10.0, 0.0))
    f = write_flight(tmp_path / "c", clutter_scene="flat_reflectors",
                     clutter_altitude=altitude, clutter_max_scatterers=300, **kw)
    n = write_flight(tmp_path / "n", **kw)

    def profile(flight):
        from raysim.io.mmwave_config import read_mmwave_config

        m = read_mmwave_config(flight.radar_config)
        x = read_dca1000(flight.capture, m.fmt).cube[0].astype(complex)  # [chirp, channel, sample]
        spec = np.fft.fft(x * np.hanning(x.shape[-1]), axis=-1)
        ranges = m.config.bin_ranges(x.shape[-1])
        return ranges, 10 * np.log10((np.abs(spec) ** 2).sum(axis=(0, 1)) + 1e-30)

    ranges, with_clutter = profile(f)
    _, without = profile(n)
    ground = (ranges > altitude + 0.5) & (ranges < 20.0)
    assert np.median(with_clutter[ground] - without[ground]) >= CLUTTER_GAIN_DB
    k = int(np.argmin(np.abs(ranges - 8.0)))
    # the capture is scaled to full scale: compare the target against the capture's peak
    assert abs((with_clutter[k] - with_clutter.max()) - (without[k] - without.max())) \
        <= TARGET_CHANGE_DB
    with pytest.raises(ValueError, match="--clutter-scene"):
        clutter_points("moon", None, None, (0, 0, 0))
