"""Roll and pitch from the ground plane (compensation.ground_plane).

Closed form: points of the plane ``e_z . p = h`` in W, seen through an attitude
off by ``phi = (tilt_n, tilt_e, 0)``, are ``exp(-[phi]x) p``; the fit's tilt is
``phi`` exactly without noise, and a ground sloped by ``s`` about north gives
``tilt_n + s``. Coverage: the stated covariance of the tilt against its error over
Monte-Carlo draws of the points' range and angle errors (the model of
:func:`point_covariance`), with outliers; and, frames seen through their own tilt
errors, the covariance scaled to the leave-one-frame-out jackknife.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.geometry import az_el
from compensation.ground_plane import (
    MIN_GROUND_POINTS,
    GroundPlaneWarning,
    fit_ground_plane,
    ground_check,
    ground_tilt,
    point_covariance,
)
from compensation.radar_inertial import ImuErrors, estimate_radar_inertial
from compensation.strapdown import static_motion

#: Height of the radar over the ground [m] and the ground's extent (x, y) [m].
HEIGHT, EXTENT = 15.0, 12.0
#: Range spread [m] (a 0.15 m bin over sqrt(12)), azimuth and elevation spreads [rad].
RANGE_SIGMA, AZ_SIGMA, EL_SIGMA = 0.043, float(np.deg2rad(0.5)), float(np.deg2rad(1.0))
#: True correction of the attitude (tilt_n, tilt_e) [rad].
TILT = np.deg2rad([0.4, -0.65])
#: Noise-free fit: the tilt to rounding [rad].
EXACT_RAD = 1e-9
#: Monte-Carlo draws, points per draw and outliers among them.
DRAWS, POINTS, OUTLIERS = 150, 30, 6
#: Mahalanobis distance of the 2-D tilt error: its 95 % point (chi-square, 2 dof) and the
#: least fraction of draws within it (binomial: 0.95 less 3 sigma of 150 draws is 0.897).
CHI2_95, MIN_COVERAGE = 5.991, 0.89
#: Largest fraction within it: a spread stated so wide that it says little (the
#: chi-square scaling of the covariance only ever widens it).
MAX_COVERAGE = 0.995


def _ground(rng, n: int, slope_n: float = 0.0) -> np.ndarray:
    """``n`` ground points in W from the radar, ``[n, 3]`` (z down, ``z = h`` at x = y = 0,
    sloped by ``slope_n`` about north)."""
    xy = rng.uniform(-EXTENT, EXTENT, size=(n, 2))
    z = HEIGHT - np.tan(slope_n) * xy[:, 1]
    return np.column_stack([xy, z])


def _seen(p_w: np.ndarray, tilt=TILT) -> np.ndarray:
    """The points as an attitude off by ``tilt`` has them: ``exp(-[phi]x) p``."""
    return p_w @ Rotation.from_rotvec([tilt[0], tilt[1], 0.0]).as_matrix()


def _noisy(rng, p: np.ndarray):
    """Points with range and angle errors drawn from the model, and their covariances."""
    r = np.linalg.norm(p, axis=1)
    az, el = az_el(p / r[:, None])
    r2 = r + rng.normal(0, RANGE_SIGMA, r.size)
    az2 = az + rng.normal(0, AZ_SIGMA, r.size)
    el2 = el + rng.normal(0, EL_SIGMA, r.size)
    from compensation.geometry import direction

    q = r2[:, None] * direction(az2, el2)
    return q, point_covariance(r2, az2, el2, RANGE_SIGMA, AZ_SIGMA, EL_SIGMA)


def test_noise_free_plane_gives_the_tilt_exactly():
    rng = np.random.default_rng(0)
    p = _seen(_ground(rng, 20))
    cov = point_covariance(*(lambda r: (r, *az_el(p / r[:, None])))(np.linalg.norm(p, axis=1)),
                           RANGE_SIGMA, AZ_SIGMA, EL_SIGMA)
    fit = fit_ground_plane(p, cov)
    assert fit.usable and fit.inliers == 20
    assert np.allclose(fit.tilt, TILT, atol=EXACT_RAD, rtol=0)
    assert abs(fit.height - HEIGHT) < 1e-6
    assert np.allclose(fit.normal, Rotation.from_rotvec([*TILT, 0]).as_matrix()[2], atol=1e-9)


def test_sloped_ground_biases_the_tilt_by_its_slope():
    """The stated assumption: the fit levels the ground, a slope s shows as a tilt s."""
    rng = np.random.default_rng(1)
    slope = np.deg2rad(2.0)
    p = _seen(_ground(rng, 20, slope_n=slope))
    r = np.linalg.norm(p, axis=1)
    fit = fit_ground_plane(p, point_covariance(r, *az_el(p / r[:, None]), RANGE_SIGMA,
                                               AZ_SIGMA, EL_SIGMA))
    n_w = np.array([0.0, np.tan(slope), 1.0]) / np.hypot(1.0, np.tan(slope))
    rot = Rotation.from_rotvec([*TILT, 0.0]).as_matrix()
    assert np.allclose(fit.normal, rot.T @ n_w, atol=EXACT_RAD, rtol=0)
    # to first order the slope adds to the tilt (second order: their product)
    assert np.allclose(fit.tilt, TILT + [slope, 0.0], atol=np.linalg.norm(TILT) * slope,
                       rtol=0)
    assert fit.report()["assumption"].startswith("level flat ground")


def test_stated_covariance_covers_the_error_with_outliers():
    rng = np.random.default_rng(2)
    d2, used = [], 0
    for _ in range(DRAWS):
        q, cov = _noisy(rng, _seen(_ground(rng, POINTS)))
        q[:OUTLIERS, 2] += rng.uniform(1.0, 4.0, OUTLIERS)     # not the ground: above it
        fit = fit_ground_plane(q, cov, seed=int(rng.integers(1 << 30)), warn=False)
        if not fit.usable:
            continue
        used += 1
        err = fit.tilt - TILT
        d2.append(float(err @ np.linalg.solve(fit.tilt_covariance, err)))
    assert used >= 0.95 * DRAWS
    cover = np.mean(np.array(d2) <= CHI2_95)
    assert MIN_COVERAGE <= cover <= MAX_COVERAGE, cover


#: Frames of the jackknife draws, points per frame, draws, and the spread of every frame's
#: own tilt error [rad] (an attitude error of the frame that its points' covariance does
#: not hold); the least coverage of 100 draws (0.95 less 3 binomial sigma: 0.885).
FRAMES, FRAME_POINTS, FRAME_DRAWS = 6, 10, 100
FRAME_TILT_SIGMA = float(np.deg2rad(0.5))
MIN_FRAME_COVERAGE = 0.885


def test_jackknife_over_frames_covers_errors_the_points_do_not_state():
    """Every frame seen through its own tilt error (not in the points' covariance): the
    covariance from the points alone covers too seldom; scaled to the leave-one-frame-out
    jackknife (groups) it covers."""
    rng = np.random.default_rng(6)
    d2 = {True: [], False: []}
    for _ in range(FRAME_DRAWS):
        frames = [_noisy(rng, _seen(_ground(rng, FRAME_POINTS),
                                    tilt=TILT + rng.normal(0.0, FRAME_TILT_SIGMA, 2)))
                  for _ in range(FRAMES)]
        q, cov = (np.concatenate(v) for v in zip(*frames, strict=True))
        groups = np.repeat(np.arange(FRAMES), FRAME_POINTS)
        seed = int(rng.integers(1 << 30))
        for jack in (True, False):
            fit = fit_ground_plane(q, cov, groups=groups if jack else None, seed=seed,
                                   warn=False)
            assert fit.usable
            assert (fit.spread_scale >= 1.0) if jack else (fit.spread_scale == 1.0)
            err = fit.tilt - TILT
            d2[jack].append(float(err @ np.linalg.solve(fit.tilt_covariance, err)))
    cover = {k: float(np.mean(np.array(v) <= CHI2_95)) for k, v in d2.items()}
    assert MIN_FRAME_COVERAGE <= cover[True] <= MAX_COVERAGE, cover
    assert cover[False] < MIN_FRAME_COVERAGE, cover


def test_groups_are_checked():
    rng = np.random.default_rng(7)
    q, cov = _noisy(rng, _seen(_ground(rng, 20)))
    with pytest.raises(ValueError, match="groups must be integers of shape"):
        fit_ground_plane(q, cov, groups=np.zeros(19, dtype=int))
    with pytest.raises(ValueError, match="groups must be integers of shape"):
        fit_ground_plane(q, cov, groups=np.zeros(20))


def test_too_few_points_and_bad_fit_warn():
    rng = np.random.default_rng(3)
    p = _seen(_ground(rng, MIN_GROUND_POINTS - 1))
    r = np.linalg.norm(p, axis=1)
    cov = point_covariance(r, *az_el(p / r[:, None]), RANGE_SIGMA, AZ_SIGMA, EL_SIGMA)
    with pytest.warns(GroundPlaneWarning, match="at least 8 needed"):
        fit = fit_ground_plane(p, cov)
    assert not fit.usable and np.all(np.isnan(fit.tilt))
    # a rough ground: heights scattered 20 times beyond the stated spreads
    p = _seen(_ground(rng, 100))
    r = np.linalg.norm(p, axis=1)
    cov = point_covariance(r, *az_el(p / r[:, None]), RANGE_SIGMA, AZ_SIGMA, EL_SIGMA)
    sig = np.sqrt(np.einsum("j,njk,k->n", [0, 0, 1.0], cov, [0, 0, 1.0]))
    p[:, 2] += 20 * sig * rng.normal(size=sig.size)
    with pytest.warns(GroundPlaneWarning, match="bad fit|needed"):
        fit = fit_ground_plane(p, cov)
    assert not fit.usable


def test_a_steep_plane_is_no_ground():
    """Points on a wall-like plane (30 deg from level, beyond the 20 deg a ground may lean
    in the attitude's error): no tilt, a warning."""
    rng = np.random.default_rng(5)
    p = _seen(_ground(rng, 30), tilt=np.deg2rad([30.0, 0.0]))
    r = np.linalg.norm(p, axis=1)
    cov = point_covariance(r, *az_el(p / r[:, None]), RANGE_SIGMA, AZ_SIGMA, EL_SIGMA)
    with pytest.warns(GroundPlaneWarning):
        fit = fit_ground_plane(p, cov)
    assert not fit.usable


def test_no_ground_in_the_window_warns():
    t = np.arange(8) * 1e-4
    rc = np.zeros((8, 4, 16), complex)
    pos = np.column_stack([np.arange(4) * 2e-3, np.zeros(4), np.zeros(4)])
    with pytest.warns(GroundPlaneWarning, match="no ground return in the range window"):
        fit = ground_tilt([rc], pos, [static_motion(t)], wavelength=3.9e-3,
                          range_axis=np.arange(16) * 0.15, gates=[])
    assert not fit.usable


def test_a_contradicted_attitude_is_named():
    rng = np.random.default_rng(4)
    q, cov = _noisy(rng, _seen(_ground(rng, 40), tilt=np.deg2rad([0.0, 3.0])))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = fit_ground_plane(q, cov)
    assert len(ground_check(fit)) == 1 and "disagree" in ground_check(fit)[0]
    q, cov = _noisy(rng, _seen(_ground(rng, 40), tilt=np.zeros(2)))
    assert ground_check(fit_ground_plane(q, cov, warn=False)) == ()


def test_tilt_covariance_is_checked():
    imu = ImuErrors(1e-3, 1e-4, 0.1, 0.01)
    with pytest.raises(ValueError, match="tilt_covariance"):
        estimate_radar_inertial(np.arange(10) * 0.01, np.zeros((10, 3)), np.zeros((10, 3)),
                                [np.arange(4) * 1e-3], None, imu_errors=imu,
                                initial_velocity=np.zeros(3), tilt_covariance=np.eye(3))
