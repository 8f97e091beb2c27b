"""Reproduction of the paper's experiments with and without motion compensation.

For every case of :mod:`raysim.studies.cases` the exact point-target oracle renders
the IF frames, an IMU (preset of :mod:`raysim.platform.imu`) samples the motion, the
strapdown integration of :mod:`compensation` gives the pose at every chirp,
and four chains are evaluated on the same cubes:

``uncompensated``
    conventional beam scan and Doppler FFT;
``paper``
    the published chain (tilt element phase, slow-time phase of translation
    and of the lever-arm rotation from the integrated displacement, yaw beam
    projection), slow-time phase applied towards the direction estimated by
    that chain at chirp 128;
``paper_vrt``
    the same with the published rotation phase ``v_r(nT) nT``;
``exact``
    the rigid-body projection using all six degrees of freedom.

Metrics (CONVENTIONS.md, :mod:`raysim.processing.metrics`): pseudo-velocity and Doppler
-3 dB width of the target's slow-time signal (target range gate, beam towards
the true direction); angle error of the single-chirp azimuth-elevation map of
chirp 128 (index 127); entropy and peak of the azimuth-elevation map at the
target gate, coherently integrated over each frame and summed in power over
the frames (20 frames for the yaw case).

Initial conditions of the strapdown integration (the flight controller's
state at ``t = 0``): attitude, position and velocity from the truth
trajectory (``velocity="given"``), or the hover assumption.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import time
from dataclasses import dataclass, field

import numpy as np

from compensation import (
    beam_projection,
    integrate_imu,
    paper_chain,
    rigid_body_projection,
)
from raysim.echoes.oracle import direction, simulate_point_targets
from raysim.io.files import atomic_savefig, atomic_write_text
from raysim.platform.imu import get_preset, simulate_imu
from raysim.platform.motion import stationary
from raysim.processing import metrics
from raysim.processing.maps import Map, range_compress
from raysim.studies.cases import PAPER_CASES, PaperCase

#: Chains evaluated for every case, in table order.
CHAINS = ("uncompensated", "paper", "paper_vrt", "exact")
#: Index of "chirp 128" of the paper (0-based).
ANGLE_CHIRP = 127
#: IMU sample rate of the reproduction [Hz].
IMU_RATE = 1000.0
#: IMU record margin before the first and after the last chirp [s].
IMU_MARGIN = 0.02


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
        Frames accumulated in the yaw case (None keeps the case's 20).
    angle_half_width_deg, angle_step_deg : float
        Local azimuth/elevation grid around the truth for the chirp-128 angle
        estimate [deg].
    map_half_width_deg, map_step_deg : float
        Azimuth-elevation grid of the accumulated map (entropy) [deg].
    map_taper_sll_db : float or None
        Sidelobe level of the separable Taylor taper (nbar 4) used for the
        accumulated azimuth-elevation map [dB]; None for uniform weights.
    range_half_width : float
        Range window of the RA/RD figures around the target [m].
    imu_rate : float
        IMU output rate [Hz].
    velocity : {"given", "hover"}
        Initial-velocity handling of the strapdown integration.
    """

    sample_rate: float | None = None
    yaw_frames: int | None = None
    angle_half_width_deg: float = 15.0
    angle_step_deg: float = 0.5
    map_half_width_deg: float = 30.0
    map_step_deg: float = 1.0
    map_taper_sll_db: float | None = 35.0
    range_half_width: float = 3.0
    imu_rate: float = IMU_RATE
    velocity: str = "given"

    @classmethod
    def quick(cls, **changes) -> ReproductionSettings:
        """Reduced sizes for tests: 2.5 MHz sampling, coarser angle grids."""
        base = dict(sample_rate=2.5e6, angle_step_deg=0.5, angle_half_width_deg=12.0,
                    map_step_deg=2.0, map_half_width_deg=24.0, range_half_width=1.5)
        base.update(changes)
        return cls(**base)


def _axis(centre: float, half_deg: float, step_deg: float) -> np.ndarray:
    n = int(round(half_deg / step_deg))
    return centre + np.deg2rad(np.arange(-n, n + 1) * step_deg)


@dataclass
class _CaseData:
    case: PaperCase
    config: object
    positions: np.ndarray
    grid_shape: tuple
    range_axis: np.ndarray
    gate: int
    window: np.ndarray
    rc_window: np.ndarray          # [chirp, channel, window] frame 0
    rc_gate: np.ndarray            # [frame, chirp, channel, 1]
    chirp_times: np.ndarray        # [frame, chirp]
    u_true: np.ndarray
    az_a: np.ndarray
    el_a: np.ndarray
    az_m: np.ndarray
    el_m: np.ndarray
    map_weights: np.ndarray | None = None
    stationary: dict = field(default_factory=dict)


def _render(case: PaperCase, settings: ReproductionSettings, trajectory, num_frames: int):
    cfg = case.config
    if settings.sample_rate is not None:
        cfg = cfg.with_(sample_rate=settings.sample_rate)
    cfg = cfg.with_(num_frames=num_frames)
    arr = case.array()
    r_axis = cfg.range_axis()
    gate = int(np.argmin(np.abs(r_axis - case.target_range)))
    half = int(math.ceil(settings.range_half_width / cfg.range_resolution))
    window = np.arange(max(gate - half, 0), min(gate + half + 1, r_axis.size))
    rc_gate, times, rc_window = [], [], None
    for f in range(num_frames):
        fr = simulate_point_targets(cfg, arr, [case.target()], trajectory,
                                    lever_arm=case.lever_arm, frame=f)
        rc = range_compress(fr.data)
        if f == 0:
            rc_window = np.ascontiguousarray(rc[:, :, window])
        rc_gate.append(np.ascontiguousarray(rc[:, :, gate:gate + 1]))
        times.append(fr.chirp_times)
        del fr, rc
    return cfg, arr, r_axis, gate, window, rc_window, np.stack(rc_gate), np.stack(times)


def _taper(grid_shape, sll_db):
    """Separable Taylor taper ``[channel]`` (x major, y minor), or None."""
    if sll_db is None:
        return None
    from scipy.signal.windows import taylor

    nx, ny = grid_shape
    return np.outer(taylor(nx, nbar=4, sll=sll_db), taylor(ny, nbar=4, sll=sll_db)).ravel()


def prepare_case(case: PaperCase, settings: ReproductionSettings) -> _CaseData:
    """Render a case's frames (and its stationary reference) once, keeping the gated cells."""
    frames = case.num_frames if settings.yaw_frames is None or case.num_frames == 1 \
        else int(settings.yaw_frames)
    cfg, arr, r_axis, gate, window, rc_window, rc_gate, times = _render(
        case, settings, case.trajectory, frames)
    data = _CaseData(
        case=case, config=cfg, positions=arr.virtual_positions, grid_shape=arr.grid_shape,
        range_axis=r_axis, gate=gate, window=window, rc_window=rc_window, rc_gate=rc_gate,
        chirp_times=times, u_true=direction(case.target_az, case.target_el),
        az_a=_axis(case.target_az, settings.angle_half_width_deg, settings.angle_step_deg),
        el_a=_axis(case.target_el, settings.angle_half_width_deg, settings.angle_step_deg),
        az_m=_axis(case.target_az, settings.map_half_width_deg, settings.map_step_deg),
        el_m=_axis(case.target_el, settings.map_half_width_deg, settings.map_step_deg),
        map_weights=_taper(arr.grid_shape, settings.map_taper_sll_db))
    # stationary reference: same target and grids, platform at rest (every frame identical)
    _, _, _, _, _, rc_w0, rc_g0, _ = _render(case, settings, stationary(), 1)
    ref = _evaluate_uncompensated(data, rc_gate=np.repeat(rc_g0, frames, axis=0))
    data.stationary = {"width_hz": ref["doppler_width_hz"], "entropy": ref["entropy"],
                       "pseudo_velocity_mps": ref["pseudo_velocity_mps"],
                       "map": ref["_map"]}
    return data


# ----------------------------------------------------------------- metrics
def _doppler(data: _CaseData, slow: np.ndarray) -> dict:
    cfg = data.config
    pv = metrics.pseudo_velocity(slow, cfg.chirp_interval, cfg.center_wavelength)
    return {"pseudo_velocity_mps": pv, "pseudo_velocity_bins": pv / cfg.velocity_resolution,
            "doppler_width_hz": metrics.doppler_mainlobe_width(slow, cfg.chirp_interval)}


def _angle(data: _CaseData, power: np.ndarray) -> dict:
    m = Map(power, ("azimuth", "elevation"), {"azimuth": data.az_a, "elevation": data.el_a})
    pk = m.peak()
    c = data.case
    return {"az_deg": math.degrees(pk["azimuth"]), "el_deg": math.degrees(pk["elevation"]),
            "angle_error_deg": metrics.angle_error_deg(pk["azimuth"], pk["elevation"],
                                                       c.target_az, c.target_el),
            "_u_hat": direction(pk["azimuth"], pk["elevation"])}


def _accumulated(data: _CaseData, power: np.ndarray) -> dict:
    m = Map(power, ("azimuth", "elevation"), {"azimuth": data.az_m, "elevation": data.el_m})
    pk = m.peak()
    return {"entropy": metrics.image_entropy(power),
            "map_az_deg": math.degrees(pk["azimuth"]), "map_el_deg": math.degrees(pk["elevation"]),
            "_map": power}


def _common(data: _CaseData) -> dict:
    return dict(element_positions=data.positions, wavelength=data.config.center_wavelength,
                range_axis=data.range_axis[[data.gate]], range_gates=[0],
                grid_shape=data.grid_shape)


def _evaluate_uncompensated(data: _CaseData, rc_gate=None) -> dict:
    rc_gate = data.rc_gate if rc_gate is None else rc_gate
    kw = _common(data)
    c = data.case
    slow = beam_projection(rc_gate[0], azimuth=[c.target_az], elevation=[c.target_el],
                           **kw).data[:, 0, 0, 0]
    out = _doppler(data, slow)
    one = beam_projection(rc_gate[0][ANGLE_CHIRP:ANGLE_CHIRP + 1], azimuth=data.az_a,
                          elevation=data.el_a, **kw)
    out.update(_angle(data, one.chirp_power(0)[0]))
    acc = 0.0
    for f in range(rc_gate.shape[0]):
        mean = rc_gate[f].mean(axis=0, keepdims=True)       # coherent sum commutes
        acc = acc + beam_projection(mean, azimuth=data.az_m, elevation=data.el_m,
                                    weights=data.map_weights, **kw).chirp_power(0)[0]
    out.update(_accumulated(data, acc))
    return out


def _evaluate_compensated(data: _CaseData, motion, chain: str) -> dict:
    kw = _common(data)
    c = data.case
    n = data.config.num_chirps
    frames = [motion.select(slice(f * n, (f + 1) * n)) for f in range(data.rc_gate.shape[0])]
    rp = "published" if chain == "paper_vrt" else "integrated"

    def run(rc, mot, az, el, u=None, weights=None):
        if chain == "exact":
            return rigid_body_projection(rc, motion=mot, azimuth=az, elevation=el,
                                         weights=weights, **kw)
        return paper_chain(rc, motion=mot, azimuth=az, elevation=el, rotation_phase=rp,
                           direction=data.u_true if u is None else u, weights=weights, **kw)

    found: list[str] = []

    def noted(beams):
        found.extend(w for w in beams.warnings if w not in found)
        return beams

    sel = slice(ANGLE_CHIRP, ANGLE_CHIRP + 1)
    ang = _angle(data, noted(run(data.rc_gate[0][sel], frames[0].select(sel), data.az_a,
                                 data.el_a)).chirp_power(0)[0])
    u_hat = ang["_u_hat"]          # the paper chain corrects slow time towards its estimate
    out = _doppler(data, noted(run(data.rc_gate[0], frames[0], [c.target_az], [c.target_el],
                                   u_hat)).data[:, 0, 0, 0])
    out.update(ang)
    acc = 0.0
    for f, mot in enumerate(frames):
        acc = acc + noted(run(data.rc_gate[f], mot, data.az_m, data.el_m, u_hat,
                              data.map_weights)).coherent_power()[0]
    out.update(_accumulated(data, acc))
    out["warnings"] = found
    return out


def platform_motion(data: _CaseData, imu: str, seed: int, settings: ReproductionSettings):
    """IMU samples along the case trajectory, integrated to the pose at every chirp."""
    case = data.case
    t = data.chirp_times.ravel()
    samples = simulate_imu(case.trajectory, imu, rate=settings.imu_rate,
                           start=t[0] - IMU_MARGIN, end=t[-1] + IMU_MARGIN, seed=seed)
    t_ref = float(t[0])
    kwargs = {}
    if settings.velocity == "given":
        kwargs["initial_velocity"] = case.trajectory.velocity([t_ref])[0]
    return integrate_imu(*samples.to_arrays(), t, lever_arm=case.lever_arm,
                         reference_time=t_ref,
                         initial_attitude=case.trajectory.attitude([t_ref]).as_matrix()[0],
                         initial_position=case.trajectory.position([t_ref])[0],
                         velocity=settings.velocity, **kwargs)


# ------------------------------------------------------------------ tables
_METRICS = ("pseudo_velocity_mps", "pseudo_velocity_bins", "doppler_width_hz",
            "width_improvement_pct", "width_vs_stationary", "angle_error_deg", "az_deg",
            "el_deg", "entropy", "entropy_vs_stationary", "map_az_deg", "map_el_deg")


def _paper_values(case: PaperCase, chain: str) -> dict:
    p = case.paper
    before = chain == "uncompensated"
    out = {}
    if "pseudo_velocity_before" in p:
        out["paper_pseudo_velocity_mps"] = p["pseudo_velocity_before" if before
                                             else "pseudo_velocity_after"]
        out["paper_doppler_width_hz"] = p["width_before_hz" if before else "width_after_hz"]
        if not before:
            out["paper_width_improvement_pct"] = p["width_improvement_pct"]
    if "az_before_deg" in p:
        az = p["az_before_deg" if before else "az_after_deg"]
        out["paper_angle_error_deg"] = metrics.angle_error_deg(
            math.radians(az), case.target_el, case.target_az, case.target_el)
    if "az_el_before_deg" in p:
        az, el = p["az_el_before_deg" if before else "az_el_after_deg"]
        out["paper_angle_error_deg"] = metrics.angle_error_deg(
            math.radians(az), math.radians(el), case.target_az, case.target_el)
        out["paper_entropy"] = p["entropy_before" if before else "entropy_after"]
    return out


def _summarise(data: _CaseData, chain: str, runs: list[dict], unc: dict, imu: str) -> dict:
    st = data.stationary
    for r in runs:
        r["width_improvement_pct"] = 100.0 * (unc["doppler_width_hz"] - r["doppler_width_hz"]) \
            / unc["doppler_width_hz"]
        r["width_vs_stationary"] = r["doppler_width_hz"] / st["width_hz"]
        r["entropy_vs_stationary"] = r["entropy"] - st["entropy"]
    row = {"case": data.case.name, "chain": chain, "imu": imu if chain != "uncompensated"
           else "-", "seeds": len(runs), "num_chirps": data.config.num_chirps,
           "frames": int(data.rc_gate.shape[0]),
           "velocity_bin_mps": data.config.velocity_resolution,
           "doppler_bin_hz": data.config.doppler_resolution,
           "stationary_width_hz": st["width_hz"], "stationary_entropy": st["entropy"]}
    for key in _METRICS:
        vals = np.array([r[key] for r in runs], dtype=float)
        row[key] = float(vals.mean())
        row[key + "_std"] = float(vals.std(ddof=1)) if vals.size > 1 else 0.0
    row.update(_paper_values(data.case, chain))
    found: list[str] = []
    for r in runs:
        found.extend(w for w in r.get("warnings", ()) if w not in found)
    row["warnings"] = " | ".join(found)
    return row


def run_case(case: PaperCase, *, imu: str = "ideal", seeds=(0,),
             settings: ReproductionSettings | None = None, figures_dir: str | None = None,
             chains=CHAINS) -> list[dict]:
    """Evaluate every chain on one case; one table row per chain (mean and std over seeds).

    Parameters
    ----------
    case : PaperCase
    imu : str
        IMU preset name (``ideal``, ``tactical``, ``consumer_mems``).
    seeds : sequence of int
        IMU error seeds; the radar frames are the same for every seed.
    settings : ReproductionSettings, optional
    figures_dir : str, optional
        Write RA/RD/RE figures (first seed) there.
    chains : sequence of str
        Subset of :data:`CHAINS`.

    Returns
    -------
    list of dict
        Rows with the metrics (``*_std`` over seeds), the stationary
        reference, the paper's values and ``warnings``: the distinct
        ``BeamCube.warnings`` of the chain over all seeds, joined by ``" | "``
        (empty when every assumption held).
    """
    settings = ReproductionSettings() if settings is None else settings
    get_preset(imu)
    seeds = list(seeds)
    if not seeds:
        raise ValueError("seeds must hold at least one seed")
    for ch in chains:
        if ch not in CHAINS:
            raise ValueError(f"chains entries must be in {CHAINS}, got {ch!r}")
    data = prepare_case(case, settings)
    unc = _evaluate_uncompensated(data)
    runs: dict[str, list[dict]] = {ch: [] for ch in chains if ch != "uncompensated"}
    first_motion = None
    for seed in seeds:
        motion = platform_motion(data, imu, seed, settings)
        first_motion = first_motion or motion
        for ch in runs:
            runs[ch].append(_evaluate_compensated(data, motion, ch))
    rows = []
    if "uncompensated" in chains:
        rows.append(_summarise(data, "uncompensated", [unc], unc, imu))
    rows.extend(_summarise(data, ch, runs[ch], unc, imu) for ch in runs)
    if figures_dir is not None:
        write_case_figures(data, first_motion, figures_dir, imu=imu,
                           maps={"uncompensated": unc["_map"],
                                 **{ch: runs[ch][0]["_map"] for ch in runs},
                                 "stationary": data.stationary["map"]})
    return rows


def reproduce(cases=None, *, imu: str = "ideal", seeds: int = 1,
              settings: ReproductionSettings | None = None, out_dir: str | None = None,
              figures: bool = True, chains=CHAINS, progress=None) -> dict:
    """Run the paper's experiments and (optionally) write the table and figures.

    Parameters
    ----------
    cases : sequence of str, optional
        Case names (default all of :data:`raysim.studies.cases.PAPER_CASES`).
    imu : str
        IMU preset.
    seeds : int
        Number of IMU seeds (0 .. seeds-1).
    settings : ReproductionSettings, optional
    out_dir : str, optional
        Directory for ``reproduction.json``, ``reproduction.csv`` and figures.
    figures : bool
        Write the RA/RD/RE figures into ``out_dir/figures``.
    chains : sequence of str
        Subset of :data:`CHAINS`.
    progress : callable, optional
        Called with a message string after each case.

    Returns
    -------
    dict
        ``{"meta": {...}, "rows": [...]}``.
    """
    settings = ReproductionSettings() if settings is None else settings
    names = list(PAPER_CASES) if not cases else list(cases)
    for name in names:
        if name not in PAPER_CASES:
            raise ValueError(f"unknown case {name!r}; expected some of {sorted(PAPER_CASES)}")
    if int(seeds) < 1:
        raise ValueError(f"seeds must be >= 1, got {seeds!r}")
    fig_dir = None
    if out_dir is not None:
        os.makedirs(out_dir, exist_ok=True)
    if out_dir is not None and figures:
        fig_dir = os.path.join(out_dir, "figures")
        os.makedirs(fig_dir, exist_ok=True)
    rows = []
    t0 = time.perf_counter()
    for name in names:
        rows.extend(run_case(PAPER_CASES[name], imu=imu, seeds=range(int(seeds)),
                             settings=settings, figures_dir=fig_dir, chains=chains))
        if progress is not None:
            progress(f"{name}: done after {time.perf_counter() - t0:.1f} s")
    result = {"meta": {"imu": imu, "seeds": int(seeds), "imu_rate_hz": settings.imu_rate,
                       "velocity": settings.velocity,
                       "sample_rate_hz": settings.sample_rate or PAPER_CASES[names[0]]
                       .config.sample_rate,
                       "lever_arm_m": PAPER_CASES[names[0]].lever_arm.tolist(),
                       "settings": settings.__dict__, "seconds": time.perf_counter() - t0},
              "rows": rows}
    if out_dir is not None:
        write_results(result, out_dir)
    return result


def write_results(result: dict, out_dir: str) -> tuple[str, str]:
    """Write ``reproduction.json`` and ``reproduction.csv`` atomically; returns both paths."""
    rows = result["rows"]
    jpath = os.path.join(out_dir, "reproduction.json")
    cpath = os.path.join(out_dir, "reproduction.csv")
    atomic_write_text(jpath, json.dumps(result, indent=2, default=float) + "\n")
    keys: list[str] = []
    for r in rows:
        keys.extend(k for k in r if k not in keys)
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=keys)
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(cpath, buf.getvalue())
    return jpath, cpath


def _fmt(row: dict, key: str, digits: int) -> str:
    v = row.get(key)
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    s = f"{v:.{digits}f}"
    if row.get("seeds", 1) > 1 and key + "_std" in row:
        s += f" +-{row[key + '_std']:.{digits}f}"
    return s


#: Table columns: (header, row key, decimals); ``None`` key = text column.
_COLUMNS = (
    ("case", "case", None), ("chain", "chain", None), ("imu", "imu", None),
    ("pv [m/s]", "pseudo_velocity_mps", 3), ("paper", "paper_pseudo_velocity_mps", 3),
    ("pv [bins]", "pseudo_velocity_bins", 3),
    ("width [Hz]", "doppler_width_hz", 1), ("paper", "paper_doppler_width_hz", 1),
    ("width/stat", "width_vs_stationary", 3),
    ("impr [%]", "width_improvement_pct", 1), ("paper", "paper_width_improvement_pct", 1),
    ("angle err [deg]", "angle_error_deg", 3), ("paper", "paper_angle_error_deg", 2),
    ("entropy [nats]", "entropy", 3), ("paper", "paper_entropy", 2),
    ("stat. entropy", "stationary_entropy", 3),
)


def format_table(rows: list[dict]) -> str:
    """Plain-text table: our numbers (mean +- std over seeds) beside the paper's."""
    cells = [[h for h, _, _ in _COLUMNS]]
    for r in rows:
        cells.append([str(r.get(k, "-")) if d is None else _fmt(r, k, d)
                      for _, k, d in _COLUMNS])
    widths = [max(len(c[i]) for c in cells) for i in range(len(_COLUMNS))]
    lines = []
    for j, row in enumerate(cells):
        parts = [c.ljust(w) if _COLUMNS[i][2] is None else c.rjust(w)
                 for i, (c, w) in enumerate(zip(row, widths, strict=True))]
        lines.append("  ".join(parts))
        if j == 0:
            lines.append("-" * len(lines[0]))
    return "\n".join(lines)


# ----------------------------------------------------------------- figures
def _chain_beams(data: _CaseData, motion, chain: str, rc, az, el, u_hat=None):
    """Beams of one chain on the figure window (frame 0 cells given in ``rc``)."""
    kw = dict(element_positions=data.positions, wavelength=data.config.center_wavelength,
              range_axis=data.range_axis[data.window], grid_shape=data.grid_shape,
              azimuth=az, elevation=el)
    if chain == "uncompensated":
        return beam_projection(rc, chirp_time=motion.time, **kw)
    if chain == "exact":
        return rigid_body_projection(rc, motion=motion, **kw)
    rp = "published" if chain == "paper_vrt" else "integrated"
    return paper_chain(rc, motion=motion, direction=data.u_true if u_hat is None else u_hat,
                       rotation_phase=rp, **kw)


def write_case_figures(data: _CaseData, motion, folder: str, *, imu: str, maps: dict) -> list:
    """RA (chirp 128), RD (beam towards the target) and RE (accumulated) maps per chain.

    Writes ``<case>_<imu>_{ra,rd,re}.png`` into ``folder`` (temporary file, then
    ``os.replace``); returns the paths.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    c = data.case
    n = data.config.num_chirps
    m0 = motion.select(slice(0, n))
    chains = [ch for ch in CHAINS if ch in maps]
    r = data.range_axis[data.window]
    sel = slice(ANGLE_CHIRP, ANGLE_CHIRP + 1)
    paths = []

    def save(fig, kind):
        path = os.path.join(folder, f"{c.name}_{imu}_{kind}.png")
        atomic_savefig(fig, path, dpi=90)
        plt.close(fig)
        paths.append(path)

    def db(p):
        p = np.asarray(p, dtype=float)
        return 10 * np.log10(np.maximum(p / p.max(), 1e-6))

    # RA: chirp 128 at the target elevation
    fig, axes = plt.subplots(1, len(chains), figsize=(4 * len(chains), 3.6), squeeze=False,
                             layout="constrained")
    for ax, ch in zip(axes[0], chains, strict=True):
        b = _chain_beams(data, m0.select(sel), ch, data.rc_window[sel], data.az_m, [c.target_el])
        im = ax.pcolormesh(np.rad2deg(data.az_m), r, db(b.chirp_power(0)[:, :, 0]),
                           vmin=-40, vmax=0, shading="auto")
        ax.axvline(np.rad2deg(c.target_az), color="w", lw=0.6, ls="--")
        ax.set(title=f"{ch}", xlabel="azimuth [deg]", ylabel="range [m]")
    fig.colorbar(im, ax=axes[0].tolist(), label="dB")
    fig.suptitle(f"{c.name}: range-azimuth, chirp {ANGLE_CHIRP + 1}, el "
                 f"{np.rad2deg(c.target_el):.0f} deg ({imu} IMU)")
    save(fig, "ra")

    # RD: beam towards the true direction
    fig, axes = plt.subplots(1, len(chains), figsize=(4 * len(chains), 3.6), squeeze=False,
                             layout="constrained")
    for ax, ch in zip(axes[0], chains, strict=True):
        b = _chain_beams(data, m0, ch, data.rc_window, [c.target_az], [c.target_el])
        spec = np.abs(b.doppler()[:, :, 0, 0]) ** 2
        im = ax.pcolormesh(b.velocity(), r, db(spec.T), vmin=-50, vmax=0, shading="auto")
        ax.set(title=ch, xlabel="range rate [m/s]", ylabel="range [m]", xlim=(-4, 4))
    fig.colorbar(im, ax=axes[0].tolist(), label="dB")
    fig.suptitle(f"{c.name}: range-Doppler towards the target ({imu} IMU)")
    save(fig, "rd")

    # RE: accumulated azimuth-elevation map at the target gate
    keys = chains + (["stationary"] if "stationary" in maps else [])
    fig, axes = plt.subplots(1, len(keys), figsize=(3.6 * len(keys), 3.4), squeeze=False,
                             layout="constrained")
    for ax, ch in zip(axes[0], keys, strict=True):
        im = ax.pcolormesh(np.rad2deg(data.az_m), np.rad2deg(data.el_m), db(maps[ch]).T,
                           vmin=-30, vmax=0, shading="auto")
        ax.plot(np.rad2deg(c.target_az), np.rad2deg(c.target_el), "w+", ms=8)
        ax.set(title=f"{ch}\nH = {metrics.image_entropy(maps[ch]):.2f} nats",
               xlabel="azimuth [deg]", ylabel="elevation [deg]")
    fig.colorbar(im, ax=axes[0].tolist(), label="dB")
    fig.suptitle(f"{c.name}: azimuth-elevation, {data.rc_gate.shape[0]} frame(s) ({imu} IMU)")
    save(fig, "re")
    return paths
