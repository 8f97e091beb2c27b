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

import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["FlightFiles", "write_flight", "FLIGHT_RADAR", "measure_store",
           "measure_targets", "calibrated_flight_table", "DEFAULT5_TARGETS", "DEFAULT_BOARD",
           "board_resolves_elevation"]

#: Waveform of the flight: TI 3 Tx x 4 Rx TDM (TX0, TX2, TX1), 64 loops, 150 samples.
FLIGHT_RADAR = dict(num_chirps=64, sample_rate=2.5e6, idle_time=10e-6, frame_period=0.05)
#: Relative l2 error of the flight's synthesis with slow-time decimation: the exact rows
#: are the oracle's tone sum, the interpolation gets ``DECIMATION_EPS_SHARE`` of it (1e-6)
#: unless ``decimate_tolerance`` says otherwise.
FLIGHT_SYNTHESIS_EPS = 1e-5
#: Name and format tag of the flight's truth (:meth:`FlightFiles.truth`).
TRUTH_FILE, TRUTH_FORMAT = "truth.json", "raysim-flight-truth-1"
#: The files :func:`write_flight` writes in its folder.
FLIGHT_FILES = ("adc_data.bin", "radar.cfg", "flight.ulg", TRUTH_FILE)
#: Largest ADC value of the written capture (the IF cube is scaled to it) [counts].
FULL_SCALE_COUNTS = 8000.0
#: The board of a flight unless told: xWR18xx, 3 TX (TX1 raised lambda/2) x 4 RX.
DEFAULT_BOARD = "xWR18xx"
#: ``targets="default5"``: five stationary targets (range [m], azimuth, elevation [deg])
#: spread over 4-9 m, azimuth -25..30 deg and elevation -5, 0, +5 deg, at least 1 m apart
#: in range so that each has its own range cells.
DEFAULT5_TARGETS = ((4.5, -25.0, 0.0), (5.5, 12.0, 5.0), (6.5, -8.0, -5.0),
                    (7.7, 30.0, 0.0), (8.8, 3.0, 5.0))


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
        ``(range_m, az_deg, el_deg)`` of the (first) point target from the nominal
        pose, directions in the nominal radar frame N (:mod:`raysim.platform.mounting`).
    imu : str
        IMU preset (grade) of the log.
    targets : tuple of tuple
        Every target ``(range_m, az_deg, el_deg)``; default ``(target,)``.
    board : str
        TI board whose antennas and lanes the capture has.
    mounting_deg : tuple of float
        Radar mounting ``R_BA`` (yaw, pitch, roll) [deg].
    imu_rate : float
        Logged IMU rate [Hz] (boxcar-averaged when ``imu_boxcar``).
    imu_boxcar : bool
        Whether the log is a flight controller's boxcar average.
    gaps : tuple of (float, float)
        Logger gaps ``(start, length)`` [s, IMU clock].
    attitude : bool
        Whether the log holds the flight controller's attitude.
    log_attitude_deg : ndarray, shape ``[frame, 3]``, optional
        That attitude at each frame's first ramp, (yaw, pitch, roll) [deg]: the
        truth turned by the controller's roll and pitch error
        (:func:`raysim.pipeline.flight_log.controller_tilt_error`); None without it.
    clock_drift_ppm : float
        IMU clock rate error [ppm].
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
    targets: tuple = ()
    board: str = DEFAULT_BOARD
    mounting_deg: tuple = (0.0, 0.0, 0.0)
    imu_rate: float = 1000.0
    imu_boxcar: bool = False
    gaps: tuple = ()
    attitude: bool = True
    clock_drift_ppm: float = 0.0
    log_attitude_deg: np.ndarray | None = None

    def __post_init__(self) -> None:
        if not self.targets:
            object.__setattr__(self, "targets", (tuple(self.target),))

    def truth(self) -> dict:
        """Every field as JSON-ready values, paths relative to the flight's folder
        (:func:`raysim.pipeline.flight_truth.read_truth` reads them back)."""
        import json
        from dataclasses import fields

        folder = Path(self.capture).parent
        out = {"format": TRUTH_FORMAT}
        for f in fields(self):
            v = getattr(self, f.name)
            if isinstance(v, Path):
                v = v.relative_to(folder).as_posix()
            elif isinstance(v, np.ndarray):
                v = v.tolist()
            elif isinstance(v, tuple):
                v = json.loads(json.dumps(v))          # nested tuples as lists
            out[f.name] = v
        return out

    def _extra(self) -> tuple:
        """Options every command of this flight needs beyond today's: board, mounting, gaps."""
        out = () if self.board == DEFAULT_BOARD else ("--board", self.board)
        if tuple(self.mounting_deg) != (0.0, 0.0, 0.0):
            out += ("--mounting-deg", ",".join(repr(float(x)) for x in self.mounting_deg))
        if self._max_gap() is not None:
            out += ("--max-gap", repr(self._max_gap()))
        return out

    def _max_gap(self) -> float | None:
        """``--max-gap`` [s] that fills the logger gaps inside the window a compensation of
        every frame uses (IMU clock, :data:`compensation.ingestion.WINDOW_MARGIN` each
        side); None when none lies there."""
        from compensation.ingestion import WINDOW_MARGIN

        lo = self.start + self.time_offset - WINDOW_MARGIN
        hi = float(self.frame_starts[-1]) + FLIGHT_RADAR["frame_period"] + self.time_offset \
            + WINDOW_MARGIN
        inside = [n for s, n in self.gaps if s < hi and s + n > lo]
        return round(max(inside) + 0.02, 3) if inside else None

    def apparent_direction(self, frame: int = 0, target: int = 0) -> tuple[float, float]:
        """``(az, el)`` [deg] of a target from the radar at the hover point, the platform
        displaced by ``-initial_position[frame]`` (``u = (cos el sin az, sin el, cos el cos
        az)`` in the nominal radar frame N): where the compensated beams of a run starting
        at ``frame`` see it."""
        from compensation.geometry import direction
        from raysim.platform.mounting import mounting_matrix

        r, az, el = self.targets[target]
        m = mounting_matrix(self.mounting_deg)
        v = r * direction(np.deg2rad(az), np.deg2rad(el)) - m.T @ self.initial_position[frame]
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
                *self._extra(), *extra]


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
        accelerometer bias of 20 mg tilts it by about 1 deg). ``"log"``: left to the
        compensate stage, which reads the log's ``vehicle_attitude`` at the first ramp
        (level 0, 0, 0 when the log holds none, ``attitude=False``).
        """
        if attitude == "flight_controller":
            att = tuple(float(x) for x in self.initial_attitude_deg[0])
        elif attitude in ("level", "log"):
            att = None if attitude == "log" else "level"
        else:
            raise ValueError(f"attitude: got {attitude!r}, expected 'flight_controller', "
                             f"'level' or 'log'")
        opts = dict(source=self.capture, imu=self.imu_log, radar_config=self.radar_config,
                    capture_t0=float(self.start), imu_grade=self.imu, velocity="radar",
                    time_offset="auto", initial_attitude_deg=att,
                    lever_arm=tuple(float(x) for x in self.lever_arm))
        if self.board != DEFAULT_BOARD:
            opts["board"] = self.board
        if self._max_gap() is not None:
            opts["max_gap"] = self._max_gap()
        from compensation.calibration import OFFSET_SEARCH_HALF_WIDTH

        # an offset set near or past the default search: as a user who knows their sync asks
        if abs(self.time_offset) > 0.8 * OFFSET_SEARCH_HALF_WIDTH:
            opts["time_offset_search"] = math.ceil(1.5e3 * abs(self.time_offset)) / 1e3
        return opts

    def calibrating_command(self, out: str | Path, *extra: str,
                            attitude: str = "flight_controller") -> list[str]:
        """``raysim compensate`` arguments (without ``raysim``) of :meth:`calibrating_options`
        with the output ``out`` and the ``extra`` arguments."""
        o = self.calibrating_options(attitude)
        att = o["initial_attitude_deg"]
        att = () if att is None else ("--initial-attitude-deg", att if isinstance(att, str)
                                      else ",".join(repr(x) for x in att))
        return ["compensate", str(o["source"]), "--radar-config", str(o["radar_config"]),
                "--imu", str(o["imu"]), "--capture-t0", repr(o["capture_t0"]),
                "--imu-grade", o["imu_grade"], "--velocity", o["velocity"], "--time-offset",
                o["time_offset"], *att,
                "--lever-arm", ",".join(repr(x) for x in o["lever_arm"]), "--out", str(out),
                *(("--time-offset-search", repr(o["time_offset_search"]))
                  if "time_offset_search" in o else ()), *self._extra(), *extra]


def board_resolves_elevation(board: str) -> bool:
    """Whether ``board``'s virtual array spans the elevation aperture the self-calibration
    takes to resolve elevation (:data:`compensation.calibration.MIN_APERTURE_WAVELENGTHS`)."""
    from compensation.calibration import MIN_APERTURE_WAVELENGTHS
    from raysim.io.ti_boards import BOARDS

    b = BOARDS[board]
    y = [t[1] + q[1] for t in b.tx for q in b.rx]          # half wavelengths
    return (max(y) - min(y)) / 2 >= MIN_APERTURE_WAVELENGTHS


def write_flight(folder: str | Path, *, trajectory=None, imu: str = "consumer_mems",
                 imu_rate: float = 1000.0, time_offset: float = 0.003, seed: int = 0,
                 frames: int = 2, target=(11.3, 20.0, 0.0), lever_arm=(0.0, 0.0, 0.05),
                 start: float = 0.5, targets=None, board: str = DEFAULT_BOARD,
                 mounting_deg=None, imu_boxcar: bool = False, imu_fast_rate: float = 2000.0,
                 log_gaps: int = 0, gaps_in_capture: bool = False,
                 clock_drift_ppm: float = 0.0, attitude: bool = True,
                 clutter_scene: str | None = None, clutter_altitude: float | None = None,
                 clutter_max_scatterers: int = 200_000, clutter_specular: bool = False,
                 decimate="auto",
                 decimate_tolerance: float | None = None,
                 progress: bool = False) -> FlightFiles:
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
        Logged IMU rate [Hz].
    time_offset : float
        IMU clock minus radar clock at truth time 0 [s].
    seed : int
        Seed of the jitter, the IMU errors and the logger gaps.
    frames : int
        Radar frames.
    target : (float, float, float)
        Range [m], azimuth and elevation [deg] of the point target.
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    start : float
        Truth (radar-clock) time of the first ramp [s]; the IMU starts at 0.
    targets : sequence of (float, float, float) or str, optional
        Several stationary targets ``(range [m], az [deg], el [deg])``, or
        ``"default5"`` (:data:`DEFAULT5_TARGETS`); replaces ``target``.
    board : str
        TI board (:data:`raysim.io.ti_boards.BOARDS`): its antennas, RX feed
        signs and LVDS lanes; 3-TX boards fire TX0, TX2, TX1, 2-TX boards TX0,
        TX1; the 60 GHz boards start at 60 GHz.
    mounting_deg : str or (float, float, float), optional
        Radar mounting (:mod:`raysim.platform.mounting`); default ``down``.
        Target directions are in the nominal radar frame N.
    imu_boxcar : bool
        Log the IMU as a flight controller does: ``imu_fast_rate`` samples
        boxcar-averaged into ``imu_rate`` (:mod:`raysim.pipeline.flight_log`).
    imu_fast_rate : float
        Internal IMU rate of the boxcar [Hz].
    log_gaps : int
        Logger gaps of 50-160 ms, seeded, outside the window a compensation
        uses unless ``gaps_in_capture`` puts the first inside the capture.
    clock_drift_ppm : float
        IMU clock rate error [ppm].
    attitude : bool
        Write the flight controller's attitude as ``vehicle_attitude``.
    clutter_scene : str, optional
        Add the ground clutter field of this bundled scene
        (:mod:`raysim.pipeline.flight_clutter`) where the mounted radar points,
        rendered by the same oracle with the element pattern.
    clutter_altitude : float, optional
        Hover height above that ground [m]; default the scene's.
    clutter_max_scatterers : int
        Bound on the clutter field's scatterers (cost).
    clutter_specular : bool
        Add the ground's coherent specular mirror below the radar to the clutter.
    decimate : "auto" or "off"
        Slow-time decimation of the targets' and the clutter's synthesis
        (:func:`raysim.synthesis.select.synthesize` on the oracle's delays, tone
        sum rows, band read from the delays, checked on a channel at every chirp;
        refused with the reason where it cannot hold the tolerance). ``"off"``:
        the oracle's own render, every chirp exact.
    decimate_tolerance : float, optional
        Relative error (l2 and worst chirp row) of the interpolation against the
        undecimated render; default ``0.1 x FLIGHT_SYNTHESIS_EPS``.
    progress : bool
        A progress bar over the frames on stderr and the sizes announced.

    Returns
    -------
    FlightFiles
    """
    from raysim.echoes.oracle import PointTarget, simulate_point_targets
    from raysim.io.files import atomic_write_text, check_output, written_together
    from raysim.io.flight_logs.ulog import write_px4_ulog
    from raysim.io.mmwave_config import sdk_cfg_text
    from raysim.io.ti_boards import BOARDS, resolve_board
    from raysim.io.ti_dca1000 import Dca1000Format, write_dca1000
    from raysim.pipeline.flight_log import flight_log
    from raysim.platform.motion import hover_jitter
    from raysim.platform.mounting import mount_array, mount_pattern, nominal_target_position
    from raysim.platform.mounting import mounting_deg as mount_ypr
    from raysim.radar.arrays import tdm_mimo
    from raysim.radar.config import RadarConfig

    if not (isinstance(frames, int) and frames >= 1):
        raise ValueError(f"frames must be a positive integer, got {frames!r}")
    if not (np.isfinite(start) and start > 0):
        raise ValueError(f"start must be a positive time [s] (the IMU starts at 0), got "
                         f"{start!r}")
    from raysim.pipeline.flight_log import check_flight_log
    from raysim.synthesis.select import check_decimate, check_decimate_tolerance

    decimate = check_decimate(decimate)
    tolerance = check_decimate_tolerance(decimate_tolerance, FLIGHT_SYNTHESIS_EPS,
                                         "decimate_tolerance (--decimate-tolerance)")
    check_flight_log(seed, time_offset, clock_drift_ppm, imu_rate, imu_fast_rate, imu_boxcar)
    folder = check_output(folder, "dir", "folder", names=FLIGHT_FILES)
    layout = resolve_board(board, tx_order=(0,), rx_enabled=(0,), start_freq_hz=77e9
                           if BOARDS.get(board) is None or BOARDS[board].band_ghz[0] > 70
                           else 60e9, wavelength=1.0, where="--board: ")
    band = BOARDS[layout.name].band_ghz
    tx_order = (0, 2, 1) if len(layout.tx) == 3 else tuple(range(len(layout.tx)))
    rx_on = (0, 1, 2, 3)
    carrier = {} if band[0] <= 77.0 <= band[1] else dict(carrier_frequency=band[0] * 1e9 + 1e9)
    cfg = RadarConfig(num_tx_slots=len(tx_order), num_frames=frames, **FLIGHT_RADAR, **carrier)
    tgts = _targets(target if targets is None else targets, cfg)
    mount = mount_ypr(mounting_deg)
    size_flight(cfg, frames, len(tx_order) * len(rx_on), folder, announce=progress)
    with written_together(folder, FLIGHT_FILES):   # a capture without its log: none
        traj = hover_jitter(seed) if trajectory is None else trajectory
        lay = resolve_board(layout.name, tx_order=tx_order, rx_enabled=rx_on,
                            start_freq_hz=cfg.carrier_frequency, wavelength=cfg.center_wavelength)
        name = ("TI 3Tx x 4Rx (TX0, TX2, TX1)" if layout.name == DEFAULT_BOARD
                else f"TI {layout.name} (TX{', TX'.join(map(str, tx_order))})")
        array = tdm_mimo(lay.tx[list(tx_order)], lay.rx[list(rx_on)], name=name)
        lever = np.asarray(lever_arm, dtype=float)
        points = [PointTarget.at(r, np.deg2rad(az), np.deg2rad(el), radar_origin=lever)
                  if mounting_deg is None else
                  PointTarget(nominal_target_position(r, np.deg2rad(az), np.deg2rad(el), lever,
                                                      mount), np.zeros(3))
                  for r, az, el in tgts]
        mounted = mount_array(array, mount)
        clutter = []
        if clutter_scene is not None:
            from raysim.pipeline.flight_clutter import clutter_points

            clutter, summary = clutter_points(clutter_scene, cfg, array, lever,
                                              altitude=clutter_altitude, seed=seed,
                                              max_scatterers=clutter_max_scatterers,
                                              mounting_deg=mount, specular=clutter_specular)
            if progress:
                print(f"flight: {summary}", file=sys.stderr, flush=True)
        ks = range(frames)
        if progress and frames > 1:
            from tqdm import tqdm

            ks = tqdm(ks, unit="frame", desc="flight", file=sys.stderr)
        def render(pts, f: int) -> np.ndarray:
            if decimate == 1:                  # the oracle's own render, every chirp exact
                return simulate_point_targets(cfg, mounted, pts, traj, lever_arm=lever,
                                              frame=f, t0=start, pattern=mount_pattern(
                                                  cfg.pattern, mount)).data
            from raysim.echoes.oracle import check_frame_memory, point_target_delays
            from raysim.synthesis.frame import adc_samples
            from raysim.synthesis.select import synthesize, tones_error

            # the delays and amplitudes twice: the path groups of the decimation copy theirs
            check_frame_memory(cfg, mounted, 2 * len(pts))
            tau, amp = point_target_delays(cfg, mounted, traj, pts, lever_arm=lever, frame=f,
                                           t0=start, pattern=mount_pattern(cfg.pattern, mount))
            eps = max(FLIGHT_SYNTHESIS_EPS, tones_error(len(pts)))
            return adc_samples(synthesize(tau, amp, cfg, method="tones", eps=eps,
                                          decimate=decimate, decimate_tolerance=tolerance), cfg)

        def frame(f: int) -> np.ndarray:
            data = render(points, f)
            if clutter:
                data = data + render(clutter, f)
            return data

        cube = np.stack([frame(f) for f in ks])
        feed = np.tile(lay.rx_phase[list(rx_on)], len(tx_order))      # [channel]: RX feed signs
        if np.any(feed != 1):
            cube = cube * feed[None, None, :, None]
        cube = cube * (FULL_SCALE_COUNTS / np.abs(cube).max())
        fmt = Dca1000Format.from_radar_config(cfg, num_rx=len(rx_on), t0=start,
                                              layout=lay.layout or "2lane")
        capture = write_dca1000(folder / "adc_data.bin", cube, fmt)
        radar_cfg = atomic_write_text(folder / "radar.cfg",
                                      sdk_cfg_text(cfg, tx_order=tx_order, rx_enabled=rx_on))
        end = start + frames * cfg.frame_interval + 0.05
        tail = 0.0 if log_gaps <= int(gaps_in_capture) else 0.65 + 0.3 * log_gaps   # room after
        samples, att, gaps = flight_log(
            traj, imu, rate=imu_rate, times=[start, end + tail], seed=seed,
            time_offset=time_offset, clock_drift_ppm=clock_drift_ppm, boxcar=imu_boxcar,
            fast_rate=imu_fast_rate, gaps=log_gaps, gaps_in_capture=gaps_in_capture,
            attitude=attitude, capture=(start, end - 0.05))
        ulog = write_px4_ulog(folder / "flight.ulg", samples, att, averaged=bool(imu_boxcar))
        starts = start + np.arange(frames) * cfg.frame_interval
        flight = FlightFiles(Path(capture), Path(radar_cfg), Path(ulog), float(start), starts,
                           float(time_offset), np.asarray(traj.velocity(starts), dtype=float),
                           np.rad2deg(np.asarray(traj.euler(starts), dtype=float)),
                           np.asarray(traj.position(starts), dtype=float), lever, tgts[0],
                           imu, tuple(tgts), layout.name, tuple(float(x) for x in mount),
                           float(imu_rate), bool(imu_boxcar), tuple(gaps), bool(attitude),
                           float(clock_drift_ppm), None if att is None else np.array(
                               [att.euler_deg(time_offset + (1 + 1e-6 * clock_drift_ppm) * t)
                                for t in starts]))
        from raysim.io.files import atomic_write_json

        atomic_write_json(folder / TRUTH_FILE, flight.truth(), indent=1)
    return flight


def _targets(value, cfg) -> list:
    """The flight's targets, checked: one ``(r, az, el)``, several, or ``"default5"``."""
    if isinstance(value, str):
        if value != "default5":
            raise ValueError(f"--targets: got {value!r}, expected 'default5'")
        value = DEFAULT5_TARGETS
    value = list(value)
    if value and np.ndim(value[0]) == 0:          # one target (r, az, el)
        value = [value]
    if not value:
        raise ValueError("--target: expected at least one target R,AZ,EL")
    return [check_flight_target(t, cfg) for t in value]


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


def size_flight(cfg, frames: int, channels: int, folder: Path, announce: bool = False) -> int:
    """Size a flight before allocating: refuse it (memory, disk) or announce a large capture.

    The peak is the complex128 cube ``[frame, chirp, channel, sample]`` of the
    echoes plus its scaled copy and the int16 capture; the capture on disk is
    ``frames x chirps x channels x samples x 2 x 2`` bytes.

    Returns
    -------
    int
        Estimated capture size [bytes].
    """
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
    if disk > LARGE_OUTPUT_BYTES or announce:
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


#: Half width of the range cells measured around each target [range resolutions]: its
#: own cell and the neighbours a range between two cells straddles, not the next
#: target's (targets 0.4 m apart at 15 cm resolution took each other's peak with 0.45 m).
TARGET_RANGE_HALF_WIDTH_CELLS = 1.5
#: Half width of the azimuths searched for each target's peak [deg]: its main lobe
#: (the 8-channel azimuth aperture's -3 dB half width is about 6.4 deg at
#: boresight), so the ground under the radar in the same cells, 26 deg away and
#: stronger, is not taken for a target at 30 deg.
TARGET_AZIMUTH_HALF_WIDTH_DEG = 8.0


def measure_targets(store, flight: FlightFiles, first: int = 0) -> np.ndarray:
    """The beam metrics of every target in every frame of a compensated store.

    Each target is measured on the range cells within
    :data:`TARGET_RANGE_HALF_WIDTH_CELLS` range resolutions of its range and its peak
    looked for within
    :data:`TARGET_AZIMUTH_HALF_WIDTH_DEG` of its azimuth, at the store's elevation
    nearest its apparent elevation, against its apparent azimuth
    (:meth:`FlightFiles.apparent_direction` of frame ``first``). Between two elevations
    of the store the peak's azimuth is interpolated linearly to the target's own: an
    array that resolves elevation (IWR6843AOP) moves the azimuth peak of a beam off its
    target's elevation, 0.25 deg at 0.7 deg off.

    Returns
    -------
    ndarray, shape ``[target, frame, 3]``
        ``beam_angle_error_deg`` [deg], ``beam_pseudo_velocity_bins`` [bins],
        ``doppler_leakage_db`` [dB].
    """
    from raysim.io.mmwave_config import read_mmwave_config
    from raysim.io.zarr_store import open_store
    from raysim.measure.beams import BEAM_METRICS, beam_metrics, zero_doppler_peak

    ds = store if hasattr(store, "data_vars") else open_store(store)
    cfg = read_mmwave_config(flight.radar_config, board=flight.board).config
    ranges, els = (np.asarray(ds[n].values, dtype=float) for n in ("range", "elevation"))
    beams = ds["beams"].values                     # [frame, chirp, range, azimuth, elevation]
    az = ds["azimuth"].values
    opts = dict(chirp_interval=cfg.chirp_interval, wavelength=cfg.center_wavelength,
                velocity_resolution=cfg.velocity_resolution,
                search_deg=TARGET_AZIMUTH_HALF_WIDTH_DEG)
    out = []
    for j, (r, _, _) in enumerate(flight.targets):
        az_true, el_true = flight.apparent_direction(first, j)
        cells = np.flatnonzero(np.abs(ranges - r)
                               <= TARGET_RANGE_HALF_WIDTH_CELLS * cfg.range_resolution)
        if cells.size == 0:
            raise ValueError(f"the store's range cells {ranges.min():.2f}..{ranges.max():.2f} "
                             f"m miss target {j} at {r:g} m")
        e = int(np.argmin(np.abs(els - el_true)))
        o = e + (1 if el_true > els[e] else -1)                   # the other side of it
        w = (el_true - els[e]) / (els[o] - els[e]) if 0 <= o < els.size else 0.0
        rows = []
        for k, b in enumerate(beams[..., e][:, :, cells]):       # [chirp, range, azimuth]
            m = beam_metrics(b, az, az_true, **opts)
            if w > 0:        # the peak's azimuth interpolated to the target's own elevation
                p0, p1 = (zero_doppler_peak(x, az, az_true, opts["search_deg"])[2]
                          for x in (b, beams[k, ..., o][:, cells]))
                m["beam_angle_error_deg"] = abs((1 - w) * p0 + w * p1 - az_true)
            rows.append([m[q] for q in BEAM_METRICS])
        out.append(rows)
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
    seeds_ = range(int(sys.argv[2]) if len(sys.argv) > 2 else 6)
    table = calibrated_flight_table(sys.argv[1], seeds_,
                                    frames=int(sys.argv[3]) if len(sys.argv) > 3 else 4)
    print("| seed | angle [deg] | pseudo-velocity [bin] | leakage [dB] | offset error [ms] "
          "| CPU [s] |\n|---|---|---|---|---|---|")
    for row in table:
        print(f"| {row['seed']} | {row['beam_angle_error_deg']:.3f} | "
              f"{row['beam_pseudo_velocity_bins']:.4f} | {row['doppler_leakage_db']:.1f} | "
              f"{row['offset_error_ms']:+.3f} | {row['cpu_s']:.1f} |")
