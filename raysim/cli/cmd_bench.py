"""``raysim bench``: speed, accuracy and memory benchmarks, as JSON (and a chart)."""

from __future__ import annotations

import argparse
import sys

EPILOG = """\
examples:
  raysim bench --quick --out bench_quick.json
  raysim bench --out bench.json --chart speed_accuracy.png
  raysim bench --quick --chart-only --chart speed_accuracy.png
  raysim bench --realtime-only --out realtime.json

Measures the fused kernel (+ slow-time decimation) against FINUFFT for 1e5 paths
(key synthesis_1e5: speedup_vs_finufft, relative_error, threads, clock), NUFFT
vs direct-sum vs tone-sum synthesis for 10 to 1e5 paths on the
paper frame (256 chirps x 400 channels x 600 samples), the oracle against a
pure-write floor and a naive NumPy synthesis (wall and CPU seconds),
compensation + processing against the bare FFT chain, real-time compensation
of a TI-size frame (key realtime_compensation: frames per second against the
frame rate, best of repeats), the real-time stream (key realtime: 200
consecutive raw IF frames replayed at the frame rate through
compensation.RealtimeStream, p50/p95/p99 of each frame's latency including the
range transform, per gated-cell count 1, 3, 8, and what the paper frame
needs), the per-frame time split, re-projection, and the peak memory of a
1e5-path frame (child process). Slow references are timed on
a subset and extrapolated linearly; the JSON says which. The chart adds the
ray-tracing knobs (trace samples, depth, re-trace interval) on the bundled
rough_terrain scene when Sionna RT's LLVM backend runs, and notes their absence
otherwise. See docs/speed.md.

With --out the JSON goes to the file and a short table of the results (the
numbers of each section, the full set in the JSON) to stdout; without it the
JSON goes to stdout. Progress lines always go to stderr.

exit status: 0 done, 1 a benchmark failed, 2 invalid options.
"""

#: Rows of one section shown by :func:`summary_table` (the rest is in the JSON).
ROWS_PER_SECTION = 8


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
    p.add_argument("--realtime-only", action="store_true",
                   help="only the real-time stream (key realtime, about a minute)")
    p.add_argument("--no-memory", action="store_true",
                   help="skip the child-process memory measurement")
    p.add_argument("--clock", choices=("cpu", "wall"), default="cpu",
                   help="time in CPU seconds of this process (default; robust on a shared "
                   "machine) or in wall seconds (what a user waits on an idle machine)")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``raysim bench``; returns the exit code."""
    from raysim.bench import suite as bench

    if args.chart_only and not args.chart:
        raise ValueError("--chart-only needs --chart OUT.png")
    from raysim.cli.options import check_output

    for name in ("out", "chart"):
        value = getattr(args, name)
        if value is not None:
            check_output(value, "file", f"--{name}")

    def log(msg: str) -> None:
        print(msg, file=sys.stderr, flush=True)

    bench.set_clock(args.clock)

    if args.realtime_only:
        from raysim.bench.realtime import bench_stream

        log("real-time stream: 200 TI frames replayed at the frame rate, per-frame latency")
        result = {"schema": bench.SCHEMA, "machine": bench.machine_info(),
                  "realtime": bench_stream()}
    elif args.chart_only:
        result = {"schema": bench.SCHEMA, "quick": args.quick, "machine": bench.machine_info()}
    else:
        result = bench.run(quick=args.quick, memory=not args.no_memory, log=log)
    if args.chart:
        from raysim.bench.speed_chart import draw_chart, measure_knobs

        log("speed-versus-accuracy chart")
        knobs = measure_knobs(quick=args.quick, log=log)
        draw_chart(knobs, args.chart)
        result["chart"] = {"png": args.chart, "knobs": knobs}
    if args.out:
        bench.atomic_write_json(args.out, result)
        print(summary_table(result))
        log(f"results written to {args.out}")
    else:
        import json

        print(json.dumps(result, indent=2, default=bench._json_default))
    return 0


def _leaves(obj, prefix: str = ""):
    """``(dotted key, number)`` of every numeric leaf of nested dicts (lists skipped)."""
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from _leaves(v, f"{prefix}.{k}" if prefix else str(k))
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        yield prefix, float(obj)


def summary_table(result: dict) -> str:
    """A short text table of a bench result: section, quantity, value.

    At most :data:`ROWS_PER_SECTION` numbers per section (``memory``,
    ``synthesis``, ``oracle``, ...), then a count of those left out; the
    machine description is skipped.
    """
    lines = [f"{'section':<14} {'quantity':<52} {'value':>12}"]
    for section, body in result.items():
        if section in ("machine", "schema", "notes", "chart", "quick", "clock"):
            continue
        rows = list(_leaves(body))
        if not rows and isinstance(body, str):
            lines.append(f"{section:<14} {body}")
        for key, value in rows[:ROWS_PER_SECTION]:
            lines.append(f"{section:<14} {(key or section)[:52]:<52} {value:>12.4g}")
        if len(rows) > ROWS_PER_SECTION:
            lines.append(f"{section:<14} ({len(rows) - ROWS_PER_SECTION} more in the JSON)")
    return "\n".join(lines)
