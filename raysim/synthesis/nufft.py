"""IF synthesis for many paths with a non-uniform FFT along fast time.

For one chirp ``n`` and one channel ``m`` the stop-and-hop IF samples are a
sum of complex tones (docs/conventions.md)::

    s[n, m, k] = sum_p a[p, n, m] exp(+j 2 pi (f_c tau + mu tau k / f_s - mu tau^2 / 2))

with ``tau = tau[p, n, m]``. Written with the beat frequency in cycles per
sample ``nu = mu tau / f_s`` this is ``sum_p c_p exp(+j k x_p)``, ``x_p = 2 pi nu``:
a type-1 NUFFT from the non-uniform points ``x_p`` to the uniform ``sample``
grid. :func:`synthesize_nufft` evaluates it with FINUFFT for every
``(chirp, channel)`` pair, so each path keeps its *exact* delay at every
channel: near-field curvature, the ``mu tau^2 / 2`` term, the change of beat
frequency across channels and any array layout (TDM slots, irregular
elements) enter exactly. The only approximation is FINUFFT's own, set by
``eps``. See ``docs/speed.md`` for why the array axis is not folded into a
2-D/3-D transform.

Cost per chirp: about ``num_channels * (num_paths * (w + 10) + 2 K log 2K)``
operations, ``w ~ -log10(eps) + 1`` kernel width, against
``num_channels * num_paths * K`` complex multiplies for the tone sum.

:class:`PathDelays` is the compact description of many paths (vertex
positions and lengths, not delays): ``tau[path, chirp, channel]`` is computed
one chirp and one block of channels at a time and never stored whole.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from raysim.radar.config import RadarConfig
from raysim.synthesis.paths import PathDelays, _fresh, element_positions

__all__ = ["MIN_EPS", "BLOCK_BYTES", "PathDelays", "element_positions", "check_eps",
           "check_chirps", "default_threads", "as_source", "dense_blocks", "synthesize_nufft"]

#: Smallest tolerance the NUFFT path accepts: the output is complex64
#: (relative rounding ~6e-8) and strengths are rounded in float32 above 1e-6.
MIN_EPS = 1e-7
#: Working-set target of one (chirp, channel block) of path arrays [bytes].
BLOCK_BYTES = 48 * 2**20
#: Bytes of temporaries per (path, channel) pair inside a channel block.
_BYTES_PER_PAIR = 64


def check_eps(eps: float, *, floor: float = MIN_EPS) -> float:
    """Validate a relative tolerance ``eps`` in ``[floor, 1)``."""
    try:
        value = float(eps)
    except (TypeError, ValueError):
        raise ValueError(f"eps must be a number, got {eps!r}") from None
    if not math.isfinite(value) or not floor <= value < 1.0:
        raise ValueError(f"eps must lie in [{floor:g}, 1), got {eps!r}")
    return value


def check_chirps(chirps, num_chirps: int) -> range:
    """Validate a chirp selection: ``None`` (all) or a step-1 ``range`` inside the frame."""
    if chirps is None:
        return range(num_chirps)
    if (not isinstance(chirps, range) or chirps.step != 1
            or (len(chirps) and (chirps[0] < 0 or chirps[-1] >= num_chirps))):
        raise ValueError(f"chirps must be a step-1 range within [0, {num_chirps}), "
                         f"got {chirps!r}")
    return chirps


def default_threads() -> int:
    """Worker threads used by default: the CPUs this process may run on."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - non-Linux
        return max(1, os.cpu_count() or 1)


class _DenseSource:
    """``tau``/``amplitude`` arrays of shape ``[path, chirp, channel]`` as a block source."""

    def __init__(self, tau, amplitude) -> None:
        tau = np.asarray(tau, dtype=np.float64)
        if tau.ndim != 3 or 0 in tau.shape:
            raise ValueError(f"tau must have shape [path, chirp, channel], got shape {tau.shape}")
        if not np.all(np.isfinite(tau)):
            raise ValueError("tau contains NaN or inf delays")
        amp = np.asarray(amplitude)
        try:
            amp = np.broadcast_to(amp, tau.shape)
        except ValueError:
            raise ValueError(
                f"amplitude shape {amp.shape} does not broadcast to tau shape {tau.shape}"
            ) from None
        if not np.all(np.isfinite(amp)):
            raise ValueError("amplitude contains NaN or inf values")
        self.tau, self.amp = tau, amp
        self.shape = tau.shape

    @property
    def num_paths(self) -> int:
        return self.shape[0]

    @property
    def num_chirps(self) -> int:
        return self.shape[1]

    @property
    def num_channels(self) -> int:
        return self.shape[2]

    def delays(self, chirp: int, channels: slice = slice(None)) -> np.ndarray:
        return np.ascontiguousarray(self.tau[:, chirp, channels].T)

    def _delays(self, chirp: int, channels: slice, alloc) -> np.ndarray:
        return self.delays(chirp, channels)

    def channel_amplitudes(self, chirp: int, channels: slice = slice(None)) -> np.ndarray:
        return self.amp[:, chirp, channels].T

    def select(self, mask: np.ndarray) -> _DenseSource:
        """The paths where ``mask`` [path] is True."""
        return _DenseSource(self.tau[mask], self.amp[mask])

    def channel_subset(self, channels: np.ndarray) -> _DenseSource:
        """The same paths seen by the channels ``channels`` [k] only."""
        idx = np.asarray(channels, dtype=np.int64)
        return _DenseSource(self.tau[:, :, idx], self.amp[:, :, idx])


def as_source(tau, amplitude=None):
    """Wrap ``tau``/``amplitude`` arrays or a :class:`PathDelays` as a block source."""
    if isinstance(tau, PathDelays):
        if amplitude is not None:
            raise ValueError("amplitude must be None when tau is a PathDelays "
                             "(its amplitudes are part of the description)")
        return tau
    if amplitude is None:
        raise ValueError("amplitude is required when tau is an array of delays")
    return _DenseSource(tau, amplitude)


def _block_amplitudes(src, chirp: int, channels: slice) -> np.ndarray:
    """Amplitudes ``[channel, path]`` or ``[1, path]`` (broadcast) of one block."""
    if isinstance(src, PathDelays):
        return src.amplitudes(chirp)[None, :]
    return src.channel_amplitudes(chirp, channels)


def dense_blocks(src, chirps: range, max_elements: int = 2**22
                 ) -> Iterator[tuple[int, slice, np.ndarray, np.ndarray]]:
    """Yield ``(chirp, channels, tau, amplitude)`` with ``tau``/``amplitude`` of
    shape ``[path, 1, channel_block]``, bounded to ``max_elements`` each.

    Used to feed the tone and direct sums from a :class:`PathDelays` without
    materialising ``[path, chirp, channel]``.
    """
    n_path, n_chan = src.num_paths, src.num_channels
    step = max(1, min(n_chan, max_elements // max(n_path, 1)))
    for n in chirps:
        for m0 in range(0, n_chan, step):
            ch = slice(m0, min(m0 + step, n_chan))
            tau = src.delays(n, ch).T[:, None, :]
            amp = np.broadcast_to(_block_amplitudes(src, n, ch).T[:, None, :], tau.shape)
            yield n, ch, tau, amp


# --------------------------------------------------------------------------- NUFFT
class _Worker:
    """One FINUFFT plan and its scratch buffers (one per thread)."""

    def __init__(self, num_samples: int, eps: float) -> None:
        import finufft

        self.plan = finufft.Plan(1, (num_samples,), n_trans=1, eps=eps, isign=1,
                                 dtype="complex128", nthreads=1, spread_sort=0, modeord=0)
        self.buf = np.empty(num_samples, dtype=np.complex128)
        self._scratch: dict[str, np.ndarray] = {}

    def scratch(self, key: str, shape: tuple, dtype=np.float64) -> np.ndarray:
        """A reusable array of ``shape`` for ``key`` (no fresh pages per block)."""
        n = int(np.prod(shape))
        a = self._scratch.get(key)
        if a is None or a.size < n or a.dtype != np.dtype(dtype):
            a = np.empty(n, dtype)
            self._scratch[key] = a
        return a[:n].reshape(shape)


def _strengths(tau: np.ndarray, amp: np.ndarray, config: RadarConfig, exact_trig: bool,
               alloc=_fresh) -> tuple[np.ndarray, np.ndarray]:
    """NUFFT points ``x [channel, path]`` [rad/sample] and strengths ``c [channel, path]``.

    ``x = 2 pi (nu - round(nu))`` with ``nu = mu tau / f_s``, and
    ``c = a exp(j 2 pi (f_c tau - mu tau^2 / 2 + h x / (2 pi)))``, ``h = K // 2``:
    the shift ``h`` maps FINUFFT's centred modes ``j = -h..K-1-h`` to samples
    ``k = j + h``. Phases are reduced in float64 before any rounding.
    """
    fc, mu, fs = config.carrier_frequency, config.chirp_rate, config.sample_rate
    h = config.num_samples // 2
    shape = tau.shape
    tmp = alloc("tmp", shape)
    # f_c tau - mu tau^2 / 2 + h nu = tau (f_c + h mu / f_s - mu tau / 2)  (mod 1: h is integer)
    cyc = np.multiply(tau, -0.5 * mu, out=alloc("cyc", shape))
    cyc += fc + h * mu / fs
    cyc *= tau
    cyc -= np.rint(cyc, out=tmp)                         # [-0.5, 0.5] cycles
    nu = np.multiply(tau, mu / fs, out=alloc("nu", shape))
    nu -= np.rint(nu, out=tmp)                           # wrapped beat [cycles/sample]
    nu *= 2.0 * np.pi
    c = alloc("c", shape, np.complex128)
    if exact_trig:
        np.exp(np.multiply(cyc, 2j * np.pi, out=c), out=c)
    else:
        ph = np.multiply(cyc, 2.0 * np.pi, out=alloc("ph", shape, np.float32),
                         casting="same_kind")
        cs = alloc("cs", shape, np.float32)
        c.real = np.cos(ph, out=cs)
        c.imag = np.sin(ph, out=cs)
    c *= amp
    return nu, c


def _render_group(src, config: RadarConfig, worker: _Worker, chirp: int, channels: range,
                  block: int, exact_trig: bool, out_rows: np.ndarray) -> None:
    """Render chirp ``chirp`` for ``channels`` into ``out_rows[channel - first, sample]``."""
    first = channels.start
    for m0 in range(channels.start, channels.stop, block):
        ch = slice(m0, min(m0 + block, channels.stop))
        tau = src._delays(chirp, ch, worker.scratch)     # [channel, path]
        amp = _block_amplitudes(src, chirp, ch)          # [channel or 1, path]
        x, c = _strengths(tau, amp, config, exact_trig, worker.scratch)
        for i in range(x.shape[0]):
            worker.plan.setpts(x[i])
            worker.plan.execute(c[i], out=worker.buf)
            out_rows[ch.start - first + i] += worker.buf


def synthesize_nufft(tau, amplitude, config: RadarConfig, *, eps: float = 1e-6,
                     out: np.ndarray | None = None, chirps: range | None = None,
                     threads: int | None = None) -> np.ndarray:
    """Sum of IF tones on the ``[chirp, channel, sample]`` grid by 1-D type-1 NUFFTs.

    Parameters
    ----------
    tau : ndarray, shape ``[path, chirp, channel]``, or PathDelays
        Two-way delay of each path at each chirp and channel [s], or the
        compact description from which they are computed block by block.
    amplitude : array_like, broadcastable to ``tau``, or None
        Complex IF amplitude [sqrt(W)] without the propagation phase; ``None``
        when ``tau`` is a :class:`PathDelays`.
    config : RadarConfig
        Waveform (``f_c``, ``mu``, ``f_s``, samples per chirp).
    eps : float
        Requested relative error of the result (l2 over the rendered block),
        in ``[1e-7, 1)``.
    out : ndarray, shape ``[len(chirps), channel, sample]``, complex64, optional
        Buffer to add into (not cleared).
    chirps : range, optional
        Chirps to render (default all); ``out`` holds them in order.
    threads : int, optional
        Worker threads (default: the usable CPUs); channels are split between them.

    Returns
    -------
    ndarray, shape ``[chirp, channel, sample]``, complex64

    Notes
    -----
    Every ``(chirp, channel)`` row is one FINUFFT type-1 transform
    ``f_j = sum_p c_p exp(+i j x_p)``, ``j = -K//2 .. K-1-K//2``, with
    ``x_p = 2 pi mu tau / f_s`` (wrapped to ``[-pi, pi)``) and strengths that
    carry ``a exp(j 2 pi (f_c tau - mu tau^2 / 2))`` and the shift from centred
    modes to samples. FINUFFT's tolerance is relative to the l2 norm of the
    output; the float32 rounding of the strength phase (``eps >= 1e-6``) adds
    at most 2e-7 rad per path. Temporaries are bounded by
    :data:`BLOCK_BYTES` per thread.
    """
    eps = check_eps(eps)
    src = as_source(tau, amplitude)
    n_path, n_chirp, n_chan = src.num_paths, src.num_chirps, src.num_channels
    k = config.num_samples
    chirps = check_chirps(chirps, n_chirp)
    if out is None:
        out = np.zeros((len(chirps), n_chan, k), dtype=np.complex64)
    elif out.shape != (len(chirps), n_chan, k) or out.dtype != np.complex64:
        raise ValueError(f"out must be complex64 of shape {(len(chirps), n_chan, k)}, "
                         f"got {out.dtype} {out.shape}")
    threads = default_threads() if threads is None else int(threads)
    if threads < 1:
        raise ValueError(f"threads must be >= 1, got {threads!r}")
    threads = min(threads, n_chan)
    # the NUFFT error adds to a ~1e-7 floor (float32 phases, complex64 output)
    exact_trig = eps < 1e-6
    nufft_eps = max(0.5 * eps, 1e-14)
    block = max(1, min(n_chan, BLOCK_BYTES // (_BYTES_PER_PAIR * max(n_path, 1))))
    bounds = np.linspace(0, n_chan, threads + 1).round().astype(int)
    groups = [range(bounds[i], bounds[i + 1]) for i in range(threads)]
    workers = [_Worker(k, nufft_eps) for _ in range(threads)]
    acc = np.empty((n_chan, k), dtype=np.complex128)
    pool = ThreadPoolExecutor(threads) if threads > 1 else None
    try:
        for i, n in enumerate(chirps):
            acc[...] = 0.0
            jobs = [(g, w) for g, w in zip(groups, workers, strict=True) if len(g)]
            if pool is None:
                for g, w in jobs:
                    _render_group(src, config, w, n, g, block, exact_trig, acc[g.start:g.stop])
            else:
                futures = [pool.submit(_render_group, src, config, w, n, g, block, exact_trig,
                                       acc[g.start:g.stop]) for g, w in jobs]
                for f in futures:
                    f.result()
            out[i] += acc
    finally:
        if pool is not None:
            pool.shutdown()
    return out
