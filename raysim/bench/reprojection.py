"""Re-projection against re-tracing per chirp (``scene-report --bench-reprojection``)."""

from __future__ import annotations

import json
import math
import os
import time

import numpy as np

from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

__all__ = ["bench_scene_reprojection"]


def bench_scene_reprojection(scene: str = "rough_terrain", *, num_chirps: int = 16,
                       array_size: int = 8, samples_per_src: int = 100_000,
                       repeat: int = 3) -> dict:
    """Wall time of re-projection per chirp vs re-tracing per chirp (CPU).

    Both produce the delays of the scene's paths for one chirp of a hovering
    platform. Re-tracing runs :class:`raysim.echoes.rt.trace.MonostaticTracer` from
    the chirp's pose (only the phase centre; per-channel delays would need one
    trace per channel). Re-projection runs
    :func:`raysim.echoes.rt.reproject.path_lengths` for the same chirp, either for
    the phase centre only (same output as one trace) or for every channel.

    Parameters
    ----------
    scene : str
        Registry name.
    num_chirps : int
        Chirps timed (each traced once).
    array_size : int
        Virtual UPA size for the per-channel re-projection.
    samples_per_src : int
        Rays per trace.
    repeat : int
        Repetitions of the re-projection timing (best is kept).

    Returns
    -------
    dict
        ``trace_s_per_chirp``, ``reproject_s_per_chirp`` (phase centre),
        ``reproject_all_channels_s_per_chirp``, ``ratio`` (trace / re-projection,
        phase centre), ``ratio_all_channels`` (``channels`` traces / one
        per-channel re-projection), ``num_paths``, ``channels`` and the settings.
    """
    from raysim.echoes.rt.reproject import element_positions, path_lengths
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.platform.motion import hover_jitter

    for name, v in (("num_chirps", num_chirps), ("array_size", array_size),
                    ("samples_per_src", samples_per_src), ("repeat", repeat)):
        if not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be a positive integer, got {v!r}")
    config = RadarConfig(num_chirps=num_chirps, idle_time=440e-6)
    lever = np.array([0.0, 0.0, 0.1])
    motion = hover_jitter(7)
    loaded = load_scene(scene, frequency=config.carrier_frequency)
    tracer = MonostaticTracer(samples_per_src=samples_per_src)
    paths = tracer(loaded, config, motion, lever, time=0.0)            # warm-up and frozen set
    times = config.chirp_times()
    t = time.perf_counter()
    for tn in times:
        tracer(loaded, config, motion, lever, time=float(tn))
    trace_s = (time.perf_counter() - t) / num_chirps
    centre = upa(1, 1, spacing=1e-3)
    full = upa(array_size, array_size, wavelength=config.wavelength)

    def per_chirp(array):
        geo = element_positions(config, array, motion, lever)
        best = math.inf
        for _ in range(repeat):
            t = time.perf_counter()
            for n in range(num_chirps):
                path_lengths(paths, geo[0][n:n + 1], geo[1][n:n + 1], geo[2][n:n + 1])
            best = min(best, (time.perf_counter() - t) / num_chirps)
        return best

    rep_c = per_chirp(centre)
    rep_a = per_chirp(full)
    m = full.num_channels
    return {"scene": scene, "num_paths": paths.num_paths, "num_chirps": num_chirps,
            "samples_per_src": samples_per_src, "channels": m,
            "trace_s_per_chirp": trace_s, "reproject_s_per_chirp": rep_c,
            "reproject_all_channels_s_per_chirp": rep_a,
            "ratio": trace_s / rep_c, "ratio_all_channels": m * trace_s / rep_a}


def main_bench() -> None:  # pragma: no cover - ``python -m raysim.studies.scene_report``
    from raysim.echoes.rt import backend

    backend.configure("cpu", threads=int(os.environ.get("RAYSIM_RT_THREADS", "2")))
    print(json.dumps(bench_scene_reprojection(), indent=1))
