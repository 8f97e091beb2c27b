"""Estimators from the radar against their closed forms (synthetic measurements)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.clock_offset import fit_time_shift, phase_misfit
from compensation.ego_velocity import fit_ego_velocity, slow_time_velocity
from compensation.geometry import direction
from compensation.gyro_bias import _skew, fit_gyro_bias

#: Range-rate recovery from a noise-free tone [m/s] (float64 phase of 64 samples).
TONE_TOL = 1e-9
#: Velocity recovery from exact range rates [m/s].
VELOCITY_TOL = 1e-9
#: Relative agreement of covariances with their closed form [1].
COV_RTOL = 1e-6
#: Time-shift recovery from exact linearised phases [s].
SHIFT_TOL = 1e-12
#: Gyro-bias recovery from directions drifting exactly as the first-order model,
#: relative to |b| [1]: the fit linearises about the mean direction, an error of
#: the order of the largest drift angle |b| t (2.6e-3 rad here).
BIAS_RTOL = 5e-3

LAM = 3.9e-3
T = np.arange(64) * 60e-6


@pytest.mark.parametrize("v_r", [-1.1, -0.2, 0.0, 0.37, 0.9])
def test_slow_time_velocity_of_a_tone(v_r):
    """``y = exp(j 4 pi v_r t / lambda)`` (phase growing with range) gives back ``v_r``."""
    y = 2.0 * np.exp(1j * (4 * np.pi * v_r * T / LAM + 0.3))
    v, s = slow_time_velocity(y, T, LAM)
    assert abs(v - v_r) <= TONE_TOL
    assert s <= TONE_TOL


def test_slow_time_velocity_spread_follows_the_line_fit():
    """White phase noise: slope spread sigma_phi / sqrt(sum (t - tbar)^2) (Kay eq. 3.41)."""
    rng = np.random.default_rng(1)
    sig_phi = 0.05
    est = []
    for _ in range(200):
        y = np.exp(1j * (4 * np.pi * 0.2 * T / LAM + rng.normal(0, sig_phi, T.size)))
        est.append(slow_time_velocity(y, T, LAM))
    est = np.array(est)
    expect = LAM / (4 * np.pi) * sig_phi / np.sqrt(np.sum((T - T.mean()) ** 2))
    assert abs(np.std(est[:, 0]) / expect - 1) < 0.2        # 200 draws: ~5 % spread of a std
    assert abs(np.median(est[:, 1]) / expect - 1) < 0.2


def _dirs(n, rng):
    return direction(rng.uniform(-1, 1, n), rng.uniform(-0.6, 0.6, n))


def test_ego_velocity_exact_and_covariance_closed_form():
    """Kellner's model ``v_r = -u . v``; covariance ``(A^T A / s^2 + I / p^2)^-1``."""
    rng = np.random.default_rng(2)
    u = _dirs(12, rng)
    v = np.array([0.3, -0.1, 0.05])
    s = np.full(12, 1e-3)
    fit = fit_ego_velocity(u, -u @ v, s, prior_sigma=1.0)
    closed = np.linalg.inv(u.T @ u / 1e-6 + np.eye(3))
    np.testing.assert_allclose(fit.covariance, closed, rtol=COV_RTOL)
    # maximum a posteriori: the prior shrinks by about (s / p)^2 = 1e-6 relative
    assert np.all(np.abs(fit.velocity - closed @ (u.T @ (u @ v)) / 1e-6) <= VELOCITY_TOL)
    assert np.all(np.abs(fit.velocity - v) <= 1e-5 * np.linalg.norm(v))
    assert fit.inliers.all()


def test_ego_velocity_rejects_moving_scatterers():
    """Three of twelve detections move: the consensus drops them, the fit holds."""
    rng = np.random.default_rng(3)
    u = _dirs(12, rng)
    v = np.array([-0.2, 0.4, 0.1])
    vr = -u @ v + rng.normal(0, 1e-3, 12)
    vr[[1, 5, 9]] += [0.8, -0.5, 1.3]
    fit = fit_ego_velocity(u, vr, np.full(12, 1e-3))
    assert not fit.inliers[[1, 5, 9]].any() and fit.inliers.sum() == 9
    assert np.all(np.abs(fit.velocity - v) <= 5 * fit.sigma)
    naive = np.linalg.lstsq(-u, vr, rcond=None)[0]
    assert np.linalg.norm(naive - v) > 10 * np.linalg.norm(fit.velocity - v)


def test_ego_velocity_minimal_consensus_rejects_nothing():
    """Five stationary scatterers whose stated spreads are 1000x too small: no four agree
    within the threshold, so none is rejected (any three fit exactly, which is no
    consensus) and the fit uses all five."""
    from compensation.ego_velocity import MIN_CONSENSUS

    rng = np.random.default_rng(4)
    u = rng.normal(size=(5, 3)) + [0.0, 0.0, 3.0]
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    v = np.array([0.05, -0.02, 0.03])
    noise = np.array([1.0, -1.0, 0.5, -0.5, 0.8]) * 1e-3               # [m/s]
    fit = fit_ego_velocity(u, -u @ v + noise, np.full(5, 1e-6))
    assert MIN_CONSENSUS == 4 and fit.inliers.all()
    ls, *_ = np.linalg.lstsq(-u, -u @ v + noise, rcond=None)           # all five, l2
    assert np.linalg.norm(fit.velocity - v) < 3 * np.linalg.norm(ls - v) + 1e-4


def test_ego_velocity_single_direction_keeps_the_prior_across():
    """One scatterer observes only its line of sight; across it the prior remains."""
    u = direction(np.array([0.3]), np.array([-0.1]))
    v = np.array([0.3, -0.1, 0.05])
    fit = fit_ego_velocity(u, -u @ v, [1e-4], prior_sigma=0.5)
    assert abs(u[0] @ fit.velocity - u[0] @ v) <= 1e-6
    e1 = np.cross(u[0], [0, 1, 0])
    e1 /= np.linalg.norm(e1)
    assert e1 @ fit.covariance @ e1 == pytest.approx(0.25, rel=1e-6)


def test_ego_velocity_bad_input():
    with pytest.raises(ValueError, match="directions must have shape"):
        fit_ego_velocity(np.zeros((3, 2)), np.zeros(3), np.ones(3))
    with pytest.raises(ValueError, match="sigma .* is needed with 2 detection"):
        fit_ego_velocity(np.eye(3)[:2], np.zeros(2))


def _tracks(delta, rng, n_tracks=6, drift=0.0, t_ref=0.0):
    """Linearised residual phase ``r(t) (delta + rho (t - t_ref)) + a + b t`` per track."""
    out = []
    for k in range(n_tracks):
        t = 0.05 * k + T
        rate = 4 * np.pi / LAM * 0.02 * np.sin(2 * np.pi * 120 * t + rng.uniform(0, 6))
        phi = rate * (delta + drift * (t - t_ref)) + rng.normal() + rng.normal() * 50 * t
        out.append((t, phi, rate, np.ones(t.size)))
    return out


def test_time_shift_recovered_from_bent_rates():
    rng = np.random.default_rng(4)
    fit = fit_time_shift(_tracks(0.7e-3, rng))
    assert abs(fit.offset - 0.7e-3) <= SHIFT_TOL
    tr = _tracks(0.4e-3, rng, drift=2e-4, t_ref=0.1)
    both = fit_time_shift(tr, drift=True, reference_time=0.1)
    assert abs(both.offset - 0.4e-3) <= SHIFT_TOL and abs(both.drift - 2e-4) <= 1e-10
    assert phase_misfit(tr) > 0


def test_time_shift_unobservable_without_bending():
    """A constant velocity within each frame is absorbed by the per-track line: refused."""
    t = T
    tracks = [(t, 3.0 * t, np.full(t.size, 5.0), np.ones(t.size))] * 3
    with pytest.raises(ValueError, match="unobservable"):
        fit_time_shift(tracks)


def _drift_dirs(bias, dirs_w, times, att):
    """Apparent directions ``u - [u]_x phi(t)`` of stationary scatterers, the world-frame
    attitude error ``phi = int R b ds`` (trapezoid rule over the frames)."""
    rb = np.asarray(att) @ bias
    phi = np.vstack([np.zeros(3), np.cumsum(0.5 * (rb[1:] + rb[:-1])
                                            * np.diff(times)[:, None], axis=0)])
    out = np.empty((times.size, len(dirs_w), 3))
    for k in range(times.size):
        for j, u in enumerate(dirs_w):
            out[k, j] = u - _skew(u) @ phi[k]
    return out


def test_gyro_bias_from_drifting_directions():
    rng = np.random.default_rng(5)
    times = np.arange(6) * 0.05
    att = Rotation.from_euler("ZYX", rng.normal(0, 0.02, (6, 3))).as_matrix()
    dirs = _dirs(3, rng)
    b = np.deg2rad([0.4, -0.6, 0.3])
    fit = fit_gyro_bias(times, _drift_dirs(b, dirs, times, att), att)
    assert np.linalg.norm(fit.bias - b) <= BIAS_RTOL * np.linalg.norm(b)


def test_gyro_bias_single_scatterer_keeps_the_prior_about_its_line_of_sight():
    times = np.arange(5) * 0.05
    att = np.broadcast_to(np.eye(3), (5, 3, 3))
    u = direction(0.3, -0.2)
    b = np.deg2rad([0.4, -0.6, 0.3])
    fit = fit_gyro_bias(times, _drift_dirs(b, [u], times, att), att, prior_sigma=0.1)
    across = b - (b @ u) * u
    assert np.linalg.norm(fit.bias - across) <= BIAS_RTOL * np.linalg.norm(b)
    # the unobserved axis is the mean direction, off u by the drift: second order
    assert u @ fit.covariance @ u == pytest.approx(0.01, rel=BIAS_RTOL ** 2)
    with pytest.raises(ValueError, match="at least 2 frames"):
        fit_gyro_bias(times[:1], np.zeros((1, 1, 3)), att[:1])
