"""``raysim stability``: compute every stability map of the motion compensation."""

from __future__ import annotations

import argparse

EPILOG = """\
examples:
  raysim stability --out out/stability --quick
      every map on small axes (2-5 values per axis), a few minutes on 2 cores
  raysim stability --out out/stability
      the full maps (340 points)
  raysim stability --out out/stability --maps clock lever_arm --executor serial
      two maps, points in a plain loop instead of a Dask cluster
  raysim stability --out out/stability_forward --quick --mounting-deg forward
      the same body motions seen by a forward-looking radar

maps: rotation_azimuth rotation_elevation frequency_chirps imu_grade imu_rate clock
      lever_arm hover_jitter
chains: none, paper, paper:published, exact (raysim.vocabulary)
per map: NAME.png (failure boundaries), NAME.nc (metrics pseudo_velocity_mps,
pseudo_velocity_bins, doppler_width_hz, angle_error_worst_deg, angle_error_deg,
map_angle_error_deg, entropy_ae_nats per chain, grid point and seed), NAME.json
(seed medians, fail fractions), plus summary.json; see docs/stability.md.
"""


def register(subparsers) -> None:
    """Add the ``stability`` subcommand to ``subparsers``."""
    p = subparsers.add_parser(
        "stability",
        help="stability maps of the compensation chains (figures, NetCDF, JSON)",
        description="Sweep rotation amplitude x target angle, motion frequency x frame length, "
        "IMU grade, IMU rate, clock errors, lever-arm error and hover jitter; write one PNG "
        "(failure boundary drawn), one NetCDF and one JSON per map plus summary.json, and "
        "print a table of the worst fail fraction per map and chain. Finished maps found in "
        "OUT are reused, so an interrupted run resumes.",
        epilog=EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter,
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
    p.add_argument("--mounting-deg", default=None, metavar="YAW,PITCH,ROLL|NAME",
                   help="radar mounting R_BA: Z-Y-X Euler angles [deg] or down, forward, "
                   "oblique; target angles in the mounted radar's nominal frame "
                   "(default: down)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Execute ``raysim stability``; prints the summary table; returns the exit code."""
    from raysim.cli.options import check_output, known_name
    from raysim.platform.mounting import mounting_deg
    from raysim.studies.stability import MAPS, summary_table, write_stability

    for name in args.maps or ():
        known_name(name, MAPS, "--maps", "stability map")
    mounting_deg(args.mounting_deg)          # checked before anything is written
    maps = args.maps or list(MAPS)
    check_output(args.out, "dir", "--out", names=["summary.json"] + [
        f"{m}.{ext}" for m in maps for ext in ("json", "nc", "png")])
    summary = write_stability(args.out, quick=args.quick, maps=args.maps,
                              progress=not args.no_progress, executor=args.executor,
                              mounting_deg=args.mounting_deg)
    print(summary_table(summary))
    print(f"wrote {len(summary)} maps to {args.out}")
    return 0
