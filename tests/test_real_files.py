"""Real files from the field (``../shared/real-data``): logs and radar configurations.

Every file there is read with the right rate, units, frame and board. What a
file holds is measured here independently of the readers (pyulog and
pymavlink directly): the stamp intervals, the flight controller's own attitude
(``vehicle_attitude``, ``ATT``) against the attitude the accelerometer gives in
FRD (specific force ``(0, 0, -g)`` when level), the flight controller's body
rates against the gyro. The tests skip where the folder is absent (a user's
clone has no ``../shared``); ``RAYSIM_REAL_DATA`` names another folder.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

from raysim.io import read_imu_log
from raysim.io.mmwave_config import read_mmwave_config

REAL = Path(os.environ.get("RAYSIM_REAL_DATA") or
            Path(__file__).resolve().parents[1].parent / "shared" / "real-data")
pytestmark = pytest.mark.skipif(not REAL.is_dir(), reason=f"{REAL} is absent")

#: The rate read must be within this fraction of the rate the log holds.
RATE_RTOL = 0.03
#: Roll / pitch from the mean accelerometer against the flight controller's
#: attitude [deg]: a consumer accelerometer's bias (20 mg: 1.1 deg) plus the
#: estimator's own error.
LEVEL_TOL_DEG = 1.5
G = 9.80665


def _level_deg(accel: np.ndarray) -> tuple[float, float]:
    """Roll and pitch [deg] of the mean specific force in FRD."""
    f = accel.mean(axis=0)
    roll = np.degrees(np.arctan2(-f[1], -f[2]))
    pitch = np.degrees(np.arcsin(np.clip(f[0] / np.linalg.norm(f), -1, 1)))
    return float(roll), float(pitch)


def _quat_roll_pitch_deg(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Roll and pitch [deg] of PX4 quaternions ``[n, 4]`` (w, x, y, z; body FRD to NED)."""
    w, x, y, z = q.T
    roll = np.degrees(np.arctan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y)))
    pitch = np.degrees(np.arcsin(np.clip(2 * (w * y - z * x), -1, 1)))
    return roll, pitch


# --------------------------------------------------------------------------- PX4 ULog

def test_px4_small_log_sensor_combined_rate_units_frame():
    from pyulog import ULog

    path = REAL / "ulog" / "sample_log_small.ulg"
    s = read_imu_log(path)
    assert "sensor_combined instance 0" in s.source and "time since boot" in s.source
    log = ULog(str(path), ["sensor_combined", "vehicle_attitude"])
    d = {x.name: x.data for x in log.data_list}
    held = 1e6 / np.median(np.diff(d["sensor_combined"]["timestamp"]))
    assert abs(s.rate / held - 1) < RATE_RTOL and 195 < s.rate < 215      # ~205 Hz
    assert s.time.size == d["sensor_combined"]["timestamp"].size
    assert np.max(np.diff(s.time)) == pytest.approx(0.161303, abs=1e-6)  # the logger gap
    assert abs(np.linalg.norm(s.accel.mean(axis=0)) - G) < 0.3            # m/s^2
    assert s.accel.mean(axis=0)[2] < -9.0                                  # FRD: z down
    assert np.max(np.abs(s.gyro)) < 0.5             # rad/s on a still vehicle (not deg/s)
    q = np.column_stack([d["vehicle_attitude"][f"q[{i}]"] for i in range(4)])
    roll, pitch = _quat_roll_pitch_deg(q)
    r_acc, p_acc = _level_deg(s.accel)
    assert abs(r_acc - np.mean(roll)) < LEVEL_TOL_DEG
    assert abs(p_acc - np.mean(pitch)) < LEVEL_TOL_DEG


@pytest.mark.parametrize("name, interval_s", [("sample_log_small.ulg", 4.9e-3),
                                              ("sample_appended_multiple.ulg", 4.0e-3)])
def test_px4_averaging_interval_in_seconds_whatever_the_firmware_logged(name, interval_s):
    """``gyro_integral_dt``: integer microseconds in the newer log, float32 seconds in the
    older one; both read as the averaging interval in seconds (about the sample period of
    the 205 / 250 Hz boxcar), and each sample placed at its interval's middle."""
    from pyulog import ULog

    path = REAL / "ulog" / name
    s = read_imu_log(path)
    assert s.interval == pytest.approx(interval_s, rel=0.05)
    assert s.interval == pytest.approx(1 / s.rate, rel=0.1)
    d = ULog(str(path), ["sensor_combined"]).data_list[0].data
    stamp = d["timestamp"][0] * 1e-6
    assert stamp - s.time[0] == pytest.approx(s.interval / 2, abs=2e-5)   # middle, [s]


def test_px4_logger_gap_is_judged_over_the_capture_window():
    """The 161 ms logger gap: 3.5 s away it does not refuse the log; across it, it needs
    ``max_gap`` and is then filled with a warning."""
    from compensation.ingestion import judge_imu_window

    s = read_imu_log(REAL / "ulog" / "sample_log_small.ulg")
    k = int(np.argmax(np.diff(s.time)))
    end = s.time[k + 1]
    keep, fill, notes = judge_imu_window(s.time, (end + 3.5, end + 3.6))
    assert fill.size == 0 and notes[0].startswith("imu window") and "0.1613 s" in notes[0]
    across = (s.time[k] + 0.05, s.time[k] + 0.4)
    with pytest.raises(ValueError, match=r"gap of 0.1613 s.*--max-gap"):
        judge_imu_window(s.time, across)
    keep, fill, notes = judge_imu_window(s.time, across, max_gap=0.2)
    assert fill.size == 32 and notes[-1].startswith("imu gaps filled")


def test_px4_small_log_lists_every_instance_and_reads_the_one_asked():
    path = REAL / "ulog" / "sample_log_small.ulg"
    s = read_imu_log(path)
    for k in range(3):                       # three IMUs: vehicle_imu instances 0..2
        assert f"vehicle_imu[{k}]" in s.source
    v = read_imu_log(path, topic="vehicle_imu", instance=2)
    assert "vehicle_imu instance 2" in v.source and abs(v.rate - 2.0) < 0.1   # logged at 2 Hz
    assert abs(np.linalg.norm(v.accel.mean(axis=0)) - G) < 0.3     # delta_velocity / dt
    with pytest.raises(ValueError, match=r"instance=5.*sensor_combined\[0\]"):
        read_imu_log(path, instance=5)
    with pytest.raises(ValueError, match=r"topic='sensor_gyro'.*sensor_gyro_fifo"):
        read_imu_log(path, topic="sensor_gyro")


def test_px4_appended_log_gyro_matches_the_attitude_rates():
    """Gyro in rad/s and FRD: against ``vehicle_attitude`` roll/pitch/yaw speed, which this
    firmware stamps as it stamps ``sensor_combined``, at the end of the averaging interval
    (correlation 0.9988 there, 0.958 half an interval off), so it is compared at the
    reader's mid-interval time plus half the interval."""
    from pyulog import ULog

    path = REAL / "ulog" / "sample_appended_multiple.ulg"
    s = read_imu_log(path)
    assert "sensor_combined" in s.source and abs(s.rate / 250.0 - 1) < RATE_RTOL
    att = next(x.data for x in ULog(str(path), ["vehicle_attitude"]).data_list)
    t = att["timestamp"] * 1e-6
    ref = np.column_stack([att["rollspeed"], att["pitchspeed"], att["yawspeed"]])
    inside = (t > s.time[0]) & (t < s.time[-1])
    g = np.column_stack([np.interp(t[inside], s.time + s.interval / 2, s.gyro[:, i])
                         for i in range(3)])
    for i in range(3):
        r = ref[inside, i]
        assert np.std(r) > 1e-3
        assert np.corrcoef(g[:, i], r)[0, 1] > 0.9, f"axis {i}"
        scale = float(np.dot(g[:, i] - g[:, i].mean(), r - r.mean()) / np.sum((r - r.mean()) ** 2))
        assert abs(scale - 1) < 0.1, f"axis {i}: scale {scale}"


#: Unit-quaternion norm of the ULog attitude read (float32 storage: about 1e-7).
QUAT_NORM_TOL = 1e-5


@pytest.mark.parametrize("name, rate", [("sample_log_small.ulg", 205.0),
                                        ("sample_appended_multiple.ulg", 31.3)])
def test_px4_vehicle_attitude_read_beside_the_imu(name, rate):
    """``vehicle_attitude`` read on the IMU's clock: unit quaternions, the rate the log holds
    (measured with pyulog), and its roll/pitch against the quaternion formula."""
    from pyulog import ULog

    from raysim.io.flight_logs.attitude import read_attitude_log

    path = REAL / "ulog" / name
    att = read_attitude_log(path)
    raw = next(x.data for x in ULog(str(path), ["vehicle_attitude"]).data_list)
    q = np.column_stack([raw[f"q[{i}]"] for i in range(4)]).astype(float)
    assert np.all(np.abs(np.linalg.norm(q, axis=1) - 1) < QUAT_NORM_TOL)
    assert "vehicle_attitude" in att.source and "time since boot" in att.source
    held = 1e6 / np.median(np.diff(raw["timestamp"].astype(float)))
    assert abs(att.rate / held - 1) < RATE_RTOL and abs(att.rate / rate - 1) < RATE_RTOL
    assert att.time[0] == pytest.approx(raw["timestamp"][0] * 1e-6)
    s = read_imu_log(path)                   # the same clock: the spans overlap
    assert att.time[0] < s.time[-1] and s.time[0] < att.time[-1]
    roll, pitch = _quat_roll_pitch_deg(q)
    ypr = att.rotation.as_euler("ZYX", degrees=True)
    assert np.allclose(ypr[:, 2], roll, atol=1e-6) and np.allclose(ypr[:, 1], pitch, atol=1e-6)


# --------------------------------------------------------------------------- ArduPilot

def _dataflash(path, kind):
    from pymavlink import DFReader

    log, rows = DFReader.DFReader_binary(str(path)), []
    while (m := log.recv_match(type=[kind])) is not None:
        rows.append(m.to_dict())
    return rows


def test_dataflash_2015_log_with_timems():
    pytest.importorskip("pymavlink")
    path = REAL / "dataflash" / "erle_pxf_copter_19-4-2015_7.BIN"
    s = read_imu_log(path)                  # no AttributeError: TimeUS
    assert "IMU instance 0" in s.source and "TimeMS" in s.source
    imu = _dataflash(path, "IMU")
    ms = np.array([r["TimeMS"] for r in imu])
    assert s.time[0] == pytest.approx(ms[0] * 1e-3)
    held = 1e3 / np.median(np.diff(ms))
    assert abs(s.rate / held - 1) < RATE_RTOL
    assert abs(np.linalg.norm(s.accel.mean(axis=0)) - G) < 0.3
    att = _dataflash(path, "ATT")
    r_acc, p_acc = _level_deg(s.accel)
    assert abs(r_acc - np.mean([a["Roll"] for a in att])) < LEVEL_TOL_DEG
    assert abs(p_acc - np.mean([a["Pitch"] for a in att])) < LEVEL_TOL_DEG


@pytest.mark.parametrize("name", ["erle_pxf_copter_19-4-2015_7.BIN",
                                  "amc_backend_log_80k.bin"])
def test_dataflash_att_read_and_its_tilt_matches_the_accelerometer(name):
    """``ATT`` read on the IMU's clock; its roll/pitch over the log against the tilt of the
    mean specific force (the copter near rest on the ground in both logs)."""
    pytest.importorskip("pymavlink")
    from raysim.io.flight_logs.attitude import read_attitude_log

    path = REAL / "dataflash" / name
    att = read_attitude_log(path)
    s = read_imu_log(path)
    assert "ArduPilot DataFlash ATT" in att.source
    rows = _dataflash(path, "ATT")
    stamp = "TimeUS" if "TimeUS" in rows[0] else "TimeMS"
    t = np.array([r[stamp] for r in rows]) * (1e-6 if stamp == "TimeUS" else 1e-3)
    assert att.time[0] == pytest.approx(t[0])
    assert abs(att.rate * np.median(np.diff(t)) - 1) < RATE_RTOL
    inside = (att.time >= s.time[0]) & (att.time <= s.time[-1])
    assert inside.sum() >= 2                                       # the same clock
    ypr = att.rotation[inside].as_euler("ZYX", degrees=True)
    r_acc, p_acc = _level_deg(s.accel)
    assert abs(r_acc - ypr[:, 2].mean()) < LEVEL_TOL_DEG
    assert abs(p_acc - ypr[:, 1].mean()) < LEVEL_TOL_DEG
    assert att.euler_deg(att.time[0])[0] == pytest.approx(rows[0]["Yaw"], abs=1e-4)


def test_dataflash_recent_fragment_instances_and_batch_sampler():
    pytest.importorskip("pymavlink")
    path = REAL / "dataflash" / "amc_backend_log_80k.bin"
    s = read_imu_log(path)
    assert "IMU instance 0" in s.source and "TimeUS" in s.source
    assert "IMU[1]" in s.source                               # the second IMU listed
    assert "ISBD[0]" in s.source and "accel 0 sample" in s.source   # gyro-only batch: why
    us = np.array([r["TimeUS"] for r in _dataflash(path, "IMU") if r["I"] == 0])
    assert abs(s.rate / (1e6 / np.median(np.diff(us))) - 1) < RATE_RTOL
    att = _dataflash(path, "ATT")
    r_acc, p_acc = _level_deg(s.accel)
    assert abs(r_acc - np.mean([a["Roll"] for a in att])) < LEVEL_TOL_DEG
    assert abs(p_acc - np.mean([a["Pitch"] for a in att])) < LEVEL_TOL_DEG
    s1 = read_imu_log(path, instance=1)
    assert "IMU instance 1" in s1.source
    with pytest.raises(ValueError, match=r"topic='ISBD'.*ISBD\[0\]"):
        read_imu_log(path, topic="ISBD")


# --------------------------------------------------------------------------- TI configurations

def _half_wavelengths(m) -> np.ndarray:
    """Virtual positions (x, y) in units of lambda/2, ``[channel, 2]``."""
    return np.round(m.array.virtual_positions[:, :2] / (m.config.center_wavelength / 2), 6)


@pytest.mark.parametrize("name, f0_ghz, samples, loops, tx_order", [
    ("tiros_1443_3d.cfg", 77.0, 240, 16, (0, 2, 1)),
    ("tiros_1843_3d.cfg", 77.0, 256, 16, (0, 2, 1)),
])
def test_77ghz_three_tx_cfgs_get_the_shared_14xx_18xx_layout(name, f0_ghz, samples, loops,
                                                              tx_order):
    m = read_mmwave_config(REAL / "mmwave" / name)
    assert m.board == "xWR14xx/xWR18xx" and m.tx_order == tx_order
    assert m.fmt.num_samples == samples and m.config.num_chirps == loops
    assert m.config.carrier_frequency == pytest.approx(f0_ghz * 1e9 + 70e12 * 7e-6)
    v = _half_wavelengths(m)
    # TX2 (slot 1) two lambda along x; TX1 (slot 2) lambda along x, raised lambda/2
    assert np.array_equal(v[4:8], [[4, 0], [5, 0], [6, 0], [7, 0]])
    assert np.array_equal(v[8:12], [[2, 1], [3, 1], [4, 1], [5, 1]])
    assert m.fmt.layout == "2lane"
    assert read_mmwave_config(REAL / "mmwave" / name, board="xWR14xx").fmt.layout == "4lane"


def test_1642_cfg_is_ambiguous_and_its_board_gives_eight_in_a_row():
    path = REAL / "mmwave" / "tiros_1642_2d.cfg"
    with pytest.raises(ValueError, match=r"xWR14xx.*xWR16xx.*xWR18xx.*--board"):
        read_mmwave_config(path)
    m = read_mmwave_config(path, board="xWR16xx")
    assert m.board == "xWR16xx" and m.tx_order == (0, 1) and m.fmt.num_samples == 256
    assert np.array_equal(_half_wavelengths(m), [[i, 0] for i in range(8)])
    assert m.array.grid_shape is None or m.array.grid_shape[1] == 1


def test_6843_cfgs_need_their_board():
    isk, aop = REAL / "mmwave" / "tiros_6843ISK_3d.cfg", REAL / "mmwave" / "tiros_6843AOP_2d.cfg"
    for path in (isk, aop):
        with pytest.raises(ValueError, match="IWR6843ISK.*IWR6843AOP.*IWR6843ODS"):
            read_mmwave_config(path)
    m = read_mmwave_config(isk, board="IWR6843ISK")
    assert m.config.carrier_frequency == pytest.approx(60e9 + 100e12 * 7e-6)
    assert m.fmt.num_samples == 240 and m.config.num_chirps == 16
    # TI's antGeometry0/1 of the ISK (virtual order TX0, TX1, TX2): x = -antGeometry0
    ag0 = np.array([0, -1, -2, -3, -2, -3, -4, -5, -4, -5, -6, -7])
    ag1 = np.array([-1, -1, -1, -1, 0, 0, 0, 0, -1, -1, -1, -1])
    by_tx = {t: _half_wavelengths(m)[4 * s: 4 * s + 4] for s, t in enumerate(m.tx_order)}
    ti = {t: np.column_stack([-ag0, ag1 + 1])[4 * t: 4 * t + 4] for t in range(3)}
    for t in range(3):
        assert np.array_equal(by_tx[t], ti[t])
    a = read_mmwave_config(aop, board="IWR6843AOP")
    assert a.tx_order == (0, 1) and np.array_equal(a.channel_sign, [1, -1, 1, -1] * 2)
    # TI's AOP geometry: TX0's four virtual antennas a 2x2 square, TX1's one diagonal away
    ag0 = np.array([-1, -1, 0, 0, -3, -3, -2, -2])
    ag1 = np.array([-1, 0, -1, 0, -3, -2, -3, -2])
    assert np.array_equal(_half_wavelengths(a), np.column_stack([-ag0, ag1]))


def test_studio_json_6843_three_tx():
    path = REAL / "mmwave" / "eyes_mmwaveDevice.mmwave.json"
    with pytest.raises(ValueError, match="IWR6843ISK.*IWR6843AOP"):
        read_mmwave_config(path)
    m = read_mmwave_config(path, board="IWR6843ISK")
    assert m.tx_order == (0, 1, 2) and m.config.num_chirps == 85 and m.num_frames == 100
    assert 60e9 < m.config.carrier_frequency < 64e9
    assert m.array.virtual_positions.shape == (12, 3)


def test_advanced_subframe_cfg_is_refused_by_name():
    with pytest.raises(ValueError, match="advFrameCfg.*not supported"):
        read_mmwave_config(REAL / "mmwave" / "jetson_profile_advanced_subframe.cfg")


def test_px4_log_exported_by_ulog2csv_reads_as_the_log(tmp_path):
    """pyulog's own CSV export of ``sensor_combined`` (float32 printed, microsecond stamps)."""
    from pyulog.ulog2csv import convert_ulog2csv

    from raysim.io.flight_logs.ulog import read_px4_ulog

    log = REAL / "ulog" / "sample_log_small.ulg"
    convert_ulog2csv(str(log), "sensor_combined", str(tmp_path), ",", None, None)
    (csv,) = tmp_path.glob("*_sensor_combined_0.csv")
    got, want = read_imu_log(csv), read_px4_ulog(log, topic="sensor_combined", instance=0)
    assert "PX4 sensor_combined (pyulog ulog2csv)" in got.source
    assert got.interval == want.interval > 0          # each sample a 4-5 ms average
    np.testing.assert_allclose(got.time, want.time, rtol=0, atol=1e-6)
    f32 = 2.0 ** -24                     # float32 printed to round trip: half an ulp
    np.testing.assert_allclose(got.gyro, want.gyro, rtol=f32, atol=1e-30)
    np.testing.assert_allclose(got.accel, want.accel, rtol=f32, atol=1e-30)


def test_every_real_file_is_covered_here():
    """A new file in the folder needs a test above."""
    covered = {"sample_log_small.ulg", "sample_appended_multiple.ulg",
               "erle_pxf_copter_19-4-2015_7.BIN", "amc_backend_log_80k.bin",
               "tiros_1443_3d.cfg", "tiros_1642_2d.cfg", "tiros_1843_3d.cfg",
               "tiros_6843ISK_3d.cfg", "tiros_6843AOP_2d.cfg",
               "jetson_profile_advanced_subframe.cfg", "eyes_mmwaveDevice.mmwave.json"}
    present = {p.name for p in REAL.rglob("*") if p.is_file() and p.name != "README.md"}
    assert present <= covered, sorted(present - covered)
