"""Slow-time decimation: exact rows on a subset of chirps, least-squares interpolation between.

For a fixed channel and fast-time sample the IF samples along slow time,
``s[n] = sum_p a_p exp(j 2 pi ((f_c + mu t_k) tau_p[n] - mu tau_p[n]^2 / 2))``,
form a signal whose instantaneous frequency is at most
``B_p = max dD_p/dn / lambda_min`` cycles per chirp for path ``p``, with ``D_p``
its two-way length and ``lambda_min = c / (f_c + mu T_sweep)`` the shortest
wavelength of the sweep. On a hovering platform ``B`` is a few hundredths of a
cycle per chirp for static scatterers (platform motion only) and about 0.15
for walking-speed clutter, far below the Nyquist limit of every 2nd chirp.

:func:`path_doppler` bounds ``B_p`` from the geometry (element displacement
between chirps, with its second difference as margin, ``2 |v_p| T_chirp`` of a
moving path, the change of its per-chirp vertices and length). That is the
instantaneous frequency only. A vibrating platform (or a rotor, a swinging
limb) phase-modulates every path, and the spectrum of a sinusoidal phase
modulation of peak deviation ``beta`` [rad] at ``f_m`` has lines at every
multiple of ``f_m``: ``exp(j beta sin(2 pi f_m t)) = sum_n J_n(beta)
exp(j 2 pi n f_m t)`` (Jacobi-Anger). Carson's rule, bandwidth ``2 (beta + 1)
f_m``, keeps about 98 % of the power; a relative error ``tol`` needs the band
``N f_m`` with ``sum_{|n| > N} J_n(beta)^2 <= tol^2`` (:func:`bessel_tail`,
:func:`sideband_order`), far beyond the instantaneous ``beta f_m`` when
``beta`` is small (0.1 mm at 200 Hz: ``beta = 0.32``, ``N = 5`` at 1e-7).
Given a tolerance, :func:`path_doppler` adds these sidebands: the motion over
the frame is split into its best quadratic (the slow part, whose instantaneous
frequency the steps cover: drift, acceleration) and a fast residual, whose peak
deviation and modulating frequency ``W = max |d^2 r| / (2 pi max |d r|)`` (exact
for a sinusoid) give ``sideband_order(beta, SIDEBAND_SHARE tol) W`` for the
elements (:func:`platform_sidebands`, the worst channel, every line of sight)
and for each path's own per-chirp vertices (:func:`path_sidebands`); amplitudes
that vary over chirps (element gains at every chirp's pose) add their own band
(:func:`amplitude_band`).
:func:`plan_decimation` then picks, for a band ``B``, a factor ``D`` and the
exact chirps (every D-th chirp, the last one, and the midpoints of the gaps
near the edges where the design below misses the tolerance), and for every
other chirp ``n`` real weights ``w`` on its nearest exact chirps ``m_i`` (the
fewest of :data:`TAP_CHOICES` that meet the tolerance mid-frame) that minimise
the mean-square error over the band,
``int_{-B}^{B} |exp(j 2 pi f n) - sum_i w_i exp(j 2 pi f m_i)|^2 df``
(normal equations with the prolate matrix ``sinc(2 B (m_i - m_j))`` plus a
small ridge, Slepian's prolate spheroidal setting). Every
interpolated chirp carries its own modelled error, the largest
``|E(f)| = |1 - sum_i w_i exp(j 2 pi f (m_i - n))|`` over ``|f| <= B``: the
relative error of interpolating any sum of paths whose slow-time frequencies
lie in the band. Where a chirp's error exceeds the tolerance, or its weights
would amplify the exact rows' own error (``||w||_2 >`` :data:`MAX_GAIN`), the
gap around it is halved (its midpoint computed exactly) until every chirp
passes.

:func:`plan_groups` splits the paths by their own bound (static scatterers
apart from moving clutter), plans each group with its own factor and keeps the
split that minimises the modelled cost (paths x exact chirps, plus a per-row
overhead). Each group's interpolation error is below its tolerance relative to
that group's signal; paths with independent phases add in power, so the sum is
too.

The bound is a model, so it is checked after the fact
(:func:`raysim.synthesis.select.render_checked`): a few channels
(:func:`check_channels`, :data:`CHECK_SHARE` of them) are rendered at every
chirp, interpolated with the plan and compared (:func:`check_errors`: relative
l2 and worst chirp row); the factor is halved (:func:`halve`) until both fit,
or decimation is refused.

Refusal (factor 1, every chirp exact, with the reason in ``plan.reason``):
fewer chirps than :data:`MIN_CHIRPS`; a Doppler band too wide
for factor 2; too few chirps saved to be worth it; or a failed check at factor 2.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.paths import PathDelays
from raysim.synthesis.slowtime import interpolate, scatter_add  # noqa: F401 (re-exported)

__all__ = ["TAPS", "TAP_CHOICES", "MAX_FACTOR", "MIN_CHIRPS", "MAX_GAIN", "DecimationPlan",
           "doppler_bound", "path_doppler", "interpolation_error", "plan_decimation", "plan_groups",
           "interpolate", "scatter_add", "bessel_tail", "sideband_order", "carson_bandwidth",
           "platform_sidebands", "path_sidebands", "amplitude_band", "CHECK_SHARE",
           "check_channels", "spread_channels", "channel_subset", "check_errors", "halve"]

#: Exact chirps each interpolated chirp draws on (its nearest ones): the fewest of these
#: that meets the tolerance in the middle of the frame.
TAP_CHOICES = (4, 6, 8, 12, 16, 24, 32, 48, 64)
#: Default taps of :func:`interpolation_error`.
TAPS = 24
#: Largest decimation factor tried by ``"auto"``.
MAX_FACTOR = 32
#: Fewest chirps with which decimation is attempted.
MIN_CHIRPS = 64
#: Smallest fraction of chirps that decimation must save.
MIN_SAVING = 0.2
#: Largest l2 norm of one chirp's weights (gain on the exact rows' own error).
MAX_GAIN = 1.5
#: Tikhonov term of the normal equations, as a fraction of the tolerance (squared, relative
#: to the prolate matrix's unit diagonal): keeps the weights bounded where the exact chirps
#: oversample the band, at an error cost of about this fraction of the tolerance.
RIDGE_SHARE = 0.1
#: Smallest ridge: the prolate matrix is near-singular, and LU in float64 needs a margin
#: above its ~1e-16 rounding.
RIDGE_FLOOR = 1e-14
#: Frequencies per oscillation of ``|E(f)|`` at which each chirp's error is evaluated.
ERROR_GRID = 12
#: Safety factor on the error maximum read off that grid (|E| is smooth between points).
GRID_MARGIN = 1.05
#: Modelled cost of one exact chirp of one group in path-equivalents per channel
#: (row set-up, FFT, interpolation), used to decide how to split paths into groups.
ROW_OVERHEAD_PATHS = 1000
#: Most path groups planned separately.
MAX_GROUPS = 4
#: Share of the interpolation tolerance left to the motion's sidebands beyond the planned
#: band (their power is cut at ``(SIDEBAND_SHARE tol)^2``, :func:`sideband_order`).
SIDEBAND_SHARE = 0.1
#: Degree of the polynomial over the frame taken as the motion's slow part (its
#: instantaneous frequency is in the step bound; the rest is modelled as modulation).
SLOW_DEGREE = 2
#: Share of the channels rendered at every chirp by the a-posteriori check of
#: :func:`raysim.synthesis.select.render_checked` (at least one channel, at most
#: :data:`MAX_CHECK_CHANNELS`).
CHECK_SHARE = 0.01
#: Most channels the a-posteriori check renders at every chirp.
MAX_CHECK_CHANNELS = 8


@dataclass(frozen=True)
class DecimationPlan:
    """Which chirps are computed exactly and how the others are interpolated.

    Attributes
    ----------
    factor : int
        Decimation factor ``D`` (1: every chirp exact).
    exact : ndarray of int, shape ``[n_exact]``
        Local chirp indices (0 = first rendered chirp) computed exactly, increasing.
    missing : ndarray of int, shape ``[n_missing]``
        Local chirp indices interpolated.
    weights : ndarray, shape ``[n_missing, n_exact]``, float32
        Interpolation matrix: ``rows[missing] = weights @ rows[exact]``.
    doppler : float
        Bound of the slow-time frequency [cycles per chirp].
    error : float
        Largest modelled relative interpolation error over the missing chirps.
    reason : str
        Why this factor (or why decimation was refused).
    """

    factor: int
    exact: np.ndarray
    missing: np.ndarray
    weights: np.ndarray
    doppler: float
    error: float
    reason: str


def _step_bound(v: np.ndarray, axis_max=None) -> np.ndarray | float:
    """Largest displacement per chirp of positions ``[..., chirp, 3]`` [m], with the
    largest second difference added as margin for motion between chirps.

    ``axis_max=None``: one float over everything; else the maximum over the chirp
    axis only (one value per leading index)."""
    if v.shape[-2] < 2:
        return 0.0 if axis_max is None else np.zeros(v.shape[:-2])
    d1 = np.diff(v, axis=-2)
    step = np.linalg.norm(d1, axis=-1)
    out = step.max(axis=-1)
    if v.shape[-2] >= 3:
        out = out + np.linalg.norm(np.diff(d1, axis=-2), axis=-1).max(axis=-1)
    return float(np.max(out)) if axis_max is None else out


def _top_wavelength(config: RadarConfig) -> float:
    f_top = config.carrier_frequency + config.chirp_rate * config.num_samples / config.sample_rate
    return SPEED_OF_LIGHT / f_top


def _platform_step(src: PathDelays) -> float:
    """Largest two-way length change per chirp from the elements' motion [m]."""
    step = _step_bound(np.swapaxes(src.tx_positions, 0, 1))            # [channel, chirp, 3]
    return 2.0 * step if src.rx_positions is None \
        else step + _step_bound(np.swapaxes(src.rx_positions, 0, 1))


def bessel_tail(beta: float, order: int) -> float:
    """Power of the sidebands beyond ``order`` of a sinusoidal phase modulation.

    ``exp(j beta sin(2 pi f_m t)) = sum_n J_n(beta) exp(j 2 pi n f_m t)`` (Jacobi-Anger),
    so the share of the power outside ``|f| <= order f_m`` is
    ``sum_{|n| > order} J_n(beta)^2`` (summed from the band edge outwards in float64).

    Parameters
    ----------
    beta : float
        Peak phase deviation [rad], >= 0.
    order : int
        Highest sideband kept, >= 0.
    """
    from scipy.special import jv

    beta, order = abs(float(beta)), int(order)
    n = np.arange(order + 1, order + 64 + int(2 * beta))
    return float(2.0 * np.sum(jv(n, beta) ** 2))


def sideband_order(beta: float, tol: float) -> int:
    """Fewest sidebands ``N`` of a sinusoidal phase modulation of peak deviation ``beta`` [rad]
    whose truncation leaves a relative l2 error of at most ``tol``:
    ``sqrt(bessel_tail(beta, N)) <= tol``.

    Carson's rule (``N = beta + 1``, bandwidth ``2 (beta + 1) f_m``) keeps about 98 % of the
    power; a tolerance of 1e-7 needs ``N`` of about ``beta + 6 beta^(1/3) + 5`` for large
    ``beta`` and ``log(tol) / log(beta / 2)`` for small ``beta``.
    """
    if not (tol > 0):
        raise ValueError(f"tol must be > 0, got {tol!r}")
    beta = abs(float(beta))
    n = max(0, int(beta) - 1)
    while bessel_tail(beta, n) > tol * tol:
        n += 1
    while n > 0 and bessel_tail(beta, n - 1) <= tol * tol:
        n -= 1
    return n


def carson_bandwidth(beta: float, f_m: float) -> float:
    """Carson's rule: bandwidth ``2 (beta + 1) f_m`` of a phase modulation of peak deviation
    ``beta`` [rad] at ``f_m`` (any frequency unit; same unit out)."""
    return 2.0 * (abs(float(beta)) + 1.0) * float(f_m)


def _modulation(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fast part of positions ``v [..., chirp, 3]`` [m]: the residual after the best
    quadratic fit over the chirps (the slow part, whose instantaneous frequency the
    step bound covers). Returns its peak deviation ``max_n |r|`` [m] and its modulating
    frequency ``W = max |d^2 r| / (2 pi max |d r|)`` [cycles per chirp] (exact for a
    sinusoid, dominated by the fastest component otherwise), each shape ``[...]``."""
    n = v.shape[-2]
    if n < 4:
        z = np.zeros(v.shape[:-2])
        return z, z
    t = np.linspace(-1.0, 1.0, n)
    basis = np.polynomial.legendre.legvander(t, min(SLOW_DEGREE, n - 2))  # [chirp, deg + 1]
    coef = np.einsum("kn,...nc->...kc", np.linalg.pinv(basis), v)
    r = v - np.einsum("nk,...kc->...nc", basis, coef)
    dev = np.linalg.norm(r, axis=-1).max(axis=-1)
    d1 = np.diff(r, axis=-2)
    s1 = np.linalg.norm(d1, axis=-1).max(axis=-1)
    s2 = np.linalg.norm(np.diff(d1, axis=-2), axis=-1).max(axis=-1)
    w = np.where(s1 > 0, s2 / (2.0 * np.pi * np.where(s1 > 0, s1, 1.0)), 0.0)
    return dev, np.minimum(w, 0.5)


def _sideband_margin(dev_m: np.ndarray, w: np.ndarray, wavelength: float,
                     tol: float) -> np.ndarray:
    """Band beyond the instantaneous frequency needed by the sidebands [cycles per chirp]:
    ``sideband_order(beta, SIDEBAND_SHARE tol) W`` with ``beta = 2 pi dev / lambda``."""
    beta = 2.0 * np.pi * np.asarray(dev_m, dtype=float) / wavelength
    out = np.zeros(beta.shape)
    flat_b, flat_w, flat_o = beta.reshape(-1), np.broadcast_to(w, beta.shape).reshape(-1), \
        out.reshape(-1)
    memo: dict = {}
    for i, b in enumerate(flat_b):
        key = float(f"{b:.3g}") if b > 0 else 0.0
        key = max(key, b)
        if key not in memo:
            memo[key] = sideband_order(key, SIDEBAND_SHARE * tol)
        flat_o[i] = memo[key] * flat_w[i]
    return out


def platform_sidebands(src: PathDelays, config: RadarConfig, tol: float) -> float:
    """Sideband margin of the elements' motion [cycles per chirp], the worst channel.

    The fast part of each channel's tx and rx motion (:func:`_modulation`) is
    modelled as a sinusoidal phase modulation of peak deviation
    ``beta = 2 pi (dev_tx + dev_rx) / lambda_min`` (every line of sight) at ``W``;
    its Bessel sidebands out to :func:`sideband_order` ``(beta, SIDEBAND_SHARE tol)``
    times ``W`` are added to the instantaneous Doppler bound.
    """
    dev, w = _modulation(np.swapaxes(src.tx_positions, 0, 1))          # [channel]
    if src.rx_positions is None:
        dev = 2.0 * dev
    else:
        dev_r, w_r = _modulation(np.swapaxes(src.rx_positions, 0, 1))
        dev, w = dev + dev_r, np.maximum(w, w_r)
    margin = _sideband_margin(dev, w, _top_wavelength(config), tol)
    return float(margin.max(initial=0.0))


def path_sidebands(src: PathDelays, config: RadarConfig, tol: float) -> np.ndarray:
    """Sideband margin of each path's own per-chirp vertex motion (rotors, tracks)
    [cycles per chirp], shape ``[path]`` (zero for fixed vertices)."""
    dev = np.zeros(src.num_paths)
    w = np.zeros(src.num_paths)
    for v in (src.first_vertex, src.last_vertex):
        if v.ndim == 3:
            d, f = _modulation(v)
            dev, w = dev + d, np.maximum(w, f)
    if src.interior_length.ndim == 2:
        d, f = _modulation(np.stack([src.interior_length, 0 * src.interior_length,
                                     0 * src.interior_length], axis=-1))
        dev, w = dev + d, np.maximum(w, f)
    if not np.any(dev):
        return dev
    return _sideband_margin(dev, w, _top_wavelength(config), tol)


def path_doppler(src: PathDelays, config: RadarConfig, tol: float | None = None) -> np.ndarray:
    """Bound of the slow-time frequency of each path [cycles per chirp], shape ``[path]``.

    ``(max step of tx + max step of rx + 2 |velocity_p| T_chirp + steps of the
    path's per-chirp vertices and length) / lambda_min``, ``lambda_min`` the
    wavelength at the top of the sweep (the instantaneous frequency), plus with
    ``tol`` the sideband margins of the motion's fast part
    (:func:`platform_sidebands`, :func:`path_sidebands`) at that tolerance.
    """
    step = np.full(src.num_paths, _platform_step(src))
    if src.velocity is not None:
        step += 2.0 * np.linalg.norm(src.velocity, axis=1) * config.chirp_interval
    for v in (src.first_vertex, src.last_vertex):
        if v.ndim == 3:
            step += _step_bound(v, axis_max=True)
    if src.interior_length.ndim == 2 and src.num_chirps > 1:
        step += np.abs(np.diff(src.interior_length, axis=1)).max(axis=1)
    band = step / _top_wavelength(config)
    if tol is not None:
        band += platform_sidebands(src, config, tol) + path_sidebands(src, config, tol)
    if src.amplitude.ndim == 2:
        band += amplitude_band(src.amplitude, tol)
    return band


def amplitude_band(amplitude: np.ndarray, tol: float | None = None) -> np.ndarray:
    """Slow-time band of amplitudes that vary over chirps [cycles per chirp], ``[path]``.

    An element gain read at every chirp's pose (``[path, chirp]``) modulates the
    path. Its instantaneous part is ``max |a[n+1] - a[n]| / (2 pi max |a|)`` plus the
    same of the second difference as margin (exact for ``a = exp(j 2 pi f n)`` and
    for ``cos(2 pi f n)``); with ``tol`` the fast residual ``r`` after the best
    quadratic (as :func:`_modulation`) adds its sidebands as a modulation of index
    ``max |r| / max |a|`` at ``W`` (:func:`sideband_order` at ``SIDEBAND_SHARE tol``).
    """
    a = np.asarray(amplitude)
    peak = np.abs(a).max(axis=1)
    scale = np.where(peak > 0, peak, 1.0)
    if a.shape[1] < 2:
        return np.zeros(a.shape[0])
    d1 = np.diff(a, axis=1)
    out = np.abs(d1).max(axis=1)
    if a.shape[1] >= 3:
        out = out + np.abs(np.diff(d1, axis=1)).max(axis=1)
    band = out / (2.0 * np.pi * scale)
    if tol is not None:
        # the fast residual after the best quadratic, as _modulation, on complex rows
        n = a.shape[1]
        if n < 4:
            return band
        basis = np.polynomial.legendre.legvander(np.linspace(-1.0, 1.0, n),
                                                 min(SLOW_DEGREE, n - 2))
        r = a - (a @ np.linalg.pinv(basis).T) @ basis.T
        d1 = np.diff(r, axis=1)
        s1 = np.abs(d1).max(axis=1)
        s2 = np.abs(np.diff(d1, axis=1)).max(axis=1)
        w = np.minimum(np.where(s1 > 0, s2 / (2.0 * np.pi * np.where(s1 > 0, s1, 1.0)), 0.0),
                       0.5)
        beta = np.abs(r).max(axis=1) / scale
        # sideband_order grows with beta: round beta up to a grid of 2^(1/4) steps, so
        # that a few orders serve every path
        live = beta > 0
        grid = np.zeros(beta.shape)
        grid[live] = 2.0 ** (np.ceil(4.0 * np.log2(beta[live])) / 4.0)
        keys, inverse = np.unique(grid, return_inverse=True)
        orders = np.array([sideband_order(k, SIDEBAND_SHARE * tol) if k > 0 else 0
                           for k in keys])
        band += orders[inverse.reshape(-1)] * w
    return band


def doppler_bound(src: PathDelays, config: RadarConfig, tol: float | None = None) -> float:
    """Bound of the slow-time frequency of every path [cycles per chirp] (max of
    :func:`path_doppler`; the platform's part alone without paths)."""
    platform = _platform_step(src) / _top_wavelength(config)
    if tol is not None:
        platform += platform_sidebands(src, config, tol)
    return float(path_doppler(src, config, tol).max(initial=platform))


def _weights_for(off: np.ndarray, band: float, tol: float):
    """Least-squares weights for neighbour offsets ``off`` [pattern, K] (chirps), with their
    modelled error (largest ``|E(f)|`` over ``|f| <= band``) and l2 gain."""
    two_b = 2.0 * band
    gram = np.sinc(two_b * (off[:, :, None] - off[:, None, :]))
    gram += max((RIDGE_SHARE * tol) ** 2, RIDGE_FLOOR) * np.eye(off.shape[1])
    w = np.linalg.solve(gram, np.sinc(two_b * off)[..., None])[..., 0]
    # |E(f)| oscillates at most band * max|off| times over [0, band]: sample each period
    # ERROR_GRID times (|E(-f)| = |E(f)| for real weights)
    n_f = int(ERROR_GRID * (1.0 + band * float(np.abs(off).max(initial=0.0))))
    f = np.linspace(0.0, band, n_f)
    ph = np.exp((2j * np.pi) * off[:, None, :] * f[None, :, None])    # [pattern, F, K]
    # einsum, not matmul: stacked small products through BLAS wake its thread pool
    err = GRID_MARGIN * np.abs(1.0 - np.einsum("pfk,pk->pf", ph, w)).max(axis=1)
    return w, err, np.linalg.norm(w, axis=1)


def _design(n_local: int, exact: np.ndarray, band: float, taps: int, tol: float, memo=None):
    """Least-squares weights of every non-exact chirp on its nearest exact chirps.

    ``memo`` (dict) keeps the weights of offset patterns already designed.
    Returns ``(missing [n_miss], cols [n_miss, K] (indices into exact), w [n_miss, K],
    err [n_miss], gain [n_miss])``.
    """
    is_exact = np.zeros(n_local, bool)
    is_exact[exact] = True
    missing = np.flatnonzero(~is_exact)
    k = min(taps, exact.size)
    if missing.size == 0:
        return missing, np.zeros((0, k), np.int64), np.zeros((0, k)), np.zeros(0), np.zeros(0)
    dist = np.abs(exact[None, :] - missing[:, None])                   # [miss, exact]
    cols = np.sort(np.argpartition(dist, k - 1, axis=1)[:, :k], axis=1)
    # chirps with the same pattern of neighbour offsets share their weights
    pattern, inverse = np.unique(exact[cols] - missing[:, None], axis=0, return_inverse=True)
    memo = {} if memo is None else memo
    keys = [p.tobytes() for p in pattern]
    new = [i for i, key in enumerate(keys) if key not in memo]
    if new:
        w, err, gain = _weights_for(pattern[new].astype(np.float64), band, tol)
        for j, i in enumerate(new):
            memo[keys[i]] = (w[j], err[j], gain[j])
    w = np.stack([memo[key][0] for key in keys])
    err = np.array([memo[key][1] for key in keys])
    gain = np.array([memo[key][2] for key in keys])
    inverse = inverse.reshape(-1)
    return missing, cols, w[inverse], err[inverse], gain[inverse]


@lru_cache(maxsize=256)
def _plan_factor(n_local: int, band: float, factor: int, tol: float):
    """Exact chirps and weights for one factor, or None when the band is too wide.

    Starts from every ``factor``-th chirp plus the last one; chirps whose design
    misses ``tol`` or ``MAX_GAIN`` become exact, until every other chirp meets both.
    """
    if 2.0 * band * factor >= 0.95:                                    # decimated Nyquist
        return None
    taps = next((k for k in TAP_CHOICES
                 if interpolation_error(band, factor, k, tol) <= 0.5 * tol), None)
    if taps is None:
        return None
    exact = np.union1d(np.arange(0, n_local, factor), [n_local - 1])
    memo: dict = {}
    while True:
        missing, cols, w, err, gain = _design(n_local, exact, band, taps, tol, memo)
        bad = missing[(err > tol) | (gain > MAX_GAIN)]
        if bad.size == 0:
            break
        # refine the gaps that hold a failing chirp (near the edges): add their midpoints
        right = np.searchsorted(exact, bad)
        exact = np.union1d(exact, (exact[right - 1] + exact[right]) // 2)
    weights = np.zeros((missing.size, exact.size), np.float32)
    np.put_along_axis(weights, cols, w.astype(np.float32), axis=1)
    weights.setflags(write=False)
    exact.setflags(write=False)
    missing.setflags(write=False)
    return exact, missing, weights, float(err.max(initial=0.0))


def interpolation_error(doppler: float, factor: int, taps: int = TAPS,
                        tol: float = 1e-6) -> float:
    """Modelled relative error of interpolating a band of ``doppler`` cycles/chirp
    sampled every ``factor`` chirps, in the middle of a long frame.

    The largest ``|E(f)|`` over the band of the least-squares weights on the
    ``taps`` nearest samples, at the chirp half-way between two of them
    (ridge set for tolerance ``tol``); ``inf`` when the band reaches the decimated Nyquist limit.
    """
    if factor < 2:
        return 0.0
    if 2.0 * doppler * factor >= 0.95:
        return math.inf
    off = factor * (np.arange(taps) - taps // 2) + factor // 2 + (factor % 2)
    return float(_weights_for(off[None, :].astype(np.float64), doppler, tol)[1][0])


def _refuse(n_local: int, doppler: float, reason: str) -> DecimationPlan:
    return DecimationPlan(1, np.arange(n_local, dtype=np.int64), np.zeros(0, np.int64),
                          np.zeros((0, n_local), np.float32), doppler, 0.0, reason)


def _check_decimate(decimate) -> None:
    if not (decimate == "auto" or (isinstance(decimate, (int, np.integer))
                                   and not isinstance(decimate, bool) and decimate >= 1)):
        raise ValueError(f"decimate must be 'auto' or an integer >= 1, got {decimate!r}")


def _plan_band(n_local: int, doppler: float, eps: float, decimate) -> DecimationPlan:
    """Plan for every path of one band (see :func:`plan_decimation`)."""
    if decimate == "auto":
        # the largest factors below the decimated Nyquist limit (smaller ones need more
        # exact chirps; the edges may favour one a little below the largest)
        top = min(MAX_FACTOR, max(2, int(math.ceil(0.95 / (2.0 * max(doppler, 1e-9))) - 1)))
        # right at the decimated Nyquist limit no tap count may reach eps: then smaller
        # factors, three at a time, shrinking by a quarter
        batches = []
        while True:
            batches.append(range(max(2, top - 2), top + 1))
            if top <= 4:
                break
            top = max(2, min(top - 3, int(0.75 * top)))
    else:
        batches = [(int(decimate),)]
    factors = batches[0]
    # quantise the band upwards (3 significant digits) so that the design cache is hit
    band = float(f"{doppler * 1.0005:.3g}") if doppler > 0 else 1e-6
    band = max(band, doppler)
    ok = {}
    for batch in batches:
        designs = {d: _plan_factor(n_local, band, d, float(eps)) for d in batch}
        ok = {d: p for d, p in designs.items() if p is not None}
        if ok:
            break
    if not ok:
        return _refuse(n_local, doppler, f"Doppler band {doppler:.3g} cycles/chirp too wide for "
                       f"factor {factors[0]} at tolerance {eps:g}")
    # the cheapest factor, not the largest: edge chirps may have to be exact
    factor = min(ok, key=lambda d: (ok[d][0].size, -d))
    exact, missing, w, err = ok[factor]
    if missing.size < MIN_SAVING * n_local:
        return _refuse(n_local, doppler, f"only {missing.size} of {n_local} chirps would be "
                       "interpolated")
    return DecimationPlan(factor, exact, missing, w, doppler, err,
                          f"Doppler band {doppler:.3g} cycles/chirp, factor {factor}, "
                          f"{exact.size} of {n_local} chirps exact")


def _screen(src, config: RadarConfig, n_local: int, decimate, bound=None) -> str | None:
    """Why decimation cannot apply at all (None if it may)."""
    _check_decimate(decimate)
    if decimate == 1:
        return "decimate=1"
    if not isinstance(src, PathDelays) and bound is None:
        return "dense delays: no geometry to bound the Doppler band"
    if n_local < MIN_CHIRPS:
        return f"too few chirps ({n_local} < {MIN_CHIRPS})"
    return None


def plan_decimation(src: PathDelays, config: RadarConfig, num_chirps: int, eps: float,
                    decimate="auto") -> DecimationPlan:
    """Plan the decimation of ``num_chirps`` consecutive chirps of all paths at tolerance ``eps``.

    Parameters
    ----------
    src : PathDelays
    config : RadarConfig
    num_chirps : int
        Chirps rendered (chirps near the edges of this range may have to be exact).
    eps : float
        Error share allowed for interpolation (relative l2).
    decimate : "auto" or int >= 1
        ``"auto"``: of the factors up to :data:`MAX_FACTOR` that meet ``eps``,
        the one with the fewest exact chirps; an integer: that factor if it
        meets ``eps``, else refusal.
    """
    n_local = int(num_chirps)
    why = _screen(src, config, n_local, decimate)
    if why is not None:
        return _refuse(n_local, math.nan, why)
    return _plan_band(n_local, doppler_bound(src, config, eps), eps, decimate)


def plan_groups(src: PathDelays, config: RadarConfig, num_chirps: int, eps: float,
                decimate="auto", bound=None) -> list[tuple[np.ndarray, DecimationPlan]]:
    """Split the paths by their Doppler bound and plan each group (see the module docstring).

    Candidate bands are the geometric levels ``b_min * 2^j`` up to the largest
    path bound; a dynamic programme over the sorted levels chooses contiguous
    groups (at most :data:`MAX_GROUPS`) that minimise ``sum (paths +
    ROW_OVERHEAD_PATHS) x exact chirps``. ``bound`` [path]: the paths' bands, where
    ``src`` is not a PathDelays (:func:`raysim.synthesis.dense_decimation.dense_doppler`).

    Returns
    -------
    list of (indices [n_g] int, DecimationPlan)
        Path indices of each group (together every path once) and its plan.
    """
    n_local = int(num_chirps)
    why = _screen(src, config, n_local, decimate, bound)
    everything = np.arange(src.num_paths)
    if why is not None:
        return [(everything, _refuse(n_local, math.nan, why))]
    if src.num_paths == 0:
        return [(everything, plan_decimation(src, config, n_local, eps, decimate))]
    bound = path_doppler(src, config, eps) if bound is None else np.asarray(bound, float)
    hi = float(bound.max())
    lo = max(float(bound.min()), hi * 2.0**-10)    # a still platform: static bounds are 0
    if decimate != "auto" or hi <= 2.0 * lo:
        return [(everything, _plan_band(n_local, hi, eps, decimate))]
    n_lev = int(math.ceil(math.log(hi / lo) / math.log(2.0)))
    edges = lo * 2.0 ** np.arange(n_lev + 1)
    edges[-1] = hi
    level = np.minimum(np.searchsorted(edges, bound, side="left"), n_lev)
    counts = np.bincount(level, minlength=n_lev + 1)
    levels = np.flatnonzero(counts)
    plans = {int(j): _plan_band(n_local, float(edges[j]), eps, decimate) for j in levels}
    # dp[g][i]: cheapest cost of levels[:i] in g groups; a group ends at its top level
    cum = np.concatenate([[0], np.cumsum(counts[levels])])
    n = levels.size
    inf = math.inf
    dp = [[inf] * (n + 1) for _ in range(MAX_GROUPS + 1)]
    back = [[-1] * (n + 1) for _ in range(MAX_GROUPS + 1)]
    dp[0][0] = 0.0
    for g in range(1, MAX_GROUPS + 1):
        for i in range(1, n + 1):
            rows = plans[int(levels[i - 1])].exact.size
            for s in range(i):
                c = dp[g - 1][s] + (cum[i] - cum[s] + ROW_OVERHEAD_PATHS) * rows
                if c < dp[g][i]:
                    dp[g][i], back[g][i] = c, s
    g = min(range(1, MAX_GROUPS + 1), key=lambda k: dp[k][n])
    groups, i = [], n
    while g > 0:
        s = back[g][i]
        top = int(levels[i - 1])
        members = np.flatnonzero((level >= levels[s]) & (level <= top))
        groups.append((members, plans[top]))
        i, g = s, g - 1
    return groups[::-1]


# ------------------------------------------------------------------ a-posteriori check
def check_channels(src: PathDelays, count: int | None = None) -> np.ndarray:
    """Channels the a-posteriori check renders at every chirp, shape ``[k]`` (increasing).

    ``count`` defaults to :data:`CHECK_SHARE` of the channels (at least 1, at most
    :data:`MAX_CHECK_CHANNELS`): the channel whose motion has the widest sidebands
    (largest ``dev * W`` of :func:`_modulation`, the lever arm's ends under rotation),
    then the first and the last, then evenly spaced ones.
    """
    n_ch = src.num_channels
    if count is None:
        count = min(MAX_CHECK_CHANNELS, max(1, int(round(CHECK_SHARE * n_ch))))
    count = min(int(count), n_ch)
    if count < 1:
        raise ValueError(f"count must be >= 1, got {count!r}")
    dev, w = _modulation(np.swapaxes(src.tx_positions, 0, 1))
    return spread_channels(int(np.argmax(dev * np.maximum(w, 1e-12))), n_ch, count)


def spread_channels(first: int, n_ch: int, count: int) -> np.ndarray:
    """``count`` check channels: ``first`` (the most modulated), both ends, then evenly
    spread ones, sorted (int64 ``[count]``)."""
    picks = [int(first)]
    for c in [0, n_ch - 1] + list(np.linspace(0, n_ch - 1, count + 2).round().astype(int)):
        if len(picks) >= count:
            break
        if int(c) not in picks:
            picks.append(int(c))
    return np.array(sorted(picks), dtype=np.int64)


def channel_subset(src: PathDelays, channels: np.ndarray) -> PathDelays:
    """The same paths seen by the channels ``channels`` [k] only."""
    idx = np.asarray(channels, dtype=np.int64)
    return PathDelays(src.first_vertex, src.last_vertex, src.interior_length, src.amplitude,
                      src.tx_positions[:, idx],
                      None if src.rx_positions is None else src.rx_positions[:, idx],
                      src.velocity, None if src.element_times is None
                      else src.element_times[:, idx], src.reference_time)


def check_errors(got: np.ndarray, ref: np.ndarray) -> tuple[float, float]:
    """Relative l2 error of ``got`` against ``ref`` (both ``[chirp, ...]``) and its worst
    chirp row ``max_n |got[n] - ref[n]| / |ref[n]|`` (a zero row: 0 if matched, else inf)."""
    diff = (got - ref).reshape(got.shape[0], -1)
    refn = np.linalg.norm(ref.reshape(ref.shape[0], -1), axis=1)
    errn = np.linalg.norm(diff, axis=1)
    total = float(np.linalg.norm(refn))
    l2 = float(np.linalg.norm(errn)) / total if total > 0 else (0.0 if not errn.any() else math.inf)
    with np.errstate(divide="ignore", invalid="ignore"):
        row = np.where(refn > 0, errn / np.where(refn > 0, refn, 1.0),
                       np.where(errn > 0, math.inf, 0.0))
    return l2, float(row.max(initial=0.0))


def halve(plan: DecimationPlan, n_local: int, eps: float, why: str) -> DecimationPlan:
    """The plan with half the factor and twice the band (below 3/4 of the new decimated
    Nyquist limit), or refusal (factor 1) saying ``why``."""
    factor = plan.factor // 2
    if factor >= 2:
        band = min(2.0 * max(plan.doppler, 1e-6), 0.375 / factor)
        new = _plan_band(n_local, band, eps, factor)
        if new.factor > 1:
            return replace(new, reason=f"{new.reason} (halved: {why})")
    return replace(_refuse(n_local, plan.doppler, ""),
                   reason=f"a-posteriori check failed ({why}); every chirp exact")
