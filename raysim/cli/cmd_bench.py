"""``raysim bench``: speed, accuracy and memory benchmarks, as JSON (and a chart)."""

from __future__ import annotations

import argparse
import sys

EPILOG = """\
examples:
  raysim bench --quick --out bench_quick.json
  raysim bench --out bench.json --chart speed_accuracy.png
  raysim bench --quick --chart-only --chart speed_accuracy.png

Measures the fused kernel (+ slow-time decimation) against FINUFFT for 1e5 paths
(key synthesis_1e5: speedup_vs_finufft, relative_error, threads, clock), NUFFT
vs direct-sum vs tone-sum synthesis for 10 to 1e5 paths on the
paper frame (256 chirps x 400 channels x 600 samples), the oracle against the
write + range-FFT floor and a naive NumPy synthesis, compensation + processing
against the bare FFT chain, the per-frame time split, re-projection, and the
peak memory of a 1e5-path frame (child process). Slow references are timed on
a subset and extrapolated linearly; the JSON says which. The chart adds the
ray-tracing knobs (trace samples, depth, re-trace interval) on the bundled
rough_terrain scene when Sionna RT's LLVM backend runs, and notes their absence
otherwise. See docs/speed.md.

exit status: 0 done, 1 a benchmark failed, 2 invalid options.
"""


def register(subparsers) -> None:
    """Add the ``bench`` subcommand."""
    p = subparsers.add_parser(
        "bench", help="speed / accuracy / memory benchmarks (JSON, optional chart)",
        description="Benchmark IF synthesis, the oracle, processing and memory; save JSON.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true",
                   help="small subsets, about a minute (default: full run, tens of minutes)")
    p.add_argument("--out", metavar="FILE.json", help="write the results here (atomic)")
    p.add_argument("--chart", metavar="OUT.png",
                   help="also draw the speed-versus-accuracy chart to this PNG")
    p.add_argument("--chart-only", action="store_true",
                   help="only measure and draw the chart (needs --chart)")
    p.add_argument("--no-memory", action="store_true",
                   help="skip the child-process memory measurement")
    p.add_argument("--clock", choices=("cpu", "wall"), default="cpu",
                   help="time in CPU seconds of this process (default; robust on a shared "
                   "machine) or in wall seconds (what a user waits on an idle machine)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``raysim bench``; returns the exit code."""
    from raysim.studies import bench

    if args.chart_only and not args.chart:
        raise ValueError("--chart-only needs --chart OUT.png")
    for name in ("out", "chart"):
        value = getattr(args, name)
        if value is not None and not value.strip():
            raise ValueError(f"--{name} must be a file name, got {value!r}")

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    bench.set_clock(args.clock)

    if args.chart_only:
        result = {"schema": bench.SCHEMA, "quick": args.quick, "machine": bench.machine_info()}
    else:
        result = bench.run(quick=args.quick, memory=not args.no_memory, log=log)
    if args.chart:
        from raysim.studies.speed_chart import draw_chart, measure_knobs

        log("speed-versus-accuracy chart")
        knobs = measure_knobs(quick=args.quick, log=log)
        draw_chart(knobs, args.chart)
        result["chart"] = {"png": args.chart, "knobs": knobs}
    if args.out:
        bench.atomic_write_json(args.out, result)
        log(f"results written to {args.out}")
    else:
        import json

        print(json.dumps(result, indent=2, default=bench._json_default))
    return 0
