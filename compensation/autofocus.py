"""Radar autofocus: the residual per-chirp platform phase, estimated from the radar data.

The IMU-driven chain (:func:`compensation.exact.rigid_body_projection` with the
pose of :func:`compensation.strapdown.integrate_imu`) removes the platform
motion the IMU log shows. A flight controller logs its IMU at 200-250 Hz, each
sample a boxcar average over its interval, so the 100-200 Hz rotor vibration
reaches the log attenuated by ``|sinc(f / rate)|`` and folded below
``rate / 2`` (docs/imu.md): the compensated beams keep a residual phase,
mostly the line-of-sight displacement at rotor frequencies,

    phi_n(u) = 2 k d_n . u,     k = 2 pi / lambda,

nearly the same for every cell near boresight. :func:`estimate_phase_error`
estimates its common part from the data (phase-gradient autofocus, PGA: Wahl
et al. 1994; Jakowatz et al. 1996, ch. 4):

1. cells (range x beam) are selected: local maxima of the slow-time power,
   stationary (their pulse-pair Doppler within ``stationary_bins`` of zero),
   at least ``min_snr_db`` above the noise in their Doppler peak, the
   ``max_cells`` strongest;
2. each cell's Doppler peak is circularly shifted to zero; the window is the
   whole Doppler band (a vibration puts its sidebands anywhere in it, and the
   narrowing window of SAR PGA would cut the paired echoes the estimate
   needs);
3. the phase gradient between successive chirps is the ML kernel
   ``dphi_n = arg sum_c conj(g_{n-1,c}) g_{n,c}``;
4. ``phi = cumsum(dphi)`` less its least-squares constant and linear trend
   corrects the cells, and steps 2-4 repeat until the update falls below
   :data:`CONVERGENCE_RAD` or after ``iterations``.

What it cannot observe
----------------------
* A constant phase and a linear phase in slow time: a constant is the
  scatterers' own phase, a linear phase is a Doppler shift, which the radar
  cannot tell from a velocity of the scene (an along-line-of-sight velocity
  error of the platform, ``v = lambda / (4 pi) dphi/dt``). Both are removed
  from the estimate and left in the data (the velocity is the IMU chain's, or
  the ego-velocity fit's, :mod:`compensation.ego_velocity`) unless the cells
  are declared stationary (``doppler="stationary"``): their common Doppler is
  then a platform velocity error along ``u0``, estimated and removed too.
* Direction dependence: one phase per chirp for all cells. The phase at a
  direction ``u`` differs from the estimate (the phase at the cells'
  power-weighted direction ``u0``) by ``2 k d_n . (u - u0)``; for a
  displacement along boresight that is ``2 k d_z (cos theta - cos theta0)``,
  second order in the angle, for a lateral one first order. Over wide beams
  only the common part is corrected.
* Frequencies above half the chirp rate (one phase per chirp; they alias) and
  everything below the Doppler resolution ``1 / (N T)`` (the linear trend
  absorbs it). The band is ``(1 / (N T), 1 / (2 T))``, :attr:`Autofocus.band`.

TDM MIMO: the beams of a TDM frame sum every slot's channels, each compensated
with the pose of its own ramp, so the residual seen in a beam at chirp ``n`` is
the mean of the phases at the slot times, the phase at the mean slot time to
first order. The estimate is stamped with those times (``slot_times``) and
corrects every chirp's beams; a per-channel cube is corrected per slot, the
phase evaluated at each slot's time (:func:`correct_phase` with ``times``
``[chirp, channel]``; cubic spline, exact for vibration well below half the
chirp rate). The spread of the phase over the slots of one chirp,
``2 k |d'| dT``, is not corrected.

Uncertainty (:attr:`Autofocus.sigma`, per chirp): the error of the estimate
at a chirp is the power-weighted mean of the cells' phase errors there (the
gradients' errors telescope in the sum); its variance is the larger of the
thermal value ``s2 / (2 sum_c |g_c|^2)`` (``s2`` the noise power per sample,
from the median of the Doppler spectra) and the weighted spread of the cells'
phases about the common one (each cell's own constant and linear phase
removed; this includes the direction-dependent part), propagated through the
trend removal. The cells are taken as independent.
"""

from __future__ import annotations

import warnings as _warnings
from dataclasses import dataclass, replace

import numpy as np
import scipy.fft

from ._checks import finite_array, positive
from .guards import CompensationWarning
from .projection import BeamCube

__all__ = ["Autofocus", "autofocus_beams", "estimate_phase_error", "correct_phase",
           "CONVERGENCE_RAD", "MIN_CHIRPS"]

#: Iterations stop when the rms update of the phase falls below this [rad].
CONVERGENCE_RAD = 1e-4
#: Fewest chirps an estimate needs (a trend of 2 parameters, then a shape).
MIN_CHIRPS = 8
#: Cells per block when the cube is scanned for scatterers (bounds the memory of
#: the Doppler FFT to ``chirp x BLOCK_CELLS`` complex64 values).
BLOCK_CELLS = 1 << 15
#: Cells of the sample of the cube from which the noise floor is estimated.
NOISE_SAMPLE_CELLS = 4096


@dataclass(frozen=True, eq=False)
class Autofocus:
    """The residual per-chirp phase estimated by :func:`estimate_phase_error`.

    Attributes
    ----------
    phase : ndarray, shape ``[chirp]``
        Residual platform phase common to the cells [rad], its constant and
        linear trend removed (unobservable); the data is corrected by
        ``exp(-j phase)``.
    sigma : ndarray, shape ``[chirp]``
        One-sigma uncertainty of ``phase`` [rad] (NaN when nothing was estimated).
    time : ndarray, shape ``[chirp]``
        Time of each phase [s]: the chirp time, or the mean slot time (TDM).
    cells : int
        Cells (scatterers) used; 0 when none qualified.
    iterations : int
        PGA iterations run.
    wavelength : float or None
        Wavelength [m] of the data, for :meth:`displacement`.
    direction : tuple of float or None
        ``(az, el)`` [rad]: power-weighted direction ``u0`` of the cells, where
        the phase applies exactly (BeamCube input only).
    angle_spread : float or None
        Power-weighted rms angle of the cells' directions about ``u0`` [rad].
    range_rate : float or None
        With ``doppler="stationary"``: the common range rate the stationary
        cells showed [m/s] (positive receding), removed with the phase as its
        linear part; None with ``doppler="keep"`` (the linear phase left as is).
    range_rate_sigma : float or None
        Its one-sigma uncertainty [m/s].
    warnings : tuple of str
        ``"autofocus: ..."`` texts: nothing estimated, or an estimate not
        above its uncertainty.
    """

    phase: np.ndarray
    sigma: np.ndarray
    time: np.ndarray
    cells: int
    iterations: int
    wavelength: float | None = None
    direction: tuple | None = None
    angle_spread: float | None = None
    range_rate: float | None = None
    range_rate_sigma: float | None = None
    warnings: tuple = ()

    @property
    def rms(self) -> float:
        """Rms of :attr:`phase` [rad]."""
        return float(np.sqrt(np.mean(self.phase ** 2)))

    @property
    def sigma_rms(self) -> float:
        """Rms of :attr:`sigma` [rad] (NaN when nothing was estimated)."""
        return float(np.sqrt(np.mean(self.sigma ** 2)))

    @property
    def band(self) -> tuple[float, float]:
        """Frequencies the estimate covers, ``(1 / (N T), 1 / (2 T))`` [Hz]."""
        n = self.time.size
        dt = float(np.mean(np.diff(self.time)))
        return 1.0 / (n * dt), 1.0 / (2.0 * dt)

    def displacement(self) -> np.ndarray:
        """Line-of-sight displacement ``phase lambda / (4 pi)`` [m], shape ``[chirp]``."""
        if self.wavelength is None:
            raise ValueError("the estimate carries no wavelength; give wavelength= to "
                             "estimate_phase_error")
        return self.phase * self.wavelength / (4 * np.pi)

    def phase_at(self, times) -> np.ndarray:
        """The phase at ``times`` [s] (cubic spline through :attr:`phase`), any shape [rad]."""
        from scipy.interpolate import CubicSpline

        t = finite_array("times", times)
        return CubicSpline(self.time, self.phase, extrapolate=True)(t)

    def report(self) -> dict:
        """Plain-number summary (SI units) for output attributes and JSON."""
        est = self.cells > 0
        out = {"rms_phase_rad": self.rms, "sigma_rad": self.sigma_rms if est else None,
               "band_hz": list(self.band), "cells": int(self.cells),
               "iterations": int(self.iterations), "warnings": list(self.warnings)}
        if self.wavelength is not None:
            out["rms_displacement_m"] = float(np.sqrt(np.mean(self.displacement() ** 2)))
        if self.range_rate is not None:
            out["range_rate_mps"] = self.range_rate
            out["range_rate_sigma_mps"] = self.range_rate_sigma
        if self.direction is not None:
            out["direction_rad"] = [float(a) for a in self.direction]
            out["angle_spread_rad"] = self.angle_spread
        return out


def _detrend_basis(n: int) -> np.ndarray:
    """Orthonormal basis ``[n, 2]`` of constant and linear sequences."""
    q, _ = np.linalg.qr(np.column_stack([np.ones(n), np.arange(n, dtype=float)]))
    return q


def _detrend(phi: np.ndarray, q: np.ndarray) -> np.ndarray:
    return phi - q @ (q.T @ phi)


def _propagate(var: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Variance ``[chirp]`` of the detrended sequence of independent errors of variance ``var``.

    ``diag(P V P)`` with ``P = I - q q^T``:
    ``v_n - 2 v_n |q_n|^2 + q_n^T (sum_m v_m q_m q_m^T) q_n``.
    """
    m = np.einsum("m,mi,mj->ij", var, q, q)
    return var * (1 - 2 * np.sum(q ** 2, axis=1)) + np.einsum("ni,ij,nj->n", q, m, q)


def _noise_per_bin(x: np.ndarray) -> float:
    """Mean noise power per Doppler bin of one cell (unnormalised FFT), from a sample.

    The median of ``|X|^2`` over cells and bins is the noise's median
    ``ln 2 * mean`` where most bins hold noise (a sparse or stationary scene).
    """
    n_cell = x.shape[1]
    idx = np.unique(np.linspace(0, n_cell - 1, min(n_cell, NOISE_SAMPLE_CELLS)).astype(int))
    spec = scipy.fft.fft(x[:, idx].astype(np.complex64), axis=0)
    return float(np.median(np.abs(spec) ** 2)) / np.log(2.0)


def _candidates(x: np.ndarray, cell_shape: tuple, threshold: float, stationary_bins: float,
                max_cells: int) -> np.ndarray:
    """Flat indices of the selected cells, strongest first.

    A cell qualifies when its Doppler peak power exceeds ``threshold``, its
    pulse-pair Doppler lies within ``stationary_bins`` of zero and its
    slow-time power is a local maximum of the cells (no neighbour one step
    away along any cell axis is stronger): one cell per peak of a scatterer's
    response, so that the cells' noises are nearly independent.
    """
    import itertools

    n, n_cell = x.shape
    power = np.empty(n_cell, dtype=np.float32)
    keep_i, keep_p = [], []
    for c0 in range(0, n_cell, BLOCK_CELLS):
        blk = x[:, c0:c0 + BLOCK_CELLS]
        spec = scipy.fft.fft(blk.astype(np.complex64), axis=0)
        peak = (np.abs(spec) ** 2).max(axis=0)
        power[c0:c0 + blk.shape[1]] = np.mean(np.abs(blk) ** 2, axis=0)
        pp = np.sum(np.conj(blk[:-1]) * blk[1:], axis=0)
        bins = np.abs(np.angle(pp)) * n / (2 * np.pi)
        ok = np.flatnonzero((peak > threshold) & (bins <= stationary_bins))
        keep_i.append(ok + c0)
        keep_p.append(peak[ok])
    idx, peak = np.concatenate(keep_i), np.concatenate(keep_p)
    if idx.size == 0:
        return idx.astype(int)
    pos = np.array(np.unravel_index(idx, cell_shape))                     # [axis, cand]
    shape = np.array(cell_shape)[:, None]
    local = np.ones(idx.size, dtype=bool)
    for off in itertools.product((-1, 0, 1), repeat=len(cell_shape)):
        if not any(off):
            continue
        nb = pos + np.array(off)[:, None]
        inside = np.all((nb >= 0) & (nb < shape), axis=0)
        nb_idx = np.ravel_multi_index(tuple(np.clip(nb, 0, shape - 1)), cell_shape)
        local &= ~inside | (power[nb_idx] <= power[idx])
    idx, peak = idx[local], peak[local]
    return idx[np.argsort(-peak, kind="stable")[:max_cells]]


def _pga(g: np.ndarray, noise: float, iterations: int, q: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray, int]:
    """PGA on the cells ``g [chirp, cell]``: phase ``[chirp]``, its variance, iterations.

    The window is the whole Doppler band (module docstring, step 2).
    """
    n, k = g.shape
    g = g.astype(np.complex128)
    total = np.zeros(n)
    it = 0
    while it < iterations:
        it += 1
        spec = np.fft.fft(g, axis=0)
        peak = np.argmax(np.abs(spec), axis=0)
        h = g * np.exp(-2j * np.pi * np.outer(np.arange(n), peak) / n)   # peak to bin 0
        dphi = np.angle(np.sum(np.conj(h[:-1]) * h[1:], axis=1))
        phi = _detrend(np.concatenate([[0.0], np.cumsum(dphi)]), q)
        g *= np.exp(-1j * phi)[:, None]
        total += phi
        if np.sqrt(np.mean(phi ** 2)) < CONVERGENCE_RAD:
            break
    # Error of the estimate at chirp n: the power-weighted mean of the cells' phase
    # errors there (the gradients' errors telescope in the sum). Thermal part: the
    # phase noise of a sample of power |h|^2 in noise s2 is s2 / (2 |h|^2).
    h = g * np.exp(-2j * np.pi * np.outer(np.arange(n), np.argmax(
        np.abs(np.fft.fft(g, axis=0)), axis=0)) / n)
    w = np.abs(h) ** 2                                                   # [chirp, cell]
    s2 = noise / n                                                       # per sample
    var_th = s2 / (2 * np.maximum(w.sum(axis=1), 1e-300))
    if k > 1:                      # spread of the cells' phases about the common one
        # each cell's own constant and linear phase (its position, its Doppler) is not error
        dev = _detrend(np.unwrap(np.angle(h * np.conj(np.sum(h, axis=0))[None, :]), axis=0),
                       q)
        var_sp = (w ** 2 * dev ** 2).sum(axis=1) / np.maximum(w.sum(axis=1) ** 2,
                                                              1e-300) * k / (k - 1)
    else:
        var_sp = np.zeros(n)
    return _detrend(total, q), np.maximum(var_th, var_sp), it


def _common_doppler(g: np.ndarray, noise: float) -> tuple[float, float]:
    """Common linear phase of the cells ``g [chirp, cell]`` (slope [rad/chirp]) and its variance.

    Each cell's least-squares phase slope (its Doppler; unwrapped, the cells
    are stationary so a step stays far below pi), averaged with the weights of
    the cells' powers; variance from thermal noise
    (``12 s2 / (2 N (N^2 - 1) sum p)``) or the cells' spread, the larger.
    """
    n, k = g.shape
    psi = np.unwrap(np.angle(g * np.conj(g[n // 2])[None, :]), axis=0)
    x = np.arange(n) - (n - 1) / 2.0
    slope = x @ psi / (x @ x)                                            # [cell]
    p = np.mean(np.abs(g) ** 2, axis=0)
    s = float(p @ slope / p.sum())
    var = 12 * (noise / n) / (2 * n * (n * n - 1) * p.sum())
    if k > 1:
        var = max(var, float((p ** 2 @ (slope - s) ** 2) / p.sum() ** 2 * k / (k - 1)))
    return s, var


def _cells_of(data) -> tuple[np.ndarray, tuple, np.ndarray | None, float | None]:
    """``[chirp, cell]`` view, the cell shape, chirp times and wavelength of the input."""
    if isinstance(data, BeamCube):
        x = data.data
        return (x.reshape(x.shape[0], -1), x.shape[1:], np.asarray(data.chirp_time, float),
                float(data.wavelength))
    x = np.asarray(data)
    if x.ndim < 2 or not np.iscomplexobj(x):
        raise ValueError(f"data must be a BeamCube or a complex array [chirp, ...] of two or "
                         f"more axes, got {x.dtype} array of shape {x.shape}")
    return x.reshape(x.shape[0], -1), x.shape[1:], None, None


def check_selection(max_cells, iterations, min_snr_db, stationary_bins) -> tuple[float, float]:
    """Checked cell-selection options of an autofocus: ``(min_snr_db, stationary_bins)``.

    Raises ValueError naming the option when ``max_cells`` or ``iterations`` is not a
    positive integer, ``min_snr_db`` not finite or ``stationary_bins`` not positive.
    """
    if not (isinstance(max_cells, (int, np.integer)) and max_cells >= 1):
        raise ValueError(f"max_cells must be a positive integer, got {max_cells!r}")
    if not (isinstance(iterations, (int, np.integer)) and iterations >= 1):
        raise ValueError(f"iterations must be a positive integer, got {iterations!r}")
    snr = float(min_snr_db)
    if not np.isfinite(snr):
        raise ValueError(f"min_snr_db must be a finite number of dB, got {min_snr_db!r}")
    return snr, positive("stationary_bins", stationary_bins)


def estimate_phase_error(data, *, chirp_time=None, slot_times=None,
                         wavelength: float | None = None, max_cells: int = 32,
                         min_snr_db: float = 20.0, stationary_bins: float = 2.0,
                         iterations: int = 8, doppler: str = "keep",
                         sidelobe_db: float | None = None) -> Autofocus:
    """Estimate the residual per-chirp phase common to the cells (phase-gradient autofocus).

    Parameters
    ----------
    data : BeamCube or ndarray, shape ``[chirp, ...]``, complex
        Compensated beams (``[chirp, range, azimuth, elevation]``) or any cube
        with slow time first, e.g. ``[chirp, range, beam]``; every other axis
        is a cell.
    chirp_time : array_like, shape ``[chirp]``, optional
        Chirp times [s]; default the BeamCube's, else required.
    slot_times : array_like, shape ``[chirp, slot]``, optional
        TDM: the start of every transmit slot [s], each slot with the same
        number of channels; the phases are stamped with their mean.
    wavelength : float, optional
        Wavelength [m] (default the BeamCube's), for the displacement.
    max_cells : int
        Most cells used (the strongest qualifying).
    min_snr_db : float
        A cell's Doppler peak must exceed the noise per Doppler bin by this [dB].
    stationary_bins : float
        Largest pulse-pair Doppler of a cell, in Doppler bins ``1 / (N T)``
        (moving targets and micro-Doppler are left out).
    iterations : int
        Most PGA iterations.
    doppler : {"keep", "stationary"}
        ``"keep"``: the linear phase is left as is (a Doppler shift the data
        cannot tell from a velocity of the scene). ``"stationary"``: the
        selected cells are taken as stationary, so their common Doppler is a
        platform velocity error along ``u0``: it is estimated
        (:attr:`Autofocus.range_rate`) and its linear phase joins the
        estimate (a lateral velocity error, ``v . (u - u0)``, stays).
    sidelobe_db : float, optional
        Drop the cells this far [dB] or more below the strongest of their range gate
        (the first cell axis): where the array's sidelobes come that close, a
        sidelobe carries its scatterer's phase and Doppler at another beam's
        direction (:mod:`compensation.sidelobes`). Left out: every cell kept.

    Returns
    -------
    Autofocus
        With ``cells == 0``, zero phase, NaN sigma and an ``"autofocus"``
        warning (also issued as :class:`CompensationWarning`) when no cell
        qualifies.

    Raises
    ------
    ValueError
        Fewer than :data:`MIN_CHIRPS` chirps, non-finite data, bad times or options.

    Examples
    --------
    >>> import numpy as np
    >>> n = np.arange(64)
    >>> err = 0.3 * np.sin(2 * np.pi * n / 20)
    >>> cube = np.ones((64, 4, 3), complex) * np.exp(1j * err)[:, None, None]
    >>> cube[:, 1, 1] *= 100.0
    >>> af = estimate_phase_error(cube, chirp_time=n * 1e-4)
    >>> q = np.polyfit(n, err, 1)
    >>> bool(np.abs(af.phase - (err - np.polyval(q, n))).max() < 1e-6)
    True
    """
    x, cell_shape, t_beam, lam = _cells_of(data)
    n = x.shape[0]
    if n < MIN_CHIRPS:
        raise ValueError(f"data must hold at least {MIN_CHIRPS} chirps, got {n}")
    if not np.all(np.isfinite(x)):
        raise ValueError("data must be finite; it holds NaN or infinite values")
    if slot_times is not None:
        st = finite_array("slot_times", slot_times, ndim=2)
        if st.shape[0] != n:
            raise ValueError(f"slot_times must have shape [chirp={n}, slot], got {st.shape}")
        t = st.mean(axis=1)
    elif chirp_time is not None:
        t = finite_array("chirp_time", chirp_time, shape=(n,))
    elif t_beam is not None:
        t = t_beam
    else:
        raise ValueError("chirp_time is required for an array input ([chirp] times in s)")
    if np.any(np.diff(t) <= 0):
        raise ValueError("chirp_time must be strictly increasing")
    if wavelength is not None:
        lam = positive("wavelength", wavelength)
    snr, stationary_bins = check_selection(max_cells, iterations, min_snr_db, stationary_bins)
    if doppler not in ("keep", "stationary"):
        raise ValueError(f"doppler must be 'keep' or 'stationary', got {doppler!r}")

    noise = _noise_per_bin(x)
    sel = _candidates(x, cell_shape, noise * 10 ** (snr / 10), stationary_bins, max_cells)
    if sidelobe_db is not None:
        from .sidelobes import main_lobe_cells

        sel = main_lobe_cells(x, sel, cell_shape, positive("sidelobe_db", sidelobe_db))
    q = _detrend_basis(n)
    if sel.size == 0:
        text = (f"autofocus: no stationary scatterer {snr:g} dB above the noise in "
                f"{x.shape[1]} cells; nothing estimated, the data left as is")
        _warnings.warn(text, CompensationWarning, stacklevel=2)
        return Autofocus(np.zeros(n), np.full(n, np.nan), t, 0, 0, lam, warnings=(text,))
    g = x[:, sel]
    phase, var_grad, it = _pga(g, noise, int(iterations), q)
    sigma = np.sqrt(_propagate(var_grad, q))
    rate = rate_sigma = None
    if doppler == "stationary":
        slope, var_slope = _common_doppler(g * np.exp(-1j * phase)[:, None], noise)
        x = np.arange(n) - (n - 1) / 2.0
        phase = phase + slope * x
        sigma = np.sqrt(sigma ** 2 + var_slope * x ** 2)
        if lam is not None:          # phase 4 pi R / lambda: range rate from the slope
            dt = float(np.mean(np.diff(t)))
            rate = slope / dt * lam / (4 * np.pi)
            rate_sigma = float(np.sqrt(var_slope)) / dt * lam / (4 * np.pi)
    direction = spread = None
    if isinstance(data, BeamCube):
        direction, spread = _cells_direction(data, sel, g)
    warns: tuple = ()
    if np.sqrt(np.mean(phase ** 2)) <= np.sqrt(np.mean(sigma ** 2)):
        warns = (f"autofocus: estimated residual phase rms {np.sqrt(np.mean(phase ** 2)):.3g} "
                 f"rad is not above its uncertainty {np.sqrt(np.mean(sigma ** 2)):.3g} rad",)
    return Autofocus(phase, sigma, t, int(sel.size), it, lam, direction, spread, rate,
                     rate_sigma, warns)


def _cells_direction(beams: BeamCube, sel: np.ndarray, g: np.ndarray) -> tuple:
    """Power-weighted ``(az, el)`` of the cells and their rms angle about it [rad]."""
    from .geometry import direction

    _, ia, ie = np.unravel_index(sel, beams.data.shape[1:])
    az, el = np.asarray(beams.azimuth)[ia], np.asarray(beams.elevation)[ie]
    w = np.mean(np.abs(g) ** 2, axis=0)
    w = w / w.sum()
    u = np.stack([direction(a, e) for a, e in zip(az, el, strict=True)])    # [cell, 3]
    u0 = (w[:, None] * u).sum(axis=0)
    u0 /= np.linalg.norm(u0)
    ang = np.arccos(np.clip(u @ u0, -1.0, 1.0))
    return ((float(np.arctan2(u0[0], u0[2])), float(np.arcsin(u0[1]))),
            float(np.sqrt((w * ang ** 2).sum())))


def correct_phase(data, estimate: Autofocus, *, times=None):
    """Remove the estimated phase: ``data * exp(-j phase(t))``.

    Parameters
    ----------
    data : BeamCube or ndarray, shape ``[chirp, ...]``, complex
        Cube to correct.
    estimate : Autofocus
        From :func:`estimate_phase_error`.
    times : array_like, optional
        Time [s] of every sample along the leading axes of ``data``, e.g.
        ``[chirp]``, or ``[chirp, channel]`` for a TDM cube whose channels
        were sent at their slot's time; the phase is evaluated there (cubic
        spline). Default: :attr:`Autofocus.time`, one phase per chirp.

    Returns
    -------
    BeamCube or ndarray
        The corrected cube, same type, shape and dtype.
    """
    x = data.data if isinstance(data, BeamCube) else np.asarray(data)
    if not isinstance(estimate, Autofocus):
        raise ValueError(f"estimate must be a compensation.Autofocus, got {type(estimate)!r}")
    if x.shape[0] != estimate.phase.size:
        raise ValueError(f"data has {x.shape[0]} chirps, the estimate {estimate.phase.size}")
    if times is None:
        ph = estimate.phase
    else:
        t = finite_array("times", times)
        if t.ndim < 1 or t.shape != x.shape[: t.ndim]:
            raise ValueError(f"times must have the shape of the leading axes of data "
                             f"{x.shape}, got {t.shape}")
        ph = estimate.phase_at(t)
    ph = ph.reshape(ph.shape + (1,) * (x.ndim - ph.ndim))
    out = (x * np.exp(-1j * ph).astype(np.complex64 if x.dtype == np.complex64
                                       else np.complex128)).astype(x.dtype, copy=False)
    return replace(data, data=out) if isinstance(data, BeamCube) else out


def autofocus_beams(beams: BeamCube, *, slot_times=None, **options) -> tuple[BeamCube, Autofocus]:
    """Estimate the residual per-chirp phase of compensated beams and remove it.

    Parameters
    ----------
    beams : BeamCube
        Beams after the IMU-driven chain, ``data [chirp, range, azimuth, elevation]``.
    slot_times : array_like, shape ``[chirp, slot]``, optional
        TDM slot start times [s] (see :func:`estimate_phase_error`).
    **options
        ``max_cells``, ``min_snr_db``, ``stationary_bins``, ``iterations`` of
        :func:`estimate_phase_error`.

    Returns
    -------
    (BeamCube, Autofocus)
        The corrected beams (their ``warnings`` extended by the estimate's)
        and the estimate.
    """
    if not isinstance(beams, BeamCube):
        raise ValueError(f"beams must be a compensation.BeamCube, got {type(beams)!r}")
    est = estimate_phase_error(beams, slot_times=slot_times, **options)
    if est.cells == 0:
        return beams.with_warnings(est.warnings), est
    return correct_phase(beams, est).with_warnings(est.warnings), est
