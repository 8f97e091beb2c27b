"""Batch least squares of prior plus measurements, and the spreads of measurement groups.

:func:`solve_batch` is one Gauss-Newton step of a prior and linear measurements
with some components held (consider analysis). :func:`group_scales` estimates
one variance factor per group of measurements (the radar-inertial estimate's
detected scatterers and ground clutter, :data:`DETECTED_GROUP` and
:data:`GROUND_GROUP`): a single reduced chi-square scales every spread alike, so
where one group's spreads are understated more than another's, the noisier
group keeps too much weight and the stated covariance is too small along the
directions it constrains. The factors are Helmert's variance components (Koch,
Parameter Estimation and Hypothesis Testing in Linear Models, 2nd ed. 1999,
sec. 3.6; Teunissen and Amiri-Simkooei, J. Geodesy 82, 2008): each group's
quadratic form of the residuals over its expectation, the residual degrees of
freedom shared among the groups by the hat matrix, iterated to the fixed point.

What it cannot do: a group's factor is a scale of its stated covariance, not a
new shape (a spread that grows along the record, a bias common to its rows
stays as stated); a group with as few rows as the state it constrains has
almost no residual degrees of freedom and keeps its stated spreads.
"""

from __future__ import annotations

import numpy as np

__all__ = ["DETECTED_GROUP", "GROUND_GROUP", "group_scales", "solve_batch"]

#: Group of the Doppler measurements of the scatterers detected in the compensated cells.
DETECTED_GROUP = 0
#: Group of the Doppler measurements of the ground clutter beyond them.
GROUND_GROUP = 1
#: Most fixed-point passes of the variance components (Helmert's iteration converges
#: in a few where the groups' residuals are independent).
GROUP_SCALE_PASSES = 20
#: Relative change of every factor below which the passes stop [1].
GROUP_SCALE_RTOL = 1e-3


def solve_batch(h, residual, noise_cov, prior_cov, x_lin, consider=None
                ) -> tuple[np.ndarray, np.ndarray]:
    """One Gauss-Newton step of prior plus linear measurements, some components held.

    Minimises ``(x_lin + d)^T P0^-1 (x_lin + d) + (r - H d)^T C^-1 (r - H d)``
    over the estimated components; the ``consider`` components stay at
    ``x_lin`` and their prior spread is carried into the others' covariance
    (Schmidt's consider analysis: ``P_aa = I_a^-1 + S P_cc S^T`` with the
    sensitivity ``S = -I_a^-1 H_a^T C^-1 H_c``; Tapley, Schutz and Born,
    Statistical Orbit Determination, 2004, sec. 6.2).

    Parameters
    ----------
    h : array_like, shape ``[measurement, state]``
    residual : array_like, shape ``[measurement]``
        Measured minus predicted at ``x_lin``.
    noise_cov : array_like, shape ``[measurement, measurement]``
    prior_cov : array_like, shape ``[state, state]``
        Prior covariance (zero mean); its cross terms between held and
        estimated components are ignored.
    x_lin : array_like, shape ``[state]``
        Linearisation point.
    consider : array_like of bool, shape ``[state]``, optional
        Components held at ``x_lin`` (default none).

    Returns
    -------
    (ndarray, ndarray)
        The new state ``[state]`` and its covariance ``[state, state]``.
    """
    h = np.asarray(h, dtype=float)
    p0 = np.asarray(prior_cov, dtype=float)
    x0 = np.asarray(x_lin, dtype=float)
    c = np.zeros(x0.size, dtype=bool) if consider is None else np.asarray(consider, dtype=bool)
    a = ~c
    ha, hc = h[:, a], h[:, c]
    p0a_inv = np.linalg.inv(p0[np.ix_(a, a)])
    ci_ha = np.linalg.solve(noise_cov, ha)
    info = p0a_inv + ha.T @ ci_ha
    paa = np.linalg.inv(info)
    x = x0.copy()
    x[a] = x0[a] + paa @ (ci_ha.T @ np.asarray(residual, dtype=float) - p0a_inv @ x0[a])
    pcc = p0[np.ix_(c, c)]
    sens = -paa @ (ci_ha.T @ hc)
    cov = np.zeros_like(p0)
    cov[np.ix_(a, a)] = paa + sens @ pcc @ sens.T
    cov[np.ix_(a, c)] = sens @ pcc
    cov[np.ix_(c, a)] = (sens @ pcc).T
    cov[np.ix_(c, c)] = pcc
    return x, 0.5 * (cov + cov.T)


def group_scales(h, residual, noise_cov, prior_cov, x_lin, group, consider=None) -> np.ndarray:
    """Variance factor of each group of measurements, at least one (Helmert).

    The covariance of the first ``group.size`` measurements is modelled as
    ``D C D``, ``D = diag(sqrt(s[group]))``: each group's spreads scaled by its
    factor, the correlation between rows kept; later rows (measurements of
    another kind, e.g. a flight controller's attitude) keep theirs. At the
    solution of :func:`solve_batch` with that covariance the residuals ``e``
    give per group ``q_g = e_g^T C_gg^-1 e_g``; its expectation is
    ``m_g - tr(C_gg^-1 (H P H^T)_gg)`` (``m_g`` rows, ``P`` the posterior
    covariance of the estimated components, ``C - H P H^T`` the residuals'
    covariance), the group's share of the degrees of freedom. Each factor is
    multiplied by their ratio until none changes by more than
    :data:`GROUP_SCALE_RTOL`; a factor below one is set to one (spreads are never
    scaled down).

    Parameters
    ----------
    h : array_like, shape ``[measurement, state]``
    residual : array_like, shape ``[measurement]``
        Measured minus predicted at ``x_lin``.
    noise_cov : array_like, shape ``[measurement, measurement]``
        Stated covariance.
    prior_cov : array_like, shape ``[state, state]``
    x_lin : array_like, shape ``[state]``
    group : array_like of int, shape ``[grouped]``
        Group (>= 0) of each of the first ``grouped`` measurements.
    consider : array_like of bool, shape ``[state]``, optional
        Components held at ``x_lin`` (:func:`solve_batch`).

    Returns
    -------
    ndarray, shape ``[max(group) + 1]``
        Factor of each group's variances [1] (one where a group has no rows).
    """
    h = np.asarray(h, dtype=float)
    r = np.asarray(residual, dtype=float)
    c0 = np.asarray(noise_cov, dtype=float)
    g = np.asarray(group, dtype=int).ravel()
    if g.size == 0 or g.min() < 0 or g.size > r.size:
        raise ValueError(f"group: expected {r.size} or fewer integers >= 0, got {g.size} "
                         f"(minimum {g.min() if g.size else None})")
    p0 = np.asarray(prior_cov, dtype=float)
    held = np.zeros(p0.shape[0], dtype=bool) if consider is None else np.asarray(consider, bool)
    ha = h[:, ~held]
    p0a_inv = np.linalg.inv(p0[np.ix_(~held, ~held)])
    rows = [np.flatnonzero(g == k) for k in range(g.max() + 1)]
    s = np.ones(len(rows))
    for _ in range(GROUP_SCALE_PASSES):
        f = np.sqrt(s[g])
        c = c0.copy()
        c[:g.size, :g.size] *= np.outer(f, f)
        x, _ = solve_batch(h, r, c, p0, x_lin, held)
        e = r - h @ (x - x_lin)
        hph = ha @ np.linalg.solve(p0a_inv + ha.T @ np.linalg.solve(c, ha), ha.T)
        new = s.copy()
        for k, idx in enumerate(rows):
            if idx.size:
                ckk = c[np.ix_(idx, idx)]
                dof = idx.size - np.trace(np.linalg.solve(ckk, hph[np.ix_(idx, idx)]))
                new[k] = max(1.0, s[k] * float(e[idx] @ np.linalg.solve(ckk, e[idx]))
                             / max(dof, 1.0))
        done = np.all(np.abs(new - s) <= GROUP_SCALE_RTOL * s)
        s = new
        if done:
            break
    return s
