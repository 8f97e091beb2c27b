"""Files of a stability map: NetCDF, JSON summary, the heat-map figure and the console table.

Variable names of the NetCDF datasets, keys of the JSON summaries and labels
of the figures are the metric names of :data:`raysim.vocabulary.METRICS`.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from raysim.io.files import atomic_savefig, atomic_write
from raysim.studies.stability.grids import tick_labels
from raysim.studies.stability.metrics import STABILITY_METRICS
from raysim.vocabulary import metric_unit

__all__ = ["write_netcdf", "read_netcdf", "failing_values", "summarise", "plot_stability",
           "summary_table"]


def _netcdf_engine() -> str:
    """``netcdf4`` (NetCDF-4) when netCDF4 imports, as :func:`raysim.io.storage.netcdf_engine`.

    Falls back to ``h5netcdf``, then to ``scipy`` (NetCDF-3) only in an
    installation without netCDF4 (a raysim dependency). Files of any of them
    are read by the netcdf4 engine.
    """
    from raysim.io.storage import netcdf_engine

    return netcdf_engine() or "scipy"


def write_netcdf(ds, path: str | os.PathLike) -> Path:
    """Write a stability dataset to NetCDF atomically (booleans stored as int8)."""
    out = ds.copy()
    for name in list(out.data_vars):
        if out[name].dtype == bool:
            out[name] = out[name].astype(np.int8)
            out[name].attrs["dtype"] = "bool"
    return atomic_write(path, lambda p: out.to_netcdf(p, engine=_netcdf_engine()))


def read_netcdf(path: str | os.PathLike):
    """Read a dataset written by :func:`write_netcdf` (booleans restored)."""
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"stability NetCDF file {str(path)!r} does not exist")
    try:
        with xr.open_dataset(path, engine=_netcdf_engine()) as f:
            ds = f.load()
    except (OSError, ValueError, TypeError) as exc:
        raise ValueError(f"stability NetCDF file {str(path)!r} is unreadable or truncated: "
                         f"{exc}") from None
    for name in list(ds.data_vars):
        if ds[name].attrs.get("dtype") == "bool":
            ds[name] = ds[name].astype(bool)
    return ds


def failing_values(fail_fraction) -> dict:
    """The failure boundary as a table: failing values of axis 0 per value of axis 1.

    Parameters
    ----------
    fail_fraction : xarray.DataArray
        Fraction of seeds failing, dims ``(<axis 0>, <axis 1>)`` (one chain).

    Returns
    -------
    dict
        ``{f"{axis-1 value:g}": [axis-0 values where fraction >= 0.5]}``.
    """
    a0, a1 = fail_fraction.dims
    out = {}
    for v1 in fail_fraction[a1].values:
        col = fail_fraction.sel({a1: v1}).values >= 0.5
        out[f"{v1:g}"] = [float(v) for v in fail_fraction[a0].values[col]]
    return out


def _map_axes(ds) -> list[str]:
    return [d for d in ds.pseudo_velocity_mps.dims if d not in ("chain", "seed")]


def summarise(ds) -> dict:
    """JSON-ready summary: metric arrays (seed median) and failure flags per chain.

    Returns
    -------
    dict
        ``map``, ``title``, ``note``, ``quick``, ``strapdown``, ``mounting_deg``
        (yaw, pitch, roll [deg] of the radar mounting), ``axes``
        (name -> units and values), ``units`` (metric -> unit),
        ``velocity_bin`` [m/s], ``half_beamwidth_deg``, ``chains`` (chain key ->
        metric -> seed-median array, ``fail_fraction``, ``failing``,
        ``worse_than_none_fraction``) and ``warnings``.
    """
    out = {"map": ds.attrs["map"], "title": ds.attrs["title"], "note": ds.attrs["note"],
           "quick": bool(ds.attrs["quick"]), "strapdown": ds.attrs.get("strapdown", ""),
           "mounting_deg": json.loads(ds.attrs.get("mounting_deg", "[0.0, 0.0, 0.0]")),
           "axes": {}, "units": {m: metric_unit(m) for m in STABILITY_METRICS}, "chains": {}}
    for a in _map_axes(ds):
        out["axes"][a] = {"units": ds[a].attrs.get("units", ""), "values": ds[a].values.tolist()}
    out["velocity_bin"] = ds.velocity_bin.values.tolist()
    out["half_beamwidth_deg"] = ds.half_beamwidth_deg.values.tolist()
    for c in ds.chain.values.tolist():
        sub = ds.sel(chain=c)
        rec = {m: np.round(sub[m].median("seed").values, 6).tolist() for m in STABILITY_METRICS}
        rec["fail_fraction"] = sub.fail.mean("seed").values.tolist()
        rec["failing"] = failing_values(sub.fail.mean("seed"))
        if "worse_than_none" in ds:
            rec["worse_than_none_fraction"] = sub.worse_than_none.mean("seed").values.tolist()
        out["chains"][c] = rec
    out["warnings"] = json.loads(ds.attrs.get("warnings", "[]"))
    return out


def _flat(x):
    if isinstance(x, list):
        for v in x:
            yield from _flat(v)
    else:
        yield float(x)


def summary_table(summary: dict) -> str:
    """Console table of map summaries: one row per map and chain.

    Columns: worst fail fraction over the grid, worst "worse than none"
    fraction, and the largest seed-median ``|pseudo_velocity_mps|`` and
    ``angle_error_worst_deg`` over the grid.
    """
    head = ("map", "chain", "fail", "worse than none", "max |pseudo_velocity_mps|",
            "max angle_error_worst_deg")
    rows = []
    for name, s in summary.items():
        for c, r in s["chains"].items():
            worse = r.get("worse_than_none_fraction")
            rows.append((name, c, f"{max(_flat(r['fail_fraction'])):.2f}",
                         "-" if worse is None or c == "none" else f"{max(_flat(worse)):.2f}",
                         f"{np.nanmax(np.abs(list(_flat(r['pseudo_velocity_mps'])))):.4g}",
                         f"{np.nanmax(list(_flat(r['angle_error_worst_deg']))):.4g}"))
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h)
              for i, h in enumerate(head)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True)),
             "  ".join("-" * w for w in widths)]
    lines += ["  ".join(v.ljust(w) for v, w in zip(r, widths, strict=True)) for r in rows]
    return "\n".join(lines)


def plot_stability(ds, path: str | os.PathLike) -> Path:
    """Heat-map figure of a stability map with the failure boundary drawn (matplotlib Agg).

    Rows: ``|pseudo_velocity_mps|`` in Doppler velocity bins and
    ``angle_error_worst_deg`` in half beamwidths; columns: chains. Colour is
    log10 of the normalised metric, so the failure boundary of each criterion
    is the 0 contour (drawn black), the boundary of the combined criterion
    (either fails, majority of seeds) is dotted white, and where a chain is
    worse than no compensation the boundary of that region is drawn dashed red.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    axes = _map_axes(ds)
    chains = ds.chain.values.tolist()
    pv = (np.abs(ds.pseudo_velocity_mps) / ds.velocity_bin).median("seed")
    ae = (ds.angle_error_worst_deg / ds.half_beamwidth_deg).median("seed")
    worse = ds.worse_than_none.mean("seed") if "worse_than_none" in ds else None
    fail = ds.fail.mean("seed")
    fig, grid = plt.subplots(2, len(chains), figsize=(3.6 * len(chains), 6.4), squeeze=False)
    fig.subplots_adjust(left=0.08, right=0.9, bottom=0.09, top=0.9, wspace=0.42, hspace=0.42)
    for row, (metric, label) in enumerate(((pv, "|pseudo_velocity_mps| / velocity bin"),
                                           (ae, "angle_error_worst_deg / half beamwidth"))):
        for col, c in enumerate(chains):
            ax = grid[row, col]
            z = np.log10(np.maximum(metric.sel(chain=c).values, 1e-3))
            if len(axes) == 1:
                z = z[:, None]
                xs, ys = np.arange(ds[axes[0]].size), np.array([0.0])
            else:
                xs, ys = np.arange(ds[axes[1]].size), np.arange(ds[axes[0]].size)
            mesh = ax.pcolormesh(xs, ys, z if len(axes) > 1 else z.T, vmin=-2, vmax=2,
                                 cmap="RdYlGn_r", shading="nearest")
            if min(z.shape) > 1:
                ax.contour(xs, ys, z, levels=[0.0], colors="k", linewidths=2)
                f = fail.sel(chain=c).values.astype(float)
                if 0 < f.max() and f.min() < 1:
                    ax.contour(xs, ys, f, levels=[0.5], colors="w", linestyles=":",
                               linewidths=1.5)
                if worse is not None and c != "none":
                    w = worse.sel(chain=c).values.astype(float)
                    if 0 < w.max() and w.min() < 1:
                        ax.contour(xs, ys, w, levels=[0.5], colors="r", linestyles="--")
            if len(axes) > 1:
                ax.set_xticks(xs, tick_labels(axes[1], ds[axes[1]].values), fontsize=7)
                ax.set_yticks(ys, tick_labels(axes[0], ds[axes[0]].values), fontsize=7)
                ax.set_xlabel(f"{axes[1]} [{ds[axes[1]].attrs.get('units', '')}]", fontsize=8)
            if col == 0:
                ax.set_ylabel(f"{axes[0]} [{ds[axes[0]].attrs.get('units', '')}]", fontsize=8)
            ax.set_title(f"{c}: {label}", fontsize=7)
        cax = fig.add_axes([0.92, 0.56 - 0.47 * row, 0.012, 0.34])
        fig.colorbar(mesh, cax=cax, label="log10 (fail above 0)")
    mount = json.loads(ds.attrs.get("mounting_deg", "[0.0, 0.0, 0.0]"))
    mounted = "" if not any(mount) else f", radar mounted {tuple(mount)} deg"
    fig.suptitle(f"{ds.attrs['title']}{mounted}  (black: boundary of this criterion; "
                 f"white dotted: either criterion fails; red dashed: worse than none)",
                 fontsize=9)
    try:
        return atomic_savefig(fig, Path(path), dpi=100)
    finally:
        plt.close(fig)
