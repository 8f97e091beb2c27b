"""One entry point for IF synthesis that picks the fastest adequate method.

Three ways to evaluate the same stop-and-hop tone sum
``s[n, m, k] = sum_p a exp(+j 2 pi (f_c tau + mu tau t_k - mu tau^2 / 2))``:

``"direct"``
    :func:`raysim.synthesis.tones.synthesize_if_direct`, term by term in complex128:
    the reference, exact to rounding, ~22 ns per (path, chirp, channel, sample).
``"tones"``
    :func:`raysim.synthesis.tones.synthesize_if`, exact tones accumulated in complex64,
    ~4 ns per term: one complex multiply per output sample per path. The
    complex64 accumulation limits its relative error to about
    ``2e-7 + 2e-8 sqrt(paths)`` (:func:`tones_error`; 6e-6 at 1e5 paths).
``"nufft"``
    :func:`raysim.synthesis.nufft.synthesize_nufft`, one FINUFFT type-1
    transform per (chirp, channel), ~42 ns per (path, chirp, channel) plus
    ~40 us per (chirp, channel) on one thread; error set by ``eps``.

``"kernel"``
    :func:`raysim.synthesis.kernel.synthesize_kernel`, the fused exact kernel
    (compiled extension; :class:`PathDelays` input only): ~20 ns per (path,
    chirp, channel) on one thread at ``eps = 1e-5``; error model
    :func:`raysim.synthesis.kernel.kernel_error`.

``"drjit"``
    :func:`raysim.synthesis.drjit_kernel.synthesize_drjit`, the same kernel written
    in Dr.Jit (CUDA where a GPU is present, else LLVM; :class:`PathDelays` only;
    float64 grid, same error model). ``"auto"`` picks it for compact paths where a
    CUDA device is present (:data:`GPU_MIN_PATHS` paths or more), never on the
    CPU, where the C++ kernel is about 11x faster; ``decimate`` does not apply to it.

``method="auto"`` picks ``"direct"`` when ``eps < 1e-6`` (below what complex64
output carries) and otherwise the cheapest of ``"tones"`` (only where
:func:`tones_error` is below ``eps``), ``"kernel"`` (only for a
:class:`PathDelays`, when the extension is built and its modelled error is
below ``eps``) and ``"nufft"`` by the cost model :func:`estimate_seconds`; the
tone sum wins for a handful of paths, the kernel (else the NUFFT) from about
20 paths per frame on the paper radar. Without the extension ``auto`` falls
back to FINUFFT.

``decimate`` (``"auto"`` or an integer) computes exact rows on a subset of the
chirps only (every D-th one, plus a few near the edges) and interpolates the
others along slow time (:mod:`raysim.synthesis.decimate`); with ``"auto"`` the
paths are split by their own Doppler bound (static scatterers, whose band is
set by the platform's motion alone, get a much larger factor than moving
clutter). It applies to ``"kernel"`` and ``"nufft"``, and to ``"tones"`` for arrays
of delays (whose band is read from the delays themselves:
:mod:`raysim.synthesis.dense_decimation`), and is refused (every chirp exact) where
its assumptions fail.
"""

from __future__ import annotations

from typing import Literal

import numpy as np

from raysim.radar.config import RadarConfig
from raysim.synthesis.kernel import KERNEL_MIN_EPS
from raysim.synthesis.nufft import (
    MIN_EPS,
    PathDelays,
    as_source,
    check_chirps,
    check_eps,
    dense_blocks,
    synthesize_nufft,
)
from raysim.synthesis.tones import synthesize_if, synthesize_if_direct

#: Paths from which ``"auto"`` hands compact paths to the Dr.Jit kernel on a CUDA device
#: (below it the tone sum or the CPU kernel are quicker than a GPU launch).
GPU_MIN_PATHS = 1000

Method = Literal["auto", "nufft", "tones", "direct", "kernel", "drjit"]
METHODS = ("auto", "nufft", "tones", "direct", "kernel", "drjit")

#: Cost-model constants [s], measured on 2 cores (see docs/speed.md).
COST_DIRECT_PER_TERM = 22e-9
COST_TONES_PER_TERM = 3.8e-9
COST_NUFFT_PER_PAIR = 42e-9
COST_NUFFT_PER_ROW = 40e-6
#: Fused kernel, one thread, at width 7 (eps = 1e-5) [s per (path, row)] and per row (FFT).
COST_KERNEL_PER_PAIR = 20e-9
COST_KERNEL_PER_ROW = 15e-6
#: Share of ``eps`` given to slow-time interpolation when decimating.
DECIMATION_EPS_SHARE = 0.1
#: FINUFFT tolerance of the a-posteriori check's rows where the frame's rows are tone sums.
CHECK_NUFFT_EPS = 1e-7
#: Tolerance below which only the complex128 direct sum qualifies.
DIRECT_BELOW_EPS = 1e-6


class DecimationRefused(UserWarning):
    """``decimate="auto"`` rendered every chirp exactly; the message says why."""


#: Kinds of refusal already reported by :func:`say_refused` in this process.
_SAID: set = set()


def check_decimate(decimate) -> str | int:
    """``decimate`` as ``"auto"`` or an integer factor (``"off"`` is 1); ValueError otherwise."""
    if decimate == "off":
        return 1
    if decimate == "auto" or (isinstance(decimate, (int, np.integer))
                              and not isinstance(decimate, bool) and decimate >= 1):
        return decimate if decimate == "auto" else int(decimate)
    raise ValueError(f"decimate must be 'auto', 'off' or an integer >= 1, got {decimate!r}")


def check_decimate_tolerance(tolerance, eps: float, name: str = "decimate_tolerance") -> float:
    """The interpolation tolerance: ``tolerance``, or ``DECIMATION_EPS_SHARE * eps`` if None.

    Raises ValueError naming ``name`` unless it is a number in ``(0, 0.1]`` (relative error).
    """
    if tolerance is None:
        return DECIMATION_EPS_SHARE * float(eps)
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float, np.floating)) \
            or not 0 < float(tolerance) <= 0.1:
        raise ValueError(f"{name} must be a relative error in (0, 0.1], got {tolerance!r}")
    return float(tolerance)


def say_refused(report: list[dict]) -> str | None:
    """Warn (:class:`DecimationRefused`) once per kind of reason when every group of a
    decimation ``report`` was refused (factor 1); returns the reason, or None."""
    import re
    import warnings

    if not report or any(g["factor"] > 1 for g in report):
        return None
    reason = "; ".join(dict.fromkeys(str(g["reason"]) for g in report if g["reason"]))
    kind = re.sub(r"[-+.\deE]*\d[-+.\deE]*", "#", reason)
    if kind not in _SAID:
        _SAID.add(kind)
        warnings.warn(f"slow-time decimation refused, every chirp rendered exactly: {reason}",
                      DecimationRefused, stacklevel=3)
    return reason


def tones_error(num_paths: int) -> float:
    """Relative l2 error of the complex64 tone sum with ``num_paths`` paths (model).

    ``2e-7 + 2e-8 sqrt(num_paths)``: per-term complex64 rounding plus the
    random-walk growth of the complex64 accumulator (measured 3e-7 at 50
    paths, 5.9e-6 at 1e5 paths against the complex128 direct sum).
    """
    return 2e-7 + 2e-8 * float(np.sqrt(max(int(num_paths), 1)))


def estimate_seconds(method: str, num_paths: int, num_chirps: int, num_channels: int,
                     num_samples: int, eps: float = 1e-6) -> float:
    """Predicted single-thread synthesis time of one block [s].

    Parameters
    ----------
    method : {"direct", "tones", "nufft", "kernel"}
    num_paths, num_chirps, num_channels, num_samples : int
        Extent of the work ``[path, chirp, channel, sample]``.
    eps : float
        Requested tolerance (sets the NUFFT kernel width).
    """
    terms = float(num_paths) * num_chirps * num_channels * num_samples
    if method == "direct":
        return COST_DIRECT_PER_TERM * terms
    if method == "tones":
        return COST_TONES_PER_TERM * terms
    if method == "nufft":
        width = min(16.0, max(2.0, 1.0 - np.log10(0.5 * eps)))
        rows = float(num_chirps) * num_channels
        return rows * (COST_NUFFT_PER_ROW * (num_samples / 600.0)
                       + COST_NUFFT_PER_PAIR * (0.45 + 0.55 * width / 7.3) * num_paths)
    if method == "kernel":
        from raysim.synthesis.kernel import kernel_error

        width = kernel_error(num_paths, max(eps, KERNEL_MIN_EPS), num_samples)[1].width
        rows = float(num_chirps) * num_channels
        return rows * (COST_KERNEL_PER_ROW * (num_samples / 600.0)
                       + COST_KERNEL_PER_PAIR * (0.5 + 0.5 * width / 7.0) * num_paths)
    raise ValueError("method must be one of ('direct', 'tones', 'nufft', 'kernel'), "
                     f"got {method!r}")


def kernel_qualifies(num_paths: int, num_samples: int, eps: float) -> bool:
    """Whether the fused kernel is built and its modelled error is below ``eps``."""
    from raysim.synthesis import kernel

    return (kernel.available() and eps >= KERNEL_MIN_EPS
            and kernel.kernel_error(num_paths, eps, num_samples)[0] <= eps)


def choose_method(num_paths: int, num_chirps: int, num_channels: int, num_samples: int,
                  eps: float = 1e-6, *, compact: bool = True) -> str:
    """The method ``method="auto"`` uses for this problem size and tolerance.

    Parameters
    ----------
    num_paths, num_chirps, num_channels, num_samples : int
    eps : float
    compact : bool
        The paths are a :class:`PathDelays` (the kernel needs their geometry).

    Returns
    -------
    str
        ``"direct"`` if ``eps < 1e-6``; ``"drjit"`` for compact paths on a CUDA
        device (:data:`GPU_MIN_PATHS` or more); else the cheapest of ``"tones"``,
        ``"kernel"`` and ``"nufft"`` by :func:`estimate_seconds` (tones only
        where :func:`tones_error` is below ``eps``; the kernel only when
        :func:`kernel_qualifies`).
    """
    eps = check_eps(eps, floor=np.finfo(float).eps)
    if eps < DIRECT_BELOW_EPS:
        return "direct"
    if compact and num_paths >= GPU_MIN_PATHS:
        from raysim.synthesis.drjit_kernel import backend

        if backend() == "cuda":
            return "drjit"
    candidates = ("tones", "nufft") if tones_error(num_paths) <= eps else ("nufft",)
    if compact and kernel_qualifies(num_paths, num_samples, eps):
        candidates += ("kernel",)
    cost = {m: estimate_seconds(m, num_paths, num_chirps, num_channels, num_samples, eps)
            for m in candidates}
    return min(cost, key=cost.get)


def synthesize(tau, amplitude, config: RadarConfig, *, method: Method = "auto",
               eps: float = 1e-6, out: np.ndarray | None = None,
               chirps: range | None = None, threads: int | None = None,
               decimate: str | int = 1, decimate_tolerance: float | None = None,
               decimation_report: list | None = None) -> np.ndarray:
    """IF samples of many paths on the ``[chirp, channel, sample]`` grid.

    Parameters
    ----------
    tau : ndarray, shape ``[path, chirp, channel]``, or PathDelays
        Two-way delays [s], or a compact :class:`~raysim.synthesis.nufft.PathDelays`
        (vertices and lengths; delays are computed per chirp and channel block,
        never stored whole). Point targets and ray-traced paths use the same call.
    amplitude : array_like, broadcastable to ``tau``, or None
        Complex IF amplitudes [sqrt(W)] without the propagation phase;
        ``None`` with a ``PathDelays``.
    config : RadarConfig
    method : {"auto", "nufft", "tones", "direct", "kernel", "drjit"}
        See the module docstring.
    eps : float
        Requested relative l2 error of the result. ``"nufft"`` needs
        ``eps >= 1e-7``; ``"tones"`` needs ``eps >= tones_error(paths)``.
    out : ndarray, shape ``[len(chirps), channel, sample]``, optional
        Buffer to add into (complex64; complex128 for ``"direct"``).
    chirps : range, optional
        Chirps to render (default all).
    threads : int, optional
        Threads for the NUFFT and the kernel (default: usable CPUs).
    decimate : "auto", "off" or int, default 1
        Slow-time decimation factor for ``"kernel"`` and ``"nufft"`` (and ``"tones"``
        for arrays of delays)
        (:func:`raysim.synthesis.decimate.plan_groups`; the row method gets
        ``(1 - DECIMATION_EPS_SHARE) eps``). ``1`` or ``"off"`` renders every
        chirp exactly; refused (every chirp exact) where its assumptions fail.
        The interpolation is checked after the fact on a few channels rendered
        at every chirp (:func:`render_checked`): the factor is halved until the
        measured error (relative l2 and worst chirp row) is within
        ``decimate_tolerance``, or decimation is refused. When ``"auto"`` is
        refused for every path, a :class:`DecimationRefused` warning says why
        (once per kind of reason and process) and every chirp is rendered exactly.
    decimate_tolerance : float, optional
        Relative l2 error, and worst chirp row, of the interpolation against
        the undecimated render; default ``DECIMATION_EPS_SHARE * eps``.
    decimation_report : list, optional
        Receives one dict per path group of the decimation (factor, band,
        exact chirps, measured check errors, reason).

    Returns
    -------
    ndarray, shape ``[chirp, channel, sample]``
        complex64, or complex128 for ``"direct"``.

    Examples
    --------
    >>> import numpy as np
    >>> from raysim.radar.config import RadarConfig
    >>> cfg = RadarConfig(num_chirps=2, chirp_duration=6e-6)
    >>> tau = np.full((3, 2, 4), 2 * 10.0 / 299_792_458.0)
    >>> synthesize(tau, 1.0, cfg, method="nufft", eps=1e-6).shape
    (2, 4, 60)
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    eps = check_eps(eps, floor=np.finfo(float).eps)
    decimate = check_decimate(decimate)
    tol = check_decimate_tolerance(decimate_tolerance, eps)
    src = as_source(tau, amplitude)
    n_chirp = src.num_chirps
    chirps = check_chirps(chirps, n_chirp)
    if method == "auto":
        method = choose_method(src.num_paths, len(chirps), src.num_channels,
                               config.num_samples, eps, compact=isinstance(src, PathDelays))
    if method == "drjit":
        from raysim.synthesis.drjit_kernel import synthesize_drjit

        if not isinstance(src, PathDelays):
            raise ValueError("method 'drjit' needs a PathDelays (it computes the delays from "
                             "the geometry); use method='nufft' for arrays of delays")
        return synthesize_drjit(src, config, eps=eps, out=out, chirps=chirps)
    if method == "kernel" and not isinstance(src, PathDelays):
        raise ValueError("method 'kernel' needs a PathDelays (it computes the delays from the "
                         "geometry); use method='nufft' for arrays of delays")
    if method == "kernel" and not kernel_qualifies(src.num_paths, config.num_samples,
                                                   max(eps, KERNEL_MIN_EPS)):
        raise ValueError(f"method 'kernel' is not available here (extension not built) or "
                         f"cannot reach eps={eps!r}; use method='nufft' or 'direct'")
    if method in ("nufft", "tones", "kernel") and eps < MIN_EPS:
        raise ValueError(f"eps={eps!r} is below the complex64 floor {MIN_EPS:g} of "
                         f"method {method!r}; use method='direct'")
    if method == "tones" and eps < tones_error(src.num_paths):
        raise ValueError(f"eps={eps!r} is below the {tones_error(src.num_paths):.1e} that "
                         f"method 'tones' reaches with {src.num_paths} paths (complex64 "
                         f"accumulation); use method='nufft' or 'direct'")
    # decimation needs its row share of eps to stay above the methods' floor; the tone sum
    # only for arrays of delays (their band is read from the delays themselves)
    decimable = method in ("nufft", "kernel") or (method == "tones"
                                                  and not isinstance(src, PathDelays))
    if decimable and decimate != 1 and \
            (1.0 - DECIMATION_EPS_SHARE) * eps >= MIN_EPS:
        rows_eps = (1.0 - DECIMATION_EPS_SHARE) * eps
        shape = (len(chirps), src.num_channels, config.num_samples)
        if out is not None and (out.shape != shape or out.dtype != np.complex64):
            raise ValueError(f"out must be complex64 of shape {shape}, "
                             f"got {out.dtype} {out.shape}")
        target = out if out is not None and out.flags.c_contiguous \
            else np.zeros(shape, dtype=np.complex64)

        def render(part, chirp_list, rows, check=False):
            _render_chirps(part, config, method, rows_eps, chirp_list, rows, threads,
                           double_grid=check or None)

        report = [] if decimation_report is None else decimation_report
        start = len(report)
        done = render_checked(src, config, chirps, tol, decimate, render, target, report=report)
        if decimate == "auto":
            say_refused(report[start:])
        if done:
            if out is None or target is out:
                return target
            out += target
            return out
    if method == "kernel":
        from raysim.synthesis.kernel import synthesize_kernel

        return synthesize_kernel(src, config, eps=eps, out=out, chirps=chirps, threads=threads)
    if method == "nufft":
        return synthesize_nufft(src if isinstance(src, PathDelays) else src.tau,
                                None if isinstance(src, PathDelays) else src.amp,
                                config, eps=eps, out=out, chirps=chirps, threads=threads)
    dtype = np.complex128 if method == "direct" else np.complex64
    shape = (len(chirps), src.num_channels, config.num_samples)
    if out is None:
        out = np.zeros(shape, dtype=dtype)
    elif out.shape != shape or out.dtype != dtype:
        raise ValueError(f"out must be {np.dtype(dtype)} of shape {shape}, "
                         f"got {out.dtype} {out.shape}")
    if not isinstance(src, PathDelays) and len(chirps) == n_chirp:
        if method == "tones":
            return synthesize_if(src.tau, src.amp, config, out=out)
        out += synthesize_if_direct(src.tau, src.amp, config)
        return out
    first = chirps.start if len(chirps) else 0
    for n, ch, tau_b, amp_b in dense_blocks(src, chirps):
        row = out[n - first: n - first + 1, ch]
        if method == "tones":
            block = np.zeros(row.shape, dtype=np.complex64)
            synthesize_if(tau_b, amp_b, config, out=block)
            row += block
        else:
            row += synthesize_if_direct(tau_b, amp_b, config)
    return out


def _render_chirps(src, config: RadarConfig, method: str, eps: float, chirp_list: np.ndarray,
                   rows: np.ndarray, threads: int | None,
                   double_grid: bool | None = None) -> None:
    """Render the chirps ``chirp_list`` (increasing) into ``rows[i]`` (complex64, added).

    ``double_grid=True`` accumulates the kernel's grid in float64 (the a-posteriori
    check's rows: the float32 grid's rounding differs from row to row, so it does not
    interpolate, and with many paths it reaches the interpolation's share of ``eps``).
    """
    if method == "tones" and not double_grid:       # arrays of delays (see synthesize)
        synthesize_if(src.tau[:, chirp_list], src.amp[:, chirp_list], config, out=rows)
        return
    if method == "tones":
        # the check's rows: the tone sum's complex64 accumulation differs from row to row
        # (tones_error) and does not interpolate; FINUFFT at a tight eps does not
        eps = CHECK_NUFFT_EPS
    if method == "kernel":
        from raysim.synthesis.kernel import kernel_error, render_rows

        design = kernel_error(src.num_paths, eps, config.num_samples, double_grid)[1]
        render_rows(src, config, design, chirp_list, rows, threads=threads)
        return
    i = 0
    while i < chirp_list.size:                     # FINUFFT: one call per run of chirps
        j = i
        while j + 1 < chirp_list.size and chirp_list[j + 1] == chirp_list[j] + 1:
            j += 1
        run = range(int(chirp_list[i]), int(chirp_list[j]) + 1)
        synthesize_nufft(src if isinstance(src, PathDelays) else src.tau,
                         None if isinstance(src, PathDelays) else src.amp, config, eps=eps,
                         out=rows[i:j + 1], chirps=run, threads=threads)
        i = j + 1


def _fit_group(plan, full: np.ndarray, n_local: int, eps: float):
    """Halve ``plan`` until interpolating ``full`` [chirp, k, sample] from its exact rows
    meets ``eps`` (relative l2 and worst row). Returns ``(plan, prediction, (l2, row))``."""
    from raysim.synthesis.decimate import check_errors, halve, scatter_add

    while plan.factor > 1:
        pred = np.zeros_like(full)
        scatter_add(pred, np.ascontiguousarray(full[plan.exact]), plan)
        l2, row = check_errors(pred, full)
        if l2 <= eps and row <= eps:
            return plan, pred, (l2, row)
        plan = halve(plan, n_local, eps, f"l2 {l2:.2g}, worst row {row:.2g} at factor "
                      f"{plan.factor} > {eps:g}")
    return plan, full.copy(), (0.0, 0.0)


def render_checked(src: PathDelays, config: RadarConfig, chirps: range, eps: float, decimate,
                   render, target: np.ndarray, report: list | None = None) -> bool:
    """Decimated render whose interpolation error is measured, not only modelled.

    1. :func:`~raysim.synthesis.decimate.plan_groups` at ``eps`` (a-priori bound:
       Doppler plus sidebands).
    2. Every decimated group renders the :func:`~raysim.synthesis.decimate.check_channels` at
       every chirp; its plan is interpolated there and compared
       (:func:`~raysim.synthesis.decimate.check_errors`, relative l2 and worst chirp
       row against the group's own signal); while either exceeds ``eps`` the
       factor is halved (band doubled), down to refusal (every chirp exact).
    3. The same on the sum of the groups: the group with the largest error is halved
       until the total meets ``eps``.
    4. The exact rows of every group on all channels, interpolated into ``target``.

    The check costs the check channels' share of an undecimated frame (about
    :data:`~raysim.synthesis.decimate.CHECK_SHARE`).

    Parameters
    ----------
    src : PathDelays, or arrays of delays (``as_source``)
        The paths; the band of arrays of delays is read from them
        (:func:`~raysim.synthesis.dense_decimation.dense_doppler`).
    config : RadarConfig
    chirps : range
        Chirps rendered (``target[i]`` is chirp ``chirps[i]``).
    eps : float
        Tolerance of the interpolation (relative l2 and worst chirp row).
    decimate : "auto" or int >= 1
    render : callable ``(part: PathDelays, chirp_list: ndarray[int], rows: ndarray, check=False)``
        Adds the rows of the absolute chirps ``chirp_list`` into ``rows`` ``[len, channel,
        sample]`` (complex64) with the undecimated method; ``check=True`` for the check
        channels, which it renders without row-to-row rounding noise where the method
        has any (the fused kernel's float32 grid: a float64 grid there), so that the
        check measures the interpolation and not the rows' own rounding.
    target : ndarray, shape ``[len(chirps), channel, sample]``, complex64, C-contiguous
        Receives the result (added).
    report : list, optional
        Receives one dict per group: ``paths, factor, band, exact_chirps, check_l2,
        check_row, reason``.

    Returns
    -------
    bool
        False where every group was refused before any rendering (nothing added:
        render the usual way); True when ``target`` holds the result.
    """
    n_local = len(chirps)
    from raysim.synthesis.decimate import (
        CHECK_SHARE,
        MAX_CHECK_CHANNELS,
        channel_subset,
        check_channels,
        check_errors,
        halve,
        plan_groups,
        scatter_add,
    )

    compact = isinstance(src, PathDelays)
    bound = None
    if not compact and decimate != 1 and n_local and src.num_paths:
        from raysim.synthesis.dense_decimation import dense_doppler

        run = slice(chirps.start, chirps.stop)
        bound = dense_doppler(src.tau[:, run], src.amp[:, run], config, eps)
    groups = plan_groups(src, config, n_local, eps, decimate, bound=bound)
    if all(plan.factor == 1 for _, plan in groups):
        if report is not None:
            report.extend({"paths": int(m.size), "factor": 1, "band": p.doppler,
                           "exact_chirps": n_local, "check_l2": 0.0, "check_row": 0.0,
                           "reason": p.reason} for m, p in groups)
        return False
    if compact:
        chk = check_channels(src)
    else:
        from raysim.synthesis.dense_decimation import dense_check_channels

        chk = dense_check_channels(src.tau[:, chirps.start:chirps.stop], min(
            MAX_CHECK_CHANNELS, max(1, int(round(CHECK_SHARE * src.num_channels)))))
    every = chirps.start + np.arange(n_local)
    shape = (n_local, chk.size, target.shape[2])
    state = []
    for members, plan in groups:
        part = src
        if members.size < src.num_paths:
            mask = np.zeros(src.num_paths, bool)
            mask[members] = True
            part = src.select(mask)
        full = np.zeros(shape, np.complex64)
        if plan.factor == 1:                       # exact anyway: nothing to check
            state.append([members, part, plan, full, full, (0.0, 0.0)])
            continue
        render(channel_subset(part, chk) if compact else part.channel_subset(chk), every, full,
               check=True)
        plan, pred, errs = _fit_group(plan, full, n_local, eps)
        state.append([members, part, plan, full, pred, errs])
    while True:
        full_sum = sum(s[3] for s in state)
        pred_sum = sum(s[4] for s in state)
        l2, row = check_errors(pred_sum, full_sum)
        if (l2 <= eps and row <= eps) or all(s[2].factor == 1 for s in state):
            break
        worst = max((s for s in state if s[2].factor > 1),
                    key=lambda s: float(np.linalg.norm(s[4] - s[3])))
        plan = halve(worst[2], n_local, eps, f"sum of groups: l2 {l2:.2g}, worst row "
                      f"{row:.2g} > {eps:g}")
        worst[2], worst[4], worst[5] = _fit_group(plan, worst[3], n_local, eps)
    for members, part, plan, _, _, errs in state:
        if plan.factor == 1:
            render(part, every, target)
        else:
            exact = np.zeros((plan.exact.size,) + target.shape[1:], np.complex64)
            render(part, chirps.start + plan.exact, exact)
            scatter_add(target, exact, plan)
            del exact
        if report is not None:
            report.append({"paths": int(members.size), "factor": int(plan.factor),
                           "band": float(plan.doppler), "exact_chirps": int(plan.exact.size),
                           "check_l2": errs[0], "check_row": errs[1], "reason": plan.reason})
    return True
