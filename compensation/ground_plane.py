"""Roll and pitch from the ground plane in the radar data.

A down-looking radar over flat ground sees ground clutter: each clutter
scatterer has a range ``r`` and a direction ``u``, a point ``p = r u``. A
down-looking radar's points are the scatterers that every ground cell's plane
waves give (:mod:`compensation.ground_dense`: range from the range kernel over
the cells, direction from the whole array at one slot-aligned instant), over a
dense ground also those of the range-Doppler cells (:mod:`compensation.ground_dbs`,
where the range cells give too few); a mounted
radar's are its beam maxima (azimuth from the array, elevation from the raised
TX's phase comparison, :func:`compensation.elevation.measure_elevation`). Formed
with the platform's estimated attitude ``R_est`` the points are in W as that
attitude has it; with the true attitude ``R = exp([phi]x) R_est`` the ground
points satisfy ``e_z . exp([phi]x) p = h`` (``e_z`` down in W, ``h`` the height).
A robust plane fit (RANSAC, Fischler and Bolles, CACM 1981, then weighted
least squares with every point's spread along the plane's normal,
``sigma_i^2 = n^T C_i n``, the effective-variance method) gives ``phi``'s
horizontal components, the correction of roll and pitch ``(tilt_n, tilt_e)``
(:mod:`compensation.radar_inertial`), and their covariance ``(J^T W J)^-1``,
scaled up by the reduced chi-square when above one, and again until it covers
the spread of the fits that leave one group out (the jackknife: groups of azimuth
sectors about the nadir for the dense points, whose errors the frames share;
frames for the beam maxima).

Assumption: the ground in view is flat and level. A ground sloped by ``s``
biases the tilt by ``s`` (the fit levels the ground, not gravity); a wall or a
roof in the range window is an outlier only when the ground dominates it.
What it cannot observe: the heading (a rotation about the normal leaves the
plane unchanged), and, with the frames as groups, the error common to every frame
(a hovering platform sees the same scatterers sharing the same cells in every
frame; the sectors' jackknife sees it as the spread between parts of the ground). Its warnings
(:class:`GroundPlaneWarning`): no ground point in the range window, too few
points on the plane, a fit whose residuals exceed the points' spreads.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.linalg import eigh
from scipy.spatial.transform import Rotation

from ._checks import finite_array
from .calibration import DIRECTION_SIGMA, UNRESOLVED_DIRECTION_SIGMA, detect_scatterers
from .geometry import direction, direction_tangents
from .ground_dbs import DOPPLER_BELOW_POINTS, doppler_ground_directions, unseen
from .ground_dense import (
    DENSE_ANGLE_SIGMA,
    DENSE_RANGE_SIGMA_CELLS,
    SNAPSHOT_CHIRP,
    dense_ground_directions,
)
from .ground_looks import GroundLook
from .mounting import mounting_rotation, radar_frame_motion, world_directions
from .observability import ObservabilityWarning
from .radar_inertial import DEFAULT_TILT_SIGMA
from .strapdown import PlatformMotion

__all__ = ["ASSUMPTION", "GroundPlane", "GroundPlaneWarning", "fit_ground_plane", "fit_looks",
           "ground_check", "ground_points", "ground_tilt", "point_covariance"]

#: What the ground tilt assumes (in every report).
ASSUMPTION = ("level flat ground in view: a ground sloped by s biases roll and pitch by s; "
              "heading not observed")
#: Fewest points on the plane for a tilt estimate.
MIN_GROUND_POINTS = 8
#: Reduced chi-square of the fit above which it is called bad (residuals well beyond the
#: points' spreads: a sloped, stepped or curved ground, or clutter that is no ground).
MAX_CHI2 = 9.0
#: RANSAC draws of three points (seeded): with half the points outliers, 200 draws miss
#: an all-inlier triple with probability 0.875^200, about 3e-12.
RANSAC_DRAWS = 200
#: A point is on the plane within this many of its spreads along the normal (RANSAC), and
#: then of the spreads the fit's residuals show (its reduced chi-square when above one).
INLIER_SIGMAS = 3.0
#: Largest angle between a candidate plane's normal and the assumed down [rad]: a
#: steeper plane is a wall or a roof edge, not the ground below.
MAX_NORMAL_ANGLE = float(np.deg2rad(20.0))
#: Detection of the ground clutter: most scatterers, and dynamic range [dB] (the far
#: ground is weaker than the near: grazing incidence and range).
GROUND_COUNT = 40
GROUND_DYNAMIC_RANGE_DB = 45.0
#: Azimuth axis of the ground search [rad] (-70..70 deg in 2 deg steps: the ground
#: fills the beam).
GROUND_AZIMUTH = np.deg2rad(np.arange(-70.0, 70.5, 2.0))
#: Most passes of fitting and re-selecting the points on the plane.
RESELECT_PASSES = 5
#: Least fraction of the points on the plane: the fit assumes most ground points follow
#: their spreads and takes the rest for outliers (wrong directions of cells shared by
#: several scatterers); with fewer, the ground is rough, not flat, or not the main
#: return, and errors beyond the spreads are no longer rare, which a fit of the few
#: cannot tell (a breakdown point of one half, as least median of squares: Rousseeuw,
#: JASA 1984).
MIN_INLIER_FRACTION = 0.5
#: Spread of a ground clutter point's azimuth and elevation [rad]: several scatterers
#: share a range cell and beam, which turns the measured directions (the flights'
#: ``parking_lot`` clutter, every point matched to its scatterer: median error 1.6 deg in
#: azimuth and 2.1 deg in elevation, a Gaussian spread of 2.4 and 3.2 deg; the tails
#: beyond are the outliers).
GROUND_ANGLE_SIGMA = float(np.deg2rad(3.0))
#: Gauss-Newton passes of the weighted fit (each re-linearises at the current tilt).
FIT_PASSES = 6
#: Fewest groups (frames) for the leave-one-group-out jackknife of the tilt's spread.
MIN_JACKKNIFE_GROUPS = 3


class GroundPlaneWarning(ObservabilityWarning):
    """The ground plane gives no tilt, or a doubtful one (too few points, a bad fit)."""


@dataclass(frozen=True)
class GroundPlane:
    """Ground plane fitted to the clutter points and the tilt correction it gives.

    Attributes
    ----------
    tilt : ndarray, shape ``[2]``
        Correction ``(tilt_n, tilt_e)`` of the attitude the points were formed
        with [rad] (``R = exp([phi]x) R_est``, ``phi = (tilt_n, tilt_e, 0)``);
        NaN when no fit.
    tilt_covariance : ndarray, shape ``[2, 2]``
        Its covariance [rad^2]; NaN when no fit.
    height : float
        Distance of the plane from the radar [m].
    normal : ndarray, shape ``[3]``
        Unit normal of the plane in the points' frame, pointing away from the radar.
    points : int
        Points given.
    inliers : int
        Points on the plane.
    chi2 : float
        Reduced chi-square of the inliers at the fit.
    rms : float
        Root mean square of the inliers' distances from the plane [m].
    warnings : tuple of str
    spread_scale : float
        Factor (>= 1) on the points' covariance that made it cover the spread of the
        leave-one-group-out fits (the jackknife over frames); 1 without groups.
    looks : tuple of compensation.ground_looks.GroundLook
        The frames' points and the attitudes that turned them into W (the dense
        points of :func:`ground_tilt`, which
        :func:`compensation.ground_refit.refit_ground` turns with another
        integration); empty otherwise.
    source : str
        The cells the points come from: ``"range"`` (one snapshot's range cells, or
        a mounted radar's beam maxima) or ``"range+doppler"`` (with the range-Doppler
        cells, :mod:`compensation.ground_dbs`).
    jackknifed : bool
        Whether every leave-one-group-out fit gave a tilt (the jackknife ran); range-
        Doppler points give a tilt only where it did.
    """

    tilt: np.ndarray
    tilt_covariance: np.ndarray
    height: float
    normal: np.ndarray
    points: int
    inliers: int
    chi2: float
    rms: float
    warnings: tuple[str, ...] = field(default_factory=tuple)
    spread_scale: float = 1.0
    looks: tuple = field(default=(), repr=False, compare=False)
    source: str = "range"
    jackknifed: bool = False

    @property
    def usable(self) -> bool:
        """Whether the fit gives a tilt (enough points on the plane, not a bad fit, a
        spread below the prior's :data:`compensation.radar_inertial.DEFAULT_TILT_SIGMA`)."""
        return bool(np.all(np.isfinite(self.tilt)) and self.inliers >= MIN_GROUND_POINTS
                    and self.inliers >= MIN_INLIER_FRACTION * self.points
                    and bool(np.hypot(*self.tilt) <= MAX_NORMAL_ANGLE)
                    and self.chi2 <= MAX_CHI2
                    and bool(np.all(self.tilt_sigma < DEFAULT_TILT_SIGMA))
                    and (self.source == "range" or self.jackknifed))

    @property
    def tilt_sigma(self) -> np.ndarray:
        """One-sigma spread of :attr:`tilt`, shape ``[2]`` [rad]."""
        return np.sqrt(np.diag(self.tilt_covariance))

    def report(self) -> dict:
        """Tilt [deg] and its spread, the fit's figures and the assumption (SI otherwise)."""
        return {"tilt_deg": np.rad2deg(self.tilt).tolist(),
                "tilt_sigma_deg": np.rad2deg(self.tilt_sigma).tolist(),
                "height_m": self.height, "points": self.points, "inliers": self.inliers,
                "chi2": self.chi2, "rms_m": self.rms, "spread_scale": self.spread_scale,
                "point_cells": self.source, "used": self.usable,
                "assumption": ASSUMPTION, "warnings": list(self.warnings)}


def point_covariance(ranges, azimuth, elevation, range_sigma, azimuth_sigma,
                     elevation_sigma) -> np.ndarray:
    """Covariance of points ``r u(az, el)`` from independent range and angle errors.

    Parameters
    ----------
    ranges, azimuth, elevation : array_like, shape ``[point]``
        [m, rad, rad].
    range_sigma, azimuth_sigma, elevation_sigma : array_like, broadcast to ``[point]``
        One-sigma spreads [m, rad, rad].

    Returns
    -------
    ndarray, shape ``[point, 3, 3]`` [m^2]
        ``s_r^2 u u^T + r^2 (s_az^2 a a^T + s_el^2 e e^T)``, ``a, e`` the
        derivatives of ``u`` along azimuth and elevation (first order).
    """
    r, az, el = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (ranges, azimuth, elevation))
    sr, sa, se = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in
                                       (range_sigma, azimuth_sigma, elevation_sigma)), r)[:3]
    u = direction(az, el)
    da, de = direction_tangents(az, el)
    return ((sr ** 2)[:, None, None] * np.einsum("ni,nj->nij", u, u)
            + (r ** 2 * sa ** 2)[:, None, None] * np.einsum("ni,nj->nij", da, da)
            + (r ** 2 * se ** 2)[:, None, None] * np.einsum("ni,nj->nij", de, de))


def _ransac(p: np.ndarray, cov: np.ndarray, rng) -> np.ndarray:
    """Inliers ``[point]`` of the plane through three points that holds the most points
    within :data:`INLIER_SIGMAS` of their spread along its normal (ties: least squares,
    then the earliest draw); all draws scored at once."""
    idx = np.array([rng.choice(p.shape[0], 3, replace=False) for _ in range(RANSAC_DRAWS)])
    a = p[idx[:, 0]]                                                    # [draw, 3]
    n = np.cross(p[idx[:, 1]] - a, p[idx[:, 2]] - a)
    norm = np.linalg.norm(n, axis=1)
    ok = norm >= 1e-12
    n = n / np.where(ok, norm, 1.0)[:, None]
    n = n * np.where(n[:, 2] == 0.0, 1.0, np.sign(n[:, 2]))[:, None]   # pointing down
    ok &= np.arccos(np.clip(n[:, 2], -1.0, 1.0)) <= MAX_NORMAL_ANGLE
    if not np.any(ok):
        return np.zeros(p.shape[0], dtype=bool)
    n, a = n[ok], a[ok]
    z = (p @ n.T - np.sum(a * n, axis=1)) / np.sqrt(np.einsum("di,nij,dj->nd", n, cov, n))
    inl = np.abs(z) <= INLIER_SIGMAS                                    # [point, draw]
    best = np.lexsort((np.sum(np.where(inl, z ** 2, 0.0), axis=0), -inl.sum(axis=0)))[0]
    return inl[:, best]


def _weighted_fit(p: np.ndarray, cov: np.ndarray, tilt: np.ndarray):
    """Gauss-Newton of ``e_z . exp([phi]x) p_i = h`` over ``(tilt_n, tilt_e, h)``: the tilt,
    height, the covariance ``[3, 3]`` of the three and the normalised residuals."""
    x = np.array([tilt[0], tilt[1], 0.0])
    rot = Rotation.from_rotvec([x[0], x[1], 0.0]).as_matrix()
    w = 1.0 / np.einsum("j,njk,k->n", rot[2], cov, rot[2])
    x[2] = float(np.sum(w * (p @ rot[2])) / np.sum(w))          # the weighted mean height
    for _ in range(FIT_PASSES):
        rot = Rotation.from_rotvec([x[0], x[1], 0.0]).as_matrix()
        q = p @ rot.T                                   # the points levelled
        w = 1.0 / np.einsum("j,njk,k->n", rot[2], cov, rot[2])   # spread along the normal
        # d(e_z . exp([d]x) q)/d(d) = (q_y, -q_x) for a small turn d; d/dh = -1
        jac = np.column_stack([q[:, 1], -q[:, 0], -np.ones(p.shape[0])])
        res = q[:, 2] - x[2]
        info = jac.T @ (w[:, None] * jac)
        step = -np.linalg.solve(info, jac.T @ (w * res))
        x = x + step
        if np.max(np.abs(step[:2])) < 1e-12:
            break
    rot = Rotation.from_rotvec([x[0], x[1], 0.0]).as_matrix()
    q = p @ rot.T
    var = np.einsum("j,njk,k->n", rot[2], cov, rot[2])
    jac = np.column_stack([q[:, 1], -q[:, 0], -np.ones(p.shape[0])])
    info = jac.T @ (jac / var[:, None])
    return x, np.linalg.inv(info), (q[:, 2] - x[2]) / np.sqrt(var)


def fit_ground_plane(points, covariance, *, groups=None, seed: int = 0,
                     warn: bool = True) -> GroundPlane:
    """Robust plane fit of ground points and the roll and pitch correction it gives.

    Parameters
    ----------
    points : array_like, shape ``[point, 3]``
        Points in W as the estimated attitude has it (z down) [m].
    covariance : array_like, shape ``[point, 3, 3]``
        Their covariances [m^2] (:func:`point_covariance`).
    groups : array_like of int, shape ``[point]``, optional
        Group (frame) of every point. With :data:`MIN_JACKKNIFE_GROUPS` or more, the
        tilt's covariance is scaled up until it covers the spread of the fits that
        leave one group out (the delete-one jackknife, Efron and Stein, Ann. Stat.
        1981): the spreads the points show across frames where the model's
        understate them (errors heavier than the spreads, or larger on the points
        that fix the tilt). Errors common to every frame (the same scatterers sharing
        the same cells) show in neither.
    seed : int
        Seed of the RANSAC draws.
    warn : bool
        Issue the warnings as :class:`GroundPlaneWarning` (in the result either way).

    Returns
    -------
    GroundPlane
        Inliers by RANSAC, then by the weighted fit (:data:`INLIER_SIGMAS`); the
        covariance scaled by the reduced chi-square when above one, then by
        :attr:`GroundPlane.spread_scale`. Without enough points on the plane the
        tilt is NaN.
    """
    p = finite_array("points", points, ndim=2)
    if p.shape[1] != 3:
        raise ValueError(f"points must have shape [point, 3], got {p.shape}")
    cov = finite_array("covariance", covariance, shape=(p.shape[0], 3, 3))
    if groups is not None:
        groups = np.asarray(groups)
        if groups.shape != (p.shape[0],) or not np.issubdtype(groups.dtype, np.integer):
            raise ValueError(f"groups must be integers of shape [{p.shape[0]}] (one per "
                             f"point), got {groups.dtype} of shape {groups.shape}")
    notes: list[str] = []
    nan2 = np.full(2, np.nan)
    if p.shape[0] < MIN_GROUND_POINTS:
        notes.append(f"ground plane: {p.shape[0]} ground point(s) in the range window, at "
                     f"least {MIN_GROUND_POINTS} needed; no tilt from the ground (the ground "
                     f"may lie outside the window, or its cells hold more scatterers than a "
                     f"few plane waves separate: dense clutter)")
        out = GroundPlane(nan2, np.full((2, 2), np.nan), float("nan"), np.full(3, np.nan),
                          p.shape[0], 0, float("nan"), float("nan"), tuple(notes))
    else:
        inl = _ransac(p, cov, np.random.default_rng(seed))
        x = np.zeros(3)
        c3 = np.full((3, 3), np.nan)
        chi2 = rms = float("nan")
        for _ in range(RESELECT_PASSES):    # fit, re-select at the fit, until it settles
            if inl.sum() < MIN_GROUND_POINTS:
                break
            x, c3, z = _weighted_fit(p[inl], cov[inl], x[:2])
            rot = Rotation.from_rotvec([x[0], x[1], 0.0]).as_matrix()
            var_all = np.einsum("j,njk,k->n", rot[2], cov, rot[2])
            z_all = ((p @ rot.T)[:, 2] - x[2]) / np.sqrt(var_all)
            chi2 = float(np.sum(z ** 2) / max(inl.sum() - 3, 1))
            rms = float(np.sqrt(np.mean((z * np.sqrt(var_all[inl])) ** 2)))
            new = np.abs(z_all) <= INLIER_SIGMAS * max(1.0, np.sqrt(chi2))
            if np.array_equal(new, inl):
                break
            inl = new
        n_in = int(inl.sum())
        if n_in < MIN_GROUND_POINTS or not np.isfinite(chi2):
            notes.append(f"ground plane: {n_in} of {p.shape[0]} points on one plane, at least "
                         f"{MIN_GROUND_POINTS} needed; no tilt from the ground")
            x[:2], c3 = np.nan, np.full((3, 3), np.nan)
        else:
            c3 = c3 * max(chi2, 1.0)
            if n_in < MIN_INLIER_FRACTION * p.shape[0]:
                notes.append(f"ground plane: bad fit, {n_in} of {p.shape[0]} points on the "
                             f"plane (fewer than {MIN_INLIER_FRACTION:.0%}): the ground is "
                             f"rough, not flat or not the main return; no tilt from the ground")
            elif not np.hypot(*x[:2]) <= MAX_NORMAL_ANGLE:
                notes.append(f"ground plane: the plane fitted is tilted by "
                             f"{np.rad2deg(np.hypot(*x[:2])):.1f} deg, more than "
                             f"{np.rad2deg(MAX_NORMAL_ANGLE):.0f}: not the ground below; no "
                             f"tilt from the ground")
            elif chi2 > MAX_CHI2:
                notes.append(f"ground plane: bad fit, residual rms {rms:.3f} m (reduced "
                             f"chi-square {chi2:.1f} > {MAX_CHI2:g}): the ground is not flat "
                             f"or not the main return; no tilt from the ground")
        normal = Rotation.from_rotvec([x[0], x[1], 0.0]).as_matrix()[2] if np.all(
            np.isfinite(x[:2])) else np.full(3, np.nan)
        out = GroundPlane(x[:2].copy(), c3[:2, :2].copy(), float(x[2]), normal, p.shape[0],
                          n_in, chi2, rms, tuple(notes))
        if groups is not None and np.all(np.isfinite(out.tilt)):
            scale, ran = _jackknife_scale(p, cov, groups, out.tilt_covariance, seed)
            out = replace(out, tilt_covariance=out.tilt_covariance * scale,
                          spread_scale=scale, jackknifed=ran)
        if np.any(out.tilt_sigma >= DEFAULT_TILT_SIGMA):
            out = replace(out, warnings=(*out.warnings, (
                f"ground plane: tilt spread {np.rad2deg(out.tilt_sigma.max()):.1f} deg, no "
                f"less than the prior's {np.rad2deg(DEFAULT_TILT_SIGMA):.0f} deg (the points "
                f"fix it no better than the prior); no tilt from the ground")))
    if warn:
        for text in out.warnings:
            warnings.warn(text, GroundPlaneWarning, stacklevel=2)
    return out


def _jackknife_scale(p: np.ndarray, cov: np.ndarray, groups: np.ndarray,
                     tilt_cov: np.ndarray, seed: int) -> tuple[float, bool]:
    """Least factor (>= 1) on ``tilt_cov`` ``[2, 2]`` that covers the delete-one-group
    jackknife covariance ``(K - 1) / K sum_k (t_k - t_mean)(t_k - t_mean)^T`` of the tilt:
    the largest generalised eigenvalue of the two, and whether it ran. 1 (not run) with
    fewer than :data:`MIN_JACKKNIFE_GROUPS` groups or when a fit without a group gives
    no tilt (the jackknife needs every one)."""
    labels = np.unique(groups)
    if labels.size < MIN_JACKKNIFE_GROUPS:
        return 1.0, False
    tilts = []
    for g in labels:
        keep = groups != g
        if keep.sum() < MIN_GROUND_POINTS:
            return 1.0, False
        t = fit_ground_plane(p[keep], cov[keep], seed=seed, warn=False).tilt
        if not np.all(np.isfinite(t)):
            return 1.0, False
        tilts.append(t)
    d = np.asarray(tilts) - np.mean(tilts, axis=0)
    jack = (labels.size - 1) / labels.size * (d.T @ d)
    return float(max(1.0, np.max(eigh(jack, tilt_cov, eigvals_only=True)))), True


def ground_points(rc, element_positions, motion: PlatformMotion, *, wavelength: float,
                  range_axis, gates, **options) -> tuple[np.ndarray, np.ndarray]:
    """Ground clutter points of a frame and their covariances.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        One range-compressed frame.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m].
    motion : PlatformMotion
        Motion of the frame (its attitude is the ``R_est`` of the points).
    wavelength : float
        [m].
    range_axis : array_like, shape ``[range]``
        Range of every bin [m].
    gates : array_like of int
        Range bins where the ground lies.
    **options
        For :func:`compensation.rigid_body_projection` (``channel_slot``,
        ``grid_shape``, ``method``).

    Returns
    -------
    (ndarray, ndarray)
        Points ``[point, 3]`` [m] (W as ``motion`` has it, from the radar) and
        their covariances ``[point, 3, 3]`` [m^2]: range to a bin's centre
        (spread ``bin / sqrt(12)``), azimuth :data:`compensation.calibration.DIRECTION_SIGMA`,
        elevation its measured spread (else the unresolved fan's).
    """
    r_axis = np.asarray(range_axis, dtype=float)
    gates = np.asarray(gates, dtype=int)
    if gates.size == 0:
        return np.zeros((0, 3)), np.zeros((0, 3, 3))
    found = detect_scatterers(rc, element_positions, motion, wavelength=wavelength,
                              range_axis=r_axis, azimuth=GROUND_AZIMUTH,
                              elevation=GROUND_AZIMUTH, range_gates=gates,
                              count=GROUND_COUNT, dynamic_range_db=GROUND_DYNAMIC_RANGE_DB,
                              **options)
    if not found:
        return np.zeros((0, 3)), np.zeros((0, 3, 3))
    r = r_axis[[s.gate for s in found]]
    az = np.array([s.azimuth for s in found])
    el = np.array([s.elevation for s in found])
    se = np.array([UNRESOLVED_DIRECTION_SIGMA if s.elevation_sigma is None
                   else max(s.elevation_sigma, GROUND_ANGLE_SIGMA) for s in found])
    bin_m = float(np.median(np.diff(r_axis))) if r_axis.size > 1 else 0.0
    return r[:, None] * direction(az, el), point_covariance(
        r, az, el, bin_m / np.sqrt(12.0), max(DIRECTION_SIGMA, GROUND_ANGLE_SIGMA), se)


def dense_points(rc, element_positions, motion: PlatformMotion, *, wavelength: float,
                 range_axis, gates, channel_slot=None) -> tuple[np.ndarray, np.ndarray]:
    """Ground points of a frame from every ground cell's plane waves and their covariances.

    :func:`compensation.ground_dense.dense_ground_directions` (its parameters), each
    point ``r u`` with :data:`compensation.ground_dense.DENSE_RANGE_SIGMA_CELLS` in range
    and :data:`compensation.ground_dense.DENSE_ANGLE_SIGMA` in azimuth and elevation.

    Returns
    -------
    (ndarray, ndarray)
        Points ``[point, 3]`` [m] (W as ``motion`` has it, from the radar) and their
        covariances ``[point, 3, 3]`` [m^2].
    """
    r_axis = np.asarray(range_axis, dtype=float)
    r, u = dense_ground_directions(rc, element_positions, motion, wavelength=wavelength,
                                   range_axis=r_axis, gates=gates, channel_slot=channel_slot)
    return _dense_covariance(r, u, r_axis)


def _dense_covariance(r: np.ndarray, u: np.ndarray, r_axis: np.ndarray):
    """Points ``r u`` ``[point, 3]`` and their covariances ``[point, 3, 3]`` with the dense
    points' spreads (range cells ``r_axis`` [m])."""
    if r.size == 0:
        return np.zeros((0, 3)), np.zeros((0, 3, 3))
    az, el = np.arctan2(u[:, 0], u[:, 2]), np.arcsin(np.clip(u[:, 1], -1.0, 1.0))
    cell = float(r_axis[1] - r_axis[0])
    return r[:, None] * u, point_covariance(r, az, el, DENSE_RANGE_SIGMA_CELLS * cell,
                                            DENSE_ANGLE_SIGMA, DENSE_ANGLE_SIGMA)


#: Most frames (spread over the record) whose dense ground points are fitted: their
#: receiver noise and interpolation errors average, the mixing of scatterers that share
#: cells they repeat (each 0.5 s of CPU; docs/self_calibration.md).
DENSE_FRAMES = 6
#: Azimuth sectors about the nadir of the spatial jackknife (a hovering platform sees
#: the same scatterers in every frame, so frames share their errors; sectors do not).
JACKKNIFE_SECTORS = 8


def sector_groups(points) -> np.ndarray:
    """Sector ``[point]`` (0 .. :data:`JACKKNIFE_SECTORS` - 1) of every point's bearing
    ``atan2(p_e, p_n)`` about the nadir: the groups of the spatial jackknife."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    bearing = np.arctan2(p[:, 1], p[:, 0]) + np.pi
    return np.minimum((bearing / (2 * np.pi) * JACKKNIFE_SECTORS).astype(int),
                      JACKKNIFE_SECTORS - 1)


def ground_tilt(rcs, element_positions, motions, *, wavelength: float, range_axis, gates,
                gyro_bias_sigma: float = 0.0, warn: bool = True, mounting=None,
                **options) -> GroundPlane:
    """Roll and pitch correction of a record's initial attitude from the ground in ``gates``.

    The ground points of every frame (a down-looking radar's: :func:`dense_points` of
    up to :data:`DENSE_FRAMES` frames spread over the record, their covariances times
    the frames' number (a hover repeats one look), every azimuth sector about the
    nadir a group of the jackknife, :func:`sector_groups`; a mounted
    radar's: :func:`ground_points`, every frame a group), each frame formed with its
    own motion of the one integration, so all are in W as the initial attitude has
    it, fitted together (:func:`fit_ground_plane`; module docstring: the assumption
    of level flat ground); the jackknife widens the stated spread to the one the
    groups show. A hovering platform moves far less than a range cell over a
    record, so the same scatterers share the same cells in every frame: with frames
    as groups that part of the error shows in no spread. Where the range cells give
    fewer than :data:`compensation.ground_dbs.DOPPLER_BELOW_POINTS` points a frame, or
    no usable plane (dense clutter: more scatterers a cell than three plane waves),
    every picked frame's range-Doppler cells add their points
    (:func:`compensation.ground_dbs.doppler_ground_directions`, less those of
    scatterers the range cells found), each frame's another look turned by its middle
    loop's attitude, and the fit is of them all (:attr:`GroundPlane.source`). The
    gyro bias turns the later frames'
    attitude: its spread over the frames' mean time since the first chirp is added
    to the tilt's. The dense points are kept with the attitudes that turned them
    (:attr:`GroundPlane.looks`), to be fitted again with another integration
    (:func:`compensation.ground_refit.refit_ground`).

    Parameters
    ----------
    rcs : sequence of ndarray, each shape ``[chirp, channel, range]``
        Range-compressed frames.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m].
    motions : sequence of PlatformMotion
        Motion of every frame (one integration; its attitude at the first chirp is
        the ``R_est`` the tilt corrects).
    wavelength, range_axis, gates, **options
        As :func:`ground_points` (the dense points take ``channel_slot`` of ``options``).
    gyro_bias_sigma : float
        Spread of the gyro bias left in ``motions`` [rad/s].
    warn : bool
        Issue the warnings (:class:`GroundPlaneWarning`).
    mounting : array_like ``[3, 3]``, optional
        ``R_BA`` of a radar that does not look down: every frame's points are found
        with the motion seen from its nominal frame N
        (:func:`compensation.mounting.radar_frame_motion`: the search grid and the
        array's axes are the radar's), then turned into W (``R_BA p``,
        ``R_BA C R_BA^T``) and fitted there, where the ground is level.

    Returns
    -------
    GroundPlane
    """
    if len(rcs) != len(motions) or len(rcs) < 1:
        raise ValueError(f"rcs holds {len(rcs)} frames and motions {len(motions)}; expected "
                         f"the same number, at least one")
    rot = None if mounting is None else mounting_rotation(mounting)
    if rot is None:         # the down-looking radar: every ground cell's plane waves
        pick = np.unique(np.linspace(0, len(rcs) - 1, min(DENSE_FRAMES, len(rcs))).round()
                         ).astype(int)
        slots = options.get("channel_slot")
        pose = (1 if slots is None else int(np.max(slots)) + 1) * SNAPSHOT_CHIRP
        # a hover repeats one look: the same scatterers mix in the same cells in every
        # frame, so the frames together hold one frame's information on that error
        looks = []
        for k in pick:
            p, c = dense_points(rcs[k], element_positions, motions[k], wavelength=wavelength,
                                range_axis=range_axis, gates=gates, channel_slot=slots)
            looks.append(GroundLook(int(k), pose, np.asarray(motions[k].attitude[pose]), p,
                                    c * pick.size))
        fit = fit_looks(tuple(looks), motions, gyro_bias_sigma=gyro_bias_sigma,
                        range_axis=range_axis, gates=gates)
        if not fit.usable or fit.points < DOPPLER_BELOW_POINTS * pick.size:
            # dense clutter: the range-Doppler cells hold fewer scatterers than the range
            # cells; a scatterer found in both counts once
            r_axis = np.asarray(range_axis, dtype=float)
            for k, look in zip(pick, tuple(looks), strict=True):
                r, u, at = doppler_ground_directions(
                    rcs[k], element_positions, motions[k], wavelength=wavelength,
                    range_axis=r_axis, gates=gates, channel_slot=slots)
                p, c = _dense_covariance(r, u, r_axis)
                new = unseen(p, look.points, float(r_axis[1] - r_axis[0]))
                looks.append(GroundLook(int(k), at, np.asarray(motions[k].attitude[at]),
                                        p[new], c[new] * pick.size))
            fit = replace(fit_looks(tuple(looks), motions, gyro_bias_sigma=gyro_bias_sigma,
                                    range_axis=range_axis, gates=gates),
                          source="range+doppler")
            if np.all(np.isfinite(fit.tilt)) and not fit.jackknifed:
                fit = replace(fit, warnings=(*fit.warnings, (
                    f"ground plane: {fit.points} points of dense clutter, too few for the "
                    f"jackknife over azimuth sectors to check their spread; no tilt from "
                    f"the ground")))
    else:
        found = [ground_points(rc, element_positions, radar_frame_motion(m, rot),
                               wavelength=wavelength, range_axis=range_axis, gates=gates,
                               **options) for rc, m in zip(rcs, motions, strict=True)]
        found = [world_directions(p, rot, c) for p, c in found]
        points = np.concatenate([p for p, _ in found])
        groups = np.concatenate([np.full(len(p), k) for k, (p, _) in enumerate(found)])
        fit = _finish(fit_ground_plane(points, np.concatenate([c for _, c in found]),
                                       groups=groups.astype(int), warn=False),
                      motions, gyro_bias_sigma, range_axis, gates)
    if warn:
        for text in fit.warnings:
            warnings.warn(text, GroundPlaneWarning, stacklevel=2)
    return fit


def _finish(fit: GroundPlane, motions, gyro_bias_sigma: float, range_axis=None,
            gates=None) -> GroundPlane:
    """The fit with its window's note when empty (``range_axis``, ``gates``) and the gyro
    bias's turn over the frames' mean time since the first chirp added to its covariance."""
    if fit.points == 0:
        r_axis = np.zeros(0) if range_axis is None else np.asarray(range_axis, dtype=float)
        g = np.zeros(0, dtype=int) if gates is None else np.asarray(gates, dtype=int)
        where = (f"{r_axis[g].min():.2f}-{r_axis[g].max():.2f} m" if g.size
                 else "(no cell)")
        fit = replace(fit, warnings=(f"ground plane: no ground return in the range window "
                                     f"{where}; no tilt from the ground",))
    t0 = float(motions[0].time[0])
    span = float(np.mean([np.mean(m.time) for m in motions]) - t0)
    return replace(fit, tilt_covariance=fit.tilt_covariance
                   + np.eye(2) * (float(gyro_bias_sigma) * span) ** 2)


def fit_looks(looks, motions, *, gyro_bias_sigma: float = 0.0, range_axis=None,
              gates=None) -> GroundPlane:
    """Plane fit of the ground points of looks and the roll and pitch correction it gives.

    Parameters
    ----------
    looks : sequence of compensation.ground_looks.GroundLook
        Every frame's points in W and their covariances.
    motions : sequence of PlatformMotion
        The record's motion (its first chirp the time the tilt is of).
    gyro_bias_sigma : float
        Spread of the gyro bias left in the attitudes of the looks [rad/s]: its turn
        over the frames' mean time since the first chirp is added to the covariance.
    range_axis, gates : array_like, optional
        The ground's range window (named in the warning when no point was found).

    Returns
    -------
    GroundPlane
        :func:`fit_ground_plane` of every look's points, every azimuth sector about
        the nadir a group of the jackknife (:func:`sector_groups`); the looks kept in
        :attr:`GroundPlane.looks`. Not warned (its warnings in the result).
    """
    looks = tuple(looks)
    points = np.concatenate([k.points for k in looks])
    fit = fit_ground_plane(points, np.concatenate([k.covariance for k in looks]),
                           groups=sector_groups(points), warn=False)
    return replace(_finish(fit, motions, gyro_bias_sigma, range_axis, gates), looks=looks)


#: Mahalanobis distance of the ground's tilt from a given attitude above which the two
#: are said to disagree (chi-square of 2 degrees of freedom: 11.8 is its 99.73 % point,
#: three sigma).
DISAGREE_CHI2 = 11.8


def ground_check(fit: GroundPlane) -> tuple[str, ...]:
    """Warnings when the ground's tilt contradicts the attitude the points were formed with.

    Parameters
    ----------
    fit : GroundPlane
        The fit with the given attitude (:func:`ground_tilt`): its tilt is the
        correction the ground asks of that attitude.

    Returns
    -------
    tuple of str
        One warning when the correction is beyond :data:`DISAGREE_CHI2` of its
        covariance (a wrong attitude, or a sloped ground); none otherwise or
        without a usable fit.
    """
    if not fit.usable:
        return ()
    d2 = float(fit.tilt @ np.linalg.solve(fit.tilt_covariance, fit.tilt))
    if d2 <= DISAGREE_CHI2:
        return ()
    n, e = np.rad2deg(fit.tilt)
    sn, se = np.rad2deg(fit.tilt_sigma)
    return (f"ground plane: the given attitude and the ground disagree by tilt (N, E) "
            f"{n:.2f} +- {sn:.2f}, {e:.2f} +- {se:.2f} deg (beyond three sigma): a wrong "
            f"attitude, or the ground in view is not level",)
