"""Dr.Jit kernel (CUDA, or LLVM on a CPU) against the C++ kernel and FINUFFT, same run.

Workload: the paper frame of ``raysim bench``'s ``synthesis_1e5`` (paper radar,
20 x 20 virtual UPA, paper hover motion, ``hover_paths(paths, seed=1)``: 1e5
paths, 256 chirps x 400 channels x 600 samples) at ``eps = 1e-5``.

Each method renders the first ``--chirps`` chirps x all channels (FINUFFT: one
chirp), once as a warm-up (Dr.Jit traces and compiles its kernel there) and
then ``--repeats`` times; the median wall time, its spread (min, max) and the
per-frame extrapolation (x 256 / chirps) are reported. Dr.Jit's time includes
its host-to-device copies of the geometry, the spreading, the FFT (CuPy where
present, else SciPy) and the copy of the rows back to NumPy, as
``method="drjit"`` runs it; the C++ kernel and FINUFFT use ``--threads`` CPU
threads. Errors: relative l2 against the complex128 direct sum of chirp 0 on
the first ``--acc-channels`` channels. ``phase_float32``: the same Dr.Jit
kernel with every value in float32 (phase, strength and grid), to tell whether
the phase needs float64. ``decimated_frame_estimate_s``: the Dr.Jit time per
chirp times the exact chirps of ``plan_groups`` (weighted by their paths), plus
the planning and the slow-time interpolation as timed here (an estimate:
``method="drjit"`` does not decimate yet).

Usage::

    python -m raysim.bench.gpu_kernel --backend llvm --paths 2000 --chirps 1 --repeats 2
    python -m raysim.bench.gpu_kernel --backend cuda --json gpu.json
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time

import numpy as np


def _device() -> dict:
    info = {"python": sys.version.split()[0], "machine": platform.machine(),
            "cpus": os.cpu_count(), "loadavg": list(os.getloadavg())}
    try:
        with open("/proc/cpuinfo") as fh:
            names = [ln.split(":", 1)[1].strip() for ln in fh if ln.startswith("model name")]
        info["cpu"] = names[0] if names else "unknown"
    except OSError:
        info["cpu"] = "unknown"
    try:
        q = "name,driver_version,clocks.sm,clocks.max.sm,clocks.mem,memory.total"
        out = subprocess.run(["nvidia-smi", f"--query-gpu={q}", "--format=csv,noheader"],
                             capture_output=True, text=True, timeout=30)
        if out.returncode == 0:
            info["gpu"] = out.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        pass
    return info


def _time(fn, repeats: int) -> dict:
    """Warm-up once, then ``repeats`` wall-clock runs: median, min, max [s]."""
    fn()
    runs = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        runs.append(time.perf_counter() - t)
    return {"median_s": statistics.median(runs), "min_s": min(runs), "max_s": max(runs),
            "runs_s": runs}


def _rel(x, ref) -> float:
    return float(np.linalg.norm(x - ref) / np.linalg.norm(ref))


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--paths", type=int, default=100_000)
    ap.add_argument("--chirps", type=int, default=4, help="chirps timed per repeat")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--threads", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--eps", type=float, default=1e-5)
    ap.add_argument("--backend", choices=("cuda", "llvm"), default=None)
    ap.add_argument("--acc-channels", type=int, default=2)
    ap.add_argument("--skip", default="",
                    help="comma-separated: spread,kernel,nufft,float32,decim")
    ap.add_argument("--json", default=None, help="write the results here")
    args = ap.parse_args(argv)
    if args.paths < 1 or args.chirps < 1 or args.repeats < 1 or args.threads < 1:
        raise ValueError(f"paths, chirps, repeats and threads must be >= 1, got {args.paths}, "
                         f"{args.chirps}, {args.repeats}, {args.threads}")
    skip = {s for s in args.skip.split(",") if s}

    from raysim.bench.workloads import hover_paths, paper_setup, subset
    from raysim.synthesis import drjit_kernel, kernel
    from raysim.synthesis.select import synthesize

    backend = args.backend or drjit_kernel.backend()
    cfg, arr, traj, lever = paper_setup()
    n_chirp, n_ch, k = cfg.num_chirps, arr.num_channels, cfg.num_samples
    pd = hover_paths(args.paths, cfg, arr, traj, lever, seed=1)
    chirps = range(args.chirps)
    scale = n_chirp / args.chirps
    res: dict = {"workload": {"paths": args.paths, "frame": [n_chirp, n_ch, k],
                              "eps": args.eps, "timed_chirps": args.chirps,
                              "repeats": args.repeats, "threads_cpu": args.threads,
                              "clock": "wall (time.perf_counter)"},
                 "device": _device(), "drjit_backend": backend}
    acc = subset(pd, 1, args.acc_channels)
    t0 = time.perf_counter()
    ref = synthesize(acc, None, cfg, method="direct")
    res["direct_reference_s"] = time.perf_counter() - t0
    import raysim

    res["raysim"] = os.path.dirname(raysim.__file__)
    print(f"device: {res['device']}; raysim from {res['raysim']}", flush=True)

    # Dr.Jit
    out_dj = {}

    def run_drjit():
        out_dj["x"] = drjit_kernel.synthesize_drjit(pd, cfg, eps=args.eps, chirps=chirps,
                                                    use=backend)

    t0 = time.perf_counter()
    run_drjit()
    first = time.perf_counter() - t0
    tm = _time(run_drjit, args.repeats)
    tm["first_call_s"] = first
    tm["frame_s"] = tm["median_s"] * scale
    tm["relative_error"] = _rel(out_dj["x"][0, :args.acc_channels], ref[0])
    res["drjit"] = tm
    print(f"drjit/{backend}: {tm['median_s'] / args.chirps * 1e3:.1f} ms/chirp "
          f"(min {tm['min_s'] / args.chirps * 1e3:.1f}, max {tm['max_s'] / args.chirps * 1e3:.1f})"
          f", frame {tm['frame_s']:.2f} s, error {tm['relative_error']:.2e}", flush=True)

    # Dr.Jit spreading alone (geometry copies, gathers, phase, scatter; no FFT, no copy back)
    if "spread" not in skip:
        import drjit as dr

        from raysim.radar.config import SPEED_OF_LIGHT
        from raysim.synthesis.kernel import kernel_error

        design = kernel_error(args.paths, args.eps, k, double_grid=True)[1]
        mu, fs = cfg.chirp_rate, cfg.sample_rate
        consts = (pd.reference_time, 1.0 / SPEED_OF_LIGHT,
                  cfg.carrier_frequency + (k // 2) * mu / fs, 0.5 * mu, mu / fs)
        types = drjit_kernel._types(backend)
        step = max(1, min(n_ch, drjit_kernel.MAX_PAIRS // args.paths))

        def run_spread():
            for n in chirps:
                for c0 in range(0, n_ch, step):
                    c1 = min(n_ch, c0 + step)
                    grid = types[0](np.zeros(2 * (c1 - c0) * design.grid_size))
                    drjit_kernel._spread_chirp(types, pd, n, design, consts, grid, c0, c1)
            dr.sync_thread()

        tm = _time(run_spread, args.repeats)
        res["drjit_spread_only"] = tm
        print(f"drjit/{backend} spreading only: {tm['median_s'] / args.chirps * 1e3:.1f} "
              f"ms/chirp", flush=True)

    # C++ kernel
    if "kernel" not in skip and kernel.available():
        out_k = {}

        def run_kernel():
            out_k["x"] = synthesize(pd, None, cfg, method="kernel", eps=args.eps, chirps=chirps,
                                    threads=args.threads)

        tm = _time(run_kernel, args.repeats)
        tm["frame_s"] = tm["median_s"] * scale
        tm["relative_error"] = _rel(out_k["x"][0, :args.acc_channels], ref[0])
        tm["isa"] = kernel.isa()
        res["cpp_kernel"] = tm
        res["drjit_speedup_vs_cpp_kernel"] = tm["median_s"] / res["drjit"]["median_s"]
        print(f"C++ kernel ({args.threads} threads): {tm['median_s'] / args.chirps * 1e3:.1f} "
              f"ms/chirp, frame {tm['frame_s']:.2f} s, error {tm['relative_error']:.2e}; "
              f"Dr.Jit x{res['drjit_speedup_vs_cpp_kernel']:.2f}", flush=True)
    elif "kernel" not in skip:
        res["cpp_kernel"] = {"status": "extension not built"}

    # FINUFFT, one chirp
    if "nufft" not in skip:
        out_n = {}

        def run_nufft():
            out_n["x"] = synthesize(pd, None, cfg, method="nufft", eps=args.eps, chirps=range(1),
                                    threads=args.threads)

        tm = _time(run_nufft, args.repeats)
        tm["frame_s"] = tm["median_s"] * n_chirp
        tm["relative_error"] = _rel(out_n["x"][0, :args.acc_channels], ref[0])
        res["finufft"] = tm
        res["drjit_speedup_vs_finufft"] = tm["frame_s"] / res["drjit"]["frame_s"]
        print(f"FINUFFT ({args.threads} threads): {tm['median_s'] * 1e3:.1f} ms/chirp, frame "
              f"{tm['frame_s']:.2f} s, error {tm['relative_error']:.2e}", flush=True)

    # float32 throughout: does the phase need float64?
    if "float32" not in skip:
        import importlib

        keep = drjit_kernel._types

        def float32_types(name):
            mod = importlib.import_module(f"drjit.{name}")
            return mod.Float32, mod.UInt32

        drjit_kernel._types = float32_types
        try:
            x32 = drjit_kernel.synthesize_drjit(acc, cfg, eps=args.eps, use=backend)
            err32 = _rel(x32[0], ref[0])
        finally:
            drjit_kernel._types = keep
        res["phase_float32"] = {"relative_error": err32,
                                "needs_float64": bool(err32 > args.eps)}
        print(f"Dr.Jit all-float32: error {err32:.2e} -> phase needs float64: "
              f"{err32 > args.eps}", flush=True)

    # decimated frame (estimate)
    if "decim" not in skip:
        from raysim.synthesis.decimate import plan_groups, scatter_add
        from raysim.synthesis.select import DECIMATION_EPS_SHARE

        t0 = time.perf_counter()
        groups = plan_groups(pd, cfg, n_chirp, DECIMATION_EPS_SHARE * args.eps)
        t_plan = time.perf_counter() - t0
        rows = np.zeros((n_chirp, 4, k), np.complex64)
        t0 = time.perf_counter()
        for _, p in groups:
            scatter_add(rows, np.zeros((p.exact.size, 4, k), np.complex64), p)
        t_int = (time.perf_counter() - t0) * n_ch / 4
        work = sum(g.size * p.exact.size for g, p in groups) / (args.paths * n_chirp)
        per_chirp = res["drjit"]["median_s"] / args.chirps
        res["decimated_frame_estimate_s"] = {
            "total": per_chirp * n_chirp * work + t_plan + t_int,
            "drjit_rows": per_chirp * n_chirp * work, "planning": t_plan,
            "interpolation_cpu": t_int, "exact_work_fraction": work,
            "groups": [{"paths": int(g.size), "factor": int(p.factor),
                        "exact_chirps": int(p.exact.size)} for g, p in groups]}
        print(f"decimated frame (estimate): {res['decimated_frame_estimate_s']['total']:.3f} s "
              f"(work {work:.3f}, planning {t_plan:.3f} s, interpolation {t_int:.3f} s)",
              flush=True)

    if args.json:
        with open(args.json, "w") as fh:
            json.dump(res, fh, indent=1)
    return res


if __name__ == "__main__":
    main()
