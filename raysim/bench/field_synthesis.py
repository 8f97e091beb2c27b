"""Clutter-field synthesis: the compact way against dense re-projection, same paths, same run.

    PYTHONPATH=$PWD python -m raysim.bench.field_synthesis [--scene flat_reflectors]

Traces a bundled scene with the scene report's QUICK settings and its persistent
clutter field (10 scatterers per cell), then synthesises the hovering frame's
frozen paths with ``synthesize_paths(compact=False)`` (dense ``[path, chirp,
channel]`` re-projection, then ``synthesize`` at the report's eps: the baseline)
and ``compact=True`` (``PathDelays`` with per-chirp element gains, fused kernel
where built). Prints one JSON object: path count, wall (``perf_counter``) and
CPU (``process_time``, all threads) seconds of each, their ratios, the relative
l2 difference of the two cubes, the synthesis threads and the load average
before and after. Both timings exclude the trace.
"""

import argparse
import json
import os
import time

import numpy as np

from raysim.echoes.ground.field import FieldSettings
from raysim.echoes.rt.reproject import synthesize_paths
from raysim.echoes.rt.scenes import load_scene
from raysim.echoes.rt.trace import MonostaticTracer
from raysim.echoes.scene_clutter import SceneClutter
from raysim.platform.motion import stationary
from raysim.studies.scene_report import QUICK, hover_trajectory
from raysim.synthesis.nufft import default_threads


def _clocked(fn):
    w, c = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w, time.process_time() - c


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", default="flat_reflectors")
    a = p.parse_args()
    s = QUICK.with_values(clutter="field")
    cfg, arr, lever = s.radar(), s.array(), np.asarray(s.lever_arm)
    t0 = float(cfg.chirp_times()[0])
    model = SceneClutter(FieldSettings(scatterers_per_cell=s.clutter_per_cell,
                                        seed=s.trace_seed))
    scene = load_scene(a.scene, frequency=cfg.carrier_frequency)
    tracer = model.tracer(MonostaticTracer(max_depth=s.max_depth,
                                           samples_per_src=s.samples_per_src,
                                           seed=s.trace_seed))
    paths, _ = model.paths(scene, tracer(scene, cfg, stationary(), lever, time=t0), cfg, arr,
                           stationary(), lever, time=t0)
    traj = hover_trajectory(s.jitter_seed, t0)
    load0 = os.getloadavg()[0]
    run = {}
    for name, compact in (("dense", False), ("compact", True)):
        run[name] = _clocked(lambda c=compact: synthesize_paths(
            paths, cfg, arr, traj, lever, compact=c, eps=s.nufft_eps,
            path_chunk=s.path_chunk)[0])
    ref, fast = run["dense"][0], run["compact"][0]
    print(json.dumps({
        "scene": a.scene, "paths": paths.num_paths,
        "frame": list(ref.shape), "eps": s.nufft_eps, "threads": default_threads(),
        "dense_wall_s": run["dense"][1], "dense_cpu_s": run["dense"][2],
        "compact_wall_s": run["compact"][1], "compact_cpu_s": run["compact"][2],
        "wall_ratio_dense_over_compact": run["dense"][1] / run["compact"][1],
        "cpu_ratio_dense_over_compact": run["dense"][2] / run["compact"][2],
        "relative_difference": float(np.linalg.norm(fast - ref) / np.linalg.norm(ref)),
        "load_before": load0, "load_after": os.getloadavg()[0]}, indent=1))


if __name__ == "__main__":
    main()
