"""``raysim score``: a compensated store of a simulated flight against the flight's truth.

Reads the ``truth.json`` that ``raysim flight`` wrote into the flight's folder and
measures every target in every frame of the store (the beam metrics of
:mod:`raysim.measure.beams`: angle error, residual pseudo-velocity, Doppler power
outside +-1 bin) and the store's clock offset against the stated limits
(:data:`raysim.pipeline.flight_truth.LIMITS`), whatever tool compensated it.
"""

from __future__ import annotations

import argparse
import json

EPILOG = """\
examples:
  raysim flight flight_dir --targets default5
  raysim compensate ...  --out flight_dir/compensated.zarr   # the printed command
  raysim score flight_dir flight_dir/compensated.zarr
  raysim score flight_dir flight_dir/compensated.zarr --json

exit status: 0 every limit held, 1 a limit missed, 2 invalid input (no truth.json, a
store whose range cells miss a target).
"""


def register(subparsers) -> None:
    """Add the ``score`` subcommand."""
    p = subparsers.add_parser(
        "score", help="score a compensated store of a simulated flight against its truth",
        description=__doc__.split("\n\n")[0], epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("folder", help="the flight's folder (written by raysim flight)")
    p.add_argument("store", help="the compensated store (raysim compensate --out)")
    p.add_argument("--first-frame", type=int, default=None, metavar="K",
                   help="flight frame of the store's first frame (default: the store's "
                   "frame coordinate, which compensate --frames K:... sets)")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    """Execute ``raysim score``; returns the exit code."""
    from pathlib import Path

    from raysim.pipeline.flight_truth import score_flight

    if args.first_frame is not None and args.first_frame < 0:
        raise ValueError(f"--first-frame must be >= 0, got {args.first_frame}")
    if not Path(args.store).exists():
        raise ValueError(f"store {args.store!r} does not exist; expected the output of "
                         f"raysim compensate")
    s = score_flight(args.folder, args.store, first=args.first_frame)
    if args.json:
        print(json.dumps(s, indent=1))
    else:
        units = {"beam_angle_error_deg": "deg", "beam_pseudo_velocity_bins": "bin",
                 "doppler_leakage_db": "dB", "offset_error_ms": "ms"}
        print("worst over targets and frames (limit, held):")
        for k, v in s["worst"].items():
            text = "not in the store" if v is None else f"{v:+.3f} {units[k]}"
            held = {True: "yes", False: "NO", None: "-"}[s["passed"][k]]
            print(f"  {k}: {text} (limit {s['limits'][k]:g} {units[k]}, {held})")
        print("per target, frame: angle [deg], pseudo-velocity [bin], leakage [dB]")
        for j, rows in enumerate(s["targets"]):
            print(f"  target {j}: " + "; ".join(f"{a:.3f}, {b:+.3f}, {c:.1f}"
                                                  for a, b, c in rows))
    return 0 if s["passed"]["all"] else 1
