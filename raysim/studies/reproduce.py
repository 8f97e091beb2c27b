"""Reproduction of the paper's experiments with and without motion compensation.

Every case of :mod:`raysim.scenario.paper_cases` is a scenario
(:func:`raysim.scenario.scenario_from_case`); its frames are rendered by
the pipeline's echo source (:func:`raysim.pipeline.sources.frame_source`), so
``raysim simulate --case NAME`` and ``raysim reproduce`` see the same frames.
An IMU (preset of :mod:`raysim.platform.imu`) samples the scenario's motion,
:func:`raysim.pipeline.estimate.estimate_motion` integrates it to the pose at
every chirp, and the chains of :mod:`raysim.vocabulary` are applied by
:func:`raysim.pipeline.chains.project` on the same cubes:

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

Metrics (names and units in :data:`raysim.vocabulary.METRICS`):
``pseudo_velocity_mps`` / ``_bins`` and ``doppler_width_hz`` of the target's
slow-time signal (target range gate, beam towards the true direction);
``angle_error_deg``, ``az_deg``, ``el_deg`` of the single-chirp AE map of
chirp :func:`raysim.pipeline.analysis.angle_chirp` (the paper's chirp 128) on
the grid of :data:`~raysim.pipeline.analysis.SINGLE_CHIRP_HALF_WIDTH_DEG` /
:data:`~raysim.pipeline.analysis.SINGLE_CHIRP_STEP_DEG` around the truth, as
in :func:`raysim.pipeline.analysis.analyse`; ``entropy_ae_nats``,
``map_az_deg``, ``map_el_deg`` of the AE map at the target gate, coherently
integrated over each frame and summed in power over the frames (20 frames
for the yaw case). The stationary platform is the reference
(:data:`raysim.vocabulary.REFERENCE`), rendered from the same scenario at rest.

Initial conditions of the strapdown integration (the flight controller's
state at ``t = 0``): attitude, position and velocity from the truth
trajectory (``velocity="given"``), or the hover assumption.
"""

from __future__ import annotations

import math
import os
import time
from dataclasses import dataclass, field

import numpy as np

from raysim.echoes.oracle import direction
from raysim.pipeline.analysis import SINGLE_CHIRP_HALF_WIDTH_DEG, SINGLE_CHIRP_STEP_DEG, angle_chirp
from raysim.pipeline.analysis import local_axis as _axis
from raysim.pipeline.chains import project
from raysim.pipeline.estimate import VELOCITY_MODES, estimate_motion
from raysim.pipeline.sensors import imu_record
from raysim.pipeline.sources import frame_source, reference_target
from raysim.platform.imu import get_preset
from raysim.processing import metrics
from raysim.processing.maps import Map, range_compress
from raysim.scenario import Scenario, scenario_from_case
from raysim.scenario.paper_cases import PAPER_CASES, get_case
from raysim.studies.reproduce_output import format_table, write_case_figures, write_results
from raysim.vocabulary import MAPS, REFERENCE, ChainSpec, metric_unit, parse_chain, parse_chains

__all__ = ["DEFAULT_CHAINS", "ROW_METRICS", "IMU_RATE", "ReproductionSettings", "case_scenario",
           "prepare_case", "platform_motion", "run_case", "reproduce", "format_table",
           "write_results", "write_case_figures"]

#: Chains evaluated for every case, in table order (:func:`raysim.vocabulary.parse_chains`).
DEFAULT_CHAINS = ("none", "paper", "paper:published", "exact")
#: IMU sample rate of the reproduction [Hz].
IMU_RATE = 1000.0
#: Metrics of every row (mean and ``_std`` over seeds), names of :data:`raysim.vocabulary.METRICS`.
ROW_METRICS = ("pseudo_velocity_mps", "pseudo_velocity_bins", "doppler_width_hz",
               "width_improvement_pct", "width_vs_stationary", "angle_error_deg", "az_deg",
               "el_deg", "entropy_ae_nats", "entropy_vs_stationary", "map_az_deg", "map_el_deg")


@dataclass(frozen=True)
class ReproductionSettings:
    """Sizes and grids of a reproduction run.

    Attributes
    ----------
    sample_rate : float or None
        ADC rate override [Hz] (None keeps the paper's 10 MHz). A lower rate
        keeps range resolution and every motion effect, only shrinking the
        unambiguous range window.
    yaw_frames : int or None
        Frames accumulated in multi-frame cases (None keeps the case's 20).
    angle_half_width_deg, angle_step_deg : float
        Local azimuth/elevation grid around the truth for the single-chirp
        angle estimate [deg]; default the pipeline's grid
        (:data:`~raysim.pipeline.analysis.SINGLE_CHIRP_HALF_WIDTH_DEG`,
        :data:`~raysim.pipeline.analysis.SINGLE_CHIRP_STEP_DEG`).
    map_half_width_deg, map_step_deg : float
        Azimuth-elevation grid of the accumulated AE map (entropy) [deg].
    map_taper_sll_db : float or None
        Sidelobe level of the separable Taylor taper (nbar 4) used for the
        accumulated AE map [dB]; None for uniform weights.
    range_half_width : float
        Range window of the RA/RD figures around the target [m].
    imu_rate : float
        IMU output rate [Hz].
    velocity : {"given", "hover"}
        Initial-velocity handling of the strapdown integration.
    """

    sample_rate: float | None = None
    yaw_frames: int | None = None
    angle_half_width_deg: float = SINGLE_CHIRP_HALF_WIDTH_DEG
    angle_step_deg: float = SINGLE_CHIRP_STEP_DEG
    map_half_width_deg: float = 30.0
    map_step_deg: float = 1.0
    map_taper_sll_db: float | None = 35.0
    range_half_width: float = 3.0
    imu_rate: float = IMU_RATE
    velocity: str = "given"

    def __post_init__(self) -> None:
        if self.velocity not in VELOCITY_MODES:
            raise ValueError(f"velocity: got {self.velocity!r}, expected one of "
                             f"{list(VELOCITY_MODES)}")
        if not (self.imu_rate > 0 and math.isfinite(self.imu_rate)):
            raise ValueError(f"imu_rate: got {self.imu_rate!r}, expected a positive rate in Hz")

    @classmethod
    def quick(cls, **changes) -> ReproductionSettings:
        """Reduced sizes for tests: 2.5 MHz sampling, coarser accumulated map."""
        base = dict(sample_rate=2.5e6, map_step_deg=2.0, map_half_width_deg=24.0,
                    range_half_width=1.5)
        base.update(changes)
        return cls(**base)


@dataclass
class _CaseData:
    name: str
    scenario: Scenario
    paper: dict                    # chain -> metric -> the paper's value
    config: object
    trajectory: object
    lever_arm: np.ndarray
    positions: np.ndarray
    grid_shape: tuple
    range_axis: np.ndarray
    gate: int
    window: np.ndarray
    rc_window: np.ndarray          # [chirp, channel, window] frame 0
    rc_gate: np.ndarray            # [frame, chirp, channel, 1]
    chirp_times: np.ndarray        # [frame, chirp]
    target_az: float               # [rad]
    target_el: float               # [rad]
    u_true: np.ndarray
    az_a: np.ndarray
    el_a: np.ndarray
    az_m: np.ndarray
    el_m: np.ndarray
    map_weights: np.ndarray | None = None
    stationary: dict = field(default_factory=dict)


def case_scenario(name: str, settings: ReproductionSettings | None = None) -> Scenario:
    """The scenario of a paper case with the settings' sample rate and frame count."""
    settings = ReproductionSettings() if settings is None else settings
    s = scenario_from_case(name)
    changes: dict = {}
    if settings.sample_rate is not None:
        changes["radar.sample_rate_hz"] = float(settings.sample_rate)
    if settings.yaw_frames is not None and s.frames > 1:
        changes["frames"] = int(settings.yaw_frames)
    return s.with_values(changes) if changes else s


def _render(scenario: Scenario, trajectory, gate: int, window: np.ndarray):
    """Range-compressed cells of every frame: the gate of all frames, the window of frame 0."""
    source = frame_source(scenario, trajectory)
    rc_gate, times, rc_window = [], [], None
    for f in range(scenario.frames):
        fr = source(f)
        rc = range_compress(fr.data)
        if f == 0:
            rc_window = np.ascontiguousarray(rc[:, :, window])
        rc_gate.append(np.ascontiguousarray(rc[:, :, gate:gate + 1]))
        times.append(fr.chirp_times)
        del fr, rc
    return rc_window, np.stack(rc_gate), np.stack(times)


def _taper(grid_shape, sll_db):
    """Separable Taylor taper ``[channel]`` (x major, y minor), or None."""
    if sll_db is None:
        return None
    from scipy.signal.windows import taylor

    nx, ny = grid_shape
    return np.outer(taylor(nx, nbar=4, sll=sll_db), taylor(ny, nbar=4, sll=sll_db)).ravel()


def prepare_case(name: str, settings: ReproductionSettings) -> _CaseData:
    """Render a case's frames (and its stationary reference) once, keeping the gated cells."""
    case = get_case(name)
    scenario = case_scenario(name, settings)
    cfg, arr, traj = scenario.radar_config(), scenario.virtual_array(), scenario.trajectory()
    ref = reference_target(scenario)
    r_axis = cfg.range_axis()
    gate = int(np.argmin(np.abs(r_axis - ref.range_m)))
    half = int(math.ceil(settings.range_half_width / cfg.range_resolution))
    window = np.arange(max(gate - half, 0), min(gate + half + 1, r_axis.size))
    rc_window, rc_gate, times = _render(scenario, traj, gate, window)
    az, el = math.radians(ref.az_deg), math.radians(ref.el_deg)
    data = _CaseData(
        name=name, scenario=scenario, paper=case["paper"], config=cfg, trajectory=traj,
        lever_arm=scenario.lever_arm, positions=arr.virtual_positions,
        grid_shape=arr.grid_shape, range_axis=r_axis, gate=gate, window=window,
        rc_window=rc_window, rc_gate=rc_gate, chirp_times=times, target_az=az, target_el=el,
        u_true=direction(az, el),
        az_a=_axis(az, settings.angle_half_width_deg, settings.angle_step_deg),
        el_a=_axis(el, settings.angle_half_width_deg, settings.angle_step_deg),
        az_m=_axis(az, settings.map_half_width_deg, settings.map_step_deg),
        el_m=_axis(el, settings.map_half_width_deg, settings.map_step_deg),
        map_weights=_taper(arr.grid_shape, settings.map_taper_sll_db))
    # stationary reference: same scenario at rest (every frame identical, rendered once)
    at_rest = scenario.with_values({"motion": {}, "frames": 1})
    _, rc_g0, _ = _render(at_rest, at_rest.trajectory(), gate, window)
    st = _evaluate(data, parse_chain("none"),
                   rc_gate=np.repeat(rc_g0, rc_gate.shape[0], axis=0))
    data.stationary = {k: st[k] for k in ("doppler_width_hz", "entropy_ae_nats",
                                          "pseudo_velocity_mps")}
    data.stationary["map"] = st["_map"]
    return data


# ----------------------------------------------------------------- metrics
def _doppler(data: _CaseData, slow: np.ndarray) -> dict:
    cfg = data.config
    pv = metrics.pseudo_velocity(slow, cfg.chirp_interval, cfg.center_wavelength)
    return {"pseudo_velocity_mps": pv, "pseudo_velocity_bins": pv / cfg.velocity_resolution,
            "doppler_width_hz": metrics.doppler_mainlobe_width(slow, cfg.chirp_interval)}


def _angle(data: _CaseData, power: np.ndarray) -> dict:
    """Single-chirp metrics of an AE power map ``[azimuth, elevation]`` on the local grid."""
    pk = Map(power, MAPS["ae"], {"azimuth": data.az_a, "elevation": data.el_a}).peak()
    return {"az_deg": math.degrees(pk["azimuth"]), "el_deg": math.degrees(pk["elevation"]),
            "angle_error_deg": metrics.angle_error_deg(pk["azimuth"], pk["elevation"],
                                                       data.target_az, data.target_el),
            "_u_hat": direction(pk["azimuth"], pk["elevation"])}


def _accumulated(data: _CaseData, power: np.ndarray) -> dict:
    """Metrics of the accumulated AE power map ``[azimuth, elevation]``."""
    ae = Map(power, MAPS["ae"], {"azimuth": data.az_m, "elevation": data.el_m})
    pk = ae.peak()
    return {"entropy_ae_nats": ae.entropy(), "map_az_deg": math.degrees(pk["azimuth"]),
            "map_el_deg": math.degrees(pk["elevation"]), "_map": ae}


def _evaluate(data: _CaseData, spec: ChainSpec, motion=None, rc_gate=None) -> dict:
    """Metrics of one chain on the gated cells (``rc_gate`` default: the case's)."""
    rc_gate = data.rc_gate if rc_gate is None else rc_gate
    n_frames = rc_gate.shape[0]
    n = data.config.num_chirps
    if spec.compensated:
        if motion is None:
            raise ValueError(f"chain {spec.key!r} needs motion (the platform pose at every chirp)")
        frames = [motion.select(slice(f * n, (f + 1) * n)) for f in range(n_frames)]
    else:
        frames = [None] * n_frames
    found: list[str] = []

    def beams(rc, mot, az, el, toward=None, weights=None):
        out = project(spec, rc, data.positions, wavelength=data.config.center_wavelength,
                      range_axis=data.range_axis[[data.gate]], azimuth=az, elevation=el,
                      motion=mot, direction=toward, grid_shape=data.grid_shape,
                      weights=weights, range_gates=[0])
        found.extend(w for w in out.warnings if w not in found)
        return out

    c = angle_chirp(n)
    sel = slice(c, c + 1)
    m0 = frames[0]
    one = beams(rc_gate[0][sel], None if m0 is None else m0.select(sel), data.az_a, data.el_a,
                data.u_true)
    out = _angle(data, one.chirp_power(0)[0])
    u_hat = out.pop("_u_hat")      # the paper chain corrects slow time towards its estimate
    out.update(_doppler(data, beams(rc_gate[0], m0, [data.target_az], [data.target_el],
                                    u_hat).data[:, 0, 0, 0]))
    acc = 0.0
    for f in range(n_frames):
        if spec.compensated:
            acc = acc + beams(rc_gate[f], frames[f], data.az_m, data.el_m, u_hat,
                              data.map_weights).coherent_power()[0]
        else:
            mean = rc_gate[f].mean(axis=0, keepdims=True)       # coherent sum commutes
            acc = acc + beams(mean, None, data.az_m, data.el_m,
                              weights=data.map_weights).chirp_power(0)[0]
    out.update(_accumulated(data, acc))
    out["warnings"] = found
    return out


def platform_motion(data: _CaseData, imu: str, seed: int, settings: ReproductionSettings):
    """IMU samples along the scenario's motion, integrated to the pose at every chirp.

    The IMU record is :func:`raysim.pipeline.sensors.imu_record` over the chirps; the
    integration is :func:`raysim.pipeline.estimate.estimate_motion`.
    """
    t = data.chirp_times.ravel()
    samples = imu_record(data.trajectory, imu, rate=settings.imu_rate, times=t, seed=seed)
    return estimate_motion(*samples.to_arrays(), t, lever_arm=data.lever_arm,
                           trajectory=data.trajectory, velocity=settings.velocity)


# ------------------------------------------------------------------ rows
def _paper_values(data: _CaseData, key: str) -> dict:
    """``paper_<metric>`` of the paper's values for a chain (``none``: before, else after)."""
    vals = data.paper.get("none" if key == "none" else "paper", {})
    out = {f"paper_{m}": v for m, v in vals.items()}
    if "az_deg" in vals:
        el = math.radians(vals["el_deg"]) if "el_deg" in vals else data.target_el
        out["paper_angle_error_deg"] = metrics.angle_error_deg(
            math.radians(vals["az_deg"]), el, data.target_az, data.target_el)
    return out


def _summarise(data: _CaseData, key: str, runs: list[dict], unc: dict, imu: str) -> dict:
    st = data.stationary
    for r in runs:
        r["width_improvement_pct"] = 100.0 * (unc["doppler_width_hz"] - r["doppler_width_hz"]) \
            / unc["doppler_width_hz"]
        r["width_vs_stationary"] = r["doppler_width_hz"] / st["doppler_width_hz"]
        r["entropy_vs_stationary"] = r["entropy_ae_nats"] - st["entropy_ae_nats"]
    row = {"case": data.name, "chain": key, "imu": imu if key != "none" else "-",
           "seeds": len(runs), "num_chirps": data.config.num_chirps,
           "frames": int(data.rc_gate.shape[0]),
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
        IMU error seeds; the radar frames are the same for every seed.
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
    unc = _evaluate(data, parse_chain("none"))
    runs: dict[str, list[dict]] = {s.key: [] for s in specs if s.compensated}
    first_motion = None
    for seed in seeds:
        motion = platform_motion(data, imu, seed, settings)
        first_motion = first_motion or motion
        for s in specs:
            if s.compensated:
                runs[s.key].append(_evaluate(data, s, motion))
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
        Number of IMU seeds (0 .. seeds-1).
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
    if int(seeds) < 1:
        raise ValueError(f"seeds must be >= 1, got {seeds!r}")
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
    result = {"meta": {"imu": imu, "seeds": int(seeds), "imu_rate_hz": settings.imu_rate,
                       "velocity": settings.velocity, "chains": keys,
                       "sample_rate_hz": first.radar.sample_rate_hz,
                       "lever_arm_m": first.lever_arm.tolist(),
                       "units": {m: metric_unit(m) for m in ROW_METRICS},
                       "settings": settings.__dict__, "seconds": time.perf_counter() - t0},
              "rows": rows}
    if out_dir is not None:
        write_results(result, out_dir)
    return result
