"""``raysim compensate``: motion-compensate a stored IF cube with an IMU log.

The cube is a frame store written by :mod:`raysim.io.storage` (a Zarr store
directory, opened with :func:`raysim.io.storage.open_store`, or a NetCDF file
``.nc`` from :func:`raysim.io.storage.export_netcdf`; one frame, ``--frame``) or
an ``.npz`` file with these keys:

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
=====================  =========================  =================================

IMU log (``--imu FILE``, or a second positional argument), any format of
:func:`raysim.io.flight_logs.read_imu_log`: the project's IMU CSV (units in
the header, ``#`` comments; what :func:`raysim.io.write_imu_csv` writes), a
PX4 ULog ``.ulg`` (``sensor_combined``), an ArduPilot DataFlash ``.bin``
(``IMU``; needs ``raysim[ardupilot]``) or a ROS 2 bag (folder, ``.mcap`` or
``.db3``; ``sensor_msgs/msg/Imu``, FLU turned into FRD). Times are on the IMU
clock [s] (``--time-offset`` is IMU clock minus radar clock), angular rate and
specific force in the body frame FRD. It may be left out when the frame store
holds an IMU log (``imu_time``, ``imu_gyro``, ``imu_accel``).

Output (``.npz``, written to a temporary file then moved into place):
``beams [chirp, range, azimuth, elevation]`` (complex64),
``doppler_power [doppler, range, azimuth, elevation]`` (float32), and the axes
``chirp_times`` [s], ``range_m``, ``azimuth_deg``, ``elevation_deg``,
``velocity_mps``, ``chain`` (the chain key) and ``warnings`` (the result's
assumption warnings, see :mod:`compensation.guards`; also printed on stderr as
``warning: <chain>: <text>``).

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
    p.add_argument("cube", help="raysim Zarr store, NetCDF file (.nc) or .npz (keys: see "
                   "`raysim compensate --help`)")
    p.add_argument("imu_positional", nargs="?", default=None, metavar="imu",
                   help="IMU log, same as --imu")
    p.add_argument("--imu", default=None, metavar="FILE",
                   help="IMU log: CSV (units in the header), PX4 .ulg, ArduPilot .bin or a "
                   "ROS 2 bag (folder, .mcap, .db3); left out: the IMU log of the frame store")
    p.add_argument("--frame", type=int, default=0,
                   help="frame of a Zarr / NetCDF store to compensate (position along frame)")
    p.add_argument("--out", required=True, help="output .npz")
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
    p.add_argument("--chain", default="exact", metavar="CHAIN",
                   help=f"one of {', '.join(CHAINS)} or paper:published")
    p.add_argument("--direction-deg", default=None, metavar="AZ,EL",
                   help="target direction for the paper chain's slow-time correction [deg]")
    p.set_defaults(func=run)


def _load_store(path: str, frame: int) -> dict:
    """Cube keys (as in the ``.npz`` layout) and the IMU log of one frame of a store."""
    from raysim.io import storage

    if path.endswith(".nc") and not os.path.isdir(path):
        ds = storage.read_netcdf(path)
    else:
        ds = storage.open_store(path)
    n = int(ds.sizes.get("frame", 0))
    if not -n <= frame < n:
        raise ValueError(f"--frame {frame} is outside the store {path!r}, which holds {n} "
                         f"frame(s)")
    fr = storage.frame_from_dataset(ds, frame)
    cfg = fr.config
    out = {"data": np.asarray(fr.data), "chirp_times": np.asarray(fr.chirp_times, dtype=float),
           "element_positions": fr.array.virtual_positions,
           "carrier_frequency": cfg.carrier_frequency, "bandwidth": cfg.bandwidth,
           "chirp_duration": cfg.chirp_duration, "sample_rate": cfg.sample_rate,
           "lever_arm": np.asarray(fr.lever_arm, dtype=float)}
    if fr.array.grid_shape:
        out["grid_shape"] = np.asarray(fr.array.grid_shape)
    if all(k in ds.variables for k in ("imu_time", "imu_gyro", "imu_accel")):
        out["_imu"] = np.column_stack([np.asarray(ds["imu_time"].values, dtype=float),
                                       np.asarray(ds["imu_gyro"].values, dtype=float),
                                       np.asarray(ds["imu_accel"].values, dtype=float)])
    if not np.iscomplexobj(out["data"]):
        raise ValueError(f"store {path!r}: if_data must be complex IF samples, got "
                         f"{out['data'].dtype}")
    return out


def _load_cube(path: str, frame: int = 0) -> dict:
    if not path.endswith(".npz"):
        from raysim.io import storage

        if storage.store_exists(path) or (path.endswith(".nc") and os.path.isfile(path)):
            return _load_store(path, frame)
    if not os.path.isfile(path):
        raise ValueError(f"cube file {path!r} does not exist")
    with np.load(path) as z:
        need = ("data", "chirp_times", "element_positions", "carrier_frequency", "bandwidth",
                "chirp_duration", "sample_rate")
        missing = [k for k in need if k not in z]
        if missing:
            raise ValueError(f"cube file {path!r} lacks keys {missing}; expected {list(need)}")
        out = {k: z[k] for k in z.files}
    data = out["data"]
    if data.ndim != 3 or not np.iscomplexobj(data):
        raise ValueError(f"cube 'data' must be complex [chirp, channel, sample], got "
                         f"{data.dtype} {data.shape}")
    return out


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


def _self_calibrate(args, cube: dict, imu: np.ndarray, offset: float | None, lam: float,
                    options: dict):
    """Motion with the clock offset and/or velocity estimated from the cube, and the report.

    One frame: the gyro bias (a drift over frames) is not estimated. Scatterers
    are detected on the selected range cells.
    """
    from compensation.calibration import self_calibrate
    from raysim.processing.maps import range_compress

    estimate = (("time_offset",) if offset is None else ()) + (
        ("velocity",) if args.velocity == "radar" else ())
    n = cube["data"].shape[-1]
    r_axis = _range_axis(cube, n)
    r_lo, r_hi = span_option(args.range_m, "--range-m", False)
    gates = np.flatnonzero((r_axis >= r_lo) & (r_axis <= r_hi))
    grid = tuple(int(v) for v in cube["grid_shape"]) if "grid_shape" in cube else None
    res = self_calibrate([range_compress(cube["data"])], [np.asarray(cube["chirp_times"],
                                                                     dtype=float)],
                         cube["element_positions"], imu[:, 0], imu[:, 1:4], imu[:, 4:7],
                         wavelength=lam, range_axis=r_axis, estimate=estimate,
                         time_offset=0.0 if offset is None else offset, grid_shape=grid,
                         detect_gates=gates if gates.size else None, **options)
    return res.motions[0], res.report()


def _range_axis(cube: dict, n_samples: int) -> np.ndarray:
    """Range of each bin of the unpadded range FFT [m]."""
    bw, tc, fs = (float(cube[k]) for k in ("bandwidth", "chirp_duration", "sample_rate"))
    return SPEED_OF_LIGHT * np.arange(n_samples) * fs / n_samples / (2.0 * bw / tc)


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
    from raysim.cli.options import check_output
    from raysim.pipeline.chains import project
    from raysim.processing.maps import range_compress

    spec = _chain(args.chain)
    check_output(args.out, "file", "--out")
    cube = _load_cube(args.cube, args.frame)
    fc, bw = float(cube["carrier_frequency"]), float(cube["bandwidth"])
    tc, fs = float(cube["chirp_duration"]), float(cube["sample_rate"])
    lam = SPEED_OF_LIGHT / (fc + bw / 2)
    grid = tuple(int(v) for v in cube["grid_shape"]) if "grid_shape" in cube else None
    u = None
    if spec.name == "paper":
        if args.direction_deg is None:
            raise ValueError(f"--chain {spec.key} needs --direction-deg AZ,EL (target "
                             f"direction)")
        u = direction(*np.deg2rad(_floats(args.direction_deg, 2, "--direction-deg")))
    motion = calibration = None
    if spec.compensated:
        if args.imu is not None and args.imu_positional is not None:
            raise ValueError(f"give the IMU log once: --imu {args.imu!r} and the positional "
                             f"{args.imu_positional!r} were both given")
        imu_path = args.imu if args.imu is not None else args.imu_positional
        if imu_path is not None:
            imu = _load_imu(imu_path)
        elif "_imu" in cube:
            imu = cube["_imu"]
        else:
            raise ValueError(f"{args.cube!r} holds no IMU log; give an IMU log with --imu FILE")
        lever = (_floats(args.lever_arm, 3, "--lever-arm") if args.lever_arm is not None
                 else np.asarray(cube.get("lever_arm", np.zeros(3)), dtype=float))
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
        kwargs.update(lever_arm=lever, initial_attitude=attitude,
                      velocity="hover" if args.velocity == "radar" else args.velocity)
        if offset is None or args.velocity == "radar":
            motion, calibration = _self_calibrate(args, cube, imu, offset, lam, kwargs)
        else:
            motion = integrate_imu(imu[:, 0], imu[:, 1:4], imu[:, 4:7],
                                   [np.asarray(cube["chirp_times"], dtype=float)],
                                   time_offset=offset, **kwargs)
    n_samples = cube["data"].shape[-1]
    r_axis = SPEED_OF_LIGHT * np.arange(n_samples) * fs / n_samples / (2.0 * bw / tc)
    r_lo, r_hi = span_option(args.range_m, "--range-m", False)
    gates = np.flatnonzero((r_axis >= r_lo) & (r_axis <= r_hi))
    if gates.size == 0:
        raise ValueError(f"--range-m {args.range_m} selects no range cell; cells span "
                         f"0 .. {r_axis[-1]:.2f} m")
    az = np.deg2rad(span_grid(args.az_deg, "--az-deg"))
    el = np.deg2rad(span_grid(args.el_deg, "--el-deg"))
    rc = range_compress(cube["data"])
    beams = project(spec, rc, cube["element_positions"], wavelength=lam, range_axis=r_axis,
                    azimuth=az, elevation=el, motion=motion, direction=u, grid_shape=grid,
                    range_gates=gates)
    if motion is None:   # the conventional beamformer carries chirp indices, not times
        beams = replace(beams, chirp_time=np.asarray(cube["chirp_times"], dtype=float))
    doppler = beams.doppler()

    def write(tmp):
        with open(tmp, "wb") as fh:  # a file object: np.savez would append ".npz" to a name
            np.savez(fh, beams=beams.data,
                     doppler_power=(np.abs(doppler) ** 2).astype(np.float32),
                     chirp_times=beams.chirp_time, range_m=beams.range,
                     azimuth_deg=np.rad2deg(az), elevation_deg=np.rad2deg(el),
                     velocity_mps=beams.velocity(), chain=np.array(spec.key),
                     warnings=np.array(beams.warnings, dtype=str),
                     **({} if calibration is None else
                        {"self_calibration": np.array(json.dumps(calibration))}))

    atomic_write(args.out, write)
    for w in beams.warnings:
        print(f"warning: {spec.key}: {w}", file=sys.stderr)
    if calibration is not None:
        print(_calibration_text(calibration))
    print(f"wrote {args.out}: beams {beams.data.shape} [chirp, range, azimuth, elevation], "
          f"chain {spec.key}" + (f", {len(beams.warnings)} warning(s)" if beams.warnings
                                 else ""))
    return 0
