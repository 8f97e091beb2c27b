"""``raysim scene-report``: map entropy of the bundled scenes, hovering vs compensated."""

from __future__ import annotations

import argparse
import sys
import textwrap

from raysim.vocabulary import CHAINS, MAP_TITLES, MAPS, REFERENCE

#: Maps of the report (:data:`raysim.studies.scene_report.REPORT_MAPS`, not imported
#: here: the report's modules take seconds to import, registration must not).
REPORT_MAPS = ("rd", "ra", "ae")
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
  raysim scene-report --bench-reprojection --threads 2
      time re-projection against re-tracing per chirp (JSON on stdout)

outputs (every file written atomically): <scene>_rd.png, <scene>_ra.png, <scene>_ae.png
(one panel for the stationary reference, one per chain), <scene>.json, summary.json,
report.md, index.html.
"""


def register(subparsers) -> None:
    """Add the ``scene-report`` subcommand to ``subparsers``."""
    maps = ", ".join(f"{m} ({MAP_TITLES[m].split(' ', 1)[1].strip('()')}, dims "
                     f"{' x '.join(MAPS[m])})" for m in REPORT_MAPS)
    p = subparsers.add_parser(
        "scene-report",
        help="ray-traced scenes under hover motion: map entropy, uncompensated vs compensated",
        description=textwrap.fill(
            "Trace every bundled scene once, re-project it onto a stationary and a hovering "
            f"radar, and compare the {REFERENCE} reference with the chains {', '.join(CHAINS)} "
            f"of the hovering radar: maps {maps} (PNG, azimuth on x), their entropy, the RD "
            "power off the zero-Doppler ridge, CFAR detections against the known reflectors "
            "(per-scene JSON, summary.json, report.md, index.html).", width=88),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--scenes", nargs="+", metavar="NAME", default=None,
                   help="scenes to process (default: all bundled scenes)")
    p.add_argument("--out", default="scene_report", metavar="DIR",
                   help="output directory (default: ./scene_report)")
    p.add_argument("--chains", default=",".join(CHAINS), metavar="LIST",
                   help=f"comma list of chains of the hovering radar, from {', '.join(CHAINS)} "
                   f"and paper:published (default: {','.join(CHAINS)}); the {REFERENCE} "
                   "reference is always computed")
    p.add_argument("--quick", action="store_true",
                   help="64 chirps, 8x8 UPA, 20k rays, 6 deg grid (about 20 s per scene on 2 "
                   "cores) instead of 128 chirps, 12x12 UPA, 100k rays, 3 deg grid")
    p.add_argument("--imu", default="ideal", metavar="PRESET",
                   help="IMU preset of the pose estimate (default: ideal)")
    p.add_argument("--jitter-axes", default=None, metavar="LIST",
                   help="comma list of the axes the hover jitter moves, from x, y, z, roll, "
                   "pitch, yaw (default: all; z,roll,pitch,yaw keeps the horizontal position)")
    p.add_argument("--jitter-seed", type=int, default=None, metavar="N",
                   help="seed of the hover jitter (default: 7)")
    p.add_argument("--threads", type=int, default=None, metavar="N",
                   help="Dr.Jit threads of the ray tracer (default: all cores)")
    p.add_argument("--mover-speed", type=float, default=None, metavar="MPS",
                   help="a car (PO + SBR mesh) drives east through each scene at this speed "
                   "[m/s], reported as a mover off the clutter ridge (default: none)")
    p.add_argument("--clutter", choices=REPORT_CLUTTER, default=None,
                   help="ground clutter and multipath: the persistent clutter field (default: "
                   "calibrated sigma0, Rayleigh cells, rough-surface specular, target-ground "
                   "ghosts) or Sionna's own diffuse paths and mirror")
    p.add_argument("--clutter-per-cell", type=float, default=None, metavar="N",
                   help="scatterers of the clutter field per range x angle cell (default: 10, "
                   "which gives Rayleigh cells)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")
    p.add_argument("--bench-reprojection", action="store_true",
                   help="only time re-projection vs re-tracing per chirp and print JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``raysim scene-report``; returns the exit code."""
    from dataclasses import replace

    from raysim.cli.options import chains_option, check_output, known_name
    from raysim.echoes.rt.scenes import SCENES
    from raysim.platform.imu import PRESETS
    from raysim.studies.scene_report import FULL, QUICK, write_scene_report
    from raysim.vocabulary import parse_chains

    for name in args.scenes or ():
        known_name(name, SCENES, "--scenes", "scene")
    known_name(args.imu, PRESETS, "--imu", "IMU preset")
    if args.threads is not None and args.threads < 1:
        raise ValueError(f"--threads must be a positive integer, got {args.threads}")
    chains = parse_chains(chains_option(args.chains))
    if args.clutter_per_cell is not None and args.clutter == "sionna":
        raise ValueError("--clutter-per-cell sets the clutter field's density; it needs "
                         "--clutter field, got --clutter sionna")
    if args.bench_reprojection:
        import json

        from raysim.echoes.rt import backend
        from raysim.studies.scene_report import bench_reprojection

        backend.configure("cpu", threads=args.threads)
        print(json.dumps(bench_reprojection(), indent=1))
        return 0
    check_output(args.out, "dir", "--out")
    settings = replace(QUICK if args.quick else FULL, imu=args.imu)
    if args.jitter_axes is not None:
        settings = replace(settings, jitter_axes=tuple(
            a.strip() for a in args.jitter_axes.split(",") if a.strip()))
    if args.jitter_seed is not None:
        settings = replace(settings, jitter_seed=args.jitter_seed)
    if args.mover_speed is not None:
        settings = replace(settings, mover_speed=args.mover_speed)
    if args.clutter is not None:
        settings = replace(settings, clutter=args.clutter)
    if args.clutter_per_cell is not None:
        settings = replace(settings, clutter_per_cell=args.clutter_per_cell)
    from raysim.echoes.rt import backend

    backend.configure("cpu", threads=args.threads)
    summary = write_scene_report(args.out, scenes=args.scenes, settings=settings,
                                 progress=not args.no_progress, chains=chains)
    for name, s in summary.items():
        cols = [s["reference"]] + [{"key": c, **v} for c, v in s["chains"].items()]
        cells = ", ".join(f"{m} " + "/".join(f"{c['metrics'][f'entropy_{m}_nats']:.3f}"
                                             for c in cols)
                          for m in REPORT_MAPS)
        margin = s["exact_within_margin"]
        flag = ("" if margin is None else
                f"; exact {'within' if margin else 'OUTSIDE'} {s['entropy_margin_nats']} nats "
                f"of {REFERENCE}")
        print(f"{name}: entropy [nats] {'/'.join(c['key'] for c in cols)}: {cells}{flag}",
              file=sys.stdout)
    print(f"wrote {args.out}/report.md, index.html, summary.json")
    return 0
