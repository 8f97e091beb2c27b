"""A simulated drone flight written as the files of a real one: ULog, DCA1000 capture, SDK .cfg.

:func:`write_flight` renders a point target with the exact oracle
(:mod:`raysim.echoes.oracle`) from a platform that moves along a trajectory
(default: seeded hover jitter with rotor vibration), samples an IMU along the
same trajectory (default ``consumer_mems``, with a clock offset) and writes

* ``flight.ulg``: the IMU as PX4 ``sensor_combined`` (:mod:`raysim.io.flight_logs`),
* ``adc_data.bin``: the IF frames as a DCA1000 capture in ADC counts
  (:mod:`raysim.io.ti_dca1000`, 2 LVDS lanes, 16 bit),
* ``radar.cfg``: its mmWave SDK configuration (:mod:`raysim.io.mmwave_config`),

so that one ``raysim compensate`` command (:meth:`FlightFiles.command`,
:meth:`FlightFiles.calibrating_command`), or one call of the compensate stage
(:func:`raysim.pipeline.compensate.compensate` with
:meth:`FlightFiles.calibrating_options`), gives the compensated store.
Clocks: the radar clock is the truth time (the first ramp at ``start`` s,
``--capture-t0``), the IMU clock reads truth time plus ``time_offset``
(``--time-offset``); the IMU record starts at truth time 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["FlightFiles", "write_flight", "FLIGHT_RADAR", "measure_store",
           "calibrated_flight_table"]

#: Waveform of the flight: TI 3 Tx x 4 Rx TDM (TX0, TX2, TX1), 64 loops, 150 samples.
FLIGHT_RADAR = dict(num_chirps=64, sample_rate=2.5e6, idle_time=10e-6, frame_period=0.05)
#: The files :func:`write_flight` writes in its folder.
FLIGHT_FILES = ("adc_data.bin", "radar.cfg", "flight.ulg")
#: Largest ADC value of the written capture (the IF cube is scaled to it) [counts].
FULL_SCALE_COUNTS = 8000.0


@dataclass(frozen=True)
class FlightFiles:
    """Files of a simulated flight and the truth a test compares against.

    Attributes
    ----------
    capture, radar_config, imu_log : Path
        ``adc_data.bin``, ``radar.cfg``, ``flight.ulg``.
    start : float
        Radar-clock time of the first ramp [s].
    frame_starts : ndarray, shape ``[frame]``
        Radar-clock time of the first ramp of every frame [s].
    time_offset : float
        IMU clock minus radar clock [s].
    initial_velocity : ndarray, shape ``[frame, 3]``
        Body-origin velocity in W at the first ramp of every frame [m/s].
    initial_attitude_deg : ndarray, shape ``[frame, 3]``
        Z-Y-X Euler angles (yaw, pitch, roll) there [deg].
    initial_position : ndarray, shape ``[frame, 3]``
        Body-origin position in W there [m]; the compensation takes the
        platform at the hover point at its first ramp, so it sees the target
        from ``-initial_position`` (:meth:`apparent_direction`).
    lever_arm : ndarray, shape ``[3]``
        ``r_IR`` in B [m].
    target : tuple of float
        ``(range_m, az_deg, el_deg)`` of the point target from the nominal pose.
    imu : str
        IMU preset (grade) of the log.
    """

    capture: Path
    radar_config: Path
    imu_log: Path
    start: float
    frame_starts: np.ndarray
    time_offset: float
    initial_velocity: np.ndarray
    initial_attitude_deg: np.ndarray
    initial_position: np.ndarray
    lever_arm: np.ndarray
    target: tuple
    imu: str = "consumer_mems"

    def apparent_direction(self, frame: int = 0) -> tuple[float, float]:
        """``(az, el)`` [deg] of the target from the radar at the hover point, the platform
        displaced by ``-initial_position[frame]`` (``u = (cos el sin az, sin el, cos el cos
        az)``): where the compensated beams of a run starting at ``frame`` see it."""
        from compensation.geometry import direction

        r, az, el = self.target
        v = r * direction(np.deg2rad(az), np.deg2rad(el)) - self.initial_position[frame]
        return (float(np.rad2deg(np.arctan2(v[0], v[2]))),
                float(np.rad2deg(np.arcsin(v[1] / np.linalg.norm(v)))))

    def command(self, out: str | Path, *extra: str, frame: int | None = None) -> list[str]:
        """``raysim compensate`` arguments (without ``raysim``) that compensate the flight.

        ``frame`` None: every frame, with the velocity and attitude of the first
        ramp; ``frame`` k: that frame alone (``--frames k:k+1``), with its own.
        """
        k = 0 if frame is None else int(frame)
        v = ",".join(repr(float(x)) for x in self.initial_velocity[k])
        sel = () if frame is None else ("--frames", f"{k}:{k + 1}")
        return ["compensate", str(self.capture), "--radar-config", str(self.radar_config),
                "--imu", str(self.imu_log), "--capture-t0", repr(self.start),
                "--time-offset", repr(self.time_offset), "--velocity", "given",
                "--initial-velocity", v, "--initial-attitude-deg",
                ",".join(repr(float(x)) for x in self.initial_attitude_deg[k]), "--lever-arm",
                ",".join(repr(float(x)) for x in self.lever_arm), "--out", str(out), *sel,
                *extra]


    def calibrating_options(self, attitude: str = "flight_controller") -> dict:
        """Keyword arguments of :func:`raysim.pipeline.compensate.compensate` that compensate
        every frame with only what a user has: the IMU grade, the lever arm and the initial
        attitude; the initial velocity and the clock offset are estimated from the radar
        (``velocity="radar"``, ``time_offset="auto"``,
        :func:`compensation.calibration.self_calibrate`). The output, range cells and
        angle grid are the caller's.

        ``attitude`` ``"flight_controller"``: the attitude at the first ramp as the flight
        controller's estimate (PX4 logs it as ``vehicle_attitude``); here its value is the
        simulated one, the estimator's own error is not modelled. ``"level"``: roll and
        pitch levelled from the accelerometer over the record, heading 0 (a consumer
        accelerometer bias of 20 mg tilts it by about 1 deg).
        """
        if attitude == "flight_controller":
            att = tuple(float(x) for x in self.initial_attitude_deg[0])
        elif attitude == "level":
            att = "level"
        else:
            raise ValueError(f"attitude: got {attitude!r}, expected 'flight_controller' or "
                             f"'level'")
        return dict(source=self.capture, imu=self.imu_log, radar_config=self.radar_config,
                    capture_t0=float(self.start), imu_grade=self.imu, velocity="radar",
                    time_offset="auto", initial_attitude_deg=att,
                    lever_arm=tuple(float(x) for x in self.lever_arm))

    def calibrating_command(self, out: str | Path, *extra: str,
                            attitude: str = "flight_controller") -> list[str]:
        """``raysim compensate`` arguments (without ``raysim``) of :meth:`calibrating_options`
        with the output ``out`` and the ``extra`` arguments."""
        o = self.calibrating_options(attitude)
        att = o["initial_attitude_deg"]
        return ["compensate", str(o["source"]), "--radar-config", str(o["radar_config"]),
                "--imu", str(o["imu"]), "--capture-t0", repr(o["capture_t0"]),
                "--imu-grade", o["imu_grade"], "--velocity", o["velocity"], "--time-offset",
                o["time_offset"], "--initial-attitude-deg",
                att if isinstance(att, str) else ",".join(repr(x) for x in att),
                "--lever-arm", ",".join(repr(x) for x in o["lever_arm"]), "--out", str(out),
                *extra]


def write_flight(folder: str | Path, *, trajectory=None, imu: str = "consumer_mems",
                 imu_rate: float = 1000.0, time_offset: float = 0.003, seed: int = 0,
                 frames: int = 2, target=(11.3, 20.0, 0.0), lever_arm=(0.0, 0.0, 0.05),
                 start: float = 0.5) -> FlightFiles:
    """Simulate a flight and write its ULog, DCA1000 capture and SDK ``.cfg``.

    Parameters
    ----------
    folder : str or path-like
        Output folder (created); the three files are written atomically.
    trajectory : raysim.platform.motion.Trajectory, optional
        Body motion; default :func:`raysim.platform.motion.hover_jitter` (seed
        ``seed``: attitude and position wander plus rotor vibration).
    imu : str
        IMU preset (:mod:`raysim.platform.imu_spec`).
    imu_rate : float
        IMU output rate [Hz].
    time_offset : float
        IMU clock minus radar clock [s].
    seed : int
        Seed of the jitter and the IMU errors.
    frames : int
        Radar frames.
    target : (float, float, float)
        Range [m], azimuth and elevation [deg] of the point target.
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    start : float
        Truth (radar-clock) time of the first ramp [s]; the IMU starts at 0.

    Returns
    -------
    FlightFiles
    """
    from raysim.echoes.oracle import PointTarget, simulate_point_targets
    from raysim.io.files import atomic_write_text, check_output
    from raysim.io.flight_logs.ulog import write_px4_ulog
    from raysim.io.mmwave_config import sdk_cfg_text, ti_antenna_positions
    from raysim.io.ti_dca1000 import Dca1000Format, write_dca1000
    from raysim.pipeline.sensors import imu_record
    from raysim.platform.motion import hover_jitter
    from raysim.radar.arrays import tdm_mimo
    from raysim.radar.config import RadarConfig

    if not (isinstance(frames, int) and frames >= 1):
        raise ValueError(f"frames must be a positive integer, got {frames!r}")
    if not (np.isfinite(start) and start > 0):
        raise ValueError(f"start must be a positive time [s] (the IMU starts at 0), got "
                         f"{start!r}")
    folder = check_output(folder, "dir", "folder", names=FLIGHT_FILES)
    cfg = RadarConfig(num_tx_slots=3, num_frames=frames, **FLIGHT_RADAR)
    r, az, el = check_flight_target(target, cfg)
    tx_order, rx_on = (0, 2, 1), (0, 1, 2, 3)
    size_flight(cfg, frames, len(tx_order) * len(rx_on), folder)
    folder.mkdir(parents=True, exist_ok=True)
    traj = hover_jitter(seed) if trajectory is None else trajectory
    tx, rx = ti_antenna_positions(cfg.center_wavelength)
    array = tdm_mimo(tx[list(tx_order)], rx[list(rx_on)], name="TI 3Tx x 4Rx (TX0, TX2, TX1)")
    lever = np.asarray(lever_arm, dtype=float)
    tgt = PointTarget.at(r, np.deg2rad(az), np.deg2rad(el), radar_origin=lever)
    cube = np.stack([simulate_point_targets(cfg, array, [tgt], traj, lever_arm=lever, frame=f,
                                            t0=start).data for f in range(frames)])
    cube = cube * (FULL_SCALE_COUNTS / np.abs(cube).max())
    fmt = Dca1000Format.from_radar_config(cfg, num_rx=len(rx_on), t0=start)
    capture = write_dca1000(folder / "adc_data.bin", cube, fmt)
    radar_cfg = atomic_write_text(folder / "radar.cfg",
                                  sdk_cfg_text(cfg, tx_order=tx_order, rx_enabled=rx_on))
    end = start + frames * cfg.frame_interval + 0.05
    samples = imu_record(traj, imu, rate=imu_rate, times=[start, end], seed=seed,
                         time_offset=time_offset, start=0.0)
    ulog = write_px4_ulog(folder / "flight.ulg", samples)
    starts = start + np.arange(frames) * cfg.frame_interval
    return FlightFiles(Path(capture), Path(radar_cfg), Path(ulog), float(start), starts,
                       float(time_offset), np.asarray(traj.velocity(starts), dtype=float),
                       np.rad2deg(np.asarray(traj.euler(starts), dtype=float)),
                       np.asarray(traj.position(starts), dtype=float), lever, (r, az, el),
                       imu)


def check_flight_target(target, cfg) -> tuple[float, float, float]:
    """``(range [m], azimuth [deg], elevation [deg])`` of a flight's point target, checked.

    The target must lie in front of the radar (azimuth and elevation within
    [-90, 90] deg, the bounds a scenario's ``scene.targets`` have) and within
    the radar's unambiguous range ``(0, cfg.max_range)``.
    """
    try:
        r, az, el = (float(v) for v in target)
    except (TypeError, ValueError):
        raise ValueError(f"--target: got {target!r}, expected R,AZ,EL (three numbers)") from None
    rmax = float(cfg.max_range)
    if not (np.isfinite(r) and 0 < r < rmax):
        raise ValueError(f"--target: range {r:g} m, expected within (0, {rmax:.4g}) m (the "
                         f"radar's maximum range)")
    for name, v in (("azimuth", az), ("elevation", el)):
        if not (np.isfinite(v) and -90.0 <= v <= 90.0):
            raise ValueError(f"--target: {name} {v:g} deg, expected within [-90, 90] deg (in "
                             f"front of the radar)")
    return r, az, el


def size_flight(cfg, frames: int, channels: int, folder: Path) -> int:
    """Size a flight before allocating: refuse it (memory, disk) or announce a large capture.

    The peak is the complex128 cube ``[frame, chirp, channel, sample]`` of the
    echoes plus its scaled copy and the int16 capture; the capture on disk is
    ``frames x chirps x channels x samples x 2 x 2`` bytes.

    Returns
    -------
    int
        Estimated capture size [bytes].
    """
    import sys

    from raysim.resources import LARGE_OUTPUT_BYTES, check_memory, format_bytes, free_disk

    cells = int(frames) * int(cfg.num_chirps) * int(channels) * int(cfg.num_samples)
    check_memory(cells * (16 * 3 + 4), f"a flight of {frames} frame(s) [{cfg.num_chirps} "
                 f"chirps, {channels} channels, {cfg.num_samples} samples]", "--frames")
    disk = cells * 4
    free = free_disk(folder.resolve())
    if disk > free:
        raise ValueError(f"the capture of {frames} frame(s) would take about "
                         f"{format_bytes(disk)}, {format_bytes(free)} are free in "
                         f"{str(folder)!r}; expected a flight that fits: reduce --frames")
    if disk > LARGE_OUTPUT_BYTES:
        print(f"flight: writing about {format_bytes(disk)} of capture in {str(folder)!r}",
              file=sys.stderr, flush=True)
    return disk


#: Azimuth step [deg] of the beams measured by :func:`measure_store` (peaks interpolated
#: by a parabola on dB).
MEASURE_STEP_DEG = 0.25


def measure_store(store, flight: FlightFiles, first: int = 0) -> np.ndarray:
    """The beam metrics (:data:`raysim.measure.beams.BEAM_METRICS`) of every frame of a
    compensated store of a simulated flight.

    The store holds one elevation (the 3 Tx x 4 Rx array resolves azimuth only) and an
    azimuth grid around the target; ``first`` is the flight frame of its first frame
    (the reference of :meth:`FlightFiles.apparent_direction`).

    Returns
    -------
    ndarray, shape ``[frame, 3]``
        ``beam_angle_error_deg`` [deg], ``beam_pseudo_velocity_bins`` [bins],
        ``doppler_leakage_db`` [dB] per frame.
    """
    from raysim.io.mmwave_config import read_mmwave_config
    from raysim.io.zarr_store import open_store
    from raysim.measure.beams import BEAM_METRICS, beam_metrics

    ds = store if hasattr(store, "data_vars") else open_store(store)   # a path or a Dataset
    cfg = read_mmwave_config(flight.radar_config).config
    az_true = flight.apparent_direction(first)[0]
    out = []
    for b in ds["beams"].values[..., 0]:                         # [chirp, range, azimuth]
        m = beam_metrics(b, ds.azimuth.values, az_true, chirp_interval=cfg.chirp_interval,
                         wavelength=cfg.center_wavelength,
                         velocity_resolution=cfg.velocity_resolution)
        out.append([m[k] for k in BEAM_METRICS])
    return np.array(out)


def _grid(lo: float, hi: float, step: float) -> np.ndarray:
    """``lo, lo + step, ...`` up to ``hi`` included [deg] (the ``LO:HI:STEP`` of the CLI)."""
    return lo + step * np.arange(int(np.floor((hi - lo) / step + 1e-9)) + 1)


def calibrated_flight_table(folder: str | Path, seeds=range(4), *, frames: int = 4,
                            attitude: str = "flight_controller", **flight) -> list[dict]:
    """Write a flight per seed, compensate it with one self-calibrating compensate stage
    (:func:`raysim.pipeline.compensate.compensate` with
    :meth:`FlightFiles.calibrating_options`, what ``raysim compensate``
    :meth:`FlightFiles.calibrating_command` runs) and measure every frame.

    Returns
    -------
    list of dict
        Per seed: ``seed``, the worst over the frames of ``beam_angle_error_deg``,
        ``|beam_pseudo_velocity_bins|`` and ``doppler_leakage_db``
        (:mod:`raysim.measure.beams`), ``offset_error_ms`` (estimated minus true),
        ``cpu_s`` of the compensate stage (``time.process_time``).
    """
    import time

    from raysim.pipeline.compensate import compensate

    rows = []
    for seed in seeds:
        f = write_flight(Path(folder) / f"seed{seed}", seed=seed, frames=frames, **flight)
        out = Path(folder) / f"seed{seed}" / "compensated.zarr"
        r, az, _ = f.target
        cpu = time.process_time()
        res = compensate(**f.calibrating_options(attitude), out=out, range_m=(r - 0.5, r + 0.5),
                         azimuth_deg=_grid(az - 6, az + 6, MEASURE_STEP_DEG),
                         elevation_deg=(0.0,))
        cpu = time.process_time() - cpu
        m = measure_store(out, f)
        cal = res.calibration
        rows.append(dict(seed=int(seed), beam_angle_error_deg=float(m[:, 0].max()),
                         beam_pseudo_velocity_bins=float(np.abs(m[:, 1]).max()),
                         doppler_leakage_db=float(m[:, 2].max()),
                         offset_error_ms=1e3 * (cal["time_offset_s"] - f.time_offset),
                         cpu_s=cpu))
    return rows


if __name__ == "__main__":     # python -m raysim.pipeline.flight FOLDER [SEEDS] [FRAMES]
    import sys

    seeds_ = range(int(sys.argv[2]) if len(sys.argv) > 2 else 6)
    table = calibrated_flight_table(sys.argv[1], seeds_,
                                    frames=int(sys.argv[3]) if len(sys.argv) > 3 else 4)
    print("| seed | angle [deg] | pseudo-velocity [bin] | leakage [dB] | offset error [ms] "
          "| CPU [s] |\n|---|---|---|---|---|---|")
    for row in table:
        print(f"| {row['seed']} | {row['beam_angle_error_deg']:.3f} | "
              f"{row['beam_pseudo_velocity_bins']:.4f} | {row['doppler_leakage_db']:.1f} | "
              f"{row['offset_error_ms']:+.3f} | {row['cpu_s']:.1f} |")
