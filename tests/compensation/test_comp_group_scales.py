"""Variance components of the Doppler's measurement groups (compensation.batch_solve)
against synthetic measurements of known truth.

Detected scatterers in one plane (range rates ``-u . v`` with the noise their spreads
state) leave the velocity across the plane to a second group, ground scatterers out
of it, whose range rates carry :data:`NOISE_RATIO` times the noise their spreads
state (the vibration a 250 Hz log misses, seen along directions across the
targets). One reduced chi-square scales both groups alike: the many precise rows
hold it down, the ground rows stay understated, and so does the velocity they alone
constrain. A factor per group (Helmert's variance components) states it.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.batch_solve import GROUND_GROUP, group_scales, solve_batch
from compensation.geometry import direction
from compensation.radar_inertial import DopplerMeasurements, estimate_radar_inertial
from tests.compensation.test_comp_radar_inertial import BLOCKS, FRAMES, IMU, LEVER, SIGMA_R, _record

#: True noise of a ground range rate over its stated spread (SIGMA_R).
NOISE_RATIO = 5.0
#: Ground scatterers (azimuth, elevation) [deg] of the records, out of the targets'
#: plane (elevation 0).
GROUND = ((-30, 25), (25, -30))
#: Seeds of the records.
SEEDS = range(12)
#: Normalised errors within this bound ...
Z_TWO = 2.0
#: ... in at least this fraction of the velocity components of all records (a normal's
#: 95.4 %, less one draw in 36 for the few records) ...
COVERAGE = 0.92
#: ... or all within this bound.
Z_THREE = 3.0
#: Least ratio of the ground's factor to the detected rows' in the records: the true 25
#: (NOISE_RATIO^2) lowered by the misfit spread the ground adds to every row's
#: (compensation.ego_velocity.block_misfit) and by the Huber weights (3.6-9.4 seen).
MIN_FACTOR_RATIO = 2.0
#: Detected and ground rows of the linear problem.
LINEAR_ROWS = (60, 30)
#: Seeds of its Monte Carlo.
LINEAR_SEEDS = 200
#: Fraction of its normalised errors within Z_TWO with a factor per group (a normal's
#: 95.4 %; 600 draws, standard error 0.9 %).
LINEAR_COVERAGE = 0.95
#: Below this fraction a spread is understated (a normal's within 2 / 1.3 sigma: 88 %).
UNDERSTATED_COVERAGE = 0.88
#: Relative agreement of the median factor with its group's true variance ratio.
FACTOR_RTOL = 0.2


def _slope(tt, p):
    tc = tt - tt.mean()
    return tc @ (p - p.mean(axis=0)) / (tc @ tc)


def _velocity_z(seed: int, grouped: bool) -> tuple[np.ndarray, tuple]:
    """Normalised velocity errors ``[3]`` and the group factors of one record; ``grouped``
    false: the ground rows marked as detected (one reduced chi-square)."""
    (t, gyro, accel), measure, guess, truth, sig, true_motion = _record(
        900 + seed, "elevation 0")
    rng = np.random.default_rng(5000 + seed)
    u = np.array([direction(np.deg2rad(a), np.deg2rad(e)) for a, e in GROUND])
    u_meas = u @ Rotation.from_rotvec(-truth[3:6]).as_matrix().T

    def measure_both(motions):
        det = measure(motions)
        d, r, k, win = [], [], [], []
        for f, (mt, me) in enumerate(zip(true_motion, motions, strict=True)):
            for blk in np.array_split(np.arange(mt.num_chirps), BLOCKS):
                tt = mt.time[blk]
                st, se = _slope(tt, mt.radar_position[blk]), _slope(tt, me.radar_position[blk])
                for uj, mj in zip(u, u_meas, strict=True):
                    d.append(mj)
                    r.append(-uj @ st + mj @ se + rng.normal(0.0, NOISE_RATIO * SIGMA_R))
                    k.append(f)
                    win.append((tt[0], tt[-1]))
        n = len(r)
        return DopplerMeasurements(
            np.vstack([det.directions, d]), np.concatenate([det.range_rate, r]),
            np.concatenate([det.sigma, np.full(n, SIGMA_R)]), np.concatenate([det.frame, k]),
            np.vstack([det.window, win]),
            group=np.concatenate([det.group, np.full(n, GROUND_GROUP if grouped else 0)]))

    res = estimate_radar_inertial(t, gyro, accel, FRAMES, measure_both, imu_errors=IMU,
                                  prior_sigma=sig, iterations=2, lever_arm=LEVER, warn=False,
                                  **guess)
    return (res.state[:3] - truth[:3]) / res.sigma[:3], res.group_scale


def test_ground_factor_above_the_detected_rows_and_velocity_covered():
    """Through the radar-inertial estimate: the ground's factor is the larger (its rows'
    noise NOISE_RATIO times the stated, the detected rows' as stated) and the velocity
    lies within the stated spreads over the records."""
    runs = [_velocity_z(s, True) for s in SEEDS]
    z = np.array([zi for zi, _ in runs])
    assert np.mean(np.abs(z) <= Z_TWO) >= COVERAGE or np.all(np.abs(z) <= Z_THREE), z.round(2)
    scales = np.array([s for _, s in runs])
    assert np.all(scales[:, GROUND_GROUP] > MIN_FACTOR_RATIO * scales[:, 0]), scales


def test_one_group_scaled_by_its_chi_square():
    """The ground rows marked as detected: one group, its factor the reduced chi-square."""
    _, scale = _velocity_z(0, False)
    assert len(scale) == 1 and scale[0] > 1.0


def _linear_z(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One linear problem of LINEAR_ROWS ``-u . v`` rows: the detected ones in the plane
    ``y = 0`` (they leave ``v_y`` to the ground), the ground ones 30 deg out of it with
    NOISE_RATIO times the noise their spreads state. Normalised errors ``[3]`` with one
    reduced chi-square for all rows and with a factor per group, and the factors."""
    rng = np.random.default_rng(seed)
    n0, n1 = LINEAR_ROWS
    u = np.vstack([direction(np.deg2rad(rng.uniform(-40, 40, n0)), np.zeros(n0)),
                   direction(np.deg2rad(rng.uniform(-40, 40, n1)),
                             np.deg2rad(rng.choice([-30.0, 30.0], n1)))])
    group = np.repeat([0, GROUND_GROUP], LINEAR_ROWS)
    p0, x0, h = np.eye(3), np.zeros(3), -u
    v = rng.normal(0.0, 1.0, 3)
    y = h @ v + rng.normal(0.0, np.where(group == GROUND_GROUP, NOISE_RATIO, 1.0) * SIGMA_R)
    c = SIGMA_R ** 2 * np.eye(y.size)
    # one reduced chi-square, as the estimate scales a single group
    x, _ = solve_batch(h, y, c, p0, x0)
    res, fisher = y - h @ x, h.T @ h / SIGMA_R ** 2
    dof = y.size - np.trace(np.linalg.solve(np.linalg.inv(p0) + fisher, fisher))
    chi2 = max(float(res @ res) / SIGMA_R ** 2 / dof, 1.0)
    x1, cov1 = solve_batch(h, y, chi2 * c, p0, x0)
    scale = group_scales(h, y, c, p0, x0, group)
    root = np.sqrt(scale[group])
    x2, cov2 = solve_batch(h, y, c * np.outer(root, root), p0, x0)
    return (x1 - v) / np.sqrt(np.diag(cov1)), (x2 - v) / np.sqrt(np.diag(cov2)), scale


def test_group_factors_cover_the_velocity_where_one_chi_square_does_not():
    """Monte Carlo of the linear problem: with a factor per group the velocity lies within
    2 stated sigma as often as a normal's; with one reduced chi-square the velocity the
    noisy ground alone constrains (``v_y``) does not, its spread understated."""
    runs = [_linear_z(s) for s in range(LINEAR_SEEDS)]
    single, grouped = (np.array([r[i] for r in runs]) for i in (0, 1))
    assert np.mean(np.abs(grouped) <= Z_TWO) >= LINEAR_COVERAGE
    assert np.mean(np.abs(single) <= Z_TWO) < LINEAR_COVERAGE
    assert np.mean(np.abs(single[:, 1]) <= Z_TWO) < UNDERSTATED_COVERAGE
    # the factors near the true variance ratios (1 and NOISE_RATIO^2), median over seeds
    assert np.median([r[2] for r in runs], axis=0) == pytest.approx(
        [1.0, NOISE_RATIO ** 2], rel=FACTOR_RTOL)


def test_group_bad_input_named():
    u = np.tile([0.0, 0.0, 1.0], (4, 1))
    with pytest.raises(ValueError, match="group must hold 4"):
        DopplerMeasurements(u, np.zeros(4), np.ones(4), np.zeros(4), np.zeros((4, 2)),
                            group=np.array([0, 1, 2, 0]))
    with pytest.raises(ValueError, match="group: expected"):
        group_scales(-u, np.zeros(4), np.eye(4), np.eye(3), np.zeros(3), [-1, 0, 0, 0])
