"""Flight-log CSV exports read as they are: ArduPilot's ``IMU`` as mavlogdump.py or Mission
Planner writes it (``TimeUS`` or 2014-15 ``TimeMS``, ``GyrX..Z`` rad/s, ``AccX..Z`` m/s^2,
FRD, one row per instance ``I``). PX4's ``ulog2csv`` export is checked on a real log in
tests/test_real_files.py."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.io import read_imu_log

HEAD = "timestamp,TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz"


def _rows(times_us, instance=0):
    g = np.array([0.01, -0.02, 0.03])
    a = np.array([0.1, -0.2, -9.8])
    return [f"{1.7e9 + t * 1e-6:.6f},{t},{instance},{g[0] + 1e-4 * k},{g[1]},{g[2]},"
            f"{a[0]},{a[1]},{a[2] - 1e-3 * k},0,0,25.0,1,1,400,400"
            for k, t in enumerate(times_us)]


def test_mavlogdump_imu_csv_reads_in_si_and_frd(tmp_path):
    t = 1_000_000 + 2500 * np.arange(40)                      # 400 Hz
    path = tmp_path / "imu.csv"
    path.write_text("\n".join([HEAD, *_rows(t)]) + "\n")
    s = read_imu_log(path)
    np.testing.assert_allclose(s.time, t * 1e-6, rtol=0, atol=1e-12)
    np.testing.assert_allclose(s.gyro[:, 0], 0.01 + 1e-4 * np.arange(40))
    np.testing.assert_allclose(s.accel[:, 2], -9.8 - 1e-3 * np.arange(40))
    assert "ArduPilot IMU" in s.source and "TimeUS" in s.source


def test_old_firmware_timems_export(tmp_path):
    path = tmp_path / "imu.csv"
    rows = [f"{t},{0.01},{0.0},{0.0},{0.0},{0.0},{-9.8}" for t in range(1000, 1400, 40)]
    path.write_text("TimeMS,GyrX,GyrY,GyrZ,AccX,AccY,AccZ\n" + "\n".join(rows) + "\n")
    s = read_imu_log(path)
    np.testing.assert_allclose(s.time, np.arange(1000, 1400, 40) * 1e-3)    # 25 Hz
    assert "TimeMS" in s.source


def test_interleaved_imu_instances_are_refused_with_the_export_to_run(tmp_path):
    t = 1_000_000 + 2500 * np.arange(10)
    rows = [r for pair in zip(_rows(t, 0), _rows(t + 100, 1), strict=True) for r in pair]
    path = tmp_path / "imu.csv"
    path.write_text("\n".join([HEAD, *rows]) + "\n")
    with pytest.raises(ValueError, match=r"instances \['0', '1'\] interleave .*IMU\.I==0"):
        read_imu_log(path)


def test_px4_export_samples_sit_at_their_intervals_middle(tmp_path):
    """``ulog2csv`` rows are 4 ms averages stamped at their end: read as from the ULog."""
    from raysim.io.imu_log import read_imu_csv

    path = tmp_path / "f_sensor_combined_0.csv"
    head = ("timestamp,gyro_rad[0],gyro_rad[1],gyro_rad[2],gyro_integral_dt,"
            "accelerometer_timestamp_relative,accelerometer_m_s2[0],accelerometer_m_s2[1],"
            "accelerometer_m_s2[2],accelerometer_integral_dt,accelerometer_clipping")
    t = 20_000_000 + 4000 * np.arange(25)
    rows = [f"{s},0.01,0.02,-0.03,4000,0,0.1,0.2,-9.7,4000,0" for s in t]
    path.write_text("\n".join([head, *rows]) + "\n")
    s = read_imu_log(path)
    np.testing.assert_allclose(s.time, (t - 2000) * 1e-6, rtol=0, atol=1e-9)
    assert s.interval == pytest.approx(4e-3) and "ulog2csv" in s.source
    np.testing.assert_allclose(s.accel[0], [0.1, 0.2, -9.7])
    with pytest.raises(ValueError, match="read it with raysim.io.read_imu_log"):
        read_imu_csv(path)
