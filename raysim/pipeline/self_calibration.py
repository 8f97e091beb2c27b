"""Self-calibration stage: frames + IMU log -> corrected motion and a report of the estimates.

The unknowns an IMU cannot give (the platform velocity, the IMU-radar clock
offset, the gyro bias) are estimated from the radar frames themselves by
:func:`compensation.calibration.self_calibrate`; this module feeds it the
frames of a run (:func:`calibrate_frames`: range compression, array geometry,
TDM slot times) or of a stored record (:func:`calibrate_record`: range-compressed
frames and their slot times, as the compensate stage reads them) and turns the
result into the motion the chains use and a report with units.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from raysim.platform.kinematics import slot_times
from raysim.processing.maps import range_compress
from raysim.synthesis.frame import RadarFrame

__all__ = ["SelfCalibration", "calibrate_frames", "calibrate_record", "imu_errors"]


def imu_errors(grade: str):
    """The radar-inertial estimator's IMU figures of an IMU preset.

    Parameters
    ----------
    grade : str
        Preset name of :mod:`raysim.platform.imu_spec` (``ideal``, ``tactical``,
        ``consumer_mems``).

    Returns
    -------
    compensation.radar_inertial.ImuErrors
        Noise densities as given; each bias spread the root sum of squares of
        the turn-on bias, the bias instability and, for the accelerometer, the
        scale-factor and misalignment errors on gravity (constant biases of a
        hovering platform: 1 % of g is 10 mg); the scale spread the larger of the
        scale-factor and misalignment spreads.
    """
    from compensation.radar_inertial import ImuErrors
    from raysim.platform.imu_spec import STANDARD_GRAVITY, get_preset

    spec = get_preset(grade)
    a, g = spec.accel, spec.gyro
    return ImuErrors(a.noise_density, g.noise_density,
                     float(np.hypot.reduce([a.bias_sigma, a.bias_instability,
                                            a.scale_factor_sigma * STANDARD_GRAVITY,
                                            a.misalignment_sigma * STANDARD_GRAVITY])),
                     float(np.hypot(g.bias_sigma, g.bias_instability)),
                     max(a.scale_factor_sigma, a.misalignment_sigma))


@dataclass(frozen=True)
class SelfCalibration:
    """Corrected motion of a run and the estimates.

    Attributes
    ----------
    motion : compensation.PlatformMotion
        Pose at every chirp (every TDM slot, chirp major) of all frames, in
        order, as :func:`raysim.pipeline.estimate.estimate_motion` returns it.
    result : compensation.calibration.CalibrationResult
        Per-frame motions and estimator outputs.
    report : dict
        Estimates with one-sigma uncertainties (SI units, keys with units).
    """

    motion: object
    result: object
    report: dict


def _slot_times(frame: RadarFrame) -> np.ndarray:
    """Transmit time of every slot of every chirp of a frame, chirp major [s]."""
    return slot_times(frame.chirp_times, frame.array.num_slots,
                      frame.config.slot_interval).ravel()


def calibrate_record(rcs: Sequence, frame_times: Sequence, element_positions, imu_time,
                     gyro, accel, *, wavelength: float, range_axis, time_offset: float = 0.0,
                     estimate=None, trajectory=None, attitude_given: bool | None = None,
                     ground_doppler: bool = False, **options) -> SelfCalibration:
    """Estimate velocity, clock offset and gyro bias of a record of range-compressed frames.

    Parameters
    ----------
    rcs : sequence of ndarray, each shape ``[chirp, channel, range]``
        Range-compressed frames, in time order.
    frame_times : sequence of array_like, each shape ``[chirp * slot]``
        Start time of every chirp (TDM: every transmit slot's ramp, chirp major)
        of each frame [s, radar clock], uniform within a frame.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m].
    imu_time : array_like, shape ``[sample]``
        IMU time stamps [s, IMU clock].
    gyro, accel : array_like, shape ``[sample, 3]``
        Angular rate [rad/s] and specific force [m/s^2] in B.
    wavelength : float
        Mid-chirp wavelength [m].
    range_axis : array_like, shape ``[range]``
        Range of every bin of ``rcs`` [m].
    time_offset : float
        First guess of IMU clock minus radar clock [s].
    estimate : sequence of str, optional
        Subset of :data:`compensation.calibration.ESTIMATES` (default all;
        the gyro bias needs two frames or more).
    trajectory : raysim.platform.motion.Trajectory, optional
        Truth of a simulation: the initial attitude and position at the first
        time come from it unless ``options`` give them. The velocity never does.
    attitude_given : bool, optional
        Whether the initial attitude is an estimate rather than the nominal
        hover attitude; default: a trajectory or ``initial_attitude`` is given.
        Without it the tilt stays at the prior, with a warning.
    ground_doppler : bool
        The ground clutter in the bins beyond the last of ``detect_gates`` joins the
        velocity's Doppler measurements, assumed at rest (``ground_gates`` of
        :func:`compensation.calibration.self_calibrate`).
    **options
        For :func:`compensation.calibration.self_calibrate` (``lever_arm``,
        ``channel_slot``, ``grid_shape``, ``detect_gates``, ``mounting`` (``R_BA``
        of a mounted radar), ``velocity``,
        ``initial_attitude``, ``imu_grade``, ``hover_window`` ...); ``imu_grade``
        also gives the radar-inertial estimate its IMU figures
        (:func:`imu_errors`) unless ``imu_errors`` is given.

    Returns
    -------
    SelfCalibration
    """
    from compensation import PlatformMotion
    from compensation.calibration import ESTIMATES, self_calibrate
    from compensation.guards import CompensationWarning

    if len(rcs) < 1 or len(rcs) != len(frame_times):
        raise ValueError(f"rcs holds {len(rcs)} frames and frame_times {len(frame_times)}; "
                         f"expected the same number, at least one")
    times = [np.asarray(t, dtype=float).ravel() for t in frame_times]
    t0 = float(times[0][0])
    if trajectory is not None:
        options.setdefault("initial_attitude", trajectory.attitude([t0]).as_matrix()[0])
        options.setdefault("initial_position", trajectory.position([t0])[0])
    options.setdefault("velocity", "hover")
    if attitude_given is None:
        attitude_given = trajectory is not None or options.get("initial_attitude") is not None
    if options.get("imu_grade") is not None and options.get("imu_errors") is None:
        options["imu_errors"] = imu_errors(options["imu_grade"])
    if ground_doppler:
        if options.get("detect_gates") is None:
            raise ValueError("ground_doppler: needs detect_gates, the compensated bins the "
                             "ground lies beyond")
        options["ground_gates"] = np.arange(int(np.max(options["detect_gates"])) + 1,
                                            len(range_axis))
    if estimate is None:
        estimate = ESTIMATES if len(rcs) > 1 else tuple(e for e in ESTIMATES
                                                        if e != "gyro_bias")
    with warnings.catch_warnings(record=True) as caught:   # kept for the report, shown below
        warnings.simplefilter("always")
        res = self_calibrate(list(rcs), times, element_positions, imu_time, gyro, accel,
                             wavelength=wavelength, range_axis=range_axis,
                             estimate=tuple(estimate), time_offset=time_offset,
                             reference_time=t0, attitude_given=bool(attitude_given), **options)
    shown: dict = {}
    for w in caught:
        shown.setdefault((w.category, str(w.message)), w)
    for w in shown.values():
        warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    ms = res.motions
    motion = PlatformMotion(np.concatenate([m.time for m in ms]),
                            np.concatenate([m.attitude for m in ms]),
                            np.concatenate([m.position for m in ms]),
                            np.concatenate([m.velocity for m in ms]),
                            np.concatenate([m.angular_rate for m in ms]), ms[0].lever_arm,
                            ms[0].warnings)
    report = res.report()
    # the fits' own warnings (the clock's per-chirp fallback or ambiguity) join the report
    report["warnings"] = list(dict.fromkeys([*report.get("warnings", ()), *(
        text for cat, text in shown if issubclass(cat, CompensationWarning))]))
    if ground_doppler and "velocity" in estimate and not any(
            "ground scatterers" in n for n in report["notes"]):
        report["notes"].append("velocity: Doppler of 0 ground scatterers (no dense ground point "
                               "beyond the compensated cells fitted well enough)")
    return SelfCalibration(motion, res, report)


def calibrate_frames(frames: Sequence[RadarFrame], imu_time, gyro, accel, *,
                     time_offset: float = 0.0, estimate=None, trajectory=None,
                     **options) -> SelfCalibration:
    """Estimate velocity, clock offset and gyro bias from frames and an IMU log.

    :func:`calibrate_record` of the frames' range-compressed cubes and TDM
    slot times.

    Parameters
    ----------
    frames : sequence of RadarFrame
        The record, in time order (one geometry).
    imu_time : array_like, shape ``[sample]``
        IMU time stamps [s, IMU clock].
    gyro, accel : array_like, shape ``[sample, 3]``
        Angular rate [rad/s] and specific force [m/s^2] in B.
    time_offset : float
        First guess of IMU clock minus radar clock [s].
    estimate : sequence of str, optional
        Subset of :data:`compensation.calibration.ESTIMATES` (default all;
        the gyro bias needs two frames or more).
    trajectory : raysim.platform.motion.Trajectory, optional
        Truth of a simulation: the initial attitude and position at the first
        chirp come from it (an aligned navigation solution), as in
        :func:`raysim.pipeline.estimate.estimate_motion`. The velocity never
        does.
    **options
        For :func:`compensation.calibration.self_calibrate` (``scatterers``,
        ``iterations``, ``drift``, ``offset_search``, ``imu_grade``,
        ``hover_window``, ``initial_attitude`` ...).

    Returns
    -------
    SelfCalibration
    """
    if len(frames) < 1:
        raise ValueError("frames must hold at least one frame")
    first = frames[0]
    cfg, arr = first.config, first.array
    options.setdefault("lever_arm", np.asarray(first.lever_arm, dtype=float))
    if arr.num_slots > 1:
        options.setdefault("channel_slot", arr.tx_slot)
    if arr.grid_shape is not None and arr.num_slots == 1:
        options.setdefault("grid_shape", arr.grid_shape)
    rcs = [range_compress(np.asarray(fr.data)) for fr in frames]
    return calibrate_record(rcs, [_slot_times(fr) for fr in frames], arr.virtual_positions,
                            imu_time, gyro, accel, wavelength=cfg.center_wavelength,
                            range_axis=cfg.range_axis(), time_offset=time_offset,
                            estimate=estimate, trajectory=trajectory, **options)
