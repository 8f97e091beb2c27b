"""IF synthesis by the fused kernel written once in Dr.Jit (CUDA where a GPU is present, else LLVM).

The same algorithm as :mod:`raysim.synthesis.kernel` (the C++ extension), as one
Dr.Jit kernel per chirp over every ``(channel, path)`` pair:

* the exact delay ``tau = (|x_tx - v_f(t)| + L + |v_l(t) - x_rx|) / c`` in
  float64 (near field; moving scatterers at the channel's transmit instant);
* the phase ``f_c tau - mu tau^2 / 2 + h nu`` reduced modulo one cycle in
  float64 and the strength ``a exp(j 2 pi phase)`` (Dr.Jit's float64 sin/cos);
* the spreading of that strength at ``nu = mu tau / f_s`` (cycles per sample,
  wrapped) onto the oversampled grid of ``nf`` points with ``w`` taps of the
  exponential-of-semicircle kernel, evaluated exactly (no polynomial fit), by
  ``dr.scatter_reduce(dr.ReduceOp.Add, ...)`` into a float64 grid.

The FFT over the grids and the deconvolution then run in NumPy (``scipy.fft``),
or in CuPy when the CUDA backend is used and CuPy is installed. The design
(width, grid size, deconvolution) is :func:`raysim.synthesis.kernel.kernel_error`
with a float64 grid, so the error model is the same: kernel truncation
``10^(1-w)`` + complex64 output rounding.
"""

from __future__ import annotations

import importlib

import numpy as np

from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.kernel import KERNEL_MIN_EPS, kernel_error
from raysim.synthesis.nufft import check_chirps, check_eps
from raysim.synthesis.paths import PathDelays

__all__ = ["available", "backend", "synthesize_drjit", "MAX_PAIRS"]

#: Most (channel, path) pairs traced in one launch (bounds the gathered inputs).
MAX_PAIRS = 1 << 24


def available() -> bool:
    """Whether Dr.Jit imports and has a usable CUDA or LLVM backend."""
    try:
        import drjit as dr
    except ImportError:
        return False
    return bool(dr.has_backend(dr.JitBackend.CUDA) or dr.has_backend(dr.JitBackend.LLVM))


def backend() -> str:
    """``"cuda"`` where a GPU and driver are present, else ``"llvm"``; ``"missing"``
    without Dr.Jit."""
    if not available():
        return "missing"
    import drjit as dr

    return "cuda" if dr.has_backend(dr.JitBackend.CUDA) else "llvm"


def _types(name: str):
    mod = importlib.import_module(f"drjit.{name}")
    return mod.Float64, mod.UInt32


def _spread_chirp(T, src: PathDelays, n: int, design, consts, grid, ch0: int, ch1: int):
    """Scatter the strengths of channels ``ch0:ch1`` of chirp ``n`` into ``grid``
    (Dr.Jit Float64 of size ``2 * (ch1 - ch0) * nf``, re/im interleaved)."""
    import drjit as dr

    F, U = T
    p_n, m_n = src.num_paths, ch1 - ch0
    nf, w, beta = design.grid_size, design.width, design.beta
    t_ref, inv_c, a_coef, half_mu, beat = consts

    def col(a, i=None):                      # one float64 column as a Dr.Jit array
        return F(np.ascontiguousarray(a if i is None else a[:, i], dtype=np.float64))

    fv = src.first_vertex if src.first_vertex.ndim == 2 else src.first_vertex[:, n]
    lv = src.last_vertex if src.last_vertex.ndim == 2 else src.last_vertex[:, n]
    length = src.interior_length if src.interior_length.ndim == 1 \
        else src.interior_length[:, n]
    amp = src.amplitudes(n)
    vel = np.zeros((p_n, 3)) if src.velocity is None else src.velocity
    tx = src.tx_positions[n, ch0:ch1]
    rx = tx if src.rx_positions is None else src.rx_positions[n, ch0:ch1]
    dt = np.zeros(m_n) if src.element_times is None \
        else src.element_times[n, ch0:ch1] - t_ref

    idx = dr.arange(U, p_n * m_n)
    m = idx // p_n
    p = idx - m * p_n
    g = dr.gather
    dtm = g(F, col(dt), m)
    d1 = F(0.0)
    d2 = F(0.0)
    for i in range(3):
        v_i = g(F, col(vel, i), p) * dtm
        e1 = g(F, col(tx, i), m) - (g(F, col(fv, i), p) + v_i)
        e2 = g(F, col(rx, i), m) - (g(F, col(lv, i), p) + v_i)
        d1 = dr.fma(e1, e1, d1)
        d2 = dr.fma(e2, e2, d2)
    tau = (dr.sqrt(d1) + g(F, col(length), p) + dr.sqrt(d2)) * inv_c
    cyc = tau * (a_coef - half_mu * tau)
    cyc = cyc - dr.floor(cyc + 0.5)                  # [-1/2, 1/2] cycles
    nu = tau * beat
    nu = nu - dr.floor(nu + 0.5)                     # cycles per sample
    s, c = dr.sincos(2.0 * np.pi * cyc)
    ar, ai = g(F, col(amp.real), p), g(F, col(amp.imag), p)
    re = ar * c - ai * s
    im = ar * s + ai * c
    x = nu * nf                                       # position on the grid [points]
    left = dr.ceil(x - 0.5 * w)
    base = U(m) * (2 * nf)
    for k in range(w):
        pos = left + k
        z = (pos - x) * (2.0 / w)
        phi = dr.exp(beta * (dr.sqrt(dr.maximum(1.0 - z * z, 0.0)) - 1.0))
        phi = dr.select(z * z < 1.0, phi, 0.0)
        cell = U(pos - nf * dr.floor(pos * (1.0 / nf)))   # periodic grid (exact integers)
        dr.scatter_reduce(dr.ReduceOp.Add, grid, re * phi, base + 2 * cell)
        dr.scatter_reduce(dr.ReduceOp.Add, grid, im * phi, base + 2 * cell + 1)
    dr.eval(grid)


def synthesize_drjit(src: PathDelays, config: RadarConfig, *, eps: float = 1e-6,
                     out: np.ndarray | None = None, chirps: range | None = None,
                     use: str | None = None) -> np.ndarray:
    """Sum of IF tones on the ``[chirp, channel, sample]`` grid by the Dr.Jit kernel.

    Parameters
    ----------
    src : PathDelays
        Compact paths.
    config : RadarConfig
    eps : float
        Requested relative l2 error, in ``[1e-7, 1)``.
    out : ndarray, shape ``[len(chirps), channel, sample]``, complex64, optional
        Buffer to add into.
    chirps : range, optional
        Chirps to render (default all).
    use : {"cuda", "llvm"}, optional
        Dr.Jit backend (default: :func:`backend`).

    Returns
    -------
    ndarray, shape ``[chirp, channel, sample]``, complex64
    """
    import scipy.fft

    if not isinstance(src, PathDelays):
        raise ValueError(f"the Dr.Jit kernel needs a PathDelays, got {type(src).__name__}")
    use = backend() if use is None else use
    if use not in ("cuda", "llvm"):
        raise ValueError(f"use must be 'cuda' or 'llvm' (Dr.Jit backends), got {use!r}")
    if not available():
        raise RuntimeError("Dr.Jit with a CUDA or LLVM backend is needed for method='drjit'")
    eps = check_eps(eps, floor=KERNEL_MIN_EPS)
    chirps = check_chirps(chirps, src.num_chirps)
    n_chan, k = src.num_channels, config.num_samples
    shape = (len(chirps), n_chan, k)
    if out is None:
        out = np.zeros(shape, dtype=np.complex64)
    elif out.shape != shape or out.dtype != np.complex64:
        raise ValueError(f"out must be complex64 of shape {shape}, got {out.dtype} {out.shape}")
    if src.num_paths == 0 or len(chirps) == 0:
        return out
    _, design = kernel_error(src.num_paths, eps, k, double_grid=True)
    T = _types(use)
    fc, mu, fs = config.carrier_frequency, config.chirp_rate, config.sample_rate
    h = k // 2
    consts = (src.reference_time, 1.0 / SPEED_OF_LIGHT, fc + h * mu / fs, 0.5 * mu, mu / fs)
    nf = design.grid_size
    modes = (np.arange(k) - h) % nf
    step = max(1, min(n_chan, MAX_PAIRS // src.num_paths))
    for i, n in enumerate(chirps):
        for c0 in range(0, n_chan, step):
            c1 = min(n_chan, c0 + step)
            grid = T[0](np.zeros(2 * (c1 - c0) * nf))
            _spread_chirp(T, src, n, design, consts, grid, c0, c1)
            g = _fft_rows(grid, c1 - c0, nf, use, scipy.fft)
            out[i, c0:c1] += (g[:, modes] * design.deconv).astype(np.complex64)
    return out


def _fft_rows(grid, rows: int, nf: int, use: str, sfft) -> np.ndarray:
    """``ifft`` (forward-normalised) of the ``[rows, nf]`` complex grids, as NumPy."""
    if use == "cuda":
        try:
            import cupy as cp
        except ImportError:
            cp = None
        if cp is not None:                  # stay on the GPU for the transform
            arr = cp.asarray(grid).reshape(rows, nf, 2)
            spec = cp.fft.ifft(arr[..., 0] + 1j * arr[..., 1], axis=-1, norm="forward")
            return cp.asnumpy(spec)
    arr = np.asarray(grid.numpy()).reshape(rows, nf, 2)
    return sfft.ifft(arr[..., 0] + 1j * arr[..., 1], axis=-1, norm="forward")
