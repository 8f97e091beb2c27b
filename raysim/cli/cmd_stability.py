"""``raysim stability``: compute every stability map of the motion compensation."""

from __future__ import annotations

import argparse
import sys


def register(subparsers) -> None:
    """Add the ``stability`` subcommand to ``subparsers``."""
    p = subparsers.add_parser(
        "stability",
        help="stability maps of the compensation chains (figures, NetCDF, JSON)",
        description="Sweep rotation amplitude x target angle, motion frequency x frame length, "
        "IMU grade, IMU rate, clock errors, lever-arm error and hover jitter; write one PNG "
        "(failure boundary drawn), one NetCDF and one JSON per map plus summary.json. "
        "Finished maps found in OUT are reused, so an interrupted run resumes.",
    )
    p.add_argument("--out", required=True, metavar="DIR", help="output directory")
    p.add_argument("--quick", action="store_true",
                   help="small axes and fewer seeds (a few minutes on 2 cores)")
    p.add_argument("--maps", nargs="+", metavar="NAME", default=None,
                   help="only these maps (default: all)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--executor", choices=("auto", "dask", "serial"), default="auto",
                   help="run the points on an in-process Dask cluster (auto: when installed) "
                   "or in a plain loop")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``raysim stability``; returns the exit code."""
    from raysim.studies.stability import MAPS, write_stability

    if args.maps:
        bad = [m for m in args.maps if m not in MAPS]
        if bad:
            raise ValueError(f"--maps: unknown stability map {bad[0]!r}; expected one of "
                             f"{sorted(MAPS)}")
    summary = write_stability(args.out, quick=args.quick, maps=args.maps,
                              progress=not args.no_progress, executor=args.executor)
    for name, s in summary.items():
        fails = {c: max(_flat(r["fail_fraction"])) for c, r in s["chains"].items()}
        print(f"{name}: worst fail fraction per chain {fails}", file=sys.stdout)
    print(f"wrote {len(summary)} maps to {args.out}")
    return 0


def _flat(x):
    if isinstance(x, list):
        for v in x:
            yield from _flat(v)
    else:
        yield float(x)
