"""Outputs of ``raysim reproduce``: the table, the JSON / CSV files and the figures.

The rows and maps come from :mod:`raysim.studies.reproduce`; metric names and
units are those of :data:`raysim.vocabulary.METRICS`, chain keys those of
:func:`raysim.vocabulary.parse_chains`, and every map is drawn by
:func:`raysim.report.figures.plot_map`.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os

import numpy as np

from raysim.io.files import atomic_savefig, atomic_write_text
from raysim.measure.point import angle_chirp, map_grid
from raysim.pipeline.beams import Beamformer
from raysim.processing.maps import Map, doppler_fft
from raysim.report.figures import plot_map
from raysim.vocabulary import MAPS, REFERENCE, chain_label, parse_chain

__all__ = ["write_results", "format_table", "write_case_figures"]


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


#: Table columns: (header, row key, decimals); ``None`` decimals = text column.
_COLUMNS = (
    ("case", "case", None), ("chain", "chain", None), ("imu", "imu", None),
    ("pv [m/s]", "pseudo_velocity_mps", 3), ("paper", "paper_pseudo_velocity_mps", 3),
    ("pv [bins]", "pseudo_velocity_bins", 3),
    ("width [Hz]", "doppler_width_hz", 1), ("paper", "paper_doppler_width_hz", 1),
    ("width/stat", "width_vs_stationary", 3),
    ("impr [%]", "width_improvement_pct", 1), ("paper", "paper_width_improvement_pct", 1),
    ("angle err [deg]", "angle_error_deg", 3), ("paper", "paper_angle_error_deg", 2),
    ("AE entropy [nats]", "entropy_ae_nats", 3), ("paper", "paper_entropy_ae_nats", 2),
    ("stat. entropy", f"{REFERENCE}_entropy_ae_nats", 3),
)


def format_table(rows: list[dict]) -> str:
    """Plain-text table: our numbers (mean +- std over seeds) beside the paper's.

    Columns: ``pseudo_velocity_mps``, ``pseudo_velocity_bins``,
    ``doppler_width_hz``, ``width_vs_stationary``, ``width_improvement_pct``,
    ``angle_error_deg``, ``entropy_ae_nats`` and the stationary reference's
    entropy; ``paper`` columns hold the paper's values (``paper_<metric>``).
    """
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
def _chain_beams(data, motion, key: str, rc, chirps, az, el):
    """Beams of one chain on the figure window (frame 0 cells of chirps ``chirps`` in ``rc``)."""
    bf = Beamformer(key, data.array, data.config.center_wavelength,
                    motion=motion if parse_chain(key).compensated else None)
    return bf(rc, chirps, data.range_axis[data.window], az, el, data.reference.direction)


def write_case_figures(data, motion, folder: str, *, imu: str, maps: dict) -> list:
    """RA (angle chirp), RD (beam towards the target) and AE (accumulated) maps per chain.

    Parameters
    ----------
    data : raysim.studies.reproduce._Case
        Rendered case (frame-0 cells of the range window, reference).
    motion : compensation.PlatformMotion or None
        Pose at every TDM slot of every chirp (first seed); None when only
        ``none`` is drawn.
    folder : str
    imu : str
        IMU preset name (file names and titles).
    maps : dict
        Chain key (and :data:`~raysim.vocabulary.REFERENCE`) -> accumulated AE
        :class:`~raysim.processing.maps.Map` (``azimuth``, ``elevation``).

    Writes ``<case>_<imu>_{ra,rd,ae}.png`` into ``folder`` (temporary file, then
    ``os.replace``); returns the paths.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cfg = data.config
    n = cfg.num_chirps
    m0 = None if motion is None else motion.select(slice(0, n * data.array.num_slots))
    grid = map_grid()
    chains = [k for k in maps if k != REFERENCE]
    r = data.range_axis[data.window]
    c = angle_chirp(n)
    sel = slice(c, c + 1)
    az_deg, el_deg = np.rad2deg(data.target_az), np.rad2deg(data.target_el)
    paths = []

    def panels(keys, width):
        fig, axes = plt.subplots(1, len(keys), figsize=(width * len(keys), 3.6), squeeze=False,
                                 layout="constrained")
        return fig, axes[0]

    def save(fig, kind):
        path = os.path.join(folder, f"{data.name}_{imu}_{kind}.png")
        atomic_savefig(fig, path, dpi=90)
        plt.close(fig)
        paths.append(path)

    # RA: the angle chirp at the target elevation
    fig, axes = panels(chains, 4)
    for ax, key in zip(axes, chains, strict=True):
        b = _chain_beams(data, m0, key, data.rc_window[sel], [c], grid, [data.target_el])
        m = Map(np.abs(b[0, :, :, 0]) ** 2, MAPS["ra"], {"range": r, "azimuth": grid})
        im = plot_map(ax, m, title=chain_label(key), dynamic_range_db=40.0)
        ax.axvline(az_deg, color="w", lw=0.6, ls="--")
    fig.colorbar(im, ax=axes.tolist(), label="dB")
    fig.suptitle(f"{data.name}: RA (range-azimuth), chirp {c + 1}, el {el_deg:.0f} deg "
                 f"({imu} IMU)")
    save(fig, "ra")

    # RD: beam towards the true direction
    fig, axes = panels(chains, 4)
    for ax, key in zip(axes, chains, strict=True):
        b = _chain_beams(data, m0, key, data.rc_window, np.arange(n), [data.target_az],
                         [data.target_el])
        spec = np.abs(doppler_fft(b[:, :, 0, 0], axis=0)) ** 2          # [doppler, range]
        m = Map(spec.T, MAPS["rd"], {"range": r, "doppler": cfg.velocity_axis(spec.shape[0])})
        im = plot_map(ax, m, title=chain_label(key), dynamic_range_db=50.0, xlim=(-4, 4))
    fig.colorbar(im, ax=axes.tolist(), label="dB")
    fig.suptitle(f"{data.name}: RD (range-Doppler) towards the target ({imu} IMU)")
    save(fig, "rd")

    # AE: accumulated azimuth-elevation map at the target gate
    keys = chains + ([REFERENCE] if REFERENCE in maps else [])
    fig, axes = panels(keys, 3.6)
    for ax, key in zip(axes, keys, strict=True):
        im = plot_map(ax, maps[key], dynamic_range_db=30.0,
                      title=f"{chain_label(key)}\nH = {maps[key].entropy():.2f} nats")
        ax.plot(az_deg, el_deg, "w+", ms=8)
    fig.colorbar(im, ax=axes.tolist(), label="dB")
    fig.suptitle(f"{data.name}: AE (azimuth-elevation), {data.frames} frame(s) "
                 f"({imu} IMU)")
    save(fig, "ae")
    return paths
