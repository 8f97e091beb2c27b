"""Speed-versus-accuracy chart: time per frame against error for each fidelity knob.

For every knob the simulator exposes, :func:`measure_knobs` renders the same
scene at each setting and records the time per paper frame (256 chirps) and
the relative l2 error of the IF cube against the knob's highest-fidelity
setting. :func:`draw_chart` draws one panel per knob, marks the Pareto front
(no other setting is both faster and more accurate) and highlights the
default. Knobs:

``nufft_eps``
    NUFFT tolerance ``eps`` (reference: the complex128 direct sum), 2,000
    ground paths of a drone hovering 20 m up.
``motion``
    Stop-and-hop (pose frozen per chirp, default) against intra-chirp motion
    (delays at every sample, the reference), one target at 15 m, paper
    pitch oscillation 10 deg at 20 Hz.
``geometry``
    Plane-wave element delays (range and direction at the array centroid)
    against the exact spherical delays (default and reference), 2,000 ground
    paths from 2 m to 60 m.
``kernel_eps``
    Tolerance ``eps`` of the fused C++ kernel (``method="kernel"``, reference:
    the complex128 direct sum), the same 2,000 hover paths as ``nufft_eps``.
``decimation``
    Slow-time decimation off (``decimate=1``, default and reference) against
    ``decimate="auto"`` (exact rows on every D-th chirp, Kaiser-sinc
    interpolation between), fused kernel at ``eps = 1e-5``, whole slow time.
    Both kernel knobs need the compiled extension; without it they are left
    out and ``not_measured`` says so. (A tube-density knob of a scattering
    engine is not drawn: no such engine exists yet.)
``chirp_block``
    Chirps synthesised per block in :func:`raysim.synthesis.streaming.render_stream`
    (memory against per-call overhead); same values, so only time differs.

Ray-tracing knobs (:func:`measure_rt_knobs`, bundled scene
:data:`RT_SCENE`, 8 x 8 UPA, seeded hover, NUFFT synthesis; time = trace +
re-projection + synthesis of one frame of :data:`RT_CHIRPS` chirps):

``rt_samples``
    Rays shot per trace (``MonostaticTracer.samples_per_src``), reference
    :data:`RT_REFERENCE_SAMPLES`.
``rt_depth``
    Bounces of scene-geometry paths (``max_depth``), reference 3.
``rt_retrace``
    Trace once per frame and re-project (``render_scene(retrace_every=None)``)
    against a fresh trace every K chirps. Reference: trace once, because a
    re-trace re-samples the diffuse hit points (they move with the radar and
    get new random phases), so re-tracing is the approximation here, not the
    exact model.

Their error is that of the channel-averaged range-Doppler power map, not of
the IF cube: two diffuse samplings are independent speckle realisations, so
the cube error between any two sample counts is the clutter's share of the
cube norm whatever the count (see docs/speed.md). Without Sionna RT's LLVM
backend the three panels are skipped and ``not_measured`` says why.

Dominance uses :data:`TIME_TOLERANCE`: a setting dominates another only if it
is faster by more than that fraction (timing noise on a shared machine) and
not less accurate, or at least as fast and strictly more accurate.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

#: Resolution of the PNG (9 panels at 90 dpi stay below 300 kB for docs/).
CHART_DPI = 90
#: Relative timing difference below which two settings count as equally fast.
TIME_TOLERANCE = 0.10
#: Paths of the multipath knobs (the chirp-block knob uses a quarter).
KNOB_PATHS = 2_000
#: Timing repeats per setting (best of); tests raise it for tiny, noisy problems.
REPEAT = 1
#: Error plotted for the reference setting itself (zero on a log axis).
REFERENCE_ERROR_FLOOR = 1e-9
#: Defaults of the simulator, per knob.
DEFAULTS = {"nufft_eps": "1e-06", "motion": "stop-and-hop", "geometry": "spherical",
            "chirp_block": "16", "kernel_eps": "1e-06", "decimation": "auto"}
#: Bundled scene of the ray-tracing knobs.
RT_SCENE = "rough_terrain"
#: Chirps per ray-traced frame (quick, full).
RT_CHIRPS = {True: 32, False: 64}
#: Side of the UPA of the ray-tracing knobs.
RT_ARRAY = 8
#: Sample counts of the ``rt_samples`` knob (quick, full); the default is added if missing.
RT_SAMPLES = {True: (1_000, 10_000, 100_000),
              False: (1_000, 3_000, 10_000, 30_000, 100_000)}
#: Highest-fidelity sample count (reference of ``rt_samples``).
RT_REFERENCE_SAMPLES = 300_000
#: Depths of the ``rt_depth`` knob (the largest is the reference).
RT_DEPTHS = (1, 2, 3)
#: Re-trace intervals K of the ``rt_retrace`` knob (quick, full); ``None`` = trace once.
RT_RETRACE = {True: (None, 8, 1), False: (None, 16, 4, 1)}
#: NUFFT tolerance of the ray-traced frames (``scene_report`` settings).
RT_EPS = 1e-5


def pareto_front(times, errors, *, time_tolerance: float = TIME_TOLERANCE) -> np.ndarray:
    """Mask of the settings no other setting dominates.

    Parameters
    ----------
    times : array_like, shape ``[setting]``
        Time per frame [s].
    errors : array_like, shape ``[setting]``
        Relative error (dimensionless).
    time_tolerance : float
        Fraction by which a setting must be faster to dominate on time.

    Returns
    -------
    ndarray of bool, shape ``[setting]``
    """
    t = np.asarray(times, dtype=float)
    e = np.asarray(errors, dtype=float)
    if t.shape != e.shape or t.ndim != 1:
        raise ValueError(f"times and errors must be 1-D of equal length, got {t.shape}, {e.shape}")
    if not 0 <= time_tolerance < 1:
        raise ValueError(f"time_tolerance must lie in [0, 1), got {time_tolerance!r}")
    front = np.ones(t.size, dtype=bool)
    for i in range(t.size):
        faster = t < t[i] * (1 - time_tolerance)
        more_accurate = (e < e[i]) & ~np.isclose(e, e[i], rtol=1e-3)
        dominated = (faster & (e <= e[i] * (1 + 1e-3))) | ((t <= t[i]) & more_accurate)
        dominated[i] = False
        front[i] = not dominated.any()
    return front


def _rel(x, ref) -> float:
    return float(np.linalg.norm(np.asarray(x) - ref) / np.linalg.norm(ref))


def _cpu(fn: Callable, *args, repeat: int = 1, **kwargs):
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.process_time()
        out = fn(*args, **kwargs)
        best = min(best, time.process_time() - t0)
    return best, out


def _knob(name: str, label: str, settings: list[dict], note: str, *,
          default: str | None = None, time_label: str | None = None) -> dict:
    times = [s["s_per_frame"] for s in settings]
    errors = [max(s["rel_error"], REFERENCE_ERROR_FLOOR) for s in settings]
    front = pareto_front(times, errors)
    default = DEFAULTS[name] if default is None else default
    for s, f in zip(settings, front, strict=True):
        s["pareto"] = bool(f)
        # a setting's label may carry what it chose in brackets: "auto (D=20/3)"
        s["default"] = s["setting"].split(" (")[0] == default
    return {"knob": name, "label": label, "default": default, "note": note,
            "time_label": time_label or "time per paper frame [CPU s]",
            "default_on_front": bool(any(s["pareto"] for s in settings if s["default"])),
            "settings": settings}


def _tolerance_knob(method: str, eps_values, *, quick: bool, repeat: int, name: str,
                    label: str, note: str) -> dict:
    """Time and error of a synthesis method over its tolerances, and the direct sum.

    One thread; timed on a few chirps x all 400 channels of :data:`KNOB_PATHS` hover
    paths (best of ``repeat`` interleaved runs), error on 1 chirp x 16 channels
    against the complex128 direct sum; times scaled to a whole paper frame.
    """
    from raysim.bench.workloads import hover_paths, paper_setup, subset
    from raysim.synthesis.select import synthesize

    cfg, arr, traj, lever = paper_setup()
    pd = hover_paths(KNOB_PATHS, cfg, arr, traj, lever, seed=11)
    n_t = 2 if quick else 8
    timed = subset(pd, n_t, arr.num_channels)
    acc = subset(pd, 1, 16)
    ref = synthesize(acc, None, cfg, method="direct")
    best = dict.fromkeys(eps_values, np.inf)
    for _ in range(repeat):                             # interleaved repeats (load drift)
        for eps in eps_values:
            t, _ = _cpu(synthesize, timed, None, cfg, method=method, eps=eps, threads=1)
            best[eps] = min(best[eps], t)
    settings = [{"setting": f"{eps:.0e}", "s_per_frame": best[eps] * cfg.num_chirps / n_t,
                 "rel_error": _rel(synthesize(acc, None, cfg, method=method, eps=eps), ref)}
                for eps in eps_values]
    n_dir = 8 if quick else 32
    t_dir, _ = _cpu(synthesize, subset(pd, 1, n_dir), None, cfg, method="direct")
    settings.append({"setting": "direct", "s_per_frame": t_dir * cfg.num_chirps * (
        arr.num_channels / n_dir), "rel_error": 0.0, "reference": True})
    return _knob(name, label, settings, note.format(n_t=n_t))


def measure_nufft_eps(*, quick: bool) -> dict:
    """NUFFT tolerance against the direct sum (2,000 hover paths)."""
    eps_values = (1e-2, 1e-4, 1e-6, 1e-7) if quick else (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7)
    return _tolerance_knob("nufft", eps_values, quick=quick,
                           repeat=max(REPEAT, 1 if quick else 2), name="nufft_eps",
                           label=f"NUFFT tolerance eps ({KNOB_PATHS:,} paths)",
                           note="timed on {n_t} chirps x 400 channels, error on 1 chirp x 16 "
                                "channels")


def measure_kernel_eps(*, quick: bool) -> dict:
    """Fused kernel tolerance against the direct sum (2,000 hover paths, one thread)."""
    return _tolerance_knob("kernel", (1e-3, 1e-4, 1e-5, 1e-6), quick=quick,
                           repeat=max(REPEAT, 2), name="kernel_eps",
                           label=f"fused kernel eps ({KNOB_PATHS:,} paths)",
                           note="one thread, timed on {n_t} chirps x 400 channels, error on 1 "
                                "chirp x 16 channels against the complex128 direct sum")


def measure_decimation(*, quick: bool) -> dict:
    """Slow-time decimation off (reference) and auto, fused kernel at eps 1e-5."""
    from raysim.bench.workloads import hover_paths, paper_setup, subset
    from raysim.synthesis.decimate import plan_groups
    from raysim.synthesis.select import DECIMATION_EPS_SHARE, synthesize

    eps = 1e-5
    cfg, arr, traj, lever = paper_setup()
    pd = hover_paths(KNOB_PATHS, cfg, arr, traj, lever, seed=11)
    n_ch = 16 if quick else 40
    timed = subset(pd, cfg.num_chirps, n_ch)
    groups = plan_groups(timed, cfg, cfg.num_chirps, DECIMATION_EPS_SHARE * eps, "auto")
    factors = "/".join(str(p.factor) for _, p in groups)
    best = {1: np.inf, "auto": np.inf}
    for _ in range(max(REPEAT, 2)):
        for d in best:
            t, _ = _cpu(synthesize, timed, None, cfg, method="kernel", eps=eps, threads=1,
                        decimate=d)
            best[d] = min(best[d], t)
    acc = subset(pd, cfg.num_chirps, 4)
    ref = synthesize(acc, None, cfg, method="kernel", eps=eps)
    scale = arr.num_channels / n_ch
    settings = [
        {"setting": "off", "s_per_frame": best[1] * scale, "rel_error": 0.0, "reference": True},
        {"setting": f"auto (D={factors})", "s_per_frame": best["auto"] * scale,
         "rel_error": _rel(synthesize(acc, None, cfg, method="kernel", eps=eps,
                                      decimate="auto"), ref)},
    ]
    return _knob("decimation", "slow-time decimation (kernel, eps 1e-5)", settings,
                 f"one thread, all 256 chirps x {n_ch} channels timed, scaled to 400; error on "
                 "256 chirps x 4 channels against decimation off; plan: "
                 + "; ".join(f"{g.size} paths: {p.reason}" for g, p in groups))


def measure_motion(*, quick: bool) -> dict:
    """Stop-and-hop against intra-chirp motion (one target, pitch 10 deg at 20 Hz)."""
    from raysim.bench.workloads import paper_setup
    from raysim.echoes.oracle import simulate_point_targets
    from raysim.pipeline.sources import point_targets
    from raysim.scenario import scenario_from_case

    case = scenario_from_case("rotation_y")
    n_c = 8 if quick else 32
    cfg = case.radar_config().with_(num_chirps=n_c)
    arr = paper_setup(n_c)[1]                      # the paper's 20 x 20 UPA
    tgt = point_targets(case)
    traj = case.trajectory()
    scale = case.radar.num_chirps / n_c
    t_ref, ref = _cpu(simulate_point_targets, cfg, arr, tgt, traj,
                      lever_arm=case.lever_arm, intra_chirp=True, repeat=REPEAT)
    t_sh, sh = _cpu(simulate_point_targets, cfg, arr, tgt, traj,
                    lever_arm=case.lever_arm, intra_chirp=False, repeat=REPEAT)
    settings = [
        {"setting": "stop-and-hop", "s_per_frame": t_sh * scale,
         "rel_error": _rel(sh.data, ref.data.astype(np.complex128))},
        {"setting": "intra-chirp", "s_per_frame": t_ref * scale, "rel_error": 0.0,
         "reference": True},
    ]
    return _knob("motion", "platform motion within a chirp (rotation_y case)", settings,
                 f"timed on {n_c} chirps x 400 channels")


def plane_wave_delays(paths, chirp: int) -> np.ndarray:
    """Plane-wave approximation of :meth:`PathDelays.delays`, shape ``[channel, path]`` [s].

    Each leg is the exact distance to the array centroid minus the projection
    of the element offset on the unit direction of the vertex (far-field).
    """
    from raysim.radar.config import SPEED_OF_LIGHT

    x = paths.tx_positions[chirp]
    c = x.mean(axis=0)
    off = x - c

    def leg(v):
        r = v - c
        dist = np.linalg.norm(r, axis=1)
        u = r / dist[:, None]
        return dist[None, :] - off @ u.T

    first = paths.first_vertex if paths.first_vertex.ndim == 2 else paths.first_vertex[:, chirp]
    last = paths.last_vertex if paths.last_vertex.ndim == 2 else paths.last_vertex[:, chirp]
    length = paths.interior_length if paths.interior_length.ndim == 1 \
        else paths.interior_length[:, chirp]
    return (leg(first) + leg(last) + length) / SPEED_OF_LIGHT


def measure_geometry(*, quick: bool) -> dict:
    """Plane-wave against exact spherical element delays (2,000 near ground paths)."""
    from raysim.bench.workloads import paper_setup
    from raysim.synthesis.nufft import PathDelays, synthesize_nufft

    cfg, arr, traj, lever = paper_setup()
    rng = np.random.default_rng(12)
    n = KNOB_PATHS
    r = rng.uniform(2.0, 60.0, n)
    ang = rng.uniform(-np.pi, np.pi, n)
    h = np.minimum(r, 2.0 + rng.uniform(0, 18.0, n))
    g = np.sqrt(np.maximum(r**2 - h**2, 0.0))
    pts = np.stack([g * np.cos(ang), g * np.sin(ang), h], axis=1)
    amp = np.exp(2j * np.pi * rng.random(n)) / r**2
    n_t = 2 if quick else 8
    pd = PathDelays.for_array(pts, pts, np.zeros(n), amp, cfg.with_(num_chirps=n_t), arr, traj,
                              lever_arm=lever)
    scale = cfg.num_chirps / n_t

    def render(delay_fn):
        out = np.zeros((n_t, arr.num_channels, cfg.num_samples), np.complex64)
        for k in range(n_t):
            tau = delay_fn(pd, k)                                  # [channel, path]
            synthesize_nufft(tau.T[:, None, :], np.broadcast_to(amp[:, None, None],
                                                                (n, 1, arr.num_channels)),
                             cfg.with_(num_chirps=1), eps=1e-6, out=out[k:k + 1], threads=1)
        return out

    t_sph, sph = _cpu(render, lambda p, k: p.delays(k), repeat=REPEAT)
    t_pw, pw = _cpu(render, plane_wave_delays, repeat=REPEAT)
    settings = [
        {"setting": "spherical", "s_per_frame": t_sph * scale, "rel_error": 0.0,
         "reference": True},
        {"setting": "plane-wave", "s_per_frame": t_pw * scale, "rel_error": _rel(pw, sph)},
    ]
    return _knob("geometry", f"element geometry ({KNOB_PATHS:,} paths, 2-60 m)", settings,
                 f"timed on {n_t} chirps x 400 channels, NUFFT eps 1e-6 for both")


def measure_chirp_block(*, quick: bool) -> dict:
    """Chirp block size of the streaming renderer (500 paths, 8 x 8 array, 256 chirps)."""
    from raysim.bench.workloads import hover_paths, paper_setup
    from raysim.radar.arrays import upa
    from raysim.synthesis.select import synthesize
    from raysim.synthesis.streaming import render_stream

    cfg, _, traj, lever = paper_setup()
    arr = upa(8, 8, wavelength=cfg.wavelength)
    pd = hover_paths(KNOB_PATHS // (10 if quick else 4), cfg, arr, traj, lever, seed=13)
    ref = synthesize(pd, None, cfg, method="direct", chirps=range(2))
    blocks = (1, 16, 256) if quick else (1, 4, 16, 64, 256)
    first: dict[int, np.ndarray] = {}
    best = dict.fromkeys(blocks, np.inf)
    # repeats interleaved over the settings, so load changes hit all of them alike
    for _ in range(max(REPEAT, 1 if quick else 3)):
        for b in blocks:
            def keep(f, n0, block, b=b):
                if n0 == 0:
                    first[b] = block[:2].copy()

            t, _ = _cpu(render_stream, lambda f: pd, cfg, keep, chirp_block=b, method="nufft",
                        eps=1e-6, threads=1, progress=False)
            best[b] = min(best[b], t)
    settings = [{"setting": str(b), "s_per_frame": best[b],
                 "rel_error": _rel(first[b], ref) if b >= 2 else None} for b in blocks]
    common = max(s["rel_error"] for s in settings if s["rel_error"] is not None)
    for s in settings:
        if s["rel_error"] is None:
            s["rel_error"] = common
    return _knob("chirp_block", "chirps per block (streaming, 8 x 8 array)", settings,
                 "whole 256-chirp frames; blocks give identical samples, error vs direct sum")


def rd_power_map(cube: np.ndarray) -> np.ndarray:
    """Channel-averaged range-Doppler power ``[doppler, range]`` (Hann windows, no shift).

    Parameters
    ----------
    cube : ndarray, shape ``[chirp, channel, sample]``

    Returns
    -------
    ndarray, shape ``[chirp, sample]``, float64
    """
    c = np.asarray(cube, dtype=np.complex128)
    r = np.fft.fft(c * np.hanning(c.shape[2])[None, None, :], axis=2)
    d = np.fft.fft(r * np.hanning(c.shape[0])[:, None, None], axis=0)
    return np.mean(np.abs(d) ** 2, axis=1)


def _samples_label(n: int) -> str:
    m, e = f"{n:.0e}".split("e")
    return f"{m}e{int(e)}"


def rt_defaults() -> dict:
    """Defaults of the ray-tracing knobs, read from ``MonostaticTracer`` and ``render_scene``."""
    import dataclasses
    import inspect

    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    f = {x.name: x.default for x in dataclasses.fields(MonostaticTracer)}
    k = inspect.signature(render_scene).parameters["retrace_every"].default
    return {"samples_per_src": int(f["samples_per_src"]), "max_depth": int(f["max_depth"]),
            "retrace_every": k}


def measure_rt_knobs(*, quick: bool, log: Callable[[str], None] = print,
                     threads: int | None = None) -> list[dict]:
    """Ray-tracing knobs: trace samples, depth, re-trace interval (needs Sionna RT).

    One ray-traced frame of :data:`RT_SCENE` (``RT_CHIRPS[quick]`` chirps,
    ``RT_ARRAY`` x ``RT_ARRAY`` UPA, 77 GHz paper waveform, seeded hover of
    ``scene_report``) is rendered per setting with :func:`raysim.echoes.rt.render_scene`
    and NUFFT synthesis (eps :data:`RT_EPS`, one thread); the CPU time covers
    trace, re-projection and synthesis. Error: relative l2 of
    :func:`rd_power_map` against the knob's reference.

    Raises
    ------
    raysim.echoes.rt.backend.BackendError
        When Sionna RT's LLVM backend cannot run here.
    """
    import functools

    from raysim.echoes.rt import backend
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.radar.arrays import upa
    from raysim.radar.config import RadarConfig
    from raysim.studies.scene_report import hover_trajectory
    from raysim.synthesis.nufft import synthesize_nufft

    backend.configure("cpu", threads=threads)
    d = rt_defaults()
    n_c = RT_CHIRPS[bool(quick)]
    cfg = RadarConfig(num_chirps=n_c, idle_time=180e-6)
    arr = upa(RT_ARRAY, RT_ARRAY, wavelength=cfg.wavelength)
    traj = hover_trajectory(7, float(cfg.chirp_times()[0]))
    lever = (0.0, 0.0, 0.1)
    scene = load_scene(RT_SCENE, frequency=cfg.carrier_frequency)
    MonostaticTracer(samples_per_src=1_000)(scene, cfg)          # compile the kernels first
    synth = functools.partial(synthesize_nufft, eps=RT_EPS, threads=1)
    cache: dict[tuple, tuple[float, np.ndarray, int]] = {}

    def render(samples: int, depth: int, retrace) -> tuple[float, np.ndarray, int]:
        key = (samples, depth, retrace)
        if key not in cache:
            tracer = MonostaticTracer(samples_per_src=samples, max_depth=depth)
            # clutter="sionna": these knobs act on Sionna's own diffuse paths
            t, f = _cpu(render_scene, scene, cfg, arr, traj, lever, tracer=tracer,
                        retrace_every=retrace, synthesizer=synth, repeat=REPEAT,
                        clutter="sionna")
            cache[key] = (t, rd_power_map(f.data), int(f.truth["num_paths"]))
            log(f"    samples {samples}, depth {depth}, retrace {retrace}: {t:.2f} CPU s, "
                f"{cache[key][2]} paths")
        return cache[key]

    def knob(name, label, keys, ref_key, names, default_name, note):
        ref = render(*ref_key)[1]
        settings = []
        for key, setting in zip(keys, names, strict=True):
            t, rd, n = render(*key)
            floor = 1e-12 * ref.max()           # dB difference of the clutter floor, too
            db = 10 * np.log10((rd + floor) / (ref + floor))
            s = {"setting": setting, "s_per_frame": t, "rel_error": _rel(rd, ref), "paths": n,
                 "rd_db_rms": float(np.sqrt(np.mean(db ** 2)))}
            if key == ref_key:
                s["reference"] = True
            settings.append(s)
        return _knob(name, label, settings, note, default=default_name,
                     time_label=f"time per {n_c}-chirp frame [CPU s]")

    samples = sorted(set(RT_SAMPLES[bool(quick)]) | {d["samples_per_src"],
                                                     RT_REFERENCE_SAMPLES})
    setup = (f"{RT_SCENE}, {n_c} chirps x {RT_ARRAY}x{RT_ARRAY} UPA, hover, NUFFT eps "
             f"{RT_EPS:g}; error of the channel-averaged range-Doppler power map")
    knobs = [knob("rt_samples", f"trace samples per source ({RT_SCENE})",
                  [(n, d["max_depth"], d["retrace_every"]) for n in samples],
                  (RT_REFERENCE_SAMPLES, d["max_depth"], d["retrace_every"]),
                  [_samples_label(n) for n in samples], _samples_label(d["samples_per_src"]),
                  f"{setup}; depth {d['max_depth']}, traced once")]
    depths = sorted(set(RT_DEPTHS) | {d["max_depth"]})
    knobs.append(knob("rt_depth", f"trace depth max_depth ({RT_SCENE})",
                      [(d["samples_per_src"], k, d["retrace_every"]) for k in depths],
                      (d["samples_per_src"], max(depths), d["retrace_every"]),
                      [str(k) for k in depths], str(d["max_depth"]),
                      f"{setup}; {d['samples_per_src']} samples, traced once"))
    intervals = list(dict.fromkeys([d["retrace_every"], *RT_RETRACE[bool(quick)]]))
    knobs.append(knob("rt_retrace", f"re-trace interval ({RT_SCENE})",
                      [(d["samples_per_src"], d["max_depth"], k) for k in intervals],
                      (d["samples_per_src"], d["max_depth"], None),
                      ["once" if k is None else f"every {k}" for k in intervals],
                      "once" if d["retrace_every"] is None else f"every {d['retrace_every']}",
                      f"{setup}; {d['samples_per_src']} samples, depth {d['max_depth']}; "
                      "reference: trace once (a re-trace re-samples the diffuse hit points)"))
    return knobs


def measure_tube_density(*, quick: bool) -> dict:
    """SBR ray-tube density on a 0.1 m trihedral at 15 m against Knott's closed form.

    Time: CPU seconds of one PO + SBR trace of the reflector (best of two);
    error: relative RCS error ``|sigma / sigma_closed - 1|`` (power). The
    engine's default is :data:`raysim.echoes.po.paths.TUBES_PER_WAVELENGTH`.
    """
    from raysim.bench.tube_density import TUBE_DENSITIES, tube_density_points
    from raysim.echoes.po.paths import TUBES_PER_WAVELENGTH

    densities = (0.5, 1.0, 2.0, 4.0) if quick else TUBE_DENSITIES
    settings = [{"setting": f"{p['tubes_per_wavelength']:g}/lambda",
                 "s_per_frame": p["cpu_seconds"], "tubes": p["tubes"],
                 "rel_error": abs(10 ** (p["error_db"] / 10) - 1.0)}
                for p in tube_density_points(densities, repeats=2)]
    return _knob("tube_density", "SBR tube density (0.1 m trihedral at 15 m)", settings,
                 "one PO + SBR trace of the reflector; error of its RCS against "
                 "4 pi a^4 / (3 lambda^2) (Knott, table 6.1)",
                 default=f"{TUBES_PER_WAVELENGTH:g}/lambda",
                 time_label="CPU s per trace of the reflector")


def measure_fidelity(*, quick: bool) -> dict:
    """The parking lot's geometry targets per level (:mod:`raysim.bench.fidelity_ladder`)."""
    from raysim.bench.fidelity_ladder import LADDER_SCENE, fidelity_ladder_points

    return _knob("fidelity", f"echo model of geometry targets ({LADDER_SCENE})",
                 fidelity_ladder_points(quick=quick),
                 "steady state: reduced models re-used from the frame before; reference: "
                 "every object's mesh; first_s: the first frame's trace and choice",
                 default="mesh", time_label="CPU s per frame of the targets' paths")


def measure_knobs(*, quick: bool = False, log: Callable[[str], None] = print,
                  rt: bool = True) -> dict:
    """Measure every knob; returns ``{"knobs": [...], "not_measured": {...}}``.

    ``rt=False`` leaves out the ray-tracing knobs; when Sionna RT's LLVM
    backend cannot run, they are left out and ``not_measured`` says why.
    """
    from raysim.synthesis import kernel

    knobs, not_measured = [], {}
    fns = [measure_nufft_eps, measure_motion, measure_geometry, measure_chirp_block]
    if kernel.available():
        fns[1:1] = [measure_kernel_eps, measure_decimation]
    else:
        not_measured["kernel_eps_decimation"] = (
            "fused kernel not built (pip install -e . or python setup.py build_ext --inplace); "
            "kernel tolerance and decimation panels skipped")
    for fn in fns:
        log(f"  chart knob: {fn.__name__.removeprefix('measure_')}")
        knobs.append(fn(quick=quick))
    if rt:
        from raysim.echoes.rt.backend import BackendError

        log("  chart knobs: rt_samples, rt_depth, rt_retrace, tube_density")
        try:
            knobs.extend(measure_rt_knobs(quick=quick, log=log))
            knobs.append(measure_tube_density(quick=quick))
            knobs.append(measure_fidelity(quick=quick))
        except BackendError as err:
            not_measured["rt_samples_depth_retrace"] = (
                f"Sionna RT unavailable, ray-tracing and tube-density panels skipped: {err}")
            log(f"  {not_measured['rt_samples_depth_retrace']}")
    else:
        not_measured["rt_samples_depth_retrace"] = ("ray-tracing and tube-density knobs not "
                                                    "requested")
    return {"quick": bool(quick), "time_tolerance": TIME_TOLERANCE, "knobs": knobs,
            "not_measured": not_measured,
            "time_unit": "CPU seconds per 256-chirp paper frame (extrapolated from the "
                         "chirps timed, see each knob's note); ray-tracing knobs: CPU "
                         "seconds per ray-traced frame (trace + re-projection + synthesis)"}


def _decade_limits(values) -> tuple[float, float]:
    """Log-axis limits around ``values`` spanning at least one decade."""
    lo, hi = float(np.min(values)) / 1.5, float(np.max(values)) * 1.5
    if hi / lo < 10.0:
        mid = np.sqrt(lo * hi)
        lo, hi = mid / np.sqrt(10.0), mid * np.sqrt(10.0)
    return lo, hi


def draw_chart(measured: dict, path) -> None:
    """One PNG, one panel per knob: time per frame vs error, Pareto front, default starred."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    from raysim.io.files import atomic_savefig

    knobs = measured["knobs"]
    ncol = min(len(knobs), 4)
    nrow = -(-len(knobs) // ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4.2 * ncol, 4.0 * nrow + 0.4), squeeze=False)
    for ax in axes.flat[len(knobs):]:
        ax.axis("off")
    for ax, k in zip(list(axes.flat)[:len(knobs)], knobs, strict=True):
        s = k["settings"]
        t = np.array([x["s_per_frame"] for x in s])
        e = np.array([max(x["rel_error"], REFERENCE_ERROR_FLOOR) for x in s])
        front = np.array([x["pareto"] for x in s])
        order = np.argsort(t[front])
        ax.plot(t[front][order], e[front][order], "-", color="tab:green", lw=1.5,
                label="Pareto front", zorder=1)
        ax.scatter(t[~front], e[~front], color="tab:gray", s=30, label="dominated", zorder=2)
        ax.scatter(t[front], e[front], color="tab:green", s=30, zorder=2)
        for i, (x, ti, ei) in enumerate(zip(s, t, e, strict=True)):
            ax.annotate(x["setting"] + (" (ref)" if x.get("reference") else ""), (ti, ei),
                        textcoords="offset points", xytext=(4, 4 + 9 * (i % 3)), fontsize=7)
            if x["default"]:
                ax.scatter([ti], [ei], marker="*", s=220, facecolor="gold", edgecolor="k",
                           zorder=3, label="default")
        if t.max() / t.min() < 3.0:          # settings about equally fast: linear time axis
            pad = 0.05 * t.max()
            ax.set_xlim(max(0.0, t.min() - pad), t.max() + pad)
        else:
            ax.set_xscale("log")
            ax.set_xlim(*_decade_limits(t))
        ax.set_yscale("log")
        ax.set_ylim(*_decade_limits(e))
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_minor_formatter(NullFormatter())
        ax.set_xlabel(k.get("time_label", "time per paper frame [CPU s]"))
        ax.set_ylabel("relative error of the RD power map" if k["knob"].startswith("rt_")
                      else "relative error vs highest fidelity")
        if k["default_on_front"]:
            ax.set_title(k["label"], fontsize=9)
        else:
            ax.set_title(k["label"] + "\ndefault NOT on the Pareto front", fontsize=9,
                         color="tab:red")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle("raysim speed vs accuracy (reference shown at "
                 f"{REFERENCE_ERROR_FLOOR:g}; 'quick' = {measured.get('quick')})", fontsize=10)
    notes = [str(v) for v in measured.get("not_measured", {}).values()]
    if notes:
        fig.text(0.5, 0.005, "not measured: " + "; ".join(notes), ha="center", va="bottom",
                 fontsize=8, color="tab:red", wrap=True)
    fig.tight_layout(rect=(0, 0.04 if notes else 0, 1, 1))
    atomic_savefig(fig, path, dpi=CHART_DPI, format="png")
    plt.close(fig)
