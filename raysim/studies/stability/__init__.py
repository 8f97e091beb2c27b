"""Stability maps: where IMU-driven motion compensation holds and where it fails.

A *stability map* sweeps one or two parameters of a point (rotation amplitude,
target angle, motion frequency, frame length, IMU errors, clock errors, lever
arm error, hover-jitter level) and records, for every chain (``none``,
``paper``, ``paper:published``, ``exact``; :mod:`raysim.vocabulary`), the
metrics of :data:`raysim.vocabulary.METRICS` of a single static point target,
and where the chain fails (:func:`fails`: ``|pseudo_velocity_mps|`` above one
Doppler velocity bin or ``angle_error_worst_deg`` above half the 3 dB
beamwidth). See ``docs/stability.md``.

Modules, one job each:

* :mod:`~raysim.studies.stability.point` -- :class:`StabilityPoint`, one map point
  in the TOML scenario's names and units plus the study's knobs;
* :mod:`~raysim.studies.stability.motion` -- its simulated IMU through
  :func:`raysim.pipeline.estimate.estimate_motion`;
* :mod:`~raysim.studies.stability.metrics` -- the range gate
  (:func:`raysim.echoes.gated.gated_cube`) through every chain, measured by
  :func:`raysim.measure.point.gate_metrics` (the definition every command
  uses) plus the study's ``angle_error_worst_deg``;
* :mod:`~raysim.studies.stability.criteria` -- failure thresholds;
* :mod:`~raysim.studies.stability.grids` -- the maps and their point builders;
* :mod:`~raysim.studies.stability.runner` -- points as (Dask) tasks, resumable;
* :mod:`~raysim.studies.stability.outputs` -- NetCDF, JSON, figures, console table.
"""

from raysim.io.files import atomic_write
from raysim.studies.stability.criteria import Criteria, criteria_for, fails
from raysim.studies.stability.grids import IMU_TERMS, MAPS, MapSpec
from raysim.studies.stability.metrics import (
    ANGLE_CHIRPS,
    MAP_CHAINS,
    STABILITY_METRICS,
    compensated_slow_time,
    evaluate,
    point_gate,
)
from raysim.studies.stability.motion import point_motion
from raysim.studies.stability.outputs import (
    failing_values,
    plot_stability,
    read_netcdf,
    summarise,
    summary_table,
    write_netcdf,
)
from raysim.studies.stability.point import INITS, StabilityPoint
from raysim.studies.stability.runner import run_map, write_stability

__all__ = [
    "MAP_CHAINS", "STABILITY_METRICS", "ANGLE_CHIRPS", "INITS", "IMU_TERMS", "StabilityPoint",
    "Criteria", "MapSpec", "MAPS", "point_gate", "point_motion", "compensated_slow_time",
    "evaluate", "run_map", "plot_stability", "atomic_write", "write_stability", "write_netcdf",
    "read_netcdf", "summarise", "summary_table", "criteria_for", "fails", "failing_values",
]
