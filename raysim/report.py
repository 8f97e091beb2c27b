"""Self-contained HTML reports comparing the uncompensated data with the compensation chains.

A report holds, for every available chain (``uncompensated``, ``paper``,
``exact``): range-azimuth, range-elevation, range-Doppler and
azimuth-elevation maps, Doppler cuts of the reference target, the metric table
of :func:`raysim.render.analyse` (with the values the paper reports for a paper
case), the scene entropies, the run parameters (scenario TOML, derived radar
quantities) and the software versions (numpy, sionna-rt, mitsuba, drjit, ...).
Figures are PNGs embedded as base64 ``data:`` URIs, so the single HTML file
can be mailed or archived. The file is written atomically.

Map conventions: power in dB relative to each map's maximum, clipped at
:data:`DYNAMIC_RANGE_DB` below it; range [m], range rate [m/s] (positive
receding), angles [deg] (CONVENTIONS.md).
"""

from __future__ import annotations

import base64
import html
import io
import math
import platform
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from .frame import RadarFrame
from .render import CHAINS, METRIC_UNITS, FeatureUnavailable, Reference

__all__ = ["ReportData", "collect_from_scenario", "collect_from_dataset", "build_report",
           "write_report", "software_versions", "range_angle_map", "DYNAMIC_RANGE_DB"]

#: Colour-scale depth of the maps [dB].
DYNAMIC_RANGE_DB = 40.0
#: Most chirps summed (non-coherently) into the range-angle maps.
RANGE_ANGLE_CHIRPS = 16
#: Distributions whose versions the report lists.
VERSION_PACKAGES = ("raysim", "numpy", "scipy", "xarray", "zarr", "dask", "matplotlib",
                    "sionna-rt", "mitsuba", "drjit", "pydantic")


@dataclass
class ReportData:
    """Everything a report shows, independent of where the frames came from.

    Attributes
    ----------
    title : str
    frames : dict
        Chain name -> list of :class:`~raysim.frame.RadarFrame` (same radar).
    reference : Reference or None
        Truth target.
    scenario_toml : str
        Run parameters as TOML ('' when unknown).
    paper : dict
        Values the paper reports for this case (may be empty).
    notes : list of str
        Chains that could not run, and why.
    source : str
        Where the frames came from (scenario file, store path).
    """

    title: str
    frames: dict
    reference: Reference | None = None
    scenario_toml: str = ""
    paper: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    source: str = ""


# ------------------------------------------------------------------ collect
def collect_from_scenario(scenario, *, chains: Sequence[str] = CHAINS,
                          source: str = "") -> ReportData:
    """Render a scenario in memory and apply every available chain."""
    from .render import evaluate

    res = evaluate(scenario, chains=chains, return_frames=True)
    return ReportData(scenario.name, res["frames"], res["reference"], scenario.to_toml(),
                      _paper_values(scenario), list(res["notes"]), source or scenario.name)


def _paper_values(scenario) -> dict:
    if scenario is None or scenario.motion.case is None:
        return {}
    from .cases import get_case

    return dict(get_case(scenario.motion.case).paper)


def collect_from_dataset(ds, *, chains: Sequence[str] = CHAINS, source: str = "") -> ReportData:
    """Frames of a stored Dataset (Zarr / NetCDF) plus the chains its IMU log allows."""
    from .render import compensate
    from .storage import dataset_to_frames, scenario_of

    frames = dataset_to_frames(ds)
    scenario = scenario_of(ds)
    ref = None
    if "reference_range_m" in ds.attrs:
        ref = Reference(float(ds.attrs["reference_range_m"]), float(ds.attrs["reference_az_deg"]),
                        float(ds.attrs["reference_el_deg"]))
    out = ReportData(str(ds.attrs.get("scenario_name", "stored frames")), {}, ref,
                     scenario.to_toml() if scenario is not None else "",
                     _paper_values(scenario), [], source)
    imu = ds[["imu_gyro", "imu_accel"]] if "imu_gyro" in ds else None
    for chain in chains:
        if chain == "uncompensated":
            out.frames[chain] = frames
            continue
        if imu is None:
            out.notes.append(f"{chain}: the store has no IMU log")
            continue
        try:
            out.frames[chain] = compensate(frames, chain, imu, scenario=scenario)
        except (FeatureUnavailable, ImportError) as exc:
            out.notes.append(f"{chain}: {exc}")
    return out


# ------------------------------------------------------------------- maps
def range_angle_map(frame: RadarFrame, look: str, fixed_deg: float, *,
                    limit_deg: float = 60.0, step_deg: float = 1.0,
                    max_chirps: int = RANGE_ANGLE_CHIRPS):
    """Range-azimuth (``look="azimuth"``) or range-elevation map of one frame.

    Beam scan over ``+-limit_deg`` with the other angle fixed at ``fixed_deg``,
    power summed over up to ``max_chirps`` evenly spaced chirps.

    Returns
    -------
    raysim.processing.Map
        dims ``(range, azimuth)`` or ``(range, elevation)``; angle coordinate [rad].
    """
    from .processing import Map, az_el_grid, beamform, range_compress

    if look not in ("azimuth", "elevation"):
        raise ValueError(f"look: got {look!r}, expected 'azimuth' or 'elevation'")
    cfg, arr = frame.config, frame.array
    step = max(1, frame.data.shape[0] // max_chirps)
    rc = range_compress(frame.data[::step])                     # [chirp, channel, range]
    ang = np.deg2rad(np.arange(-limit_deg, limit_deg + 1e-9, step_deg))
    fixed = np.array([math.radians(fixed_deg)])
    u = az_el_grid(ang, fixed) if look == "azimuth" else az_el_grid(fixed, ang)
    y = beamform(np.swapaxes(rc, 1, 2), arr, cfg.center_wavelength, u)  # [chirp, range, angle]
    power = np.sum(np.abs(y) ** 2, axis=0)
    n = rc.shape[-1]
    return Map(power, ("range", look), {"range": cfg.range_axis(n)[:n], look: ang})


def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _map_figure(maps: dict, kind: str, reference: Reference | None, max_range: float | None):
    import matplotlib.pyplot as plt

    chains = list(maps)
    fig, axes = plt.subplots(1, len(chains), figsize=(4.2 * len(chains), 3.6), squeeze=False)
    for ax, chain in zip(axes[0], chains, strict=True):
        m = maps[chain]
        db = m.db(-DYNAMIC_RANGE_DB)
        d0, d1 = m.dims
        c0 = np.asarray(m.coords[d0], dtype=float)
        c1 = np.asarray(m.coords[d1], dtype=float)
        if d1 in ("azimuth", "elevation"):
            c1 = np.degrees(c1)
        if d0 in ("azimuth", "elevation"):
            c0 = np.degrees(c0)
        # x: second axis (angle / doppler / elevation), y: first (range / azimuth)
        extent = [c1[0], c1[-1], c0[0], c0[-1]]
        im = ax.imshow(db, origin="lower", aspect="auto", extent=extent, cmap="viridis",
                       vmin=-DYNAMIC_RANGE_DB, vmax=0.0, interpolation="nearest")
        labels = {"range": "range [m]", "doppler": "range rate [m/s]",
                  "azimuth": "azimuth [deg]", "elevation": "elevation [deg]"}
        ax.set_xlabel(labels[d1])
        ax.set_ylabel(labels[d0])
        if d0 == "range" and max_range is not None:
            ax.set_ylim(0, max_range)
        if reference is not None:
            mark = {"range": reference.range_m, "azimuth": reference.az_deg,
                    "elevation": reference.el_deg, "doppler": 0.0}
            ax.plot(mark[d1], mark[d0], marker="+", color="red", markersize=12, mew=1.5)
        ax.set_title(f"{chain}: {kind}")
    fig.colorbar(im, ax=axes[0].tolist(), label="power [dB rel. max]", shrink=0.9)
    return fig


def _doppler_figure(slow: dict, cfg):
    import matplotlib.pyplot as plt

    from .metrics import doppler_power_spectrum

    fig, ax = plt.subplots(figsize=(8, 3.4))
    for chain, x in slow.items():
        f, p = doppler_power_spectrum(x, cfg.chirp_interval)
        ax.plot(f * cfg.center_wavelength / 2.0, 10 * np.log10(np.maximum(p / p.max(), 1e-12)),
                label=chain)
    ax.set_xlabel("range rate [m/s]  (f_D lambda / 2, positive receding)")
    ax.set_ylabel("power [dB rel. peak]")
    ax.set_ylim(-60, 3)
    ax.axhline(-3.0, color="grey", lw=0.6, ls=":")
    ax.grid(alpha=0.3)
    ax.legend()
    ax.set_title("Doppler cut at the target (Hann, 16x zero padding)")
    return fig


def software_versions() -> dict:
    """Installed versions of :data:`VERSION_PACKAGES` plus Python ('not installed' if absent)."""
    from importlib import metadata

    out = {"python": platform.python_version()}
    for dist in VERSION_PACKAGES:
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            out[dist] = "not installed"
    try:
        import compensation

        out["compensation"] = getattr(compensation, "__version__", "present")
    except ImportError:
        out["compensation"] = "not installed"
    return out


# ----------------------------------------------------------------- html
_CSS = """
body{font-family:system-ui,-apple-system,Segoe UI,sans-serif;margin:24px auto;max-width:1400px;
color:#1d2430;background:#fff}
h1{font-size:1.6em;margin-bottom:0}h2{border-bottom:1px solid #ccd;padding-bottom:4px;
margin-top:1.8em}
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccd;padding:4px 10px;
text-align:right}th{background:#eef1f6}td:first-child,th:first-child{text-align:left}
pre{background:#f5f6f8;padding:10px;overflow:auto;font-size:0.85em;max-height:420px}
img{max-width:100%;height:auto}.note{color:#8a4b00}.muted{color:#667}
"""


def _fmt(v) -> str:
    if isinstance(v, float):
        return "-" if not math.isfinite(v) else f"{v:.4g}"
    if isinstance(v, (tuple, list)):
        return ", ".join(_fmt(x) for x in v)
    return html.escape(str(v))


def build_report(data: ReportData) -> str:
    """HTML text of a report (figures embedded)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    from .render import analyse

    if not data.frames:
        raise ValueError("nothing to report: no chain produced frames")
    chains = [c for c in CHAINS if c in data.frames]
    first = data.frames[chains[0]][0]
    cfg, arr = first.config, first.array
    ref = data.reference
    metrics, rd, ae, ra, re_, slow = {}, {}, {}, {}, {}, {}
    for chain in chains:
        frames = data.frames[chain]
        m, maps = analyse(frames, ref, return_maps=True)
        metrics[chain] = m
        rd[chain], ae[chain], slow[chain] = maps["rd"], maps["ae"], maps["slow_time"]
        el0 = ref.el_deg if ref is not None else m["el_deg"]
        az0 = ref.az_deg if ref is not None else m["az_deg"]
        ra[chain] = range_angle_map(frames[0], "azimuth", el0)
        re_[chain] = range_angle_map(frames[0], "elevation", az0)
    rmax = min(cfg.max_range, 2.0 * ref.range_m) if ref is not None else None
    figs = [
        ("Range-azimuth maps", _map_figure(ra, "range-azimuth", ref, rmax),
         f"Beam scan at elevation {_fmt(ref.el_deg if ref else float('nan'))} deg, "
         f"up to {RANGE_ANGLE_CHIRPS} chirps of frame 0 summed; red cross: truth."),
        ("Range-elevation maps", _map_figure(re_, "range-elevation", ref, rmax),
         "Beam scan at the target azimuth, frame 0."),
        ("Range-Doppler maps", _map_figure(rd, "range-Doppler", ref, rmax),
         "Hann windows in fast and slow time, power summed over channels, frame 0."),
        ("Azimuth-elevation maps", _map_figure(ae, "azimuth-elevation", None, None),
         "Non-coherent beam scan at the target range gate over all frames; its entropy is "
         "entropy_ae_nats."),
        ("Doppler cuts", _doppler_figure(slow, cfg),
         "Slow-time signal of frame 0 at the target range, beamformed to the target."),
    ]
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
             f"<title>raysim report: {html.escape(data.title)}</title><style>{_CSS}</style>"
             f"</head><body>",
             f"<h1>raysim report: {html.escape(data.title)}</h1>",
             f"<p class='muted'>source: {html.escape(data.source)} &middot; written {now}</p>"]
    if ref is not None:
        parts.append(f"<p>Reference target: range {ref.range_m:.3f} m, azimuth "
                     f"{ref.az_deg:.2f} deg, elevation {ref.el_deg:.2f} deg.</p>")
    for note in data.notes:
        parts.append(f"<p class='note'>Note: {html.escape(note)}</p>")

    parts.append("<h2>Metrics</h2><table><tr><th>metric</th><th>unit</th>"
                 + "".join(f"<th>{c}</th>" for c in chains) + "</tr>")
    for key, unit in METRIC_UNITS.items():
        parts.append(f"<tr><td>{key}</td><td>{unit}</td>"
                     + "".join(f"<td>{_fmt(metrics[c][key])}</td>" for c in chains) + "</tr>")
    parts.append("</table>")
    parts.append("<p class='muted'>CONVENTIONS.md metrics: pseudo-velocity and Doppler width "
                 "from the Hann-windowed, 16x zero-padded slow-time spectrum; a stationary "
                 "platform gives about 1.44 Doppler bins. Entropies in nats of the normalised "
                 "map intensity (lower is sharper): azimuth-elevation map (scene entropy at the "
                 "target range) and range-Doppler map.</p>")
    if data.paper:
        parts.append("<h3>Values reported in the paper</h3><table><tr><th>quantity</th>"
                     "<th>value</th></tr>" + "".join(
                         f"<tr><td>{html.escape(k)}</td><td>{_fmt(v)}</td></tr>"
                         for k, v in data.paper.items()) + "</table>")
    for title, fig, caption in figs:
        parts.append(f"<h2>{title}</h2><img alt='{title}' src='data:image/png;base64,"
                     f"{_png(fig)}'><p class='muted'>{html.escape(caption)}</p>")

    derived = {
        "frames": len(data.frames[chains[0]]), "chirps": cfg.num_chirps,
        "samples per chirp": cfg.num_samples, "channels": arr.num_channels,
        "array": arr.name, "TDM slots": cfg.num_tx_slots,
        "range resolution [m]": cfg.range_resolution, "max range [m]": cfg.max_range,
        "velocity resolution [m/s]": cfg.velocity_resolution,
        "max velocity [m/s]": cfg.max_velocity, "Doppler bin [Hz]": cfg.doppler_resolution,
        "chirp interval [s]": cfg.chirp_interval, "wavelength [m]": cfg.wavelength,
    }
    parts.append("<h2>Run parameters</h2><table>" + "".join(
        f"<tr><td>{html.escape(k)}</td><td>{_fmt(v)}</td></tr>" for k, v in derived.items())
        + "</table>")
    if data.scenario_toml:
        parts.append(f"<h3>Scenario</h3><pre>{html.escape(data.scenario_toml)}</pre>")
    parts.append("<h2>Software versions</h2><table>" + "".join(
        f"<tr><td>{html.escape(k)}</td><td>{html.escape(v)}</td></tr>"
        for k, v in software_versions().items()) + "</table>")
    parts.append("</body></html>")
    return "\n".join(parts)


def write_report(data: ReportData, path: str | Path) -> Path:
    """Build the report and write it atomically to ``path``; returns the path."""
    from .storage import atomic_write_text

    path = Path(path)
    atomic_write_text(path, build_report(data))
    return path
