"""Pieces of the ``synthesis_1e5`` benchmark: the decimated whole frame, its error, the
slow-time interpolation before/after, FINUFFT's upsampling factor.

Every function takes the clock (``timer``: ``time.process_time`` for CPU seconds of
the process, all threads, or ``time.perf_counter`` for wall seconds) from its
caller (:mod:`raysim.bench.suite`), so that one ``--clock`` applies to the whole run.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable

import numpy as np

from raysim.radar.config import RadarConfig
from raysim.synthesis.nufft import PathDelays

__all__ = ["whole_frame", "interpolation_ratio", "finufft_upsampfac"]

#: Interleaved rounds of the interpolation and upsampling-factor comparisons.
ROUNDS = 5
#: Channels whose whole slow time the decimated frame is compared on, undecimated.
CHECK_CHANNELS = (0, 210)


def whole_frame(pd: PathDelays, cfg: RadarConfig, eps: float, threads: int,
                timer: Callable[[], float]) -> dict:
    """One whole decimated frame, ``synthesize(method="kernel", decimate="auto")``, timed,
    and its error on every chirp of :data:`CHECK_CHANNELS`: against the undecimated
    kernel at the row tolerance on a float64 grid (the interpolation's share,
    ``DECIMATION_EPS_SHARE * eps``), and against the usual float32-grid render (which
    adds both renders' rounding).

    Returns
    -------
    dict
        ``s_per_frame`` (planning, a-posteriori check, exact rows, interpolation),
        ``groups`` (the decimation report), ``exact_work_fraction``, ``frame_error``
        (the check's largest errors and the frame's against both references).
    """
    from raysim.synthesis.decimate import channel_subset, check_errors
    from raysim.synthesis.select import DECIMATION_EPS_SHARE, _render_chirps, synthesize

    report: list = []
    t0 = timer()
    cube = synthesize(pd, None, cfg, method="kernel", eps=eps, threads=threads,
                      decimate="auto", decimation_report=report)
    seconds = timer() - t0
    ch = np.array([c for c in CHECK_CHANNELS if c < pd.num_channels])
    got = np.ascontiguousarray(cube[:, ch])
    del cube
    part = channel_subset(pd, ch)
    rows_eps = (1 - DECIMATION_EPS_SHARE) * eps
    exact = np.zeros_like(got)                     # float64 grid: no row-to-row rounding
    _render_chirps(part, cfg, "kernel", rows_eps, np.arange(cfg.num_chirps), exact, threads,
                   double_grid=True)
    l2, row = check_errors(got, exact)
    plain = synthesize(part, None, cfg, method="kernel", eps=rows_eps, threads=threads)
    l2_32, row_32 = check_errors(got, plain)
    work = sum(g["paths"] * g["exact_chirps"] for g in report) / (pd.num_paths * cfg.num_chirps)
    checks = [(g["check_l2"], g["check_row"]) for g in report if g["factor"] > 1]
    return {"s_per_frame": seconds, "groups": report, "exact_work_fraction": work,
            "frame_error": {
                "channels": ch.tolist(), "chirps": cfg.num_chirps,
                "interpolation_tolerance": DECIMATION_EPS_SHARE * eps,
                "check_l2_max": max((c[0] for c in checks), default=0.0),
                "check_row_max": max((c[1] for c in checks), default=0.0),
                "vs_float64_grid": {"l2": l2, "worst_row": row},
                "vs_float32_grid": {"l2": l2_32, "worst_row": row_32},
                "note": ("check_*: the a-posteriori check (float64-grid check channels, "
                         "interpolation alone); vs_float64_grid: the frame against the "
                         "undecimated kernel at the row tolerance on a float64 grid "
                         "(interpolation plus the float32-grid rounding of the frame's exact "
                         "rows); vs_float32_grid: against the usual undecimated render (also "
                         "its own rounding)")}}


def interpolation_ratio(plans: list, n_chirp: int, num_samples: int, num_channels: int,
                        timer: Callable[[], float], channels: int = 100) -> dict:
    """Slow-time interpolation of every group's plan: whole weight matrix (before) against
    the banded, in-place form (after), on the same exact rows of ``channels`` channels.

    The two alternate within each of :data:`ROUNDS` rounds; the median and range per form
    are scaled to ``num_channels`` channels (the cost is proportional to the columns).
    The results agree to float32 rounding (``max_relative_difference``).
    """
    from raysim.synthesis.decimate import check_errors
    from raysim.synthesis.slowtime import scatter_add, scatter_add_dense

    rng = np.random.default_rng(0)
    shape = (channels, num_samples)
    exact = [(rng.normal(size=(p.exact.size,) + shape)
              + 1j * rng.normal(size=(p.exact.size,) + shape)).astype(np.complex64)
             for p in plans]
    outs = {name: np.zeros((n_chirp,) + shape, np.complex64) for name in ("before", "after")}
    forms = {"before": scatter_add_dense, "after": scatter_add}
    times: dict = {name: [] for name in forms}
    for _ in range(ROUNDS):
        for name, fn in forms.items():
            outs[name][...] = 0
            t0 = timer()
            for p, rows in zip(plans, exact, strict=True):
                fn(outs[name], rows, p)
            times[name].append((timer() - t0) * num_channels / channels)
    diff = check_errors(outs["after"], outs["before"])[0]
    med = {name: float(np.median(t)) for name, t in times.items()}
    return {"before_s_per_frame": med["before"], "after_s_per_frame": med["after"],
            "before_range_s": [min(times["before"]), max(times["before"])],
            "after_range_s": [min(times["after"]), max(times["after"])],
            "ratio_before_over_after": med["before"] / med["after"] if med["after"] else math.nan,
            "rounds_interleaved": ROUNDS, "timed_on_channels": channels,
            "max_relative_difference": diff,
            "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "OpenBLAS default"),
            "before": "whole [missing, exact] float32 matrix product, fancy-indexed rows",
            "after": "runs of chirps sharing their taps, [run, taps] products into a "
                     "reused buffer, added in place"}


def finufft_upsampfac(pd: PathDelays, cfg: RadarConfig, eps: float, rows: int,
                      timer: Callable[[], float]) -> dict:
    """FINUFFT time per row with ``upsampfac`` 2.0 and 1.25 on the same points.

    The two settings alternate within each of :data:`ROUNDS` rounds (best of the
    rounds per setting), so that a change of machine load hits both alike.
    """
    import finufft

    from raysim.synthesis.nufft import _strengths

    tau = pd.delays(0, slice(0, rows))
    x, c = _strengths(tau, pd.amplitudes(0)[None, :], cfg, eps < 1e-6)
    buf = np.empty(cfg.num_samples, np.complex128)
    runs = {}
    for up in (2.0, 1.25):
        plan = finufft.Plan(1, (cfg.num_samples,), n_trans=1, eps=0.5 * eps, isign=1,
                            dtype="complex128", nthreads=1, spread_sort=0, modeord=0,
                            upsampfac=up)

        def go(plan=plan):
            for i in range(rows):
                plan.setpts(x[i])
                plan.execute(c[i], out=buf)

        go()                                            # warm-up
        runs[up] = go
    best = {up: math.inf for up in runs}
    for _ in range(ROUNDS):
        for up, go in runs.items():
            t0 = timer()
            go()
            best[up] = min(best[up], timer() - t0)
    res = {f"s_per_row_upsampfac_{up}": t / rows for up, t in best.items()}
    res["ratio_2_over_1.25"] = res["s_per_row_upsampfac_2.0"] / res["s_per_row_upsampfac_1.25"]
    res["paths_per_row"] = pd.num_paths
    res["repeats_interleaved"] = ROUNDS
    return res
