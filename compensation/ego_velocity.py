"""Platform velocity from the radar: slow-time phase slopes of stationary scatterers.

A scatterer at rest in W seen in the direction ``u`` (unit vector in W) from a
radar moving with velocity ``v`` has the range rate ``v_r = -u . v`` (positive
receding, docs/conventions.md). After a motion compensation with a velocity
that is wrong by ``dv``, every stationary scatterer keeps the residual range
rate ``-u . dv``; fitting that linear model over many scatterers of different
directions gives ``dv`` (Kellner et al., "Instantaneous ego-motion estimation
using Doppler radar", ITSC 2013, eq. 3-5). Moving objects are outliers of the
model: random sample consensus, then a Huber M-estimate on the inliers.

With fewer than three independent directions part of ``dv`` is unobservable;
a zero-mean Gaussian prior of spread ``prior_sigma`` keeps the estimate
defined there (its uncertainty then equals the prior): the radial part along
the scatterers, which is all their Doppler depends on, is still estimated.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from ._checks import finite_array, positive

#: Slow-time zero padding of the coarse Doppler search [1] (a sixteenth of a bin).
COARSE_PAD = 16
#: Default spread of the zero-mean prior on each velocity component [m/s].
VELOCITY_PRIOR_SIGMA = 1.0
#: Random-sample-consensus draws of three scatterers.
RANSAC_DRAWS = 64
#: Inlier threshold in units of the measurement spread (when ``threshold`` is not given).
INLIER_SIGMAS = 4.0
#: Smallest consensus that may reject detections: more than the three unknowns, since
#: any three detections fit a velocity exactly (a minimal sample agrees with itself).
MIN_CONSENSUS = 4


@dataclass(frozen=True)
class EgoVelocity:
    """Velocity estimate of the radar from stationary scatterers.

    Attributes
    ----------
    velocity : ndarray, shape ``[3]``
        Estimated velocity, in the frame of the directions [m/s].
    covariance : ndarray, shape ``[3, 3]``
        Its covariance [m^2/s^2].
    inliers : ndarray of bool, shape ``[detection]``
        Detections consistent with a static world.
    residual_rms : float
        RMS range-rate residual over the inliers [m/s].
    """

    velocity: np.ndarray
    covariance: np.ndarray
    inliers: np.ndarray
    residual_rms: float

    @property
    def sigma(self) -> np.ndarray:
        """One-sigma uncertainty of each component, shape ``[3]`` [m/s]."""
        return np.sqrt(np.diag(self.covariance))


def slow_time_velocity(slow_time, chirp_times, wavelength: float) -> tuple[float, float]:
    """Range rate of one scatterer from its slow-time phase, with its one-sigma spread.

    Parameters
    ----------
    slow_time : array_like, shape ``[chirp]``
        Complex beam output of the scatterer (one frame) [any unit].
    chirp_times : array_like, shape ``[chirp]``
        Uniform chirp times [s].
    wavelength : float
        Wavelength of the phase ``4 pi R / lambda`` [m].

    Returns
    -------
    (float, float)
        Range rate ``v_r`` [m/s] (positive receding) and its one-sigma spread [m/s].

    Notes
    -----
    A coarse peak of the ``COARSE_PAD`` times zero-padded spectrum removes
    most of the rotation, then a least-squares line through the unwrapped
    phase (weights ``|y|^2``) refines it: ``v_r = lambda / (4 pi) dphi/dt``.
    The spread is that of the slope from the phase residual (Kay, Fundamentals
    of Statistical Signal Processing I, eq. 3.41 for a line fit).
    """
    y = np.asarray(slow_time, dtype=complex)
    t = finite_array("chirp_times", chirp_times, shape=(y.size,))
    lam = positive("wavelength", wavelength)
    if y.size < 4:
        raise ValueError(f"slow_time must hold at least 4 chirps, got {y.size}")
    dt = float(np.median(np.diff(t)))
    spec = np.abs(np.fft.fft(y, y.size * COARSE_PAD)) ** 2
    f0 = float(np.fft.fftfreq(y.size * COARSE_PAD, d=dt)[int(np.argmax(spec))])
    tm = t - t.mean()
    z = y * np.exp(-2j * np.pi * f0 * tm)
    phase = np.unwrap(np.angle(z))
    w = np.abs(z) ** 2
    if not np.any(w > 0):
        raise ValueError("slow_time is zero everywhere; no phase to fit")
    w = w / w.mean()
    tw = np.sum(w * tm) / w.sum()
    sxx = np.sum(w * (tm - tw) ** 2)
    slope = np.sum(w * (tm - tw) * phase) / sxx
    resid = phase - np.sum(w * phase) / w.sum() - slope * (tm - tw)
    var_phase = np.sum(w * resid ** 2) / max(y.size - 2, 1)
    scale = lam / (4.0 * np.pi)
    return float((2.0 * np.pi * f0 + slope) * scale), float(np.sqrt(var_phase / sxx) * scale)


def fit_ego_velocity(directions, radial_velocity, sigma=None, *, threshold: float | None = None,
                     prior_sigma: float = VELOCITY_PRIOR_SIGMA, seed: int = 0) -> EgoVelocity:
    """Robust fit of ``v_r = -u . v`` over stationary scatterers (RANSAC, then Huber).

    RANSAC rejects detections only when at least :data:`MIN_CONSENSUS` of them
    agree within the threshold; otherwise (the spreads understate the misfit)
    every detection is kept and the Huber loss weighs them.

    Parameters
    ----------
    directions : array_like, shape ``[detection, 3]``
        Unit directions ``u`` to the scatterers [1].
    radial_velocity : array_like, shape ``[detection]``
        Measured range rates [m/s] (positive receding).
    sigma : array_like, shape ``[detection]``, optional
        One-sigma spread of each range rate [m/s]; default equal weights with
        the spread taken from the residual.
    threshold : float, optional
        Inlier threshold on the range-rate residual [m/s]; default
        ``INLIER_SIGMAS`` times the median ``sigma`` (or 0.05 m/s).
    prior_sigma : float
        Spread of the zero-mean prior on each velocity component [m/s].
    seed : int
        Seed of the random sample consensus (reproducible draws).

    Returns
    -------
    EgoVelocity
        ``velocity`` is ``v``; its covariance is ``(J^T J)^-1`` of the weighted
        problem, scaled by the reduced chi-square when above one.
    """
    u = finite_array("directions", directions, ndim=2)
    if u.shape[1] != 3 or u.shape[0] < 1:
        raise ValueError(f"directions must have shape [detection >= 1, 3], got {u.shape}")
    vr = finite_array("radial_velocity", radial_velocity, shape=(u.shape[0],))
    if sigma is None:
        s = np.ones(vr.size)
        scale_known = False
    else:
        s = finite_array("sigma", sigma, shape=(vr.size,))
        if np.any(s <= 0):
            raise ValueError(f"sigma must be > 0 m/s, got minimum {s.min()!r}")
        scale_known = True
    if not scale_known and vr.size <= 3:
        raise ValueError(f"sigma (range-rate spreads) is needed with {vr.size} detection(s): "
                         f"the residual of fewer than 4 cannot give the spread")
    prior = positive("prior_sigma", prior_sigma)
    thr = (INLIER_SIGMAS * float(np.median(s)) if scale_known else 0.05) if threshold is None \
        else positive("threshold", threshold)
    inl = np.ones(vr.size, dtype=bool)
    if vr.size > MIN_CONSENSUS:            # a consensus needs spare detections
        rng = np.random.default_rng(seed)
        best = -1
        for _ in range(RANSAC_DRAWS):
            pick = rng.choice(vr.size, 3, replace=False)
            v, *_ = np.linalg.lstsq(-u[pick], vr[pick], rcond=None)
            now = np.abs(-u @ v - vr) <= thr
            if now.sum() > best:
                best, inl = int(now.sum()), now
        if best < MIN_CONSENSUS:           # spreads understated: keep all, Huber weighs them
            inl = np.ones(vr.size, dtype=bool)
    a, b, w = -u[inl], vr[inl], 1.0 / s[inl]

    def residual(v):
        return np.concatenate([(a @ v - b) * w, v / prior])

    sol = least_squares(residual, np.zeros(3), loss="huber", f_scale=float(np.median(
        thr * w)), method="trf", xtol=1e-14, ftol=1e-14, gtol=1e-14)
    jac = np.vstack([a * w[:, None], np.eye(3) / prior])
    cov = np.linalg.inv(jac.T @ jac)
    res = a @ sol.x - b
    dof = max(b.size - 3, 1)
    chi2 = float(np.sum((res * w) ** 2) / dof)
    cov = cov * (max(chi2, 1.0) if scale_known else chi2)
    rms = float(np.sqrt(np.mean(res ** 2)))
    return EgoVelocity(sol.x, cov, inl, rms)


def block_misfit(directions, range_rate, sigma, block) -> float:
    """Spread of range rates about one velocity per block beyond their stated spreads [m/s].

    A beam's range rate is that of every scatterer and sidelobe in its cell, not
    of one point at its direction, and the residual of its phase line (``sigma``)
    does not see that. Within a block every stationary scatterer sees the same
    radar velocity, so the residuals of a least-squares velocity per block
    (blocks of more than three range rates) show it: their spread ``s`` is the
    median absolute residual over all blocks times 1.4826 (the normal's MAD) and
    ``sqrt(n / (n - 3))`` for the three fitted components, robust to the moving
    or spurious scatterers a consensus rejects later.

    Parameters
    ----------
    directions : array_like, shape ``[measurement, 3]``
        Unit directions ``u`` [1].
    range_rate, sigma : array_like, shape ``[measurement]``
        Range rates and their stated spreads [m/s].
    block : array_like of int, shape ``[measurement]``
        Block of each range rate.

    Returns
    -------
    float
        ``sqrt(max(s^2 - median(sigma)^2, 0))``; zero without a block of four.
    """
    u = finite_array("directions", directions, ndim=2)
    vr = finite_array("range_rate", range_rate, shape=(u.shape[0],))
    s = finite_array("sigma", sigma, shape=(u.shape[0],))
    blk = np.asarray(block).reshape(u.shape[0])
    res, dof = [], 0
    for b in np.unique(blk):
        idx = np.flatnonzero(blk == b)
        if idx.size > 3:
            v, *_ = np.linalg.lstsq(-u[idx], vr[idx], rcond=None)
            res.append(vr[idx] + u[idx] @ v)
            dof += idx.size - 3
    if not res:
        return 0.0
    r = np.concatenate(res)
    spread = 1.4826 * np.median(np.abs(r)) * np.sqrt(r.size / dof)
    return float(np.sqrt(max(spread ** 2 - np.median(s) ** 2, 0.0)))
