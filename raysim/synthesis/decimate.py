"""Slow-time decimation: exact rows on every D-th chirp, Kaiser-sinc interpolation between.

For a fixed channel and fast-time sample the IF samples along slow time,
``s[n] = sum_p a_p exp(j 2 pi ((f_c + mu t_k) tau_p[n] - mu tau_p[n]^2 / 2))``,
form a signal whose instantaneous frequency is at most
``B = max dD/dn / lambda_min`` cycles per chirp, with ``D`` the two-way path
length and ``lambda_min = c / (f_c + mu T_sweep)`` the shortest wavelength of the
sweep. On a hovering platform ``B`` is a few hundredths of a cycle per chirp,
far below the Nyquist limit of every 2nd or 4th chirp. :func:`plan_decimation`
bounds ``B`` from the geometry (element displacement between chirps, with its
second difference as margin, and ``|velocity| T_chirp`` of each moving path, or
the change of per-chirp vertices and lengths), picks the largest factor whose
Kaiser-windowed-sinc interpolation error (Kaiser's design formula for a
``TAPS``-tap filter with transition band ``1 - 2 B D`` in decimated units) is
below its share of ``eps``, and lists the chirps computed exactly: every D-th
chirp, and every chirp near the edges of the rendered range whose filter would
reach outside it (margin chirps).

Refusal (factor 1, every chirp exact, with the reason in ``plan.reason``):
fewer chirps than ``MIN_CHIRPS``; amplitudes that vary over chirps (``[path,
chirp]``, which the bound does not cover); a Doppler band too wide for factor 2;
or too few chirps saved to be worth it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.paths import PathDelays

__all__ = ["TAPS", "MAX_FACTOR", "MIN_CHIRPS", "DecimationPlan", "doppler_bound",
           "interpolation_error", "plan_decimation", "interpolate"]

#: Taps of the slow-time interpolation filter (half on each side).
TAPS = 24
#: Largest decimation factor tried by ``"auto"``.
MAX_FACTOR = 8
#: Fewest chirps with which decimation is attempted.
MIN_CHIRPS = 64
#: Smallest fraction of chirps that decimation must save.
MIN_SAVING = 0.2


@dataclass(frozen=True)
class DecimationPlan:
    """Which chirps are computed exactly and how the others are interpolated.

    Attributes
    ----------
    factor : int
        Decimation factor ``D`` (1: every chirp exact).
    exact : ndarray of int, shape ``[n_exact]``
        Local chirp indices (0 = first rendered chirp) computed exactly.
    missing : ndarray of int, shape ``[n_missing]``
        Local chirp indices interpolated.
    weights : ndarray, shape ``[n_missing, n_exact]``, float32
        Interpolation matrix: ``rows[missing] = weights @ rows[exact]``.
    doppler : float
        Bound of the slow-time frequency [cycles per chirp].
    error : float
        Modelled relative interpolation error.
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


def _step_bound(v: np.ndarray) -> float:
    """Largest displacement per chirp of positions ``[..., chirp, 3]`` [m], with the
    largest second difference added as margin for motion between chirps."""
    if v.shape[-2] < 2:
        return 0.0
    d1 = np.diff(v, axis=-2)
    step = float(np.linalg.norm(d1, axis=-1).max())
    if v.shape[-2] >= 3:
        step += float(np.linalg.norm(np.diff(d1, axis=-2), axis=-1).max())
    return step


def doppler_bound(src: PathDelays, config: RadarConfig) -> float:
    """Bound of the slow-time frequency of every path [cycles per chirp].

    ``(max step of tx + max step of rx + 2 max |velocity| T_chirp + steps of
    per-chirp vertices and lengths) / lambda_min``, ``lambda_min`` the wavelength
    at the top of the sweep.
    """
    step = _step_bound(np.swapaxes(src.tx_positions, 0, 1))            # [channel, chirp, 3]
    step += step if src.rx_positions is None \
        else _step_bound(np.swapaxes(src.rx_positions, 0, 1))
    if src.velocity is not None and src.num_paths:
        step += 2.0 * float(np.linalg.norm(src.velocity, axis=1).max()) * config.chirp_interval
    for v in (src.first_vertex, src.last_vertex):
        if v.ndim == 3 and src.num_paths:
            step += _step_bound(v)
    if src.interior_length.ndim == 2 and src.num_chirps > 1 and src.num_paths:
        step += float(np.abs(np.diff(src.interior_length, axis=1)).max())
    f_top = config.carrier_frequency + config.chirp_rate * config.num_samples / config.sample_rate
    return step * f_top / SPEED_OF_LIGHT


def _kaiser_attenuation(transition: float, taps: int = TAPS) -> float:
    """Kaiser's estimate of the stop/pass attenuation [dB] of a ``taps``-tap filter."""
    return 14.36 * transition * taps + 7.95


def interpolation_error(doppler: float, factor: int, taps: int = TAPS) -> float:
    """Modelled relative error of interpolating by ``factor`` a band of ``doppler`` cycles/chirp.

    ``10^(-A/20)`` with Kaiser's attenuation for the transition band
    ``1 - 2 doppler factor`` (decimated units), floored at 1e-9 (float32 weights
    on complex64 rows); ``inf`` when the band reaches the decimated Nyquist limit.
    """
    transition = 1.0 - 2.0 * doppler * factor
    if transition <= 0.05:
        return math.inf
    return max(10.0 ** (-_kaiser_attenuation(transition, taps) / 20.0), 1e-9)


def _weights(n_local: int, factor: int, taps: int, attenuation: float):
    half = taps // 2
    beta = 0.1102 * (attenuation - 8.7) if attenuation > 50 else \
        0.5842 * (attenuation - 21) ** 0.4 + 0.07886 * (attenuation - 21)
    grid = np.arange(0, n_local, factor)
    exact = set(grid.tolist())
    missing, rows = [], []
    for n in range(n_local):
        if n in exact:
            continue
        e = n // factor
        idx = np.arange(e - half + 1, e + half + 1)
        if idx[0] < 0 or idx[-1] * factor > n_local - 1:
            exact.add(n)                                   # margin chirp: exact
            continue
        x = n / factor - idx
        win = np.i0(beta * np.sqrt(np.clip(1.0 - (x / half) ** 2, 0.0, None))) / np.i0(beta)
        missing.append(n)
        rows.append((idx * factor, np.sinc(x) * win))
    exact_arr = np.array(sorted(exact), dtype=np.int64)
    pos = {int(c): i for i, c in enumerate(exact_arr)}
    w = np.zeros((len(missing), exact_arr.size), dtype=np.float32)
    for r, (cols, vals) in enumerate(rows):
        w[r, [pos[int(c)] for c in cols]] = vals
    return exact_arr, np.array(missing, dtype=np.int64), w


def _refuse(n_local: int, doppler: float, reason: str) -> DecimationPlan:
    return DecimationPlan(1, np.arange(n_local, dtype=np.int64), np.zeros(0, np.int64),
                          np.zeros((0, n_local), np.float32), doppler, 0.0, reason)


def plan_decimation(src: PathDelays, config: RadarConfig, num_chirps: int, eps: float,
                    decimate="auto") -> DecimationPlan:
    """Plan the decimation of ``num_chirps`` consecutive chirps at tolerance ``eps``.

    Parameters
    ----------
    src : PathDelays
    config : RadarConfig
    num_chirps : int
        Chirps rendered (the edges of this range get exact margin chirps).
    eps : float
        Error share allowed for interpolation (relative l2).
    decimate : "auto" or int >= 1
        ``"auto"``: of the factors up to :data:`MAX_FACTOR` that meet ``eps``,
        the one with the fewest exact chirps (edge margins included); an
        integer: that factor if it meets ``eps``, else refusal.
    """
    if not (decimate == "auto" or (isinstance(decimate, (int, np.integer))
                                   and not isinstance(decimate, bool) and decimate >= 1)):
        raise ValueError(f"decimate must be 'auto' or an integer >= 1, got {decimate!r}")
    n_local = int(num_chirps)
    if decimate == 1:
        return _refuse(n_local, math.nan, "decimate=1")
    if not isinstance(src, PathDelays):
        return _refuse(n_local, math.nan, "dense delays: no geometry to bound the Doppler band")
    if n_local < MIN_CHIRPS:
        return _refuse(n_local, math.nan, f"too few chirps ({n_local} < {MIN_CHIRPS})")
    if src.amplitude.ndim == 2:
        return _refuse(n_local, math.nan, "amplitudes vary over chirps")
    doppler = doppler_bound(src, config)
    factors = range(2, MAX_FACTOR + 1) if decimate == "auto" else (int(decimate),)
    ok = [d for d in factors if interpolation_error(doppler, d) <= eps]
    if not ok:
        return _refuse(n_local, doppler, f"Doppler band {doppler:.3g} cycles/chirp too wide for "
                       f"factor {factors[0]} at eps={eps:g}")
    def weights_for(d: int):
        err = interpolation_error(doppler, d)
        attenuation = -20.0 * math.log10(max(err, 1e-300)) if err > 1e-9 else \
            _kaiser_attenuation(1.0 - 2.0 * doppler * d)
        return err, _weights(n_local, d, TAPS, min(attenuation, 300.0))

    # the cheapest factor, not the largest: the exact edge margins grow with the factor
    candidates = {d: weights_for(d) for d in ok}
    factor = min(ok, key=lambda d: (candidates[d][1][0].size, -d))
    err, (exact, missing, w) = candidates[factor]
    if missing.size < MIN_SAVING * n_local:
        return _refuse(n_local, doppler, f"only {missing.size} of {n_local} chirps would be "
                       "interpolated (edge margins)")
    return DecimationPlan(factor, exact, missing, w, doppler, err,
                          f"Doppler band {doppler:.3g} cycles/chirp, factor {factor}")


def interpolate(rows: np.ndarray, plan: DecimationPlan, col_block: int = 1 << 16) -> None:
    """Fill ``rows[plan.missing]`` from ``rows[plan.exact]`` in place.

    Parameters
    ----------
    rows : ndarray, shape ``[chirp, ...]``, complex64
        Rendered chirps (local indices), exact rows filled.
    plan : DecimationPlan
    col_block : int
        Columns (float32 values) per matrix product (bounds the temporaries).
    """
    if plan.missing.size == 0:
        return
    if rows.dtype != np.complex64 or not rows.flags.c_contiguous:
        raise ValueError(f"rows must be C-contiguous complex64, got {rows.dtype}")
    flat = rows.reshape(rows.shape[0], -1).view(np.float32)
    for c0 in range(0, flat.shape[1], col_block):
        c1 = min(c0 + col_block, flat.shape[1])
        flat[plan.missing, c0:c1] = plan.weights @ flat[plan.exact, c0:c1]
