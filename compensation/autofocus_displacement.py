"""Direction-dependent autofocus: the residual platform displacement vector per chirp.

:mod:`compensation.autofocus` estimates one phase per chirp common to all
cells; a residual platform displacement ``d_n`` gives a scatterer in direction
``u`` the phase

    phi_n(u) = 2 k d_n . u,     k = 2 pi / lambda,

so the common phase leaves ``2 k d_n . (u - u0)`` away from the cells' mean
direction ``u0``. :func:`estimate_displacement` estimates the vector ``d_n``:

1. cells are selected as in :func:`compensation.autofocus.estimate_phase_error`
   (stationary local maxima ``min_snr_db`` above the noise, the ``max_cells``
   strongest), each with the direction ``u_c`` of its beam; cells
   ``sidelobe_db`` or more below the strongest of their range gate are
   dropped (a sidelobe carries its scatterer's phase at another beam's
   direction; a weaker scatterer in the same gate goes with them;
   :mod:`compensation.sidelobes` sets it from the array's pattern);
2. each cell's Doppler peak is shifted to zero and its unwrapped phase
   history ``psi_c(n)`` is taken relative to its own constant and linear trend
   (a cell's constant is its position, its linear phase a velocity: the
   velocity is left to the ego-velocity fit, :mod:`compensation.ego_velocity`,
   and the IMU chain; it is not estimated here);
3. per chirp, weighted least squares ``psi_c(n) = 2 k u_c . d_n`` with the
   weights ``1 / var_c``, ``var_c = s2 / (2 |g_c|^2)`` the thermal phase
   variance of the cell, and a zero-mean Gaussian prior of standard deviation
   ``prior_m`` per component (what the directions do not constrain stays at
   the prior, zero): ``d_n = C 2 k U^T W psi_n``, ``C = (F + I / prior^2)^-1``,
   ``F = 4 k^2 U^T W U`` the Fisher matrix of the directions;
4. the cells are corrected by their own ``2 k u_c . d_n`` and steps 2-3 repeat
   until the update falls below :data:`CONVERGENCE_RAD` or after ``iterations``.

The beams are then corrected by ``exp(-j 2 k d_n . u_beam)``, each beam at its
own direction.

What it cannot observe
----------------------
* The constant and linear trend of ``d`` in slow time (the scatterers'
  positions and a velocity); removed from the estimate and left in the data.
* Components of ``d`` the directions do not span: with directions spread by
  a few degrees the cross-range components are weakly observed (Fisher
  eigenvalue ``~ 4 k^2 sum w_c sin^2(spread)``). The components whose
  posterior sigma exceeds :data:`UNOBSERVED_RATIO` times the prior are named
  in :attr:`DisplacementFocus.unobserved` (the eigen-directions of ``F``) and
  held near zero by the prior.
* Along an axis the virtual array has no extent (``array_spans``: an xWR16xx's
  line of elements has none vertically) every elevation gives the same beam, so
  the cells' elevations are not measured: that component of ``d`` (and of the
  velocity) is held at zero and named.
* Degenerate directions (fewer than :data:`MIN_CELLS` cells, or their
  directions spanning fewer than two dimensions, eigenvalue ratio below
  :data:`DEGENERATE_RATIO`): the vector is not estimated; the common phase
  of :func:`compensation.autofocus.estimate_phase_error` is used instead, with
  a warning saying so.
* A scatterer's far sidelobes, in beams away from its direction, are corrected
  at the beams' directions, not at the scatterer's.
* TDM: the beams sum every slot, so the estimate is stamped with the mean slot
  time of each chirp (the spread over one chirp's slots, ``2 k |d'| dT``, is
  not corrected in the beams), as in :mod:`compensation.autofocus`; a
  per-channel cube is corrected at each slot's own time in one direction
  (:meth:`DisplacementFocus.phase_at`).

Uncertainty: the posterior covariance ``C`` scaled by the reduced chi-square
of the fit when above 1 (model error: a cell's beam not exactly at its
scatterer, clutter in the cell), propagated through the trend removal; per
chirp and component (:attr:`DisplacementFocus.sigma`, ``[chirp, 3]`` in the
frame of the beam directions).
"""

from __future__ import annotations

import warnings as _warnings
from dataclasses import dataclass, replace

import numpy as np

from ._checks import finite_array, positive
from .autofocus import (
    CONVERGENCE_RAD,
    MIN_CHIRPS,
    Autofocus,
    _candidates,
    _detrend,
    _detrend_basis,
    _noise_per_bin,
    _propagate,
    autofocus_beams,
    check_selection,
)
from .cell_directions import beam_offset_doppler
from .geometry import direction, grid_directions
from .guards import CompensationWarning
from .projection import BeamCube
from .sidelobes import SIDELOBE_DB, main_lobe_cells

__all__ = ["DisplacementFocus", "estimate_displacement", "correct_displacement",
           "autofocus_displacement", "SIDELOBE_DB", "DEGENERATE_RATIO", "UNOBSERVED_RATIO",
           "MIN_CELLS", "PRIOR_M", "PRIOR_MPS"]

#: Directions are degenerate when the second-largest Fisher eigenvalue is below this
#: share of the largest (they span one dimension only) [1].
DEGENERATE_RATIO = 1e-6
#: A component is named unobserved when its posterior sigma exceeds this share of the
#: prior's [1].
UNOBSERVED_RATIO = 0.5
#: Fewest cells for a vector estimate (three components and their spread).
MIN_CELLS = 4
#: Default prior standard deviation of each displacement component [m] (the rotor band's
#: residual displacement is sub-millimetre).
PRIOR_M = 1e-3
#: Default prior standard deviation of each velocity-error component [m/s]
#: (``doppler="stationary"``).
PRIOR_MPS = 0.1


@dataclass(frozen=True, eq=False)
class DisplacementFocus:
    """The residual per-chirp displacement estimated by :func:`estimate_displacement`.

    Attributes
    ----------
    displacement : ndarray, shape ``[chirp, 3]``
        Residual platform displacement ``d_n`` [m] in the frame of the beam
        directions (``x`` azimuth, ``y`` elevation, ``z`` boresight), constant
        and linear trend removed; the phase at direction ``u`` is
        ``4 pi / lambda d_n . u``. Zero when the common phase was used.
    sigma : ndarray, shape ``[chirp, 3]``
        One-sigma uncertainty of each component [m] (NaN when not estimated).
    time : ndarray, shape ``[chirp]``
        Time of each estimate [s]: the chirp time, or the mean slot time (TDM).
    wavelength : float
        Wavelength [m].
    cells : int
        Cells used; 0 when none qualified.
    iterations : int
        Iterations run.
    fisher_eigenvalues : ndarray, shape ``[3]``
        Eigenvalues of the Fisher matrix of the directions [1 / m^2], descending.
    fisher_axes : ndarray, shape ``[3, 3]``
        Their eigen-directions, one per row.
    unobserved : tuple of str
        Eigen-directions held at the prior, ``"d along (x, y, z)"``.
    prior_m : float
        The prior standard deviation of each component [m].
    common : Autofocus or None
        The common-phase estimate used instead when the directions were degenerate.
    warnings : tuple of str
        ``"autofocus: ..."`` texts.
    velocity : ndarray, shape ``[3]``, or None
        With ``doppler="stationary"``: the platform velocity error [m/s] the
        stationary cells showed (the phase ``4 pi / lambda v . u t``), included
        in :attr:`displacement` as its linear part; None otherwise.
    velocity_sigma : ndarray, shape ``[3]``, or None
        Its one-sigma uncertainty per component [m/s].
    """

    displacement: np.ndarray
    sigma: np.ndarray
    time: np.ndarray
    wavelength: float
    cells: int
    iterations: int
    fisher_eigenvalues: np.ndarray
    fisher_axes: np.ndarray
    unobserved: tuple = ()
    prior_m: float = PRIOR_M
    common: Autofocus | None = None
    warnings: tuple = ()
    velocity: np.ndarray | None = None
    velocity_sigma: np.ndarray | None = None

    def phase(self, u) -> np.ndarray:
        """Phase ``4 pi / lambda d_n . u`` [rad] at directions ``u [..., 3]``: ``[chirp, ...]``."""
        u = np.asarray(u, float)
        if self.common is not None:
            return np.broadcast_to(self.common.phase.reshape((-1,) + (1,) * (u.ndim - 1)),
                                   (self.time.size,) + u.shape[:-1])
        return 4 * np.pi / self.wavelength * np.tensordot(self.displacement, u, axes=([1], [-1]))

    def displacement_at(self, times) -> np.ndarray:
        """``d`` at ``times`` [s] of any shape (cubic spline through :attr:`displacement`):
        ``[*times.shape, 3]`` [m], e.g. each TDM slot's time ``[chirp, slot]``."""
        from scipy.interpolate import CubicSpline

        t = finite_array("times", times)
        return CubicSpline(self.time, self.displacement, axis=0, extrapolate=True)(t)

    def phase_at(self, times, u) -> np.ndarray:
        """Phase [rad] at ``times`` [s] (any shape, e.g. ``[chirp, slot]``) in one
        direction ``u [3]``: a per-channel TDM cube is corrected at each slot's own time."""
        u = np.asarray(u, float)
        if u.shape != (3,):
            raise ValueError(f"u must be one unit vector of shape (3,), got {u.shape}")
        if self.common is not None:
            return self.common.phase_at(times)
        return 4 * np.pi / self.wavelength * (self.displacement_at(times) @ u)

    def report(self) -> dict:
        """Plain-number summary (SI units) for output attributes and JSON."""
        if self.common is not None:
            return {**self.common.report(), "mode": "displacement", "fallback": "phase",
                    "warnings": list(self.warnings)}
        est = self.cells > 0
        n = self.time.size
        dt = float(np.mean(np.diff(self.time)))
        rms_d = np.sqrt(np.mean(self.displacement ** 2, axis=0))
        ph = 4 * np.pi / self.wavelength * self.displacement[:, 2]
        return {"mode": "displacement", "rms_phase_rad": float(np.sqrt(np.mean(ph ** 2))),
                "sigma_rad": (float(4 * np.pi / self.wavelength * np.sqrt(np.mean(
                    self.sigma[:, 2] ** 2))) if est else None),
                "band_hz": [1.0 / (n * dt), 1.0 / (2.0 * dt)], "cells": int(self.cells),
                "iterations": int(self.iterations),
                "rms_displacement_m": [float(v) for v in rms_d],
                "sigma_displacement_m": ([float(v) for v in np.sqrt(np.mean(
                    self.sigma ** 2, axis=0))] if est else None),
                "fisher_eigenvalues": [float(v) for v in self.fisher_eigenvalues],
                "unobserved": list(self.unobserved), "prior_m": self.prior_m,
                **({} if self.velocity is None else {
                    "velocity_mps": [float(v) for v in self.velocity],
                    "velocity_sigma_mps": [float(v) for v in self.velocity_sigma],
                    "range_rate_mps": float(self.velocity[2]),
                    "range_rate_sigma_mps": float(self.velocity_sigma[2])}),
                "warnings": list(self.warnings)}


def _cell_phases(g: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Each cell's unwrapped phase ``[chirp, cell]`` less its Doppler peak, constant and trend."""
    n = g.shape[0]
    peak = np.argmax(np.abs(np.fft.fft(g, axis=0)), axis=0)
    h = g * np.exp(-2j * np.pi * np.outer(np.arange(n), peak) / n)
    psi = np.unwrap(np.angle(h * np.conj(h[n // 2])[None, :]), axis=0)
    return _detrend(psi, q)


def _fallback(beams, slot_times, options, text, lam, t, cells, it, ev, axes, prior):
    if cells:                       # none: the common estimate's own warning says so
        _warnings.warn(text, CompensationWarning, stacklevel=3)
    _, common = autofocus_beams(beams, slot_times=slot_times, **options)
    n = t.size
    return DisplacementFocus(np.zeros((n, 3)), np.full((n, 3), np.nan), t, lam, cells, it,
                             ev, axes, (), prior, common,
                             (text, *common.warnings) if cells else common.warnings)


def estimate_displacement(beams: BeamCube, *, slot_times=None, max_cells: int = 32,
                          min_snr_db: float = 20.0, stationary_bins: float = 2.0,
                          iterations: int = 8, prior_m: float = PRIOR_M,
                          doppler: str = "keep", prior_mps: float = PRIOR_MPS,
                          sidelobe_db: float = SIDELOBE_DB, array_spans=(True, True),
                          radar_velocity=None) -> DisplacementFocus:
    """Estimate the residual per-chirp displacement vector from the beams' stationary cells.

    Parameters
    ----------
    beams : BeamCube
        Beams after the IMU-driven chain, ``data [chirp, range, azimuth, elevation]``.
    slot_times : array_like, shape ``[chirp, slot]``, optional
        TDM slot start times [s]; the estimate is stamped with their mean.
    max_cells, min_snr_db, stationary_bins : see :func:`compensation.autofocus.estimate_phase_error`
    iterations : int
        Most iterations (estimate, correct the cells, estimate again).
    prior_m : float
        Prior standard deviation of each displacement component [m].
    doppler : {"keep", "stationary"}
        ``"keep"``: each cell's linear phase is left as is (a velocity, the
        ego-velocity fit's). ``"stationary"``: the selected cells are taken as
        stationary, so their linear phases ``2 k u_c . v T n`` give a platform
        velocity error vector ``v`` (weighted least squares over the cells,
        prior ``prior_mps`` per component), which joins the displacement as
        its linear part (:attr:`DisplacementFocus.velocity`).
    prior_mps : float
        Prior standard deviation of each velocity component [m/s].
    sidelobe_db : float
        Cells this far [dB] or more below the strongest of their range gate are
        dropped (:func:`compensation.sidelobes.sidelobe_margin_db` of the array).
    array_spans : (bool, bool)
        Whether the virtual array has any extent along the azimuth axis ``x`` and the
        elevation axis ``y``. Along an axis it lacks (a line of elements), the beams
        are the same at every angle of that axis, so a cell's direction cosine there
        is not measured: its component of ``d`` (and of ``v``) is held at the prior,
        zero, and named unobserved.
    radar_velocity : array_like, shape ``[3]``, optional
        Radar phase-centre velocity the beams were compensated with, mean over the
        frame, in the beams' frame [m/s]. With ``doppler="stationary"`` a cell's beam
        misses its scatterer by ``u_s - u_c`` (a grid step at most), and the motion
        removed along the beam leaves it the Doppler ``2 k (u_s - u_c) . v`` (10 mm/s
        at 0.3 m/s and 1.9 deg): each cell's direction ``u_s`` is refined from its
        neighbouring beams (:func:`compensation.cell_directions.refined_directions`)
        and that Doppler taken off its slope before the velocity fit. Left out: the
        slopes as measured (the fit then takes it for a velocity error).

    Returns
    -------
    DisplacementFocus
        With ``common`` set (and a warning) when the directions are degenerate
        or no cell qualified.

    Raises
    ------
    ValueError
        Not a BeamCube, fewer than :data:`MIN_CHIRPS` chirps, non-finite data, bad options.
    """
    if not isinstance(beams, BeamCube):
        raise ValueError(f"beams must be a compensation.BeamCube, got {type(beams)!r}")
    x = beams.data.reshape(beams.data.shape[0], -1)
    cell_shape = beams.data.shape[1:]
    n = x.shape[0]
    if n < MIN_CHIRPS:
        raise ValueError(f"beams must hold at least {MIN_CHIRPS} chirps, got {n}")
    if not np.all(np.isfinite(x)):
        raise ValueError("beams must be finite; they hold NaN or infinite values")
    t = np.asarray(beams.chirp_time, float)
    if slot_times is not None:
        st = finite_array("slot_times", slot_times, ndim=2)
        if st.shape[0] != n:
            raise ValueError(f"slot_times must have shape [chirp={n}, slot], got {st.shape}")
        t = st.mean(axis=1)
    snr, stationary_bins = check_selection(max_cells, iterations, min_snr_db, stationary_bins)
    prior = positive("prior_m", prior_m)
    prior_v = positive("prior_mps", prior_mps)
    if doppler not in ("keep", "stationary"):
        raise ValueError(f"doppler must be 'keep' or 'stationary', got {doppler!r}")
    margin = positive("sidelobe_db", sidelobe_db)
    options = dict(max_cells=max_cells, min_snr_db=snr, stationary_bins=stationary_bins,
                   iterations=iterations, doppler=doppler, sidelobe_db=margin)
    lam = float(beams.wavelength)
    k2 = 4 * np.pi / lam                                                 # 2 k [rad/m]

    noise = _noise_per_bin(x)
    sel = _candidates(x, cell_shape, noise * 10 ** (snr / 10), stationary_bins, max_cells)
    nan3 = np.full(3, np.nan)
    sel = main_lobe_cells(x, sel, cell_shape, margin)
    if sel.size < MIN_CELLS:
        return _fallback(beams, slot_times, options,
                         f"autofocus: {sel.size} stationary cells (fewer than {MIN_CELLS}); "
                         f"the displacement vector is not estimated, the common phase used",
                         lam, t, int(sel.size), 0, nan3, np.eye(3), prior)
    _, ia, ie = np.unravel_index(sel, cell_shape)
    u = direction(np.asarray(beams.azimuth)[ia], np.asarray(beams.elevation)[ie])  # [cell, 3]
    spans = np.asarray(array_spans, dtype=bool)
    if spans.shape != (2,):
        raise ValueError(f"array_spans must be two booleans (x, y), got {array_spans!r}")
    u[:, :2] *= spans                     # an axis the array lacks: the cell's angle unknown
    g = x[:, sel].astype(np.complex128)
    s2 = noise / n                                                       # per sample
    var_c = s2 / (2 * np.mean(np.abs(g) ** 2, axis=0))                   # [cell] rad^2
    w = 1.0 / var_c
    fisher = k2 ** 2 * (u.T * w) @ u                                     # [3, 3]
    ev, vec = np.linalg.eigh(fisher)
    ev, axes = ev[::-1], vec[:, ::-1].T
    if ev[1] < DEGENERATE_RATIO * ev[0]:
        return _fallback(beams, slot_times, options,
                         f"autofocus: the {sel.size} cells' directions span one dimension "
                         f"(Fisher eigenvalues {ev[0]:.3g}, {ev[1]:.3g}, {ev[2]:.3g}); the "
                         f"displacement vector is not estimated, the common phase used",
                         lam, t, int(sel.size), 0, ev, axes, prior)
    cov = np.linalg.inv(fisher + np.eye(3) / prior ** 2)
    gain = cov @ (u.T * w) * k2                                          # [3, cell]
    q = _detrend_basis(n)
    d = np.zeros((n, 3))
    it = 0
    while it < iterations:
        it += 1
        psi = _cell_phases(g * np.exp(-1j * k2 * (d @ u.T)), q)          # [chirp, cell]
        step = _detrend(psi @ gain.T, q)                                 # [chirp, 3]
        d += step
        if np.sqrt(np.mean((k2 * step @ u.T) ** 2)) < CONVERGENCE_RAD:
            break
    resid = _cell_phases(g * np.exp(-1j * k2 * (d @ u.T)), q)            # [chirp, cell]
    dof = max(n - 2, 1) * sel.size - 3 * max(n - 2, 1)
    chi2 = float(np.sum(resid ** 2 * w)) / max(dof, 1)
    var = np.diag(cov) * max(chi2, 1.0)                                  # [3]
    sigma = np.sqrt(np.stack([_propagate(np.full(n, v), q) for v in var], axis=1))
    post = np.sqrt(np.maximum(np.einsum("ij,jk,ik->i", axes, cov, axes), 0.0))
    unobs = tuple(f"d along ({a[0]:+.2f}, {a[1]:+.2f}, {a[2]:+.2f})"
                  for a, s in zip(axes, post, strict=True) if s > UNOBSERVED_RATIO * prior)
    vel = vel_sigma = None
    if doppler == "stationary":
        beside = 0.0 if radar_velocity is None else -k2 * beam_offset_doppler(
            beams, sel, u, finite_array("radar_velocity", radar_velocity, shape=(3,)), spans)
        vel, vel_cov = _velocity(g * np.exp(-1j * k2 * (d @ u.T)), u, w, k2, t, prior_v,
                                 beside)
        xc = t - t.mean()
        d = d + np.outer(xc, vel)
        sigma = np.sqrt(sigma ** 2 + np.outer(xc ** 2, np.diag(vel_cov)))
        vel_sigma = np.sqrt(np.diag(vel_cov))
    warns: tuple = ()
    if unobs:
        warns = (f"autofocus: the cells' directions do not constrain {', '.join(unobs)}; "
                 f"held at the prior 0 +- {prior:.3g} m",)
    return DisplacementFocus(d, sigma, t, lam, int(sel.size), it, ev, axes, unobs, prior,
                             None, warns, vel, vel_sigma)


def _velocity(g: np.ndarray, u: np.ndarray, w: np.ndarray, k2: float, t: np.ndarray,
              prior_v: float, beside=0.0) -> tuple[np.ndarray, np.ndarray]:
    """Velocity error ``[3]`` [m/s] and its covariance ``[3, 3]`` from stationary cells.

    Each cell's least-squares phase slope over time ``s_c = 2 k u_c . v``
    (unwrapped about its middle chirp: stationary cells step far below pi),
    thermal variance ``var_c / sum (t - tbar)^2``; weighted least squares with
    the prior, the covariance scaled by the reduced chi-square when above 1.
    """
    n, kc = g.shape
    psi = np.unwrap(np.angle(g * np.conj(g[n // 2])[None, :]), axis=0)
    xc = t - t.mean()
    slope = xc @ psi / (xc @ xc) - beside            # [cell] rad/s, less the beam's miss
    ws = w * (xc @ xc)                                                   # 1 / var(slope)
    cov = np.linalg.inv(k2 ** 2 * (u.T * ws) @ u + np.eye(3) / prior_v ** 2)
    v = cov @ (u.T * ws) @ slope * k2
    if kc > 3:
        chi2 = float(ws @ (slope - k2 * u @ v) ** 2) / (kc - 3)
        cov = cov * max(chi2, 1.0)
    return v, cov


def correct_displacement(beams: BeamCube, estimate: DisplacementFocus) -> BeamCube:
    """Remove the estimate: every beam times ``exp(-j 4 pi / lambda d_n . u_beam)``.

    Parameters
    ----------
    beams : BeamCube
        Beams to correct, ``data [chirp, range, azimuth, elevation]``.
    estimate : DisplacementFocus

    Returns
    -------
    BeamCube
        Same shape and dtype.
    """
    if not isinstance(estimate, DisplacementFocus):
        raise ValueError(f"estimate must be a DisplacementFocus, got {type(estimate)!r}")
    x = beams.data
    if x.shape[0] != estimate.time.size:
        raise ValueError(f"beams have {x.shape[0]} chirps, the estimate {estimate.time.size}")
    ub = grid_directions(beams.azimuth, beams.elevation)                # [azimuth, elevation, 3]
    ph = estimate.phase(ub)                                              # [chirp, az, el]
    c = np.exp(-1j * ph).astype(np.complex64 if x.dtype == np.complex64 else np.complex128)
    return replace(beams, data=(x * c[:, None]).astype(x.dtype, copy=False))


def autofocus_displacement(beams: BeamCube, *, slot_times=None, **options
                           ) -> tuple[BeamCube, DisplacementFocus]:
    """Estimate the residual displacement vector per chirp and correct every beam at its direction.

    Parameters
    ----------
    beams : BeamCube
    slot_times : array_like, shape ``[chirp, slot]``, optional
    **options
        Of :func:`estimate_displacement`.

    Returns
    -------
    (BeamCube, DisplacementFocus)
        The corrected beams (their ``warnings`` extended by the estimate's) and the estimate.
    """
    est = estimate_displacement(beams, slot_times=slot_times, **options)
    if est.cells == 0 or (est.common is not None and est.common.cells == 0):
        return beams.with_warnings(est.warnings), est
    return correct_displacement(beams, est).with_warnings(est.warnings), est
