"""``raysim sweep``: parameter sweeps over scenario keys, run as Dask tasks, resumable."""

from __future__ import annotations

import argparse
import math
import os
import sys

from raysim.vocabulary import CHAINS

EPILOG = """\
examples:
  raysim sweep --case rotation_y --param motion.sinusoids.0.amplitude_deg=linspace(0,10,6) \\
      --set radar.num_chirps=64 --out sweeps/pitch
  raysim sweep examples/case_translation_z.toml --param imu.preset=ideal,tactical,consumer_mems \\
      --seeds range(4) --out sweeps/imu
  raysim sweep examples/case_yaw.toml --param radar.num_chirps=64,128 \\
      --scheduler tcp://scheduler:8786 --out /shared/sweeps/yaw

--param KEY=VALUES may be repeated; the sweep is the Cartesian product of all
of them, times the seeds (the scenario's top-level seed). VALUES is a comma
list (1,2,4), a TOML list ([1, 2]), range(START,STOP[,STEP]),
linspace(START,STOP,NUM) or logspace(A,B,NUM). A paper case's sinusoid is
swept as motion.sinusoids.0.* only if the scenario lists it under
[[motion.sinusoids]]; with --case the case motion is used as is.

Finished points are stored one file each under OUT/points/; re-running the
same command computes only the missing points. Results: OUT/sweep.nc (one
variable per metric of raysim.vocabulary.METRICS, dims: each swept key, seed,
chain; the compensation's guard warnings of every point and chain in the
variable "warnings", summarised on stderr as "warning: CHAIN: KIND at N/M
points (e.g. TEXT)"). Chains: none, paper, paper:published, exact.

exit status: 0 all points done, 1 some points failed or the scheduler is
unavailable (finished points are kept), 2 invalid input, 130 interrupted.
"""


#: Metrics (names of :data:`raysim.vocabulary.METRICS`) printed as means after a sweep.
SUMMARY_METRICS = ("pseudo_velocity_mps", "doppler_width_hz", "angle_error_deg")
#: Most local workers (and threads each) per CPU core [1].
MAX_WORKERS_PER_CPU = 8


def register(subparsers) -> None:
    """Add the ``sweep`` subcommand."""
    from raysim.cli.options import chains_help

    p = subparsers.add_parser(
        "sweep", help="sweep scenario keys on Dask (resumable)",
        description="Run a parameter sweep over scenario keys and seeds as Dask tasks and "
        "gather the metrics into one xarray Dataset (OUT/sweep.nc).", epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenario", nargs="?", metavar="SCENARIO.toml", help="base scenario file")
    p.add_argument("--case", metavar="NAME", help="base scenario: a paper case")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUES",
                   help="swept key and its values (repeatable)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="fixed change to the base scenario (repeatable)")
    p.add_argument("--seeds", default="0", metavar="VALUES",
                   help="seeds, e.g. 0,1,2 or range(8) (default: 0)")
    p.add_argument("--chains", default=",".join(CHAINS),
                   help=chains_help(",".join(CHAINS)))
    p.add_argument("--out", required=True, metavar="DIR", help="result folder")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help="Dask scheduler address (default: a local in-process cluster)")
    p.add_argument("--workers", type=int, default=1, help="local workers (default 1)")
    p.add_argument("--threads", type=int, default=2, help="threads per local worker (default 2)")
    p.add_argument("--processes", action="store_true",
                   help="local workers as processes instead of threads")
    p.add_argument("--limit", type=int, metavar="N",
                   help="compute at most N missing points this time")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``raysim sweep``; returns the exit code."""
    from raysim.cli.options import chains_option, check_output
    from raysim.pipeline.sources import FeatureUnavailable
    from raysim.pipeline.sweep import SweepSpec, parse_values, run_sweep, warning_summary
    from raysim.scenario import load_scenario, parse_assignment, scenario_from_case
    from raysim.vocabulary import metric_unit

    if bool(args.scenario) == bool(args.case):
        raise ValueError("give exactly one base: SCENARIO.toml or --case NAME")
    # each local worker holds a scenario's render: more than a few per core only thrash
    most = MAX_WORKERS_PER_CPU * (os.cpu_count() or 1)
    for name in ("workers", "threads"):
        if not 1 <= getattr(args, name) <= most:
            raise ValueError(f"--{name}: got {getattr(args, name)}, expected 1 to {most} "
                             f"({MAX_WORKERS_PER_CPU} per CPU core of this machine)")
    check_output(args.out, "dir", "--out")
    base = load_scenario(args.scenario) if args.scenario else scenario_from_case(args.case)
    if args.set:
        base = base.with_values(dict(parse_assignment(s) for s in args.set))
    params = {}
    for item in args.param:
        if "=" not in item:
            raise ValueError(f"--param: got {item!r}, expected KEY=VALUES")
        key, text = item.split("=", 1)
        try:
            params[key.strip()] = parse_values(text)
        except ValueError as exc:
            raise ValueError(f"--param {key.strip()}: {exc}") from None
    try:
        seeds = parse_values(args.seeds)
    except ValueError as exc:
        raise ValueError(f"--seeds: {exc}") from None
    if not all(isinstance(s, int) and s >= 0 for s in seeds):
        raise ValueError(f"--seeds: got {args.seeds!r}, expected integers >= 0")
    chains = tuple(chains_option(args.chains))
    spec = SweepSpec(base, params, tuple(seeds), chains)
    try:
        res = run_sweep(spec, args.out, scheduler=args.scheduler, n_workers=args.workers,
                        threads_per_worker=args.threads, processes=args.processes,
                        limit=args.limit, progress=not args.no_progress)
    except FeatureUnavailable as exc:
        print(f"raysim sweep: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        if exc.filename is not None:                         # a file, not the network
            raise ValueError(f"--out {args.out!r}: cannot write {exc.filename!r}: "
                             f"{exc.strerror or exc}") from None
        where = (f"cannot reach the Dask scheduler {args.scheduler!r}" if args.scheduler
                 else "the local Dask cluster failed")
        print(f"raysim sweep: {where}: {exc}", file=sys.stderr)
        return 1
    if res.removed:
        print(f"note: removed {len(res.removed)} leftover file(s) of an interrupted writer of "
              f"{args.out!r}", file=sys.stderr)
    ds = res.dataset
    total = int(ds.attrs["points_total"])
    print(f"{args.out}: {int(ds.attrs['points_done'])}/{total} points done "
          f"({len(res.computed)} computed now, {len(res.skipped)} from before, "
          f"{len(res.failed)} failed)")
    for key, err in res.failed.items():
        print(f"failed point {key}: {err}", file=sys.stderr)
    for chain in spec.chains:
        sub = ds.sel(chain=chain)
        vals = [f"{m}={float(sub[m].mean()):.4g} {metric_unit(m)}" for m in
                SUMMARY_METRICS if not math.isnan(float(sub[m].mean(skipna=True)))]
        if vals:
            print(f"  {chain} (mean over points): {', '.join(vals)}")
    for line in warning_summary(ds):
        print(f"warning: {line}", file=sys.stderr)
    print(f"results: {res.path}")
    return 1 if res.failed or int(ds.attrs["points_done"]) < total and args.limit is None else 0
