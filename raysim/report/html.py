"""Self-contained HTML reports comparing the chains of :mod:`raysim.vocabulary`.

A report holds, for every available chain (``none``, ``paper``,
``paper:published``, ``exact``, ``dpca``): the RA, RE, RD and AE maps
(:data:`raysim.vocabulary.MAPS`, drawn by :func:`raysim.report.figures.plot_map`
with the axes of :data:`raysim.vocabulary.FIGURE_AXES`), Doppler cuts of the
reference target, the metric table of :func:`raysim.measure.point.measure`
(names and units of :data:`raysim.vocabulary.METRICS`, with the values the
paper reports for a paper case), the compensation's guard warnings per chain,
the price of the ``dpca`` chain (sub-aperture kept, beamwidth growth, gain lost),
the run parameters (motion label, scenario TOML, derived radar quantities)
and the software versions (numpy, sionna-rt, mitsuba, drjit, ...). Figures
are PNGs embedded as base64 ``data:`` URIs, so the single HTML file can be
mailed or archived. The file is written atomically.

Map conventions: power in dB relative to each map's maximum, clipped at
:data:`DYNAMIC_RANGE_DB` below it; range [m], range rate [m/s] (positive
receding), angles [deg] (docs/conventions.md).
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

from raysim.measure.point import POINT_METRICS
from raysim.pipeline.beams import PRICE_PREFIX
from raysim.pipeline.sources import LazyFrames, Reference
from raysim.synthesis.frame import RadarFrame
from raysim.vocabulary import (
    CHAINS,
    FIGURE_AXES,
    MAP_TITLES,
    METRICS,
    metric_unit,
    parse_chains,
)

__all__ = ["ReportData", "StoredFrames", "collect_from_scenario", "collect_from_dataset",
           "build_report", "progress_bar", "counted_frames",
           "write_report", "software_versions", "zoom_limits", "DYNAMIC_RANGE_DB"]

#: Colour-scale depth of the maps [dB].
DYNAMIC_RANGE_DB = 40.0
#: Maps are zoomed on the cells within this many dB of their peak (target, clutter ridge) [dB].
ZOOM_DB = 20.0
#: Smallest zoom window, in cells of the map's grid along each axis.
ZOOM_MIN_CELLS = 8
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
        (``reference``, ``chains`` metrics, ``maps``, ``warnings``, ``notes``),
        keyed by chain (:attr:`raysim.vocabulary.ChainSpec.key`).
    frame : RadarFrame
        Frame 0 (its config and array describe the radar).
    num_frames : int
    scenario_toml : str
        Run parameters as TOML ('' when unknown).
    paper : dict
        Values the paper reports for this case (may be empty).
    source : str
        Where the frames came from (scenario file, store path).
    motion : str
        Label of the platform motion (:attr:`raysim.platform.motion.Trajectory.name`,
        e.g. ``pitch 10 deg @ 20 Hz``; '' when unknown).
    """

    title: str
    result: dict
    frame: RadarFrame
    num_frames: int = 1
    scenario_toml: str = ""
    paper: dict = field(default_factory=dict)
    source: str = ""
    motion: str = ""


# ------------------------------------------------------------------ collect
def collect_from_scenario(scenario, *, chains: Sequence[str] = CHAINS,
                          source: str = "", progress: bool = False) -> ReportData:
    """Render a scenario in memory and measure every available chain.

    ``chains``: names or specs (:func:`raysim.vocabulary.parse_chains`);
    ``progress``: a tqdm bar on stderr (one step per frame rendered, then the
    chains' measurement, :func:`progress_bar`).
    """
    from raysim.pipeline.run import evaluate

    keys = [c.key for c in parse_chains(chains)]
    traj = scenario.trajectory()
    bar = progress_bar(scenario.frames, scenario.name, progress)
    frames = counted_frames(scenario, traj, bar, lambda: f"measuring chains {', '.join(keys)}")
    ref, notes = direction_for_chains(frames, frames.reference, keys)
    res = evaluate(scenario, chains=keys, frames=frames, reference=ref, return_maps=True)
    bar.close()
    res["notes"] = notes + res["notes"]
    return ReportData(scenario.name, res, frames[0], len(frames), scenario.to_toml(),
                      _paper_values(scenario), source or scenario.name, traj.name)


def progress_bar(frames: int, desc: str, enabled: bool):
    """A tqdm bar on stderr over ``frames`` frame reads (disabled: a silent stand-in)."""
    import sys

    from tqdm.auto import tqdm

    return tqdm(total=int(frames), desc=str(desc), unit="frame", file=sys.stderr,
                disable=not enabled, leave=False, mininterval=0.0)


def counted_frames(scenario, trajectory, bar, then) -> LazyFrames:
    """The frames of a scenario rendered on access (:class:`LazyFrames`), each first
    render a step of ``bar`` (:func:`progress_bar`); once all are rendered the bar says
    ``then()``. ``reference`` is the scenario's reference target, as for
    :func:`raysim.pipeline.sources.frame_source`."""
    from raysim.pipeline.sources import frame_source

    source_of = frame_source(scenario, trajectory)
    frames = LazyFrames(_counted(source_of, bar, "rendering", then), scenario.frames)
    frames.reference = getattr(source_of, "reference", None)
    return frames


def _counted(read, bar, what: str, then):
    """``read(f)`` that advances ``bar`` the first time each frame is read; once every
    frame was read the bar says ``then()`` (the work that follows)."""
    seen: set[int] = set()

    def counted(f: int):
        if f not in seen:
            bar.set_postfix_str(f"{what} frame {f}")
        out = read(f)
        if f not in seen:
            seen.add(f)
            if len(seen) == bar.total:
                bar.set_postfix_str(then(), refresh=False)
            bar.update()
        return out

    return counted


def direction_for_chains(frames, reference, chains: Sequence[str]):
    """A look direction for the chains that need one, on a scene without a reference target.

    The ``paper`` chains correct the slow-time phase towards one direction (the
    reference target's). A ray-traced scene without a discrete target (users'
    meshes, a bare ground) has none: its strongest return is taken instead, the
    peak of frame 0 uncompensated (:func:`raysim.measure.point.measure` with
    chain ``none``: the range-profile peak ``range_m`` [m] and the AE map's peak
    ``map_az_deg``, ``map_el_deg`` [deg]), and a note says so. When the peak is
    not finite, boresight at that range is taken, also stated.

    Parameters
    ----------
    frames : sequence of RadarFrame
        ``data`` ``[chirp, channel, sample]``; only frame 0 is read.
    reference : Reference or None
        The scene's reference target (returned unchanged when given).
    chains : sequence of str
        Chain keys of the report.

    Returns
    -------
    reference : Reference or None
        The reference, or the strongest return's direction when a chain needs one.
    notes : list of str
        What was chosen and why (empty when nothing was).
    """
    from raysim.pipeline.sources import Reference

    needs = [c for c in chains if str(c).split(":")[0] == "paper"]
    if reference is not None or not needs or len(frames) == 0:
        return reference, []
    from raysim.measure.point import measure

    m = measure([frames[0]], None, chain="none")
    r, az, el = m["range_m"], m.get("map_az_deg"), m.get("map_el_deg")
    if az is None or el is None or not (np.isfinite(az) and np.isfinite(el)):
        ref = Reference(float(r), 0.0, 0.0)
        how = "boresight (the AE map has no finite peak)"
    else:
        ref = Reference(float(r), float(az), float(el))
        how = "the strongest return's direction (frame 0, uncompensated)"
    note = (f"the scene has no reference target: the chains {', '.join(needs)} correct "
            f"towards {how}: range {ref.range_m:.2f} m, azimuth {ref.az_deg:.1f} deg, "
            f"elevation {ref.el_deg:.1f} deg; the angle errors are measured from it")
    return ref, [note]


def _paper_values(scenario) -> dict:
    if scenario is None or scenario.motion.case is None:
        return {}
    from raysim.scenario.paper_cases import paper_values

    return paper_values(scenario.motion.case)


class StoredFrames(LazyFrames):
    """The frames of a stored Dataset, read one at a time when accessed (frame 0 is kept).

    With a lazy (dask-backed) Dataset, e.g. ``open_store(path, load=False)``,
    an analysis holds about two frames in memory, not the whole store.

    Parameters
    ----------
    ds : xarray.Dataset
        Frame Dataset (:mod:`raysim.io.storage` layout), lazy or in memory.
    source : str
        The store, for messages.
    on_read : callable, optional
        ``on_read(read)`` wraps the frame reader ``read(f) -> RadarFrame`` (progress).

    Raises
    ------
    ValueError
        When a frame's chunks cannot be read or decoded (naming the store and the frame).
    """

    def __init__(self, ds, source: str = "dataset", on_read=None):
        from raysim.io.storage import array_from_dataset, config_from_attrs

        self._ds = ds
        config, array = config_from_attrs(ds.attrs), array_from_dataset(ds)
        lever = np.asarray(ds.attrs.get("lever_arm_m", [0, 0, 0]), dtype=float)

        def read(f: int) -> RadarFrame:
            sub = ds.isel(frame=f)
            try:                          # a lazy store decodes its chunks here
                data = np.asarray(sub["if_data"].values)
                times = np.asarray(sub["chirp_time"].values, dtype=float)
            except (MemoryError, KeyboardInterrupt):
                raise
            except Exception as exc:
                raise ValueError(f"store {source!r}: frame {f} cannot be read "
                                 f"({type(exc).__name__}: {exc}); expected complete, "
                                 f"decodable chunk files (a truncated or corrupted file?)"
                                 ) from exc
            return RadarFrame(data, config, array, times, lever, int(sub["frame"].values),
                              {"source": source})

        super().__init__(read if on_read is None else on_read(read), int(ds.sizes["frame"]))

    def chirp_times(self) -> np.ndarray:
        """Stored chirp start times of all frames, shape ``[frame * chirp]`` [s]."""
        return np.asarray(self._ds["chirp_time"].values, dtype=float).ravel()


def collect_from_dataset(ds, *, chains: Sequence[str] = CHAINS, source: str = "",
                         progress: bool = False) -> ReportData:
    """Frames of a stored Dataset (Zarr / NetCDF), measured through every chain its IMU log
    and scenario allow.

    Frames are read one at a time (:class:`StoredFrames`): give a lazy Dataset
    (``raysim.io.storage.open_store(path, load=False)``) and a report of a
    store of any length holds about two frames in memory. ``progress``: a tqdm bar
    on stderr (one step per frame read, then the chains' measurement).
    """
    from raysim.io.storage import scenario_of
    from raysim.measure.point import measure
    from raysim.pipeline.run import evaluate

    keys = [c.key for c in parse_chains(chains)]
    bar = progress_bar(ds.sizes.get("frame", 0), source or "store", progress)
    frames = StoredFrames(ds, source or "dataset",
                          on_read=lambda read: _counted(
                              read, bar, "reading", lambda: f"measuring chains {', '.join(keys)}"))
    scenario = scenario_of(ds)
    motion = str(ds.attrs.get("motion_name", ""))
    ref = None
    if "reference_range_m" in ds.attrs:
        ref = Reference(float(ds.attrs["reference_range_m"]), float(ds.attrs["reference_az_deg"]),
                        float(ds.attrs["reference_el_deg"]))
    title = str(ds.attrs.get("scenario_name", "stored frames"))
    if scenario is None:
        m, maps = measure(frames, ref, return_maps=True)
        bar.close()
        res = {"reference": ref, "chains": {"none": m}, "maps": {"none": maps},
               "warnings": {"none": []},
               "notes": ["the store carries no scenario: compensation chains skipped"]}
        return ReportData(title, res, frames[0], len(frames), "", {}, source, motion)
    imu = ds[["imu_gyro", "imu_accel"]].load() if "imu_gyro" in ds else None
    notes = []
    if imu is None:
        keys = [c for c in keys if c == "none"] or ["none"]
        notes.append("the store has no IMU log: compensation chains skipped")
    ref, picked = direction_for_chains(frames, ref, keys)
    notes += picked
    res = evaluate(scenario, chains=keys, frames=frames, imu=imu, reference=ref,
                   return_maps=True)
    bar.close()
    res["notes"] = notes + res["notes"]
    return ReportData(title, res, frames[0], len(frames), scenario.to_toml(),
                      _paper_values(scenario), source, motion or scenario.trajectory().name)


# ------------------------------------------------------------------- maps
def _png(fig) -> str:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def zoom_limits(m, mark=(None, None), *, max_range: float | None = None,
                zoom_db: float = ZOOM_DB) -> tuple:
    """Axis limits of a map figure around its strong cells and the truth mark.

    The window covers every cell within ``zoom_db`` of the map's peak (the
    target and the clutter ridge) and the mark, spans at least
    :data:`ZOOM_MIN_CELLS` cells, gets a margin of a quarter of its span on
    each side and stays within the map.

    Parameters
    ----------
    m : raysim.processing.maps.Map
        Two-dimensional map (axes of :data:`raysim.vocabulary.FIGURE_AXES`).
    mark : (float or None, float or None)
        Truth position in figure units (x, y), e.g. ``(az_deg, range_m)``.
    max_range : float, optional
        Cells beyond this range [m] are not considered.
    zoom_db : float
        Depth of the cells kept [dB below the peak].

    Returns
    -------
    (xlim, ylim)
        Each a ``(low, high)`` pair in figure units (degrees for angles).
    """
    from raysim.report.figures import map_image, map_name

    x, y, db = map_image(m)
    xa, ya = FIGURE_AXES[map_name(m)]
    keep = np.ones(db.shape, dtype=bool)
    if max_range is not None:
        if ya == "range":
            keep &= (y <= max_range)[:, None]
        if xa == "range":
            keep &= (x <= max_range)[None, :]
    shown = np.where(keep, db, -np.inf)
    strong = shown >= shown.max() - zoom_db
    out = []
    for values, hit, mk in ((x, strong.any(axis=0), mark[0]), (y, strong.any(axis=1), mark[1])):
        v = np.asarray(values, dtype=float)
        lo, hi = float(v[hit].min()), float(v[hit].max())
        if mk is not None and np.isfinite(mk):
            lo, hi = min(lo, float(mk)), max(hi, float(mk))
        cell = float(np.median(np.abs(np.diff(v)))) if v.size > 1 else 1.0
        span = max(hi - lo, ZOOM_MIN_CELLS * cell)
        centre = 0.5 * (lo + hi)
        lo, hi = centre - 0.75 * span, centre + 0.75 * span
        out.append((max(lo, float(v.min()) - 0.5 * cell), min(hi, float(v.max()) + 0.5 * cell)))
    return tuple(out)


def _map_figure(maps: dict, reference: Reference | None, max_range: float | None):
    """One panel per chain of one kind of map, drawn by :func:`~raysim.report.figures.plot_map`.

    ``maps``: chain key -> :class:`~raysim.processing.maps.Map` (all of the same
    kind, see :data:`raysim.vocabulary.MAPS`); the truth is marked with a red
    cross (a static target: range rate 0). Every panel shows the same window,
    zoomed on the strong cells of all chains (:func:`zoom_limits`; range cut at
    ``max_range`` [m]).
    """
    import matplotlib.pyplot as plt

    from raysim.report.figures import map_name, plot_map

    chains = list(maps)
    fig, axes = plt.subplots(1, len(chains), figsize=(3.6 * len(chains) + 1.2, 3.6),
                             squeeze=False, layout="constrained")
    first = maps[chains[0]]
    xa, ya = FIGURE_AXES[map_name(first)]
    mark = (None, None)
    if reference is not None:
        where = {"range": reference.range_m, "azimuth": reference.az_deg,
                 "elevation": reference.el_deg, "doppler": 0.0}
        mark = (where[xa], where[ya])
    lims = [zoom_limits(maps[c], mark, max_range=max_range) for c in chains]
    xlim = (min(lo[0][0] for lo in lims), max(lo[0][1] for lo in lims))
    ylim = (min(lo[1][0] for lo in lims), max(lo[1][1] for lo in lims))
    for ax, chain in zip(axes[0], chains, strict=True):
        m = maps[chain]
        im = plot_map(ax, m, title=chain, dynamic_range_db=DYNAMIC_RANGE_DB,
                      xlim=xlim, ylim=ylim)
        if mark[0] is not None:
            ax.plot(*mark, marker="+", color="red", markersize=12, mew=1.5)
    for ax in axes[0][1:]:
        ax.set_ylabel("")
        ax.tick_params(labelleft=False)
    fig.suptitle(MAP_TITLES[map_name(first)], fontsize=11)
    fig.colorbar(im, ax=axes[0].tolist(), label="power [dB rel. max]", shrink=0.9)
    return fig


def _doppler_figure(slow: dict, cfg):
    import matplotlib.pyplot as plt

    from raysim.processing.metrics import doppler_power_spectrum

    fig, ax = plt.subplots(figsize=(8, 3.4), layout="constrained")
    lo, hi = np.inf, -np.inf
    for chain, x in slow.items():
        f, p = doppler_power_spectrum(x, cfg.chirp_interval)
        v, db = f * cfg.center_wavelength / 2.0, 10 * np.log10(np.maximum(p / p.max(), 1e-12))
        ax.plot(v, db, label=chain)
        seen = v[db >= -50.0]                   # zoom on what rises above the plot's floor
        lo, hi = min(lo, seen.min()), max(hi, seen.max())
    span = max(hi - lo, 8 * cfg.velocity_resolution)
    centre = 0.5 * (lo + hi)
    ax.set_xlim(max(centre - 0.75 * span, -cfg.max_velocity),
                min(centre + 0.75 * span, cfg.max_velocity))
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


def _price_section(chains: Sequence[str], warnings: dict) -> str:
    """HTML section stating what a chain gives up (``dpca``: aperture, gain), '' if none."""
    found = [(c, w.removeprefix(PRICE_PREFIX)) for c in chains for w in warnings.get(c, [])
             if w.startswith(PRICE_PREFIX)]
    if not found:
        return ""
    out = ["<h2 id='price'>Price of the chains</h2>",
           "<p>The dpca chain forms its beams from a sub-aperture held fixed in the world: "
           "it gives up aperture (beamwidth grows, coherent gain falls) for every frame "
           "below.</p><ul class='price'>"]
    out.extend(f"<li><b>{html.escape(c)}</b>: {html.escape(w)}</li>" for c, w in found)
    out.append("</ul>")
    return "\n".join(out)


def _warnings_section(chains: Sequence[str], warnings: dict) -> str:
    """HTML section listing the guard warnings of every chain (or saying there are none)."""
    out = ["<h2 id='warnings'>Warnings</h2>"]
    found = [(c, w) for c in chains for w in warnings.get(c, [])
             if not w.startswith(PRICE_PREFIX)]
    if not found:
        out.append("<p class='muted'>The compensation raised no warning for any chain.</p>")
        return "\n".join(out)
    out.append("<p>The compensation flags results whose assumptions do not hold "
               "(see compensation.guards):</p><ul class='warnings'>")
    out.extend(f"<li class='note'><b>{html.escape(c)}</b>: {html.escape(w)}</li>"
               for c, w in found)
    out.append("</ul>")
    return "\n".join(out)


def build_report(data: ReportData) -> str:
    """HTML text of a report (figures embedded)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    res = data.result
    chains = list(res["chains"])          # evaluation order: the order asked for
    if not chains:
        raise ValueError("nothing to report: no chain could be evaluated")
    cfg, arr = data.frame.config, data.frame.array
    ref = res["reference"]
    metrics = res["chains"]
    warnings = res.get("warnings", {})
    slow = {c: res["maps"][c]["slow_time"] for c in chains}
    rmax = min(cfg.max_range, 2.0 * ref.range_m) if ref is not None else None
    captions = {
        "ra": f"Beam scan at elevation {_fmt(ref.el_deg if ref else float('nan'))} deg, "
              f"up to {RANGE_ANGLE_CHIRPS} chirps of frame 0 summed; red cross: truth.",
        "re": "Beam scan at the target azimuth, frame 0.",
        "rd": "Hann windows in fast and slow time, beam towards the target (through each "
              "chain), frame 0; its entropy is entropy_rd_nats.",
        "ae": "Beam power at the target range gate summed over the chirps of all frames "
              "(through each chain); its entropy is entropy_ae_nats.",
    }
    figs = [(f"{MAP_TITLES[name]} maps",
             _map_figure({c: res["maps"][c][name] for c in chains}, ref,
                         None if name == "ae" else rmax), captions[name])
            for name in ("ra", "re", "rd", "ae")]
    figs.append(("Doppler cuts", _doppler_figure(slow, cfg),
                 "Slow-time signal of frame 0 at the target range, beamformed to the target."))
    now = datetime.now(UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
             f"<title>raysim report: {html.escape(data.title)}</title><style>{_CSS}</style>"
             f"</head><body>",
             f"<h1>raysim report: {html.escape(data.title)}</h1>",
             f"<p class='muted'>source: {html.escape(data.source)} &middot; written {now}</p>"]
    if data.motion:
        parts.append(f"<p>Motion: {html.escape(data.motion)}</p>")
    if ref is not None:
        parts.append(f"<p>Reference target: range {ref.range_m:.3f} m, azimuth "
                     f"{ref.az_deg:.2f} deg, elevation {ref.el_deg:.2f} deg.</p>")
    for note in res["notes"]:
        parts.append(f"<p class='note'>Note: {html.escape(note)}</p>")
    parts.append(_warnings_section(chains, warnings))
    price = _price_section(chains, warnings)
    if price:
        parts.append(price)

    parts.append("<h2>Metrics</h2><table class='metrics'><tr><th>metric</th><th>unit</th>"
                 + "".join(f"<th>{html.escape(c)}</th>" for c in chains)
                 + "<th>definition</th></tr>")
    for key, unit in ((m, metric_unit(m)) for m in POINT_METRICS):
        parts.append(f"<tr><td>{key}</td><td>{html.escape(unit)}</td>"
                     + "".join(f"<td>{_fmt(metrics[c][key])}</td>" for c in chains)
                     + f"<td class='muted' style='text-align:left'>"
                       f"{html.escape(METRICS[key][1])}</td></tr>")
    parts.append("</table>")
    parts.append("<p class='muted'>Metrics of raysim.vocabulary.METRICS: pseudo-velocity and "
                 "Doppler width "
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
        "motion": data.motion or "-", "frames": data.num_frames, "chirps": cfg.num_chirps,
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
