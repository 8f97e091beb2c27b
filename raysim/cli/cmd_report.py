"""``raysim report``: a self-contained HTML report of a store, a scenario or a paper case."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from raysim.vocabulary import CHAINS

EPILOG = """\
examples:
  raysim report rotation_y.zarr --out rotation_y.html        # from a rendered store
  raysim report --case rotation_y --out rotation_y.html       # render in memory first
  raysim report --scenario examples/case_yaw.toml --set radar.num_chirps=64 --out yaw.html
  raysim report frames.nc --out frames.html                   # from a NetCDF export
  raysim report --case rotation_y --chains none,paper,paper:published,exact --out r.html

The report compares the chains none (no compensation), paper (paper:published
with the paper's rotation phase) and exact (when the compensation package
provides them): RA, RE, RD and AE maps, Doppler cuts, the metric table,
entropies, the compensation's warnings per chain (also printed on stderr as
"warning: CHAIN: TEXT"), the run parameters and the software versions.
Figures are embedded: the single HTML file is all there is. A ray-traced scene
without a discrete target (users' [[scene.meshes]]) gives the paper chains the
strongest return's direction instead (stated in a note). A progress bar on stderr
counts the frames read (or rendered), then names the chains being measured.

exit status: 0 written, 1 could not run here, 2 invalid input.
"""


def register(subparsers) -> None:
    """Add the ``report`` subcommand."""
    from raysim.cli.options import chains_help

    p = subparsers.add_parser(
        "report", help="write a self-contained HTML report",
        description="Write a self-contained HTML report comparing the chains none, paper "
        "and exact.", epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("store", nargs="?", metavar="STORE",
                   help="Zarr store (folder) or NetCDF file written by raysim render")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--scenario", metavar="FILE.toml", help="render this scenario in memory")
    src.add_argument("--case", metavar="NAME", help="render this paper case in memory")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change a scenario key (with --scenario / --case)")
    p.add_argument("--out", metavar="REPORT.html",
                   help="output file (default: output.report of the scenario or report.html)")
    p.add_argument("--chains", default=",".join(CHAINS),
                   help=chains_help(",".join(CHAINS)))
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``raysim report``; returns the exit code."""
    from raysim.cli.cmd_simulate import print_warnings
    from raysim.cli.options import chains_option, check_output
    from raysim.pipeline.sources import FeatureUnavailable
    from raysim.report.html import collect_from_dataset, collect_from_scenario, write_report
    from raysim.scenario import load_scenario, parse_assignment, scenario_from_case

    chains = chains_option(args.chains)
    given = [x for x in (args.store, args.scenario, args.case) if x]
    if len(given) != 1:
        raise ValueError("give exactly one source: STORE, --scenario FILE.toml or --case NAME")
    if args.set and args.store:
        raise ValueError("--set applies to --scenario / --case, not to a stored render")
    default_out = "report.html"
    try:
        if args.store:
            from raysim.io import storage

            path = Path(args.store)
            check_output(args.out or default_out, "file", "--out", inputs=[("STORE", path)])
            if storage.store_exists(path):
                ds = storage.open_store(path, load=False)     # frames are read one at a time
            elif path.is_file() and path.suffix in (".nc", ".nc4", ".netcdf"):
                ds = storage.read_netcdf(path)
            else:
                raise ValueError(f"STORE: got {args.store!r}, expected a Zarr store written by "
                                 f"raysim render or a NetCDF export (.nc)")
            if ds.sizes.get("frame", 0) == 0:
                raise ValueError(f"STORE {args.store!r} holds no complete frame yet")
            data = collect_from_dataset(ds, chains=chains, source=str(path),
                                        progress=not args.no_progress)
        else:
            scenario = (load_scenario(args.scenario) if args.scenario
                        else scenario_from_case(args.case))
            if args.set:
                scenario = scenario.with_values(dict(parse_assignment(s) for s in args.set))
            default_out = scenario.output.report or default_out
            check_output(args.out or default_out, "file",
                         "--out" if args.out or not scenario.output.report else "output.report",
                         inputs=[("--scenario", args.scenario)])
            data = collect_from_scenario(scenario, chains=chains,
                                         source=args.scenario or f"paper case {args.case}",
                                         progress=not args.no_progress)
    except FeatureUnavailable as exc:
        print(f"raysim report: {exc}", file=sys.stderr)
        return 1
    out = write_report(data, args.out or default_out)
    for note in data.result["notes"]:
        print(f"note: {note}", file=sys.stderr)
    print_warnings(data.result.get("warnings", {}))
    print(f"report written: {out}")
    return 0
