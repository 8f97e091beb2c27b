"""Scene simulation of the report: hover trajectory, IMU pose estimate, traced IF frames."""

from __future__ import annotations

import functools
import time

import numpy as np

from .settings import ReportSettings

__all__ = ["hover_trajectory", "imu_samples", "scene_motion", "simulate_scene", "path_kinds"]


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


def hover_trajectory(seed: int, t0: float = 0.0):
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

    Returns
    -------
    raysim.platform.motion.Trajectory
    """
    from raysim.platform.motion import AXES, Ramp, Trajectory, hover_jitter

    jitter = hover_jitter(seed)
    q0 = jitter.states([t0])[0][0]
    return jitter + Trajectory(tuple(Ramp(a, offset=-float(v)) for a, v in zip(AXES, q0,
                                                                               strict=True)),
                               name="nominal pose at t0")


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
        From four IMU periods before the first to four after the last chirp.
    """
    from raysim.platform.imu import simulate_imu

    t = np.asarray(chirp_times, dtype=float)
    margin = 4.0 / settings.imu_rate
    samples = simulate_imu(trajectory, settings.imu, rate=settings.imu_rate,
                           start=float(t[0]) - margin, end=float(t[-1]) + margin,
                           seed=settings.imu_seed)
    return samples.to_arrays()


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


def simulate_scene(scene: str, settings: ReportSettings, trajectory, *, progress=None) -> dict:
    """Trace ``scene`` once at the nominal pose and synthesise both IF frames.

    Parameters
    ----------
    scene : str
        Registry name.
    settings : ReportSettings
    trajectory : raysim.platform.motion.Trajectory
        Hover motion of the moving platform.
    progress : callable, optional
        ``progress(message)`` after each step.

    Returns
    -------
    dict
        ``"stationary"``, ``"hover"``: IF cubes ``[chirp, channel, sample]``
        complex64 [sqrt(W)]; ``"paths"`` (:class:`raysim.echoes.rt.trace.PathSet`),
        ``"scene"`` (:class:`raysim.echoes.rt.scenes.RadarScene`), ``"seconds"``.
    """
    from raysim.echoes.rt.reproject import synthesize_paths
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.platform.motion import stationary
    from raysim.synthesis.nufft import synthesize_nufft

    config = settings.radar()
    array = settings.array()
    lever = np.asarray(settings.lever_arm, dtype=float)
    seconds = {}
    t = time.perf_counter()
    loaded = load_scene(scene, frequency=config.carrier_frequency)
    tracer = MonostaticTracer(max_depth=settings.max_depth,
                              samples_per_src=settings.samples_per_src, seed=settings.trace_seed)
    paths = tracer(loaded, config, stationary(), lever, time=float(config.chirp_times()[0]))
    seconds["trace"] = time.perf_counter() - t
    if progress:
        progress("traced")
    synth = functools.partial(synthesize_nufft, eps=settings.nufft_eps)
    out = {"paths": paths, "scene": loaded}
    for name, motion in (("stationary", stationary()), ("hover", trajectory)):
        t = time.perf_counter()
        out[name], _ = synthesize_paths(paths, config, array, motion, lever,
                                        path_chunk=settings.path_chunk, synthesizer=synth)
        seconds[f"synthesis_{name}"] = time.perf_counter() - t
        if progress:
            progress(f"synthesised {name}")
    out["seconds"] = seconds
    return out
