"""Reproduction of the paper's experiments with and without motion compensation.

Every case of :mod:`raysim.scenario.paper_cases` is a scenario
(:func:`raysim.scenario.scenario_from_case`) plus the study's knobs
(:class:`ReproductionSettings`). Its frames are rendered by the pipeline's
echo source (:func:`raysim.pipeline.sources.frame_source`), its IMU log by
:func:`raysim.pipeline.sensors.imu_log` (IMU seed ``k`` of a run is the
scenario's ``imu_seed + k``), integrated by
:func:`raysim.pipeline.estimate.scenario_motion` to the pose at every TDM slot
of every chirp, and every metric is measured by :mod:`raysim.measure.point`:
``raysim simulate --case NAME`` and ``raysim reproduce`` see the same frames,
the same motion and print the same values. The chains of
:mod:`raysim.vocabulary` are:

``none``
    conventional beam scan and Doppler FFT;
``paper``
    the published chain (tilt element phase, slow-time phase of translation
    and of the lever-arm rotation from the integrated displacement, yaw beam
    projection), slow-time phase applied towards the direction this chain
    estimates at the angle chirp;
``paper:published``
    the same with the published rotation phase ``v_r(nT) nT``;
``exact``
    the rigid-body projection using all six degrees of freedom.

Metrics (names and units in :data:`raysim.vocabulary.METRICS`, definitions in
:func:`raysim.measure.point.gate_metrics`, parameters in docs/conventions.md):
``pseudo_velocity_mps`` / ``_bins``, ``doppler_width_hz``,
``angle_error_deg``, ``az_deg``, ``el_deg``, ``entropy_ae_nats``,
``map_az_deg``, ``map_el_deg``. The stationary platform is the reference
(:data:`raysim.vocabulary.REFERENCE`): the same scenario at rest, its one
frame standing for every frame.

Initial conditions of the strapdown integration (the flight controller's
state at ``t = 0``): attitude, position and velocity from the truth
trajectory (``velocity="given"``), or the hover assumption.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from raysim.measure.point import PointCells, PointGate, gate_metrics, point_cells
from raysim.pipeline.estimate import VELOCITY_MODES, scenario_motion
from raysim.pipeline.run import motion_times
from raysim.pipeline.sensors import imu_log
from raysim.pipeline.sources import LazyFrames, Reference, frame_source, reference_target
from raysim.platform.imu import get_preset
from raysim.processing import metrics
from raysim.scenario import Scenario, scenario_from_case
from raysim.scenario.paper_cases import PAPER_CASES, get_case
from raysim.studies.reproduce_output import format_table, write_case_figures, write_results
from raysim.vocabulary import CHAIN_KEYS, REFERENCE, metric_unit, parse_chains

__all__ = ["DEFAULT_CHAINS", "ROW_METRICS", "ReproductionSettings", "case_scenario",
           "prepare_case", "platform_motion", "run_case", "reproduce", "format_table",
           "write_results", "write_case_figures"]

#: Chains evaluated for every case, in table order (:func:`raysim.vocabulary.parse_chains`).
DEFAULT_CHAINS = CHAIN_KEYS
#: Most IMU seeds of one reproduction [1]: each renders and measures every case again
#: (seconds to minutes a seed), so more is a mistyped count, refused before any work.
MAX_SEEDS = 1000
#: Metrics of every row (mean and ``_std`` over seeds), names of :data:`raysim.vocabulary.METRICS`.
ROW_METRICS = ("pseudo_velocity_mps", "pseudo_velocity_bins", "doppler_width_hz",
               "width_improvement_pct", "width_vs_stationary", "angle_error_deg", "az_deg",
               "el_deg", "entropy_ae_nats", "entropy_vs_stationary", "map_az_deg", "map_el_deg")
#: Metrics of :func:`raysim.measure.point.gate_metrics` a row reports.
_MEASURED = ("pseudo_velocity_mps", "pseudo_velocity_bins", "doppler_width_hz",
             "angle_error_deg", "az_deg", "el_deg", "entropy_ae_nats", "map_az_deg", "map_el_deg")


@dataclass(frozen=True)
class ReproductionSettings:
    """The study's knobs beside each case's scenario.

    Attributes
    ----------
    overrides : mapping
        Scenario key path -> value applied to every case
        (:meth:`raysim.scenario.Scenario.with_values`), e.g.
        ``{"radar.sample_rate_hz": 2.5e6, "imu.rate_hz": 500.0}``. A lower ADC
        rate keeps range resolution and every motion effect, only shrinking
        the unambiguous range window.
    yaw_frames : int or None
        Frames of the multi-frame cases (None keeps the case's 20); single-frame
        cases keep one.
    range_half_width : float
        Range window of the RA/RD figures around the target [m].
    velocity : {"given", "hover"}
        Initial-velocity handling of the strapdown integration.
    """

    overrides: Mapping[str, Any] = field(default_factory=dict)
    yaw_frames: int | None = None
    range_half_width: float = 3.0
    velocity: str = "given"

    def __post_init__(self) -> None:
        if self.velocity not in VELOCITY_MODES:
            raise ValueError(f"velocity: got {self.velocity!r}, expected one of "
                             f"{list(VELOCITY_MODES)}")
        if not isinstance(self.overrides, Mapping):
            raise ValueError(f"overrides: got {type(self.overrides).__name__}, expected a "
                             f"mapping of scenario key paths to values")
        object.__setattr__(self, "overrides", dict(self.overrides))
        if self.yaw_frames is not None and int(self.yaw_frames) < 1:
            raise ValueError(f"yaw_frames: got {self.yaw_frames!r}, expected >= 1 or None")
        if not (self.range_half_width > 0 and math.isfinite(self.range_half_width)):
            raise ValueError(f"range_half_width: got {self.range_half_width!r}, expected a "
                             f"positive distance [m]")

    @classmethod
    def quick(cls, **changes) -> ReproductionSettings:
        """Reduced sizes for tests: 2.5 MHz sampling, a narrower figure window."""
        overrides = {"radar.sample_rate_hz": 2.5e6, **changes.pop("overrides", {})}
        base = dict(overrides=overrides, range_half_width=1.5)
        base.update(changes)
        return cls(**base)


@dataclass(eq=False)
class _Case:
    """A rendered case: its scenario, the target's cells and the stationary reference."""

    name: str
    scenario: Scenario
    paper: dict                    # chain -> metric -> the paper's value
    reference: Reference
    cells: PointCells              # the target's gate in every frame, frame 0's cube
    chirp_times: np.ndarray        # [frame * chirp] [s]
    window: np.ndarray             # range bins of the figures
    stationary: dict = field(default_factory=dict)

    @property
    def config(self):
        return self.cells.gate.config

    @property
    def array(self):
        return self.cells.gate.array

    @property
    def frames(self) -> int:
        return self.cells.gate.num_frames

    @property
    def target_az(self) -> float:
        """Reference azimuth [rad]."""
        return math.radians(self.reference.az_deg)

    @property
    def target_el(self) -> float:
        """Reference elevation [rad]."""
        return math.radians(self.reference.el_deg)

    @property
    def range_axis(self) -> np.ndarray:
        return self.cells.range_axis

    @property
    def rc_window(self) -> np.ndarray:
        """Frame 0's cells of the figure window, ``[chirp, channel, range]``."""
        return self.cells.cube[:, :, self.window]


def case_scenario(name: str, settings: ReproductionSettings | None = None) -> Scenario:
    """The scenario of a paper case with the settings' overrides and frame count."""
    settings = ReproductionSettings() if settings is None else settings
    s = scenario_from_case(name)
    changes = dict(settings.overrides)
    if settings.yaw_frames is not None and s.frames > 1:
        changes["frames"] = int(settings.yaw_frames)
    return s.with_values(changes) if changes else s


def _frames(scenario: Scenario) -> LazyFrames:
    return LazyFrames(frame_source(scenario, scenario.trajectory()), scenario.frames)


def prepare_case(name: str, settings: ReproductionSettings) -> _Case:
    """Render a case's frames (and its stationary reference) once, keeping the target's cells."""
    scenario = case_scenario(name, settings)
    frames = _frames(scenario)
    ref = frames.reference if frames.reference is not None else reference_target(scenario)
    cells = point_cells(frames, ref)
    cfg = cells.gate.config
    half = int(math.ceil(settings.range_half_width / cfg.range_resolution))
    i = cells.range_bin
    window = np.arange(max(i - half, 0), min(i + half + 1, cells.range_axis.size))
    data = _Case(name, scenario, get_case(name)["paper"], ref, cells, frames.chirp_times(),
                 window)
    # stationary reference: the same scenario at rest, its one frame standing for every frame
    at_rest = scenario.with_values({"motion": {}, "frames": 1})
    g0 = point_cells(_frames(at_rest), ref).gate
    still = PointGate(np.repeat(g0.snapshots, data.frames, axis=0), g0.range_m, g0.config,
                      g0.array)
    extra: dict = {}
    st = gate_metrics(still, ref, chain="none", maps=extra)
    data.stationary = {k: st[k] for k in ("doppler_width_hz", "entropy_ae_nats",
                                          "pseudo_velocity_mps")}
    data.stationary["map"] = extra["ae"]
    return data


def _evaluate(data: _Case, chain: str, motion=None) -> dict:
    """Metrics of one chain on the case's gate (:func:`raysim.measure.point.gate_metrics`)."""
    found: list[str] = [] if motion is None else list(motion.warnings)
    extra: dict = {}
    out = gate_metrics(data.cells.gate, data.reference, chain=chain, motion=motion,
                       warnings=found, maps=extra)
    out = {k: out[k] for k in _MEASURED}
    out["_map"] = extra["ae"]
    out["warnings"] = found
    return out


def platform_motion(data: _Case, imu: str, seed: int, settings: ReproductionSettings):
    """The case's IMU log with preset ``imu`` and seed ``imu_seed + seed``, integrated.

    The log is :func:`raysim.pipeline.sensors.imu_log` of the case's scenario
    (``imu.preset`` = ``imu``, ``imu.seed`` = ``scenario.imu_seed + seed``), so
    seed 0 is the IMU ``raysim simulate --case`` sees; the integration is
    :func:`raysim.pipeline.estimate.scenario_motion` at every TDM slot of every
    chirp (:func:`raysim.pipeline.run.motion_times`).
    """
    scenario = data.scenario.with_values({"imu.preset": imu,
                                          "imu.seed": data.scenario.imu_seed + int(seed)})
    traj = scenario.trajectory()
    times = motion_times(_FrameAxes(data), data.chirp_times)
    return scenario_motion(scenario, imu_log(scenario, traj), times, traj,
                           velocity=settings.velocity)


class _FrameAxes:
    """What :func:`raysim.pipeline.run.motion_times` reads of a frame: its array and config."""

    def __init__(self, data: _Case) -> None:
        self.array, self.config = data.array, data.config


# ------------------------------------------------------------------ rows
def _paper_values(data: _Case, key: str) -> dict:
    """``paper_<metric>`` of the paper's values for a chain (``none``: before, else after)."""
    vals = data.paper.get("none" if key == "none" else "paper", {})
    out = {f"paper_{m}": v for m, v in vals.items()}
    if "az_deg" in vals:
        el = math.radians(vals["el_deg"]) if "el_deg" in vals else data.target_el
        out["paper_angle_error_deg"] = metrics.angle_error_deg(
            math.radians(vals["az_deg"]), el, data.target_az, data.target_el)
    return out


def _summarise(data: _Case, key: str, runs: list[dict], unc: dict, imu: str) -> dict:
    st = data.stationary
    for r in runs:
        r["width_improvement_pct"] = 100.0 * (unc["doppler_width_hz"] - r["doppler_width_hz"]) \
            / unc["doppler_width_hz"]
        r["width_vs_stationary"] = r["doppler_width_hz"] / st["doppler_width_hz"]
        r["entropy_vs_stationary"] = r["entropy_ae_nats"] - st["entropy_ae_nats"]
    row = {"case": data.name, "chain": key, "imu": imu if key != "none" else "-",
           "seeds": len(runs), "num_chirps": data.config.num_chirps,
           "frames": data.frames,
           "velocity_bin_mps": data.config.velocity_resolution,
           "doppler_bin_hz": data.config.doppler_resolution,
           f"{REFERENCE}_doppler_width_hz": st["doppler_width_hz"],
           f"{REFERENCE}_entropy_ae_nats": st["entropy_ae_nats"]}
    for m in ROW_METRICS:
        vals = np.array([r[m] for r in runs], dtype=float)
        row[m] = float(vals.mean())
        row[m + "_std"] = float(vals.std(ddof=1)) if vals.size > 1 else 0.0
    row.update(_paper_values(data, key))
    found: list[str] = []
    for r in runs:
        found.extend(w for w in r.get("warnings", ()) if w not in found)
    row["warnings"] = " | ".join(found)
    return row


def run_case(name: str, *, imu: str = "ideal", seeds=(0,),
             settings: ReproductionSettings | None = None, figures_dir: str | None = None,
             chains=DEFAULT_CHAINS) -> list[dict]:
    """Evaluate chains on one paper case; one table row per chain (mean and std over seeds).

    Parameters
    ----------
    name : str
        Paper case (key of :data:`raysim.scenario.paper_cases.PAPER_CASES`).
    imu : str
        IMU preset name (``ideal``, ``tactical``, ``consumer_mems``).
    seeds : sequence of int
        IMU error seeds, offsets to the scenario's ``imu_seed`` (seed 0 is the
        IMU of ``raysim simulate --case``); the radar frames are the same for
        every seed.
    settings : ReproductionSettings, optional
    figures_dir : str, optional
        Write the RA/RD/AE figures (first seed) there.
    chains : str or sequence of str
        Chains (:func:`raysim.vocabulary.parse_chains`), e.g. ``"none,paper:published"``.

    Returns
    -------
    list of dict
        Rows with ``case``, ``chain`` (its key), the metrics of
        :data:`ROW_METRICS` (``*_std`` over seeds), the stationary reference
        (``stationary_<metric>``), the paper's values (``paper_<metric>``) and
        ``warnings``: the distinct ``BeamCube.warnings`` of the chain over all
        seeds, joined by ``" | "`` (empty when every assumption held).
    """
    settings = ReproductionSettings() if settings is None else settings
    get_preset(imu)
    seeds = list(seeds)
    if not seeds:
        raise ValueError("seeds must hold at least one seed")
    specs = parse_chains(chains)
    data = prepare_case(name, settings)
    unc = _evaluate(data, "none")
    runs: dict[str, list[dict]] = {s.key: [] for s in specs if s.compensated}
    first_motion = None
    for seed in seeds:
        motion = platform_motion(data, imu, seed, settings)
        first_motion = first_motion or motion
        for s in specs:
            if s.compensated:
                runs[s.key].append(_evaluate(data, s.key, motion))
    rows = [_summarise(data, s.key, runs[s.key] if s.compensated else [unc], unc, imu)
            for s in specs]
    if figures_dir is not None:
        maps = {s.key: (runs[s.key][0] if s.compensated else unc)["_map"] for s in specs}
        maps[REFERENCE] = data.stationary["map"]
        write_case_figures(data, first_motion, figures_dir, imu=imu, maps=maps)
    return rows


def reproduce(cases=None, *, imu: str = "ideal", seeds: int = 1,
              settings: ReproductionSettings | None = None, out_dir: str | None = None,
              figures: bool = True, chains=DEFAULT_CHAINS, progress=None) -> dict:
    """Run the paper's experiments and (optionally) write the table and figures.

    Parameters
    ----------
    cases : sequence of str, optional
        Case names (default all of :data:`raysim.scenario.paper_cases.PAPER_CASES`).
    imu : str
        IMU preset.
    seeds : int
        Number of IMU seeds (0 .. seeds-1, offsets to the scenario's ``imu_seed``).
    settings : ReproductionSettings, optional
    out_dir : str, optional
        Directory for ``reproduction.json``, ``reproduction.csv`` and figures.
    figures : bool
        Write the RA/RD/AE figures into ``out_dir/figures``.
    chains : str or sequence of str
        Chains (:func:`raysim.vocabulary.parse_chains`).
    progress : callable, optional
        Called with a message string after each case.

    Returns
    -------
    dict
        ``{"meta": {...}, "rows": [...]}``; ``meta["units"]`` gives the unit
        of every metric column (:func:`raysim.vocabulary.metric_unit`).
    """
    settings = ReproductionSettings() if settings is None else settings
    names = list(PAPER_CASES) if not cases else list(cases)
    for name in names:
        if name not in PAPER_CASES:
            raise ValueError(f"unknown case {name!r}; expected some of {sorted(PAPER_CASES)}")
    if not 1 <= int(seeds) <= MAX_SEEDS:
        raise ValueError(f"seeds must be 1 to {MAX_SEEDS} (each renders every case again), "
                         f"got {seeds!r}")
    keys = [s.key for s in parse_chains(chains)]
    fig_dir = None
    if out_dir is not None:
        os.makedirs(out_dir, exist_ok=True)
    if out_dir is not None and figures:
        fig_dir = os.path.join(out_dir, "figures")
        os.makedirs(fig_dir, exist_ok=True)
    rows = []
    t0 = time.perf_counter()
    for name in names:
        rows.extend(run_case(name, imu=imu, seeds=range(int(seeds)), settings=settings,
                             figures_dir=fig_dir, chains=keys))
        if progress is not None:
            progress(f"{name}: done after {time.perf_counter() - t0:.1f} s")
    first = case_scenario(names[0], settings)
    result = {"meta": {"imu": imu, "seeds": int(seeds), "imu_rate_hz": first.imu.rate_hz,
                       "velocity": settings.velocity, "chains": keys,
                       "sample_rate_hz": first.radar.sample_rate_hz,
                       "lever_arm_m": first.lever_arm.tolist(),
                       "units": {m: metric_unit(m) for m in ROW_METRICS},
                       "settings": dict(settings.__dict__), "seconds": time.perf_counter() - t0},
              "rows": rows}
    if out_dir is not None:
        write_results(result, out_dir)
    return result
