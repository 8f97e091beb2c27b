"""``raysim flight``: write a simulated drone flight as the files of a real one.

Writes ``flight.ulg`` (PX4 ULog), ``adc_data.bin`` (DCA1000 capture),
``radar.cfg`` (mmWave SDK configuration) and ``truth.json`` (what was simulated,
for ``raysim score``) of a point target seen from a
hovering drone (:func:`raysim.pipeline.flight.write_flight`) and prints the one
``raysim compensate`` command that compensates them with what a user has (IMU
grade, lever arm, the flight controller's attitude at the first ramp or
levelling), the initial velocity and the clock offset estimated from the radar
(``--velocity radar --time-offset auto``), and the command with the simulated
offset and velocity given instead.
"""

from __future__ import annotations

import argparse
import math
import shlex

import numpy as np

EPILOG = """\
examples:
  raysim flight flight_dir                      # consumer MEMS IMU, 3 ms clock offset
  raysim flight flight_dir --imu tactical --frames 4 --seed 2
  raysim flight flight_dir --time-offset 0.010 --target 15,10,0
  raysim flight flight_dir --frames 4 --attitude level   # levelled attitude in the command
  raysim flight flight_dir --targets default5 --imu-rate 250 --imu-boxcar \\
      --log-gaps 3 --clock-drift-ppm 20             # as a flight controller logs it
  raysim flight flight_dir --target 6,-10,0 --target 8,15,5 --board xWR16xx
  raysim flight flight_dir --mounting-deg forward --target 7,10,0 --no-attitude
  raysim flight flight_dir --targets default5 --clutter-scene parking_lot \\
      --clutter-altitude 8                          # ground 8 m below, in range
  raysim flight flight_dir --decimate off           # every chirp exact (oracle)

exit status: 0 written, 2 invalid input (the message names the option and the value).
"""


def register(subparsers) -> None:
    """Add the ``flight`` subcommand."""
    from raysim.cli.options import add_decimation_options
    from raysim.io.ti_boards import board_names
    from raysim.pipeline.flight import DEFAULT_BOARD

    p = subparsers.add_parser(
        "flight", help="write a simulated flight as a ULog, a DCA1000 capture and its .cfg",
        description=__doc__.split("\n\n")[0], epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("folder", help="output folder (created)")
    p.add_argument("--imu", default="consumer_mems", help="IMU preset")
    p.add_argument("--imu-rate", type=float, default=1000.0, help="logged IMU rate [Hz]")
    p.add_argument("--imu-boxcar", action="store_true",
                   help="log the IMU as a flight controller does: --imu-fast-rate samples "
                   "averaged over each --imu-rate interval (PX4 sensor_combined, ArduPilot IMU)")
    p.add_argument("--imu-fast-rate", type=float, default=2000.0,
                   help="internal IMU rate of --imu-boxcar [Hz], a multiple of --imu-rate")
    p.add_argument("--log-gaps", type=int, default=0, metavar="N",
                   help="N logger gaps of 50-160 ms (seeded), outside the window a "
                   "compensation uses unless --gaps-in-capture")
    p.add_argument("--gaps-in-capture", action="store_true",
                   help="place the first logger gap inside the capture (the printed commands "
                   "then carry --max-gap)")
    p.add_argument("--time-offset", type=float, default=0.003,
                   help="IMU clock minus radar clock [s]")
    p.add_argument("--clock-drift-ppm", type=float, default=0.0,
                   help="IMU clock rate error [ppm]")
    p.add_argument("--no-attitude", action="store_true",
                   help="leave the flight controller's attitude (vehicle_attitude) out of the "
                   "log")
    p.add_argument("--frames", type=int, default=2, help="radar frames")
    p.add_argument("--seed", type=int, default=0,
                   help="seed of the jitter, the IMU errors and the logger gaps")
    p.add_argument("--target", action="append", default=None, metavar="R,AZ,EL",
                   help="a stationary target: range [m], azimuth and elevation [deg] in the "
                   "radar frame; repeatable (default 11.3,20,0)")
    p.add_argument("--targets", choices=("default5",), default=None,
                   help="a set of targets: default5 = five targets at 4.5-8.8 m, azimuth "
                   "-25..30 deg, elevation -5/0/+5 deg")
    p.add_argument("--board", default=DEFAULT_BOARD, metavar="BOARD",
                   help=f"TI board of the capture (antennas, RX feed signs, LVDS lanes): one "
                   f"of {', '.join(board_names())}")
    p.add_argument("--mounting-deg", default=None, metavar="YAW,PITCH,ROLL|NAME",
                   help="radar mounting on the body, Z-Y-X Euler angles of R_BA [deg], or "
                   "down (default), forward, oblique")
    p.add_argument("--clutter-scene", default=None, metavar="SCENE",
                   help="add the ground clutter field of a bundled scene (flat_reflectors, "
                   "parking_lot, rough_terrain) where the mounted radar points, rendered by "
                   "the same oracle")
    p.add_argument("--clutter-altitude", type=float, default=None, metavar="METRES",
                   help="hover height above the clutter scene's ground [m] (default: the "
                   "scene's)")
    p.add_argument("--clutter-max-scatterers", type=int, default=200_000, metavar="N",
                   help="bound on the clutter field's scatterers (cost; density scaled down)")
    p.add_argument("--clutter-specular", action="store_true",
                   help="add the ground's coherent specular mirror below the radar "
                   "(Fresnel x Ament of its material) to the clutter")
    p.add_argument("--lever-arm", default="0,0,0.05", metavar="X,Y,Z",
                   help="radar phase centre in the body frame [m]")
    p.add_argument("--attitude", choices=("log", "flight_controller", "level"), default="log",
                   help="initial attitude in the printed command: the log's vehicle_attitude "
                   "(read by compensate; level when the log has none), the flight controller's "
                   "estimate at the first ramp as numbers, or accelerometer levelling")
    add_decimation_options(p, scenario=False)
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar and no size announcement")
    p.set_defaults(func=run)


def _triple(text: str, option: str) -> tuple:
    try:
        v = tuple(float(x) for x in text.split(","))
    except ValueError:
        v = ()
    if len(v) != 3:
        raise ValueError(f"{option}: got {text!r}, expected three comma-separated numbers")
    return v


#: How far [deg] past the widest target the printed azimuth grid reaches where
#: compensate's default grid does not hold it (its main lobe).
AZIMUTH_GRID_MARGIN_DEG = 10.0
#: Finest step [deg] of the printed elevation grid (a target between its values is
#: measured off its beam by at most half of it) and the most values it may have.
ELEVATION_GRID_STEP_DEG = 0.1
ELEVATION_GRID_MAX_VALUES = 41


#: A board that resolves elevation gets a grid this fine [deg] and this much wider than
#: its targets' elevations [deg] each side: the hovering platform's displacement moves a
#: target's apparent elevation off its nominal one (5 cm at 4.5 m: 0.6 deg), and the
#: IWR6843AOP's pattern, not separable in azimuth and elevation, moves the azimuth peak
#: of a beam 0.7 deg off its target's elevation by up to 0.25 deg.
ELEVATION_FINE_STEP_DEG, ELEVATION_FINE_MARGIN_DEG = 0.5, 1.5


def elevation_grid(elevations, resolves: bool = False) -> str:
    """``LO:HI:STEP`` [deg] of a beam grid holding every target elevation: the step the
    largest that divides their differences (in tenths of a degree), or where that gives
    more than :data:`ELEVATION_GRID_MAX_VALUES` values, the finest step that does not
    (a target between two values is then measured up to half a step off its beam). For
    a board that ``resolves`` elevation: :data:`ELEVATION_FINE_STEP_DEG` steps over the
    elevations widened by :data:`ELEVATION_FINE_MARGIN_DEG`."""
    if resolves:
        step, pad = ELEVATION_FINE_STEP_DEG, ELEVATION_FINE_MARGIN_DEG
        lo = np.floor((min(elevations) - pad) / step) * step
        hi = np.ceil((max(elevations) + pad) / step) * step
        return f"{lo:g}:{hi:g}:{step:g}"
    tenths = sorted({int(round(e / ELEVATION_GRID_STEP_DEG)) for e in elevations})
    lo, hi = tenths[0], tenths[-1]
    if lo == hi:
        return f"{lo * ELEVATION_GRID_STEP_DEG:g}:{hi * ELEVATION_GRID_STEP_DEG:g}:1"
    step = math.gcd(*(t - lo for t in tenths)) or 1
    if (hi - lo) // step + 1 > ELEVATION_GRID_MAX_VALUES:
        step = -(-(hi - lo) // (ELEVATION_GRID_MAX_VALUES - 1))
    d = ELEVATION_GRID_STEP_DEG
    return f"{lo * d:g}:{hi * d:g}:{step * d:g}"


def run(args) -> int:
    """Run ``raysim flight``; returns the exit code."""
    import sys

    from raysim.cli.options import check_output
    from raysim.pipeline.flight import write_flight
    from raysim.platform.imu_spec import PRESETS
    from raysim.platform.mounting import mounting_deg

    check_output(args.folder, "dir", "folder")
    if args.imu not in PRESETS:
        raise ValueError(f"--imu: got {args.imu!r}, expected one of {sorted(PRESETS)}")
    if args.targets is not None and args.target:
        raise ValueError("give --target or --targets, not both")
    targets = (args.targets if args.targets is not None
               else [_triple(t, "--target") for t in (args.target or ["11.3,20,0"])])
    if args.frames < 1:
        raise ValueError(f"--frames: got {args.frames}, expected a positive integer")
    mounting_deg(args.mounting_deg)          # checked before anything is written
    f = write_flight(args.folder, imu=args.imu, imu_rate=args.imu_rate,
                     time_offset=args.time_offset, seed=args.seed, frames=args.frames,
                     targets=targets, board=args.board, mounting_deg=args.mounting_deg,
                     lever_arm=_triple(args.lever_arm, "--lever-arm"),
                     imu_boxcar=args.imu_boxcar, imu_fast_rate=args.imu_fast_rate,
                     log_gaps=args.log_gaps, gaps_in_capture=args.gaps_in_capture,
                     clock_drift_ppm=args.clock_drift_ppm, attitude=not args.no_attitude,
                     clutter_scene=args.clutter_scene, clutter_altitude=args.clutter_altitude,
                     clutter_max_scatterers=args.clutter_max_scatterers,
                     clutter_specular=args.clutter_specular,
                     decimate=args.decimate or "auto",
                     decimate_tolerance=args.decimate_tolerance,
                     progress=not args.no_progress)
    out = f"{args.folder.rstrip('/')}/compensated.zarr"
    print(f"wrote {f.imu_log}, {f.capture}, {f.radar_config}, {f.capture.parent / 'truth.json'}"
          f" (score a compensated store against it: raysim score {shlex.quote(args.folder)} "
          f"{shlex.quote(out)})")
    if f.gaps:
        print("logger gaps (start, length) [s, IMU clock]: " + ", ".join(
            f"({s:.3f}, {n:.3f})" for s, n in f.gaps), file=sys.stderr)
    from raysim.pipeline.compensate import DEFAULT_ANGLES_DEG
    from raysim.pipeline.flight import board_resolves_elevation

    r = [t[0] for t in f.targets]
    # the elevations the beams of the first frame see: a platform drifting 0.3 m/s is
    # 15 cm off the hover point at a 0.5 s start, 2 deg at 4.5 m, and a scatterer a grid
    # step off its beam keeps the drift's Doppler across it (raysim.pipeline.grid_miss)
    seen = [f.apparent_direction(0, j)[1] for j in range(len(f.targets))]
    cells = ("--range-m", f"{min(r) - 0.5}:{max(r) + 0.5}", "--el-deg",
             elevation_grid(seen, board_resolves_elevation(f.board)))
    wide = max(abs(t[1]) for t in f.targets) + AZIMUTH_GRID_MARGIN_DEG
    if wide > DEFAULT_ANGLES_DEG.max():       # past compensate's default grid
        cells += ("--az-deg", f"{-math.ceil(wide):d}:{math.ceil(wide):d}:1")
    # the rule compensate warns by: below 2.5 x the hover jitter's highest rotor line (or
    # any boxcar average) the log cannot see the rotors, the radar autofocus estimates them
    from compensation.ingestion import VIBRATION_RATE_FACTOR
    from raysim.platform.motion import HoverJitterSpec

    if f.imu_boxcar or f.imu_rate < VIBRATION_RATE_FACTOR * HoverJitterSpec().vibration_band[1]:
        cells += ("--autofocus", "displacement")
    print("compensate with (velocity and clock offset estimated from the radar):")
    print("  raysim " + shlex.join(f.calibrating_command(out, *cells, attitude=args.attitude)))
    print("or with the simulated clock offset and initial velocity given:")
    print("  raysim " + shlex.join(f.command(out, *cells)))
    return 0
