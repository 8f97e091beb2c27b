"""The ground's tilt fitted again with another integration (compensation.ground_refit).

Closed form: a hover repeats one look, the ground points ``p`` of the plane
``e_z . p = h`` seen in B through the true attitude ``R_k = exp([phi0]x) B_k`` of
frame ``k`` (``B_k`` the true turn since the first ramp, ``phi0`` the initial
attitude's error). An integration whose attitude drifts by a horizontal gyro bias
``b`` (in W) gives ``R'_k = exp([b t_k]x) B_k``: its frames are turned by ``b t_k``
and one plane through them gives ``phi0 - b mean(t_k)``, not ``phi0``. Turned by the
integration without the drift (``B_k``) the same points give ``phi0`` within the
stated spread; each look's error common to every frame (the same points, the same
error) is in that spread (the covariance times the frames, as
:func:`compensation.ground_plane.ground_tilt` states it).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.ground_looks import GroundLook
from compensation.ground_plane import fit_looks, point_covariance
from compensation.ground_refit import GroundRetilt, refit_ground
from compensation.strapdown import PlatformMotion

#: Radar height over the ground [m], points of the look, frames and frame period [s].
HEIGHT, POINTS, FRAMES, PERIOD = 15.0, 120, 6, 0.2
#: Range [m] and angle [rad] spreads of a point (a well-measured ground).
RANGE_SIGMA, ANGLE_SIGMA = 0.02, float(np.deg2rad(0.05))
#: Initial attitude error (tilt_n, tilt_e) [rad] and horizontal gyro bias in W [rad/s].
PHI0 = np.deg2rad([0.3, -0.5])
BIAS = np.deg2rad([0.4, 0.3])
#: The recovered tilt lies within this many stated sigmas of the truth.
COVER_SIGMAS = 3.0
#: Turn of the frames by the body's jitter (rotation vectors) [rad].
JITTER = float(np.deg2rad(1.0))
#: Pose (slot) of every frame's snapshot.
POSE = 1


def _look(rng):
    """Ground points ``[point, 3]`` in W (level ground, z down) seen from the radar."""
    r = rng.uniform(HEIGHT + 0.5, HEIGHT + 8.0, POINTS)
    bearing = rng.uniform(-np.pi, np.pi, POINTS)
    horiz = np.sqrt(r ** 2 - HEIGHT ** 2)
    return np.column_stack([horiz * np.cos(bearing), horiz * np.sin(bearing),
                            np.full(POINTS, HEIGHT)])


def _motion(t0: float, att) -> PlatformMotion:
    """Two poses of one frame, both with attitude ``att`` ``[3, 3]``."""
    z = np.zeros((2, 3))
    return PlatformMotion(t0 + np.array([0.0, 1e-3]), np.stack([att, att]), z, z, z,
                          np.zeros(3))


def _record(seed: int):
    """(looks formed by the drifting integration, the drifting motions, the true-turn
    motions): one look of the ground repeated over the frames, its measurement error
    drawn once (common to every frame) in the array's frame."""
    rng = np.random.default_rng(seed)
    p_w = _look(rng)
    t = np.arange(FRAMES) * PERIOD
    turns = Rotation.from_rotvec(np.column_stack([rng.normal(0, JITTER, (FRAMES, 2)),
                                                  rng.normal(0, JITTER, FRAMES)]))
    turns = turns * turns[0].inv()                     # B_0 = I
    truth = Rotation.from_rotvec([*PHI0, 0.0])
    r = np.linalg.norm(p_w, axis=1)
    az, el = np.arctan2(p_w[:, 0], p_w[:, 2]), np.arcsin(p_w[:, 1] / r)
    cov_w = point_covariance(r, az, el, RANGE_SIGMA, ANGLE_SIGMA, ANGLE_SIGMA)
    noise = np.einsum("nij,nj->ni", np.linalg.cholesky(cov_w), rng.normal(size=(POINTS, 3)))
    drift, exact = [], []
    looks = []
    for k in range(FRAMES):
        body = (truth * turns[k]).inv().apply(p_w + noise)       # in B, the same error
        r_drift = (Rotation.from_rotvec([*(BIAS * t[k]), 0.0]) * turns[k]).as_matrix()
        drift.append(_motion(t[k], r_drift))
        exact.append(_motion(t[k], turns[k].as_matrix()))
        c_b = (truth * turns[k]).inv().as_matrix()
        looks.append(GroundLook(k, POSE, r_drift, body @ r_drift.T,
                                r_drift @ c_b @ cov_w @ c_b.T @ r_drift.T * FRAMES))
    return tuple(looks), drift, exact, t


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_refit_recovers_the_first_ramps_tilt(seed):
    looks, drift, exact, t = _record(seed)
    old = fit_looks(looks, drift)
    # the drift averaged into one plane: phi0 - b mean(t), beyond the stated spread
    mean_drift = BIAS * np.mean(t)
    assert np.all(np.abs(old.tilt - (PHI0 - mean_drift)) <= COVER_SIGMAS * old.tilt_sigma)
    assert np.any(np.abs(old.tilt - PHI0) > COVER_SIGMAS * old.tilt_sigma)
    new = refit_ground(old, exact)
    assert new.usable and new.inliers == new.points
    assert np.all(np.abs(new.tilt - PHI0) <= COVER_SIGMAS * new.tilt_sigma)
    # turned back into the drifting integration: the first fit again
    again = refit_ground(new, drift)
    np.testing.assert_allclose(again.tilt, old.tilt, atol=1e-3 * old.tilt_sigma.min())


def test_retilt_gives_the_initial_attitude():
    looks, drift, exact, _ = _record(0)
    old = fit_looks(looks, drift)
    retilt = GroundRetilt(old, np.eye(3))
    assert retilt.fit is old
    att, cov = retilt(exact, old.tilt_covariance)
    truth = Rotation.from_rotvec([*PHI0, 0.0]).as_matrix()
    err = Rotation.from_matrix(att @ truth.T).as_rotvec()[:2]
    assert np.all(np.abs(err) <= COVER_SIGMAS * np.sqrt(np.diag(cov)))
    assert np.all(np.abs(retilt.fit.tilt - PHI0) <= COVER_SIGMAS * retilt.fit.tilt_sigma)


def test_refit_needs_looks():
    looks, drift, exact, _ = _record(0)
    old = fit_looks(looks, drift)
    from dataclasses import replace

    with pytest.raises(ValueError, match="no looks"):
        refit_ground(replace(old, looks=()), exact)
    with pytest.raises(ValueError, match="motions"):
        refit_ground(old, exact[:2])
