"""`raysim compensate --velocity radar --time-offset auto`: the unknowns from the cube itself."""

from __future__ import annotations

import json

import numpy as np

from raysim.cli import main
from raysim.echoes.oracle import PointTarget, simulate_point_targets
from raysim.io import write_imu_csv
from raysim.platform.imu import simulate_imu
from raysim.platform.motion import hover_jitter
from raysim.processing import metrics
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Clock-offset error of one frame's estimate [s].
OFFSET_TOL_S = 0.5e-3
#: Residual pseudo-velocity of the compensated beam [Doppler bins].
PV_TOL_BINS = 0.05
OFFSET_S = 3e-3


def test_compensate_estimates_offset_and_velocity(tmp_path, capsys):
    """One frame, consumer MEMS IMU 3 ms late, unknown velocity: both estimated, printed and
    stored; the compensated beam of the target sits at zero Doppler."""
    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6)
    arr = upa(8, 8, wavelength=cfg.wavelength)
    lever = np.array([0.03, -0.02, 0.10])
    traj = hover_jitter(4)
    targets = [PointTarget.at(12.0, np.deg2rad(20), np.deg2rad(-10), radar_origin=lever),
               PointTarget.at(9.0, np.deg2rad(-25), np.deg2rad(15), radar_origin=lever)]
    frame = simulate_point_targets(cfg, arr, targets, traj, lever_arm=lever)
    np.savez(tmp_path / "cube.npz", data=frame.data, chirp_times=frame.chirp_times,
             element_positions=arr.virtual_positions, carrier_frequency=cfg.carrier_frequency,
             bandwidth=cfg.bandwidth, chirp_duration=cfg.chirp_duration,
             sample_rate=cfg.sample_rate, grid_shape=np.array(arr.grid_shape), lever_arm=lever)
    s = simulate_imu(traj, "consumer_mems", rate=1000.0, start=-0.6, end=0.6, seed=4,
                     time_offset=OFFSET_S)
    imu = write_imu_csv(tmp_path / "imu.csv", s)
    out = tmp_path / "beams.npz"
    ypr = np.rad2deg(traj.euler([0.0])[0])
    code = main(["compensate", str(tmp_path / "cube.npz"), "--imu", str(imu), "--out", str(out),
                 "--range-m", "8:13", "--az-deg", "20:20:1", "--el-deg", "-10:-10:1",
                 "--velocity", "radar", "--time-offset", "auto",
                 "--initial-attitude-deg", ",".join(f"{a:.12g}" for a in ypr)])
    assert code == 0
    printed = capsys.readouterr().out
    assert "self-calibration" in printed and "time offset" in printed
    # the radar-inertial state: what the scene leaves unconstrained, printed and stored
    assert "unconstrained by the radar (kept at the " in printed
    with np.load(out) as z:
        report = json.loads(str(z["self_calibration"]))
        gate = int(np.argmin(np.abs(z["range_m"] - 12.0)))
        slow = z["beams"][:, gate, 0, 0]
    assert abs(report["time_offset_s"] - OFFSET_S) <= OFFSET_TOL_S
    assert report["scatterers"] >= 2
    ri = report["radar_inertial"]
    # each component the Doppler leaves alone names the prior it kept: the clock's is
    # the phase-track fit's (it ran), not the IMU grade's
    assert set(report["held_at"]) == set(ri["unconstrained"])
    assert report["held_at"]["clock_offset"] == "clock fit"
    assert len(ri["state"]) == len(ri["sigma"]) == len(ri["state_names"]) == 14
    assert set(report["unconstrained"]) <= set(ri["state_names"])
    pv = metrics.pseudo_velocity(slow, cfg.chirp_interval, cfg.center_wavelength)
    assert abs(pv) / cfg.velocity_resolution <= PV_TOL_BINS


def test_time_offset_option_refuses_words(tmp_path, capsys):
    np.savez(tmp_path / "c.npz", data=np.zeros((4, 2, 4), complex), chirp_times=np.arange(4.0),
             element_positions=np.zeros((2, 3)), carrier_frequency=77e9, bandwidth=1e9,
             chirp_duration=1e-5, sample_rate=1e6)
    t = np.arange(0, 5, 0.01)
    (tmp_path / "imu.csv").write_text("time_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z\n"
                                      + "".join(f"{v},0,0,0,0,0,-9.8\n" for v in t))
    code = main(["compensate", str(tmp_path / "c.npz"), "--imu", str(tmp_path / "imu.csv"),
                 "--out", str(tmp_path / "o.npz"), "--time-offset", "soon"])
    assert code == 2
    assert "--time-offset must be a number of seconds or 'auto', got 'soon'" in \
        capsys.readouterr().err
