"""``raysim reproduce``: the paper's experiments, uncompensated and compensated."""

from __future__ import annotations

import argparse
import sys

EPILOG = """\
examples:
  raysim reproduce --out out/reproduction
  raysim reproduce --out /tmp/repro --no-figures
  raysim reproduce --quick --cases rotation_y,yaw --out /tmp/quick
  raysim reproduce --cases rotation_y --chains none,paper,paper:published --out /tmp/rot
  raysim reproduce --imu consumer_mems --seeds 20 --chains none,exact --out /tmp/mems
  raysim reproduce --velocity hover --imu-rate 500 --out /tmp/hover

cases: stationary, rotation_y, yaw, translation_y, translation_z (each is the
scenario of `raysim simulate --case NAME`).
chains: none, paper, paper:published (the paper's rotation phase v_r(nT) nT),
exact. Metrics use the names of raysim.vocabulary.METRICS (pseudo_velocity_mps,
doppler_width_hz, angle_error_deg, entropy_ae_nats, ...).

exit status: 0 success, 2 invalid input (the message names the offending value).
"""


def register(subparsers) -> None:
    """Add the ``reproduce`` subcommand."""
    from raysim.cli.options import chains_help

    p = subparsers.add_parser(
        "reproduce",
        help="run the paper's experiments with and without motion compensation",
        description="Render the paper's cases (scenarios) with the exact point-target oracle, "
        "simulate an IMU, and compare the uncompensated processing (chain none) with the "
        "paper's compensation chain and the exact rigid-body projection. Prints one table "
        "(ours beside the paper's values), writes reproduction.json / reproduction.csv and "
        "RA/RD/AE figures.",
        epilog=EPILOG,
        formatter_class=lambda prog: argparse.RawDescriptionHelpFormatter(prog, width=96),
    )
    p.add_argument("--out", default="reproduction", metavar="DIR",
                   help="output directory for the table and figures/ (default: reproduction)")
    p.add_argument("--cases", default=None, metavar="NAMES",
                   help="comma-separated case names (default: all of "
                   "stationary,rotation_y,yaw,translation_y,translation_z)")
    p.add_argument("--imu", default="ideal", metavar="PRESET",
                   help="IMU preset: ideal (default), tactical or consumer_mems")
    p.add_argument("--seeds", type=int, default=None, metavar="N",
                   help="IMU seeds (mean and spread); default 1 for ideal, 20 otherwise")
    p.add_argument("--velocity", choices=("given", "hover"), default="given",
                   help="initial velocity: from the flight controller (truth at t=0, default) "
                   "or the hover assumption (zero mean over the IMU record)")
    p.add_argument("--imu-rate", type=float, default=None, metavar="HZ",
                   help="IMU output rate (default: the scenario's imu.rate_hz, 1000)")
    p.add_argument("--quick", action="store_true",
                   help="reduced size: 2.5 MHz sampling (radar.sample_rate_hz), a narrower "
                   "figure window")
    p.add_argument("--chains", default="none,paper,paper:published,exact", metavar="NAMES",
                   help=chains_help("none,paper,paper:published,exact"))
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.set_defaults(func=run)


def run(args) -> int:
    """Execute ``raysim reproduce``; returns the exit code."""
    from raysim.cli.options import chains_option, check_output, known_name
    from raysim.platform.imu import PRESETS
    from raysim.scenario.paper_cases import PAPER_CASES
    from raysim.studies.reproduce import (
        MAX_SEEDS,
        ReproductionSettings,
        format_table,
        reproduce,
    )

    known_name(args.imu, PRESETS, "--imu", "IMU preset")
    seeds = args.seeds if args.seeds is not None else (1 if args.imu == "ideal" else 20)
    if not 1 <= seeds <= MAX_SEEDS:
        raise ValueError(f"--seeds: got {seeds}, expected 1 to {MAX_SEEDS} (each seed renders "
                         f"every case again)")
    if args.imu_rate is not None and not args.imu_rate > 0:
        raise ValueError(f"--imu-rate must be a positive rate in Hz, got {args.imu_rate}")
    chains = chains_option(args.chains)
    cases = None if not args.cases else [c.strip() for c in args.cases.split(",") if c.strip()]
    if args.cases is not None and not cases:
        raise ValueError(f"--cases: got {args.cases!r}, expected case names separated by commas")
    for case in cases or ():
        known_name(case, PAPER_CASES, "--cases", "case")
    check_output(args.out, "dir", "--out", names=("reproduction.json", "reproduction.csv"))
    make = ReproductionSettings.quick if args.quick else ReproductionSettings
    overrides = {} if args.imu_rate is None else {"imu.rate_hz": float(args.imu_rate)}
    settings = make(overrides=overrides, velocity=args.velocity)
    result = reproduce(cases, imu=args.imu, seeds=seeds, settings=settings, out_dir=args.out,
                       figures=not args.no_figures, chains=chains,
                       progress=lambda msg: print(msg, file=sys.stderr, flush=True))
    print(format_table(result["rows"]))
    print(f"\nwrote {args.out}/reproduction.json, {args.out}/reproduction.csv"
          + ("" if args.no_figures else f" and figures in {args.out}/figures"))
    return 0
