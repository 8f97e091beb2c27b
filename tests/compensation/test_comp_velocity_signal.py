"""The IMU noise's velocity error estimated from Doppler residuals (least-squares collocation).

Closed form: for a random walk ``w`` (kernel ``N^2 min(s, s')``) measured once, exactly,
at ``s_m``, the conditional mean is the Brownian bridge ``w(s_m) min(s, s_m) / s_m``
(Moritz, *Advanced Physical Geodesy*, 1980, ch. 2; Karatzas & Shreve, 1991, 2.9.B).
Statistics: over simulated realisations the estimate's error divided by its
conditional spread has unit spread.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from compensation import PlatformMotion
from compensation.velocity_signal import (
    imu_noise_kernel,
    velocity_signal,
    with_velocity_signal,
)

#: Consumer-MEMS noise (160 ug/sqrt(Hz), 0.014 deg/s/sqrt(Hz), 1 % scale), SI units.
IMU = SimpleNamespace(accel_noise_density=160e-6 * 9.80665,
                      gyro_noise_density=np.deg2rad(0.014), accel_scale_sigma=0.01)
G = 9.80665
#: Relative error of the closed forms (float64 sums of a few terms).
CLOSED_FORM_RTOL = 1e-9
#: Realisations of the statistical check, and the band its normalised spread must fall in
#: (the sample spread of 3 x 600 unit normals is within 0.06 of one at 3 sigma).
DRAWS, SPREAD_BAND = 600, (0.9, 1.1)


def test_one_exact_measurement_gives_the_brownian_bridge():
    imu = SimpleNamespace(accel_noise_density=2e-3, gyro_noise_density=0.0,
                          accel_scale_sigma=0.0)
    s_m, w_m = 0.2, 3e-3                       # measured along +x: J = [1, 0, 0]
    k_mm = imu_noise_kernel([s_m], [s_m], np.zeros((1, 3)), np.zeros((1, 3)), imu, G)[0, 0]
    alpha = np.array([w_m / k_mm[0, 0]])       # C^-1 r of a noiseless measurement
    t = np.array([0.0, 0.05, 0.1, 0.2, 0.3])
    s = velocity_signal(t, 0.0, [s_m], [[1.0, 0.0, 0.0]], alpha, imu, G, np.zeros((5, 3)),
                        np.zeros((1, 3)))
    np.testing.assert_allclose(s[:, 0], w_m * np.minimum(t, s_m) / s_m,
                               rtol=CLOSED_FORM_RTOL, atol=1e-15)
    assert np.all(s[:, 1:] == 0.0)


def test_estimate_error_is_covered_by_its_conditional_spread():
    """Random walks of the accelerometer and (horizontal) of the gyro through gravity,
    measured by the Doppler of five directions in 24 blocks over half a second: the error
    of the estimate over its conditional spread has unit spread, and the estimate removes
    most of the error."""
    rng = np.random.default_rng(5)
    t_meas = np.repeat(np.linspace(0.01, 0.5, 24), 5)
    u = rng.normal(size=(5, 3)) + [0.0, 0.0, 3.0]
    u = np.tile(u / np.linalg.norm(u, axis=1, keepdims=True), (24, 1))
    j = -u                                               # v_r = -u . dv
    sigma = 2e-5                                         # Doppler spread [m/s]
    t_eval = np.array([0.0, 0.13, 0.26, 0.39, 0.52])
    t_all = np.concatenate([t_meas, t_eval])
    zero = np.zeros((t_all.size, 3))
    k = imu_noise_kernel(t_all, t_all, zero, zero, IMU, G)             # [a, b, 3, 3]
    n = t_all.size
    kf = k.transpose(0, 2, 1, 3).reshape(3 * n, 3 * n)
    draw = np.linalg.cholesky(kf + 1e-18 * np.eye(3 * n))
    m = t_meas.size
    jm = np.zeros((m, 3 * n))
    for i in range(m):
        jm[i, 3 * i:3 * i + 3] = j[i]
    c = jm @ kf @ jm.T + sigma ** 2 * np.eye(m)
    ev = slice(3 * m, 3 * n)
    post = kf[ev, ev] - kf[ev] @ jm.T @ np.linalg.solve(c, jm @ kf[:, ev])
    spread = np.sqrt(np.diag(post)).reshape(-1, 3)
    z, before, after = [], [], []
    for _ in range(DRAWS):
        w = (draw @ rng.normal(size=3 * n)).reshape(n, 3)
        y = np.einsum("mi,mi->m", j, w[:m]) + sigma * rng.normal(size=m)
        est = velocity_signal(t_eval, 0.0, t_meas, j, np.linalg.solve(c, y), IMU, G,
                              np.zeros((t_eval.size, 3)), np.zeros((m, 3)))
        err = est - w[m:]
        keep = spread > 0
        z.append(err[keep] / spread[keep])
        before.append(np.abs(w[m:]).max())
        after.append(np.abs(err).max())
    z = np.concatenate(z)
    assert SPREAD_BAND[0] < z.std() < SPREAD_BAND[1], z.std()
    assert np.median(after) < 0.3 * np.median(before)


def test_signal_moves_velocity_and_position_by_its_integral():
    """A constant signal ``c`` from the reference on: velocities + c, positions
    + c (t - t_ref), on every frame."""
    c = np.array([1e-3, -2e-3, 5e-4])
    ms = [PlatformMotion(t, np.tile(np.eye(3), (t.size, 1, 1)), np.zeros((t.size, 3)),
                         np.zeros((t.size, 3)), np.zeros((t.size, 3)), np.zeros(3))
          for t in (np.linspace(0.5, 0.51, 11), np.linspace(0.6, 0.61, 11))]
    out = with_velocity_signal(ms, 0.5, lambda t: np.tile(c, (np.size(t), 1)))
    for m, o in zip(ms, out, strict=True):
        np.testing.assert_allclose(o.velocity, np.tile(c, (m.time.size, 1)), rtol=1e-12)
        np.testing.assert_allclose(o.position, (m.time - 0.5)[:, None] * c, rtol=1e-9,
                                   atol=1e-15)
        assert np.array_equal(o.attitude, m.attitude)


def test_bad_shapes_are_named():
    with pytest.raises(ValueError, match="jac_velocity"):
        velocity_signal([0.0], 0.0, [0.1, 0.2], [[1.0, 0.0, 0.0]], [1.0, 1.0], IMU, G,
                        np.zeros((1, 3)), np.zeros((2, 3)))
