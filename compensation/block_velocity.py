"""Velocity error common to the Doppler rows of one block, as a variance component.

The radar-inertial estimate's rows are range rates ``r_m = -u_m . v + n_m`` of
scatterers in blocks of chirps. Where the IMU log does not resolve a vibration
(a 250 Hz boxcar log under rotors), the integrated motion misses a velocity
``e_b`` that is the same for every row of block ``b``: the rows of a block fit
one velocity to their own noise while that velocity scatters from block to
block. No per-row spread represents it; a covariance term common to a block
does: ``C += sum_b U_b Q U_b^T`` (rows ``m, n`` of one block: ``u_m^T Q u_n``;
blocks independent), ``Q = diag(q_N, q_E, q_D)`` in W.

:func:`block_velocity_variance` estimates ``q`` by restricted maximum
likelihood (Fisher scoring of the REML score; Harville, J. Am. Stat. Assoc.
72, 1977, eqs. 4.3-4.4; Searle, Casella and McCulloch, Variance Components,
1992, sec. 6.6): ``e^T C^-1 C_k C^-1 e = tr(R C_k)`` for each axis ``k``, with
``e`` the residuals of the batch solution, ``C_k = sum_b U_b E_kk U_b^T`` and
``R = C^-1 - C^-1 H P H^T C^-1`` the residuals' weight (``P`` the posterior
covariance of the estimated components), so that the part of the block
velocities the state absorbs (a constant velocity, a bias's trend) is not
counted. A component whose scatter the stated spreads already explain is zero
(it is kept at the boundary), so a log that resolves the motion leaves the
covariance as stated.

What it cannot do: it needs blocks with rows along the axis (a block seen in a
narrow cone constrains its velocity across the cone only, through the state);
the velocity error is taken independent between blocks (a vibration slower
than a block's spacing is partly a drift the state absorbs); ``Q`` is one for
the record (a vibration that changes over it gets its mean).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import cho_factor, cho_solve

__all__ = ["block_covariance", "block_velocity_variance"]

#: Most Fisher-scoring passes of the block velocity variances.
BLOCK_VARIANCE_PASSES = 30
#: Change of every variance below which the passes stop, relative to the largest of
#: the variances and the stated range-rate variances [1].
BLOCK_VARIANCE_RTOL = 1e-3


def _block_factors(directions: np.ndarray, blocks: np.ndarray, rows: int) -> np.ndarray:
    """``U_k`` per axis: ``[axis, row, block]``, column ``b`` holding ``u_m[k]`` on
    block ``b``'s rows (zero on the rows past the grouped ones)."""
    nb = int(blocks.max()) + 1
    out = np.zeros((3, rows, nb))
    idx = np.arange(blocks.size)
    for k in range(3):
        out[k, idx, blocks] = directions[:, k]
    return out


def block_covariance(directions, blocks, q, rows=None) -> np.ndarray:
    """Covariance of the range rates from a velocity error common to each block.

    Parameters
    ----------
    directions : array_like, shape ``[measurement, 3]``
        Unit direction of each row in W [1].
    blocks : array_like of int, shape ``[measurement]``
        Block (>= 0) of each row.
    q : array_like, shape ``[3]``
        Variance of the block velocity error along W's axes [m^2/s^2].
    rows : int, optional
        Size of the output (>= the measurements; later rows get zero).

    Returns
    -------
    ndarray, shape ``[rows, rows]``
        ``u_m^T diag(q) u_n`` for rows of one block, zero across blocks [m^2/s^2].
    """
    u = np.asarray(directions, dtype=float)
    b = np.asarray(blocks, dtype=int).ravel()
    q = np.asarray(q, dtype=float).ravel()
    if u.ndim != 2 or u.shape[1] != 3 or b.size != u.shape[0]:
        raise ValueError(f"directions [measurement, 3] and blocks [measurement] expected, got "
                         f"{u.shape} and {b.shape}")
    if q.size != 3 or np.any(~np.isfinite(q)) or np.any(q < 0):
        raise ValueError(f"q: expected 3 finite variances >= 0, got {q.tolist()}")
    same = b[:, None] == b[None, :]
    c = np.where(same, (u * q) @ u.T, 0.0)
    n = b.size if rows is None else int(rows)
    if n < b.size:
        raise ValueError(f"rows must be >= {b.size}, got {n}")
    out = np.zeros((n, n))
    out[:b.size, :b.size] = c
    return out


def block_velocity_variance(h, residual, noise_cov, prior_cov, x_lin, directions, blocks,
                            consider=None) -> np.ndarray:
    """Variance of a velocity error common to each block's rows, per axis of W (REML).

    The covariance of the rows is modelled as ``C0 + sum_k q_k C_k``
    (module docstring); ``q`` starts at zero and takes Fisher-scoring steps
    ``q += F^-1 s``, ``s_k = e^T C^-1 C_k C^-1 e - tr(R C_k)``,
    ``F_kl = tr(R C_k R C_l)``, a negative component set to zero, until no
    component changes by more than :data:`BLOCK_VARIANCE_RTOL` of the largest
    stated variance and the variances.

    Parameters
    ----------
    h : array_like, shape ``[measurement, state]``
        Rows' sensitivity to the state; the first ``directions.shape[0]``
        rows are the Doppler's, later ones (another sensor) have no block term.
    residual : array_like, shape ``[measurement]``
        Measured minus predicted at ``x_lin``.
    noise_cov : array_like, shape ``[measurement, measurement]``
        Stated covariance ``C0``.
    prior_cov : array_like, shape ``[state, state]``
    x_lin : array_like, shape ``[state]``
    directions : array_like, shape ``[doppler, 3]``
        Unit direction of each Doppler row in W [1].
    blocks : array_like of int, shape ``[doppler]``
        Block (>= 0) of each Doppler row.
    consider : array_like of bool, shape ``[state]``, optional
        Components held (:func:`compensation.batch_solve.solve_batch`).

    Returns
    -------
    ndarray, shape ``[3]``
        ``q`` [m^2/s^2], each >= 0.
    """
    h = np.asarray(h, dtype=float)
    r = np.asarray(residual, dtype=float)
    c0 = np.asarray(noise_cov, dtype=float)
    u = np.asarray(directions, dtype=float)
    b = np.unique(np.asarray(blocks, dtype=int).ravel(), return_inverse=True)[1].ravel()
    if u.ndim != 2 or u.shape[1] != 3 or b.size != u.shape[0] or b.size > r.size:
        raise ValueError(f"directions [doppler, 3] and blocks [doppler] with doppler <= "
                         f"{r.size} expected, got {u.shape} and {b.shape}")
    p0 = np.asarray(prior_cov, dtype=float)
    x0 = np.asarray(x_lin, dtype=float)
    held = np.zeros(p0.shape[0], dtype=bool) if consider is None else np.asarray(consider, bool)
    ha = h[:, ~held]
    p0a_inv = np.linalg.inv(p0[np.ix_(~held, ~held)])
    # the prior's pull on the estimated components, as in solve_batch
    prior_pull = p0a_inv @ x0[~held]
    uk = _block_factors(u, b, r.size)                       # [axis, row, block]
    cks = [uk[k] @ uk[k].T for k in range(3)]
    floor = float(np.max(np.diag(c0)[:b.size]))
    q = np.zeros(3)
    for _ in range(BLOCK_VARIANCE_PASSES):
        c = c0 + sum(qk * ck for qk, ck in zip(q, cks, strict=True))
        fac = cho_factor(c)
        ci_h = cho_solve(fac, ha)
        p = np.linalg.inv(p0a_inv + ha.T @ ci_h)
        d = p @ (ci_h.T @ r - prior_pull)
        ci_e = cho_solve(fac, r - ha @ d)
        ci_u = [cho_solve(fac, uk[k]) for k in range(3)]    # C^-1 U_k  [row, block]
        g = [ha.T @ ci_u[k] for k in range(3)]              # H^T C^-1 U_k  [state, block]
        # U_k^T R U_l = U_k^T C^-1 U_l - G_k^T P G_l
        rkl = [[uk[k].T @ ci_u[m] - g[k].T @ p @ g[m] for m in range(3)] for k in range(3)]
        score = np.array([np.sum((uk[k].T @ ci_e) ** 2) - np.trace(rkl[k][k])
                          for k in range(3)])
        fisher = np.array([[np.sum(rkl[k][m] ** 2) for m in range(3)] for k in range(3)])
        step = np.linalg.lstsq(fisher, score, rcond=None)[0]
        new = np.maximum(q + step, 0.0)
        done = np.all(np.abs(new - q) <= BLOCK_VARIANCE_RTOL * max(floor, new.max()))
        q = new
        if done:
            break
    return q
