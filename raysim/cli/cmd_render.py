"""``raysim render``: render a scenario file into a resumable Zarr store."""

from __future__ import annotations

import argparse
import sys

from raysim.cli.options import add_decimation_options

EPILOG = """\
examples:
  raysim render examples/case_rotation_y.toml --out rotation_y.zarr
  raysim render examples/scene_parking_lot.toml --out lot.zarr --netcdf lot.nc
  raysim render examples/case_yaw.toml --out yaw.zarr --set radar.num_chirps=64

The store is an xarray/Zarr dataset with dims frame, chirp, channel, sample
(see docs/user_guide.md). Re-running the same command after an interruption
keeps the finished frames and continues with the next one; --overwrite starts
again.

exit status: 0 all frames rendered, 1 the renderer could not run here (e.g.
Sionna RT unavailable), 2 invalid input, 130 interrupted (finished frames kept).
"""


def register(subparsers) -> None:
    """Add the ``render`` subcommand."""
    p = subparsers.add_parser(
        "render", help="render a scenario file into a Zarr store (resumable)",
        description="Render every frame of a scenario into a Zarr store, with the truth pose "
        "per chirp and the simulated IMU log beside the IF cube.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scenario", metavar="SCENARIO.toml", help="scenario file")
    p.add_argument("--out", metavar="STORE.zarr",
                   help="Zarr store to write (default: output.store of the scenario)")
    p.add_argument("--netcdf", metavar="FILE.nc", help="also export to NetCDF when finished")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="change a scenario key, e.g. frames=4 (repeatable)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace an existing store instead of resuming it")
    add_decimation_options(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``raysim render``; returns the exit code."""
    from raysim.cli.options import check_output
    from raysim.pipeline.run import render
    from raysim.pipeline.sources import FeatureUnavailable
    from raysim.scenario import load_scenario, parse_assignment

    scenario = load_scenario(args.scenario)
    if args.set:
        scenario = scenario.with_values(dict(parse_assignment(s) for s in args.set))
    for key in ("decimate", "decimate_tolerance"):
        if getattr(args, key) is not None:
            scenario = scenario.with_values({f"synthesis.{key}": getattr(args, key)})
    out = args.out or scenario.output.store
    if not out:
        raise ValueError("no output store: pass --out STORE.zarr or set output.store in the "
                         "scenario file")
    inputs = [("SCENARIO", args.scenario)]
    check_output(out, "dir", "--out" if args.out else "output.store", inputs=inputs)
    nc = args.netcdf or scenario.output.netcdf
    if nc:
        check_output(nc, "file", "--netcdf" if args.netcdf else "output.netcdf",
                     inputs=inputs + [("the store", out)])
    try:
        summary = render(scenario, out, overwrite=args.overwrite,
                         progress=not args.no_progress, export_netcdf=nc)
    except FeatureUnavailable as exc:
        print(f"raysim render: {exc}", file=sys.stderr)
        return 1
    for note in summary.notes:
        print(f"note: {note}", file=sys.stderr)
    msg = (f"{summary.path}: {summary.frames_resumed + summary.frames_rendered}/"
           f"{summary.frames_total} frames ({summary.frames_rendered} rendered now")
    msg += f", {summary.frames_resumed} kept from before)" if summary.frames_resumed else ")"
    print(msg)
    if nc:
        print(f"NetCDF export: {nc}")
    return 0
