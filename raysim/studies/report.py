"""Self-contained HTML reports comparing the uncompensated data with the compensation chains.

A report holds, for every available chain (``uncompensated``, ``paper``,
``exact``): range-azimuth, range-elevation, range-Doppler and
azimuth-elevation maps, Doppler cuts of the reference target, the metric table
of :func:`raysim.pipeline.analysis.analyse` (with the values the paper reports for a paper
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

from raysim.pipeline.analysis import ANALYSIS_METRICS
from raysim.pipeline.sources import Reference
from raysim.synthesis.frame import RadarFrame
from raysim.vocabulary import CHAINS, metric_unit

__all__ = ["ReportData", "collect_from_scenario", "collect_from_dataset", "build_report",
           "write_report", "software_versions", "DYNAMIC_RANGE_DB"]

#: Colour-scale depth of the maps [dB].
DYNAMIC_RANGE_DB = 40.0
#: Chirps of frame 0 summed (in power) into the range-angle maps.
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
    result : dict
        Output of :func:`raysim.pipeline.run.evaluate` with ``return_maps=True``
        (``reference``, ``chains`` metrics, ``maps``, ``notes``).
    frame : RadarFrame
        Frame 0 (its config and array describe the radar).
    num_frames : int
    scenario_toml : str
        Run parameters as TOML ('' when unknown).
    paper : dict
        Values the paper reports for this case (may be empty).
    source : str
        Where the frames came from (scenario file, store path).
    """

    title: str
    result: dict
    frame: RadarFrame
    num_frames: int = 1
    scenario_toml: str = ""
    paper: dict = field(default_factory=dict)
    source: str = ""


# ------------------------------------------------------------------ collect
def collect_from_scenario(scenario, *, chains: Sequence[str] = CHAINS,
                          source: str = "") -> ReportData:
    """Render a scenario in memory and measure every available chain."""
    from raysim.pipeline.run import evaluate
    from raysim.pipeline.sources import LazyFrames, frame_source

    frames = LazyFrames(frame_source(scenario, scenario.trajectory()), scenario.frames)
    res = evaluate(scenario, chains=chains, frames=frames, reference=frames.reference,
                   return_maps=True)
    return ReportData(scenario.name, res, frames[0], len(frames), scenario.to_toml(),
                      _paper_values(scenario), source or scenario.name)


def _paper_values(scenario) -> dict:
    if scenario is None or scenario.motion.case is None:
        return {}
    from raysim.studies.cases import paper_values

    return paper_values(scenario.motion.case)


def collect_from_dataset(ds, *, chains: Sequence[str] = CHAINS, source: str = "") -> ReportData:
    """Frames of a stored Dataset (Zarr / NetCDF), measured through every chain its IMU log
    and scenario allow."""
    from raysim.io.storage import dataset_to_frames, scenario_of
    from raysim.pipeline.analysis import analyse
    from raysim.pipeline.run import evaluate

    frames = dataset_to_frames(ds)
    scenario = scenario_of(ds)
    ref = None
    if "reference_range_m" in ds.attrs:
        ref = Reference(float(ds.attrs["reference_range_m"]), float(ds.attrs["reference_az_deg"]),
                        float(ds.attrs["reference_el_deg"]))
    title = str(ds.attrs.get("scenario_name", "stored frames"))
    if scenario is None:
        m, maps = analyse(frames, ref, return_maps=True)
        res = {"reference": ref, "chains": {"none": m},
               "maps": {"none": maps},
               "notes": ["the store carries no scenario: compensation chains skipped"]}
        return ReportData(title, res, frames[0], len(frames), "", {}, source)
    imu = ds[["imu_gyro", "imu_accel"]] if "imu_gyro" in ds else None
    notes = []
    if imu is None:
        chains = [c for c in chains if c == "none"]
        notes.append("the store has no IMU log: compensation chains skipped")
    res = evaluate(scenario, chains=chains, frames=frames, imu=imu, reference=ref,
                   return_maps=True)
    res["notes"] = notes + res["notes"]
    return ReportData(title, res, frames[0], len(frames), scenario.to_toml(),
                      _paper_values(scenario), source)


# ------------------------------------------------------------------- maps
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
        if (d0, d1) == ("azimuth", "elevation"):      # azimuth across, elevation up
            d0, d1, db = d1, d0, db.T
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
                    "elevation": reference.el_deg, "doppler": 0.0}  # static target
            ax.plot(mark[d1], mark[d0], marker="+", color="red", markersize=12, mew=1.5)
        ax.set_title(f"{chain}: {kind}")
    fig.colorbar(im, ax=axes[0].tolist(), label="power [dB rel. max]", shrink=0.9)
    return fig


def _doppler_figure(slow: dict, cfg):
    import matplotlib.pyplot as plt

    from raysim.processing.metrics import doppler_power_spectrum

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
    res = data.result
    chains = [c for c in CHAINS if c in res["chains"]]
    if not chains:
        raise ValueError("nothing to report: no chain could be evaluated")
    cfg, arr = data.frame.config, data.frame.array
    ref = res["reference"]
    metrics = res["chains"]
    ra = {c: res["maps"][c]["ra"] for c in chains}
    re_ = {c: res["maps"][c]["re"] for c in chains}
    rd = {c: res["maps"][c]["rd"] for c in chains}
    ae = {c: res["maps"][c]["ae"] for c in chains}
    slow = {c: res["maps"][c]["slow_time"] for c in chains}
    rmax = min(cfg.max_range, 2.0 * ref.range_m) if ref is not None else None
    figs = [
        ("Range-azimuth maps", _map_figure(ra, "range-azimuth", ref, rmax),
         f"Beam scan at elevation {_fmt(ref.el_deg if ref else float('nan'))} deg, "
         f"up to {RANGE_ANGLE_CHIRPS} chirps of frame 0 summed; red cross: truth."),
        ("Range-elevation maps", _map_figure(re_, "range-elevation", ref, rmax),
         "Beam scan at the target azimuth, frame 0."),
        ("Range-Doppler maps", _map_figure(rd, "range-Doppler", ref, rmax),
         "Hann windows in fast and slow time, beam towards the target (through each chain), "
         "frame 0; its entropy is entropy_rd_nats."),
        ("Azimuth-elevation maps", _map_figure(ae, "azimuth-elevation", ref, None),
         "Beam power at the target range gate summed over the chirps of all frames (through "
         "each chain); its entropy is entropy_ae_nats."),
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
    for note in res["notes"]:
        parts.append(f"<p class='note'>Note: {html.escape(note)}</p>")

    parts.append("<h2>Metrics</h2><table><tr><th>metric</th><th>unit</th>"
                 + "".join(f"<th>{c}</th>" for c in chains) + "</tr>")
    for key, unit in ((m, metric_unit(m)) for m in ANALYSIS_METRICS):
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
        "frames": data.num_frames, "chirps": cfg.num_chirps,
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
    from raysim.io.storage import atomic_write_text

    path = Path(path)
    atomic_write_text(path, build_report(data))
    return path
