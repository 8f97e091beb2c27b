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
(see docs/user_guide.md). After rendering, stderr says what was traced (paths
or scatterers per source kind of the first frame rendered, paths per mesh of a
[[scene.meshes]] scene), the frames written and the store's size. Re-running
the same command after an interruption keeps the finished frames and continues
with the next one; --overwrite starts again.

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
    for line in traced_lines(scenario, summary, nc):
        print(line, file=sys.stderr)
    msg = (f"{summary.path}: {summary.frames_resumed + summary.frames_rendered}/"
           f"{summary.frames_total} frames ({summary.frames_rendered} rendered now")
    msg += f", {summary.frames_resumed} kept from before)" if summary.frames_resumed else ")"
    print(msg)
    if nc:
        print(f"NetCDF export: {nc}")
    return 0


#: Names of the path kinds of :func:`raysim.pipeline.sources.path_kinds` in the summary.
_KIND_NAMES = {"specular": "specular ground", "diffuse": "diffuse", "target": "point targets",
               "po_centre": "PO centres of meshes", "other_specular": "other specular"}


def traced_lines(scenario, summary, netcdf=None) -> list[str]:
    """What ``raysim render`` traced and wrote, as lines for stderr.

    Parameters
    ----------
    scenario : raysim.scenario.Scenario
    summary : raysim.pipeline.run.RenderSummary
        Its ``truth`` is the first rendered frame's: a traced scene's paths are
        counted per kind (:func:`raysim.pipeline.sources.path_kinds`) and, for
        users' meshes, per mesh (the scene report's
        :func:`raysim.studies.scene_report.meshes.mesh_summary`).
    netcdf : path-like, optional
        The NetCDF export, whose size is given too.

    Returns
    -------
    list of str
        ``traced (frame F): ...`` (point targets, or the paths per kind, the
        clutter field's scatterers and the movers), ``meshes: ...`` for a
        ``[[scene.meshes]]`` scene, and ``wrote: ...`` (frames and sizes).
    """
    from raysim.pipeline.sources import path_kinds
    from raysim.resources import format_bytes, tree_bytes

    lines = []
    scene = scenario.scene
    if summary.first_frame is not None:
        head = f"traced (frame {summary.first_frame}):"
        paths = summary.truth.get("paths")
        if scene.kind == "points":
            lines.append(f"{head} {len(scene.targets)} point target(s) (exact echo model)")
        elif paths is not None:
            kinds = path_kinds(paths)
            parts = [f"{_KIND_NAMES.get(k, k)} {n}" for k, n in kinds.items() if n]
            lines.append(f"{head} {paths.num_paths} paths of its first trace"
                         + (f" ({', '.join(parts)})" if parts else ""))
            clutter = summary.truth.get("clutter") or {}
            if "num_scatterers" in clutter:
                lines.append(f"  clutter field: {clutter['num_scatterers']} scatterers "
                             f"(the diffuse paths above are those in view)")
            movers = [f"{len(v)} {k}" for k, v in (("car(s)", scene.movers),
                                                     ("rotor(s)", scene.rotors)) if v]
            if movers:
                lines.append(f"  movers: {', '.join(movers)} (moving scatterers, "
                             f"not in the paths above)")
            if scene.kind == "meshes":
                from raysim.studies.scene_report.meshes import mesh_boxes, mesh_summary

                per = mesh_summary(mesh_boxes(scenario), paths, {})
                lines.append("  meshes: " + ", ".join(f"{m['name']} {m['num_paths']} paths"
                                                      for m in per))
    size = f"{format_bytes(tree_bytes(summary.path))} in {summary.path}"
    if netcdf:
        size += f", {format_bytes(tree_bytes(netcdf))} in {netcdf}"
    lines.append(f"wrote: {summary.frames_rendered} frame(s) rendered now, "
                 f"{summary.frames_resumed} kept, "
                 f"{summary.frames_resumed + summary.frames_rendered}/{summary.frames_total} "
                 f"in the store; {size}")
    return lines
