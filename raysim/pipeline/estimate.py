"""Motion estimate (stage 3 of the run path): IMU samples -> the platform pose at every chirp.

Every study and command integrates its IMU through :func:`estimate_motion`, so
the initial state and the velocity handling are defined once.
"""

from __future__ import annotations

import numpy as np

from raysim.io.scenario import Scenario

__all__ = ["VELOCITY_MODES", "estimate_motion", "scenario_motion", "split_frames"]

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
    if velocity == "given":
        options.setdefault("initial_velocity", trajectory.velocity([t_ref])[0])
    if "initial_attitude" not in options:
        options["initial_attitude"] = trajectory.attitude([t_ref]).as_matrix()[0]
    if "initial_position" not in options:
        options["initial_position"] = trajectory.position([t_ref])[0]
    return integrate_imu(np.asarray(imu_time), np.asarray(gyro), np.asarray(accel), frames,
                         lever_arm=lever_arm, time_offset=time_offset, reference_time=t_ref,
                         velocity=velocity, **options)


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
    """
    traj = scenario.trajectory() if trajectory is None else trajectory
    return estimate_motion(imu["imu_time"].values, imu["imu_gyro"].values,
                           imu["imu_accel"].values, chirp_times, lever_arm=scenario.lever_arm,
                           trajectory=traj, time_offset=scenario.imu.time_offset_s,
                           velocity=velocity)
