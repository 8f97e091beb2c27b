"""Strapdown integration: closed forms, accuracy against exact trajectories, validation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation import STANDARD_GRAVITY, integrate_imu
from raysim.platform.imu import simulate_imu
from raysim.platform.motion import Trajectory, hover_jitter, sinusoid

#: Attitude error bound with an ideal 1 kHz IMU [rad] (matrix entries).
ATTITUDE_TOL = 2e-6
#: Radar phase-centre position error bound [m] (1 um = 0.003 rad at 77 GHz).
POSITION_TOL = 1e-6
LEVER = np.array([0.05, -0.02, 0.10])


def _rest_accel(n: int) -> np.ndarray:
    return np.tile([0.0, 0.0, -STANDARD_GRAVITY], (n, 1))


def test_constant_rate_matches_closed_form():
    """A constant body rate w gives R(t) = exp([w t]_x) exactly."""
    t = np.linspace(0.0, 0.05, 51)
    w = np.array([0.3, -0.2, 1.1])
    gyro = np.tile(w, (t.size, 1))
    accel = Rotation.from_rotvec(np.outer(t, w)).apply(np.array([0.0, 0.0, -STANDARD_GRAVITY]),
                                                       inverse=True)
    tc = np.array([0.0, 0.0123, 0.037, 0.05])
    m = integrate_imu(t, gyro, accel, tc, velocity="given", initial_velocity=np.zeros(3))
    ref = Rotation.from_rotvec(np.outer(tc, w)).as_matrix()
    np.testing.assert_allclose(m.attitude, ref, atol=1e-12)
    np.testing.assert_allclose(m.position, 0.0, atol=1e-12)
    np.testing.assert_allclose(m.angular_rate, np.tile(w, (tc.size, 1)), atol=1e-12)


def test_constant_acceleration_matches_closed_form():
    """Level body, constant world acceleration a: p = v0 t + a t^2 / 2."""
    t = np.linspace(0.0, 0.04, 41)
    a = np.array([0.5, -1.0, 2.0])
    accel = np.tile(a - np.array([0.0, 0.0, STANDARD_GRAVITY]), (t.size, 1))
    v0 = np.array([0.1, 0.2, -0.3])
    tc = np.linspace(0.0, 0.04, 7)
    m = integrate_imu(t, np.zeros((t.size, 3)), accel, tc, velocity="given", initial_velocity=v0,
                      initial_position=[1.0, 2.0, 3.0])
    np.testing.assert_allclose(m.position, [1.0, 2.0, 3.0] + np.outer(tc, v0)
                               + 0.5 * np.outer(tc**2, a), atol=1e-12)
    np.testing.assert_allclose(m.velocity, v0 + np.outer(tc, a), atol=1e-12)


TRAJECTORIES = {
    "pitch_20hz": sinusoid("pitch", np.deg2rad(10), 20.0),
    "yaw_10hz": sinusoid("yaw", np.deg2rad(20), 10.0),
    "translation_y": sinusoid("y", 0.05, 5.0),
    "coning": (sinusoid("roll", 0.2, 15.0) + sinusoid("pitch", 0.2, 15.0, 1.0)
               + sinusoid("z", 0.05, 5.0)),
    "hover_jitter": hover_jitter(3),
}


@pytest.mark.parametrize("name", sorted(TRAJECTORIES))
def test_ideal_imu_recovers_pose(name):
    traj: Trajectory = TRAJECTORIES[name]
    s = simulate_imu(traj, "ideal", rate=1000.0, start=-0.02, end=0.06)
    tc = 0.003 + np.arange(256) * 60e-6
    t0 = tc[0]
    m = integrate_imu(s.time, s.gyro, s.accel, tc, lever_arm=LEVER,
                      initial_attitude=traj.attitude([t0]).as_matrix()[0],
                      initial_position=traj.position([t0])[0], velocity="given",
                      initial_velocity=traj.velocity([t0])[0])
    rot = traj.attitude(tc).as_matrix()
    np.testing.assert_allclose(m.attitude, rot, atol=ATTITUDE_TOL)
    np.testing.assert_allclose(m.radar_position, traj.position(tc) + rot @ LEVER,
                               atol=POSITION_TOL)
    np.testing.assert_allclose(m.angular_rate, traj.angular_rate(tc), atol=1e-3)
    # radar velocity v + R (w x r) against a central difference of the truth
    h = 1e-6
    fd = ((traj.position(tc + h) + traj.attitude(tc + h).as_matrix() @ LEVER)
          - (traj.position(tc - h) + traj.attitude(tc - h).as_matrix() @ LEVER)) / (2 * h)
    np.testing.assert_allclose(m.radar_velocity, fd, atol=1e-4)


def test_time_offset_aligns_clocks():
    """IMU clock = radar clock + 3.7 ms: passing the offset gives the same pose."""
    traj = sinusoid("roll", 0.1, 12.0)
    offset = 3.7e-3
    s = simulate_imu(traj, "ideal", rate=1000.0, start=-0.02, end=0.05, time_offset=offset)
    tc = np.linspace(0.0, 0.03, 64)
    m = integrate_imu(s.time, s.gyro, s.accel, tc, time_offset=offset, velocity="given",
                      initial_velocity=np.zeros(3))
    np.testing.assert_allclose(m.attitude, traj.attitude(tc).as_matrix(), atol=ATTITUDE_TOL)
    wrong = integrate_imu(s.time, s.gyro, s.accel, tc, velocity="given",
                          initial_velocity=np.zeros(3))
    assert np.abs(wrong.attitude - traj.attitude(tc).as_matrix()).max() > 1e-3


def test_hover_assumption_zero_mean_velocity():
    """Over whole periods of a sinusoid the hover assumption finds the true velocity."""
    traj = sinusoid("y", 0.05, 5.0)
    s = simulate_imu(traj, "ideal", rate=2000.0, start=0.0, end=0.4)   # two periods
    tc = np.linspace(0.1, 0.13, 32)
    m = integrate_imu(s.time, s.gyro, s.accel, tc, velocity="hover")
    np.testing.assert_allclose(m.velocity, traj.velocity(tc), atol=1e-5)
    # a window that is not a whole period leaves a constant velocity error only
    m2 = integrate_imu(s.time, s.gyro, s.accel, tc, velocity="hover", hover_window=(0.0, 0.15))
    err = m2.velocity - traj.velocity(tc)
    assert np.ptp(err, axis=0).max() < 1e-5 and np.abs(err).max() > 1e-3


@pytest.mark.parametrize("change, match", [
    (dict(gyro="nan"), "gyro must be finite"),
    (dict(accel="inf"), "accel must be finite"),
    (dict(imu_time="unsorted"), "imu_time must be strictly increasing"),
    (dict(chirp_times="late"), "IMU record must cover every chirp"),
    (dict(gyro="short"), r"gyro must have shape \[41, 3\]"),
    (dict(velocity="given"), "needs initial_velocity"),
    (dict(velocity="drift"), "velocity must be one of"),
    (dict(initial_attitude="bad"), "proper rotation"),
])
def test_bad_input_names_the_parameter(change, match):
    t = np.linspace(0.0, 0.04, 41)
    kw = dict(imu_time=t, gyro=np.zeros((41, 3)), accel=_rest_accel(41),
              chirp_times=np.linspace(0.0, 0.03, 8))
    opts = {}
    for key, val in change.items():
        if key == "gyro" and val == "nan":
            kw["gyro"][5, 1] = np.nan
        elif key == "accel":
            kw["accel"][3, 2] = np.inf
        elif key == "imu_time":
            kw["imu_time"] = t.copy()
            kw["imu_time"][[10, 11]] = kw["imu_time"][[11, 10]]
        elif key == "chirp_times":
            kw["chirp_times"] = np.linspace(0.0, 0.05, 8)
        elif key == "gyro":
            kw["gyro"] = np.zeros((40, 3))
        elif key == "initial_attitude":
            opts["initial_attitude"] = np.diag([1.0, 1.0, 2.0])
        else:
            opts[key] = val
    with pytest.raises(ValueError, match=match):
        integrate_imu(kw["imu_time"], kw["gyro"], kw["accel"], kw["chirp_times"], **opts)
