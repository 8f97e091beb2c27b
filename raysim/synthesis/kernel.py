"""IF synthesis by the fused exact kernel (compiled extension), with its error model.

For every ``(chirp, channel)`` row and every path, the C++ extension
``raysim.synthesis._kernel._ext`` computes in one pass (no per-path NumPy
temporaries):

* the exact delay from the :class:`~raysim.synthesis.paths.PathDelays`
  geometry, ``tau = (|x_tx - v_f(t)| + L + |v_l(t) - x_rx|) / c`` in float64
  (square roots; near field; moving scatterers at the channel's transmit
  instant ``t``, so TDM slots are exact);
* the phase ``f_c tau - mu tau^2 / 2 + h nu`` reduced modulo one cycle in
  float64 (``h = K // 2``, ``nu = mu tau / f_s``), and its sin/cos by a float64
  polynomial (error < 1e-11) times the amplitude: the same strengths
  :func:`raysim.synthesis.nufft._strengths` gives FINUFFT;
* the spreading of that strength at ``x = 2 pi (nu - round(nu))`` onto an
  oversampled grid of ``nf >= 2 K`` points with the exponential-of-semicircle
  kernel ``exp(beta (sqrt(1 - (2 z / w)^2) - 1))`` (width ``w`` from the
  tolerance, evaluated by a per-tap polynomial), accumulated in float32
  (float64 where the tolerance needs it).

Python then runs a batched FFT (``scipy.fft``) over the grids and divides the
modes ``-h .. K-1-h`` by the kernel's Fourier transform (deconvolution). Rows
are split between OpenMP threads; the kernel has an AVX2+FMA copy chosen at
run time and a portable (x86-64-v2) copy.

Error budget (relative l2 of the result), :func:`kernel_error`:
spreading-kernel truncation (``10^(1-w)``, FINUFFT's rule for oversampling 2)
+ polynomial kernel fit (measured in float32 at design time) + float32 grid
accumulation (``1e-7 sqrt(1 + paths w / nf)``, measured) + complex64 output
(6e-8). The grid is float64 when the float32 terms would exceed a third of
``eps``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.nufft import check_chirps, check_eps, default_threads
from raysim.synthesis.paths import PathDelays

__all__ = ["available", "isa", "KernelDesign", "kernel_error", "synthesize_kernel",
           "render_rows", "KERNEL_MIN_EPS"]

try:  # the compiled extension is optional: FINUFFT is the fallback
    from raysim.synthesis._kernel import _ext
except ImportError:  # pragma: no cover - depends on the build
    _ext = None

#: Smallest tolerance the kernel accepts (complex64 output rounding, float64 grid).
KERNEL_MIN_EPS = 1e-7
#: Largest kernel width [grid points].
MAX_WIDTH = 16
#: Working-set target of one chirp block of grids [bytes].
GRID_BYTES = 64 * 2**20
#: Relative rounding of the float32 grid per sqrt(term per cell) (measured, see kernel_error).
GRID32_ROUNDING = 1e-7
#: complex64 output rounding.
OUTPUT_ROUNDING = 6e-8


def available() -> bool:
    """Whether the compiled kernel is importable."""
    return _ext is not None


def isa() -> str:
    """Instruction set the kernel uses here: ``"avx2"``, ``"portable"`` or ``"missing"``."""
    return "missing" if _ext is None else _ext.isa()


def _nice_size(n: int) -> int:
    """Smallest even integer >= n whose only prime factors are 2, 3 and 5."""
    m = max(2, int(n) + (int(n) % 2))
    while True:
        r = m
        for p in (2, 3, 5):
            while r % p == 0:
                r //= p
        if r == 1:
            return m
        m += 2


@dataclass(frozen=True)
class KernelDesign:
    """Spreading kernel and grid for one tolerance and frame.

    Attributes
    ----------
    width : int
        Kernel width ``w`` [grid points].
    beta : float
        Exponential-of-semicircle shape parameter (``2.30 w``).
    grid_size : int
        Oversampled grid ``nf`` (>= 2 * samples, 2-3-5 smooth).
    coef : ndarray, shape ``[degree + 1, width]``
        Power-series coefficients (lowest first) of each tap's kernel value in
        ``s = 2 t - 1``, ``t`` in ``[0, 1)`` the fractional grid offset.
    fit_error : float
        Largest float32 Horner error of the taps against the exact kernel.
    deconv : ndarray, shape ``[samples]``, float64
        ``1 / phi_hat(k - h)`` for output sample ``k`` (``h = samples // 2``).
    double_grid : bool
        Accumulate in float64 (else float32).
    """

    width: int
    beta: float
    grid_size: int
    coef: np.ndarray
    fit_error: float
    deconv: np.ndarray
    double_grid: bool


def _es(z: np.ndarray, width: int, beta: float) -> np.ndarray:
    a = 1.0 - (2.0 * z / width) ** 2
    return np.where(a > 0.0, np.exp(beta * (np.sqrt(np.clip(a, 0.0, None)) - 1.0)), 0.0)


@lru_cache(maxsize=32)
def _kernel_tables(width: int, num_samples: int, grid_size: int):
    beta = 2.30 * width
    s = np.cos(np.pi * (np.arange(400) + 0.5) / 400)        # Chebyshev nodes in [-1, 1]
    t = 0.5 * (s + 1.0)
    taps = _es(width / 2 - t[:, None] - np.arange(width)[None, :], width, beta)
    s_check = np.linspace(-1.0, 1.0, 2001)
    t_check = 0.5 * (s_check + 1.0)
    exact = _es(width / 2 - t_check[:, None] - np.arange(width)[None, :], width, beta)
    best = None
    for degree in range(width + 1, width + 10):
        cheb = np.polynomial.chebyshev.chebfit(s, taps, degree)          # [degree + 1, width]
        coef = np.stack([np.polynomial.chebyshev.cheb2poly(cheb[:, i]) for i in range(width)],
                        axis=1)
        # float32 Horner, as the kernel does it
        c32 = coef.astype(np.float32)
        s32 = s_check.astype(np.float32)[:, None]
        val = np.broadcast_to(c32[-1], (s32.shape[0], width)).astype(np.float32)
        for d in range(degree - 1, -1, -1):
            val = val * s32 + c32[d]
        err = float(np.abs(val.astype(np.float64) - exact).max())
        if best is None or err < best[1]:
            best = (coef, err)
        if err < 10.0 ** (-width - 1) or err < 2e-7:
            break
    coef, err = best
    # phi_hat(j) = int phi(z) cos(2 pi j z / nf) dz (Gauss-Legendre)
    x, wq = np.polynomial.legendre.leggauss(4 * width + 40)
    z = 0.5 * width * x
    phi = _es(z, width, beta) * wq * 0.5 * width
    h = num_samples // 2
    j = np.arange(num_samples) - h
    phat = np.cos(2.0 * np.pi * np.outer(j, z) / grid_size) @ phi
    return beta, coef, err, 1.0 / phat


def kernel_error(num_paths: int, eps: float, num_samples: int,
                 double_grid: bool | None = None) -> tuple[float, KernelDesign]:
    """Modelled relative l2 error of the kernel method and the design that reaches it.

    Parameters
    ----------
    num_paths : int
        Paths summed per row.
    eps : float
        Requested relative tolerance.
    num_samples : int
        Samples per chirp ``K``.
    double_grid : bool, optional
        Force the grid precision (default: float32 unless it would not meet ``eps``).

    Returns
    -------
    (error, design) : (float, KernelDesign)
    """
    eps = check_eps(eps, floor=KERNEL_MIN_EPS)
    width = int(min(MAX_WIDTH, max(2, math.ceil(-math.log10(eps / 3.0 / 10.0)))))
    nf = _nice_size(2 * int(num_samples))
    beta, coef, fit, deconv = _kernel_tables(width, int(num_samples), nf)
    spread = 10.0 ** (1 - width)
    grid32 = GRID32_ROUNDING * math.sqrt(1.0 + num_paths * width / nf)
    if double_grid is None:
        double_grid = fit + grid32 > eps / 3.0
    if double_grid:
        # float64 grid: tap polynomial in float64 (the fit itself, ~1e-12 of the peak)
        fit, grid32 = 10.0 ** (-width - 1), 0.0
    err = spread + fit + grid32 + OUTPUT_ROUNDING
    return err, KernelDesign(width, beta, nf, coef, fit, deconv, bool(double_grid))


# --------------------------------------------------------------------------- rendering
def _classes(src: PathDelays) -> tuple[np.ndarray, int, int, int]:
    """Path order ``twin | static | moving`` and the class sizes.

    ``twin``: monostatic-equivalent array and ``first_vertex == last_vertex`` at every
    chirp (one square root per pair); ``moving``: non-zero velocity.
    """
    n = src.num_paths
    moving = np.zeros(n, bool) if src.velocity is None else np.any(src.velocity != 0, axis=1)
    if src.rx_positions is None:
        f, v = src.first_vertex, src.last_vertex
        if f.ndim != v.ndim:                       # [path, 3] against [path, chirp, 3]
            f, v = (a[:, None, :] if a.ndim == 2 else a for a in (f, v))
        twin = (f == v).reshape(n, -1).all(axis=1) & ~moving
    else:
        twin = np.zeros(n, bool)
    static = ~twin & ~moving
    order = np.concatenate([np.flatnonzero(twin), np.flatnonzero(static),
                            np.flatnonzero(moving)])
    return order, int(twin.sum()), int(static.sum()), int(moving.sum())


def _soa(v: np.ndarray, order: np.ndarray, chirps: np.ndarray) -> list[np.ndarray]:
    """Coordinates of ``v`` ([path, 3] or [path, chirp, 3]) as contiguous ``[B or 1, path]``."""
    if v.ndim == 2:
        return [np.ascontiguousarray(v[order, i])[None, :] for i in range(3)]
    sub = v[order[:, None], chirps]                             # [path, B, 3], block only
    return [np.ascontiguousarray(sub[:, :, i].T) for i in range(3)]


def _per_chirp(v: np.ndarray, order: np.ndarray, chirps: np.ndarray) -> np.ndarray:
    """``[path]`` or ``[path, chirp]`` values as contiguous ``[B or 1, path]``."""
    if v.ndim == 1:
        return np.ascontiguousarray(v[order])[None, :]
    return np.ascontiguousarray(v[order[:, None], chirps].T)


def render_rows(src: PathDelays, config: RadarConfig, design: KernelDesign,
                chirp_list, out: np.ndarray, *, threads: int | None = None,
                portable: bool = False) -> np.ndarray:
    """Add the IF rows of the chirps ``chirp_list`` into ``out`` (complex64).

    Parameters
    ----------
    src : PathDelays
    config : RadarConfig
    design : KernelDesign
        From :func:`kernel_error`.
    chirp_list : sequence of int, length ``R``
        Chirp indices (any order, within the frame).
    out : ndarray, shape ``[R, channel, sample]``, complex64
        ``out[i]`` receives chirp ``chirp_list[i]`` (added).
    threads : int, optional
        OpenMP threads (default: the usable CPUs) for spreading and FFTs.
    portable : bool
        Use the portable copy of the kernel even where AVX2 is available.
    """
    import scipy.fft

    if _ext is None:
        raise RuntimeError("the compiled kernel raysim.synthesis._kernel._ext is not built; "
                           "run `pip install -e .` (needs a C++ compiler with OpenMP)")
    chirp_list = np.asarray(chirp_list, dtype=np.int64).reshape(-1)
    n_chan, k = src.num_channels, config.num_samples
    if out.shape != (chirp_list.size, n_chan, k) or out.dtype != np.complex64:
        raise ValueError(f"out must be complex64 of shape {(chirp_list.size, n_chan, k)}, "
                         f"got {out.dtype} {out.shape}")
    threads = default_threads() if threads is None else int(threads)
    if threads < 1:
        raise ValueError(f"threads must be >= 1, got {threads!r}")
    if chirp_list.size == 0 or src.num_paths == 0:
        return out
    order, n_twin, n_static, n_moving = _classes(src)
    nf, w = design.grid_size, design.width
    gdtype = np.complex128 if design.double_grid else np.complex64
    block = int(max(1, min(chirp_list.size,
                           GRID_BYTES // (n_chan * nf * np.dtype(gdtype).itemsize))))
    coef = np.ascontiguousarray(design.coef, dtype=np.float64)
    fc, mu, fs = config.carrier_frequency, config.chirp_rate, config.sample_rate
    h = k // 2
    dbls = np.array([src.reference_time, 1.0 / SPEED_OF_LIGHT, fc + h * mu / fs, 0.5 * mu,
                     mu / fs], dtype=np.float64)
    zeros = np.zeros((1, 1))
    vel = [np.ascontiguousarray(src.velocity[order, i]) for i in range(3)] \
        if src.velocity is not None else [zeros] * 3
    fv, lv = src.first_vertex, src.last_vertex
    per_chirp = fv.ndim == 3 or lv.ndim == 3
    if per_chirp:                                  # one stride for both vertex sets
        fv, lv = (np.broadcast_to(v[:, None, :], (v.shape[0], src.num_chirps, 3))
                  if v.ndim == 2 else v for v in (fv, lv))
    modes = (np.arange(k) - h) % nf
    deconv = design.deconv.astype(np.float32 if gdtype == np.complex64 else np.float64)
    for b0 in range(0, chirp_list.size, block):
        cb = chirp_list[b0:b0 + block]
        nb = cb.size
        first = _soa(fv, order, cb)
        last = _soa(lv, order, cb)
        length = _per_chirp(src.interior_length, order, cb)
        amp = _per_chirp(src.amplitude, order, cb)
        ar, ai = np.ascontiguousarray(amp.real), np.ascontiguousarray(amp.imag)
        tx = np.ascontiguousarray(src.tx_positions[cb])
        rx = tx if src.rx_positions is None else np.ascontiguousarray(src.rx_positions[cb])
        times = zeros if src.element_times is None \
            else np.ascontiguousarray(src.element_times[cb])
        if n_moving and src.element_times is None:  # pragma: no cover - PathDelays forbids it
            raise ValueError("moving paths need element_times")
        grid = np.zeros((nb, n_chan, nf), dtype=gdtype)
        ints = np.array([n_twin, n_static, n_moving, n_chan, nb, nf, w, coef.shape[0] - 1,
                         threads, int(design.double_grid),
                         src.num_paths if per_chirp else 0,
                         src.num_paths if length.shape[0] > 1 else 0,
                         src.num_paths if amp.shape[0] > 1 else 0], dtype=np.int64)
        arrays = (*first, *last, length, ar, ai, *vel, times, tx, rx, coef, grid)
        ptrs = np.array([a.ctypes.data for a in arrays], dtype=np.uint64)
        _ext.spread(ints.ctypes.data, ptrs.ctypes.data, dbls.ctypes.data, int(bool(portable)))
        spec = scipy.fft.ifft(grid, axis=-1, norm="forward", workers=threads, overwrite_x=True)
        res = spec[..., modes]
        res *= deconv
        out[b0:b0 + nb] += res
    return out


def synthesize_kernel(src: PathDelays, config: RadarConfig, *, eps: float = 1e-6,
                      out: np.ndarray | None = None, chirps: range | None = None,
                      threads: int | None = None, portable: bool = False) -> np.ndarray:
    """Sum of IF tones on the ``[chirp, channel, sample]`` grid by the fused kernel.

    Parameters
    ----------
    src : PathDelays
        Compact paths (dense delay arrays are not supported: use FINUFFT).
    config : RadarConfig
    eps : float
        Requested relative l2 error, in ``[1e-7, 1)``.
    out : ndarray, shape ``[len(chirps), channel, sample]``, complex64, optional
        Buffer to add into.
    chirps : range, optional
        Chirps to render (default all).
    threads : int, optional
        Threads (default: the usable CPUs).
    portable : bool
        Force the portable (non-AVX2) copy of the kernel.

    Returns
    -------
    ndarray, shape ``[chirp, channel, sample]``, complex64
    """
    if not isinstance(src, PathDelays):
        raise ValueError(f"the kernel needs a PathDelays, got {type(src).__name__}")
    eps = check_eps(eps, floor=KERNEL_MIN_EPS)
    chirps = check_chirps(chirps, src.num_chirps)
    shape = (len(chirps), src.num_channels, config.num_samples)
    if out is None:
        out = np.zeros(shape, dtype=np.complex64)
    elif out.shape != shape or out.dtype != np.complex64:
        raise ValueError(f"out must be complex64 of shape {shape}, got {out.dtype} {out.shape}")
    _, design = kernel_error(src.num_paths, eps, config.num_samples)
    return render_rows(src, config, design, np.arange(chirps.start, chirps.stop), out,
                       threads=threads, portable=portable)
