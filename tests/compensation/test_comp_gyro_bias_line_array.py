"""Gyro bias of an array that resolves azimuth only (compensation.gyro_bias, ``spread``).

The oracle: the platform turns at a constant body rate between frames, by ``d_k``,
``R_k+1 = R_k exp([d_k]_x)``; a gyroscope with scale and cross-axis matrix ``M`` and
bias ``b`` integrates exactly to ``R_est,k+1 = R_est,k exp([M d_k + b dt]_x)``, and a
stationary scatterer in the world direction ``u`` appears at ``R_est,k R_k^T u`` (the
fit's ``-[u]_x (int R ds) b`` is its first order in ``b``; Titterton & Weston,
Strapdown Inertial Navigation Technology, 2nd ed., eq. 11.6). The array measures each
scatterer's azimuth, with a spread, and not its elevation: the elevation stays at the
first frame's value frame after frame (what compensation.calibration's direction
search does on such an array). With the targets near elevation 0 the azimuth drift
sees the bias about the elevation axis only.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.geometry import direction
from compensation.gyro_bias import BIAS_PRIOR_SIGMA, SCALE_SIGMA, fit_gyro_bias

#: Azimuth spread of a measured direction [rad] (a few hundredths of a degree, as
#: the xWR18xx's twelve-element azimuth row gives on the flights' targets).
AZIMUTH_SIGMA = float(np.deg2rad(0.02))
#: Targets: (azimuth, elevation) [deg] of the flights' default5.
TARGETS_DEG = ((-25.0, -5.0), (-10.0, 0.0), (5.0, 5.0), (15.0, 0.0), (30.0, -5.0))
#: Frames and their period [s] (the flights': six frames 50 ms apart).
FRAMES, PERIOD = 6, 0.05
#: Gyro bias [rad/s] (a consumer MEMS gyroscope's, several tenths of deg/s).
BIAS = np.deg2rad([0.72, -0.45, 0.37])
#: Spread of the platform's turn from one frame to the next [rad] per axis (hover
#: jitter of about 30 deg/s: the flights' records span 2-4 deg).
TURN_SIGMA = float(np.deg2rad(1.5))
#: Monte Carlo draws of the azimuth noise (and of the gyro's scale matrix).
DRAWS = 300
#: Stated spreads within which every draw's observed components must lie.
SIGMAS = 4.0
#: Band of the variance of the observed component's error over the stated one: the
#: residual's 24 degrees of freedom give a Student t (variance 24/22 = 1.09); the
#: sample variance of DRAWS has a standard error of sqrt(2 / DRAWS) = 8 % (measured:
#: 1.25 with an exact gyro, where the fit's first order in the bias on turns of a
#: few degrees adds a little; 1.03 with the scale error drawn and stated).
Z_VARIANCE = (0.7, 1.35)
#: Relative agreement of a held component with the prior.
PRIOR_RTOL = 1e-9


def _record(rng, frame, gyro_matrix=None):
    """Times ``[frame]``, integrated attitude ``[frame, 3, 3]`` and the measured
    directions ``[frame, target, 3]`` in W of a hovering platform seen by an
    azimuth-only array whose angles are taken in the frame ``frame`` (N to W)."""
    t = np.arange(FRAMES) * PERIOD
    m = np.eye(3) if gyro_matrix is None else gyro_matrix
    truth = [Rotation.from_euler("ZYX", rng.normal(0.0, np.deg2rad(2.0), 3))]
    est = [truth[0]]
    for d in rng.normal(0.0, TURN_SIGMA, (FRAMES - 1, 3)):
        truth.append(truth[-1] * Rotation.from_rotvec(d))
        est.append(est[-1] * Rotation.from_rotvec(m @ d + BIAS * PERIOD))
    az, el = np.deg2rad(np.array(TARGETS_DEG)).T
    u_w = direction(az, el) @ frame.T                                   # [target, 3]
    out = np.empty((FRAMES, az.size, 3))
    for k in range(FRAMES):
        turn = (est[k] * truth[k].inv()).as_matrix()
        x, y, z = (u_w @ turn.T @ frame).T                              # apparent, in N
        az_app = np.arctan2(x, z) + rng.normal(0.0, AZIMUTH_SIGMA, az.size)
        out[k] = direction(az_app, el) @ frame.T      # elevation not measured: held
    return t, np.stack([r.as_matrix() for r in est]), out


def _axes(fit):
    """Bias directions ``[3, axis]`` the fit observes (stated variance below the prior's),
    best first, and those it holds at the prior."""
    lam, vec = np.linalg.eigh(fit.covariance)
    held = np.isclose(lam, BIAS_PRIOR_SIGMA ** 2, rtol=PRIOR_RTOL)
    return vec[:, ~held], vec[:, held]


def _z_scores(rng, frame, scale):
    """Error over stated spread of the observed components (best first) of DRAWS
    records, the gyro's ``M - I`` drawn with spread ``scale`` and stated with it."""
    z = []
    for _ in range(DRAWS):
        m = np.eye(3) + rng.normal(0.0, scale, (3, 3))
        t, att, dirs = _record(rng, frame, m)
        fit = fit_gyro_bias(t, dirs, att, spread=(1.0, np.inf), frame=frame, scale_sigma=scale)
        seen, held = _axes(fit)
        # about N's elevation axis (y of N), the body turned into W mid-record
        assert abs(att[FRAMES // 2] @ seen[:, 0] @ frame[:, 1]) > 0.99
        assert held.shape[1] >= 1
        np.testing.assert_allclose(held.T @ fit.bias, 0.0, atol=1e-12)
        np.testing.assert_allclose(np.diag(held.T @ fit.covariance @ held),
                                   BIAS_PRIOR_SIGMA ** 2, rtol=PRIOR_RTOL)
        zk = seen.T @ (fit.bias - BIAS) / np.sqrt(np.diag(seen.T @ fit.covariance @ seen))
        assert np.all(np.abs(zk) <= SIGMAS), zk
        z.append(zk[0])
    return np.array(z)


@pytest.mark.parametrize("scale", [0.0, SCALE_SIGMA])
def test_azimuth_drift_gives_the_observed_component_within_its_stated_spread(scale):
    """Over DRAWS draws of the azimuth noise (and of the gyro's scale and cross-axis
    matrix): the best observed bias direction is the rotation about the array's
    elevation axis (turned into W), its error of the stated variance; every observed
    component within SIGMAS stated sigma; at least one direction held at the prior
    (estimate 0, spread BIAS_PRIOR_SIGMA)."""
    rng = np.random.default_rng(11)
    frame = Rotation.from_euler("ZYX", [0.4, -0.3, 1.2]).as_matrix()    # a mounted radar
    z = _z_scores(rng, frame, scale)
    assert Z_VARIANCE[0] <= np.var(z) <= Z_VARIANCE[1], np.var(z)


def test_held_elevation_taken_as_measured_biases_the_fit():
    """The same record fitted as if the elevation were measured (isotropic spread): the
    held elevation reads as no drift and pulls the bias across it towards zero, far
    beyond the azimuth-only fit's error."""
    rng = np.random.default_rng(12)
    frame = np.eye(3)
    t, att, dirs = _record(rng, frame)
    right = fit_gyro_bias(t, dirs, att, spread=(1.0, np.inf), scale_sigma=0.0)
    wrong = fit_gyro_bias(t, dirs, att, scale_sigma=0.0)
    seen = _axes(right)[0][:, 0]
    assert abs(seen @ (right.bias - BIAS)) <= SIGMAS * np.sqrt(seen @ right.covariance @ seen)
    # the isotropic fit claims the other components too, and misses them by most of them
    assert np.linalg.norm(wrong.bias - BIAS) > 0.5 * np.linalg.norm(BIAS - (seen @ BIAS) * seen)


@pytest.mark.parametrize("spread", [(1.0, 0.0), (np.nan, 1.0), (1.0, 1.0, 1.0), (-1.0, 1.0)])
def test_bad_spread_refused(spread):
    rng = np.random.default_rng(13)
    t, att, dirs = _record(rng, np.eye(3))
    with pytest.raises(ValueError, match="spread must be positive"):
        fit_gyro_bias(t, dirs, att, spread=spread)
