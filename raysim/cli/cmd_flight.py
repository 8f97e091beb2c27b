"""``raysim flight``: write a simulated drone flight as the files of a real one.

Writes ``flight.ulg`` (PX4 ULog), ``adc_data.bin`` (DCA1000 capture) and
``radar.cfg`` (mmWave SDK configuration) of a point target seen from a
hovering drone (:func:`raysim.pipeline.flight.write_flight`) and prints the one
``raysim compensate`` command that compensates them with what a user has (IMU
grade, lever arm, the flight controller's attitude at the first ramp or
levelling), the initial velocity and the clock offset estimated from the radar
(``--velocity radar --time-offset auto``), and the command with the simulated
offset and velocity given instead.
"""

from __future__ import annotations

import argparse
import shlex

EPILOG = """\
examples:
  raysim flight flight_dir                      # consumer MEMS IMU, 3 ms clock offset
  raysim flight flight_dir --imu tactical --frames 4 --seed 2
  raysim flight flight_dir --time-offset 0.010 --target 15,10,0
  raysim flight flight_dir --frames 4 --attitude level   # levelled attitude in the command

exit status: 0 written, 2 invalid input (the message names the option and the value).
"""


def register(subparsers) -> None:
    """Add the ``flight`` subcommand."""
    p = subparsers.add_parser(
        "flight", help="write a simulated flight as a ULog, a DCA1000 capture and its .cfg",
        description=__doc__.split("\n\n")[0], epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("folder", help="output folder (created)")
    p.add_argument("--imu", default="consumer_mems", help="IMU preset")
    p.add_argument("--imu-rate", type=float, default=1000.0, help="IMU rate [Hz]")
    p.add_argument("--time-offset", type=float, default=0.003,
                   help="IMU clock minus radar clock [s]")
    p.add_argument("--frames", type=int, default=2, help="radar frames")
    p.add_argument("--seed", type=int, default=0, help="seed of the jitter and IMU errors")
    p.add_argument("--target", default="11.3,20,0", metavar="R,AZ,EL",
                   help="target range [m], azimuth and elevation [deg]")
    p.add_argument("--attitude", choices=("flight_controller", "level"),
                   default="flight_controller",
                   help="initial attitude in the printed command: the flight controller's "
                   "estimate at the first ramp (numbers) or accelerometer levelling")
    p.set_defaults(func=run)


def run(args) -> int:
    """Run ``raysim flight``; returns the exit code."""
    from raysim.cli.options import check_output
    from raysim.pipeline.flight import write_flight
    from raysim.platform.imu_spec import PRESETS

    check_output(args.folder, "dir", "folder")
    if args.imu not in PRESETS:
        raise ValueError(f"--imu: got {args.imu!r}, expected one of {sorted(PRESETS)}")
    try:
        target = tuple(float(v) for v in args.target.split(","))
    except ValueError:
        target = ()
    if len(target) != 3:
        raise ValueError(f"--target: got {args.target!r}, expected R,AZ,EL (three numbers)")
    if args.frames < 1:
        raise ValueError(f"--frames: got {args.frames}, expected a positive integer")
    f = write_flight(args.folder, imu=args.imu, imu_rate=args.imu_rate,
                     time_offset=args.time_offset, seed=args.seed, frames=args.frames,
                     target=target)
    out = f"{args.folder.rstrip('/')}/compensated.zarr"
    print(f"wrote {f.imu_log}, {f.capture}, {f.radar_config}")
    cells = ("--range-m", f"{target[0] - 0.5}:{target[0] + 0.5}", "--el-deg", "0:0:1")
    print("compensate with (velocity and clock offset estimated from the radar):")
    print("  raysim " + shlex.join(f.calibrating_command(out, *cells, attitude=args.attitude)))
    print("or with the simulated clock offset and initial velocity given:")
    print("  raysim " + shlex.join(f.command(out, *cells)))
    return 0
