"""IF synthesis from per-(chirp, channel) two-way delays.

Every echo source (point targets, ray-traced paths) reduces to a set of paths
with a two-way delay ``tau[path, chirp, channel]`` and a complex amplitude.
With stop-and-hop timing the IF samples of one (chirp, channel) are a sum of
complex tones (docs/conventions.md)::

    s[n, m, k] = sum_p a[p, n, m] exp(+j 2 pi (f_c tau + mu tau t_k - mu tau^2 / 2))

Each tone is a geometric sequence in ``k``. We evaluate it with a two-level
split ``k = i * B + b``: ``z^k = (z^B)^i * z^b`` with ``B ~ sqrt(K)``; both
short factor tables are running products in complex128 (rounding ~1e-15,
far below the complex64 output), so one complex64 multiply per output sample
remains. That makes a single-path frame cost about as much
as writing the cube. :func:`synthesize_if_direct` is the plain reference.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from raysim.radar.config import RadarConfig


def _check_paths(tau: np.ndarray, amplitude, config: RadarConfig):
    tau = np.asarray(tau, dtype=np.float64)
    if tau.ndim != 3:
        raise ValueError(f"tau must have shape [path, chirp, channel], got shape {tau.shape}")
    if not np.all(np.isfinite(tau)):
        raise ValueError("tau contains NaN or inf delays")
    amp = np.broadcast_to(np.asarray(amplitude), tau.shape)
    if not np.all(np.isfinite(amp)):
        raise ValueError("amplitude contains NaN or inf values")
    return tau, amp


def _block_size(num_samples: int) -> int:
    # near sqrt(K) minimises the two small factor tables
    b = max(1, int(round(np.sqrt(num_samples))))
    while num_samples % b:
        b -= 1
    return b


def _powers(z: np.ndarray, n: int) -> np.ndarray:
    """``z**[0, 1, ..., n-1]`` along a new last axis, by a complex128 running product.

    ``n`` is about ``sqrt(samples)`` (~25), so the product's rounding stays
    near 1e-15, far below the complex64 output; it replaces ``n`` complex
    exponentials per (chirp, channel) by one.
    """
    out = np.empty(z.shape + (n,), dtype=np.complex128)
    out[..., 0] = 1.0
    out[..., 1:] = z[..., None]
    return np.cumprod(out, axis=-1, out=out)


def synthesize_if(tau: np.ndarray, amplitude, config: RadarConfig, *, out: np.ndarray | None = None,
                  chirp_block: int = 2, workers: int | None = None) -> np.ndarray:
    """Sum of IF tones on the ``[chirp, channel, sample]`` grid (stop-and-hop).

    Parameters
    ----------
    tau : ndarray, shape ``[path, chirp, channel]``
        Two-way delay of each path at each chirp and channel [s].
    amplitude : array_like, broadcastable to ``tau``
        Complex IF amplitude [sqrt(W)], without the propagation phase.
    config : RadarConfig
        Waveform (``f_c``, ``mu``, ``f_s``, samples per chirp).
    out : ndarray, shape ``[chirp, channel, sample]``, complex64, optional
        Buffer to add into (it is *not* cleared); a new one is made if omitted.
    chirp_block : int
        Chirps processed together (bounds the temporaries).
    workers : int, optional
        Threads, each on its own range of chirps (default: all cores).

    Returns
    -------
    ndarray, shape ``[chirp, channel, sample]``, complex64
    """
    tau, amp = _check_paths(tau, amplitude, config)
    n_path, n_chirp, n_chan = tau.shape
    k = config.num_samples
    fresh = out is None and n_path > 0
    if out is None and n_path == 0:
        return np.zeros((n_chirp, n_chan, k), dtype=np.complex64)
    if fresh:
        # written block by block below: np.empty avoids touching every page twice
        out = np.empty((n_chirp, n_chan, k), dtype=np.complex64)
    elif out.shape != (n_chirp, n_chan, k) or out.dtype != np.complex64:
        raise ValueError(
            f"out must be complex64 of shape {(n_chirp, n_chan, k)}, got {out.dtype} {out.shape}"
        )
    fc, mu, fs = config.carrier_frequency, config.chirp_rate, config.sample_rate
    b = _block_size(k)
    nb = k // b
    view = out.reshape(n_chirp, n_chan, nb, b)

    def run(first: int, last: int) -> None:
        # chirps [first, last): disjoint slices of ``out``, so threads never overlap
        scratch = np.empty((min(chirp_block, last - first), n_chan, nb, b), dtype=np.complex64)
        for n0 in range(first, last, chirp_block):
            n1 = min(n0 + chirp_block, last)
            blk = scratch[: n1 - n0]
            for p in range(n_path):
                t = tau[p, n0:n1]                          # [chirp, channel]
                w = (2 * np.pi / fs) * (mu * t)            # beat phase step per sample [rad]
                phase0 = 2 * np.pi * (fc * t - 0.5 * mu * t * t)
                head = _powers(np.exp(1j * w * b), nb)     # z^(i B)
                head *= (amp[p, n0:n1] * np.exp(1j * phase0))[..., None]
                tail = _powers(np.exp(1j * w), b)          # z^b
                target = view[n0:n1] if (fresh and p == 0) else blk
                np.multiply(head.astype(np.complex64)[..., :, None],
                            tail.astype(np.complex64)[..., None, :], out=target)
                if target is blk:
                    view[n0:n1] += blk

    workers = max(1, min(int(workers or os.cpu_count() or 1), n_chirp))
    if workers == 1:
        run(0, n_chirp)
    else:
        # NumPy releases the GIL in its loops: chirp ranges run in parallel
        edges = np.linspace(0, n_chirp, workers + 1).round().astype(int)
        with ThreadPoolExecutor(workers) as pool:
            list(pool.map(run, edges[:-1], edges[1:]))
    return out


def synthesize_if_direct(tau: np.ndarray, amplitude, config: RadarConfig) -> np.ndarray:
    """Reference: the same sum evaluated term by term in complex128.

    Returns
    -------
    ndarray, shape ``[chirp, channel, sample]``, complex128
    """
    tau, amp = _check_paths(tau, amplitude, config)
    fc, mu = config.carrier_frequency, config.chirp_rate
    t = config.fast_time()
    out = np.zeros(tau.shape[1:] + (t.size,), dtype=np.complex128)
    for p in range(tau.shape[0]):
        tp = tau[p][..., None]
        out += amp[p][..., None] * np.exp(2j * np.pi * (fc * tp + mu * tp * t - 0.5 * mu * tp**2))
    return out


def synthesize_if_intrachirp(tau: np.ndarray, amplitude, config: RadarConfig) -> np.ndarray:
    """IF samples when the delay changes within a chirp.

    Parameters
    ----------
    tau : ndarray, shape ``[path, chirp, channel, sample]``
        Two-way delay at every sample instant [s].
    amplitude : array_like, broadcastable to ``tau``
        Complex IF amplitude [sqrt(W)].

    Returns
    -------
    ndarray, shape ``[chirp, channel, sample]``, complex64

    Notes
    -----
    Uses the dechirped phase ``2 pi (f_c tau(t) + mu tau(t) t - mu tau(t)^2 / 2)``
    with the delay evaluated at each sample time, i.e. the echo leaving the
    target at ``t - tau``; the delay's own change over ``tau`` (~1e-7 s) is
    neglected.
    """
    tau = np.asarray(tau, dtype=np.float64)
    if tau.ndim != 4 or tau.shape[-1] != config.num_samples:
        raise ValueError(
            f"tau must have shape [path, chirp, channel, {config.num_samples}], got {tau.shape}"
        )
    amp = np.broadcast_to(np.asarray(amplitude), tau.shape)
    fc, mu = config.carrier_frequency, config.chirp_rate
    t = config.fast_time()
    out = np.zeros(tau.shape[1:], dtype=np.complex64)
    for p in range(tau.shape[0]):
        tp = tau[p]
        out += (amp[p] * np.exp(2j * np.pi * (fc * tp + mu * tp * t - 0.5 * mu * tp**2))
                ).astype(np.complex64)
    return out
