"""Scene simulation of the report: the hover motion, its IMU estimate, the twin frames.

The frames come from the pipeline's stationary / hover twin
(:func:`raysim.pipeline.sources.hover_twin`), the IMU record from
:func:`raysim.pipeline.sensors.imu_record` and the pose estimate from
:func:`raysim.pipeline.estimate.estimate_motion`.
"""

from __future__ import annotations

import math

import numpy as np

from raysim.pipeline.sources import path_kinds

from .settings import MOVER_START_NE, ReportSettings

__all__ = ["hover_trajectory", "report_trajectory", "imu_samples", "scene_motion",
           "simulate_scene", "path_kinds", "report_mover"]


def hover_trajectory(seed: int, t0: float = 0.0, axes=None):
    """Seeded hover jitter that starts at the nominal hover pose at ``t0``.

    :func:`raysim.platform.motion.hover_jitter` (default spectrum) through
    :func:`raysim.pipeline.sources.nominal_at`: its pose at ``t0`` removed on
    the moving axes, so the stationary and the hovering radar share the first
    chirp's pose and differ only by the motion within the frame.

    Parameters
    ----------
    seed : int
        Seed of the jitter.
    t0 : float
        Time at which the pose is nominal [s].
    axes : sequence of str, optional
        Axes of :data:`raysim.platform.motion.AXES` the jitter moves (default all
        six); the others stay at the nominal pose.

    Returns
    -------
    raysim.platform.motion.Trajectory
    """
    from raysim.pipeline.sources import nominal_at
    from raysim.platform.motion import hover_jitter

    return nominal_at(hover_jitter(seed), t0, axes)


def report_trajectory(settings: ReportSettings):
    """Motion of the report's moving radar.

    Traced scenes: the scenario's motion on ``settings.jitter_axes``, at the
    nominal pose at the first chirp (:func:`raysim.pipeline.sources.nominal_at`).
    Point scenes: the scenario's motion itself (the frames of ``raysim simulate``).

    Returns
    -------
    raysim.platform.motion.Trajectory
    """
    from raysim.pipeline.sources import nominal_at

    scenario = settings.scenario
    if scenario.scene.kind == "points":
        return scenario.trajectory()
    t0 = float(settings.radar().chirp_times()[0])
    return nominal_at(scenario.trajectory(), t0, settings.jitter_axes)


def imu_samples(trajectory, chirp_times, settings: ReportSettings):
    """Simulated IMU record along the trajectory, covering the chirps with a margin.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
    chirp_times : ndarray, shape ``[chirp]`` [s]
    settings : ReportSettings
        The scenario's IMU (preset, rate, seed, clock errors).

    Returns
    -------
    time : ndarray, shape ``[sample]`` [s, IMU clock]
    gyro : ndarray, shape ``[sample, 3]`` [rad/s]
    accel : ndarray, shape ``[sample, 3]`` [m/s^2]
        From :func:`raysim.pipeline.sensors.imu_record`.
    """
    from raysim.pipeline.sensors import imu_record

    s = settings.scenario
    return imu_record(trajectory, s.imu_spec(), rate=s.imu.rate_hz, times=chirp_times,
                      seed=s.imu_seed, time_offset=s.imu.time_offset_s,
                      clock_drift_ppm=s.imu.clock_drift_ppm).to_arrays()


def scene_motion(trajectory, chirp_times, settings: ReportSettings):
    """Pose estimate at every chirp: :func:`imu_samples` through the pipeline's estimate.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
        Truth motion (it also gives the initial pose and velocity, as a flight
        controller would).
    chirp_times : ndarray, shape ``[chirp]`` [s]
    settings : ReportSettings
        The scenario's IMU and lever arm.

    Returns
    -------
    compensation.PlatformMotion
        From :func:`raysim.pipeline.estimate.estimate_motion` (``velocity="given"``),
        in the nominal radar frame N of ``radar.mounting_deg``.
    """
    from raysim.pipeline.estimate import estimate_motion
    from raysim.platform.mounting import mount_motion

    t = np.asarray(chirp_times, dtype=float)
    motion = estimate_motion(*imu_samples(trajectory, t, settings), t,
                             lever_arm=settings.scenario.lever_arm, trajectory=trajectory,
                             time_offset=settings.scenario.imu.time_offset_s, velocity="given")
    return mount_motion(motion, settings.scenario.radar.mounting_deg)   # beams in N


def report_mover(scene, settings: ReportSettings, t0: float = 0.0, ground=None):
    """The report's car: :data:`MOVER_START_NE` on the ground, driving east, or None.

    Parameters
    ----------
    scene : raysim.echoes.rt.scenes.RadarScene
        Gives the ground height under the start point.
    settings : ReportSettings
        ``mover_speed`` [m/s] (None: no mover).
    t0 : float
        Time at which the car is at the start point [s].
    ground : raysim.echoes.ground.surface.GroundSurface, optional
        The scene's ground (read from ``scene`` when omitted).

    Returns
    -------
    raysim.echoes.moving.cars.CarMover or None
    """
    if settings.mover_speed is None:
        return None
    from raysim.echoes.ground.surface import GroundSurface
    from raysim.echoes.moving.cars import CarMover
    from raysim.echoes.moving.scatterers import RigidTrajectory

    north, east = MOVER_START_NE
    ground = GroundSurface.from_scene(scene) if ground is None else ground
    _, z = ground.locate(np.array([[north, east, 0.0]]))
    if not np.isfinite(z[0]):
        raise ValueError(f"scene {scene.name!r} has no ground under the mover start "
                         f"{MOVER_START_NE} (north, east) [m]")
    start = np.array([north, east, z[0]])
    return CarMover("mover", RigidTrajectory(start, heading=math.pi / 2,
                                             speed=float(settings.mover_speed), t0=t0))


def simulate_scene(settings: ReportSettings, trajectory, *, progress=None, movers=()) -> dict:
    """The twin frames of the report's scenario (:func:`raysim.pipeline.sources.hover_twin`).

    Traced scenes are traced once at the nominal pose; both frames share the
    trace (and the moving objects' scattering centres, traced at the same
    instant), so they differ only by the platform motion within the frame.

    Parameters
    ----------
    settings : ReportSettings
        Scenario, rays, NUFFT tolerance, path chunk and the report's car
        (``mover_speed``, :func:`report_mover`).
    trajectory : raysim.platform.motion.Trajectory
        Motion of the moving platform (:func:`report_trajectory`).
    progress : callable, optional
        ``progress(message)`` after each step.
    movers : sequence
        Moving objects besides the report's car, as for ``hover_twin``.

    Returns
    -------
    dict
        As :func:`raysim.pipeline.sources.hover_twin`: ``"stationary"`` and
        ``"hover"`` RadarFrames ``[chirp, channel, sample]``, ``"reference"``,
        ``"seconds"`` and, for traced scenes, ``"paths"``, ``"path_kinds"``,
        ``"tracks"``, ``"movers"``, ``"scene"``, ``"clutter"``.
    """
    from raysim.pipeline.sources import hover_twin

    extra = list(movers)
    if settings.mover_speed is not None:
        extra.append(lambda scene, ground, t0: report_mover(scene, settings, t0, ground))
    return hover_twin(settings.scenario, trajectory, samples_per_src=settings.samples_per_src,
                      nufft_eps=settings.nufft_eps, path_chunk=settings.path_chunk,
                      movers=extra, progress=progress)
