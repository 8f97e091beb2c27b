"""Inputs in the wrong units or with holes are refused with a message that names them."""

from __future__ import annotations

import numpy as np
import pytest

from compensation import beam_projection, integrate_imu
from compensation.strapdown import COVERAGE_TOLERANCE, GYRO_FULL_SCALE, STANDARD_GRAVITY

EPOCH = 1.7e9        # a flight log's POSIX clock [s]


def _imu(t0=0.0, n=200, rate=1000.0, gyro_scale=1.0, accel_scale=1.0):
    t = t0 + np.arange(n) / rate
    gyro = np.zeros((n, 3))
    gyro[:, 1] = 0.2 * np.sin(2 * np.pi * 5 * (t - t0)) * gyro_scale
    accel = np.tile([0.0, 0.0, -STANDARD_GRAVITY], (n, 1)) * accel_scale
    return t, gyro, accel


def test_gyro_beyond_full_scale_is_reported():
    """A rate in deg/s read as rad/s (or a motion no gyro measures) gives a stated warning."""
    t, gyro, accel = _imu()
    plain = integrate_imu(t, gyro, accel, t[10:20], velocity="hover").warnings
    assert not any(w.startswith("gyro units:") for w in plain)
    gyro[:, 2] = np.rad2deg(0.7)                   # 0.7 rad/s written in deg/s: 40 "rad/s"
    assert np.rad2deg(0.7) > GYRO_FULL_SCALE
    m = integrate_imu(t, gyro, accel, t[10:20], velocity="hover")
    assert any(w.startswith("gyro units:") and "deg/s given?" in w for w in m.warnings)


def test_accelerometer_in_g_is_refused():
    t, gyro, accel = _imu(accel_scale=1.0 / STANDARD_GRAVITY)          # (0, 0, -1) g
    with pytest.raises(ValueError, match=r"accel has a mean magnitude of 1 m/s\^2.*in g\?"):
        integrate_imu(t, gyro, accel, t[10:20], velocity="hover")


@pytest.mark.parametrize("gravity", [-9.81, 0.0, np.nan])
def test_gravity_must_be_a_positive_magnitude(gravity):
    t, gyro, accel = _imu()
    with pytest.raises(ValueError, match="gravity must be a finite positive number"):
        integrate_imu(t, gyro, accel, t[10:20], velocity="hover", gravity=gravity)


def test_coverage_tolerance_is_absolute_on_an_epoch_clock():
    """Chirps 1.7 s after the record on a 1.7e9 s clock are refused (a relative
    tolerance of 1e-9 let them through); rounding-level overshoot is accepted."""
    t, gyro, accel = _imu(t0=EPOCH)
    with pytest.raises(ValueError, match="imu_time only covers"):
        integrate_imu(t, gyro, accel, np.array([t[5], t[-1] + 1.7]), velocity="hover")
    m = integrate_imu(t, gyro, accel, np.array([t[5], t[-1] + 0.5 * COVERAGE_TOLERANCE]),
                      velocity="hover")
    assert m.num_chirps == 2


def _cube():
    rng = np.random.default_rng(0)
    x = (rng.normal(size=(4, 4, 3)) + 1j * rng.normal(size=(4, 4, 3))).astype(np.complex64)
    p = np.stack(np.meshgrid(np.arange(2), np.arange(2), indexing="ij"), -1).reshape(4, 2)
    pos = np.column_stack([p * 2e-3, np.zeros(4)])
    return x, pos


def test_nan_in_the_cube_is_named():
    x, pos = _cube()
    x[2, 1, 0] = np.nan
    with pytest.raises(ValueError, match=r"rc must be finite; 1 entries are not.*\[2, 1, 0\]"):
        beam_projection(x, pos, wavelength=3.9e-3, range_axis=[1.0, 2.0, 3.0],
                        azimuth=[0.0], elevation=[0.0])


def test_angle_grid_in_degrees_is_named():
    x, pos = _cube()
    with pytest.raises(ValueError, match=r"azimuth must be angles in radians.*30.*degrees\?"):
        beam_projection(x, pos, wavelength=3.9e-3, range_axis=[1.0, 2.0, 3.0],
                        azimuth=np.arange(-30.0, 31.0, 1.0), elevation=[0.0])
    out = beam_projection(x, pos, wavelength=3.9e-3, range_axis=[1.0, 2.0, 3.0],
                          azimuth=np.deg2rad(np.arange(-30.0, 31.0, 1.0)), elevation=[0.0])
    assert out.data.shape == (4, 3, 61, 1)
