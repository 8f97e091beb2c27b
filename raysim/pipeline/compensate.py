"""Compensate stage: a stored IF cube or a raw capture plus an IMU log -> compensated beams.

:func:`compensate` is the one implementation behind ``raysim compensate`` (the
command only parses its options and prints) and the studies that compensate
recorded files (:mod:`raysim.pipeline.flight`). It reads the input
(:mod:`raysim.io.compensate_io`), estimates the platform motion at every
transmit slot of every selected frame (one integration over the record,
:func:`raysim.pipeline.estimate.estimate_record`; or, when the clock offset or
the velocity is unknown, the self-calibration of
:func:`raysim.pipeline.self_calibration.calibrate_record`), projects every
frame with its own motion through the chain (:func:`raysim.pipeline.chains.project`)
and writes the output.

Input (``source``): a raw TI DCA1000 capture (``adc_data.bin``) with its radar
configuration (``radar_config``: an mmWave SDK ``.cfg`` or an mmWave Studio
``.json`` export, :mod:`raysim.io.mmwave_config`; it sets the waveform, the
TDM slot order of the virtual array and the binary layout; every frame, or
``frames="LO:HI"``), a frame store written by :mod:`raysim.io.storage` (a Zarr
store directory, or a NetCDF file ``.nc`` from
:func:`raysim.io.storage.export_netcdf`; ``frame`` or ``frames``) or an ``.npz``
file (or a MATLAB ``.mat`` of v7 or older: vectors ``1 x n`` or ``n x 1``) with these keys:

=====================  =========================  =================================
key                    shape                      meaning
=====================  =========================  =================================
``data``               ``[chirp, channel, sample]``  IF samples: complex (I/Q) or real
``chirp_times``        ``[chirp]``                chirp start times, radar clock [s]
``element_positions``  ``[channel, 3]``           virtual positions p_tx + p_rx in A [m]
``carrier_frequency``  scalar                     f_c [Hz]
``bandwidth``          scalar                     B [Hz]
``chirp_duration``     scalar                     T_c [s]
``sample_rate``        scalar                     f_s [Hz]
``grid_shape``         ``[2]`` (optional)         (nx, ny), x major, y minor
``lever_arm``          ``[3]`` (optional)         r_IR in B [m]
``tx_slot``            ``[channel]`` (optional)   TDM slot of each channel
``slot_interval``      scalar (optional)          ramp-to-ramp interval of slots [s]
=====================  =========================  =================================

TDM MIMO: the IMU log is integrated once to the start of every transmit slot
of every selected frame, and each slot's channels are compensated with the
pose of their own ramp (exact, dpca and paper chains).

IMU log (``imu``): a file of any format of
:func:`raysim.io.flight_logs.read_imu_log` (the project's IMU CSV, PX4 ULog,
ArduPilot DataFlash ``.bin``, ROS 1 or 2 bag; FLU turned into FRD), or a table
``[sample, 7]`` (time [s, IMU clock], angular rate [rad/s], specific force
[m/s^2], body frame FRD). ``time_offset`` is IMU clock minus radar clock. It
may be left out when the frame store holds an IMU log. The source inside a log
(``imu_topic``, ``imu_instance``; default the complete one with the highest
rate) is reported as :attr:`CompensateResult.imu_source` and the store's
``imu_source`` attribute. The log is judged over the window it is used for
(the selected slots on the IMU clock plus
:data:`compensation.ingestion.WINDOW_MARGIN`): gaps outside it are not judged,
gaps inside it up to ``max_gap`` are filled by interpolation with a warning,
a log that does not cover the window is refused as such
(:func:`compensation.ingestion.judge_imu_window`). A capture's antennas come
from ``board`` or ``antenna_positions`` (:mod:`raysim.io.ti_boards`).

Output (``out``): a labelled Zarr store
(:func:`raysim.io.compensate_io.write_compensated_store`) with ``beams
[frame, chirp, range, azimuth, elevation]``, ``doppler_power``, ``chirp_time``,
``slot_time``, the axes and the attributes ``chain``, ``warnings``,
``velocity``, ``time_offset_s``, ``self_calibration`` and, with ``autofocus``,
``autofocus`` (JSON, per frame); or, for one frame and a path ending in
``.npz``, the file of :func:`raysim.io.compensate_io.write_compensated_npz`
(the autofocus report under ``autofocus`` in its ``self_calibration`` JSON).
The warnings are the chains' and the integration's assumption warnings
(:mod:`compensation.guards`), in the output and in
:attr:`CompensateResult.warnings`.

Autofocus (``autofocus``, ``--autofocus [auto|off|phase|stationary|displacement]``): after
the IMU-driven chain, the residual per-chirp phase common to the stationary
scatterers (vibration the IMU log cannot see) is estimated from each frame's
beams and removed (:func:`compensation.autofocus.autofocus_beams`; TDM: stamped
at each chirp's mean slot time); ``displacement``: the residual displacement
vector, every beam corrected at its own direction
(:func:`compensation.autofocus_displacement.autofocus_displacement`); its report
(rms phase, band, sigma, cells) is :attr:`CompensateResult.autofocus`. ``auto``
(the command's default, ``--autofocus off`` to skip) applies ``displacement`` where
the chain warns that it leaves motion in the data (:data:`AUTOFOCUS_CAUSES`).

Errors name the parameter by its ``raysim compensate`` option (``--frames``,
``--range-m`` ...): parameter ``x_y`` is option ``--x-y``.
"""

from __future__ import annotations

import os
import warnings
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from raysim.io.compensate_io import (
    check_compensated_output,
    load_input,
    write_compensated_npz,
    write_compensated_store,
)
from raysim.io.store_guard import remove_debris, writer_lock
from raysim.pipeline.chains import project
from raysim.pipeline.compensate_size import gated_range_compress, output_bytes
from raysim.pipeline.estimate import estimate_record, ground_retilt, ground_tilt_of_record
from raysim.pipeline.gap_segments import GROUND_ROLE, motions_by_segment
from raysim.pipeline.grid_miss import grid_miss_warning
from raysim.pipeline.imu_inputs import imu_table, imu_window, log_attitude
from raysim.pipeline.self_calibration import calibrate_record
from raysim.processing.maps import range_compress
from raysim.vocabulary import parse_chain

__all__ = ["CompensateResult", "compensate", "VELOCITY_CHOICES", "DEFAULT_ANGLES_DEG"]

#: Initial-velocity handling: zero mean over the hover window (``hover``), given
#: (``given``), or estimated from the Doppler of stationary scatterers (``radar``).
VELOCITY_CHOICES = ("hover", "given", "radar")
#: Default azimuth and elevation grid [deg] (``-60:60:1``).
DEFAULT_ANGLES_DEG = -60.0 + np.arange(121.0)


@dataclass(frozen=True, eq=False)
class CompensateResult:
    """What :func:`compensate` wrote.

    Attributes
    ----------
    out : pathlib.Path
        The output (Zarr store or ``.npz``).
    chain : str
        Chain key (:mod:`raysim.vocabulary`).
    frames : list of int
        Frame numbers within the source of the compensated frames.
    beams : list of compensation.BeamCube
        One per frame, ``data [chirp, range, azimuth, elevation]``.
    warnings : tuple of str
        Assumption warnings of all frames, each once, in order.
    calibration : dict or None
        Self-calibration report (estimates with one-sigma uncertainties, SI
        units) when the clock offset or the velocity was estimated.
    time_offset : float or None
        IMU clock minus radar clock applied [s] (given, or estimated);
        None for the chain ``none``.
    imu_source : str or None
        The IMU source read: file, topic or message, instance, rate and time
        base (:func:`raysim.io.flight_logs.read_imu_log`); None for ``none``.
    notes : tuple of str
        What the run chose or cleaned for the user (the default range window,
        debris of an interrupted writer removed).
    autofocus : list of dict or None
        Per frame, :meth:`compensation.autofocus.Autofocus.report` (rms phase
        [rad], sigma [rad], band [Hz], cells), or with ``"displacement"``
        :meth:`compensation.autofocus_displacement.DisplacementFocus.report`;
        None without ``autofocus``.
    """

    out: Path
    chain: str
    frames: list
    beams: list
    warnings: tuple
    calibration: dict | None
    time_offset: float | None
    imu_source: str | None = None
    notes: tuple = ()
    autofocus: list | None = None

    @property
    def shape(self) -> tuple:
        """``(frame, chirp, range, azimuth, elevation)`` of the beams."""
        return (len(self.beams),) + tuple(self.beams[0].data.shape)


def _vector(value, n: int, option: str) -> np.ndarray:
    """``n`` finite floats, or a ValueError naming ``option`` and the value."""
    try:
        v = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        v = np.zeros(0)
    if v.size != n or not np.all(np.isfinite(v)):
        raise ValueError(f"{option}: got {value!r}, expected {n} finite numbers")
    return v


def _angles(value, option: str) -> np.ndarray:
    """A non-empty grid of finite angles [deg] -> [rad], shape ``[angle]``."""
    try:
        v = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        v = np.zeros(0)
    if v.size < 1 or not np.all(np.isfinite(v)):
        raise ValueError(f"{option}: got {value!r}, expected one or more finite angles [deg]")
    return np.deg2rad(v)


def _frames_text(frames) -> str | None:
    """``frames`` as ``"LO:HI"`` / ``"K"`` text: given so, or an int ``K``, or ``(LO, HI)``."""
    if frames is None or isinstance(frames, str):
        return frames
    if isinstance(frames, (int, np.integer)) and not isinstance(frames, bool):
        return str(int(frames))
    if (isinstance(frames, (tuple, list)) and len(frames) == 2
            and all(isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                    for v in frames)):
        return f"{int(frames[0])}:{int(frames[1])}"
    raise ValueError(f"--frames: got {frames!r}, expected 'LO:HI', 'K', an int K or a pair "
                     f"(LO, HI) of frame numbers")


def _attitude(value):
    """``initial_attitude_deg``: ``"level"`` or (yaw, pitch, roll) [deg] -> ``R_WB`` [3, 3]
    (None: the nominal hover attitude, identity)."""
    from scipy.spatial.transform import Rotation

    if value is None:
        return np.eye(3)
    if isinstance(value, str):
        if value.strip() != "level":
            raise ValueError(f"--initial-attitude-deg: got {value!r}, expected YAW,PITCH,ROLL "
                             f"[deg] or 'level'")
        return "level"
    ypr = np.deg2rad(_vector(value, 3, "--initial-attitude-deg"))
    return Rotation.from_euler("ZYX", ypr).as_matrix()


def _motions(inp, imu: np.ndarray, rcs: list, *, r_axis, gates, lever_arm, time_offset,
             velocity, initial_velocity, initial_attitude_deg, imu_grade, attitude_track=None,
             mounting_deg=None, ground_doppler: bool = False, imu_interval: float = 0.0,
             azimuth=None, offset_search=None):
    """Per-frame motions, the self-calibration report (or None) and the offset applied [s].

    ``rcs`` receives the range-compressed frames when they are computed for the
    self-calibration (the projection then reuses them). The motions are the body's
    (W); a mounted radar's (``mounting_deg``) scatterers and ground are found in its
    nominal frame and turned into W for the estimates.
    """
    options = dict(lever_arm=lever_arm, initial_attitude=_attitude(initial_attitude_deg),
                   imu_grade=imu_grade, velocity="hover" if velocity == "radar" else velocity)
    if velocity == "given":
        if initial_velocity is None:
            raise ValueError("--velocity given needs --initial-velocity VN,VE,VD")
        options["initial_velocity"] = _vector(initial_velocity, 3, "--initial-velocity")
    from raysim.platform.mounting import is_default_mounting, mounting_matrix

    auto = isinstance(time_offset, str)
    time_t = [inp.slot_times[k].ravel() for k in range(len(inp.frames))]
    if not (auto or velocity == "radar"):
        # one integration over every slot of every selected frame, chirp major, slot minor
        motions = estimate_record(imu[:, 0], imu[:, 1:4], imu[:, 4:7], time_t,
                                  time_offset=time_offset, **options)
        return motions, None, float(time_offset)
    # Every selected frame takes part (the gyro bias, a drift over frames, needs two or
    # more); stationary scatterers are detected on the selected range cells of frame 0.
    estimate = (("time_offset",) if auto else ()) + (("velocity",) if velocity == "radar" else ())
    if len(inp.frames) > 1:
        estimate += ("gyro_bias",)
    rcs.extend(range_compress(np.asarray(inp.read(k)))[..., : r_axis.size]
               for k in range(len(inp.frames)))
    given = initial_attitude_deg is not None
    ground = ground_tilt_of_record(inp, imu, rcs, time_t, r_axis, gates, 0.0 if auto
                                   else time_offset, options, warn=False,
                                   mounting=mounting_deg) if velocity == "radar" else None
    tilt_cov = retilt = None
    if ground is not None and not given and ground.usable:   # roll and pitch from the ground
        from scipy.spatial.transform import Rotation

        retilt = ground_retilt(ground, options)    # again at the clock and gyro bias found
        options["initial_attitude"] = (Rotation.from_rotvec([*ground.tilt, 0.0]).as_matrix()
                                       @ options["initial_attitude"])
        tilt_cov, given = ground.tilt_covariance, True
    if inp.num_slots > 1:
        options["channel_slot"] = inp.tx_slot
    mount = None if is_default_mounting(mounting_deg) else mounting_matrix(mounting_deg)
    from compensation.calibration import DETECT_AXIS

    # scatterers searched over the boards' +-60 deg, and as far as the beams asked for
    wide = DETECT_AXIS
    if azimuth is not None and (np.min(azimuth) < wide[0] or np.max(azimuth) > wide[-1]):
        wide = np.arange(min(wide[0], np.min(azimuth)), max(wide[-1], np.max(azimuth)) + 1e-9,
                         wide[1] - wide[0])
    cal = calibrate_record(rcs, time_t, inp.element_positions, imu[:, 0], imu[:, 1:4],
                           imu[:, 4:7], wavelength=inp.config.center_wavelength,
                           range_axis=r_axis, estimate=estimate,
                           time_offset=0.0 if auto else time_offset,
                           grid_shape=inp.grid_shape, detect_gates=gates,
                           detect_grid=(wide, DETECT_AXIS),
                           attitude_given=given, tilt_covariance=tilt_cov,
                           attitude_track=attitude_track, ground=retilt, imu_interval=imu_interval,
                           ground_doppler=ground_doppler, mounting=mount, **options,
                           **({} if offset_search is None else {"offset_search": offset_search}))
    report = cal.report
    if auto:
        from compensation.calibration import OFFSET_SEARCH_HALF_WIDTH

        report["time_offset_search_s"] = float(offset_search or OFFSET_SEARCH_HALF_WIDTH)
    from compensation.azimuth_shift import calibration_azimuth_check

    report["warnings"] = [*report.get("warnings", ()), *calibration_azimuth_check(   # warned
        cal.result, rcs, inp.element_positions, [t[:, inp.tx_slot] for t in inp.slot_times],
        wavelength=inp.config.center_wavelength, range_axis=r_axis, grid_shape=inp.grid_shape,
        channel_slot=options.get("channel_slot"), mounting=mount)]
    if ground is not None:   # without an attitude its failures, with one a disagreement
        from compensation.ground_plane import GroundPlaneWarning, ground_check

        ground = ground if retilt is None else retilt.fit
        report["ground_plane"] = {**ground.report(), "role": (
            GROUND_ROLE if tilt_cov is not None else "check of the given attitude"
            if initial_attitude_deg is not None else "not used")}
        found = ground_check(ground) if initial_attitude_deg is not None else ground.warnings
        for text in found:
            warnings.warn(text, GroundPlaneWarning, stacklevel=3)
        report["warnings"] = [*report.get("warnings", ()), *found]
    return list(cal.result.motions), report, float(report["time_offset_s"] if auto
                                                   else time_offset)


#: Warnings of the IMU-driven chain that say it leaves motion in the data, by their
#: prefix, and what each means (``autofocus="auto"`` then removes it).
AUTOFOCUS_CAUSES = {"imu rate:": "the log does not resolve the vibration",
                    "azimuth:": "the stationary scatterers keep a Doppler the estimated "
                                "velocity does not remove"}


def _autofocus_needed(motions, calibration, notes: list) -> str | bool:
    """``"displacement"`` where the chain's warnings name motion left in the data (a note
    says why), else False."""
    said = [w for m in motions or () for w in m.warnings]
    said += list((calibration or {}).get("warnings", ()))
    causes = [why for prefix, why in AUTOFOCUS_CAUSES.items()
              if any(w.startswith(prefix) for w in said)]
    if not causes:
        return False
    notes.append(f"autofocus: displacement applied ({'; '.join(causes)}: the warnings "
                 f"below); --autofocus off keeps the IMU-driven chain alone")
    return "displacement"


def _size_job(inp, out: Path, range_m, beams: int, calibrating: bool, notes: list
              ) -> tuple[np.ndarray, np.ndarray]:
    """The range axis ``[cell]`` [m] and the cells compensated, the job sized as a whole.

    ``range_m`` None chooses the window
    (:func:`raysim.pipeline.compensate_size.choose_range_window`, its note
    appended to ``notes``); the job is then refused when it does not fit the
    memory or the disk available, before anything large is allocated.
    """
    from raysim.pipeline.compensate_size import check_job, choose_range_window, job_bytes

    cfg = inp.config
    chirps, channels, n_samples = (int(n) for n in inp.read(0).shape)
    r_axis = cfg.bin_ranges(n_samples if cfg.complex_sampling else n_samples // 2)
    n_frames = len(inp.frames)

    def size(cells: int) -> int:
        return job_bytes(n_frames, chirps, channels, n_samples, cells, beams,
                         calibrating=calibrating)

    if range_m is None:
        gates, note = choose_range_window(r_axis, lambda: inp.read(0), size=size)
        if note:
            notes.append(note)
    else:
        r_lo, r_hi = _vector(range_m, 2, "--range-m")
        gates = np.flatnonzero((r_axis >= r_lo) & (r_axis <= r_hi))
        if gates.size == 0:
            raise ValueError(f"--range-m {r_lo:g}:{r_hi:g} selects no range cell; cells span "
                             f"0 .. {r_axis[-1]:.2f} m")
    shape = [n_frames, chirps, int(gates.size), beams]
    check_job(size(gates.size), out, output_bytes(n_frames, chirps, gates.size, beams),
              f"beams {shape} [frame, chirp, range, beam]")
    return r_axis, gates


def compensate(source, imu=None, *, out, chain="exact", frames=None,
               frame: int | None = None, radar_config=None, layout: str | None = None,
               capture_t0: float = 0.0, range_m=None, azimuth_deg=None,
               elevation_deg=None, lever_arm=None, time_offset: float | str = 0.0,
               velocity: str = "hover", initial_velocity=None,
               initial_attitude_deg=None, imu_grade: str | None = None,
               direction_deg=None, max_gap: float | None = None, imu_topic: str | None = None,
               imu_instance: int | None = None, board: str | None = None,
               antenna_positions=None, mounting_deg=None, progress: bool = False,
               autofocus: bool | str = False, ground_doppler: bool = False,
               time_offset_search: float | None = None,
               drop_incomplete: bool = False) -> CompensateResult:
    """Motion-compensate a stored IF cube or a raw capture with an IMU log and write the beams.

    Parameters
    ----------
    source : str or path-like
        Zarr store, NetCDF ``.nc``, ``.npz`` cube, or DCA1000 capture (``.bin``,
        or any file with ``radar_config``); formats in the module docstring.
    imu : str, path-like or ndarray ``[sample, 7]``, optional
        IMU log (file, or table of time [s, IMU clock], gyro [rad/s], accel
        [m/s^2], FRD); default the IMU log of the frame store. Not used by the
        chain ``none``.
    out : str or path-like
        Output: a Zarr store (a new path, or an earlier compensated store to
        replace), or for one frame a path ending in ``.npz``. Checked before
        any computation.
    chain : str or raysim.vocabulary.ChainSpec
        ``exact`` (rigid-body projection), ``paper``, ``paper:published``,
        ``dpca`` (displaced phase centre: one sub-aperture size for every frame,
        the smallest any frame's motion leaves, its price the first entry of
        the warnings) or ``none`` (conventional beamformer).
    frames : str, int or (int, int), optional
        ``"LO:HI"`` or ``(LO, HI)`` (HI excluded), or ``"K"`` / ``K``: frames of
        a capture or store (default every frame of a capture, ``frame`` of a
        store).
    frame : int, optional
        Frame of a store (None: the first, or ``frames``).
    radar_config : str or path-like, optional
        mmWave SDK ``.cfg`` or Studio ``.json`` of a capture.
    layout : {"2lane", "4lane"}, optional
        LVDS lanes of a capture (default from the configuration).
    drop_incomplete : bool
        Read the whole frames of a capture that ends inside a frame (stopped by
        hand), the rest dropped with a warning; default refused.
    capture_t0 : float
        Radar-clock time of the first ramp of a capture [s].
    range_m : (float, float), optional
        Range cells ``lo <= r <= hi`` to compensate [m]; default every cell
        when the job fits :data:`raysim.pipeline.compensate_size.AUTO_BUDGET_BYTES`,
        else the cells around the strongest return that fit (said in the
        result's ``notes``).
    azimuth_deg, elevation_deg : array_like, optional
        Beam grid axes [deg]; default -60..60 in 1 deg steps.
    lever_arm : array_like, shape ``[3]``, optional
        ``r_IR`` in B [m]; default the input's, else zero.
    time_offset : float or "auto"
        IMU clock minus radar clock [s]; ``"auto"`` estimates it from the radar
        (residual slow-time phase of stationary scatterers against the IMU).
    time_offset_search : float, optional
        Half-width [s] of the ``"auto"`` search about 0 (default
        :data:`compensation.calibration.OFFSET_SEARCH_HALF_WIDTH`, 10 ms): an
        offset beyond it is not found. Its cost grows with it (0.5 ms steps).
    velocity : {"hover", "given", "radar"}
        Initial velocity: zero mean over the hover window, ``initial_velocity``,
        or estimated from the Doppler of stationary scatterers (per frame).
    initial_velocity : array_like, shape ``[3]``, optional
        Body velocity in W at the first chirp [m/s] (``velocity="given"``).
    initial_attitude_deg : (float, float, float) or "level", optional
        Attitude at the first chirp, Z-Y-X Euler angles (yaw, pitch, roll)
        [deg], or ``"level"`` (roll and pitch from accelerometer levelling,
        heading 0); default the IMU log's attitude at the first ramp on its
        clock (:mod:`raysim.io.flight_logs.attitude`; the offset ``"auto"``
        takes 0), else level (0, 0, 0), which is no estimate:
        ``velocity="radar"`` then measures roll and pitch from the ground clutter
        in the cells beyond ``range_m`` (:mod:`compensation.ground_plane`, level
        flat ground assumed; the calibration report's ``ground_plane``), else
        keeps the tilt at its prior and warns that it is unobservable; a note
        says which. With ``velocity="radar"`` the log's attitude is also a
        measurement of roll and pitch at every frame, and the ground plane a
        check of it (a warning when they disagree).
    imu_grade : {"ideal", "tactical", "consumer_mems"}, optional
        Sets the hover window of ``velocity`` hover / radar and of ``"level"``,
        and the IMU figures (noise, bias spreads) of ``velocity="radar"``;
        default the whole record and consumer-MEMS figures.
    direction_deg : (float, float), optional
        Target direction (azimuth, elevation) [deg] of the paper chain's
        slow-time correction (required by ``paper``).
    max_gap : float, optional
        Largest gap of the IMU log [s] inside the window used (the selected
        chirps on the IMU clock plus a margin) that is filled by linear
        interpolation, with a warning; default
        :data:`compensation.ingestion.DEFAULT_MAX_GAP`. Gaps outside the window
        are not judged (:func:`compensation.ingestion.judge_imu_window`).
    imu_topic : str, optional
        Source inside the IMU log: a PX4 topic (``sensor_gyro_fifo``,
        ``vehicle_imu``, ``sensor_combined``), an ArduPilot message (``IMU``,
        ``GYR``, ``ISBD``) or a ROS topic; default the best present.
    imu_instance : int, optional
        Instance of that source (PX4 multi-id, ArduPilot ``I``); default the
        best present.
    board : str, optional
        TI board of a capture (:data:`raysim.io.mmwave_config.BOARDS`); needed
        when the configuration fits boards with different antenna layouts.
    antenna_positions : str or path-like, optional
        CSV / JSON file of the TX and RX positions of a capture
        (:func:`raysim.io.mmwave_config.read_antenna_positions`); replaces
        ``board``.
    mounting_deg : str or (float, float, float), optional
        Radar mounting ``R_BA``: (yaw, pitch, roll) [deg] or a name of
        :data:`raysim.platform.mounting.MOUNTING_PRESETS`; default ``down``
        (A parallel to B), or the mounting a rendered store was simulated
        with. Other mountings give beams in the nominal radar
        frame (:func:`raysim.platform.mounting.mount_motion`); the self-calibration
        (``velocity="radar"``, ``time_offset="auto"``) finds the scatterers and the
        ground there and turns their directions into the body's frame by ``R_BA``
        (:mod:`compensation.mounting`).
    progress : bool
        A progress bar on stderr for records of several frames.
    autofocus : bool or {"phase", "stationary", "displacement", "auto"}
        ``"auto"`` (``raysim compensate``'s default): ``"displacement"`` where the
        IMU-driven chain states that it leaves motion in the data (an ``imu rate:``
        warning: the log does not resolve the vibration; an ``azimuth:`` warning: the
        stationary scatterers keep a Doppler the estimated velocity does not remove),
        with a note, else none. Otherwise: after the chain, estimate and remove the
        residual per-chirp phase
        common to the stationary scatterers (:func:`compensation.autofocus.autofocus_beams`):
        ``True`` or ``"phase"`` leaves the linear phase (Doppler) as it is,
        ``"stationary"`` also removes the common Doppler of those scatterers (a
        platform velocity error along the line of sight), ``"displacement"``
        estimates the residual displacement vector per chirp and corrects every
        beam at its own direction (:mod:`compensation.autofocus_displacement`).
        Not with the chain ``none``.
    ground_doppler : bool
        With ``velocity="radar"``, the ground clutter beyond the compensated cells also
        measures the velocity by its Doppler, assumed at rest (:mod:`compensation.ground_doppler`).

    Returns
    -------
    CompensateResult

    Raises
    ------
    ValueError
        Bad input, named: the output path (one of the inputs, a file or folder
        raysim did not write, or written by another process now), missing
        files, frame selections, radar configurations, option values, an IMU
        log that does not cover the chirps, a job larger than the memory or
        disk available (the size and the settings to reduce).
    """
    spec = parse_chain(chain)
    if autofocus not in (False, None, True, "phase", "stationary", "displacement", "auto"):
        raise ValueError(f"--autofocus: got {autofocus!r}, expected 'phase', 'stationary', "
                         f"'displacement' or 'auto'")
    if autofocus == "auto" and not spec.compensated:
        autofocus = False
    if autofocus and not spec.compensated:
        raise ValueError(f"--autofocus: follows the IMU-driven chain; the chain {spec.key!r} "
                         f"compensates nothing")
    if velocity not in VELOCITY_CHOICES:
        raise ValueError(f"--velocity: got {velocity!r}, expected one of {VELOCITY_CHOICES}")
    if isinstance(time_offset, str):
        if time_offset != "auto":
            raise ValueError(f"--time-offset: got {time_offset!r}, expected a number of "
                             f"seconds or 'auto'")
    else:
        time_offset = float(_vector(time_offset, 1, "--time-offset")[0])
    if time_offset_search is not None:
        time_offset_search = float(_vector(time_offset_search, 1, "--time-offset-search")[0])
        if not isinstance(time_offset, str):
            raise ValueError(f"--time-offset-search: the half-width of the --time-offset auto "
                             f"search; --time-offset is {time_offset!r}")
        if time_offset_search <= 0:
            raise ValueError(f"--time-offset-search: got {time_offset_search!r}, expected a "
                             f"positive half-width [s] of the --time-offset auto search")
    from raysim.platform.mounting import is_default_mounting, mount_motion
    from raysim.platform.mounting import mounting_deg as ypr

    mounted = not is_default_mounting(mounting_deg)     # a bad mounting named here
    out = Path(out)
    as_npz = check_compensated_output(out, "--out", inputs=[("CUBE", source), ("--imu", imu),
                                                            ("--radar-config", radar_config)])
    with writer_lock(out):
        removed = remove_debris(out)
        notes = [f"removed {len(removed)} leftover file(s) of an interrupted writer of "
                 f"{str(out)!r}"] if removed else []
        source = os.fspath(source)
        inp = load_input(source, radar_config=None if radar_config is None
                         else os.fspath(radar_config), frames=_frames_text(frames), frame=frame,
                         layout=layout, capture_t0=capture_t0, board=board,
                         antenna_positions=antenna_positions, drop_incomplete=drop_incomplete)
        if inp.source.get("dropped_bytes"):
            notes.append(f"capture {source!r} ends inside a frame: its last "
                         f"{inp.source['dropped_bytes']} bytes are dropped (--drop-incomplete)")
        if mounting_deg is None and inp.mounting_deg is not None:   # a store's own
            mounting_deg = inp.mounting_deg
            mounted = not is_default_mounting(mounting_deg)
        if as_npz and len(inp.frames) != 1:
            raise ValueError(f"--out {str(out)!r}: an .npz holds one frame, the selection has "
                             f"{len(inp.frames)}; give a store path (no .npz) or --frames K")
        cfg = inp.config
        u = None
        if spec.name == "paper":
            from compensation.geometry import direction

            if direction_deg is None:
                raise ValueError(f"--chain {spec.key} needs --direction-deg AZ,EL (target)")
            u = direction(*np.deg2rad(_vector(direction_deg, 2, "--direction-deg")))
        az = _angles(DEFAULT_ANGLES_DEG if azimuth_deg is None else azimuth_deg, "--az-deg")
        el = _angles(DEFAULT_ANGLES_DEG if elevation_deg is None else elevation_deg, "--el-deg")
        calibrating = spec.compensated and (velocity == "radar" or time_offset == "auto")
        r_axis, gates = _size_job(inp, out, range_m, az.size * el.size, calibrating, notes)
        motions = calibration = offset = imu_source = None
        rcs: list = []                     # range-compressed frames, kept when calibrating
        window_notes: tuple = ()
        if spec.compensated:
            table, imu_source, interval = imu_table(imu, inp, source, imu_topic, imu_instance)
            table, window_notes, segments = imu_window(table, inp, time_offset, max_gap)
            if window_notes:
                from compensation.guards import CompensationWarning

                for text in window_notes:
                    warnings.warn(text, CompensationWarning, stacklevel=2)
            lever = (_vector(lever_arm, 3, "--lever-arm") if lever_arm is not None
                     else inp.lever_arm if inp.lever_arm is not None else np.zeros(3))
            def attitude_of(sub, first: bool, clock):    # a later run's: the log's at its start
                return log_attitude(initial_attitude_deg if first else None, imu, sub,
                                    time_offset if clock is None else clock, imu_topic,
                                    notes if first else [])

            def estimate(sub, sub_rcs, attitude, track, clock):
                return _motions(
                    sub, table, sub_rcs, r_axis=r_axis, gates=gates, lever_arm=lever,
                    time_offset=time_offset if clock is None else clock, velocity=velocity,
                    initial_velocity=initial_velocity,
                    initial_attitude_deg=attitude, imu_grade=imu_grade, attitude_track=track,
                    mounting_deg=mounting_deg, ground_doppler=ground_doppler,
                    imu_interval=interval, azimuth=az, offset_search=time_offset_search)
            # where filled gaps cross the frames, each run between them is its own record
            motions, calibration, offset = motions_by_segment(
                inp, segments if calibrating else [], estimate, attitude_of, table, rcs, notes)
            if mounted:          # beams in the nominal radar frame
                motions = [mount_motion(m, mounting_deg) for m in motions]
        if autofocus == "auto":
            autofocus = _autofocus_needed(motions, calibration, notes)
        doppler = "stationary" if autofocus in ("stationary", "displacement") else "keep"
        results, found, focus = [], list(window_notes), [] if autofocus else None
        if motions is not None:       # what the grid leaves a scatterer between its beams
            miss = grid_miss_warning(az, el, [np.mean(m.radar_velocity, axis=0)
                                              for m in motions], cfg.velocity_resolution)
            found.extend([miss] if miss else [])
        array: dict = {}
        if calibration is not None:   # what the scene leaves unconstrained (also warned)
            found.extend(w for w in calibration.get("warnings", ()) if w not in found)
        sub = None
        if spec.name == "dpca":        # one sub-aperture size for every frame: comparable maps
            from raysim.pipeline.beams import common_subaperture

            sub, price = common_subaperture(
                inp.element_positions, motions, cfg.center_wavelength, grid_shape=inp.grid_shape,
                channel_slot=inp.tx_slot if inp.num_slots > 1 else None)
        ks = range(len(inp.frames))
        if len(inp.frames) > 1 and progress:
            import sys

            from tqdm import tqdm

            ks = tqdm(ks, unit="frame", desc="compensate", file=sys.stderr)
        for k in ks:
            mot = None if motions is None else motions[k]
            # TDM: every slot's channels with the pose of their own ramp
            channel_slot = inp.tx_slot if mot is not None and inp.num_slots > 1 else None
            if rcs:
                rc, cells, g0 = rcs[k], r_axis, 0
            else:      # only the cells compensated, range-compressed block by block
                g0, g1 = int(gates[0]), int(gates[-1]) + 1
                rc, cells = gated_range_compress(inp.read(k), g0, g1), r_axis[g0:g1]
            beams = project(spec, rc, inp.element_positions, wavelength=cfg.center_wavelength,
                            range_axis=cells, azimuth=az, elevation=el, motion=mot,
                            direction=u, grid_shape=inp.grid_shape, range_gates=gates - g0,
                            channel_slot=channel_slot, subaperture=sub)
            if mot is None:   # the conventional beamformer carries chirp indices, not times
                beams = replace(beams, chirp_time=inp.slot_times[k, :, 0])
            if sub is not None:   # dpca: its price travels with the beams (first warning)
                beams = replace(beams, warnings=(price, *beams.warnings))
            if focus is not None:   # vibration the IMU log cannot see, from the beams
                from compensation import autofocus_displacement, sidelobes
                from compensation.autofocus import autofocus_beams
                from raysim.measure.point import angle_apertures

                if not array:          # the array's sidelobes and the axes it spans, once
                    p = inp.element_positions
                    array.update(sidelobe_db=sidelobes.array_margin_db(
                        p, beams.wavelength, az, el), spans=angle_apertures(p, beams.wavelength))
                opts = dict(slot_times=inp.slot_times[k], doppler=doppler,
                            sidelobe_db=array["sidelobe_db"])
                moving = {} if mot is None else {   # the grid's miss of each cell, its Doppler
                    "radar_velocity": np.mean(mot.radar_velocity, axis=0)}
                beams, est = (autofocus_displacement.autofocus_displacement(
                    beams, **opts, array_spans=array["spans"], **moving)
                    if autofocus == "displacement" else autofocus_beams(beams, **opts))
                focus.append(est.report())
            found.extend(w for w in beams.warnings if w not in found)
            results.append(beams)
        if as_npz:
            report = calibration if focus is None else {**(calibration or {}),
                                                        "autofocus": focus[0]}
            write_compensated_npz(os.fspath(out), results[0], spec.key, np.rad2deg(az),
                                  np.rad2deg(el), report)
        else:
            import json

            attrs = {"velocity": velocity}
            if imu_source is not None:
                attrs["imu_source"] = imu_source
            if calibration is not None:
                attrs["self_calibration"] = json.dumps(calibration)
            if offset is not None:     # the offset applied: given, or estimated ('auto')
                attrs["time_offset_s"] = offset
            if mounted:
                attrs["mounting_deg"] = list(ypr(mounting_deg))
            if focus is not None:
                attrs["autofocus"] = json.dumps(focus)
            write_compensated_store(os.fspath(out), inp, results, chain=spec.key,
                                    warnings=found, azimuth_deg=np.rad2deg(az),
                                    elevation_deg=np.rad2deg(el), extra_attrs=attrs)
        return CompensateResult(out, spec.key, list(inp.frames), results, tuple(found),
                                calibration, offset, imu_source, tuple(notes), focus)
