"""``raysim compensate``: motion-compensate a stored IF cube or a raw capture with an IMU log.

The input is a raw TI DCA1000 capture (``adc_data.bin``) with its radar
configuration (``--radar-config``: an mmWave SDK ``.cfg`` or an mmWave Studio
``.json`` export, :mod:`raysim.io.mmwave_config`; it sets the waveform, the
TDM slot order of the virtual array and the binary layout; every frame, or
``--frames LO:HI``), a frame store written by :mod:`raysim.io.storage` (a Zarr
store directory, opened with :func:`raysim.io.storage.open_store`, or a NetCDF
file ``.nc`` from :func:`raysim.io.storage.export_netcdf`; ``--frame`` or
``--frames``) or an ``.npz`` file with these keys:

=====================  =========================  =================================
key                    shape                      meaning
=====================  =========================  =================================
``data``               ``[chirp, channel, sample]``  complex IF samples
``chirp_times``        ``[chirp]``                chirp start times, radar clock [s]
``element_positions``  ``[channel, 3]``           virtual positions p_tx + p_rx in A [m]
``carrier_frequency``  scalar                     f_c [Hz]
``bandwidth``          scalar                     B [Hz]
``chirp_duration``     scalar                     T_c [s]
``sample_rate``        scalar                     f_s [Hz] (complex sampling)
``grid_shape``         ``[2]`` (optional)         (nx, ny), x major, y minor
``lever_arm``          ``[3]`` (optional)         r_IR in B [m]
``tx_slot``            ``[channel]`` (optional)   TDM slot of each channel
``slot_interval``      scalar (optional)          ramp-to-ramp interval of slots [s]
=====================  =========================  =================================

TDM MIMO: the IMU log is integrated once to the start of every transmit slot
of every selected frame, and each slot's channels are compensated with the
pose of their own ramp (exact and paper chains).

IMU log (``--imu FILE``, or a second positional argument), any format of
:func:`raysim.io.flight_logs.read_imu_log`: the project's IMU CSV (units in
the header, ``#`` comments; what :func:`raysim.io.write_imu_csv` writes), a
PX4 ULog ``.ulg`` (``sensor_combined``), an ArduPilot DataFlash ``.bin``
(``IMU``; needs ``raysim[ardupilot]``) or a ROS 2 bag (folder, ``.mcap`` or
``.db3``; ``sensor_msgs/msg/Imu``, FLU turned into FRD). Times are on the IMU
clock [s] (``--time-offset`` is IMU clock minus radar clock), angular rate and
specific force in the body frame FRD. It may be left out when the frame store
holds an IMU log (``imu_time``, ``imu_gyro``, ``imu_accel``).

Output (``--out``): a labelled Zarr store (written aside, then moved into
place; :func:`raysim.cli.compensate_io.write_compensated_store`) with
``beams [frame, chirp, range, azimuth, elevation]`` (complex64),
``doppler_power [frame, doppler, range, azimuth, elevation]`` (float32),
``chirp_time [frame, chirp]`` and ``slot_time [frame, chirp, slot]`` [s], the
coordinates ``range`` [m], ``azimuth``, ``elevation`` [deg], ``doppler``
[m/s] and the attributes ``chain`` and ``warnings``; or, for one frame and a
path ending in ``.npz``: ``beams [chirp, range, azimuth, elevation]``,
``doppler_power [doppler, range, azimuth, elevation]``, ``chirp_times`` [s],
``range_m``, ``azimuth_deg``, ``elevation_deg``, ``velocity_mps``, ``chain``
and ``warnings``. The warnings are the result's assumption warnings (see
:mod:`compensation.guards`), also printed on stderr as
``warning: <chain>: <text>``.

Chains (``--chain``, names of :mod:`raysim.vocabulary`, turned into beams by
:func:`raysim.pipeline.chains.project`): ``exact`` (rigid-body projection,
default), ``paper`` (the published chain; ``paper:published`` with the
paper's rotation phase ``v_r(nT) nT``) and ``none`` (conventional beamformer,
no IMU log needed).
"""

from __future__ import annotations

import argparse
import json
import os
import sys

import numpy as np

from raysim.cli.options import chains_option, span_grid, span_option
from raysim.io.files import atomic_write
from raysim.vocabulary import CHAINS, ChainSpec, parse_chain

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
  raysim compensate cube.npz --imu rosbag2_folder --out beams.npz # ROS 2 bag
  raysim compensate rotation_y.zarr --chain paper --direction-deg 20,0 --out paper.npz
  raysim compensate rotation_y.zarr --chain paper:published --direction-deg 20,0 \\
      --out published.npz
  raysim compensate rotation_y.zarr --chain none --out none.npz  # no compensation

chains: exact (rigid-body projection), paper (the published chain, needs
--direction-deg; paper:published with the paper's rotation phase), none
(conventional beamformer; the IMU log is not used). Guard warnings go to
stderr as "warning: CHAIN: TEXT" and into the "warnings" array of the output.

exit status: 0 written, 2 invalid input (the message names the flag or file
and the value).
"""

SPEED_OF_LIGHT = 299_792_458.0


def _floats(text: str, n: int, name: str) -> np.ndarray:
    try:
        vals = np.array([float(v) for v in text.split(",")])
    except ValueError:
        raise ValueError(f"{name} must be {n} comma-separated numbers, got {text!r}") from None
    if vals.size != n or not np.all(np.isfinite(vals)):
        raise ValueError(f"{name} must be {n} comma-separated finite numbers, got {text!r}")
    return vals



class _HelpFormatter(argparse.ArgumentDefaultsHelpFormatter,
                     argparse.RawDescriptionHelpFormatter):
    """Defaults in the option help, the epilog's examples as written."""


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
                         f"{[*CHAINS, 'paper:published']}")
    return parse_chain(keys[0])


def register(subparsers) -> None:
    """Add the ``compensate`` subcommand."""
    p = subparsers.add_parser(
        "compensate", help="motion-compensate a stored IF cube (Zarr store, NetCDF or .npz) "
        "with an IMU log (CSV)",
        description=__doc__.split("\n\n")[0] + " Runs the exact rigid-body projection "
        "(or the paper's chain) on the selected range cells and angle grid.",
        epilog=EPILOG, formatter_class=_HelpFormatter)
    p.add_argument("cube", help="raysim Zarr store, NetCDF file (.nc), .npz (keys: see "
                   "`raysim compensate --help`) or DCA1000 capture (.bin, with --radar-config)")
    p.add_argument("imu_positional", nargs="?", default=None, metavar="imu",
                   help="IMU log, same as --imu")
    p.add_argument("--imu", default=None, metavar="FILE",
                   help="IMU log: CSV (units in the header), PX4 .ulg, ArduPilot .bin or a "
                   "ROS 2 bag (folder, .mcap, .db3); left out: the IMU log of the frame store")
    p.add_argument("--frame", type=int, default=0,
                   help="frame of a Zarr / NetCDF store to compensate (position along frame)")
    p.add_argument("--frames", default=None, metavar="LO:HI",
                   help="frames of a capture or store (HI excluded; default: every frame of a "
                   "capture, --frame of a store)")
    p.add_argument("--radar-config", default=None, metavar="FILE",
                   help="radar configuration of a DCA1000 capture: mmWave SDK .cfg or mmWave "
                   "Studio .json (waveform, TDM slot order, ADC format)")
    p.add_argument("--layout", choices=("2lane", "4lane"), default=None,
                   help="LVDS lanes of a DCA1000 capture (default: the Studio JSON's lane "
                   "mask, 2 lanes for an SDK .cfg)")
    p.add_argument("--capture-t0", type=float, default=0.0, metavar="SECONDS",
                   help="radar-clock time of the first ramp of a DCA1000 capture [s] (a raw "
                   "capture carries no time stamps)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.add_argument("--out", required=True,
                   help="output: a Zarr store (labelled beams and Doppler maps of every frame) "
                   "or, for one frame, an .npz")
    p.add_argument("--range-m", default="0:1e9", metavar="LO:HI", help="range cells [m]")
    p.add_argument("--az-deg", default="-60:60:1", metavar="LO:HI:STEP")
    p.add_argument("--el-deg", default="-60:60:1", metavar="LO:HI:STEP")
    p.add_argument("--lever-arm", default=None, metavar="X,Y,Z",
                   help="r_IR in B [m] (default: from the cube, else 0,0,0)")
    p.add_argument("--time-offset", default="0", metavar="SECONDS|auto",
                   help="IMU clock minus radar clock [s]; 'auto': estimated from the radar "
                   "(residual slow-time phase of stationary scatterers against the IMU)")
    p.add_argument("--velocity", choices=("hover", "given", "radar"), default="hover",
                   help="initial velocity: zero-mean over the record (hover), "
                   "--initial-velocity (given), or estimated from the Doppler of stationary "
                   "scatterers (radar, ego-velocity fit)")
    p.add_argument("--initial-velocity", default=None, metavar="VN,VE,VD",
                   help="body velocity in W at the first chirp [m/s] (--velocity given)")
    p.add_argument("--initial-attitude-deg", default="0,0,0", metavar="YAW,PITCH,ROLL",
                   help="attitude at the first chirp, Z-Y-X Euler angles [deg], or 'level' "
                   "(roll/pitch from accelerometer levelling over the IMU record, heading 0)")
    p.add_argument("--imu-grade", choices=("ideal", "tactical", "consumer_mems"),
                   default=None,
                   help="IMU grade: sets the hover window of --velocity hover/radar and of "
                   "'level' (1 s centred on the chirps for consumer_mems, 8 s for tactical, "
                   "the whole record for ideal); left out: the whole record")
    p.add_argument("--chain", default="exact", metavar="CHAIN",
                   help=f"one of {', '.join(CHAINS)} or paper:published")
    p.add_argument("--direction-deg", default=None, metavar="AZ,EL",
                   help="target direction for the paper chain's slow-time correction [deg]")
    p.set_defaults(func=run)


def _is_store(path: str) -> bool:
    from raysim.io.zarr_store import store_exists

    return store_exists(path)


def _is_compensated_store(path: str) -> bool:
    import zarr

    from raysim.cli.compensate_io import COMPENSATED_FORMAT_ATTR

    return COMPENSATED_FORMAT_ATTR in zarr.open_group(path, mode="r").attrs


def _load_imu(path: str) -> np.ndarray:
    """IMU log of any supported format as a table ``[sample, 7]``: time, gyro, accel (SI, FRD)."""
    from raysim.io.flight_logs import read_imu_log

    if not os.path.exists(path):
        raise ValueError(f"IMU file {path!r} does not exist")
    try:
        s = read_imu_log(path)
    except ImportError as exc:   # an optional reader (pymavlink for .bin) is missing
        raise ValueError(f"IMU file {path!r}: {exc}") from None
    return np.column_stack([s.time, s.gyro, s.accel])


def _time_offset(text: str) -> float | None:
    """``--time-offset`` value [s]; ``None`` for ``auto``."""
    if text.strip() == "auto":
        return None
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"--time-offset must be a number of seconds or 'auto', got "
                         f"{text!r}") from None
    if not np.isfinite(value):
        raise ValueError(f"--time-offset must be finite, got {text!r}")
    return value


def _self_calibrate(args, inp, imu: np.ndarray, offset: float | None, lam: float,
                    r_axis: np.ndarray, gates: np.ndarray, options: dict):
    """Per-frame motions with the clock offset and/or velocity estimated from the radar.

    Every selected frame takes part (the gyro bias, a drift over frames, needs
    two or more); stationary scatterers are detected on the selected range
    cells of the first frame. Returns ``(motions, report)``.
    """
    from compensation.calibration import self_calibrate
    from raysim.processing.maps import range_compress

    estimate = (("time_offset",) if offset is None else ()) + (
        ("velocity",) if args.velocity == "radar" else ())
    if len(inp.frames) > 1:
        estimate += ("gyro_bias",)
    rcs = [range_compress(inp.read(k))[..., : r_axis.size] for k in range(len(inp.frames))]
    times = [inp.slot_times[k].ravel() for k in range(len(inp.frames))]
    if inp.num_slots > 1:
        options = dict(options, channel_slot=inp.tx_slot)
    res = self_calibrate(rcs, times, inp.element_positions, imu[:, 0], imu[:, 1:4],
                         imu[:, 4:7], wavelength=lam, range_axis=r_axis, estimate=estimate,
                         time_offset=0.0 if offset is None else offset,
                         grid_shape=inp.grid_shape, detect_gates=gates, **options)
    return list(res.motions), res.report()


def _calibration_text(report: dict) -> str:
    """One line per estimate, with its one-sigma uncertainty."""
    lines = ["self-calibration (estimate +- one sigma):"]
    if report.get("time_offset_sigma_s") is not None:
        lines.append(f"  time offset {1e3 * report['time_offset_s']:.4f} +- "
                     f"{1e3 * report['time_offset_sigma_s']:.4f} ms")
    if report.get("frame_velocity_correction_mps"):
        v, s = report["initial_velocity_mps"], report["initial_velocity_sigma_mps"]
        lines.append("  initial velocity [m/s] (N, E, D) " + ", ".join(
            f"{a:.4f} +- {b:.4f}" for a, b in zip(v, s, strict=True)))
    lines.append(f"  scatterers used: {report['scatterers']}")
    return "\n".join(lines)


def run(args) -> int:
    """Execute ``raysim compensate``; returns the exit code."""
    from dataclasses import replace

    from scipy.spatial.transform import Rotation

    from compensation import integrate_imu
    from compensation.geometry import direction
    from raysim.cli.compensate_io import load_input, write_compensated_store
    from raysim.cli.options import check_output
    from raysim.pipeline.chains import project
    from raysim.processing.maps import range_compress

    spec = _chain(args.chain)
    as_npz = args.out.endswith(".npz")
    check_output(args.out, "file" if as_npz else "dir", "--out")
    if not as_npz and os.path.isdir(args.out):
        if not _is_store(args.out):
            raise ValueError(f"--out: cannot write {args.out!r}: it is an existing directory "
                             f"that is not a Zarr store (expected a new store path, or .npz "
                             f"for one frame)")
        if not _is_compensated_store(args.out):
            raise ValueError(f"--out: cannot write {args.out!r}: it is an existing Zarr store "
                             f"not written by raysim compensate (a frame store?); expected a "
                             f"new path or an earlier compensated store to replace")
    inp = load_input(args.cube, radar_config=args.radar_config, frames=args.frames,
                     frame=args.frame, layout=args.layout, capture_t0=args.capture_t0)
    if as_npz and len(inp.frames) != 1:
        raise ValueError(f"--out {args.out!r}: an .npz holds one frame, the selection has "
                         f"{len(inp.frames)}; give a store path (no .npz) or --frames K")
    cfg = inp.config
    lam = cfg.center_wavelength
    u = None
    if spec.name == "paper":
        if args.direction_deg is None:
            raise ValueError(f"--chain {spec.key} needs --direction-deg AZ,EL (target "
                             f"direction)")
        u = direction(*np.deg2rad(_floats(args.direction_deg, 2, "--direction-deg")))
    slots = inp.num_slots
    n_samples = inp.read(0).shape[-1]
    r_axis = cfg.bin_ranges(n_samples if cfg.complex_sampling else n_samples // 2)
    r_lo, r_hi = span_option(args.range_m, "--range-m", False)
    gates = np.flatnonzero((r_axis >= r_lo) & (r_axis <= r_hi))
    if gates.size == 0:
        raise ValueError(f"--range-m {args.range_m} selects no range cell; cells span "
                         f"0 .. {r_axis[-1]:.2f} m")
    motions = calibration = None
    if spec.compensated:
        if args.imu is not None and args.imu_positional is not None:
            raise ValueError(f"give the IMU log once: --imu {args.imu!r} and the positional "
                             f"{args.imu_positional!r} were both given")
        imu_path = args.imu if args.imu is not None else args.imu_positional
        if imu_path is not None:
            imu = _load_imu(imu_path)
        elif inp.imu is not None:
            imu = inp.imu
        else:
            raise ValueError(f"{args.cube!r} holds no IMU log; give an IMU log with --imu FILE")
        lever = (_floats(args.lever_arm, 3, "--lever-arm") if args.lever_arm is not None
                 else inp.lever_arm if inp.lever_arm is not None else np.zeros(3))
        if args.initial_attitude_deg.strip() == "level":
            attitude = "level"
        else:
            ypr = np.deg2rad(_floats(args.initial_attitude_deg, 3, "--initial-attitude-deg"))
            attitude = Rotation.from_euler("ZYX", ypr).as_matrix()
        kwargs = {}
        if args.velocity == "given":
            if args.initial_velocity is None:
                raise ValueError("--velocity given needs --initial-velocity VN,VE,VD")
            kwargs["initial_velocity"] = _floats(args.initial_velocity, 3, "--initial-velocity")
        offset = _time_offset(args.time_offset)
        kwargs.update(lever_arm=lever, initial_attitude=attitude, imu_grade=args.imu_grade,
                      velocity="hover" if args.velocity == "radar" else args.velocity)
        if offset is None or args.velocity == "radar":
            motions, calibration = _self_calibrate(args, inp, imu, offset, lam, r_axis, gates,
                                                   kwargs)
        else:
            # one integration over every slot of every selected frame, chirp major, slot minor
            motion = integrate_imu(imu[:, 0], imu[:, 1:4], imu[:, 4:7], inp.slot_times.ravel(),
                                   time_offset=offset, **kwargs)
            per_frame = inp.slot_times[0].size
            motions = [motion.select(slice(k * per_frame, (k + 1) * per_frame))
                       for k in range(len(inp.frames))]
    az = np.deg2rad(span_grid(args.az_deg, "--az-deg"))
    el = np.deg2rad(span_grid(args.el_deg, "--el-deg"))
    results, found = [], []
    frames = range(len(inp.frames))
    if len(inp.frames) > 1 and not args.no_progress:
        from tqdm import tqdm

        frames = tqdm(frames, unit="frame", desc="compensate", file=sys.stderr)
    for k in frames:
        mot = None if motions is None else motions[k]
        # TDM: every slot's channels with the pose of their own ramp
        channel_slot = inp.tx_slot if mot is not None and slots > 1 else None
        rc = range_compress(inp.read(k))[..., : r_axis.size]
        beams = project(spec, rc, inp.element_positions, wavelength=lam, range_axis=r_axis,
                        azimuth=az, elevation=el, motion=mot, direction=u,
                        grid_shape=inp.grid_shape, range_gates=gates, channel_slot=channel_slot)
        if mot is None:   # the conventional beamformer carries chirp indices, not times
            beams = replace(beams, chirp_time=inp.slot_times[k, :, 0])
        found.extend(w for w in beams.warnings if w not in found)
        results.append(beams)
    if as_npz:
        _write_npz(args.out, results[0], spec.key, az, el, calibration)
    else:
        attrs = {"velocity": args.velocity}
        if calibration is not None:
            attrs["self_calibration"] = json.dumps(calibration)
        if spec.compensated:   # the offset applied: given, or estimated ('auto')
            attrs["time_offset_s"] = float(calibration["time_offset_s"] if offset is None
                                           else offset)
        write_compensated_store(args.out, inp, results, chain=spec.key, warnings=found,
                                azimuth_deg=np.rad2deg(az), elevation_deg=np.rad2deg(el),
                                extra_attrs=attrs)
    for w in found:
        print(f"warning: {spec.key}: {w}", file=sys.stderr)
    if calibration is not None:
        print(_calibration_text(calibration))
    shape = (len(results),) + results[0].data.shape
    print(f"wrote {args.out}: beams {shape} [frame, chirp, range, azimuth, elevation], "
          f"chain {spec.key}" + (f", {len(found)} warning(s)" if found else ""))
    return 0


def _write_npz(path: str, beams, chain: str, az, el, calibration: dict | None) -> None:
    """The single-frame ``.npz`` output (keys in the module docstring)."""
    doppler = beams.doppler()

    def write(tmp):
        with open(tmp, "wb") as fh:  # a file object: np.savez would append ".npz" to a name
            np.savez(fh, beams=beams.data,
                     doppler_power=(np.abs(doppler) ** 2).astype(np.float32),
                     chirp_times=beams.chirp_time, range_m=beams.range,
                     azimuth_deg=np.rad2deg(az), elevation_deg=np.rad2deg(el),
                     velocity_mps=beams.velocity(), chain=np.array(chain),
                     warnings=np.array(beams.warnings, dtype=str),
                     **({} if calibration is None else
                        {"self_calibration": np.array(json.dumps(calibration))}))

    atomic_write(path, write)
