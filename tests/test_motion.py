"""Trajectory kinematics: analytic derivatives against independent numerical references."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from raysim.platform.motion import (
    HoverJitterSpec,
    Ramp,
    Sinusoid,
    Trajectory,
    constant_velocity,
    hover_jitter,
    sinusoid,
    stationary,
)

#: Central-difference step [s] and the agreement it allows (O(h^2) truncation).
FD_STEP = 1e-6
FD_RTOL = 1e-6


def ref_body_rate(traj: Trajectory, t: np.ndarray) -> np.ndarray:
    """Body rate from the rotation log of R(t-h)^T R(t+h) (no Euler-rate formula)."""
    r_minus, r_plus = traj.attitude(t - FD_STEP), traj.attitude(t + FD_STEP)
    return (r_minus.inv() * r_plus).as_rotvec() / (2 * FD_STEP)


@pytest.fixture
def six_dof() -> Trajectory:
    comps = (Sinusoid("roll", 0.3, 7.0, 0.2), Sinusoid("pitch", 0.25, 11.0, 1.0),
             Sinusoid("yaw", 0.5, 5.0, -0.4), Sinusoid("x", 0.05, 3.0),
             Sinusoid("y", 0.02, 4.0, 0.5), Ramp("z", 0.1, 0.3, 0.2))
    return Trajectory(comps)


def test_angular_rate_matches_rotation_derivative(six_dof):
    t = np.linspace(0, 0.2, 57)
    np.testing.assert_allclose(six_dof.angular_rate(t), ref_body_rate(six_dof, t),
                               rtol=FD_RTOL, atol=FD_RTOL)


def test_velocity_and_acceleration_match_position_derivatives(six_dof):
    t = np.linspace(0, 0.2, 31)
    hv, h = 1e-6, 1e-4  # first and second differences
    v_fd = (six_dof.position(t + hv) - six_dof.position(t - hv)) / (2 * hv)
    a_fd = (six_dof.position(t + h) - 2 * six_dof.position(t) + six_dof.position(t - h)) / h**2
    np.testing.assert_allclose(six_dof.velocity(t), v_fd, rtol=1e-6, atol=1e-8)
    np.testing.assert_allclose(six_dof.acceleration(t), a_fd, rtol=1e-4, atol=1e-5)


def test_euler_convention_is_scipy_zyx():
    traj = Trajectory((Ramp("yaw", 0.3), Ramp("pitch", -0.2), Ramp("roll", 0.1)))
    expected = Rotation.from_euler("ZYX", [0.3, -0.2, 0.1]).as_matrix()
    np.testing.assert_allclose(traj.attitude([0.0]).as_matrix()[0], expected, atol=1e-15)


def test_point_world_applies_rotation_then_translation():
    traj = Trajectory((Ramp("yaw", np.pi / 2), Ramp("x", 1.0)))
    p = traj.point_world([0.0], np.array([[1.0, 0.0, 0.0]]))
    np.testing.assert_allclose(p[0, 0], [1.0, 1.0, 0.0], atol=1e-15)  # forward -> east


def test_constant_velocity_and_stationary():
    traj = constant_velocity([1.0, -2.0, 0.5])
    np.testing.assert_allclose(traj.position([2.0])[0], [2.0, -4.0, 1.0])
    assert np.all(stationary().angular_rate(np.linspace(0, 1, 5)) == 0)


def test_sinusoid_amplitude_and_frequency():
    traj = sinusoid("pitch", 0.1, 20.0)
    t = np.array([1 / 80])  # quarter period
    assert traj.euler(t)[0, 1] == pytest.approx(0.1, rel=1e-12)


def test_hover_jitter_is_seeded_and_has_the_specified_rms():
    spec = HoverJitterSpec(vibration_rms=0.0)
    a, b = hover_jitter(7, spec), hover_jitter(7, spec)
    t = np.linspace(0, 200, 40_001)  # 200 Hz sampling, bands end at 8 Hz
    q = a.states(t)[0]
    np.testing.assert_array_equal(q, b.states(t)[0])
    # random tones: the time RMS over 200 s approaches sqrt(sum a^2 / 2) within 5 %
    np.testing.assert_allclose(np.std(q[:, 3]), spec.attitude_rms[0], rtol=0.05)
    np.testing.assert_allclose(np.std(q[:, 0]), spec.position_rms[0], rtol=0.05)
    assert not np.array_equal(q, hover_jitter(8, spec).states(t)[0])


@pytest.mark.parametrize("bad", [{"axis": "w", "amplitude": 1, "frequency": 1},
                                 {"axis": "x", "amplitude": 1, "frequency": -1},
                                 {"axis": "x", "amplitude": float("inf"), "frequency": 1}])
def test_bad_sinusoid(bad):
    with pytest.raises(ValueError):
        Sinusoid(**bad)
