"""Motion estimate (stage 3 of the run path): IMU samples -> the platform pose at every chirp.

Every study and command integrates its IMU through :func:`estimate_motion`, so
the initial state and the velocity handling are defined once.
"""

from __future__ import annotations

import numpy as np

from raysim.scenario import Scenario

__all__ = ["VELOCITY_MODES", "estimate_motion", "estimate_record", "ground_retilt",
           "ground_tilt_of_record",
           "scenario_motion", "split_frames"]

#: An interval above this multiple of the median chirp interval starts a new frame.
FRAME_GAP_FACTOR = 1.5


def split_frames(chirp_times) -> list[np.ndarray]:
    """Concatenated chirp times ``[chirp]`` [s] split into frames at idle gaps.

    A run's frames follow each other with idle time (``frame_period``) between
    them; :func:`compensation.integrate_imu` wants them as separate frames, each
    uniform.
    """
    t = np.asarray(chirp_times, dtype=float).ravel()
    if t.size < 3:
        return [t]
    d = np.diff(t)
    cut = np.flatnonzero(d > FRAME_GAP_FACTOR * float(np.median(d))) + 1
    return np.split(t, cut)

#: Initial-velocity handling: ``given`` takes the truth (the flight controller's
#: state), ``hover`` assumes the velocity averages to zero over the IMU record.
VELOCITY_MODES = ("given", "hover")


def _truth_initial_state(options: dict, trajectory, t_ref: float, velocity: str) -> None:
    """Fill ``options`` with the truth state of ``trajectory`` at ``t_ref`` [s] where unset.

    The attitude and position always; the velocity with ``velocity="given"``.
    """
    if velocity == "given":
        options.setdefault("initial_velocity", trajectory.velocity([t_ref])[0])
    options.setdefault("initial_attitude", trajectory.attitude([t_ref]).as_matrix()[0])
    options.setdefault("initial_position", trajectory.position([t_ref])[0])


def estimate_motion(imu_time, gyro, accel, chirp_times, *, lever_arm, trajectory,
                    time_offset: float = 0.0, velocity: str = "given", **options):
    """Strapdown-integrate IMU samples to the platform pose at every chirp.

    The initial attitude and position at the first chirp are the truth of
    ``trajectory`` (an aligned navigation solution) unless ``options`` give
    ``initial_attitude`` / ``initial_position`` (e.g. the nominal hover pose);
    the initial velocity follows ``velocity`` (:data:`VELOCITY_MODES`).

    Parameters
    ----------
    imu_time : ndarray, shape ``[sample]``
        IMU time stamps [s, IMU clock].
    gyro, accel : ndarray, shape ``[sample, 3]``
        Angular rate [rad/s] and specific force [m/s^2] in B.
    chirp_times : ndarray, shape ``[chirp]``
        Chirp start times of all frames, in order [s, radar clock].
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    trajectory : raysim.platform.motion.Trajectory
        Truth motion (initial state).
    time_offset : float
        IMU clock reading at radar time 0 [s].
    velocity : {"given", "hover"}
    **options
        Passed to :func:`compensation.integrate_imu` (``hover_window``,
        ``initial_attitude``, ``initial_position`` ...); they override the
        truth initial state.

    Returns
    -------
    compensation.PlatformMotion
    """
    from compensation import integrate_imu

    if velocity not in VELOCITY_MODES:
        raise ValueError(f"velocity: got {velocity!r}, expected one of {list(VELOCITY_MODES)}")
    t = np.asarray(chirp_times, dtype=float).ravel()
    t_ref = float(t[0])
    frames = split_frames(t)
    _truth_initial_state(options, trajectory, t_ref, velocity)
    return integrate_imu(np.asarray(imu_time), np.asarray(gyro), np.asarray(accel), frames,
                         lever_arm=lever_arm, time_offset=time_offset, reference_time=t_ref,
                         velocity=velocity, **options)


def estimate_record(imu_time, gyro, accel, frame_times, *, lever_arm, trajectory=None,
                    time_offset: float = 0.0, velocity: str = "given", **options) -> list:
    """One strapdown integration over every frame of a record, split per frame.

    The attitude and velocity carry over from frame to frame (one integration
    from the first chirp of the record, :func:`compensation.integrate_imu`);
    the motion is split with :func:`compensation.multiframe.split_motion`.

    Parameters
    ----------
    imu_time : ndarray, shape ``[sample]``
        IMU time stamps [s, IMU clock].
    gyro, accel : ndarray, shape ``[sample, 3]``
        Angular rate [rad/s] and specific force [m/s^2] in B.
    frame_times : sequence of array_like, each shape ``[time]``
        Query times of each frame, in order [s, radar clock]: the chirp start
        times, or under TDM the start of every transmit slot's ramp (chirp
        major, slot minor). Increasing; a frame need not be uniform (TDM loops
        may have idle time between them).
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    trajectory : raysim.platform.motion.Trajectory, optional
        Truth of a simulation: the initial attitude and position (and with
        ``velocity="given"`` the velocity) at the first time come from it, as
        in :func:`estimate_motion`, unless ``options`` give them. Without it
        (recorded data) ``options`` give the initial state
        (:func:`compensation.integrate_imu` defaults: level attitude, hover
        point).
    time_offset : float
        IMU clock minus radar clock [s].
    velocity : {"given", "hover"}
        :data:`VELOCITY_MODES`; ``"given"`` without a trajectory needs
        ``initial_velocity`` in ``options``.
    **options
        Passed to :func:`compensation.integrate_imu` (``initial_attitude``,
        ``initial_velocity``, ``hover_window``, ``imu_grade`` ...).

    Returns
    -------
    list of compensation.PlatformMotion
        One per frame, ``frame_times[k].size`` poses each.
    """
    from compensation import integrate_imu
    from compensation.multiframe import split_motion

    if velocity not in VELOCITY_MODES:
        raise ValueError(f"velocity: got {velocity!r}, expected one of {list(VELOCITY_MODES)}")
    frames = [np.asarray(f, dtype=float).ravel() for f in frame_times]
    if not frames or any(f.size < 1 for f in frames):
        raise ValueError(f"frame_times must hold one or more frames of at least one time, "
                         f"got sizes {[f.size for f in frames]}")
    t = np.concatenate(frames)
    t_ref = float(t[0])
    if trajectory is not None:
        _truth_initial_state(options, trajectory, t_ref, velocity)
    # query times: one integration over the record (the frames are increasing, any spacing)
    motion = integrate_imu(np.asarray(imu_time), np.asarray(gyro), np.asarray(accel), t,
                           lever_arm=lever_arm, time_offset=time_offset, reference_time=t_ref,
                           velocity=velocity, **options)
    return split_motion(motion, [f.size for f in frames])


def scenario_motion(scenario: Scenario, imu, chirp_times: np.ndarray, trajectory=None, *,
                    velocity: str = "given"):
    """:func:`estimate_motion` for a scenario and its IMU log.

    Parameters
    ----------
    scenario : Scenario
        Lever arm and IMU clock offset.
    imu : xarray.Dataset
        ``imu_time`` [s, IMU clock], ``imu_gyro`` [rad/s], ``imu_accel`` [m/s^2].
    chirp_times : ndarray, shape ``[chirp]``
        Chirp start times of all frames, in order [s].
    trajectory : raysim.platform.motion.Trajectory, optional
        Default ``scenario.trajectory()``.
    velocity : {"given", "hover"}
        Initial-velocity handling (:data:`VELOCITY_MODES`).

    Returns
    -------
    compensation.PlatformMotion
        In the nominal radar frame N of ``radar.mounting_deg``
        (:func:`raysim.platform.mounting.mount_motion`), so the beams look along
        the directions the scenario's targets are given in; W itself for the
        default ``down`` mounting.
    """
    from raysim.platform.mounting import mount_motion

    traj = scenario.trajectory() if trajectory is None else trajectory
    return mount_motion(estimate_motion(imu["imu_time"].values, imu["imu_gyro"].values,
                                        imu["imu_accel"].values, chirp_times,
                                        lever_arm=scenario.lever_arm, trajectory=traj,
                                        time_offset=scenario.imu.time_offset_s,
                                        velocity=velocity),
                        scenario.radar.mounting_deg)


def ground_tilt_of_record(inp, imu: np.ndarray, rcs: list, frame_times: list, r_axis, gates,
                          time_offset: float, options: dict, warn: bool = True,
                          mounting=None):
    """Roll and pitch of the first ramp from the ground clutter beyond the compensated cells.

    :func:`compensation.ground_plane.ground_tilt` over every frame, each formed with
    the one integration of ``options`` (the attitude it corrects: ``initial_attitude``);
    the ground is the farthest surface a down-looking radar sees, so its cells are
    those beyond the last of ``gates``. A mounted radar's ground points are found in
    its nominal frame N and turned into W by ``R_BA`` (``ground_tilt(..., mounting=R_BA)``),
    so the plane is fitted in W, where the ground is level.

    Parameters
    ----------
    inp : raysim.io.compensate_io.CompensateInput
        The input (array, slots, configuration).
    imu : ndarray, shape ``[sample, 7]``
        IMU table (time [s, IMU clock], gyro [rad/s], accel [m/s^2]).
    rcs : list of ndarray, each shape ``[chirp, channel, range]``
        Range-compressed frames.
    frame_times : list of ndarray
        Slot times of every frame [s, radar clock].
    r_axis : ndarray, shape ``[range]``
        Range of every cell [m].
    gates : ndarray of int
        The compensated cells.
    time_offset : float
        IMU clock minus radar clock [s].
    options : dict
        For :func:`estimate_record` (``lever_arm``, ``initial_attitude``, ``imu_grade``,
        ``velocity`` ...).
    warn : bool
        Issue the fit's warnings (:class:`compensation.ground_plane.GroundPlaneWarning`).
    mounting : str or (float, float, float), optional
        The radar's mounting (:func:`raysim.platform.mounting.mounting_deg`);
        default ``down``.

    Returns
    -------
    compensation.ground_plane.GroundPlane
    """
    from compensation.ground_plane import ground_tilt

    motions = estimate_record(imu[:, 0], imu[:, 1:4], imu[:, 4:7], frame_times,
                              time_offset=time_offset, **options)
    kw = dict(wavelength=inp.config.center_wavelength, range_axis=r_axis,
              gates=np.arange(int(gates[-1]) + 1, r_axis.size),
              gyro_bias_sigma=_gyro_bias_sigma(options), warn=warn,
              channel_slot=inp.tx_slot if inp.num_slots > 1 else None,
              grid_shape=inp.grid_shape,
              method="lattice" if inp.grid_shape is not None else "direct")
    from raysim.platform.mounting import is_default_mounting, mounting_matrix

    return ground_tilt(rcs, inp.element_positions, motions, **kw,
                       mounting=None if is_default_mounting(mounting) else
                       mounting_matrix(mounting))


def _gyro_bias_sigma(options: dict) -> float:
    """Spread of the gyro bias of ``options``' ``imu_grade`` (default the widest) [rad/s]."""
    from raysim.pipeline.self_calibration import imu_errors

    grade = options.get("imu_grade")
    if grade is None:
        from compensation.calibration import DEFAULT_IMU_ERRORS as errors
    else:
        errors = imu_errors(grade)
    return float(errors.gyro_bias_sigma)


def ground_retilt(ground, options: dict):
    """The ground's tilt again at the clock and gyro bias a calibration finds.

    Parameters
    ----------
    ground : compensation.ground_plane.GroundPlane
        The fit of :func:`ground_tilt_of_record` with ``options``.
    options : dict
        Those of that fit (``initial_attitude``: the attitude its tilt corrects,
        ``imu_grade``).

    Returns
    -------
    compensation.ground_refit.GroundRetilt or None
        For :func:`compensation.calibration.self_calibrate` (``ground=``); None when the
        fit kept no points to turn (a mounted radar's).
    """
    from compensation.ground_refit import GroundRetilt

    if not ground.looks:
        return None
    return GroundRetilt(ground, options["initial_attitude"], _gyro_bias_sigma(options))
