"""Scene simulation of the report: hover trajectory, IMU pose estimate, traced IF frames."""

from __future__ import annotations

import functools
import math
import time

import numpy as np

from .settings import MOVER_START_NE, ReportSettings

__all__ = ["hover_trajectory", "imu_samples", "scene_motion", "simulate_scene", "path_kinds",
           "report_mover"]


def path_kinds(paths) -> dict:
    """Path count per interaction kind.

    Parameters
    ----------
    paths : raysim.echoes.rt.trace.PathSet

    Returns
    -------
    dict
        ``specular`` (ground), ``diffuse``, ``target`` and ``other_specular`` counts.
    """
    from raysim.echoes.rt.trace import DIFFUSE, SENSING, SPECULAR

    k = paths.kind
    return {"specular": int(np.sum(k == SPECULAR)), "diffuse": int(np.sum((k & DIFFUSE) != 0)),
            "target": int(np.sum((k & SENSING) != 0)),
            "other_specular": int(np.sum(((k & SPECULAR) != 0) & (k != SPECULAR)
                                         & ((k & (DIFFUSE | SENSING)) == 0)))}


def hover_trajectory(seed: int, t0: float = 0.0, axes=None):
    """Seeded hover jitter that starts at the nominal hover pose at ``t0``.

    :func:`raysim.platform.motion.hover_jitter` wanders centimetres and degrees away
    from the hover point; constant offsets (:class:`raysim.platform.motion.Ramp`)
    remove its pose at ``t0`` on all six axes, so the stationary and the
    hovering radar share the first chirp's pose and differ only by the motion
    within the frame (a static offset would shift the range profile by a
    fraction of a bin, which is no Doppler effect).

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
    from raysim.platform.motion import AXES, Ramp, Trajectory, hover_jitter

    axes = AXES if axes is None else tuple(axes)
    if not axes or any(a not in AXES for a in axes) or len(set(axes)) != len(axes):
        raise ValueError(f"axes must be distinct names from {AXES}, got {axes!r}")
    jitter = hover_jitter(seed)
    q0 = jitter.states([t0])[0][0]
    moved = Trajectory(tuple(c for c in jitter.components if c.axis in axes),
                       name=jitter.name if len(axes) == len(AXES)
                       else f"{jitter.name} ({', '.join(axes)})")
    return moved + Trajectory(tuple(Ramp(a, offset=-float(v)) for a, v in zip(AXES, q0,
                                                                              strict=True)
                                    if a in axes), name="nominal pose at t0")


def imu_samples(trajectory, chirp_times, settings: ReportSettings):
    """Simulated IMU record along the trajectory, covering the chirps with a margin.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
    chirp_times : ndarray, shape ``[chirp]`` [s]
    settings : ReportSettings
        ``imu``, ``imu_rate`` and ``imu_seed`` are used.

    Returns
    -------
    time : ndarray, shape ``[sample]`` [s]
    gyro : ndarray, shape ``[sample, 3]`` [rad/s]
    accel : ndarray, shape ``[sample, 3]`` [m/s^2]
        Covering the chirps with the margin of :func:`raysim.pipeline.sensors.imu_margin_s`.
    """
    from raysim.pipeline.sensors import imu_record

    return imu_record(trajectory, settings.imu, rate=settings.imu_rate, times=chirp_times,
                      seed=settings.imu_seed).to_arrays()


def scene_motion(trajectory, chirp_times, settings: ReportSettings):
    """Pose estimate at every chirp: :func:`imu_samples` through the pipeline's estimate.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
        Truth motion (it also gives the initial pose and velocity, as a flight
        controller would).
    chirp_times : ndarray, shape ``[chirp]`` [s]
    settings : ReportSettings
        ``imu``, ``imu_rate``, ``imu_seed`` and ``lever_arm`` are used.

    Returns
    -------
    compensation.PlatformMotion
        From :func:`raysim.pipeline.estimate.estimate_motion` (``velocity="given"``).
    """
    from raysim.pipeline.estimate import estimate_motion

    t = np.asarray(chirp_times, dtype=float)
    return estimate_motion(*imu_samples(trajectory, t, settings), t,
                           lever_arm=np.asarray(settings.lever_arm), trajectory=trajectory,
                           velocity="given")


def _clutter_model(settings: ReportSettings):
    """The report's :class:`raysim.echoes.clutter.model.GroundClutter`, or None (Sionna diffuse)."""
    if settings.clutter == "sionna":
        return None
    from raysim.echoes.clutter.field import FieldSettings
    from raysim.echoes.clutter.model import GroundClutter

    return GroundClutter(FieldSettings(scatterers_per_cell=settings.clutter_per_cell,
                                       seed=settings.trace_seed))


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
    ground : raysim.echoes.clutter.ground.GroundSurface, optional
        The scene's ground (read from ``scene`` when omitted).

    Returns
    -------
    raysim.echoes.clutter.movers.CarMover or None
    """
    if settings.mover_speed is None:
        return None
    from raysim.echoes.clutter.ground import GroundSurface
    from raysim.echoes.clutter.movers import CarMover
    from raysim.echoes.clutter.tracks import RigidTrajectory

    north, east = MOVER_START_NE
    ground = GroundSurface.from_scene(scene) if ground is None else ground
    _, z = ground.locate(np.array([[north, east, 0.0]]))
    if not np.isfinite(z[0]):
        raise ValueError(f"scene {scene.name!r} has no ground under the mover start "
                         f"{MOVER_START_NE} (north, east) [m]")
    start = np.array([north, east, z[0]])
    return CarMover("mover", RigidTrajectory(start, heading=math.pi / 2,
                                             speed=float(settings.mover_speed), t0=t0))


def simulate_scene(scene: str, settings: ReportSettings, trajectory, *, progress=None,
                   movers=()) -> dict:
    """Trace ``scene`` once at the nominal pose and synthesise both IF frames.

    Both frames share the one trace (and the moving objects' scattering centres,
    traced at the same instant), so they differ only by the platform motion
    within the frame.

    Parameters
    ----------
    scene : str
        Registry name.
    settings : ReportSettings
    trajectory : raysim.platform.motion.Trajectory
        Hover motion of the moving platform.
    progress : callable, optional
        ``progress(message)`` after each step.
    movers : sequence
        Moving objects besides the report's car (:func:`report_mover`):
        :class:`raysim.echoes.clutter.movers.CarMover` or
        :class:`raysim.echoes.clutter.tracks.MovingObject`, driving through the
        scene in both frames, traced (PO + SBR for a CarMover, with its local
        ground: car-ground ghosts) from the nominal pose at the first chirp.

    Returns
    -------
    dict
        ``"stationary"``, ``"hover"``: IF cubes ``[chirp, channel, sample]``
        complex64 [sqrt(W)]; ``"paths"`` (:class:`raysim.echoes.rt.trace.PathSet`),
        ``"tracks"`` (list of :class:`raysim.echoes.clutter.tracks.Tracks`),
        ``"movers"`` (the :class:`raysim.echoes.clutter.tracks.MovingObject` of
        every mover, the report's car included),
        ``"scene"`` (:class:`raysim.echoes.rt.scenes.RadarScene`), ``"clutter"``
        (the field's report, empty without it), ``"seconds"``.
    """
    from raysim.echoes.clutter.tracks import synthesize_tracks
    from raysim.echoes.rt.reproject import synthesize_paths
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.platform.motion import stationary
    from raysim.synthesis.select import synthesize

    config = settings.radar()
    array = settings.array()
    lever = np.asarray(settings.lever_arm, dtype=float)
    model = _clutter_model(settings)
    seconds = {}
    t = time.perf_counter()
    t0 = float(config.chirp_times()[0])
    loaded = load_scene(scene, frequency=config.carrier_frequency)
    tracer = MonostaticTracer(max_depth=settings.max_depth,
                              samples_per_src=settings.samples_per_src, seed=settings.trace_seed)
    tracks = []
    if model is not None:
        tracer = model.tracer(tracer)
    paths = tracer(loaded, config, stationary(), lever, time=t0)
    if model is not None:
        paths, tracks = model.paths(loaded, paths, config, array, stationary(), lever, time=t0)
    radar_w = stationary().point_world([t0], lever)[0, 0]
    ground = None                      # cars are located on and traced with the ground
    if settings.mover_speed is not None or any(hasattr(m, "moving_object") for m in movers):
        from raysim.echoes.clutter.ground import GroundSurface

        ground = model.ground if model is not None else GroundSurface.from_scene(loaded)
    car = report_mover(loaded, settings, t0, ground)
    cars = [*movers, *([car] if car is not None else [])]
    objects = [m.moving_object(config, radar_w, time=t0, ground=ground)
               if hasattr(m, "moving_object") else m for m in cars]
    tracks = tracks + [m.tracks(config, radar_w, time=t0) for m in objects]
    seconds["trace"] = time.perf_counter() - t
    if progress:
        progress("traced")
    # moving points at the report's eps; frozen paths: synthesize_paths takes the compact
    # way (fused kernel, no [path, chirp, channel] delays) for the clutter field
    synth = functools.partial(synthesize, eps=settings.nufft_eps)
    out = {"paths": paths, "tracks": tracks, "scene": loaded, "movers": objects,
           "clutter": model.summary() if model is not None else {}}
    for name, motion in (("stationary", stationary()), ("hover", trajectory)):
        t = time.perf_counter()
        out[name], _ = synthesize_paths(paths, config, array, motion, lever,
                                        path_chunk=settings.path_chunk, eps=settings.nufft_eps)
        synthesize_tracks(tracks, config, array, motion, lever, out=out[name],
                          synthesizer=synth)
        seconds[f"synthesis_{name}"] = time.perf_counter() - t
        if progress:
            progress(f"synthesised {name}")
    out["seconds"] = seconds
    return out
