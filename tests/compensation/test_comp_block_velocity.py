"""Velocity error common to each block's Doppler rows (compensation.block_velocity)
against synthetic measurements of known truth.

Range rates ``-u . (v + e_b)`` of scatterers seen in blocks, ``e_b ~ N(0, Q)`` the
same for every row of block ``b`` (the vibration a 250 Hz log misses), plus the
per-row noise their spreads state. The velocity's error is the mean of the ``e_b``,
of covariance ``Q / blocks``; a reduced chi-square scales every row's spread alike
and the rows of a block count as independent, so it states about ``3 / rows`` of that
variance. The block term estimated by REML states it.
"""

from __future__ import annotations

import numpy as np
import pytest

from compensation.batch_solve import solve_batch
from compensation.block_velocity import block_covariance, block_velocity_variance
from compensation.geometry import direction

#: Blocks and rows per block of the linear problem.
BLOCKS, ROWS = 24, 16
#: Per-row noise its spreads state [m/s].
SIGMA_ROW = 0.5e-3
#: True spread of the block velocity error along N, E, D [m/s] (the scatter measured
#: on a 250 Hz boxcar flight: 21, 33 and 0.6 mm/s).
BLOCK_SIGMA = np.array([21e-3, 33e-3, 0.6e-3])
#: Seeds of the Monte Carlo.
SEEDS = 200
#: Normalised errors within this bound ...
Z_TWO = 2.0
#: ... in at least this fraction of the horizontal components with the block term (a
#: normal's 95.4 %; 400 draws, standard error 1.0 %, REML's own scatter of Q from 24
#: blocks lowers it) ...
COVERAGE = 0.92
#: ... and below this fraction with one reduced chi-square (a normal's within 2 / 1.3
#: sigma: 88 %).
UNDERSTATED_COVERAGE = 0.88
#: Relative agreement of the median estimated spread with the true one (N, E).
SIGMA_RTOL = 0.15
#: Largest median over draws of the block spread estimated where there is none, over
#: the per-row noise [1] (the estimate is clipped at zero: its median is near zero,
#: single draws reach 0.7 from the per-block velocity fits' own scatter).
NULL_RATIO = 0.25
#: Draws without a block error.
NULL_SEEDS = 20


def _problem(seed: int, block_sigma: np.ndarray):
    """Rows ``-u . (v + e_b)`` of one draw: sensitivity, range rates, stated covariance,
    directions, blocks and the true velocity."""
    rng = np.random.default_rng(seed)
    n = BLOCKS * ROWS
    u = direction(np.deg2rad(rng.uniform(-50, 50, n)), np.deg2rad(rng.uniform(-30, 10, n)))
    blocks = np.repeat(np.arange(BLOCKS), ROWS)
    v = rng.normal(0.0, 1.0, 3)
    e = rng.normal(0.0, 1.0, (BLOCKS, 3)) * block_sigma
    y = -np.einsum("mi,mi->m", u, v + e[blocks]) + rng.normal(0.0, SIGMA_ROW, n)
    return -u, y, SIGMA_ROW ** 2 * np.eye(n), u, blocks, v


def _z(seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Normalised velocity errors ``[3]`` with one reduced chi-square (the stated spreads
    scaled alike, as without the block term) and with the block term, and its spreads."""
    h, y, c, u, blocks, v = _problem(seed, BLOCK_SIGMA)
    p0, x0 = np.eye(3), np.zeros(3)
    x, _ = solve_batch(h, y, c, p0, x0)
    res = y - h @ x
    fisher = h.T @ np.linalg.solve(c, h)
    dof = y.size - np.trace(np.linalg.solve(np.linalg.inv(p0) + fisher, fisher))
    chi2 = max(float(res @ np.linalg.solve(c, res)) / dof, 1.0)
    x1, cov1 = solve_batch(h, y, chi2 * c, p0, x0)
    q = block_velocity_variance(h, y, c, p0, x0, u, blocks)
    x2, cov2 = solve_batch(h, y, c + block_covariance(u, blocks, q), p0, x0)
    return (x1 - v) / np.sqrt(np.diag(cov1)), (x2 - v) / np.sqrt(np.diag(cov2)), np.sqrt(q)


def test_block_term_covers_the_velocity_where_one_chi_square_does_not():
    """Monte Carlo: with the block term the horizontal velocity lies within 2 stated sigma
    as often as a normal's; with one reduced chi-square it does not; the estimated block
    spreads are the true ones (median over draws)."""
    runs = [_z(s) for s in range(SEEDS)]
    single, block = (np.array([r[i] for r in runs])[:, :2] for i in (0, 1))
    assert np.mean(np.abs(block) <= Z_TWO) >= COVERAGE, np.mean(np.abs(block) <= Z_TWO)
    assert np.mean(np.abs(single) <= Z_TWO) < UNDERSTATED_COVERAGE
    sig = np.median([r[2] for r in runs], axis=0)
    assert sig[:2] == pytest.approx(BLOCK_SIGMA[:2], rel=SIGMA_RTOL)


def test_no_block_error_leaves_the_stated_spreads():
    """Rows with only the noise their spreads state: the block spread's median over draws
    stays near zero (below NULL_RATIO of the per-row noise)."""
    sig = []
    for seed in range(NULL_SEEDS):
        h, y, c, u, blocks, _ = _problem(seed, np.zeros(3))
        sig.append(np.sqrt(block_velocity_variance(h, y, c, np.eye(3), np.zeros(3), u, blocks)))
    assert np.all(np.median(sig, axis=0) <= NULL_RATIO * SIGMA_ROW), np.median(sig, axis=0)


def test_block_covariance_structure_and_bad_input():
    u = np.array([[1.0, 0, 0], [0, 1.0, 0], [1.0, 0, 0]])
    c = block_covariance(u, [0, 0, 1], [4.0, 9.0, 1.0], rows=4)
    assert c.shape == (4, 4)
    assert c[0, 0] == 4.0 and c[1, 1] == 9.0 and c[0, 1] == 0.0   # u_m^T Q u_n
    assert c[0, 2] == 0.0 and c[2, 2] == 4.0 and np.all(c[3] == 0.0)  # blocks independent
    with pytest.raises(ValueError, match="q: expected 3 finite variances"):
        block_covariance(u, [0, 0, 1], [1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match="directions"):
        block_velocity_variance(-u, np.zeros(3), np.eye(3), np.eye(3), np.zeros(3), u, [0, 1])
