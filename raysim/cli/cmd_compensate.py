"""``raysim compensate``: motion-compensate a stored IF cube or a raw capture with an IMU log.

The input is a raw TI DCA1000 capture (``adc_data.bin``) with its radar
configuration (``--radar-config``: an mmWave SDK ``.cfg`` or an mmWave Studio
``.json`` export; every frame, or ``--frames LO:HI``), a frame store written by
:mod:`raysim.io.storage` (Zarr store or NetCDF ``.nc``; ``--frame`` or
``--frames``) or an ``.npz`` cube (keys in :mod:`raysim.pipeline.compensate`).
The IMU log (``--imu FILE`` or a second positional argument) is any format of
:func:`raysim.io.flight_logs.read_imu_log`, or left out for the IMU log of the
frame store; ``--imu-topic`` / ``--imu-instance`` choose the source inside it
and ``--max-gap`` the largest gap filled inside the window used. ``--board`` /
``--antenna-positions`` give a capture's antennas where the configuration does
not say the board. Output (``--out``): a labelled Zarr store, or for one frame an
``.npz`` (:mod:`raysim.io.compensate_io`); never one of the inputs, a file raysim did
not write or an output another process is writing. The job is sized before anything
large is allocated (:mod:`raysim.pipeline.compensate_size`): without ``--range-m``
every range cell when it fits, else the cells around the strongest return (a note
on stderr says which); a job that does not fit the memory or disk is refused with
its size and the options that reduce it.

This module parses the options, calls the compensate stage
(:func:`raysim.pipeline.compensate.compensate`: reading, motion estimate or
self-calibration, the chain of every frame, writing) and prints its warnings
on stderr as ``warning: <chain>: <text>``, the IMU source read, the
self-calibration's estimates and the output written.
"""

from __future__ import annotations

import sys
import warnings

import numpy as np

from raysim.cli.options import DefaultsHelpFormatter, chains_option, span_grid, span_option
from raysim.vocabulary import CHAIN_NAMES, ChainSpec, parse_chain

EPILOG = """\
examples:
  raysim compensate adc_data.bin --radar-config awr1843.cfg --imu flight.ulg \\
      --range-m 10:13 --az-deg -40:40:1 --el-deg 0:0:1 --out beams.zarr   # DCA1000 capture
  raysim compensate rotation_y.zarr --out beams.npz             # IMU log of the store
  raysim compensate rotation_y.zarr --frame 2 --range-m 14:16 --az-deg 10:30:0.5 \\
      --el-deg -10:10:0.5 --out beams.npz
  raysim compensate cube.npz --imu imu.csv --velocity given --initial-velocity 0,0,0 \\
      --lever-arm 0,0,0.1 --out beams.npz
  raysim compensate cube.npz --imu flight.ulg --out beams.npz     # PX4 log
  raysim compensate adc_data.bin --radar-config iwr6843.cfg --board IWR6843AOP \\
      --imu flight.ulg --imu-topic sensor_combined --max-gap 0.2 --out beams.zarr
  raysim compensate cube.npz --imu rosbag2_folder --out beams.npz # ROS 2 bag (or a ROS 1 .bag)
  raysim compensate rotation_y.zarr --chain paper --direction-deg 20,0 --out paper.npz
  raysim compensate rotation_y.zarr --chain paper:published --direction-deg 20,0 \\
      --out published.npz
  raysim compensate rotation_y.zarr --chain none --out none.npz  # no compensation
  raysim compensate cube.npz --imu flight.ulg --autofocus --out beams.npz  # + radar autofocus

chains: exact (rigid-body projection), paper (the published chain, needs
--direction-deg; paper:published with the paper's rotation phase), none
(conventional beamformer; the IMU log is not used), dpca (displaced phase
centre: a sub-aperture held fixed in the world, one size for every frame; its
price, "dpca price: ...", is printed with the warnings). Guard warnings go to
stderr as "warning: CHAIN: TEXT" and into the "warnings" array of the output.

exit status: 0 written, 2 invalid input (the message names the flag or file
and the value; a job too large names its size), 130 interrupted (Ctrl-C or
SIGTERM: temporary files removed).
"""

def _floats(text: str, n: int, name: str) -> np.ndarray:
    try:
        vals = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise ValueError(f"{name} must be {n} comma-separated numbers, got {text!r}") from None
    if vals.size != n or not np.all(np.isfinite(vals)):
        raise ValueError(f"{name} must be {n} comma-separated finite numbers, got {text!r}")
    return vals


class _HelpFormatter(DefaultsHelpFormatter):
    """Defaults in the option help (once), the epilog's examples as written."""


def _chain(text: str) -> ChainSpec:
    """``--chain`` value -> :class:`~raysim.vocabulary.ChainSpec`.

    Raises
    ------
    ValueError
        Naming the value and the accepted names.
    """
    keys = chains_option(text, "--chain")
    if len(keys) != 1:
        raise ValueError(f"--chain: got {text!r}, expected one chain of "
                         f"{[*CHAIN_NAMES, 'paper:published']}")
    return parse_chain(keys[0])


def register(subparsers) -> None:
    """Add the ``compensate`` subcommand."""
    p = subparsers.add_parser(
        "compensate", help="motion-compensate a radar cube (Zarr store, NetCDF, .npz or a DCA1000 "
        "capture) "
        "with an IMU or flight log (CSV, PX4 ULog, ArduPilot DataFlash, ROS 1 or 2 bag)",
        description=__doc__.split("\n\n")[0] + " Runs the exact rigid-body projection "
        "(or the paper's chain) on the selected range cells and angle grid.",
        epilog=EPILOG, formatter_class=_HelpFormatter)
    p.add_argument("cube", help="raysim Zarr store, NetCDF file (.nc), .npz or MATLAB .mat "
                   "(v7 or older; keys: see raysim.pipeline.compensate) or DCA1000 capture "
                   "(.bin, with --radar-config)")
    p.add_argument("imu_positional", nargs="?", default=None, metavar="imu",
                   help="IMU log, same as --imu")
    p.add_argument("--imu", default=None, metavar="FILE",
                   help="IMU log: CSV (units in the header, or a PX4 ulog2csv / ArduPilot "
                   "mavlogdump export), PX4 .ulg, ArduPilot .bin or a "
                   "ROS 2 bag (folder, .mcap, .db3) or ROS 1 .bag; left out: the IMU log of "
                   "the frame store")
    p.add_argument("--imu-topic", default=None, metavar="NAME",
                   help="source inside the IMU log: PX4 topic (sensor_gyro_fifo, vehicle_imu, "
                   "sensor_combined), ArduPilot message (ISBD, GYR, IMU) or ROS topic; "
                   "left out: the complete source with the highest rate")
    p.add_argument("--imu-instance", type=int, default=None, metavar="K",
                   help="instance of that source (PX4 multi-id, ArduPilot I); left out: the "
                   "best present")
    p.add_argument("--max-gap", type=float, default=None, metavar="SECONDS",
                   help="largest IMU-log gap inside the window used (the selected chirps plus "
                   "0.5 s) filled by interpolation, with a warning; gaps outside it are not "
                   "judged (default 0.06 s, or 3.5 median intervals if larger)")
    p.add_argument("--frame", type=int, default=None,
                   help="frame of a Zarr / NetCDF store to compensate (position along frame; "
                   "left out: the first, or --frames)")
    p.add_argument("--frames", default=None, metavar="LO:HI",
                   help="frames of a capture or store (HI excluded; default: every frame of a "
                   "capture, --frame of a store)")
    p.add_argument("--radar-config", default=None, metavar="FILE",
                   help="radar configuration of a DCA1000 capture: mmWave SDK .cfg or mmWave "
                   "Studio .json (waveform, TDM slot order, ADC format)")
    p.add_argument("--layout", choices=("2lane", "4lane"), default=None,
                   help="LVDS lanes of a DCA1000 capture (default: the Studio JSON's lane "
                   "mask, 2 lanes for an SDK .cfg)")
    p.add_argument("--drop-incomplete", action="store_true",
                   help="read the whole frames of a DCA1000 capture that ends inside a frame "
                   "(stopped by hand); the trailing bytes are dropped with a warning")
    p.add_argument("--board", default=None, metavar="BOARD",
                   help="TI board of a DCA1000 capture, for its antenna layout: xWR14xx, "
                   "xWR16xx, xWR18xx, IWR6843ISK, IWR6843AOP or IWR6843ODS; needed when the "
                   "configuration fits boards of different layouts")
    p.add_argument("--antenna-positions", default=None, metavar="FILE",
                   help="CSV or JSON file of the TX and RX positions of a capture (units "
                   "stated: wavelength or m; see raysim.io.mmwave_config); replaces --board")
    p.add_argument("--capture-t0", type=float, default=0.0, metavar="SECONDS",
                   help="radar-clock time of the first ramp of a DCA1000 capture [s] (a raw "
                   "capture carries no time stamps)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--out", required=True,
                   help="output: a Zarr store (labelled beams and Doppler maps of every frame) "
                   "or, for one frame, an .npz")
    p.add_argument("--range-m", default=None, metavar="LO:HI",
                   help="range cells [m]; left out: every cell when the job fits 1.2 GB, else "
                   "the cells around the strongest return that fit (a note says which)")
    p.add_argument("--az-deg", default="-60:60:1", metavar="LO:HI:STEP",
                   help="azimuth grid of the beams [deg], LO to HI inclusive in steps of STEP")
    p.add_argument("--el-deg", default="-60:60:1", metavar="LO:HI:STEP",
                   help="elevation grid of the beams [deg], LO to HI inclusive in steps of STEP")
    p.add_argument("--lever-arm", default=None, metavar="X,Y,Z",
                   help="r_IR in B [m] (default: from the cube, else 0,0,0)")
    p.add_argument("--time-offset", default="0", metavar="SECONDS|auto",
                   help="IMU clock minus radar clock [s]; 'auto': estimated from the radar "
                   "(residual slow-time phase of stationary scatterers against the IMU)")
    p.add_argument("--time-offset-search", type=float, default=None, metavar="SECONDS",
                   help="half-width of the --time-offset auto search about 0 [s] (left out: "
                   "0.01); an offset beyond it is not found: widen it for a log whose clock "
                   "is not synchronised to within 10 ms (its cost grows with it: 0.5 ms "
                   "steps, four frames each)")
    p.add_argument("--velocity", choices=("hover", "given", "radar"), default="hover",
                   help="initial velocity: zero-mean over the record (hover), "
                   "--initial-velocity (given), or estimated from the Doppler of stationary "
                   "scatterers (radar, ego-velocity fit)")
    p.add_argument("--initial-velocity", default=None, metavar="VN,VE,VD",
                   help="body velocity in W at the first chirp [m/s] (--velocity given)")
    p.add_argument("--initial-attitude-deg", default=None, metavar="YAW,PITCH,ROLL",
                   help="attitude at the first chirp, Z-Y-X Euler angles [deg], or 'level' "
                   "(roll/pitch from accelerometer levelling over the IMU record, heading 0); "
                   "left out: the IMU log's attitude at the first ramp (PX4 vehicle_attitude, "
                   "ArduPilot ATT/AHRS2, ROS orientation), else level 0,0,0 (a note says which; "
                   "--velocity radar then takes roll and pitch from the ground clutter beyond "
                   "--range-m, assuming level flat ground, else treats the tilt as unknown, "
                   "with a warning); with --velocity radar the log's attitude also measures "
                   "roll and pitch at every frame")
    p.add_argument("--mounting-deg", default=None, metavar="YAW,PITCH,ROLL|NAME",
                   help="radar mounting on the body, Z-Y-X Euler angles of R_BA [deg], or "
                   "down (default: parallel to the body, looking down), forward, oblique; "
                   "beams are then in the radar frame at the nominal pose; --velocity radar "
                   "and --time-offset auto find the scatterers and the ground there and turn "
                   "their directions into the body frame")
    p.add_argument("--imu-grade", choices=("ideal", "tactical", "consumer_mems"),
                   default=None,
                   help="IMU grade: sets the hover window of --velocity hover/radar and of "
                   "'level' (1 s centred on the chirps for consumer_mems, 8 s for tactical, "
                   "the whole record for ideal); left out: the whole record")
    p.add_argument("--chain", default="exact", metavar="CHAIN",
                   help=f"one of {', '.join(CHAIN_NAMES)} or paper:published")
    p.add_argument("--direction-deg", default=None, metavar="AZ,EL",
                   help="target direction for the paper chain's slow-time correction [deg]; "
                   "needed by --chain paper, not used by the others")
    p.add_argument("--autofocus", nargs="?", const="phase", default="auto",
                   choices=("auto", "off", "phase", "stationary", "displacement"),
                   help="'auto' (default): 'displacement' where the IMU-driven chain warns that "
                   "it leaves motion in the data (the log does not resolve the vibration, or "
                   "the stationary scatterers keep a Doppler), else off; otherwise: "
                   "after the IMU-driven chain, estimate the residual per-chirp phase "
                   "common to the stationary scatterers from the beams and remove it (rotor "
                   "vibration a low-rate IMU log cannot see); 'phase' (alone: --autofocus) "
                   "leaves the linear phase (Doppler) as it is, 'stationary' also removes "
                   "those scatterers' common Doppler (a velocity error along the line of sight), "
                   "'displacement' estimates the residual displacement vector per chirp and "
                   "corrects every beam at its own direction")
    p.add_argument("--ground-doppler", action="store_true",
                   help="with --velocity radar, the ground clutter beyond the range window also "
                   "measures the velocity by its Doppler (the ground assumed at rest): it "
                   "constrains the velocity across a narrow cone of targets")
    p.set_defaults(func=run)


def _time_offset(text: str) -> float | str:
    """``--time-offset`` value [s]; ``"auto"`` as is."""
    if text.strip() == "auto":
        return "auto"
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"--time-offset must be a number of seconds or 'auto', got "
                         f"{text!r}") from None
    if not np.isfinite(value):
        raise ValueError(f"--time-offset must be finite, got {text!r}")
    return value


def _calibration_text(report: dict) -> str:
    """One line per estimate, with its one-sigma uncertainty."""
    lines = ["self-calibration (estimate +- one sigma):"]
    if report.get("time_offset_sigma_s") is not None:
        searched = report.get("time_offset_search_s")
        outside = searched is not None and abs(report["time_offset_s"]) > searched
        lines.append(f"  time offset {1e3 * report['time_offset_s']:.4f} +- "
                     f"{1e3 * report['time_offset_sigma_s']:.4f} ms" + (
                         "" if searched is None else f" (searched +-{1e3 * searched:g} ms "
                         f"about 0{', the fit then left that window' if outside else ''}: "
                         f"--time-offset-search widens it)"))
    if report.get("frame_velocity_correction_mps") or report.get("radar_inertial"):
        v, s = report["initial_velocity_mps"], report["initial_velocity_sigma_mps"]
        lines.append("  initial velocity [m/s] (N, E, D) " + ", ".join(
            f"{a:.4f} +- {b:.4f}" for a, b in zip(v, s, strict=True)))
    ri = report.get("radar_inertial")
    if ri:
        est = dict(zip(ri["state_names"], zip(ri["state"], ri["sigma"], strict=True),
                       strict=True))
        tilt = [f"{np.rad2deg(est[n][0]):.3f} +- {np.rad2deg(est[n][1]):.3f}"
                for n in ("tilt_n", "tilt_e")]
        acc = [f"{1e3 * est[n][0] / 9.80665:.2f} +- {1e3 * est[n][1] / 9.80665:.2f}"
               for n in ("accel_bias_x", "accel_bias_y", "accel_bias_z")]
        lines.append("  tilt correction [deg] (N, E) " + ", ".join(tilt))
        lines.append("  accelerometer bias [mg] (x, y, z) " + ", ".join(acc))
        held = report.get("held_at", {})
        for source in dict.fromkeys(held.values()):
            lines.append(f"  unconstrained by the radar (kept at the {source}'s value): "
                         + ", ".join(n for n in ri["unconstrained"] if held[n] == source))
        if not ri["unconstrained"]:
            lines.append("  unconstrained by the radar: none")
        lines.append(f"  Doppler measurements used: {ri['measurements']} "
                     f"({ri['rejected']} rejected), chi2 {ri['chi2']:.2f}")
        if ri.get("noise_velocity_mps"):
            lines.append(f"  IMU noise's velocity error taken from the Doppler residuals: up "
                         f"to {1e3 * ri['noise_velocity_mps']:.2f} mm/s")
    lines.append(f"  scatterers used: {report['scatterers']}")
    lines.extend(f"  {note}" for note in report.get("notes", ()))
    gp = report.get("ground_plane")
    if gp:
        tilt = ", ".join(f"{a:.3f} +- {b:.3f}" for a, b in zip(
            gp["tilt_deg"], gp["tilt_sigma_deg"], strict=True))
        if not all(map(np.isfinite, gp["tilt_deg"])):       # too few points to fit a plane
            tilt = "not fitted"
        lines.append(f"  ground plane tilt [deg] (N, E) {tilt} ({gp['role']}; "
                     f"{gp['inliers']} of {gp['points']} points; assumes {gp['assumption']})")
    return "\n".join(lines)


def _compensate(args, spec, attitude):
    """The pipeline's ``compensate`` with the command's options."""
    from raysim.pipeline.compensate import compensate

    return compensate(
        args.cube, args.imu if args.imu is not None else args.imu_positional, out=args.out,
        chain=spec, frames=args.frames, frame=args.frame, radar_config=args.radar_config,
        layout=args.layout, capture_t0=args.capture_t0, drop_incomplete=args.drop_incomplete,
        range_m=None if args.range_m is None else span_option(args.range_m, "--range-m", False),
        azimuth_deg=span_grid(args.az_deg, "--az-deg", bound=90.0),
        elevation_deg=span_grid(args.el_deg, "--el-deg", bound=90.0),
        lever_arm=None if args.lever_arm is None else _floats(args.lever_arm, 3, "--lever-arm"),
        time_offset=_time_offset(args.time_offset), velocity=args.velocity,
        time_offset_search=args.time_offset_search,
        initial_velocity=None if args.initial_velocity is None
        else _floats(args.initial_velocity, 3, "--initial-velocity"),
        initial_attitude_deg=attitude if attitude in (None, "level")
        else _floats(attitude, 3, "--initial-attitude-deg"),
        imu_grade=args.imu_grade,
        direction_deg=None if args.direction_deg is None
        else _floats(args.direction_deg, 2, "--direction-deg"),
        max_gap=args.max_gap, imu_topic=args.imu_topic, imu_instance=args.imu_instance,
        board=args.board, antenna_positions=args.antenna_positions,
        mounting_deg=args.mounting_deg, progress=not args.no_progress,
        autofocus=False if args.autofocus == "off" else args.autofocus,
        ground_doppler=args.ground_doppler)


def run(args) -> int:
    """Execute ``raysim compensate``; returns the exit code."""
    spec = _chain(args.chain)
    if args.imu is not None and args.imu_positional is not None:
        raise ValueError(f"give the IMU log once: --imu {args.imu!r} and the positional "
                         f"{args.imu_positional!r} were both given")
    if spec.name == "paper" and args.direction_deg is None:
        raise ValueError(f"--chain {spec.key} needs --direction-deg AZ,EL (target direction)")
    if args.ground_doppler and args.velocity != "radar":
        raise ValueError(f"--ground-doppler measures the velocity: needs --velocity radar, got "
                         f"--velocity {args.velocity}")
    attitude = None if args.initial_attitude_deg is None else args.initial_attitude_deg.strip()
    result = None
    try:   # the result's warnings are printed below with their chain: each said once
        with warnings.catch_warnings(record=True) as caught:
            result = _compensate(args, spec, attitude)
    finally:
        said = () if result is None else result.warnings
        for w in caught:
            if not any(str(w.message) in text for text in said):
                warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    for note in result.notes:
        print(f"note: {note}", file=sys.stderr)
    if result.imu_source is not None:
        print(f"IMU log: {result.imu_source}")
    for w in result.warnings:
        print(f"warning: {result.chain}: {w}", file=sys.stderr)
    if args.autofocus == "off" and any(w.startswith("imu rate:") for w in result.warnings):
        print("note: --autofocus displacement estimates the vibration this log does not "
              "resolve from the stationary scatterers (docs/compensation.md, \"Radar "
              "autofocus\")", file=sys.stderr)
    elif args.autofocus == "off" and any(w.startswith("azimuth:") for w in result.warnings):
        print("note: --autofocus displacement removes a Doppler left common to the stationary "
              "scatterers of each frame (the velocity error the azimuth warning measures; "
              "docs/compensation.md, \"Radar autofocus\")", file=sys.stderr)
    if result.calibration is not None:
        print(_calibration_text(result.calibration))
    for k, rep in enumerate(result.autofocus or ()):
        sigma = "n/a" if rep["sigma_rad"] is None else f"{rep['sigma_rad']:.3g}"
        rate = "" if rep.get("range_rate_mps") is None else (
            f", range rate {rep['range_rate_mps']:.3g} +- "
            f"{rep['range_rate_sigma_mps']:.2g} m/s")
        print(f"autofocus frame {result.frames[k]}: residual phase rms {rep['rms_phase_rad']:.3g} "
              f"rad (sigma {sigma} rad), band {rep['band_hz'][0]:.0f}-{rep['band_hz'][1]:.0f} "
              f"Hz, {rep['cells']} cells{rate}")
    from raysim.resources import format_bytes, tree_bytes

    print(f"wrote {args.out} ({format_bytes(tree_bytes(args.out))}): beams {result.shape} "
          f"[frame, chirp, range, azimuth, elevation], chain {result.chain}"
          + (f", {len(result.warnings)} warning(s)" if result.warnings else ""))
    return 0
