"""The self-calibration's gyro-bias fit combined with the IMU's prior
(compensation.calibration._with_prior): the product of two Gaussians (Bishop, Pattern
Recognition and Machine Learning, 2006, eqs. 2.113-2.117, the Kalman update with an
identity measurement)."""

from __future__ import annotations

import numpy as np

from compensation.calibration import _with_prior

#: Prior spread of the gyro bias [rad/s] (a consumer MEMS turn-on bias, 0.5 deg/s).
PRIOR_SIGMA = float(np.deg2rad(0.5))
#: Draws of the Monte Carlo.
DRAWS = 4000
#: Relative agreement of a sample variance over DRAWS with the stated one (two standard
#: errors sqrt(2 / DRAWS) = 4.5 %, with margin).
VARIANCE_RTOL = 0.08


def test_loose_fit_combined_with_the_prior_matches_monte_carlo():
    """A fit three times looser than the prior on one axis, tighter on another: the stated
    covariance is the scatter of the errors of the combination over draws of bias and fit
    error, and on every axis it is below both the prior's and the fit's."""
    rng = np.random.default_rng(0)
    a = rng.normal(size=(3, 3))
    q, _ = np.linalg.qr(a)
    fit_cov = q @ np.diag(np.array([3.0, 0.5, 1.5]) ** 2 * PRIOR_SIGMA ** 2) @ q.T
    truth = rng.normal(0.0, PRIOR_SIGMA, (DRAWS, 3))
    fitted = truth + rng.multivariate_normal(np.zeros(3), fit_cov, DRAWS)
    errs, cov = [], None
    for t, f in zip(truth, fitted, strict=True):
        est, cov = _with_prior(f, fit_cov, PRIOR_SIGMA)
        errs.append(est - t)
    emp = np.cov(np.array(errs).T)
    np.testing.assert_allclose(np.diag(emp), np.diag(cov), rtol=VARIANCE_RTOL)
    assert np.all(np.diag(cov) < np.minimum(np.diag(fit_cov), PRIOR_SIGMA ** 2))


def test_scalar_closed_form():
    """One axis: mean ``m s^2 / (s^2 + c)`` and variance ``c s^2 / (s^2 + c)``."""
    c, s, m = 4.0e-4, PRIOR_SIGMA, 0.03
    est, cov = _with_prior(np.array([m, 0.0, 0.0]), np.diag([c, c, c]), s)
    assert np.isclose(est[0], m * s ** 2 / (s ** 2 + c), rtol=1e-12)
    assert np.isclose(cov[0, 0], c * s ** 2 / (s ** 2 + c), rtol=1e-12)
