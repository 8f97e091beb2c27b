"""Outputs of the report: figures, markdown, HTML and JSON files (all written atomically)."""

from __future__ import annotations

import html
import os
import re
import sys
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from raysim.io.files import atomic_savefig, atomic_write_json, atomic_write_text
from raysim.measure.scene import (
    CFAR_RANK,
    CFAR_THRESHOLD_DB,
    CFAR_TRAIN,
    MISS_REASONS,
    SCENE_METRICS,
)
from raysim.resources import check_memory
from raysim.vocabulary import CHAINS, MAP_TITLES, REFERENCE, chain_label, parse_chains

from .coverage import maps_size
from .evaluate import SceneResult, evaluate_scenario, evaluate_scene
from .meshes import NEAR_MESH_M, mesh_boxes, plot_placement
from .settings import (
    ENTROPY_MARGIN_NATS,
    FULL,
    RD_PLOT_HALF_WIDTH_BINS,
    REPORT_MAPS,
    ReportSettings,
)

__all__ = ["POINT_TABLE_METRICS", "plot_scene", "report_markdown", "report_html",
           "write_scene_report", "result_label"]

#: Point metrics of the reference target shown in ``report.md`` (all are in the JSON).
POINT_TABLE_METRICS = ("range_m", "az_deg", "el_deg", "angle_error_deg",
                       "map_angle_error_deg", "pseudo_velocity_mps", "doppler_width_hz",
                       "entropy_ae_nats", "entropy_rd_nats")


def result_label(name: str, taken=()) -> str:
    """A file-name-safe label for a scene or scenario name, unique among ``taken``.

    Characters other than letters, digits, ``_``, ``.`` and ``-`` become ``_``;
    a clash gets a suffix ``_2``, ``_3`` ...
    """
    base = re.sub(r"[^A-Za-z0-9_.-]+", "_", str(name)).strip("._") or "scenario"
    label, k = base, 2
    while label in taken:
        label, k = f"{base}_{k}", k + 1
    return label


def plot_scene(result: SceneResult, folder: str | os.PathLike, *,
               dynamic_range_db: float = 50.0) -> list[Path]:
    """One PNG per map (``<scene>_rd.png``, ``<scene>_ra.png``, ``<scene>_ae.png``).

    One panel for the stationary reference, then one per chain, each drawn by
    :func:`raysim.report.figures.plot_map` (azimuth on x wherever a map has
    it). Panels share the colour scale: dB relative to the reference map's
    peak. The RD panels zoom on the clutter ridge (+-
    :data:`RD_PLOT_HALF_WIDTH_BINS` Doppler bins); known reflectors are
    marked on the RA (azimuth, range) and AE (azimuth, elevation) panels, the
    centres of moving objects (range, folded range rate) on the RD panels,
    which then widen to show them.

    Returns
    -------
    list of Path
        The written PNG files, in :data:`REPORT_MAPS` order.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from raysim.report.figures import plot_map

    if dynamic_range_db <= 0:
        raise ValueError(f"dynamic_range_db: got {dynamic_range_db!r}, expected > 0 dB")
    panels = {REFERENCE: result.reference, **result.chains}
    paths = []
    for m in REPORT_MAPS:
        ref = float(result.reference.maps[m].values.max())
        width = 4.2 * len(panels)
        # fixed margins [in] instead of constrained layout (half of the plotting time)
        fig, axes = plt.subplots(1, len(panels), figsize=(width, 4.0),
                                 gridspec_kw={"left": 0.5 / width, "right": 1 - 0.95 / width,
                                              "bottom": 0.5 / 4.0, "top": 1 - 0.75 / 4.0,
                                              "wspace": 0.25})
        axes = np.atleast_1d(axes)
        im = None
        for ax, (key, r) in zip(axes, panels.items(), strict=True):
            mp = r.maps[m]
            xlim = None
            if m == "rd":                   # zoom on the clutter ridge (and the movers)
                dv = float(np.abs(np.diff(mp.coords["doppler"][:2]))[0])
                half = max([RD_PLOT_HALF_WIDTH_BINS] + [abs(c[2]) + 3 for mv in result.movers
                                                        for c in mv["centres"]])
                xlim = (-half * dv, half * dv)
            im = plot_map(ax, mp, title=f"{chain_label(key)}\nH = {r.entropy[m]:.3f} nats",
                          reference_power=ref, dynamic_range_db=dynamic_range_db, xlim=xlim)
            if m in ("ae", "ra"):
                for t in result.targets:
                    xy = (t["az_deg"], t["el_deg"] if m == "ae" else t["range_m"])
                    ax.plot(*xy, "c^" if t.get("mesh") else "r+", ms=7 if t.get("mesh") else 9,
                            mfc="none")
                    if t.get("mesh"):               # users' meshes: named markers
                        ax.annotate(t["name"], xy, xytext=(3, 3), textcoords="offset points",
                                    fontsize=7, color="c")
            else:                           # movers: their centres' range and range rate
                for mv in result.movers:
                    c = np.asarray(mv["centres"])
                    ax.plot(c[:, 2] * dv, c[:, 0], "wx", ms=5, mew=0.8)
        fig.colorbar(im, ax=list(axes), label=f"power [dB re {REFERENCE} peak]", shrink=0.9,
                     fraction=0.1 / width, pad=0.1 / width)
        fig.suptitle(f"{result.scene}: {MAP_TITLES[m]} map")
        out = Path(folder) / f"{result.scene}_{m}.png"
        atomic_savefig(fig, out, dpi=90)
        plt.close(fig)
        paths.append(out)
    return paths


def _chain_keys(results: dict) -> list[str]:
    """Chain keys of all scenes, in first-seen order."""
    keys: list[str] = []
    for r in results.values():
        keys += [c for c in r.chains if c not in keys]
    return keys


def _clutter_words(settings: ReportSettings) -> str:
    """The report's ground clutter model in words."""
    if settings.clutter == "sionna":
        return "Sionna's own diffuse paths and ground mirror"
    if settings.clutter == "none":
        return "none (specular paths of the scene only)"
    return (f"persistent clutter field on the ground and walls, {settings.clutter_per_cell:g} "
            "scatterers per range x angle cell at every incidence, rough-surface mirror, "
            "target-ground ghosts")


def _is_report_scene(st: ReportSettings, settings: ReportSettings) -> bool:
    """True when ``st`` is ``settings`` on one of the bundled scenes."""
    if st.scenario.scene.kind != "bundled" or settings.scenario.scene.kind != "bundled":
        return False
    return st == settings.for_scene(st.scenario.scene.name)


def _scenario_lines(results: dict, settings: ReportSettings) -> list[str]:
    """One line per result whose scenario is not the report's own (scenario files)."""
    out = []
    for s, r in results.items():
        st = r.settings
        if _is_report_scene(st, settings):
            continue
        sc, arr = st.scenario, st.array()
        what = {"points": f"{len(sc.scene.targets)} point target(s)",
                "bundled": f"bundled scene `{sc.scene.name}`",
                "mesh": "a mesh scene", "meshes": f"{len(sc.scene.meshes)} user mesh(es)"
                }[sc.scene.kind]
        if sc.scene.kind == "meshes":
            what += " (" + ", ".join(f"`{m.name}`" if getattr(m, "name", None) else
                                     f"`{os.path.basename(m.file)}`"
                                     for m in sc.scene.meshes) + ")"
        out += [f"Scenario `{s}` ({sc.name}): {what}; {st.num_chirps} chirps x "
                f"{st.radar().chirp_interval * 1e6:.0f} us, {arr.name} "
                f"({arr.num_channels} channels), {sc.frames} frame(s), motion "
                f"{sc.trajectory().name}, IMU `{st.imu}`"
                + ("." if sc.scene.kind == "points" else
                   f"; ground clutter: {_clutter_words(st)}."), ""]
    return out


def _point_lines(results: dict, cols: list) -> list[str]:
    """The table of the reference targets' point metrics (scenarios with a target)."""
    have = {s: r for s, r in results.items() if r.point}
    if not have:
        return []
    lines = ["", "Point metrics of each scenario's reference target (its first target, as "
             "`raysim simulate` measures it; units in `raysim.vocabulary.METRICS`)", "",
             "| scene | target (range, az, el) | metric | " + " | ".join(cols) + " |",
             "|---|---|---|" + "---|" * len(cols)]
    for s, r in have.items():
        ref = r.point["reference"]
        where = f"{ref['range_m']:.2f} m, {ref['az_deg']:.1f}, {ref['el_deg']:.1f} deg"
        for m in POINT_TABLE_METRICS:
            cells = " | ".join(f"{r.point['metrics'][c][m]:.4g}"
                               if c in r.point["metrics"] else "-" for c in cols)
            lines.append(f"| {s} | {where} | {m} | {cells} |")
    return lines


def _price_lines(results: dict) -> list[str]:
    """The ``dpca`` chain's price per scene and every chain's guard warnings."""
    lines = []
    priced = {s: r.chains["dpca"] for s, r in results.items()
              if "dpca" in r.chains and r.chains["dpca"].plan is not None}
    if priced:
        lines += ["", "Price of `dpca`: sub-aperture kept (elements per axis), beamwidth "
                  "growth, coherent gain lost, boresight 3 dB beamwidth of the sub-aperture, "
                  "displacement it cannot undo (normal to the array), rotation misplacement "
                  "of its elements [element spacings], and its cost against the full array: "
                  f"entropy of the `{REFERENCE}` frame through the sub-aperture minus through "
                  "the full array, per map [nats]", "",
                  "| scene | sub-aperture | beamwidth x | gain lost [dB] | beamwidth [deg] | "
                  "residual [mm] | rotation [spacings] | aperture cost rd / ra / ae [nats] |",
                  "|---|---|---|---|---|---|---|---|"]
        for s, r in priced.items():
            p = r.price()
            res = results[s]
            cost = res.aperture_cost("dpca")
            cost_txt = (" / ".join(f"{cost[m]:+.3f}" for m in REPORT_MAPS) if cost else "-")
            lines.append(
                f"| {s} | {p['sub_shape'][0]} x {p['sub_shape'][1]} of {p['full_shape'][0]} x "
                f"{p['full_shape'][1]} | {p['resolution_loss'][0]:.3g} / "
                f"{p['resolution_loss'][1]:.3g} | {p['gain_loss_db']:.2f} | "
                f"{p['beamwidth_sub_deg'][0]:.2f} / {p['beamwidth_sub_deg'][1]:.2f} | "
                f"{1e3 * p['residual_displacement_m']:.2f} | "
                f"{p['rotation_misplacement']:.3f} | {cost_txt} |")
    warned = [(s, c, w) for s, r in results.items() for c, ws in r.warnings().items()
              for w in ws]
    if warned:
        lines += ["", "Warnings of the chains:", ""]
        lines += [f"- {s}, `{c}`: {w}" for s, c, w in warned]
    return lines


def _reflector_cell(match: dict | None, cfar: dict | None) -> str:
    """A known reflector in one column: error [m] (* missed), SNR [dB] and a miss's reason."""
    if match is None and cfar is None:
        return "-"
    head = ("no detection" if match is None or "error_m" not in match else
            f"{match['error_m']:.2f}" + ("" if match["detected"] else "*"))
    if cfar is None:
        return head
    snr = "" if cfar["snr_db"] is None else f"SNR {cfar['snr_db']:.1f} dB"
    missed = match is None or not match.get("detected")
    why = ""
    if missed:
        why = ("a detection in its cell, outside the match radius"
               if cfar["status"] == "detected" else cfar["status"])
    return head + " (" + ": ".join(x for x in (snr, why) if x) + ")"


def _mesh_lines(results: dict) -> list[str]:
    """The per-mesh table of scenarios with users' meshes (what the radar saw of each)."""
    have = {s: r for s, r in results.items() if r.meshes}
    if not have:
        return []
    cols = _chain_keys(have)
    lines = ["", "Users' meshes: where each is seen from the radar (its bounding box's centre, "
             "or the point nearest the radar for a mesh under it; marked and named on the RA "
             "and AE maps), traced paths whose first bounce is on it, their total power "
             "(isotropic elements), CFAR detections within "
             f"{NEAR_MESH_M:g} m of its bounding box in the stationary frame and each chain", "",
             "| scene | mesh | range_m | az_deg | el_deg | paths | power [dBW] | detections "
             + " / ".join([REFERENCE] + cols) + " |", "|---|---|---|---|---|---|---|---|"]
    for s, r in have.items():
        where = {t["name"]: t for t in r.targets if t.get("mesh")}
        for m in r.meshes:
            t = where.get(m["name"], {})
            pw = "-" if m["power_dbw"] is None else f"{m['power_dbw']:.1f}"
            det = " / ".join(str(m["detections"].get(c, "-")) for c in [REFERENCE] + cols)
            lines.append(f"| {s} | {m['name']} | {t.get('range_m', float('nan')):.2f} | "
                         f"{t.get('az_deg', float('nan')):.1f} | "
                         f"{t.get('el_deg', float('nan')):.1f} | {m['num_paths']} | {pw} | "
                         f"{det} |")
    return lines


def _fidelity_lines(results: dict) -> list[str]:
    """Echo model per geometry target (``[scene] fidelity`` other than ``"mesh"``)."""
    rows = [(s, c) for s, r in results.items() for c in r.fidelity]
    if not rows:
        return []
    lines = ["", "Echo model per geometry target (`[scene] fidelity`): level used and "
             "predicted, paths, relative l2 error of the object's echo against its mesh "
             "(predicted / measured; point, centres), PO + SBR trace and choice time (wall)",
             "", "| scene | object | range_m | level (predicted) | paths point/centres/mesh | "
             "point error | centres error | trace_s | choice_s |",
             "|---|---|---|---|---|---|---|---|---|"]
    for s, c in rows:
        p, m = c["predicted_error"], c["measured_error"]
        lines.append(
            f"| {s} | {c['name']} | {c['range_m']:.1f} | {c['level']} ({c['predicted_level']})"
            f"{' re-used' if c['reused'] else ''} | {c['paths']['point']}/"
            f"{c['paths']['centres']}/{c['paths']['mesh']} | {p['point']:.3g} / "
            f"{m['point']:.3g} | {p['centres']:.3g} / {m['centres']:.3g} | "
            f"{c['trace_seconds']:.2f} | {c['choice_seconds']:.2f} |")
    return lines


def report_markdown(results: dict, settings: ReportSettings) -> str:
    """The report's markdown: entropy, ridge leakage and reflector tables, figure links.

    Parameters
    ----------
    results : dict
        Scene name -> :class:`SceneResult`.
    settings : ReportSettings

    Returns
    -------
    str
        Tables use the metric names of :data:`raysim.vocabulary.METRICS`
        (``entropy_rd_nats`` ...), the reference key ``stationary`` and the
        chain keys as column heads.
    """
    chains = _chain_keys(results)
    cols = [REFERENCE] + chains
    bundled = any(_is_report_scene(r.settings, settings) for r in results.values())
    radar = ([f"Radar: {settings.num_chirps} chirps x "
              f"{settings.radar().chirp_interval * 1e6:.0f} us, "
              f"{settings.array_size}x{settings.array_size} UPA, 600 samples (range window "
              f"{settings.range_window[0]:g}-{settings.range_window[1]:g} m), grid "
              f"+-{settings.grid_half_width_deg:g} deg step {settings.grid_step_deg:g} deg, "
              f"hover jitter seed {settings.jitter_seed}, IMU `{settings.imu}`.", ""]
             if bundled else
             [f"Processing: range window {settings.range_window[0]:g}-"
              f"{settings.range_window[1]:g} m, grid +-{settings.grid_half_width_deg:g} deg "
              f"step {settings.grid_step_deg:g} deg.", ""])
    diffs = [c for c in ("exact", "dpca") if c in chains]       # compensated vs reference
    lines = ["# Scene entropy report", "", *radar,
             f"Reference `{REFERENCE}`: the same scene with the platform at rest; chains "
             f"{', '.join(f'`{c}`' for c in chains)} process the hovering platform.", "",
             *([f"Ground clutter: {_clutter_words(settings)}.", ""] if bundled else []),
             *_scenario_lines(results, settings),
             f"Entropy margin of a compensated chain: {ENTROPY_MARGIN_NATS} nats. Dense clutter "
             "near nadir changes its speckle under the hover displacement (scatterers "
             "within one beam move by different fractions of a wavelength), which no "
             "beam-domain compensation undoes (the `dpca` chain holds a sub-aperture "
             "fixed in the world instead, paying in aperture); `ridge_leakage_db` shows the "
             "Doppler spread that compensation removes.", "",
             "| scene | metric | " + " | ".join(cols)
             + "".join(f" | {c} - {REFERENCE}" for c in diffs or ["exact"]) + " |",
             "|---|---|" + "---|" * (len(cols) + max(len(diffs), 1))]
    for s, r in results.items():
        res = {REFERENCE: r.reference, **r.chains}
        for m in REPORT_MAPS:
            cells = " | ".join(f"{res[c].entropy[m]:.4f}" if c in res else "-" for c in cols)
            diff = "".join(
                f" | {r.chains[c].entropy[m] - r.reference.entropy[m]:+.4f}" if c in r.chains
                else " | nan" for c in diffs or ["exact"])
            lines.append(f"| {s} | {SCENE_METRICS[m]} | {cells}{diff} |")
    for c in diffs:
        verdict = ", ".join(f"{s} {'within' if r.within_margin(c) else 'OUTSIDE'}"
                            for s, r in results.items() if c in r.chains)
        against = (f"`{REFERENCE}` through the same sub-aperture (the table below; the "
                   f"aperture's own cost is its price)" if c == "dpca" else f"`{REFERENCE}`")
        lines += ["", f"`{c}` within {ENTROPY_MARGIN_NATS} nats of {against} on every "
                  f"map: {verdict}."]
    same = {s: r for s, r in results.items() if "dpca" in r.same_aperture}
    if same:
        lines += ["", f"`dpca` against the `{REFERENCE}` frame through the same sub-aperture "
                  "(the elements `dpca` holds fixed in the world, no motion: what the motion "
                  "leaves at `dpca`'s resolution; its margin verdict uses these differences, "
                  f"the `dpca - {REFERENCE}` column above includes the aperture's cost), "
                  "entropy difference [nats] and that reference's ridge leakage:", "",
                  "| scene | " + " | ".join(f"{SCENE_METRICS[m]}" for m in REPORT_MAPS)
                  + " | ridge_leakage_db |", "|---|" + "---|" * (len(REPORT_MAPS) + 1)]
        for s, r in same.items():
            ref = r.same_aperture["dpca"]
            lines.append(f"| {s} | " + " | ".join(
                f"{r.chains['dpca'].entropy[m] - ref.entropy[m]:+.4f}" for m in REPORT_MAPS)
                + f" | {ref.ridge_leakage_db:.1f} |")
    lines += ["", "ridge_leakage_db: RD power outside Doppler bins -1..+1 relative to the "
              "total [dB]", "",
              "| scene | " + " | ".join(cols) + " |", "|---|" + "---|" * len(cols)]
    for s, r in results.items():
        res = {REFERENCE: r.reference, **r.chains}
        lines.append(f"| {s} | " + " | ".join(
            f"{res[c].ridge_leakage_db:.1f}" if c in res else "-" for c in cols) + " |")
    lines += _price_lines(results)
    lines += _point_lines(results, cols)
    fields = {s: r.clutter for s, r in results.items() if r.clutter.get("num_scatterers")}
    if fields:
        lines += ["", "Clutter field: scatterers drawn (of them on walls), expected count, "
                  "density scale (1 unless `max_scatterers` capped it), build time (wall)", "",
                  "| scene | scatterers | on walls | expected | density scale | build_s |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| {s} | {c['num_scatterers']} | {c.get('wall_scatterers', 0)} | "
                  f"{c['expected']:.0f} | {c['density_scale']:.3g} | {c['build_s']:.2f} |"
                  for s, c in fields.items()]
    lines += _mesh_lines(results)
    lines += _fidelity_lines(results)
    lines += ["", "Known reflectors: position error of the nearest detection [m] "
              "(an extended object, a mesh target: its distance from the object's "
              "oriented bounding box, 0 inside; * = outside the match radius), the SNR "
              "of the reflector's cell (an extended object matched: of its detection) "
              f"over the CFAR's noise estimate (threshold {CFAR_THRESHOLD_DB:g} dB over "
              f"the ordered statistic {CFAR_RANK} of {2 * CFAR_TRAIN} training cells "
              "along range, scaled to the clutter mean) and, for a miss, why: "
              + "; ".join(MISS_REASONS), "",
              "| scene | target | range_m | az_deg | el_deg | "
              + " | ".join(cols) + " |", "|---|---|---|---|---|" + "---|" * len(cols)]
    for s, r in results.items():
        for t in r.targets:
            matches = {REFERENCE: t.get("reference_match"), **t.get("match", {})}
            lines.append(f"| {s} | {t['name']} | {t['range_m']:.2f} | {t['az_deg']:.1f} | "
                         f"{t['el_deg']:.1f} | " + " | ".join(
                             _reflector_cell(matches.get(c), t.get("cfar", {}).get(c))
                             for c in cols) + " |")
    if any(r.movers for r in results.values()):
        lines += ["", "Movers: strongest RD cell off the zero-Doppler ridge within the mover's "
                  "range span: range rate [m/s], Doppler error to its nearest centre [bins], "
                  "contrast over the scene at that Doppler [dB] (* = not detected)", "",
                  "| scene | mover | range_m | true range rate | " + " | ".join(cols) + " |",
                  "|---|---|---|---|" + "---|" * len(cols)]
        for s, r in results.items():
            for mv in r.movers:
                cells = []
                for c in cols:
                    mt = mv["match"].get(c)
                    cells.append("-" if mt is None or "bin" not in mt else
                                 f"{mt['velocity_mps']:+.2f} ({mt['error_bins']:.1f}, "
                                 f"{mt['contrast_db']:.0f} dB)" + ("" if mt["detected"] else "*"))
                lines.append(f"| {s} | {mv['name']} | {mv['range_m']:.2f} | "
                             f"{mv['velocity_mps']:+.2f} | " + " | ".join(cells) + " |")
    lines.append("")
    if any(r.meshes for r in results.values()):
        lines += ["Placement of the meshes and the radar (top view):", "",
                  "![placement](placement.png)", ""]
    for s in results:
        lines.append(f"## {s}")
        lines += [f"![{s} {m}]({s}_{m}.png)" for m in REPORT_MAPS]
        lines.append("")
    return "\n".join(lines)


def report_html(markdown: str) -> str:
    """A small self-contained HTML rendering of the report's markdown (tables, images)."""
    body = []
    rows: list[str] = []

    def flush():
        if rows:
            body.append("<table>" + "".join(rows) + "</table>")
            rows.clear()

    for line in markdown.splitlines():
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            if all(set(c) <= {"-"} for c in cells):
                continue
            tag = "th" if not rows else "td"
            rows.append("<tr>" + "".join(f"<{tag}>{html.escape(c)}</{tag}>" for c in cells)
                        + "</tr>")
            continue
        flush()
        if line.startswith("# "):
            body.append(f"<h1>{html.escape(line[2:])}</h1>")
        elif line.startswith("## "):
            body.append(f"<h2>{html.escape(line[3:])}</h2>")
        elif line.startswith("!["):
            alt, src = line[2:].split("](")
            body.append(f'<img src="{html.escape(src[:-1])}" alt="{html.escape(alt)}" '
                        f'style="max-width:100%">')
        elif line:
            body.append(f"<p>{html.escape(line)}</p>")
    flush()
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>Scene entropy report"
            "</title><style>body{font-family:sans-serif;margin:2em}table{border-collapse:"
            "collapse;margin:1em 0}td,th{border:1px solid #999;padding:2px 6px;text-align:"
            "right}</style></head><body>" + "\n".join(body) + "</body></html>\n")


def write_scene_report(out_dir: str | os.PathLike, *, scenes: Sequence[str] | None = None,
                       settings: ReportSettings = FULL, progress: bool = True,
                       chains: Sequence[str] | str = CHAINS, scenarios: Sequence = ()) -> dict:
    """Evaluate scenes and scenarios; write figures, JSON, ``report.md`` and ``index.html``.

    Every file is written atomically (temporary file, then ``os.replace``). A
    scenario with users' meshes gets ``placement.png`` (a top view of its meshes and
    the radar, :func:`raysim.studies.scene_report.meshes.plot_placement`) before
    any tracing, and a per-mesh table in ``report.md``.

    Parameters
    ----------
    out_dir : path-like
        Output folder (created).
    scenes : sequence of str, optional
        Bundled scene names; default all bundled scenes, or none when
        ``scenarios`` are given.
    settings : ReportSettings
        :data:`FULL` or :data:`QUICK` or custom; its scenario serves the
        bundled scenes, its knobs every scene and scenario.
    progress : bool
        tqdm progress on stderr.
    chains : sequence of str or str
        Chains of the moving platform (default all of
        :data:`raysim.vocabulary.CHAINS`); the stationary reference is always
        computed.
    scenarios : sequence of raysim.scenario.Scenario
        Scenarios evaluated with their own radar, array, motion, IMU and scene
        (point targets, a bundled scene or users' meshes) and the knobs of
        ``settings``; named by their ``name`` (made file-name safe and unique).

    Returns
    -------
    dict
        ``{label: SceneResult.to_dict()}``.
    """
    from raysim.echoes.rt.scenes import SCENES

    scenarios = list(scenarios)
    scenes = (list(SCENES) if scenes is None and not scenarios
              else list(scenes or ()))
    bad = [s for s in scenes if s not in SCENES]
    if bad:
        raise ValueError(f"unknown scene {bad[0]!r}; expected one of {sorted(SCENES)}")
    if not scenes and not scenarios:
        raise ValueError(f"scenes: got {scenes!r} and no scenario, expected at least one of "
                         f"{sorted(SCENES)} or a scenario")
    parse_chains(chains)                              # bad names fail before any tracing
    jobs = []                                         # (label, settings); checked up front
    for s in scenes:
        jobs.append((result_label(s, [j[0] for j in jobs]), settings.for_scene(s)))
    for sc in scenarios:
        jobs.append((result_label(sc.name, [j[0] for j in jobs]),
                     settings.for_scenario(sc)))
    for label, st in jobs:             # the default extents widened to hold every object
        (lo, hi), w = st.range_window, st.grid_half_width_deg
        size = maps_size(st)           # sized on the extents it will run with
        check_memory(size["peak_bytes"], f"the maps of {label} ({size['gates']} range gates x "
                     f"{size['beams']} beams, {st.num_chirps} chirps)",
                     "the range window (--range-window) or the grid (--quick: 6 deg steps)")
        if lo < settings.range_window[0] or hi > settings.range_window[1] or \
                w > settings.grid_half_width_deg:
            print(f"note: {label}: maps widened to hold every mesh and point target: range "
                  f"window {lo:.1f}-{hi:.1f} m, grid +-{w:g} deg ({size['gates']} gates x "
                  f"{size['beams']} beams)", file=sys.stderr)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    placed = [(label, mesh_boxes(st.scenario), st) for label, st in jobs]
    if plot_placement(placed, out / "placement.png") is not None and progress:
        print(f"placement preview: {out / 'placement.png'}", file=sys.stderr)
    results, summary = {}, {}
    for label, st in jobs:
        r = (evaluate_scene(st.scenario.scene.name, st, progress=progress, chains=chains)
             if label in scenes else
             evaluate_scenario(st, progress=progress, chains=chains, label=label))
        results[label] = r
        summary[label] = r.to_dict()
        for t in r.targets:                    # a mesh the maps cannot show: say why
            status = t.get("cfar", {}).get(REFERENCE, {}).get("status", "")
            if t.get("mesh") and status.startswith("outside"):
                print(f"warning: {label}: mesh {t['name']} (range {t['range_m']:.1f} m, "
                      f"azimuth {t['az_deg']:.1f} deg, elevation {t['el_deg']:.1f} deg) is "
                      f"{status} (range window {st.range_window[0]:g}-"
                      f"{st.range_window[1]:g} m, grid +-{st.grid_half_width_deg:g} deg): "
                      "it is off the maps", file=sys.stderr)
        plot_scene(r, out)
        atomic_write_json(out / f"{label}.json", summary[label], indent=1)
    atomic_write_json(out / "summary.json", summary, indent=1)
    md = report_markdown(results, settings)
    atomic_write_text(out / "report.md", md)
    atomic_write_text(out / "index.html", report_html(md))
    return summary
