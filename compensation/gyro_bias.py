"""Gyro bias from the apparent angular drift of stationary scatterers over a record.

With a gyro bias ``b`` (body frame) the integrated attitude is
``R_est = R (I + [eps]_x)`` with ``eps' = b - omega x eps`` (Titterton & Weston,
Strapdown Inertial Navigation Technology, 2nd ed., eq. 11.6); the same error in
the world frame, ``phi = R eps``, obeys ``phi' = R b``, so
``phi(t) = (int_{t_0}^t R ds) b`` (the frames' attitudes integrated by the
trapezoid rule; ``R b (t - t_0)`` for a record that does not turn). The exact
chain steers with ``R_est``, so a scatterer in the world direction ``u``
appears at ``u_app = R_est R^T u = u + phi x u``: it drifts on the sky by
``-[u]_x phi(t)``. Fitting that drift over frames and scatterers (a free
initial direction per scatterer) gives ``b``. One scatterer observes the two
components across its line of sight; directions the record does not observe
keep a zero-mean prior (estimate zero, the prior's spread).

The residual is taken along each scatterer's azimuth and elevation (the
tangent plane of its direction), each divided by its spread: an array that
resolves azimuth only (a line array, the xWR18xx with its half-wavelength
elevation baseline) measures the azimuth drift to a fraction of its beam and
no elevation drift, so only the bias components the azimuth drift sees are
estimated.

The gyroscope's scale and cross-axis error ``M - I`` turns the record's own
rotation ``theta(t)`` (body frame, from the first frame) into an attitude error
``(M - I) theta(t)`` whose slope over the frames, ``(M - I) s`` with ``s`` the
least-squares slope of ``theta``, reads as a bias; over a short record of a
hovering platform (tens of deg/s of jitter) it is comparable to the bias. With
every entry of ``M - I`` of spread ``sigma_M`` its covariance is
``sigma_M^2 |s|^2 I``, added to the observed components' (a bias estimated from
directions is the record's mean drift rate; the drift is what it removes).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid
from scipy.spatial.transform import Rotation

from ._checks import finite_array, positive

#: Smallest eigenvalue of the normal matrix, relative to the largest, of a bias
#: direction counted as observed; below it (e.g. the rotation about the line of
#: sight of a single scatterer) the estimate keeps the prior (zero).
OBSERVABLE_RCOND = 1e-2
#: Default spread of the zero-mean prior on each bias component [rad/s] (3 deg/s,
#: six times the turn-on bias of a consumer MEMS gyroscope).
BIAS_PRIOR_SIGMA = float(np.deg2rad(3.0))
#: Default one-sigma scale-factor error and cross-axis sensitivity of the gyroscope [1]
#: (consumer MEMS, Bosch BMI088 class: 1 % each).
SCALE_SIGMA = 0.01


@dataclass(frozen=True)
class GyroBias:
    """Gyro bias estimate.

    Attributes
    ----------
    bias : ndarray, shape ``[3]``
        ``b`` in the body frame B [rad/s]; subtract it from the gyro samples.
    covariance : ndarray, shape ``[3, 3]``
        Its covariance [rad^2/s^2].
    residual_rms : float
        RMS of the angle residual [rad] (each angle over its relative spread).
    """

    bias: np.ndarray
    covariance: np.ndarray
    residual_rms: float

    @property
    def sigma(self) -> np.ndarray:
        """One-sigma uncertainty of each component, shape ``[3]`` [rad/s]."""
        return np.sqrt(np.diag(self.covariance))


def _skew(u: np.ndarray) -> np.ndarray:
    """``[u]_x`` for ``u [..., 3]``, shape ``[..., 3, 3]``."""
    z = np.zeros(u.shape[:-1])
    return np.stack([np.stack([z, -u[..., 2], u[..., 1]], -1),
                     np.stack([u[..., 2], z, -u[..., 0]], -1),
                     np.stack([-u[..., 1], u[..., 0], z], -1)], -2)


def _tangent_axes(u: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Unit azimuth and elevation directions ``[2, 3]`` at the unit direction ``u [3]``
    (in the frame of the directions), the angles taken in the frame ``frame^T u``
    (:func:`compensation.geometry.direction`: ``(cos el sin az, sin el, cos el cos az)``)."""
    x, y, z = frame.T @ u
    az, el = np.arctan2(x, z), np.arcsin(np.clip(y, -1.0, 1.0))
    axes = np.array([[np.cos(az), 0.0, -np.sin(az)],
                     [-np.sin(el) * np.sin(az), np.cos(el), -np.sin(el) * np.cos(az)]])
    return axes @ frame.T


def fit_gyro_bias(times, directions, attitude, *, sigma: float | None = None,
                  prior_sigma: float = BIAS_PRIOR_SIGMA, spread=(1.0, 1.0),
                  frame=None, scale_sigma: float = SCALE_SIGMA) -> GyroBias:
    """Least-squares gyro bias from scatterer directions measured frame after frame.

    Parameters
    ----------
    times : array_like, shape ``[frame]``
        Time of each measurement (frame centre) [s].
    directions : array_like, shape ``[frame, detection, 3]``
        Apparent unit directions in W of the same stationary scatterers after
        compensation with the biased attitude [1]; NaN where a scatterer was
        not measured.
    attitude : array_like, shape ``[frame, 3, 3]``
        ``R_WB`` at each measurement [1].
    sigma : float, optional
        One-sigma spread [rad] of an angle of relative spread 1 (``spread``);
        default from the residual.
    prior_sigma : float
        Spread of the zero-mean prior [rad/s] of a bias direction that is not
        observed (:data:`OBSERVABLE_RCOND`).
    spread : array_like, shape ``[2]`` or ``[detection, 2]``
        Relative spread of each detection's azimuth and elevation [1]
        (``sigma`` times it in rad); ``inf`` for an angle the directions do not
        measure (e.g. ``(1, inf)`` for an array that resolves azimuth only):
        its drift is left out.
    frame : array_like, shape ``[3, 3]``, optional
        Rotation turning the frame of the angles into W (``R_BA`` of a mounted
        radar, :mod:`compensation.mounting`); default W.
    scale_sigma : float
        One-sigma scale-factor error and cross-axis sensitivity of the
        gyroscope [1] (0: none); its drift on the record's rotation widens the
        observed components' covariance (module docstring).

    Returns
    -------
    GyroBias

    Raises
    ------
    ValueError
        Fewer than two frames, shapes that disagree, or a spread not positive
        (``scale_sigma`` negative).
    """
    t = finite_array("times", times, ndim=1)
    u = np.asarray(directions, dtype=float)
    if u.ndim != 3 or u.shape[0] != t.size or u.shape[2] != 3:
        raise ValueError(f"directions must have shape [frame={t.size}, detection, 3], got "
                         f"{u.shape}")
    att = finite_array("attitude", attitude, shape=(t.size, 3, 3))
    if t.size < 2:
        raise ValueError(f"times must hold at least 2 frames to see a drift, got {t.size}")
    prior = positive("prior_sigma", prior_sigma)
    if not (np.isfinite(scale_sigma) and scale_sigma >= 0):
        raise ValueError(f"scale_sigma must be a finite spread >= 0 [1], got {scale_sigma!r}")
    rel = np.asarray(spread, dtype=float)
    if rel.shape not in ((2,), (u.shape[1], 2)) or np.isnan(rel).any() or np.any(rel <= 0):
        raise ValueError(f"spread must be positive (inf for an angle not measured) with shape "
                         f"[2] or [detection={u.shape[1]}, 2], got {spread!r}")
    rel = np.broadcast_to(rel, (u.shape[1], 2))
    rot = np.eye(3) if frame is None else finite_array("frame", frame, shape=(3, 3))
    turned = cumulative_trapezoid(att, t, axis=0, initial=0.0)    # int R ds [frame, 3, 3]
    rows, ys, free = [], [], 0
    for j in range(u.shape[1]):
        ok = np.all(np.isfinite(u[:, j]), axis=1)
        seen_axes = np.isfinite(rel[j])
        if ok.sum() < 2 or not seen_axes.any():
            continue
        uj = u[ok, j]
        mean_u = uj.mean(axis=0)
        mean_u /= np.linalg.norm(mean_u)
        # the measured angles only, each in units of its spread
        w = (_tangent_axes(mean_u, rot) / rel[j][:, None])[seen_axes]   # [axis, 3]
        a = w @ (-_skew(mean_u) @ turned[ok])                  # [frame, axis, 3]
        rows.append((a - a.mean(axis=0)).reshape(-1, 3))
        ys.append(((uj - uj.mean(axis=0)) @ w.T).ravel())
        free += int(seen_axes.sum())    # the scatterer's initial angles
    if not rows:
        raise ValueError("directions: no scatterer measured in at least 2 frames")
    a = np.vstack(rows)
    y = np.concatenate(ys)
    lam, vec = np.linalg.eigh(a.T @ a)
    seen = lam >= OBSERVABLE_RCOND * lam.max()
    proj = vec[:, seen].T @ (a.T @ y)
    coef = vec[:, seen] @ (proj / lam[seen])
    res = y - a @ coef
    dof = max(y.size - free - int(seen.sum()), 1)
    s2 = float(np.sum(res ** 2) / dof) if sigma is None else positive("sigma", sigma) ** 2
    cov = (vec[:, seen] * (s2 / lam[seen])) @ vec[:, seen].T
    # the scale and cross-axis error on the record's rotation: slope of theta over the frames
    theta = Rotation.from_matrix(att[0].T @ att).as_rotvec()     # [frame, 3], body
    slope = (t - t.mean()) @ theta / np.sum((t - t.mean()) ** 2)
    drift = float(np.sum(slope ** 2)) * float(scale_sigma) ** 2
    cov += drift * vec[:, seen] @ vec[:, seen].T
    cov += (vec[:, ~seen] * prior ** 2) @ vec[:, ~seen].T
    return GyroBias(coef, cov, float(np.sqrt(np.mean(res ** 2))))
