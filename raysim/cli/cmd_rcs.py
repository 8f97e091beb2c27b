"""``raysim rcs``: monostatic radar cross-section of a mesh (physical optics + SBR)."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

from raysim.cli.options import MAX_SPAN_VALUES, span_grid

#: A z-up mesh's axes (x forward, y left, z up) into the frame of the epilog: +z
#: forward (az 0), +x left (az 90), +y up; a rotation (det +1), so facets keep their sides.
Z_UP_TO_RCS = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])

_EPILOG = """\
MESH is a mesh file (PLY, OBJ, STL, OFF, GLB/glTF, 3MF, COLLADA .dae; read by trimesh; in the
unit the file declares (3MF, COLLADA, glTF), else metres, or --scale) or a canonical target:
plate:A (square plate of side A), dihedral:AxB (right dihedral, faces A wide, fold B long),
trihedral:A (triangular trihedral, edge A), sphere:R (radius R), or a car: car:sedan
(detailed: wheel houses, bumpers, plates, mirrors, rims) or car:simple,
each part with its own material (--material is not used), seen at --range-m (default
50 m) from az 0 (nose) through 90 (left side) to 180 (tail), el above the horizon.
The radar sits at range * u(az, el), u = (cos el sin az, sin el, cos el cos az),
looking at the origin; canonical targets face it at az = el = 0.
SPEC is a number, a comma list (-10,0,10) or start:stop:step with stop included.
A progress bar on stderr counts the directions done (--no-progress: none).

examples:
  raysim rcs plate:0.1 --material metal --az-deg -30:30:0.5 --el-deg 0 --plot plate.png
  raysim rcs trihedral:0.1 --material metal --az-deg 0 --el-deg 0 --json
  raysim rcs plate:0.1 --material metal --az-deg 0,1,2 --el-deg 0 --range-m 15
  raysim rcs car.glb --material metal --az-deg 0:360:5 --el-deg -10 --pol HH
  raysim rcs plate_mm.stl --scale 0.001 --az-deg 0 --el-deg 0   # file in millimetres
  raysim rcs car.stl --up z --az-deg 0:180:2 --el-deg 0   # CAD frame: x forward, z up
  raysim rcs plate:0.05 --az-deg 0:90:1 --el-deg 0 --diffraction  # PO + edge fringe wave
  raysim rcs car:sedan --az-deg 0:180:1 --el-deg 0,45 --diffraction   # docs/cars.md

exit status: 0 ok, 2 bad input (values, files).
"""


def register(subparsers) -> None:
    """Add the ``rcs`` subcommand."""
    p = subparsers.add_parser(
        "rcs", help="monostatic RCS of a mesh versus angle (physical optics + SBR)",
        description="Monostatic RCS of a triangle mesh: single bounce by the physical-optics "
        "integral over each lit facet (Gordon's closed form), multiple bounces by shooting "
        "and bouncing rays (Mitsuba). Far field, or at a given range (spherical wave).",
        epilog=_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("mesh", metavar="MESH", help="mesh file or canonical target (see below)")
    p.add_argument("--material", default="metal",
                   help="material name: pec, metal, concrete, glass, dry-soil, asphalt-77ghz "
                   "(default metal)")
    p.add_argument("--az-deg", required=True, metavar="SPEC", help="azimuth(s) [deg]")
    p.add_argument("--el-deg", required=True, metavar="SPEC", help="elevation(s) [deg]")
    p.add_argument("--range-m", type=float, default=None,
                   help="radar range [m] (spherical wave); default far field")
    p.add_argument("--freq-hz", type=float, default=77e9, help="frequency [Hz] (default 77e9)")
    p.add_argument("--pol", default="VV", choices=("VV", "HH"),
                   help="co-polar channel (default VV)")
    p.add_argument("--max-bounces", type=int, default=3,
                   help="deepest bounce (1 = single-bounce PO only; default 3)")
    p.add_argument("--rays-per-wavelength", type=float, default=10.0,
                   help="SBR tube density per transverse axis (default 10)")
    p.add_argument("--scale", type=float, default=None, metavar="M_PER_UNIT",
                   help="metres per unit of a mesh file (0.001 for millimetres); left out: "
                   "the unit the file declares (3MF, COLLADA, glTF), else metres, and a file over "
                   "500 units across is refused as millimetres")
    p.add_argument("--up", choices=("y", "z"), default=None,
                   help="a mesh file's up axis: y (glTF, the frame below: +z forward, +x "
                   "left; default) or z (CAD, STL/OBJ exports: +x forward, +y left)")
    p.add_argument("--diffraction", action="store_true",
                   help="add the edge diffraction (PTD fringe wave) of the mesh's sharp and "
                   "boundary edges; conductors only; its cost is printed on stderr")
    p.add_argument("--multiple-diffraction", action="store_true",
                   help="with --diffraction, also the multiple diffraction (double and higher "
                   "orders) between the facing parallel edges of flat faces (a plate's opposite "
                   "sides, HH mostly); far field (no --range-m), mesh targets only (docs/rcs.md)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--plot", metavar="FILE", default=None, help="write a PNG pattern plot")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def parse_spec(text: str, option: str) -> np.ndarray:
    """``"5"``, ``"-10,0,10"`` or ``"start:stop:step"`` (stop included) -> angles [deg].

    Raises
    ------
    ValueError
        Naming ``option`` and the value.
    """
    s = str(text).strip()
    if ":" in s:
        return span_grid(s, option)          # names the option, the value and the limit
    try:
        values = np.array([float(x) for x in s.split(",")])
    except ValueError:
        raise ValueError(f"{option}: got {text!r}, expected a number, a comma list or "
                         "start:stop:step with step > 0 and stop >= start") from None
    if not np.all(np.isfinite(values)):
        raise ValueError(f"{option}: got {text!r}, angles must be finite")
    if len(values) > MAX_SPAN_VALUES:
        raise ValueError(f"{option}: got {text!r}, {len(values)} angles (at most "
                         f"{MAX_SPAN_VALUES})")
    return values


def load_target(text: str, scale: float | None = None, notes: list | None = None):
    """A canonical target spelling or a mesh file -> :class:`TriangleMesh` [m].

    ``scale`` (metres per file unit) and ``notes`` as in :meth:`TriangleMesh.load`.
    """
    from raysim.echoes.po.mesh import TriangleMesh
    from raysim.echoes.po.targets import canonical_target

    head = str(text).partition(":")[0]
    if head in ("plate", "dihedral", "trihedral", "sphere") and not Path(text).exists():
        if scale is not None:
            raise ValueError(f"--scale applies to a mesh file, not to the canonical target "
                             f"{text!r} (its size is in metres)")
        return canonical_target(text)
    path = Path(text)
    if not path.is_file():
        raise ValueError(f"MESH: got {text!r}, neither a mesh file nor a canonical target "
                         "(plate:A, dihedral:AxB, trihedral:A, sphere:R)")
    return TriangleMesh.load(path, scale=scale, notes=notes)


def _plot(result, path) -> None:
    from matplotlib.figure import Figure

    from raysim.io.files import atomic_savefig

    fig = Figure(figsize=(7, 4.5))
    ax = fig.add_subplot()
    db = result.rcs_dbsm
    az, el = result.azimuth_deg, result.elevation_deg
    if len(az) > 1 and len(el) > 1:
        im = ax.pcolormesh(az, el, db.T, shading="nearest")
        fig.colorbar(im, ax=ax, label="RCS [dBsm]")
        ax.set_xlabel("azimuth [deg]")
        ax.set_ylabel("elevation [deg]")
    elif len(el) > 1:
        ax.plot(el, db[0], ".-")
        ax.set_xlabel(f"elevation [deg] (azimuth {az[0]:g} deg)")
        ax.set_ylabel("RCS [dBsm]")
    else:
        ax.plot(az, db[:, 0], ".-")
        ax.set_xlabel(f"azimuth [deg] (elevation {el[0]:g} deg)")
        ax.set_ylabel("RCS [dBsm]")
    where = "far field" if result.range_m is None else f"range {result.range_m:g} m"
    ax.set_title(f"monostatic RCS, {result.frequency / 1e9:g} GHz, {result.polarisation}, {where}")
    ax.grid(True, alpha=0.3)
    atomic_savefig(fig, path, dpi=120, format="png")


def run(args) -> int:
    """Compute and print (or plot) the RCS."""
    from raysim.cli.options import check_output
    from raysim.echoes.po import monostatic_rcs, po_material

    if args.plot:
        check_output(args.plot, "file", "--plot", inputs=[("MESH", args.mesh)])
    az = parse_spec(args.az_deg, "--az-deg")
    el = parse_spec(args.el_deg, "--el-deg")
    if not (math.isfinite(args.freq_hz) and args.freq_hz > 0):
        raise ValueError(f"--freq-hz: got {args.freq_hz!r}, expected a positive frequency")
    if args.range_m is not None and not (math.isfinite(args.range_m) and args.range_m > 0):
        raise ValueError(f"--range-m: got {args.range_m!r}, expected a positive range")
    if args.multiple_diffraction and not (args.diffraction and args.range_m is None
                                        and not str(args.mesh).startswith("car:")):
        raise ValueError("--multiple-diffraction adds to --diffraction in the far field of a "
                         "mesh target: give --diffraction, leave out --range-m, not a car:")
    if str(args.mesh).startswith("car:"):
        if args.up is not None:
            raise ValueError(f"--up applies to a mesh file, not to {args.mesh!r}")
        result = _car(args, az, el)
        return _report(args, result, "per part")
    notes: list[str] = []
    mesh = load_target(args.mesh, args.scale, notes)
    if args.up is not None and not Path(args.mesh).is_file():
        raise ValueError(f"--up applies to a mesh file, not to the canonical target "
                         f"{args.mesh!r}")
    if args.up == "z":       # CAD (x forward, y left, z up) into this frame's (z, x, y)
        from raysim.echoes.po.mesh import TriangleMesh

        mesh = TriangleMesh(mesh.vertices @ Z_UP_TO_RCS.T, mesh.faces)
    for note in notes:
        print(f"note: {note}", file=sys.stderr)
    material = po_material(args.material, args.freq_hz)
    result = monostatic_rcs(mesh, material, az, el, frequency=args.freq_hz,
                            range_m=args.range_m, polarisation=args.pol,
                            max_bounces=args.max_bounces,
                            rays_per_wavelength=args.rays_per_wavelength,
                            progress=not args.no_progress, diffraction=args.diffraction,
                            multiple_diffraction=args.multiple_diffraction)
    if args.diffraction:
        info = result.info
        pairs = (f" and {info['pair_segments']} edge-pair segments"
                 if args.multiple_diffraction else "")
        print(f"note: diffraction: {info['edges']} edges in {info['edge_segments']} segments"
              f"{pairs}, {info['edge_seconds']:.3g} s of {info['seconds']:.3g} s (wall clock)",
              file=sys.stderr)
    return _report(args, result, material.name)


def _car(args, az, el):
    """``car:MODEL``: the car's parts, each with its material (raysim.studies.car_rcs)."""
    from raysim.echoes.po.rcs import RcsResult
    from raysim.studies.car_rcs import car_model, car_rcs

    parts = car_model(str(args.mesh).partition(":")[2])
    if args.scale is not None:
        raise ValueError(f"--scale applies to a mesh file, not to {args.mesh!r}")
    range_m = 50.0 if args.range_m is None else args.range_m
    r = car_rcs(parts, az, el, range_m=range_m, frequency=args.freq_hz,
                polarisation=args.pol, diffraction=args.diffraction,
                max_bounces=args.max_bounces, tubes_per_wavelength=args.rays_per_wavelength,
                progress=not args.no_progress)
    if args.diffraction:
        print(f"note: diffraction: {r.seconds:.3g} s in all (wall clock)", file=sys.stderr)
    return RcsResult(args.freq_hz, range_m, r.azimuth_deg, r.elevation_deg,
                     r.po_m2 if r.diffraction_m2 is None else r.diffraction_m2, args.pol,
                     {"diffraction": bool(args.diffraction)})


def _report(args, result, material: str) -> int:
    az, el = result.azimuth_deg, result.elevation_deg
    if args.plot:
        _plot(result, args.plot)
    if args.json:
        print(json.dumps(result.to_json()))
        return 0
    print(f"# monostatic RCS [dBsm], {result.frequency:g} Hz, {result.polarisation}, "
          f"{'far field' if result.range_m is None else f'range {result.range_m:g} m'}, "
          f"material {material}")
    print("# azimuth_deg elevation_deg rcs_dbsm")
    for i, a in enumerate(az):
        for j, e in enumerate(el):
            print(f"{a:10.3f} {e:10.3f} {result.rcs_dbsm[i, j]:10.3f}")
    return 0
