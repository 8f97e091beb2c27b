"""Slow-time band of paths given as arrays of delays (point targets, the flight).

:mod:`raysim.synthesis.decimate` bounds the band of a :class:`PathDelays` from
its geometry (element motion, vertices, velocities). Arrays of delays
``tau [path, chirp, channel]`` carry no geometry, but they hold every path's
two-way length ``D = c tau`` at every chirp and channel, which is what that
bound is made of: here it is read from ``D`` itself, per path and channel,

* instantaneous frequency: ``(max |D[n+1] - D[n]| + max |second difference|) /
  lambda_min`` (``lambda_min`` at the top of the sweep, the beat term
  ``mu tau`` included);
* sidebands of the fast part: the residual of ``D`` after its best quadratic
  over the chirps as a sinusoidal phase modulation (peak deviation and
  modulating frequency as :func:`raysim.synthesis.decimate._modulation`), its
  Bessel lines out to :func:`~raysim.synthesis.decimate.sideband_order` at
  ``SIDEBAND_SHARE tol``;
* amplitudes that vary over chirps: :func:`~raysim.synthesis.decimate.amplitude_band`
  of each channel's row;

the path's bound is the largest over its channels. The a-posteriori check of
:func:`raysim.synthesis.select.render_checked` then measures the interpolation
as for compact paths.
"""

from __future__ import annotations

import numpy as np

from raysim.radar.config import RadarConfig
from raysim.synthesis.decimate import (
    SIDEBAND_SHARE,
    SLOW_DEGREE,
    amplitude_band,
    sideband_order,
    spread_channels,
)

__all__ = ["dense_doppler", "dense_check_channels", "DENSE_BLOCK_ELEMENTS"]

#: Elements ``[path, chirp, channel]`` of the delays processed at a time (bounds the
#: float64 temporaries of the quadratic fit to a few times 64 MiB).
DENSE_BLOCK_ELEMENTS = 2**23


def _top_frequency(tau: np.ndarray, config: RadarConfig) -> float:
    """Largest slow-time phase rate per unit delay [Hz]: the top of the sweep plus the beat
    term ``mu tau`` of ``-mu tau^2 / 2``."""
    f_top = config.carrier_frequency + config.chirp_rate * config.num_samples / config.sample_rate
    return f_top + abs(config.chirp_rate) * float(np.max(np.abs(tau), initial=0.0))


def _orders(beta: np.ndarray, tol: float) -> np.ndarray:
    """``sideband_order(beta, SIDEBAND_SHARE tol)`` of every ``beta`` [rad], with ``beta``
    rounded up to a grid of 2^(1/4) steps so that a few orders serve every path."""
    grid = np.zeros(beta.shape)
    live = beta > 0
    grid[live] = 2.0 ** (np.ceil(4.0 * np.log2(beta[live])) / 4.0)
    keys, inverse = np.unique(grid, return_inverse=True)
    orders = np.array([sideband_order(k, SIDEBAND_SHARE * tol) if k > 0 else 0 for k in keys])
    return orders[inverse.reshape(-1)].reshape(beta.shape)


def _block_band(tau: np.ndarray, amp: np.ndarray, f_top: float, tol: float | None
                ) -> np.ndarray:
    """Band [cycles per chirp] of a block ``tau``/``amp`` ``[path, chirp, channel]``, ``[path]``."""
    n_path, n, n_ch = tau.shape
    cycles = np.swapaxes(tau, 1, 2) * f_top                    # [path, channel, chirp] [cycles]
    d1 = np.diff(cycles, axis=-1)
    band = np.abs(d1).max(axis=-1)
    if n >= 3:
        band += np.abs(np.diff(d1, axis=-1)).max(axis=-1)
    if tol is not None and n >= 4:
        basis = np.polynomial.legendre.legvander(np.linspace(-1.0, 1.0, n),
                                                 min(SLOW_DEGREE, n - 2))
        r = cycles - (cycles @ np.linalg.pinv(basis).T) @ basis.T
        r1 = np.diff(r, axis=-1)
        s1 = np.abs(r1).max(axis=-1)
        s2 = np.abs(np.diff(r1, axis=-1)).max(axis=-1)
        w = np.minimum(np.where(s1 > 0, s2 / (2.0 * np.pi * np.where(s1 > 0, s1, 1.0)), 0.0),
                       0.5)
        band += _orders(2.0 * np.pi * np.abs(r).max(axis=-1), tol) * w
    a = np.swapaxes(amp, 1, 2).reshape(n_path * n_ch, n)
    if np.any(a != a[:, :1]):
        band += amplitude_band(a, tol).reshape(n_path, n_ch)
    return band.max(axis=-1)


def dense_doppler(tau: np.ndarray, amplitude: np.ndarray, config: RadarConfig,
                  tol: float | None = None) -> np.ndarray:
    """Bound of the slow-time frequency of each path of arrays of delays [cycles per chirp].

    Parameters
    ----------
    tau : ndarray, shape ``[path, chirp, channel]``
        Two-way delays [s].
    amplitude : ndarray, same shape
        Complex amplitudes (broadcast views are fine).
    config : RadarConfig
    tol : float, optional
        Interpolation tolerance: adds the sideband margins (module docstring).

    Returns
    -------
    ndarray, shape ``[path]``
    """
    tau, amp = np.asarray(tau), np.broadcast_to(amplitude, np.shape(tau))
    f_top = _top_frequency(tau, config)
    step = max(1, DENSE_BLOCK_ELEMENTS // max(1, tau.shape[1] * tau.shape[2]))
    out = np.zeros(tau.shape[0])
    for p0 in range(0, tau.shape[0], step):
        sl = slice(p0, p0 + step)
        out[sl] = _block_band(tau[sl], np.asarray(amp[sl]), f_top, tol)
    return out


def dense_check_channels(tau: np.ndarray, count: int) -> np.ndarray:
    """Channels the a-posteriori check renders, shape ``[k]`` (increasing): the channel
    whose two-way lengths vary fastest (largest second difference over chirps, summed
    over paths), then the first and the last, then evenly spaced ones."""
    tau = np.asarray(tau)
    n_ch = tau.shape[2]
    count = max(1, min(int(count), n_ch))
    if tau.shape[1] >= 3:
        wiggle = np.abs(np.diff(tau, n=2, axis=1)).max(axis=1).sum(axis=0)     # [channel]
    else:
        wiggle = np.zeros(n_ch)
    return spread_channels(int(np.argmax(wiggle)), n_ch, count)
