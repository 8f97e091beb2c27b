"""Running the stability maps: points as tasks, resumable per point and per map.

:func:`run_map` evaluates one map point by point (an in-process Dask cluster
or a plain loop), keeping each finished point as a JSON record so an
interrupted map resumes; :func:`write_stability` writes every map's NetCDF,
JSON and figure plus ``summary.json``, reusing the maps already finished.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import time
from collections.abc import Sequence
from dataclasses import asdict
from pathlib import Path

import numpy as np

from raysim.io.files import atomic_write_json
from raysim.pipeline.tasks import dask_client, have_distributed, run_tasks
from raysim.platform.mounting import MOUNTING_PRESETS
from raysim.platform.mounting import mounting_deg as mounting_deg_of
from raysim.studies.stability.criteria import criteria_for
from raysim.studies.stability.grids import INT_AXES, MAPS, MapSpec
from raysim.studies.stability.metrics import MAP_CHAINS, STABILITY_METRICS, evaluate
from raysim.studies.stability.outputs import plot_stability, read_netcdf, summarise, write_netcdf
from raysim.vocabulary import metric_unit, parse_chains

__all__ = ["EXECUTORS", "POINT_VERSION", "run_map", "write_stability"]

#: Version of the per-point record format and of the chains (part of the point key).
POINT_VERSION = 3
#: How the points run: ``auto`` (Dask when installed), ``dask`` or ``serial``.
EXECUTORS = ("auto", "dask", "serial")
#: The default mounting (yaw, pitch, roll) [deg]: the radar looks down.
DOWN = MOUNTING_PRESETS["down"]


def _check_executor(executor: str) -> None:
    if executor not in EXECUTORS:
        raise ValueError(f"executor must be 'auto', 'dask' or 'serial', got {executor!r}")


def _map_spec(spec: MapSpec | str) -> MapSpec:
    if isinstance(spec, str):
        if spec not in MAPS:
            raise ValueError(f"unknown stability map {spec!r}; expected one of {sorted(MAPS)}")
        return MAPS[spec]
    return spec


def _point_key(spec: MapSpec, kw: dict, seed: int, chains: Sequence[str],
               mounting: tuple = DOWN) -> str:
    fields = {"map": spec.name, "values": kw, "seed": int(seed), "chains": list(chains),
              "version": POINT_VERSION}
    if tuple(mounting) != DOWN:              # the down radar's keys stay as they were
        fields["mounting_deg"] = list(mounting)
    blob = json.dumps(fields, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def _evaluate_point(spec: MapSpec, kw: dict, seed: int, chains: Sequence[str],
                    mounting: tuple = DOWN) -> dict:
    """One map point: metrics and thresholds (a plain, JSON-ready dict)."""
    point = spec.build(seed=seed, **kw)
    if tuple(mounting) != DOWN:
        point = point.with_(mounting_deg=mounting)
    res = evaluate(point, chains)
    crit = criteria_for(point.config, point.array)
    return {"values": kw, "seed": int(seed),
            "metrics": {c: res[c] for c in chains}, "criteria": asdict(crit),
            "warnings": res["warnings"], "strapdown": res["strapdown"]}


def _load_record(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None                             # missing or unreadable: compute again


def run_map(spec: MapSpec | str, *, quick: bool = False, chains: Sequence[str] | None = None,
            progress: bool = True, points_dir: str | os.PathLike | None = None,
            executor: str = "auto", client=None, mounting_deg=None):
    """Evaluate a stability map, point by point, resumably.

    Parameters
    ----------
    spec : MapSpec or str
        Map or its name in :data:`~raysim.studies.stability.grids.MAPS`.
    quick : bool
        Use the quick axis values and seeds.
    chains : sequence of str, optional
        Chain keys (``none``, ``paper``, ``paper:published``, ``exact``,
        ``dpca``); default the map's own (``MapSpec.chains``), else
        :data:`~raysim.studies.stability.metrics.MAP_CHAINS`.
    progress : bool
        Show a progress bar (tqdm, on stderr).
    points_dir : path-like, optional
        Folder of per-point records (``<key>.json``, written atomically as each
        point finishes); points already recorded there are not computed again,
        so an interrupted map resumes where it stopped.
    executor : {"auto", "dask", "serial"}
        ``"dask"``: one task per point on an in-process ``distributed``
        LocalCluster (one worker, two threads); ``"serial"``: a plain loop;
        ``"auto"``: Dask when ``distributed`` is importable.
    client : distributed.Client, optional
        Run the points on this client (any scheduler whose workers import raysim).
    mounting_deg : str or (float, float, float), optional
        Radar mounting of every point (:attr:`StabilityPoint.mounting_deg`): the
        map's body motion seen by a radar mounted so, its target angles in the
        nominal radar frame N; default ``down``.

    Returns
    -------
    xarray.Dataset
        Variables of :data:`~raysim.studies.stability.metrics.STABILITY_METRICS`
        (units in their ``units`` attribute) with dims
        ``(chain, <axis 0>, <axis 1>, seed)``, ``fail`` (bool,
        :func:`~raysim.studies.stability.criteria.fails`, or a chain that could not
        run: NaN metrics), ``worse_than_none``
        (bool: ``|pseudo_velocity_mps|`` or ``angle_error_worst_deg`` above the
        baseline's), and the thresholds ``velocity_bin`` [m/s],
        ``half_beamwidth_deg``, ``doppler_bin_hz`` per grid point; attribute
        ``mounting_deg`` (JSON list of yaw, pitch, roll [deg]).
    """
    spec = _map_spec(spec)
    _check_executor(executor)
    mounting = mounting_deg_of(mounting_deg)
    if chains is None:
        chains = spec.chains or MAP_CHAINS
    chains = [s.key for s in parse_chains(chains)]
    names = [a[0] for a in spec.axes]
    values = [np.asarray(a[3] if quick else a[2], dtype=float) for a in spec.axes]
    n_seed = spec.quick_seeds if quick else spec.seeds
    shape = (len(chains),) + tuple(v.size for v in values) + (n_seed,)
    todo = []
    for g in np.ndindex(*shape[1:-1]):
        kw = {name: (int(v[i]) if name in INT_AXES else float(v[i]))
              for name, v, i in zip(names, values, g, strict=True)}
        for s in range(n_seed):
            todo.append((g, s, kw, _point_key(spec, kw, s, chains, mounting)))
    pdir = None if points_dir is None else Path(points_dir)
    records: dict[str, dict] = {}
    if pdir is not None:
        pdir.mkdir(parents=True, exist_ok=True)
        for *_, key in todo:
            rec = _load_record(pdir / f"{key}.json")
            if rec is not None:
                records[key] = rec
    missing = [t for t in todo if t[3] not in records]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), initial=len(todo) - len(missing), desc=spec.name,
                   unit="point", leave=False)

    def done(key: str, rec: dict) -> None:
        records[key] = rec
        if pdir is not None:
            atomic_write_json(pdir / f"{key}.json", rec)
        if bar is not None:
            bar.update(1)

    use_dask = client is not None or executor == "dask" or (
        executor == "auto" and len(missing) > 1 and have_distributed())
    tasks = [(key, (spec, kw, s, tuple(chains), mounting)) for _, s, kw, key in missing]
    try:
        with (dask_client(client) if missing and use_dask
              else contextlib.nullcontext(False)) as cl:
            run_tasks(_evaluate_point, tasks, done, client=cl)
    finally:
        if bar is not None:
            bar.close()
    ds = _dataset(spec, quick, chains, names, values, shape, todo, records)
    ds.attrs["mounting_deg"] = json.dumps(list(mounting))
    return ds


def _dataset(spec, quick, chains, names, values, shape, todo, records):
    import xarray as xr

    data = {m: np.full(shape, np.nan) for m in STABILITY_METRICS}
    thresholds = {k: np.full(shape[1:-1], np.nan)
                  for k in ("velocity_bin", "half_beamwidth_deg", "doppler_bin_hz")}
    warn: list[str] = []
    source = set()
    for g, s, kw, key in todo:
        rec = records[key]
        for ci, c in enumerate(chains):
            for m in STABILITY_METRICS:
                data[m][(ci,) + g + (s,)] = rec["metrics"][c][m]
        for k in thresholds:
            thresholds[k][g] = rec["criteria"][k]
        warn.extend(f"{kw}: {w}" for w in rec["warnings"])
        source.add(rec["strapdown"])
    dims = ("chain",) + tuple(names) + ("seed",)
    coords = {"chain": list(chains), "seed": np.arange(shape[-1])}
    coords.update({n: v for n, v in zip(names, values, strict=True)})
    ds = xr.Dataset({m: (dims, data[m]) for m in STABILITY_METRICS}, coords=coords)
    for m in STABILITY_METRICS:
        ds[m].attrs["units"] = metric_unit(m)
    for k, v in thresholds.items():
        ds[k] = (tuple(names), v)
    ds["velocity_bin"].attrs["units"] = "m/s"
    ds["half_beamwidth_deg"].attrs["units"] = "deg"
    ds["doppler_bin_hz"].attrs["units"] = "Hz"
    # a chain that could not run (NaN: dpca beyond its spare aperture) fails too
    ds["fail"] = ((np.abs(ds.pseudo_velocity_mps) > ds.velocity_bin)
                  | (ds.angle_error_worst_deg > ds.half_beamwidth_deg)
                  | np.isnan(ds.pseudo_velocity_mps) | np.isnan(ds.angle_error_worst_deg))
    if "none" in chains:
        base = ds.sel(chain="none")
        ds["worse_than_none"] = (
            (np.abs(ds.pseudo_velocity_mps) > np.abs(base.pseudo_velocity_mps))
            | (ds.angle_error_worst_deg > base.angle_error_worst_deg + 1e-9))
    ds.attrs.update({"map": spec.name, "title": spec.title, "note": spec.note,
                     "quick": int(quick), "point_version": POINT_VERSION,
                     "strapdown": ", ".join(sorted(source - {""})),
                     "units": json.dumps({a[0]: a[1] for a in spec.axes}),
                     "warnings": json.dumps(sorted(set(warn))[:50])})
    for a in spec.axes:
        ds[a[0]].attrs["units"] = a[1]
    return ds


def write_stability(out_dir: str | os.PathLike, *, quick: bool = False,
                    maps: Sequence[str] | None = None, progress: bool = True,
                    executor: str = "auto", mounting_deg=None) -> dict:
    """Produce every stability map: NetCDF, JSON and PNG per map plus ``summary.json``.

    Each file is written atomically; a map already finished in ``out_dir``
    (its ``.nc`` exists with the same axes, ``quick`` flag and record version)
    is reused, and every finished point of an unfinished map is kept under
    ``points/<map>/``, so an interrupted run resumes where it stopped.

    Parameters
    ----------
    out_dir : path-like
    quick : bool
        Small axes and fewer seeds (a few minutes on 2 cores).
    maps : sequence of str, optional
        Subset of :data:`~raysim.studies.stability.grids.MAPS` (default all).
    progress : bool
        Progress bars on stderr.
    executor : {"auto", "dask", "serial"}
        See :func:`run_map`.
    mounting_deg : str or (float, float, float), optional
        Radar mounting of every map (see :func:`run_map`); a stored map of
        another mounting is computed again.

    Returns
    -------
    dict
        ``map name -> summary`` (:func:`~raysim.studies.stability.outputs.summarise`;
        also written to ``summary.json``).
    """
    out = Path(out_dir)
    names = list(MAPS) if maps is None else list(maps)
    for n in names:
        if n not in MAPS:
            raise ValueError(f"unknown stability map {n!r}; expected one of {sorted(MAPS)}")
    _check_executor(executor)
    mounting = mounting_deg_of(mounting_deg)
    out.mkdir(parents=True, exist_ok=True)
    with contextlib.ExitStack() as stack:
        client = None
        if executor == "dask" or (executor == "auto" and have_distributed()):
            client = stack.enter_context(dask_client())
        return _write_maps(out, names, quick, progress, client, mounting)


def _same_axes(ds, spec: MapSpec, quick: bool, mounting: tuple = DOWN) -> bool:
    """Whether a stored map was computed on the axes (and seeds) and with the mounting
    the spec and the run ask for now."""
    if int(ds.attrs.get("quick", -1)) != int(quick):
        return False
    if tuple(json.loads(ds.attrs.get("mounting_deg", "[0.0, 0.0, 0.0]"))) != tuple(mounting):
        return False
    if int(ds.attrs.get("point_version", -1)) != POINT_VERSION:
        return False                           # older record format or chains: recompute
    for name, _, full, short in spec.axes:
        want = np.asarray(short if quick else full, dtype=float)
        if name not in ds.coords or ds[name].size != want.size or not np.allclose(
                ds[name].values, want):
            return False
    return ds.sizes.get("seed", 0) == (spec.quick_seeds if quick else spec.seeds)


def _write_maps(out: Path, names: list, quick: bool, progress: bool, client,
                mounting: tuple = DOWN) -> dict:
    summary = {}
    for n in names:
        nc = out / f"{n}.nc"
        ds = None
        if nc.exists():
            try:
                old = read_netcdf(nc)
            except ValueError:
                old = None                     # unreadable: recompute and replace
            if old is not None and _same_axes(old, MAPS[n], quick, mounting):
                ds = old
        if ds is None:
            t = time.perf_counter()
            ds = run_map(n, quick=quick, progress=progress, client=client,
                         executor="serial" if client is None else "dask",
                         points_dir=out / "points" / f"{n}{'_quick' if quick else ''}",
                         mounting_deg=mounting)
            ds.attrs["seconds"] = round(time.perf_counter() - t, 2)
            write_netcdf(ds, nc)
        summ = summarise(ds)
        atomic_write_json(out / f"{n}.json", summ, indent=1)
        plot_stability(ds, out / f"{n}.png")
        summary[n] = summ
    atomic_write_json(out / "summary.json", summary, indent=1)
    return summary
