"""Self-calibration on a ray-traced bundled scene: clutter ridge with estimated against true pose.

:func:`scene_calibration` traces a bundled scene once at the nominal hover pose
(Sionna RT, :class:`raysim.echoes.rt.trace.MonostaticTracer`), synthesises
several frames of the hovering radar from the frozen paths
(:func:`raysim.echoes.rt.reproject.synthesize_paths`, hover jitter with rotor
vibration), samples an IMU (default ``consumer_mems``) with a clock offset
along the same motion, and compensates every frame with the exact chain twice:

* with the pose from the self-calibration stage
  (:func:`raysim.pipeline.self_calibration.calibrate_record`, which runs
  :func:`compensation.calibration.self_calibrate`: clock
  offset, per-frame velocity and gyro bias estimated from the radar; initial
  velocity unknown: hover guess; the initial attitude is the flight
  controller's, here the simulated one at the first chirp),
* with the true pose (an ideal IMU with the true initial state, as the scene
  report's ``exact`` chain).

The ground clutter is the settings' (``settings.clutter``): the persistent
clutter field (:class:`raysim.echoes.scene_clutter.SceneClutter`, the scene
report's default: seeded scatterers with calibrated sigma0, rough-surface
mirror, target-ground ghosts) or Sionna's own diffuse paths (``"sionna"``), traced
as :func:`raysim.echoes.rt.render.render_scene` and the scene report do. The
report's car (``settings.mover_speed``) is refused: the self-calibration
measures a stationary scene.

The radar is mounted as the settings' scenario says (``radar.mounting_deg``,
:mod:`raysim.platform.mounting`), as in the scene report: the trace and the
synthesis take the radar frame A's pose
(:func:`raysim.platform.mounting.mount_trajectory`), the IMU stays on the body,
the self-calibration finds its scatterers in the nominal radar frame N
(``mounting=R_BA``) and both chains form their beams there
(:func:`raysim.platform.mounting.mount_motion`). The default ``down`` mounting
takes none of these turns.

The metric is the scene report's ridge leakage (RD power outside Doppler bins
-1..+1 over the total, :func:`raysim.studies.scene_report.process.chain_result`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

__all__ = ["SceneCalibration", "scene_calibration"]

#: Seconds of IMU record before the first chirp (the hover window of a consumer IMU is
#: 1 s centred on the chirps, so the record covers it).
IMU_LEAD_S = 0.6


@dataclass(frozen=True)
class SceneCalibration:
    """Ridge leakage of the exact chain per frame, estimated and true pose.

    Attributes
    ----------
    leakage_estimated_db, leakage_true_db : ndarray, shape ``[frame]``
        Ridge leakage [dB] with the self-calibrated pose and with the true pose.
    time_offset_s, true_time_offset_s : float
        Estimated and true IMU clock minus radar clock [s].
    scatterers : int
        Stationary scatterers detected and used.
    report : dict
        :meth:`compensation.calibration.CalibrationResult.report`.
    seconds : dict
        Wall time of ``trace``, ``synthesis``, ``calibration``, ``chains`` [s].
    clutter : dict
        The clutter field's report
        (:meth:`raysim.echoes.scene_clutter.SceneClutter.summary`: scatterer
        count, build time); empty with Sionna's clutter.
    scatterer_positions_m : ndarray, shape ``[scatterer, 3]``
        Where the scatterers used were found, in W [m]: the range of their gate
        from the nominal radar phase centre (the lever arm; the body hovers at
        the origin) along their direction, found in N and turned by ``R_BA``.
    """

    leakage_estimated_db: np.ndarray
    leakage_true_db: np.ndarray
    time_offset_s: float
    true_time_offset_s: float
    scatterers: int
    report: dict
    seconds: dict
    clutter: dict = field(default_factory=dict)
    scatterer_positions_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))

    @property
    def worst_gap_db(self) -> float:
        """Largest ``estimated - true`` ridge leakage over the frames [dB]."""
        return float(np.max(self.leakage_estimated_db - self.leakage_true_db))


def scene_calibration(scene: str = "flat_reflectors", settings=None, *, frames: int = 4,
                      frame_period: float = 0.05, imu: str = "consumer_mems",
                      time_offset: float = 0.003, imu_seed: int = 1,
                      jitter_seed: int | None = None) -> SceneCalibration:
    """Self-calibrate a multi-frame hover over a bundled scene and compare ridge leakage.

    Parameters
    ----------
    scene : str
        Bundled scene name (:data:`raysim.echoes.rt.scenes.SCENES`).
    settings : raysim.studies.scene_report.ReportSettings, optional
        Radar (its mounting ``scenario.radar.mounting_deg`` included), array,
        tracing, ground clutter (``clutter``, ``clutter_per_cell``) and
        processing; default :data:`raysim.studies.scene_report.QUICK` (the
        persistent clutter field, the radar looking down). ``mover_speed``
        must be None.
    frames : int
        Frames (two or more, so that the gyro bias is estimated).
    frame_period : float
        Frame start to frame start [s].
    imu : str
        IMU preset of the record (:mod:`raysim.platform.imu_spec`).
    time_offset : float
        True IMU clock minus radar clock [s]; the calibration starts from 0.
    imu_seed : int
        Seed of the IMU errors.
    jitter_seed : int, optional
        Seed of the hover jitter; default ``settings.jitter_seed``.

    Returns
    -------
    SceneCalibration

    Raises
    ------
    ValueError
        An unknown scene, fewer than two frames, or settings with a mover.
    """
    import functools

    from raysim.echoes.ground.field import FieldSettings
    from raysim.echoes.moving.scatterers import synthesize_tracks
    from raysim.echoes.rt.reproject import synthesize_paths
    from raysim.echoes.rt.scenes import SCENES, load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.echoes.scene_clutter import SceneClutter
    from raysim.pipeline.estimate import estimate_motion
    from raysim.pipeline.self_calibration import calibrate_record
    from raysim.pipeline.sensors import imu_record
    from raysim.platform.motion import stationary
    from raysim.platform.mounting import (
        is_default_mounting,
        mount_motion,
        mount_trajectory,
        mounting_matrix,
    )
    from raysim.processing.maps import range_compress
    from raysim.studies.scene_report import QUICK, chain_result, hover_trajectory
    from raysim.synthesis.select import synthesize

    if scene not in SCENES:
        raise ValueError(f"unknown scene {scene!r}; expected one of {sorted(SCENES)}")
    if not (isinstance(frames, int) and frames >= 2):
        raise ValueError(f"frames must be an integer >= 2, got {frames!r}")
    settings = QUICK if settings is None else settings
    if settings.mover_speed is not None:
        raise ValueError(f"settings.mover_speed: got {settings.mover_speed!r}, expected None "
                         f"(the self-calibration study measures a stationary scene; a car "
                         f"is a moving scatterer)")
    # the report's ground clutter: the persistent field, or Sionna's diffuse paths
    model = None if settings.clutter == "sionna" else SceneClutter(FieldSettings(
        scatterers_per_cell=settings.clutter_per_cell, seed=settings.trace_seed))
    config = replace(settings.radar(), num_frames=frames, frame_period=float(frame_period))
    array = settings.array()
    lever = np.asarray(settings.lever_arm, dtype=float)
    t0 = IMU_LEAD_S
    times = [config.chirp_times(f, t0) for f in range(frames)]     # [frame][chirp] [s]
    traj = hover_trajectory(settings.jitter_seed if jitter_seed is None else jitter_seed, t0)
    mount = settings.scenario.radar.mounting_deg
    turn = None if is_default_mounting(mount) else mounting_matrix(mount)        # R_BA
    rest, lever_a = mount_trajectory(stationary(), lever, mount)    # the radar frame A's pose
    traj_a = mount_trajectory(traj, lever, mount)[0]
    seconds = {}
    t = time.perf_counter()
    loaded = load_scene(scene, frequency=config.carrier_frequency)
    tracer = MonostaticTracer(max_depth=settings.max_depth,
                              samples_per_src=settings.samples_per_src, seed=settings.trace_seed)
    tracks = []
    if model is not None:
        tracer = model.tracer(tracer)
    paths = tracer(loaded, config, rest, lever_a, time=float(times[0][0]))
    if model is not None:
        paths, tracks = model.paths(loaded, paths, config, array, rest, lever_a,
                                    time=float(times[0][0]))
    seconds["trace"] = time.perf_counter() - t
    t = time.perf_counter()
    taper = settings.channel_taper().astype(np.float32)[None, :, None]
    synth = functools.partial(synthesize, eps=settings.nufft_eps)
    rcs = []
    for f in range(frames):
        cube, _ = synthesize_paths(paths, config, array, traj_a, lever_a, frame=f, t0=t0,
                                   path_chunk=settings.path_chunk, eps=settings.nufft_eps,
                                   decimate=settings.decimate,
                                   decimate_tolerance=settings.decimate_tolerance)
        synthesize_tracks(tracks, config, array, traj_a, lever_a, out=cube, frame=f, t0=t0,
                          synthesizer=synth)
        rcs.append(range_compress(cube) * taper)
    seconds["synthesis"] = time.perf_counter() - t
    r_axis = config.bin_ranges(rcs[0].shape[-1])
    lo, hi = settings.range_window
    gates = np.flatnonzero((r_axis >= lo) & (r_axis <= hi))
    end = float(times[-1][-1]) + IMU_LEAD_S
    rec = imu_record(traj, imu, rate=settings.imu_rate, times=[t0, end], seed=imu_seed,
                     time_offset=time_offset, start=0.0).to_arrays()
    t = time.perf_counter()
    mounted = {} if turn is None else {"mounting": turn}        # scatterers found in N
    res = calibrate_record(rcs, times, array.virtual_positions, *rec,
                           wavelength=config.center_wavelength, range_axis=r_axis,
                           time_offset=0.0, grid_shape=array.grid_shape, detect_gates=gates,
                           lever_arm=lever, initial_attitude=traj.attitude([t0]).as_matrix()[0],
                           velocity="hover", imu_grade=imu, **mounted).result
    seconds["calibration"] = time.perf_counter() - t
    ideal = imu_record(traj, "ideal", rate=settings.imu_rate, times=[t0, end], seed=imu_seed,
                       start=0.0).to_arrays()
    truth = estimate_motion(*ideal, np.concatenate(times), lever_arm=lever, trajectory=traj,
                            velocity="given")
    t = time.perf_counter()
    n = config.num_chirps
    est, true = [], []
    for f in range(frames):                   # beams in N
        est.append(chain_result("exact", rcs[f], mount_motion(res.motions[f], mount),
                                settings, config, array).ridge_leakage_db)
        true.append(chain_result("exact", rcs[f],
                                 mount_motion(truth.select(slice(f * n, (f + 1) * n)), mount),
                                 settings, config, array).ridge_leakage_db)
    seconds["chains"] = time.perf_counter() - t
    found = np.zeros((0, 3))
    if res.scatterers:
        u = np.stack([sc.direction for sc in res.scatterers])                # [scatterer, 3]
        found = lever + r_axis[[sc.gate for sc in res.scatterers]][:, None] * (
            u if turn is None else u @ turn.T)
    return SceneCalibration(np.array(est), np.array(true), float(res.time_offset),
                            float(time_offset), len(res.scatterers), res.report(), seconds,
                            model.summary() if model is not None else {}, found)


if __name__ == "__main__":     # python -m raysim.studies.scene_calibration [SEEDS [MOUNTING]]
    import sys

    from raysim.studies.scene_report import QUICK

    quick = QUICK if len(sys.argv) < 3 else QUICK.with_values(
        scenario=QUICK.scenario.with_values({"radar.mounting_deg": sys.argv[2]}))
    print("| IMU seed | offset error [ms] (stated sigma) | scatterers | ridge leakage estimated "
          "/ true per frame [dB] | worst gap [dB] | CPU / wall [s] |\n|---|---|---|---|---|---|")
    for s in range(int(sys.argv[1]) if len(sys.argv) > 1 else 3):
        cpu, wall = time.process_time(), time.perf_counter()
        r = scene_calibration(settings=quick, imu_seed=s)
        cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
        pairs = ", ".join(f"{a:.1f} / {b:.1f}" for a, b in zip(
            r.leakage_estimated_db, r.leakage_true_db, strict=True))
        print(f"| {s} | {1e3 * (r.time_offset_s - r.true_time_offset_s):+.3f} "
              f"({1e3 * r.report['time_offset_sigma_s']:.3f}) | {r.scatterers} | {pairs} | "
              f"{r.worst_gap_db:+.2f} | {cpu:.0f} / {wall:.0f} |", flush=True)
