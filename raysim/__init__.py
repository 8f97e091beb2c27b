"""raysim: ray-traced FMCW mmWave MIMO radar simulation for hovering drones.

One TOML scenario describes a run (radar, array, scene, platform motion, IMU);
the pipeline renders its IF frames, simulates the IMU, estimates the motion
and evaluates every compensation chain (``none``, ``paper``, ``exact``) with
the metrics of docs/conventions.md. Motion compensation itself lives in the
separate :mod:`compensation` package, which never imports raysim.

Entry points (imported on first use, so ``import raysim`` stays cheap)
-------------------------------------------------------------------------
Scenarios (:mod:`raysim.scenario`)
    :class:`Scenario`, :func:`load_scenario` (a TOML file),
    :func:`loads_scenario` (TOML text), :func:`scenario_from_case` (a paper case).
Radar (:mod:`raysim.radar`)
    :class:`RadarConfig` (waveform, sampling, derived axes),
    :class:`VirtualArray` (UPA and TDM-MIMO layouts).
Frames and maps
    :class:`RadarFrame` (one IF frame ``[chirp, channel, sample]``,
    :mod:`raysim.synthesis.frame`), :class:`Map` (a power map with named
    axes, :mod:`raysim.processing.maps`); both have ``to_xarray()``.
Pipeline (:mod:`raysim.pipeline`)
    :func:`render` (a scenario's frames into a Zarr store),
    :func:`render_frames` (the frames in memory), :func:`evaluate` (every
    chain's metrics), :func:`estimate_motion` (IMU samples to the platform
    pose at every chirp); the point metrics and maps of given frames are
    :func:`raysim.measure.point.measure`.

Packages
--------
``scenario`` (scenario model, TOML reader, paper cases), ``radar``,
``platform`` (motion, IMU), ``echoes`` (oracle, ray tracing, clutter),
``synthesis`` (IF frames), ``processing`` (maps, metrics), ``io`` (stores,
captures, IMU logs), ``pipeline`` (the run path), ``studies``, ``cli``
(docs/architecture.md). Sionna RT / Mitsuba are only loaded by
``raysim.echoes.rt`` and only after the variant has been chosen explicitly.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: Public name -> module that defines it (imported on first access, PEP 562).
_ENTRY_POINTS = {
    "Scenario": "raysim.scenario",
    "load_scenario": "raysim.scenario",
    "loads_scenario": "raysim.scenario",
    "scenario_from_case": "raysim.scenario",
    "RadarConfig": "raysim.radar.config",
    "VirtualArray": "raysim.radar.arrays",
    "RadarFrame": "raysim.synthesis.frame",
    "Map": "raysim.processing.maps",
    "render": "raysim.pipeline.run",
    "evaluate": "raysim.pipeline.run",
    "render_frames": "raysim.pipeline.sources",
    "estimate_motion": "raysim.pipeline.estimate",
}

__all__ = ["__version__", "Scenario", "load_scenario", "loads_scenario", "scenario_from_case",
           "RadarConfig", "VirtualArray", "RadarFrame", "Map", "render", "evaluate",
           "render_frames", "estimate_motion"]

if TYPE_CHECKING:
    from raysim.pipeline.estimate import estimate_motion
    from raysim.pipeline.run import evaluate, render
    from raysim.pipeline.sources import render_frames
    from raysim.processing.maps import Map
    from raysim.radar.arrays import VirtualArray
    from raysim.radar.config import RadarConfig
    from raysim.scenario import Scenario, load_scenario, loads_scenario, scenario_from_case
    from raysim.synthesis.frame import RadarFrame


def __getattr__(name: str) -> Any:
    """An entry point of :data:`_ENTRY_POINTS`, imported on first access (or a submodule)."""
    module = _ENTRY_POINTS.get(name)
    if module is None:
        raise AttributeError(f"module 'raysim' has no attribute {name!r}; entry points: "
                             f"{', '.join(sorted(_ENTRY_POINTS))}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value          # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_ENTRY_POINTS))
