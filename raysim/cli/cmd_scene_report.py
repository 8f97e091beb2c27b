"""``raysim scene-report``: map entropy of scenes and scenarios, hovering vs compensated."""

from __future__ import annotations

import argparse
import sys
import textwrap

from raysim.cli.options import add_decimation_options
from raysim.vocabulary import CHAINS, MAP_TITLES, MAPS, REFERENCE

#: Maps of the report (:data:`raysim.studies.scene_report.REPORT_MAPS`, not imported
#: here: the report's modules take seconds to import, registration must not).
REPORT_MAPS = ("rd", "ra", "ae")
#: Scene entropy metric of each map (:data:`raysim.measure.scene.SCENE_METRICS`).
SCENE_METRICS = {m: f"scene_entropy_{m}_nats" for m in REPORT_MAPS}
#: Clutter models of the report (:data:`raysim.studies.scene_report.REPORT_CLUTTER`).
REPORT_CLUTTER = ("field", "sionna")

EPILOG = """\
examples:
  raysim scene-report --scenes flat_reflectors --quick --out out/scene_report
      one scene with the QUICK settings (about 20 s on 2 cores)
  raysim scene-report --out scene_report --threads 2
      all bundled scenes with the FULL settings (about 10 minutes)
  raysim scene-report --scenes parking_lot --imu consumer_mems --chains none,exact --out out/
      a consumer MEMS IMU, only the uncompensated and the exact chain
  raysim scene-report --scenario examples/case_rotation_y.toml --quick --out out/rot
      a point-target scenario: the scene maps, and the point metrics of its target
      per chain (the values `raysim simulate --scenario` prints)
  raysim scene-report --scenario examples/scene_user_meshes.toml --quick --out out/meshes
      the bundled example of users' meshes (PLY ground, OBJ building, GLB car)
  raysim scene-report --scenario my_meshes.toml --scenes flat_reflectors --out out/
      a scenario with [[scene.meshes]] beside a bundled scene
  raysim scene-report --bench-reprojection --threads 2
      time re-projection against re-tracing per chirp (JSON on stdout)

A scenario file keeps its own radar, array, motion, IMU and scene; --quick and the
other options set the report's knobs (rays, grid, range window) and, when given,
--imu, --jitter-seed and --clutter override the scenario's.

outputs (every file written atomically): <scene>_rd.png, <scene>_ra.png, <scene>_ae.png
(one panel for the stationary reference, one per chain), <scene>.json, summary.json,
report.md, index.html (a scenario is named by its `name`). A scenario with
[[scene.meshes]] also gets placement.png (top view of the meshes and the radar, written
before the trace), its meshes named and marked on the RA and AE maps, and a table of
what the radar saw of each (paths, power, detections). The known-reflector table gives
each reflector's SNR over the CFAR noise, the threshold and the reason of a miss.
"""


def register(subparsers) -> None:
    """Add the ``scene-report`` subcommand to ``subparsers``."""
    maps = ", ".join(f"{m} ({MAP_TITLES[m].split(' ', 1)[1].strip('()')}, dims "
                     f"{' x '.join(MAPS[m])})" for m in REPORT_MAPS)
    p = subparsers.add_parser(
        "scene-report",
        help="ray-traced scenes under hover motion: map entropy, uncompensated vs compensated",
        description=textwrap.fill(
            "Trace every bundled scene (or scenario file) once, re-project it onto a "
            "stationary and a hovering "
            f"radar, and compare the {REFERENCE} reference with the chains {', '.join(CHAINS)} "
            f"of the hovering radar: maps {maps} (PNG, azimuth on x), their entropy, the RD "
            "power off the zero-Doppler ridge, CFAR detections against the known reflectors, "
            "and the point metrics of a scenario's reference target "
            "(per-scene JSON, summary.json, report.md, index.html).", width=88),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--scenes", nargs="+", metavar="NAME", default=None,
                   help="bundled scenes to process (default: all bundled scenes, or none "
                   "when --scenario is given)")
    p.add_argument("--scenario", action="append", default=[], metavar="FILE",
                   help="a scenario TOML file (point targets, a bundled scene or "
                   "[[scene.meshes]]) processed with its own radar, array, motion and IMU; "
                   "repeatable")
    p.add_argument("--out", default="scene_report", metavar="DIR",
                   help="output directory (default: ./scene_report)")
    p.add_argument("--chains", default=",".join(CHAINS), metavar="LIST",
                   help=f"comma list of chains of the hovering radar, from {', '.join(CHAINS)} "
                   f"and paper:published (default: {','.join(CHAINS)}); the {REFERENCE} "
                   "reference is always computed")
    p.add_argument("--quick", action="store_true",
                   help="bundled scenes: 64 chirps, 8x8 UPA, 20k rays, 6 deg grid (about 20 s "
                   "per scene on 2 cores) instead of 128 chirps, 12x12 UPA, 100k rays, 3 deg "
                   "grid; scenario files: 20k rays and the 6 deg grid")
    p.add_argument("--imu", default=None, metavar="PRESET",
                   help="IMU preset of the pose estimate (default: ideal for the bundled "
                   "scenes, a scenario file's own)")
    p.add_argument("--jitter-axes", default=None, metavar="LIST",
                   help="comma list of the axes the hover motion moves, from x, y, z, roll, "
                   "pitch, yaw (default: all; z,roll,pitch,yaw keeps the horizontal position; "
                   "traced scenes only)")
    p.add_argument("--jitter-seed", type=int, default=None, metavar="N",
                   help="seed of the hover jitter (default: 7, or a scenario file's own)")
    p.add_argument("--range-window", default=None, metavar="LOW,HIGH",
                   help="processed range window [m] (default: 12,45, cut to a scenario radar's "
                        "unambiguous range and widened, as the +-60 deg grid is, to hold every "
                        "mesh and point target; a window given is kept)")
    p.add_argument("--threads", type=int, default=None, metavar="N",
                   help="Dr.Jit threads of the ray tracer (default: all cores)")
    p.add_argument("--mover-speed", type=float, default=None, metavar="MPS",
                   help="a car (PO + SBR mesh) drives east through each scene at this speed "
                   "[m/s], reported as a mover off the clutter ridge (default: none)")
    p.add_argument("--clutter", choices=REPORT_CLUTTER, default=None,
                   help="ground clutter and multipath: the persistent clutter field (default, "
                   "or a scenario file's own: "
                   "calibrated sigma0, Rayleigh cells, rough-surface specular, target-ground "
                   "ghosts) or Sionna's own diffuse paths and mirror")
    p.add_argument("--clutter-per-cell", type=float, default=None, metavar="N",
                   help="scatterers of the clutter field per range x angle cell, at every "
                   "incidence, on the ground and on walls of clutter materials (default: 10, "
                   "which gives Rayleigh cells)")
    add_decimation_options(p)
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--bench-reprojection", action="store_true",
                   help="only time re-projection vs re-tracing per chirp and print JSON")
    p.set_defaults(func=run)


def _range_window(text: str) -> tuple[float, float]:
    """``"12,45"`` -> ``(12.0, 45.0)``; errors name the option and the value."""
    import math

    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise ValueError(f"--range-window: got {text!r}, expected LOW,HIGH in metres "
                         f"(e.g. 12,45)") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and 0 <= lo < hi):
        raise ValueError(f"--range-window: got {text!r}, expected 0 <= LOW < HIGH [m]")
    return lo, hi


def _overrides(args: argparse.Namespace) -> dict:
    """Scenario values given on the command line (``ReportSettings.with_values`` keywords)."""
    out = {}
    if args.imu is not None:
        out["imu"] = args.imu
    if args.jitter_seed is not None:
        out["jitter_seed"] = args.jitter_seed
    if args.clutter is not None:
        out["clutter"] = args.clutter
    if args.clutter_per_cell is not None:
        out["clutter_per_cell"] = args.clutter_per_cell
    if args.decimate is not None:
        out["decimate"] = args.decimate
    if args.decimate_tolerance is not None:
        out["decimate_tolerance"] = args.decimate_tolerance
    return out


def run(args: argparse.Namespace) -> int:
    """Execute ``raysim scene-report``; returns the exit code."""
    from raysim.cli.options import chains_option, check_output, known_name
    from raysim.echoes.rt.scenes import SCENES
    from raysim.platform.imu import PRESETS
    from raysim.scenario import load_scenario
    from raysim.studies.scene_report import FULL, QUICK, write_scene_report
    from raysim.vocabulary import parse_chains

    for name in args.scenes or ():
        known_name(name, SCENES, "--scenes", "scene")
    if args.imu is not None:
        known_name(args.imu, PRESETS, "--imu", "IMU preset")
    if args.threads is not None and args.threads < 1:
        raise ValueError(f"--threads must be a positive integer, got {args.threads}")
    chains = parse_chains(chains_option(args.chains))
    if args.clutter_per_cell is not None and args.clutter == "sionna":
        raise ValueError("--clutter-per-cell sets the clutter field's density; it needs "
                         "--clutter field, got --clutter sionna")
    if args.bench_reprojection:
        import json

        from raysim.bench.reprojection import bench_scene_reprojection
        from raysim.echoes.rt import backend

        backend.configure("cpu", threads=args.threads)
        print(json.dumps(bench_scene_reprojection(), indent=1))
        return 0
    check_output(args.out, "dir", "--out", names=("index.html", "report.md", "summary.json",
                                                 "placement.png"))
    knobs = {}
    if args.jitter_axes is not None:
        knobs["jitter_axes"] = tuple(a.strip() for a in args.jitter_axes.split(",")
                                     if a.strip())
    if args.mover_speed is not None:
        knobs["mover_speed"] = args.mover_speed
    if args.range_window is not None:
        knobs["range_window"] = _range_window(args.range_window)
    overrides = _overrides(args)
    base = QUICK if args.quick else FULL
    settings = base.with_values(**knobs, **overrides)
    scenarios = []
    for path in args.scenario:
        sc = load_scenario(path)
        st = settings.for_scenario(sc).with_values(**overrides)  # checks knobs against it
        scenarios.append(st.scenario)
    from raysim.echoes.rt import backend

    if args.scenes or any(sc.scene.kind != "points" for sc in scenarios) or not scenarios:
        backend.configure(None, threads=args.threads)   # RAYSIM_RT_VARIANT, else the CPU
    summary = write_scene_report(args.out, scenes=args.scenes, settings=settings,
                                 progress=not args.no_progress, chains=chains,
                                 scenarios=scenarios)
    for name, s in summary.items():
        cols = [s["reference"]] + [{"key": c, **v} for c, v in s["chains"].items()]
        cells = ", ".join(f"{m} " + "/".join(f"{c['metrics'][SCENE_METRICS[m]]:.3f}"
                                             for c in cols)
                          for m in REPORT_MAPS)
        margin = s["exact_within_margin"]
        flag = ("" if margin is None else
                f"; exact {'within' if margin else 'OUTSIDE'} {s['entropy_margin_nats']} nats "
                f"of {REFERENCE}")
        print(f"{name}: scene entropy [nats] {'/'.join(c['key'] for c in cols)}: "
              f"{cells}{flag}", file=sys.stdout)
    print(f"wrote {args.out}/report.md, index.html, summary.json")
    return 0
