"""Speed and memory benchmarks of synthesis, the oracle and the processing chains.

:func:`run` measures, in one process (plus one child process for memory):

``synthesis_1e5``
    The fused kernel with slow-time decimation (whole frame rendered) against
    FINUFFT for 1e5 hover paths on the paper frame with hover jitter, same threads
    (1) and clock, errors against the complex128 direct sum and the undecimated
    kernel (:func:`bench_synthesis_1e5`).
``synthesis``
    NUFFT against the direct sum (complex128 reference) and the tone sum
    (complex64) for 10, 1e3, 1e4, 1e5 paths on the paper frame (256 chirps x
    400 channels x 600 samples), at matched accuracy: each NUFFT tolerance's
    measured error against the direct sum is reported next to its time. Slow
    methods run on a subset of chirps and channels and are extrapolated
    linearly in ``chirp * channel`` (their cost is exactly proportional); each
    row says which subset was measured.
``memory``
    A 1e5-path paper frame rendered by :func:`raysim.synthesis.streaming.render_frames`
    in a child process (progress bar on stderr); peak resident memory from
    ``getrusage(RUSAGE_SELF).ru_maxrss`` against the frame cube size.
``oracle``
    :func:`raysim.echoes.oracle.simulate_point_targets` on the paper frame with 1 and 10
    targets, against the floor (allocate and write the cube; also given with
    a range FFT, which adds two more cube allocations) and against a naive
    NumPy synthesis (``np.exp`` over the whole cube in complex128, once per
    target, one thread), in wall and CPU seconds.
``processing``
    Bare FFT chain (range + Doppler FFT) against compensation + processing
    (:func:`compensation.paper_chain`), if the ``compensation`` package is present.
``realtime_compensation``
    A TI-size TDM frame (128 chirps x 12 channels x 256 samples, 61 x 61
    grid) compensated exactly and processed: frames per second against the
    frame rate, wall clock, threads, what is included
    (:mod:`raysim.bench.realtime`).
``realtime``
    The same frame as a stream a radar delivers: 200 consecutive raw IF frames
    replayed at the frame rate through :class:`compensation.RealtimeStream`
    (range transform of the gated bins, strapdown, projection); p50/p95/p99
    of each frame's latency and service time per gated-cell count (1, 3, 8),
    the stages apart, and what the paper frame needs
    (:func:`raysim.bench.realtime.bench_stream`).
``time_split``
    Where the time of one 1e5-path NUFFT frame goes (geometry, strengths,
    transforms, accumulation), and of one oracle frame.
``reprojection``
    :func:`raysim.echoes.rt.reproject.reproject` (dense delays) against
    :meth:`raysim.synthesis.nufft.PathDelays.from_pathset` (compact), if present.

Timings are CPU seconds of the process (all threads) unless ``--clock wall``;
``oracle`` and ``realtime_compensation`` give wall and CPU seconds side by
side. The machine's load average is recorded at start and end because other
processes share the cores.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from raysim.bench.workloads import hover_paths, paper_setup, subset
from raysim.io import files
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.nufft import PathDelays, default_threads

SCHEMA = "raysim.bench.suite/1"
#: Path counts of the synthesis table.
PATH_COUNTS = (10, 1_000, 10_000, 100_000)
#: NUFFT tolerances timed for every path count.
BENCH_EPS = (1e-5, 1e-6)
#: Clock of every timing: CPU seconds of this process, all threads, by default
#: (on a shared machine wall time mostly measures the other users' load);
#: :func:`set_clock` switches to wall time, which is what a user waits on an
#: idle machine (multi-threaded steps look faster there).
TIMER = time.process_time
#: Seed of the hover jitter added to the paper motion in ``synthesis_1e5``.
JITTER_SEED = 7
CLOCKS = {"cpu": time.process_time, "wall": time.perf_counter}


def set_clock(name: str) -> None:
    """Time benchmarks in CPU seconds (``"cpu"``) or wall seconds (``"wall"``)."""
    global TIMER
    if name not in CLOCKS:
        raise ValueError(f"clock must be one of {sorted(CLOCKS)}, got {name!r}")
    TIMER = CLOCKS[name]


def _clock(fn: Callable[[], object], repeat: int = 1) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = TIMER()
        fn()
        best = min(best, TIMER() - t0)
    return float(best)


def _timed(fn: Callable, *args, **kwargs) -> tuple[float, object]:
    t0 = TIMER()
    result = fn(*args, **kwargs)
    return TIMER() - t0, result


def _rel(x: np.ndarray, ref: np.ndarray) -> float:
    return float(np.linalg.norm(x - ref) / np.linalg.norm(ref))


# --------------------------------------------------------------------------- synthesis
def bench_synthesis(*, quick: bool, counts=PATH_COUNTS, eps_values=None,
                    log: Callable[[str], None] = print) -> list[dict]:
    """NUFFT vs direct and tone sums per path count (see module docstring).

    Timing subsets (all extrapolated linearly to the 256 x 400 frame):
    direct and tone sums on ``paths_timed`` paths x ``chirps_timed`` chirps x
    all 400 channels (their cost is a per-path loop, exactly linear in paths
    and chirps); the NUFFT on all paths x ``chirps_timed`` chirps x
    ``channels_timed`` channels (constant cost per (chirp, channel) row).
    Accuracy: NUFFT and tone sum against the direct sum with *all* paths on
    1 chirp x ``channels_checked`` channels.
    """
    from raysim.synthesis.select import choose_method, synthesize

    if eps_values is None:
        eps_values = (1e-5,) if quick else BENCH_EPS
    cfg, arr, traj, lever = paper_setup()
    n_ch, k = arr.num_channels, cfg.num_samples
    budget = 1.2e7 if quick else 2.4e8              # direct-sum terms per measurement
    nu_budget = 2e6 if quick else 4e7               # NUFFT (path, row) pairs per measurement
    rows = []
    for n in counts:
        pd = hover_paths(n, cfg, arr, traj, lever, seed=n)
        # accuracy subset: every path, 1 chirp, a few channels
        ch_acc = int(np.clip(budget // (n * k), 1, 16))
        acc = subset(pd, 1, ch_acc)
        ref = synthesize(acc, None, cfg, method="direct")
        tones = synthesize(acc, None, cfg, method="tones", eps=1e-5)
        # timing subset of the reference sums: some paths, some chirps, every channel
        p_t = int(np.clip(budget // (n_ch * k), 1, n))
        c_t = int(np.clip(budget // (p_t * n_ch * k), 1, 16))
        timed = subset(pd.select(np.arange(n) < p_t), c_t, n_ch)
        t_direct, _ = _timed(synthesize, timed, None, cfg, method="direct")
        t_tones, _ = _timed(synthesize, timed, None, cfg, method="tones", eps=1e-5)
        scale_ref = (cfg.num_chirps / c_t) * (n / p_t)
        # NUFFT: all paths, a few chirps and channels
        rows_t = int(np.clip(nu_budget // n, 1, cfg.num_chirps * n_ch))
        nu_chirps = max(1, min(cfg.num_chirps, rows_t // n_ch))
        nu_ch = n_ch if rows_t >= n_ch else int(np.clip(rows_t, 8, n_ch))
        nu_pd = subset(pd, cfg.num_chirps, nu_ch)
        scale_nu = (cfg.num_chirps / nu_chirps) * (n_ch / nu_ch)
        row = {
            "paths": int(n),
            "auto_method_eps_1e-5": choose_method(n, cfg.num_chirps, n_ch, k, 1e-5),
            "direct_s_per_frame": t_direct * scale_ref,
            "tones_s_per_frame": t_tones * scale_ref,
            "tones_rel_error": _rel(tones, ref),
            "reference_timed_on": {"paths": p_t, "chirps": c_t, "channels": n_ch,
                                   "extrapolation_factor": scale_ref},
            "accuracy_checked_on": {"paths": int(n), "chirps": 1, "channels": ch_acc},
            "nufft_timed_on": {"paths": int(n), "chirps": nu_chirps, "channels": nu_ch,
                               "extrapolation_factor": scale_nu},
            "nufft": [],
        }
        for eps in eps_values:
            t_nu, _ = _timed(synthesize, nu_pd, None, cfg, method="nufft", eps=eps,
                             chirps=range(nu_chirps), threads=1)
            nu_acc = synthesize(acc, None, cfg, method="nufft", eps=eps)
            s_frame = t_nu * scale_nu
            row["nufft"].append({
                "eps": eps, "s_per_frame": s_frame,
                "rel_error_vs_direct": _rel(nu_acc, ref),
                "speedup_vs_direct": row["direct_s_per_frame"] / s_frame,
                "speedup_vs_tones": row["tones_s_per_frame"] / s_frame,
            })
        rows.append(row)
        best = row["nufft"][0]
        log(f"  {n:>7} paths: nufft(eps={best['eps']:g}) {best['s_per_frame']:9.2f} s/frame "
            f"err {best['rel_error_vs_direct']:.1e} | direct {row['direct_s_per_frame']:10.1f} "
            f"s/frame (x{best['speedup_vs_direct']:.0f}) | tones "
            f"{row['tones_s_per_frame']:9.1f} s/frame (x{best['speedup_vs_tones']:.1f})")
    return rows


# --------------------------------------------------------------------------- kernel
def bench_synthesis_1e5(*, quick: bool, paths: int = 100_000, eps: float = 1e-5,
                        threads: int = 1, log: Callable[[str], None] = print) -> dict:
    """Fused kernel (+ slow-time decimation) against FINUFFT, 1e5 paths, paper frame.

    The paper motion of :func:`paper_setup` plus hover jitter
    (:func:`raysim.platform.motion.hover_jitter`, seed :data:`JITTER_SEED`). Same
    process, same ``threads`` for both (default 1, CPU clock: robust on a shared
    machine). FINUFFT (``method="nufft"``, includes NumPy geometry and strengths) is
    timed on 1 chirp x ``nu_ch`` channels; the kernel (``method="kernel"``, includes
    geometry, spreading, FFT, deconvolution) on ``k_chirps`` chirps x 400 channels;
    both extrapolated linearly per row. The decimated frame is rendered whole
    (``decimate="auto"``: planning, a-posteriori check, exact rows, interpolation;
    :func:`raysim.bench.decimated_frame.whole_frame`) and compared with the
    undecimated kernel on every chirp of two channels; the slow-time interpolation is
    timed before/after its banded form (:func:`~raysim.bench.decimated_frame.interpolation_ratio`).
    Errors against the complex128 direct sum: the kernel on all paths x 1 chirp x
    ``acc_ch`` channels; the decimated render on ``dec_paths`` paths x 256 chirps x 2
    channels.
    """
    from raysim.bench.decimated_frame import finufft_upsampfac, interpolation_ratio, whole_frame
    from raysim.platform.motion import hover_jitter
    from raysim.synthesis import kernel
    from raysim.synthesis.decimate import plan_groups
    from raysim.synthesis.select import DECIMATION_EPS_SHARE, synthesize

    if not kernel.available():
        return {"status": "kernel extension not built; FINUFFT only"}
    cfg, arr, traj, lever = paper_setup()
    traj = traj + hover_jitter(JITTER_SEED)
    n_ch, k, n_chirp = arr.num_channels, cfg.num_samples, cfg.num_chirps
    pd = hover_paths(paths, cfg, arr, traj, lever, seed=1)
    nu_ch = 40 if quick else 100
    k_chirps = 1 if quick else 4
    # warm-up (imports, FFTW plans, first pages) before either is timed
    synthesize(subset(pd, 1, 2), None, cfg, method="nufft", eps=eps, threads=threads)
    synthesize(subset(pd, 1, 2), None, cfg, method="kernel", eps=eps, threads=threads)
    t_nu, _ = _timed(synthesize, subset(pd, 1, nu_ch), None, cfg, method="nufft", eps=eps,
                     threads=threads)
    nufft_frame = t_nu * n_chirp * n_ch / nu_ch
    t_k, _ = _timed(synthesize, pd, None, cfg, method="kernel", eps=eps, threads=threads,
                    chirps=range(k_chirps))
    kernel_frame = t_k * n_chirp / k_chirps
    t_plan, groups = _timed(plan_groups, pd, cfg, n_chirp, DECIMATION_EPS_SHARE * eps)
    frame = whole_frame(pd, cfg, eps, threads, TIMER)
    dec_frame = frame["s_per_frame"]
    interp = interpolation_ratio([p for _, p in groups if p.factor > 1], n_chirp, k, n_ch,
                                 TIMER)
    # accuracy
    acc_ch = 2 if quick else 8
    acc = subset(pd, 1, acc_ch)
    ref = synthesize(acc, None, cfg, method="direct")
    err_kernel = _rel(synthesize(acc, None, cfg, method="kernel", eps=eps), ref)
    err_nufft = _rel(synthesize(acc, None, cfg, method="nufft", eps=eps), ref)
    dec_paths = 500 if quick else 5_000
    small = subset(pd.select(np.arange(paths) < dec_paths), n_chirp, 2)
    ref_d = synthesize(small, None, cfg, method="direct")
    err_dec = _rel(synthesize(small, None, cfg, method="kernel", eps=eps, decimate="auto"), ref_d)
    # FINUFFT's upsampling factor: 2.0 (default) against 1.25 on the same rows
    upsamp = finufft_upsampfac(pd, cfg, eps, 8 if quick else 40, TIMER)
    out = {
        "paths": paths, "eps": eps, "threads": threads,
        "clock": "cpu" if TIMER is time.process_time else "wall",
        "frame": [n_chirp, n_ch, k], "isa": kernel.isa(),
        "motion": f"paper_setup motion + hover_jitter(seed={JITTER_SEED})",
        "finufft_s_per_frame": nufft_frame,
        "kernel_s_per_frame": kernel_frame,
        "kernel_decimated_s_per_frame": dec_frame,
        "decimation": {"groups": frame["groups"],
                       "exact_work_fraction": frame["exact_work_fraction"],
                       "planning_s": t_plan, "interpolation": interp,
                       "frame_error": frame["frame_error"]},
        "speedup_vs_finufft": nufft_frame / dec_frame,
        "speedup_vs_kernel": kernel_frame / dec_frame,
        "speedup_vs_finufft_no_decimation": nufft_frame / kernel_frame,
        "relative_error": max(err_kernel + frame["frame_error"]["check_l2_max"], err_dec),
        "relative_error_parts": {"kernel_all_paths": err_kernel, "decimated_frame": err_dec,
                                 "finufft_all_paths": err_nufft,
                                 "interpolation_check_all_paths":
                                     frame["frame_error"]["check_l2_max"]},
        "finufft_upsampfac": upsamp,
        "timed_on": {"finufft": {"chirps": 1, "channels": nu_ch},
                     "kernel": {"chirps": k_chirps, "channels": n_ch},
                     "kernel_decimated": {"chirps": n_chirp, "channels": n_ch}},
        "accuracy_checked_on": {"kernel": {"paths": paths, "chirps": 1, "channels": acc_ch},
                                "decimated": {"paths": dec_paths, "chirps": n_chirp,
                                              "channels": 2}},
        "baseline": ("FINUFFT per (chirp, channel) row (raysim.synthesis.nufft, NumPy geometry "
                     "and strengths included), same threads, same clock, same process"),
        "loadavg": list(os.getloadavg()),
    }
    log(f"  1e5 paths, {threads} thread(s), {out['clock']} clock: FINUFFT "
        f"{nufft_frame:.0f} s/frame, kernel {kernel_frame:.0f} s, kernel+decimation whole "
        f"frame ({len(frame['groups'])} path groups, {frame['exact_work_fraction']:.3f} of "
        f"the rows) {dec_frame:.1f} s: x{out['speedup_vs_finufft']:.1f} at error "
        f"{out['relative_error']:.1e}; interpolation banded x"
        f"{interp['ratio_before_over_after']:.2f}")
    return out


# --------------------------------------------------------------------------- memory
_MEMORY_CHILD = """
import json, time
import numpy as np
from raysim.bench.suite import peak_rss
from raysim.bench.workloads import hover_paths, paper_setup
from raysim.synthesis.streaming import render_frames
cfg, arr, traj, lever = paper_setup({chirps})
pd = hover_paths({paths}, cfg, arr, traj, lever, seed=1)
base, _ = peak_rss(reset=True)
sums = []
def keep(f, cube):
    sums.append(float(np.abs(cube[:, :, 0]).sum()))
t0 = time.perf_counter()
stats = render_frames(lambda f: pd, cfg, keep, chirp_block={block}, method="nufft", eps={eps},
                      desc="1e5-path frame")
wall = time.perf_counter() - t0
_, peak = peak_rss()
cube = cfg.num_chirps * arr.num_channels * cfg.num_samples * 8
print(json.dumps(dict(peak_rss_bytes=peak, baseline_rss_bytes=base, cube_bytes=cube,
                      path_bytes=pd.nbytes, seconds=wall, synthesis_seconds=stats.synthesis_seconds,
                      estimate_bytes=stats.peak_bytes_estimate, frames=len(sums))))
"""


def peak_rss(reset: bool = False) -> tuple[int, int]:
    """Current and peak resident set size of this process [bytes].

    Reads ``VmRSS``/``VmHWM`` from ``/proc/self/status``; ``reset=True`` first
    resets the peak to the current size (``/proc/self/clear_refs``), so the
    next peak measures what follows. Falls back to ``ru_maxrss`` elsewhere.
    """
    status = Path("/proc/self/status")
    if reset:
        try:
            Path("/proc/self/clear_refs").write_text("5")
        except OSError:
            pass
    if status.exists():
        fields = dict(line.split(":", 1) for line in status.read_text().splitlines()
                      if ":" in line)
        return (int(fields["VmRSS"].split()[0]) * 1024, int(fields["VmHWM"].split()[0]) * 1024)
    import resource

    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
    return peak, peak


def bench_memory(*, quick: bool, paths: int = 100_000, eps: float = 1e-5,
                 chirp_block: int = 16) -> dict:
    """Peak memory of a 1e5-path frame rendered in a child process (progress on stderr)."""
    chirps = 1 if quick else 256
    code = _MEMORY_CHILD.format(chirps=chirps, paths=int(paths), block=min(chirp_block, chirps),
                                eps=eps)
    res = subprocess.run([sys.executable, "-c", code], stdout=subprocess.PIPE, stderr=None,
                         text=True, check=True)
    out = json.loads(res.stdout.strip().splitlines()[-1])
    growth = out["peak_rss_bytes"] - out["baseline_rss_bytes"]
    out.update({
        "paths": int(paths), "chirps": chirps, "channels": 400, "samples": 600, "eps": eps,
        "chirp_block": min(chirp_block, chirps),
        "render_growth_bytes": growth,
        "growth_over_cube": growth / out["cube_bytes"],
        # stated bound: the writer's cube + the renderer's working set (estimate includes
        # the paths) + 32 MiB for FFTW/FINUFFT plans and thread stacks
        "bound_bytes": out["cube_bytes"] + out["estimate_bytes"] + 32 * 2**20,
        "within_bound": bool(growth <= out["cube_bytes"] + out["estimate_bytes"] + 32 * 2**20),
        "aim_bytes": 2 * out["cube_bytes"] + out["path_bytes"],
        "within_aim": bool(growth <= 2 * out["cube_bytes"] + out["path_bytes"]),
        "note": ("writer keeps one frame cube (FrameWriter); growth = peak RSS (VmHWM, reset "
                 "after building the paths) - RSS after building the paths"),
    })
    if quick:
        out["note"] += f"; quick: {chirps}-chirp frame, the full bench renders all 256 chirps"
    return out


# --------------------------------------------------------------------------- oracle
def naive_synthesis(tau: np.ndarray, amp: np.ndarray, config: RadarConfig) -> np.ndarray:
    """Textbook NumPy synthesis: ``np.exp`` over the whole ``[chirp, channel, sample]``
    cube in complex128, once per target (the baseline the oracle is compared with)."""
    t = config.fast_time()
    fc, mu = config.carrier_frequency, config.chirp_rate
    out = np.zeros(tau.shape[1:] + (t.size,), dtype=np.complex128)
    for p in range(tau.shape[0]):
        tp = tau[p][..., None]
        out += amp[p][..., None] * np.exp(2j * np.pi * (fc * tp + mu * tp * t - 0.5 * mu * tp**2))
    return out.astype(np.complex64)


def _both_clocks(fn: Callable[[], object], repeat: int = 1) -> tuple[float, float]:
    """Best wall seconds and best CPU seconds (all threads of the process) of ``fn``."""
    from raysim.bench.realtime import best_clocks

    return best_clocks(fn, repeat)[:2]


def bench_oracle(*, quick: bool) -> dict:
    """Oracle frame time against the write floor and a naive NumPy synthesis.

    Every time is given in wall and in CPU seconds: the oracle's tone sum runs on
    all CPUs of the process (``tones.synthesize_if`` threads), the naive
    synthesis on one, so the wall ratio favours the oracle by up to the thread
    count and the CPU ratio is the per-CPU-second comparison.
    """
    from raysim.echoes.oracle import PointTarget, point_target_delays, simulate_point_targets
    from raysim.processing.maps import range_compress

    cfg, arr, traj, lever = paper_setup()
    shape = (cfg.num_chirps, arr.num_channels, cfg.num_samples)

    def floor():
        cube = np.empty(shape, dtype=np.complex64)
        cube[...] = 1.0

    def floor_fft():
        cube = np.empty(shape, dtype=np.complex64)
        cube[...] = 1.0
        range_compress(cube)

    # best of 3: the first allocation of a fresh 492 MB cube pays the page faults
    floor_wall, floor_cpu = _both_clocks(floor, repeat=3)
    fft_wall, fft_cpu = _both_clocks(floor_fft, repeat=3)
    rng = np.random.default_rng(3)
    out = {"frame_shape": list(shape), "floor_wall_s": floor_wall, "floor_cpu_s": floor_cpu,
           "floor_note": "allocate + write one complex64 cube (a pure write, one thread)",
           "floor_with_range_fft_wall_s": fft_wall, "floor_with_range_fft_cpu_s": fft_cpu,
           "floor_with_range_fft_note": ("allocate + write a complex64 cube, then the Hann "
                                         "range FFT (window product and FFT output: three "
                                         "cube allocations in all)"),
           "oracle_threads": default_threads(), "naive_threads": 1, "cases": []}
    naive_chirps = 16 if quick else cfg.num_chirps
    for n_t in (1, 10):
        targets = [PointTarget.at(rng.uniform(5, 60), rng.uniform(-0.8, 0.8),
                                  rng.uniform(-0.5, 0.5)) for _ in range(n_t)]
        o_wall, o_cpu = _both_clocks(lambda targets=targets: simulate_point_targets(
            cfg, arr, targets, traj, lever_arm=lever), repeat=2)
        tau, amp = point_target_delays(cfg, arr, traj, targets, lever_arm=lever)
        naive_targets = 1 if quick else n_t
        n_wall, n_cpu = _both_clocks(lambda tau=tau, amp=amp, nt=naive_targets: naive_synthesis(
            tau[:nt, :naive_chirps], amp[:nt, :naive_chirps],
            cfg.with_(num_chirps=naive_chirps)))
        scale = (cfg.num_chirps / naive_chirps) * (n_t / naive_targets)
        n_wall, n_cpu = n_wall * scale, n_cpu * scale
        out["cases"].append({
            "targets": n_t, "oracle_wall_s": o_wall, "oracle_cpu_s": o_cpu,
            "naive_wall_s": n_wall, "naive_cpu_s": n_cpu,
            "naive_timed_on": {"chirps": naive_chirps, "targets": naive_targets},
            "oracle_over_floor_wall": o_wall / floor_wall,
            "naive_over_oracle_wall": n_wall / o_wall,
            "naive_over_oracle_cpu": n_cpu / o_cpu,
        })
    return out


# --------------------------------------------------------------------------- processing
def bench_processing(*, quick: bool) -> dict:
    """Bare range + Doppler FFT chain against compensation + processing."""
    from raysim.echoes.oracle import PointTarget, simulate_point_targets
    from raysim.processing.maps import doppler_fft, range_compress

    cfg, arr, traj, lever = paper_setup()
    frame = simulate_point_targets(cfg, arr, [PointTarget.at(15.0, np.deg2rad(20), 0.0)], traj,
                                   lever_arm=lever)
    t_range = _clock(lambda: range_compress(frame.data))
    rc = range_compress(frame.data)
    t_doppler = _clock(lambda: doppler_fft(rc, axis=0))
    out = {"range_fft_s": t_range, "doppler_fft_s": t_doppler,
           "bare_chain_s": t_range + t_doppler}
    try:
        import compensation
    except ImportError as exc:
        out["compensation"] = f"not available ({exc})"
        return out
    try:
        motion = compensation.static_motion(frame.chirp_times, lever_arm=lever)
        az = np.deg2rad(np.arange(-60, 60.1, 2.0 if quick else 1.0))
        el = np.deg2rad(np.arange(-30, 30.1, 6.0 if quick else 2.0))
        rng_axis = cfg.range_axis()
        gates = np.arange(55, 63) if quick else np.arange(50, 70)
        kw = dict(wavelength=cfg.center_wavelength, direction=np.array([0.34, 0.0, 0.94]),
                  range_axis=rng_axis, azimuth=az, elevation=el, range_gates=gates)
        t_comp = _clock(lambda: compensation.paper_chain(
            rc, arr.phase_centres, motion, grid_shape=arr.grid_shape, **kw))
        out.update({
            "compensation_chain_s": t_comp,
            "compensated_chain_s": t_range + t_comp,
            "compensated_over_bare": (t_range + t_comp) / (t_range + t_doppler),
            "compensation_setup": {"steps": list(compensation.PAPER_STEPS),
                                   "azimuth_points": az.size, "elevation_points": el.size,
                                   "range_gates": int(gates.size)},
            "measures": ("CPU seconds; bare = range FFT + Doppler FFT of the cube only; "
                         "compensated = range FFT + paper_chain (static motion) on the gates; "
                         "not the same chain, grid, baseline or clock as "
                         "raysim/bench/compensation_speed.py (docs/speed.md)"),
        })
    except Exception as exc:  # noqa: BLE001 - another package; record, do not fail the bench
        out["compensation"] = f"failed: {type(exc).__name__}: {exc}"
    return out


# --------------------------------------------------------------------------- time split
def bench_time_split(*, quick: bool, paths: int = 100_000, eps: float = 1e-5) -> dict:
    """Per-frame split of a 1e5-path NUFFT frame (one chirp timed, times 256)."""
    from raysim.echoes.oracle import PointTarget, point_target_delays
    from raysim.processing.maps import doppler_fft, range_compress
    from raysim.synthesis.nufft import _strengths, _Worker
    from raysim.synthesis.tones import synthesize_if

    cfg, arr, traj, lever = paper_setup()
    pd = hover_paths(paths, cfg, arr, traj, lever, seed=2)
    worker = _Worker(cfg.num_samples, 0.5 * eps)
    acc = np.zeros((arr.num_channels, cfg.num_samples), complex)
    t = dict(geometry=0.0, strengths=0.0, transforms=0.0, accumulate=0.0)
    step = 8
    n_ch = 48 if quick else arr.num_channels
    for m0 in range(0, n_ch, step):
        ch = slice(m0, m0 + step)
        c0 = TIMER()
        tau = pd.delays(0, ch)
        c1 = TIMER()
        x, c = _strengths(tau, pd.amplitudes(0)[None, :], cfg, False)
        c2 = TIMER()
        t["geometry"] += c1 - c0
        t["strengths"] += c2 - c1
        for i in range(x.shape[0]):
            a = TIMER()
            worker.plan.setpts(x[i])
            worker.plan.execute(c[i], out=worker.buf)
            b = TIMER()
            acc[m0 + i] += worker.buf
            t["transforms"] += b - a
            t["accumulate"] += TIMER() - b
    nufft_split = {k: v * cfg.num_chirps * arr.num_channels / n_ch for k, v in t.items()}
    # oracle frame split (10 targets)
    rng = np.random.default_rng(4)
    targets = [PointTarget.at(rng.uniform(5, 60), 0.1 * i, 0.0) for i in range(10)]
    o0 = TIMER()
    tau, amp = point_target_delays(cfg, arr, traj, targets, lever_arm=lever)
    o1 = TIMER()
    data = synthesize_if(tau, amp, cfg)
    o2 = TIMER()
    rc = range_compress(data)
    o3 = TIMER()
    doppler_fft(rc, axis=0)
    o4 = TIMER()
    return {
        "nufft_frame": {"paths": paths, "eps": eps, "threads": 1,
                        "note": f"one chirp x {n_ch} channels timed on one thread, "
                                "extrapolated to 256 x 400",
                        **{f"{k}_s": v for k, v in nufft_split.items()}},
        "oracle_frame": {"targets": 10, "delays_s": o1 - o0, "tone_synthesis_s": o2 - o1,
                         "range_fft_s": o3 - o2, "doppler_fft_s": o4 - o3},
    }


# --------------------------------------------------------------------------- re-projection
def bench_reprojection(*, quick: bool, paths: int | None = None) -> dict:
    """Dense re-projection (raysim.echoes.rt) against the compact PathDelays, same delays."""
    try:
        from raysim.echoes.rt.reproject import reproject
        from raysim.echoes.rt.trace import PathSet
    except Exception as exc:  # noqa: BLE001 - optional module
        return {"status": f"not available ({type(exc).__name__}: {exc})"}
    paths = (1_000 if quick else 10_000) if paths is None else int(paths)
    cfg, arr, traj, lever = paper_setup()
    pd = hover_paths(paths, cfg, arr, traj, lever, seed=5)
    first, last = pd.first_vertex, pd.last_vertex
    origin = np.zeros(3)
    length = (np.linalg.norm(first, axis=1) + pd.interior_length + np.linalg.norm(last, axis=1))
    n = pd.num_paths
    ps = PathSet(first, last, length, pd.amplitude, pd.velocity, np.zeros(n),
                 np.zeros((n, 1), np.uint32), np.zeros(n, np.uint32),
                 np.zeros((n, 2, 2), complex), length / SPEED_OF_LIGHT, origin, origin)
    chirps = 1 if quick else 8
    t_dense = _clock(lambda: reproject(ps, cfg, arr, traj, lever, chirps=range(chirps),
                                       if_band="none"))
    compact = PathDelays.from_pathset(ps, cfg, arr, traj, lever_arm=lever, if_band="none")
    t_compact = _clock(lambda: [compact.delays(k) for k in range(chirps)])
    dense = reproject(ps, cfg, arr, traj, lever, chirps=range(1), if_band="none").tau[:, 0]
    diff = float(np.abs(dense.T - compact.delays(0)).max())
    scale = cfg.num_chirps / chirps
    return {"paths": paths, "chirps_measured": chirps,
            "dense_reproject_s_per_frame": t_dense * scale,
            "compact_delays_s_per_frame": t_compact * scale,
            "dense_bytes_per_frame": n * cfg.num_chirps * arr.num_channels * 8,
            "compact_bytes": compact.nbytes, "max_delay_difference_s": diff}


# --------------------------------------------------------------------------- driver
def atomic_write_json(path, data: dict) -> None:
    """Write benchmark results as JSON atomically (NumPy scalars and arrays allowed)."""
    files.atomic_write_json(path, data, indent=2, default=_json_default)


def atomic_write_png(fig, path) -> None:
    """Save a matplotlib figure as PNG atomically."""
    files.atomic_savefig(fig, path, dpi=120, format="png")


def _json_default(value):
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")


def machine_info() -> dict:
    """CPU, library versions and load average of this machine."""
    import finufft
    import scipy

    return {"cpus": default_threads(), "platform": platform.platform(),
            "python": platform.python_version(), "numpy": np.__version__,
            "scipy": scipy.__version__, "finufft": getattr(finufft, "__version__", "?"),
            "loadavg_start": list(os.getloadavg())}


def run(*, quick: bool = False, memory: bool = True,
        log: Callable[[str], None] = print) -> dict:
    """Run every benchmark and return the results (see the module docstring).

    Parameters
    ----------
    quick : bool
        Smaller subsets (about a minute in all); the full run renders a whole
        1e5-path frame for the memory figure.
    memory : bool
        Run the child-process memory measurement.
    log : callable
        Progress lines.
    """
    t0 = time.perf_counter()
    result = {"schema": SCHEMA, "quick": bool(quick), "machine": machine_info(),
              "clock": "cpu" if TIMER is time.process_time else "wall",
              "notes": [
                  "direct and tone sums are timed on a subset of chirps x channels and "
                  "extrapolated linearly to the 256 x 400 frame (their cost is proportional)",
                  "NUFFT times are for the whole channel set on a subset of chirps, "
                  "extrapolated linearly to 256 chirps (constant cost per chirp)",
                  "errors are relative l2 against the complex128 direct sum on its subset",
                  ("times are CPU seconds of the benchmark process (time.process_time, all "
                   "threads; the NUFFT runs on one thread here) because the machine is shared"
                   if TIMER is time.process_time else
                   "times are wall seconds (time.perf_counter; --clock wall)")
                  + "; the memory render reports wall seconds with the default threads",
              ]}
    if memory:
        log("memory: 1e5-path frame in a child process")
        result["memory"] = bench_memory(quick=quick)
    else:
        result["memory"] = "skipped (--no-memory)"
    log("synthesis_1e5: fused kernel + decimation vs FINUFFT (1e5 paths, paper frame)")
    result["synthesis_1e5"] = bench_synthesis_1e5(quick=quick, log=log)
    log("synthesis: NUFFT vs direct sum vs tone sum (paper frame 256 x 400 x 600)")
    result["synthesis"] = bench_synthesis(quick=quick, log=log)
    log("oracle vs floor and naive NumPy")
    result["oracle"] = bench_oracle(quick=quick)
    log("processing chains")
    result["processing"] = bench_processing(quick=quick)
    log("real-time compensation: TI-size frame, wall clock")
    try:
        from raysim.bench.realtime import bench_realtime, bench_stream

        result["realtime_compensation"] = bench_realtime(quick=quick)
        log("real-time stream: 200 TI frames replayed at the frame rate, per-frame latency")
        result["realtime"] = bench_stream()
    except ImportError as exc:
        result["realtime_compensation"] = result["realtime"] = f"not available ({exc})"
    log("per-frame time split")
    result["time_split"] = bench_time_split(quick=quick)
    log("re-projection")
    result["reprojection"] = bench_reprojection(quick=quick)
    result["machine"]["loadavg_end"] = list(os.getloadavg())
    result["seconds"] = time.perf_counter() - t0
    return result
