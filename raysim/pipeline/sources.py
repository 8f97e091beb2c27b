"""Echo sources: a scenario's frames from the point-target oracle or a ray-traced scene.

Stage 1 of the run path (see :mod:`raysim.pipeline`): scenario -> IF frames
``[chirp, channel, sample]``. :func:`frame_source` loads a scene once and
returns ``f -> RadarFrame``; :class:`LazyFrames` renders frames on access.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from raysim.scenario import Scenario
from raysim.synthesis.frame import RadarFrame

__all__ = ["FeatureUnavailable", "Reference", "frame_source", "point_targets", "radar_pose",
           "reference_target", "LazyFrames", "render_frames", "nominal_at", "path_kinds",
           "hover_twin", "gated_source", "decimation"]


class FeatureUnavailable(RuntimeError):
    """A part of the simulator that this run needs is not installed or not working."""


@dataclass(frozen=True)
class Reference:
    """Truth direction and range of the reference target, from the nominal radar pose.

    Attributes
    ----------
    range_m : float
        Range [m].
    az_deg, el_deg : float
        Direction in frame A at the nominal attitude [deg] (the nominal radar
        frame N of a mounted radar, :mod:`raysim.platform.mounting`).
    """

    range_m: float
    az_deg: float
    el_deg: float

    @property
    def direction(self) -> np.ndarray:
        """Unit vector in A, shape ``[3]``."""
        from raysim.echoes.oracle import direction

        return direction(math.radians(self.az_deg), math.radians(self.el_deg))



# ------------------------------------------------------------------- sources
def point_targets(scenario: Scenario) -> list:
    """The scenario's ``[[scene.targets]]`` as oracle point targets.

    Each target is placed from the nominal radar phase centre (the lever arm,
    body frame B [m]) at ``range_m`` [m] and ``az_deg`` / ``el_deg`` [deg]
    (docs/conventions.md; directions in the nominal radar frame N of the
    scenario's ``radar.mounting_deg``), with its world velocity [m/s] and RCS [dBsm].

    Returns
    -------
    list of raysim.echoes.oracle.PointTarget
        One per target, in file order (a scene of kind ``points`` has targets).
    """
    from raysim.echoes.oracle import PointTarget
    from raysim.platform.mounting import is_default_mounting, nominal_target_position

    mount = scenario.radar.mounting_deg
    if not is_default_mounting(mount):
        return [PointTarget(nominal_target_position(t.range_m, math.radians(t.az_deg),
                                                    math.radians(t.el_deg), scenario.lever_arm,
                                                    mount),
                            np.asarray(t.velocity_mps, dtype=float), t.rcs_dbsm)
                for t in scenario.scene.targets]
    return [PointTarget.at(t.range_m, math.radians(t.az_deg), math.radians(t.el_deg),
                           velocity=t.velocity_mps, rcs_dbsm=t.rcs_dbsm,
                           radar_origin=scenario.lever_arm)
            for t in scenario.scene.targets]


def radar_pose(scenario: Scenario, trajectory) -> tuple:
    """The trajectory and lever arm that place the scenario's radar frame A.

    :func:`raysim.platform.mounting.mount_trajectory` of the body ``trajectory``
    with ``scenario.lever_arm`` and ``scenario.radar.mounting_deg``: every echo
    source (oracle, tracer, clutter field, re-projection) takes the radar's
    position, orientation, element positions and pattern boresight from them.
    The default (``down``) mounting returns ``trajectory`` and the lever arm
    themselves.

    Returns
    -------
    (raysim.platform.motion.Trajectory, ndarray)
        Radar-frame trajectory and lever arm [m], shape ``[3]``.
    """
    from raysim.platform.mounting import mount_trajectory

    return mount_trajectory(trajectory, scenario.lever_arm, scenario.radar.mounting_deg)


def _body_lever(frame: RadarFrame, scenario: Scenario) -> RadarFrame:
    """``frame`` with the scenario's own lever arm (in B) where a mounting turned it."""
    from dataclasses import replace

    from raysim.platform.mounting import is_default_mounting

    if is_default_mounting(scenario.radar.mounting_deg):
        return frame
    return replace(frame, lever_arm=scenario.lever_arm)


def _rt_scene(scenario: Scenario):
    try:
        from raysim.echoes.rt.render import render_scene
        from raysim.echoes.rt.scenes import load_scene
        from raysim.echoes.rt.trace import MonostaticTracer
    except ImportError as exc:
        raise FeatureUnavailable(
            f"scene kind {scenario.scene.kind!r} needs the ray tracer (raysim.echoes.rt with "
            f"Sionna "
            f"RT): {exc}") from None
    target = scenario.scene.name if scenario.scene.kind == "bundled" else scenario.scene.path
    if scenario.scene.kind == "mesh" and not str(target).endswith(".xml"):
        raise ValueError(f"scene.path: got {target!r}, expected a Mitsuba .xml scene file "
                         f"(give mesh files as [[scene.meshes]] entries)")
    cfg = scenario.radar_config()
    if scenario.scene.kind == "meshes":
        from raysim.echoes.rt.user_meshes import convert_user_meshes

        target = convert_user_meshes([m.placement() for m in scenario.scene.meshes],
                                     frequency=cfg.carrier_frequency).xml_path
    try:
        scene = load_scene(target, frequency=cfg.carrier_frequency)
    except ValueError:
        raise
    except Exception as exc:  # backend failures (no LLVM, no GPU) are not bad input
        raise FeatureUnavailable(f"cannot load scene {target!r} with Sionna RT: "
                                 f"{type(exc).__name__}: {exc}") from None
    from raysim.echoes.po.fidelity import resolve_fidelity

    ladder = resolve_fidelity(scenario.scene.fidelity, scenario.virtual_array(),
                              scenario.scene.fidelity_tolerance)
    tracer = MonostaticTracer(max_depth=max(1, scenario.scene.max_depth), seed=scenario.seed,
                              fidelity=ladder)
    return scene, tracer, render_scene


def _clutter(scenario: Scenario):
    """The clutter of a ray-traced scenario: one SceneClutter shared by all its frames."""
    c = scenario.scene.clutter
    if c.mode != "field":
        return c.mode
    from raysim.echoes.ground.field import FieldSettings
    from raysim.echoes.scene_clutter import SceneClutter

    return SceneClutter(FieldSettings(scatterers_per_cell=c.per_cell, reuse_distance=c.reuse_m,
                                       max_scatterers=c.max_scatterers, seed=scenario.seed,
                                       polarisation=scenario.radar.polarisation,
                                       wind_mps=c.wind_mps, vegetation=c.vegetation,
                                       walls=c.walls is not False),
                         ghosts=c.ghosts,
                         movers=[*(_car(m, seed=scenario.seed + i)
                                   for i, m in enumerate(scenario.scene.movers)),
                                 *(_rotor(r) for r in scenario.scene.rotors)])


def _rotor(spec):
    """The :class:`raysim.echoes.moving.rotors.Rotor` of one ``[[scene.rotors]]`` entry."""
    import math

    from raysim.echoes.moving.rotors import Rotor
    from raysim.echoes.moving.scatterers import RigidTrajectory

    hub = (RigidTrajectory(spec.hub_m, heading=math.radians(spec.heading_deg),
                           speed=spec.speed_mps)
           if spec.speed_mps > 0 or spec.heading_deg != 0 else spec.hub_m)
    return Rotor(spec.name, hub, axis=spec.axis, rate=spec.rate, blades=spec.blades,
                 blade_length=spec.blade_length_m, root=spec.root_m,
                 start_angle=math.radians(spec.start_angle_deg),
                 scatterers_per_blade=spec.scatterers_per_blade, rcs_dbsm=spec.rcs_dbsm,
                 rcs_per=spec.rcs_per)


def _car(spec, seed: int = 0):
    """The :class:`raysim.echoes.moving.cars.CarMover` of one ``[[scene.movers]]`` entry."""
    import math

    from raysim.echoes.moving.cars import CarMover
    from raysim.echoes.moving.scatterers import RigidTrajectory

    trajectory = RigidTrajectory(spec.start_m, heading=math.radians(spec.heading_deg),
                                 speed=spec.speed_mps, yaw_rate=math.radians(spec.yaw_rate_dps))
    return CarMover(spec.name, trajectory, spec.length_m, spec.width_m, spec.height_m,
                    seed=seed)


def frame_source(scenario: Scenario, trajectory=None) -> Callable[[int], RadarFrame]:
    """A callable that renders frame ``f`` of the scenario.

    Parameters
    ----------
    scenario : Scenario
    trajectory : Trajectory, optional
        Re-use an already built motion (default: ``scenario.trajectory()``).

    Returns
    -------
    callable
        ``source(f) -> RadarFrame`` with ``data`` ``[chirp, channel, sample]``;
        the callable carries ``source.reference`` (a :class:`Reference` or None).

    Raises
    ------
    FeatureUnavailable
        For a ray-traced scene when Sionna RT cannot be used here.
    """
    from raysim.echoes.oracle import check_frame_memory, simulate_point_targets

    cfg = scenario.radar_config()
    arr = scenario.virtual_array()
    check_frame_memory(cfg, arr, len(scenario.scene.targets), intra_chirp=scenario.intra_chirp)
    traj = scenario.trajectory() if trajectory is None else trajectory
    traj, lever = radar_pose(scenario, traj)
    if scenario.scene.kind == "points":
        targets = point_targets(scenario)

        def source(f: int) -> RadarFrame:
            return _body_lever(simulate_point_targets(
                cfg, arr, targets, traj, lever_arm=lever, frame=f,
                intra_chirp=scenario.intra_chirp, noise=scenario.noise, seed=scenario.seed + f,
                pattern=cfg.pattern), scenario)

        source.reference = reference_target(scenario)
        return source

    scene, tracer, render_scene = _rt_scene(scenario)
    clutter = _clutter(scenario)          # one field for every frame (persistent clutter)

    def rt_source(f: int) -> RadarFrame:
        return _body_lever(render_scene(scene, cfg, arr, traj, lever, tracer=tracer, frame=f,
                                        noise=scenario.noise, seed=scenario.seed + f,
                                        clutter=clutter, **decimation(scenario)), scenario)

    rt_source.reference = reference_target(scenario, scene)
    return rt_source


def decimation(scenario: Scenario) -> dict:
    """``decimate`` and ``decimate_tolerance`` of a scenario's ``[synthesis]`` section,
    as keywords of :func:`raysim.echoes.rt.reproject.synthesize_paths` and ``render_scene``."""
    return {"decimate": scenario.synthesis.decimate,
            "decimate_tolerance": scenario.synthesis.decimate_tolerance}


def reference_target(scenario: Scenario, rt_scene=None) -> Reference | None:
    """Range and direction of the first target seen from the nominal radar pose.

    Point scenes: the first ``[[scene.targets]]`` entry. Ray-traced scenes: the
    first discrete target of the loaded scene (None when it has none), its
    direction in the nominal radar frame N of ``radar.mounting_deg``.
    """
    if scenario.scene.kind == "points":
        t = scenario.scene.targets[0]
        return Reference(t.range_m, t.az_deg, t.el_deg)
    targets = getattr(rt_scene, "targets", None) or []
    if not targets:
        return None
    from raysim.echoes.oracle import az_el
    from raysim.platform.mounting import nominal_direction

    d = nominal_direction(np.asarray(targets[0].position, dtype=float) - scenario.lever_arm,
                          scenario.radar.mounting_deg)
    r = float(np.linalg.norm(d))
    az, el = az_el(d / r)
    return Reference(r, float(np.degrees(az)), float(np.degrees(el)))


class LazyFrames(Sequence):
    """The frames of a scenario, rendered when accessed (frame 0 is kept).

    Analyses of many large frames (the paper's yaw case: 20 frames of 490 MB)
    then hold about two frames in memory instead of all of them, at the price
    of rendering a frame again for every pass over the sequence.
    """

    def __init__(self, source: Callable[[int], RadarFrame], num_frames: int):
        self._source = source
        self._n = int(num_frames)
        self._first: RadarFrame | None = None
        self.reference = getattr(source, "reference", None)

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, f):
        if isinstance(f, slice):
            return [self[i] for i in range(self._n)[f]]
        f = int(f) + (self._n if int(f) < 0 else 0)
        if not 0 <= f < self._n:
            raise IndexError(f"frame {f} out of range (0..{self._n - 1})")
        if f == 0:
            if self._first is None:
                self._first = self._source(0)
            return self._first
        return self._source(f)

    def chirp_times(self) -> np.ndarray:
        """Chirp start times of all frames, frame after frame, shape ``[frame * chirp]`` [s]."""
        cfg = self[0].config
        return np.concatenate([cfg.chirp_times(f) for f in range(self._n)])


def render_frames(scenario: Scenario, trajectory=None) -> list[RadarFrame]:
    """All frames of a scenario in memory (``[chirp, channel, sample]`` each)."""
    source = frame_source(scenario, trajectory)
    return [source(f) for f in range(scenario.frames)]


# ------------------------------------------------- stationary / hover twin
def nominal_at(trajectory, t0: float, axes=None):
    """``trajectory`` moved to start at the nominal pose at ``t0``, on chosen axes only.

    Constant offsets (:class:`raysim.platform.motion.Ramp`) remove its pose at
    ``t0`` on the kept axes, so a radar on it and a stationary radar share the
    pose of the first chirp and differ only by the motion within the frame (a
    static offset would shift the range profile by a fraction of a bin, which
    is no Doppler effect).

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
    t0 : float
        Time at which the pose is nominal [s].
    axes : sequence of str, optional
        Axes of :data:`raysim.platform.motion.AXES` that move (default all six);
        the components on the others are dropped.

    Returns
    -------
    raysim.platform.motion.Trajectory
    """
    from raysim.platform.motion import AXES, Ramp, Trajectory

    axes = AXES if axes is None else tuple(axes)
    if not axes or any(a not in AXES for a in axes) or len(set(axes)) != len(axes):
        raise ValueError(f"axes must be distinct names from {AXES}, got {axes!r}")
    if not math.isfinite(t0):
        raise ValueError(f"t0 must be a finite time [s], got {t0!r}")
    q0 = trajectory.states([t0])[0][0]
    moved = Trajectory(tuple(c for c in trajectory.components if c.axis in axes),
                       name=trajectory.name if len(axes) == len(AXES)
                       else f"{trajectory.name} ({', '.join(axes)})")
    return moved + Trajectory(tuple(Ramp(a, offset=-float(v)) for a, v in zip(AXES, q0,
                                                                              strict=True)
                                    if a in axes), name="nominal pose at t0")


def path_kinds(paths) -> dict:
    """Path count per interaction kind of a :class:`raysim.echoes.rt.trace.PathSet`.

    ``specular`` (single-bounce ground mirror), ``diffuse`` (the clutter
    field's scatterers among them), ``target`` (constant-RCS point targets),
    ``po_centre`` (scattering centres of the geometry targets' meshes, physical
    optics) and ``other_specular`` counts.
    """
    from raysim.echoes.po.paths import PO_CENTRE
    from raysim.echoes.rt.trace import DIFFUSE, SENSING, SPECULAR

    k = paths.kind
    return {"specular": int(np.sum(k == SPECULAR)), "diffuse": int(np.sum((k & DIFFUSE) != 0)),
            "target": int(np.sum((k & SENSING) != 0)),
            "po_centre": int(np.sum((k & PO_CENTRE) != 0)),
            "other_specular": int(np.sum(((k & SPECULAR) != 0) & (k != SPECULAR)
                                         & ((k & (DIFFUSE | SENSING | PO_CENTRE)) == 0)))}


def hover_twin(scenario: Scenario, trajectory, *, samples_per_src: int | None = None,
               nufft_eps: float = 1e-5, path_chunk: int = 1024, movers=(),
               progress: Callable[[str], None] | None = None) -> dict:
    """Frame 0 of a scenario seen by a stationary and by a moving radar, from one trace.

    Ray-traced scenes (``bundled``, ``mesh``, ``meshes``) are traced once at
    the nominal pose at the first chirp (the scenario's tracer, clutter field,
    movers and rotors); the frozen paths and the moving objects' tracks are
    re-projected (:func:`raysim.echoes.rt.reproject.synthesize_paths`, exact
    image method for the specular ground return) onto a radar at rest
    (:func:`raysim.platform.motion.stationary`) and onto ``trajectory``, so the
    two frames differ only by the platform motion within the frame. Point
    scenes render frame 0 with the oracle of :func:`frame_source` twice (the
    frames ``raysim simulate`` renders when ``trajectory`` is the scenario's).
    With ``scenario.noise`` both frames get the same receiver noise (seed
    ``scenario.seed``).

    Parameters
    ----------
    scenario : Scenario
    trajectory : raysim.platform.motion.Trajectory
        Motion of the moving radar (e.g. :func:`nominal_at` of the scenario's).
    samples_per_src : int, optional
        Rays shot by the tracer (default the tracer's).
    nufft_eps : float
        Relative error of the IF synthesis (the frozen paths are decimated along slow
        time as the scenario's ``[synthesis]`` section says, :func:`decimation`).
    path_chunk : int
        Paths re-projected and synthesised at once.
    movers : sequence
        Extra moving objects of a traced scene, driving through it in both
        frames: :class:`raysim.echoes.moving.cars.CarMover`,
        :class:`raysim.echoes.moving.scatterers.MovingObject`, or a callable
        ``mover(scene, ground, t0)`` returning one of them or None (for objects
        placed on the loaded scene's ground).
    progress : callable, optional
        ``progress(message)`` after each step.

    Returns
    -------
    dict
        ``"stationary"``, ``"hover"``: :class:`~raysim.synthesis.frame.RadarFrame`
        (``data`` ``[chirp, channel, sample]``); ``"reference"``
        (:class:`Reference` or None); ``"seconds"`` (trace and synthesis wall
        times [s]). Traced scenes also: ``"paths"``
        (:class:`raysim.echoes.rt.trace.PathSet`), ``"path_kinds"`` (path count
        per kind: ``specular``, ``diffuse``, ``target``, ``po_centre``,
        ``other_specular``; :func:`path_kinds`),
        ``"tracks"``, ``"movers"`` (the MovingObject of every extra mover),
        ``"scene"`` (the loaded scene), ``"clutter"`` (the field's report,
        empty without it), ``"fidelity"`` (the echo model chosen per geometry
        target, :class:`raysim.echoes.po.fidelity.FidelityChoice` as dicts;
        empty for ``[scene] fidelity = "mesh"``).

    Raises
    ------
    FeatureUnavailable
        For a ray-traced scene when Sionna RT cannot be used here.
    """
    import functools
    import time
    from dataclasses import replace

    from raysim.echoes.oracle import add_noise
    from raysim.platform.motion import stationary
    from raysim.synthesis.frame import adc_samples

    if samples_per_src is not None and not (isinstance(samples_per_src, (int, np.integer))
                                            and samples_per_src >= 1):
        raise ValueError(f"samples_per_src must be a positive integer, got {samples_per_src!r}")
    cfg = scenario.radar_config()
    arr = scenario.virtual_array()
    lever = scenario.lever_arm
    seconds: dict = {}
    if scenario.scene.kind == "points":
        out = {}
        for name, motion in (("stationary", stationary()), ("hover", trajectory)):
            t = time.perf_counter()
            out[name] = frame_source(scenario, motion)(0)
            seconds[f"synthesis_{name}"] = time.perf_counter() - t
            if progress:
                progress(f"synthesised {name}")
        return dict(out, reference=reference_target(scenario), seconds=seconds)

    from raysim.echoes.moving.scatterers import synthesize_tracks
    from raysim.echoes.rt.reproject import synthesize_paths
    from raysim.echoes.scene_clutter import SceneClutter
    from raysim.synthesis.select import synthesize

    t = time.perf_counter()
    scene, tracer, _ = _rt_scene(scenario)
    if samples_per_src is not None:
        tracer = replace(tracer, samples_per_src=int(samples_per_src))
    clutter = _clutter(scenario)
    model = clutter if isinstance(clutter, SceneClutter) else None
    if model is not None:
        tracer = model.tracer(tracer)
    elif clutter == "none":
        tracer = replace(tracer, diffuse=False)
    t0 = float(cfg.chirp_times()[0])
    rest, lever_a = radar_pose(scenario, stationary())    # the radar frame A's pose
    paths = tracer(scene, cfg, rest, lever_a, time=t0)
    tracks = []
    if model is not None:
        paths, tracks = model.paths(scene, paths, cfg, arr, rest, lever_a, time=t0)
    radar_w = rest.point_world([t0], lever_a)[0, 0]
    ground = None                      # cars are located on and traced with the ground
    if movers:
        from raysim.echoes.ground.surface import GroundSurface

        ground = model.ground if model is not None else GroundSurface.from_scene(scene)
    cars = [m(scene, ground, t0) if callable(m) and not hasattr(m, "tracks") else m
            for m in movers]
    objects = [m.moving_object(cfg, radar_w, time=t0, ground=ground)
               if hasattr(m, "moving_object") else m for m in cars if m is not None]
    tracks = tracks + [m.tracks(cfg, radar_w, time=t0) for m in objects]
    seconds["trace"] = time.perf_counter() - t
    if progress:
        progress("traced")
    # moving points at this eps; frozen paths: synthesize_paths takes the compact way
    # (fused kernel, no [path, chirp, channel] delays) for the clutter field
    synth = functools.partial(synthesize, eps=nufft_eps)
    out = {"paths": paths, "path_kinds": path_kinds(paths), "tracks": tracks, "scene": scene,
           "movers": objects, "clutter": model.summary() if model is not None else {},
           "fidelity": [] if tracer.fidelity is None else tracer.fidelity.report(),
           "reference": reference_target(scenario, scene)}
    for name, motion in (("stationary", rest), ("hover", radar_pose(scenario, trajectory)[0])):
        t = time.perf_counter()
        data, _ = synthesize_paths(paths, cfg, arr, motion, lever_a, path_chunk=path_chunk,
                                   eps=nufft_eps,
                                   modulation=None if model is None else model.modulation,
                                   **decimation(scenario))
        synthesize_tracks(tracks, cfg, arr, motion, lever_a, out=data, synthesizer=synth)
        if scenario.noise:
            add_noise(data, cfg, scenario.seed)
        out[name] = RadarFrame(adc_samples(data, cfg), cfg, arr, cfg.chirp_times(), lever, 0,
                               {"scene": scene.name, "trajectory": motion.name,
                                "num_paths": paths.num_paths})
        seconds[f"synthesis_{name}"] = time.perf_counter() - t
        if progress:
            progress(f"synthesised {name}")
    out["seconds"] = seconds
    return out


def gated_source(config, array, trajectory, targets, *, range_m: float,
                 lever_arm=(0.0, 0.0, 0.0), t0: float = 0.0):
    """The gated oracle as a source: one frame's range gate nearest ``range_m``, in closed form.

    The fast source of studies that need one range gate only
    (:func:`raysim.echoes.gated.gated_cube`: equal to the point oracle's
    Hann range compression at that bin), with the element pattern of ``config``
    (``config.pattern``) as every point source.

    Parameters
    ----------
    config : raysim.radar.config.RadarConfig
        Waveform (complex sampling); one frame starting at ``t0`` [s].
    array : raysim.radar.arrays.VirtualArray
    trajectory : raysim.platform.motion.Trajectory
        Truth body motion.
    targets : sequence of raysim.echoes.oracle.PointTarget
    range_m : float
        Range of the gate [m]; the nearest unpadded range bin is used.
    lever_arm : array_like, shape ``[3]``
        Radar origin in B [m].

    Returns
    -------
    gate : ndarray, shape ``[chirp, channel]``, complex128
        Range-compressed samples at the gate [sqrt(W)].
    bin : int
        Range bin of the gate (unpadded FFT).
    gate_range_m : float
        Range of that bin [m].
    """
    from raysim.echoes.gated import gated_cube, nearest_range_bin

    m = nearest_range_bin(config, range_m)
    gate = gated_cube(config, array, trajectory, list(targets), range_bin=m,
                      lever_arm=lever_arm, t0=t0, pattern=config.pattern)
    return gate, m, float(config.range_axis(config.num_samples)[m])
