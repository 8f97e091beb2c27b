"""The velocity error the IMU's noise leaves, estimated from the radar's Doppler residuals.

The radar-inertial estimate (:mod:`compensation.radar_inertial`) corrects the
integration's inputs (initial velocity, attitude, biases, clock): one smooth
correction over the record. The IMU's white noise and scale errors leave a
velocity error that is not smooth: a random walk of the accelerometer noise,
an integrated one through gravity of the gyro noise, and the scale error times
the velocity change (``s`` the time since the reference, ``dv`` the velocity
change since then)::

    K(t, t') = (N_a^2 min(s, s') + sigma_s^2 dv . dv') I
               + g^2 N_g^2 s^2 (3 s' - s) / 6 diag(1, 1, 0)      (s <= s')

The estimate treats it as correlated measurement noise, so the initial state
is right but the motion of each frame keeps that error: at a consumer MEMS
grade (160 ug/sqrt(Hz), 1 % scale) a few mm/s within half a second, which a
radar moving across its targets at 0.3 m/s turns into tenths of a degree of
azimuth (:mod:`compensation.azimuth_shift`). Every block's Doppler measures it
along the scatterers' directions to hundredths of a mm/s, so its conditional
mean given the residuals is known (least-squares collocation: Moritz,
*Advanced Physical Geodesy*, 1980, ch. 2; the smoothed noise of a Kalman
smoother)::

    s(t) = sum_m K(t, t_m) J_m^T (C^-1 r)_m

``J_m`` the measurement's response to a velocity correction (the velocity
columns of the Jacobian), ``C`` the measurement covariance of the estimate and
``r`` its residuals. Direction errors, which the covariance also holds, are
not velocity: what is common to a scatterer over the frames stays theirs. The
position correction is the integral of ``s`` from the reference time.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ._checks import finite_array

__all__ = ["SIGNAL_STEP_S", "imu_noise_kernel", "imu_noise_terms", "smoothed_motions",
           "velocity_signal", "with_velocity_signal"]

#: Step of the grid on which the signal is integrated into a position [s] (the kernel
#: is smooth: a random walk's mean given measurements is piecewise linear between them).
SIGNAL_STEP_S = 1e-3


def imu_noise_terms(s_a, s_b, dv_a, dv_b, imu, gravity: float) -> tuple[np.ndarray, np.ndarray]:
    """The two scalar parts of ``K(t_a, t_b)`` (module docstring), ``[a, b]`` each
    [m^2/s^2]: the isotropic one (accelerometer walk and scale errors) and the one on
    the horizontal axes (gyro walk through gravity). The radar-inertial estimate's
    measurement covariance uses the same (:func:`compensation.radar_inertial`).

    Parameters
    ----------
    s_a, s_b : array_like, shapes ``[a]``, ``[b]``
        Times since the reference [s].
    dv_a, dv_b : array_like, shapes ``[a, 3]``, ``[b, 3]``
        Velocity change since the reference at those times [m/s].
    imu : compensation.ImuErrors
        ``accel_noise_density``, ``gyro_noise_density``, ``accel_scale_sigma``.
    gravity : float
        [m/s^2].
    """
    s_a, s_b = np.abs(np.asarray(s_a, dtype=float)), np.abs(np.asarray(s_b, dtype=float))
    lo, hi = np.minimum.outer(s_a, s_b), np.maximum.outer(s_a, s_b)
    iso = (imu.accel_noise_density ** 2 * lo
           + imu.accel_scale_sigma ** 2 * (np.asarray(dv_a) @ np.asarray(dv_b).T))
    tilt = (gravity * imu.gyro_noise_density) ** 2 * lo ** 2 * (3 * hi - lo) / 6
    return iso, tilt


def imu_noise_kernel(s_a, s_b, dv_a, dv_b, imu, gravity: float) -> np.ndarray:
    """``K(t_a, t_b)`` of the module docstring, ``[a, b, 3, 3]`` [m^2/s^2] (arguments as
    :func:`imu_noise_terms`)."""
    iso, tilt = imu_noise_terms(s_a, s_b, dv_a, dv_b, imu, gravity)
    out = iso[..., None, None] * np.eye(3)
    out[..., :2, :2] += tilt[..., None, None] * np.eye(2)
    return out


def velocity_signal(times, t_ref: float, meas_times, jac_velocity, weighted_residual, imu,
                    gravity: float, dv_times, dv_meas) -> np.ndarray:
    """Conditional mean of the IMU noise's velocity error at ``times``, ``[time, 3]`` [m/s].

    Parameters
    ----------
    times : array_like, shape ``[time]``
        Radar times [s].
    t_ref : float
        Reference time of the estimate [s].
    meas_times : array_like, shape ``[measurement]``
        Mid-times of the Doppler measurements' blocks [s].
    jac_velocity : array_like, shape ``[measurement, 3]``
        Response of each measurement to a velocity correction [1].
    weighted_residual : array_like, shape ``[measurement]``
        ``C^-1 r`` of the Doppler rows [s/m].
    imu, gravity
        As for :func:`imu_noise_kernel`.
    dv_times, dv_meas : array_like, shapes ``[time, 3]``, ``[measurement, 3]``
        Velocity change since the reference [m/s].
    """
    t = finite_array("times", times, ndim=1)
    tm = finite_array("meas_times", meas_times, ndim=1)
    j = finite_array("jac_velocity", jac_velocity, shape=(tm.size, 3))
    a = finite_array("weighted_residual", weighted_residual, shape=(tm.size,))
    k = imu_noise_kernel(t - t_ref, tm - t_ref, dv_times, dv_meas, imu, gravity)
    return np.einsum("tmij,mj,m->ti", k, j, a)


def with_velocity_signal(motions, t_ref: float, signal) -> list:
    """``motions`` with the velocity ``signal(times) [time, 3]`` added and its integral from
    ``t_ref`` added to the positions (on a :data:`SIGNAL_STEP_S` grid, trapezoids)."""
    end = max(float(m.time.max()) for m in motions)
    start = min(t_ref, min(float(m.time.min()) for m in motions))
    grid = np.arange(start, end + SIGNAL_STEP_S, SIGNAL_STEP_S)
    grid = np.union1d(grid, [t_ref])
    sv = signal(grid)                                                    # [grid, 3]
    pos = np.concatenate([np.zeros((1, 3)), np.cumsum(
        0.5 * (sv[1:] + sv[:-1]) * np.diff(grid)[:, None], axis=0)])
    pos -= pos[np.searchsorted(grid, t_ref)]
    out = []
    for m in motions:
        dv = np.column_stack([np.interp(m.time, grid, sv[:, i]) for i in range(3)])
        dp = np.column_stack([np.interp(m.time, grid, pos[:, i]) for i in range(3)])
        out.append(replace(m, position=m.position + dp, velocity=m.velocity + dv))
    return out


def smoothed_motions(motions, t_ref: float, meas_times, jac_velocity, weighted_residual,
                     dv_meas, imu, gravity: float) -> tuple[list, float]:
    """``motions`` with the IMU noise's velocity error estimated and removed
    (:func:`velocity_signal`, :func:`with_velocity_signal`), and the largest velocity
    correction applied [m/s]. The velocity change since the reference at any time is
    read from the motions themselves (linear between frames)."""
    t_all = np.concatenate([m.time for m in motions])
    order = np.argsort(t_all)
    v_all = np.concatenate([m.velocity for m in motions])[order] - motions[0].velocity[0]
    t_all = t_all[order]

    def signal(t):
        dv = np.column_stack([np.interp(t, t_all, v_all[:, i]) for i in range(3)])
        return velocity_signal(t, t_ref, meas_times, jac_velocity, weighted_residual, imu,
                               gravity, dv, dv_meas)

    out = with_velocity_signal(motions, t_ref, signal)
    most = max(float(np.abs(a.velocity - b.velocity).max()) for a, b in zip(
        out, motions, strict=True))
    return out, most
