"""Render a ray-traced IF frame: load a scene, trace once, re-project per chirp, synthesise."""

from __future__ import annotations

import os

import numpy as np

from raysim.echoes.oracle import add_noise
from raysim.echoes.rt.reproject import IF_BAND_MODES, SPECULAR_MODES, synthesize_paths
from raysim.echoes.rt.scenes import RadarScene, SceneDescriptor, load_scene
from raysim.echoes.rt.trace import MonostaticTracer, PathSet
from raysim.platform.motion import Trajectory, stationary
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig
from raysim.synthesis.frame import RadarFrame, adc_samples


def render_scene(scene: str | os.PathLike | SceneDescriptor | RadarScene, config: RadarConfig,
                 array: VirtualArray, trajectory: Trajectory | None = None,
                 lever_arm=(0.0, 0.0, 0.0), *, tracer: MonostaticTracer | None = None,
                 frame: int = 0, t0: float = 0.0, retrace_every: int | None = None,
                 if_band: str = "cull", path_chunk: int = 256,
                 hover_altitude: float | None = None, noise: bool = False,
                 seed: int | None = None, synthesizer=None,
                 specular: str = "image", clutter="field", decimate="auto",
                 decimate_tolerance: float | None = None, fidelity="mesh",
                 fidelity_tolerance: float | None = None) -> RadarFrame:
    """Simulate one IF frame of a ray-traced scene seen from a moving platform.

    The scene is traced once from the radar's pose at the first chirp of the
    frame (or every ``retrace_every`` chirps), the scattering points are
    frozen, and every path's length is re-projected to the actual transmit and
    receive element positions of every chirp and channel
    (:mod:`raysim.echoes.rt.reproject`) before IF synthesis.

    Parameters
    ----------
    scene : str, path-like, SceneDescriptor or RadarScene
        Registry name (``raysim.echoes.rt.scenes.SCENES``), XML path, descriptor, or an
        already loaded scene (re-used, e.g. across frames).
    config : RadarConfig
        Waveform; ``config.max_range`` sets the range window.
    array : VirtualArray
        Virtual channels in frame A.
    trajectory : Trajectory, optional
        Body motion; stationary if omitted.
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    tracer : MonostaticTracer, optional
        Tracing options (default: ``MonostaticTracer()``).
    frame : int
        Frame index; chirp times are ``config.chirp_times(frame, t0)``.
    t0 : float
        First chirp of frame 0 [s].
    retrace_every : int, optional
        Trace again from the current pose every this many chirps. Diffuse hit
        points are re-sampled at each trace, so clutter decorrelates between
        blocks; leave ``None`` (one trace per frame) for coherent clutter.
    if_band : {"cull", "taper", "none"}
        Treatment of paths beyond ``config.max_range`` (see ``reproject``).
    path_chunk : int
        Paths re-projected and synthesised at once (memory bound).
    hover_altitude : float, optional
        Override of the scene's hover altitude [m] (when ``scene`` is not loaded).
    noise : bool
        Add thermal noise ``k T0 F f_s`` per complex sample.
    seed : int, optional
        Noise seed.
    synthesizer : callable, optional
        IF synthesis ``f(tau, amplitude, config, out=cube)`` (default
        :func:`raysim.synthesis.select.synthesize`, which picks the tone sum
        or the NUFFT by path count at ``eps = 1e-6``).
    specular : {"image", "frozen"}
        Re-projection of single-bounce specular paths: exact image method
        (default) or frozen reflection point (see :mod:`raysim.echoes.rt.reproject`).
    clutter : {"field", "sionna", "none"} or SceneClutter
        Ground clutter and multipath: a persistent clutter field with rough-surface
        specular, target-ground ghosts and moving objects
        (:class:`raysim.echoes.scene_clutter.SceneClutter`; pass one instance to
        every frame to keep the field across frames; ``"field"`` makes a fresh
        one), Sionna's own diffuse paths (``"sionna"``), or no diffuse paths.
    decimate : {"auto", "off"} or int
        Slow-time decimation of the frozen paths (see
        :func:`raysim.echoes.rt.reproject.synthesize_paths`); ``"auto"`` by default.
    decimate_tolerance : float, optional
        Relative error allowed to its interpolation (default 0.1 x the synthesis eps).
    fidelity : {"mesh", "auto", "point", "centres"} or FidelityLadder
        Echo model of each geometry target (:mod:`raysim.echoes.po.fidelity`):
        its full PO + SBR centres (``"mesh"``, default), a forced reduced level,
        or the cheapest level within ``fidelity_tolerance`` of the mesh
        (``"auto"``); pass one ladder to every frame to re-use reduced models.
    fidelity_tolerance : float, optional
        Relative l2 error allowed to each object's echo (default
        :data:`raysim.echoes.po.fidelity.DEFAULT_FIDELITY_TOLERANCE`).

    Returns
    -------
    RadarFrame
        ``data`` [chirp, channel, sample] complex64 [sqrt(W)]; ``truth`` holds
        ``scene``, ``trajectory``, ``paths`` (the first :class:`PathSet`),
        ``num_traces``, ``num_paths``, ``dropped`` (counts per cull) and
        ``clutter`` (the field's report, empty without a field) and ``fidelity``
        (the ladder's choices of this frame, :class:`~raysim.echoes.po.fidelity.FidelityChoice`
        as dicts; empty for ``"mesh"``).
    """
    from dataclasses import replace

    from raysim.echoes.moving.scatterers import synthesize_tracks
    from raysim.echoes.po.fidelity import resolve_fidelity
    from raysim.echoes.scene_clutter import resolve_clutter

    if not isinstance(config, RadarConfig):
        raise ValueError(f"config must be a RadarConfig, got {type(config)}")
    if not isinstance(array, VirtualArray):
        raise ValueError(f"array must be a VirtualArray, got {type(array)}")
    if if_band not in IF_BAND_MODES:
        raise ValueError(f"if_band must be one of {IF_BAND_MODES}, got {if_band!r}")
    if specular not in SPECULAR_MODES:
        raise ValueError(f"specular must be one of {SPECULAR_MODES}, got {specular!r}")
    if retrace_every is not None and (int(retrace_every) != retrace_every or retrace_every < 1):
        raise ValueError(f"retrace_every must be a positive integer or None, "
                         f"got {retrace_every!r}")
    trajectory = stationary() if trajectory is None else trajectory
    tracer = MonostaticTracer() if tracer is None else tracer
    ladder = resolve_fidelity(fidelity, array, fidelity_tolerance)
    if ladder is not None:
        tracer = replace(tracer, fidelity=ladder)
    ladder = tracer.fidelity
    num_choices = 0 if ladder is None else len(ladder.choices)
    model = resolve_clutter(clutter)
    if model is not None:
        tracer = model.tracer(tracer)
    elif clutter == "none":
        tracer = replace(tracer, diffuse=False)
    if not isinstance(scene, RadarScene):
        scene = load_scene(scene, frequency=config.carrier_frequency,
                           hover_altitude=hover_altitude)
    lever = np.asarray(lever_arm, dtype=float)
    chirp_times = config.chirp_times(frame, t0)
    n = config.num_chirps
    block = n if retrace_every is None else int(retrace_every)
    data = np.zeros((n, array.num_channels, config.num_samples), dtype=np.complex64)
    dropped: dict[str, int] = {}
    first: PathSet | None = None
    num_paths = 0
    for c0 in range(0, n, block):
        c1 = min(c0 + block, n)
        paths = tracer(scene, config, trajectory, lever, time=float(chirp_times[c0]))
        tracks = []
        if model is not None:
            paths, tracks = model.paths(scene, paths, config, array, trajectory, lever,
                                        time=float(chirp_times[c0]))
        first = paths if first is None else first
        num_paths += paths.num_paths
        _, cut = synthesize_paths(paths, config, array, trajectory, lever, out=data[c0:c1],
                                  chirps=np.arange(c0, c1), path_chunk=path_chunk, frame=frame,
                                  t0=t0, if_band=if_band, synthesizer=synthesizer,
                                  specular=specular, decimate=decimate,
                                  decimate_tolerance=decimate_tolerance,
                                  modulation=None if model is None else model.modulation)
        cut += synthesize_tracks(tracks, config, array, trajectory, lever, out=data[c0:c1],
                                 chirps=np.arange(c0, c1), frame=frame, t0=t0, if_band=if_band,
                                 synthesizer=synthesizer)
        for k, v in paths.dropped.items():
            dropped[k] = dropped.get(k, 0) + v
        dropped["if_band"] = dropped.get("if_band", 0) + cut
    if noise:
        add_noise(data, config, seed)
    truth = {"scene": scene.name, "trajectory": trajectory.name, "paths": first,
             "num_traces": len(range(0, n, block)), "num_paths": num_paths, "dropped": dropped,
             "clutter": {} if model is None else model.summary(),
             "fidelity": [] if ladder is None else ladder.report()[num_choices:]}
    return RadarFrame(adc_samples(data, config), config, array, chirp_times, lever, frame, truth)
