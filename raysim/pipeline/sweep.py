"""Parameter sweeps on Dask, resumable point by point.

A sweep varies any scenario key path (``radar.num_chirps``,
``motion.sinusoids.0.amplitude_deg``, ``imu.preset`` ...) over a list of
values, takes the Cartesian product of all varied keys and repeats every
combination for each seed (the scenario's top-level ``seed``). Every point is
one Dask task that renders the scenario in memory and measures it with
:func:`raysim.pipeline.run.evaluate`.

Resumability: a point is identified by a hash of the base scenario, its
values and its seed. Each finished point is written atomically to
``<out>/points/<hash>.json`` (by the worker, and again by the client if the
worker's file system is not shared); a rerun skips every point whose file
exists, so an interrupted sweep only computes what is missing. The gathered
results are one :class:`xarray.Dataset` with one dimension per varied key
(named by :func:`dimension_name`: the key path as a Python identifier, e.g.
``imu_preset`` for ``imu.preset``, usable with ``.sel``; the key path itself is
the coordinate's attribute ``key_path``), ``seed`` and ``chain``, one variable per metric
of :data:`raysim.vocabulary.METRICS` (NaN where a point is missing or
failed) and ``warnings`` (the compensation's guard warnings of that point and
chain, one per line, '' for none; :func:`warning_summary` condenses them),
written to ``<out>/sweep.nc``. Chains are the keys of
:func:`raysim.vocabulary.parse_chains` (``none``, ``paper``,
``paper:published``, ``exact``).

One folder, one sweep: ``<out>/sweep.json`` records the spec (base scenario,
parameters, seeds, chains); a sweep given an ``--out`` whose ``sweep.json``
describes another spec raises :class:`ValueError` naming what differs
(:func:`check_out_dir`) instead of mixing the two sweeps' points.

Scheduler: a :class:`distributed.LocalCluster` by default (in-process threads,
``processes=False``, which suits a 2-core machine), or any scheduler address
(``tcp://host:8786``) of a real cluster whose workers can import raysim.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import re
import time
import traceback
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from raysim.measure.point import POINT_METRICS
from raysim.scenario import Scenario, parse_value, validate_scenario
from raysim.vocabulary import metric_unit, parse_chains

__all__ = ["SweepSpec", "SweepPoint", "SweepResult", "parse_values", "sweep_points",
           "point_key", "run_sweep", "gather_results", "load_point", "warning_summary",
           "BOOKKEEPING_VARIABLES", "MAX_POINTS", "dimension_name", "dimension_names",
           "check_out_dir"]

#: Variables of a sweep Dataset that are not metrics.
BOOKKEEPING_VARIABLES = ("point_done", "warnings")
#: Most points of one sweep (values of every key times the seeds) [1]: each point renders
#: a scenario (seconds to minutes), so more is a mistyped range, refused before expanding.
MAX_POINTS = 100_000


def parse_values(text: str) -> list:
    """Values of a swept key from the command line.

    Accepted forms: ``1,2,4`` (comma list), ``[1, 2, 4]`` (TOML list),
    ``range(START, STOP[, STEP])`` (integers, STOP excluded),
    ``linspace(START, STOP, NUM)`` (floats, STOP included),
    ``logspace(START_EXP, STOP_EXP, NUM)`` (base 10).

    Raises
    ------
    ValueError
        For an empty list or a malformed range.
    """
    text = text.strip()
    m = re.fullmatch(r"(range|linspace|logspace)\((.*)\)", text)
    if m:
        fn, args = m.group(1), [a.strip() for a in m.group(2).split(",")]
        try:
            nums = [float(a) for a in args]
        except ValueError:
            raise ValueError(f"{text!r}: arguments of {fn}() must be numbers") from None
        if not all(math.isfinite(n) for n in nums):
            raise ValueError(f"{text!r}: arguments of {fn}() must be finite numbers")
        if fn == "range":
            if not 1 <= len(nums) <= 3 or any(n != int(n) for n in nums):
                raise ValueError(f"{text!r}: range() takes 1 to 3 integers")
            if len(nums) == 3 and nums[2] == 0:
                raise ValueError(f"{text!r}: range() step must not be zero")
            count = len(range(*[int(n) for n in nums]))
        else:
            if len(nums) != 3 or nums[2] != int(nums[2]) or nums[2] < 1:
                raise ValueError(f"{text!r}: {fn}(START, STOP, NUM) needs an integer NUM >= 1")
            count = int(nums[2])
        if count > MAX_POINTS:
            raise ValueError(f"{text!r}: {count} values, more than a sweep's {MAX_POINTS} "
                             f"points; expected a shorter range")
        if fn == "range":
            vals = list(range(*[int(n) for n in nums]))
        else:
            gen = np.linspace if fn == "linspace" else np.logspace
            vals = [float(v) for v in gen(nums[0], nums[1], int(nums[2]))]
    elif text.startswith("["):
        vals = parse_value(text)
        if not isinstance(vals, list):
            raise ValueError(f"{text!r}: not a valid TOML list")
    else:
        vals = [parse_value(v.strip()) for v in text.split(",") if v.strip()]
    if not vals:
        raise ValueError(f"{text!r}: no values")
    return vals


@dataclass(frozen=True)
class SweepSpec:
    """What to sweep.

    Attributes
    ----------
    base : Scenario
        Scenario every point starts from.
    parameters : dict
        Key path -> list of values (order kept; becomes a dimension).
    seeds : tuple of int
        Values of the scenario ``seed`` each combination is run with.
    chains : tuple of str
        Processing chains measured: names accepted by
        :func:`raysim.vocabulary.parse_chains`, stored as their keys.
    """

    base: Scenario
    parameters: dict = field(default_factory=dict)
    seeds: tuple = (0,)
    chains: tuple = ("none",)

    def __post_init__(self) -> None:
        if not isinstance(self.base, Scenario):
            raise ValueError(f"base must be a Scenario, got {type(self.base).__name__}")
        params = {}
        for k, vals in dict(self.parameters).items():
            vals = list(vals)
            if not vals:
                raise ValueError(f"parameter {k!r}: empty list of values")
            if k == "seed":
                raise ValueError("sweep the seed with --seeds (SweepSpec seeds=...), "
                                 "not as a parameter")
            params[k] = vals
        object.__setattr__(self, "parameters", params)
        seeds = tuple(int(s) for s in self.seeds)
        if not seeds or any(s < 0 for s in seeds):
            raise ValueError(f"seeds must be a non-empty list of integers >= 0, got {self.seeds}")
        object.__setattr__(self, "seeds", seeds)
        total = math.prod(len(v) for v in params.values()) * len(seeds)
        if total > MAX_POINTS:
            shape = " x ".join(str(len(v)) for v in params.values())
            raise ValueError(f"the sweep has {total} points ({shape} values x {len(seeds)} "
                             f"seeds), more than {MAX_POINTS}; expected fewer values or seeds")
        chains = tuple(c.key for c in parse_chains(self.chains))
        object.__setattr__(self, "chains", chains)


@dataclass(frozen=True)
class SweepPoint:
    """One task: the values of the varied keys, the seed and the point's hash key."""

    index: tuple
    values: dict
    seed: int
    key: str


def point_key(base: Scenario, values: dict, seed: int, chains: Sequence[str]) -> str:
    """Hash (16 hex digits) identifying a point: base scenario, values, seed, chains."""
    base_d = base.to_dict()
    base_d.pop("output", None)
    blob = json.dumps({"base": base_d, "values": values, "seed": int(seed),
                       "chains": list(chains)}, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def sweep_points(spec: SweepSpec) -> list[SweepPoint]:
    """Every point of the sweep, each validated (bad key paths / values raise here)."""
    names = list(spec.parameters)
    grids = [range(len(spec.parameters[n])) for n in names]
    points = []
    for idx in itertools.product(*grids):
        values = {n: spec.parameters[n][i] for n, i in zip(names, idx, strict=True)}
        for si, seed in enumerate(spec.seeds):
            _scenario_of(spec.base, values, seed)  # validate now, not in a worker
            points.append(SweepPoint(idx + (si,), values, seed,
                                     point_key(spec.base, values, seed, spec.chains)))
    return points


def _scenario_of(base: Scenario, values: dict, seed: int) -> Scenario:
    try:
        return base.with_values({**values, "seed": int(seed)})
    except ValueError as exc:
        raise ValueError(f"sweep point {values} seed {seed}: {exc}") from None


# ------------------------------------------------------------------ tasks
def _point_metrics(scenario: Scenario, chains: Sequence[str]) -> dict:
    """Metrics of one point (``chains``: chain -> metric -> value), ``warnings``
    (chain -> guard warnings) and ``notes``."""
    from raysim.pipeline.run import evaluate

    res = evaluate(scenario, chains=chains)
    return {"chains": res["chains"], "warnings": res["warnings"], "notes": res["notes"]}


def _point_path(out_dir: Path, key: str) -> Path:
    return Path(out_dir) / "points" / f"{key}.json"


def _jsonable(obj):
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


def _run_point(base_json: str, values: dict, seed: int, chains: list, key: str,
               out_dir: str) -> dict:
    """Dask task: evaluate one point and persist it atomically. Never raises."""
    from raysim.io.storage import atomic_write_text

    t0 = time.perf_counter()
    try:
        scenario = _scenario_of(validate_scenario(json.loads(base_json)), values, seed)
        res = _point_metrics(scenario, chains)
    except Exception as exc:  # reported to the client, point left missing
        return {"key": key, "values": values, "seed": seed,
                "error": f"{type(exc).__name__}: {exc}",
                "traceback": traceback.format_exc(limit=5)}
    record = _jsonable({"key": key, "values": values, "seed": seed, "chains": res["chains"],
                        "warnings": res.get("warnings", {}), "notes": res["notes"],
                        "elapsed_s": time.perf_counter() - t0})
    try:
        atomic_write_text(_point_path(Path(out_dir), key), json.dumps(record, indent=1))
    except OSError:
        pass  # not a shared file system: the client writes it
    return record


def load_point(out_dir: str | Path, key: str) -> dict | None:
    """The stored record of a finished point, or None."""
    p = _point_path(Path(out_dir), key)
    if not p.is_file():
        return None
    try:
        return json.loads(p.read_text())
    except (OSError, json.JSONDecodeError):
        return None  # unreadable: computed again


# ---------------------------------------------------------------- results
@dataclass
class SweepResult:
    """Outcome of :func:`run_sweep`.

    Attributes
    ----------
    dataset : xarray.Dataset
        Metrics with dims ``(*parameters, seed, chain)``.
    computed : list of str
        Keys of the points computed by this call.
    skipped : list of str
        Keys found finished on disk.
    failed : dict
        Key -> error message of points that raised.
    path : str
        ``sweep.nc`` written (empty if nothing was written).
    removed : list of str
        Temporary files of an interrupted writer removed by this call.
    """

    dataset: Any
    computed: list = field(default_factory=list)
    skipped: list = field(default_factory=list)
    failed: dict = field(default_factory=dict)
    path: str = ""
    removed: list = field(default_factory=list)


def _coord(values: list):
    if all(isinstance(v, bool) for v in values):
        return np.array(values, dtype=bool)
    if all(isinstance(v, int) and not isinstance(v, bool) for v in values):
        return np.array(values, dtype=np.int64)
    if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return np.array(values, dtype=float)
    return np.array([json.dumps(v) if not isinstance(v, str) else v for v in values],
                    dtype=object)


def dimension_name(key: str) -> str:
    """A Python identifier for a swept key path: ``imu.preset`` -> ``imu_preset``.

    Every character that cannot appear in an identifier becomes ``_``; a name
    that would start with a digit gets the prefix ``p_``.
    """
    name = re.sub(r"\W", "_", str(key))
    return f"p_{name}" if not name or name[0].isdigit() else name


def dimension_names(keys: Sequence[str]) -> dict:
    """Key path -> dimension name (:func:`dimension_name`), unique and never ``seed`` /
    ``chain`` (a clash gets the suffix ``_2``, ``_3`` ...)."""
    out: dict = {}
    taken = {"seed", "chain"}
    for key in keys:
        base = name = dimension_name(key)
        n = 1
        while name in taken:
            n += 1
            name = f"{base}_{n}"
        taken.add(name)
        out[key] = name
    return out


def gather_results(spec: SweepSpec, out_dir: str | Path, points: list[SweepPoint] | None = None):
    """Assemble the stored point records into one Dataset (NaN where missing)."""
    import xarray as xr

    points = sweep_points(spec) if points is None else points
    names = list(spec.parameters)
    shape = tuple(len(spec.parameters[n]) for n in names) + (len(spec.seeds), len(spec.chains))
    arrays = {m: np.full(shape, np.nan) for m in POINT_METRICS}
    warns = np.full(shape, "", dtype=object)
    done = np.zeros(shape[:-1], dtype=bool)
    for p in points:
        rec = load_point(out_dir, p.key)
        if rec is None:
            continue
        done[p.index] = True
        for ci, chain in enumerate(spec.chains):
            metrics = (rec.get("chains") or {}).get(chain) or {}
            for m in POINT_METRICS:
                v = metrics.get(m)
                if v is not None:
                    arrays[m][p.index + (ci,)] = float(v)
            warns[p.index + (ci,)] = "\n".join((rec.get("warnings") or {}).get(chain) or [])
    dim_of = dimension_names(names)
    dims = tuple(dim_of[n] for n in names) + ("seed", "chain")
    coords = {dim_of[n]: (dim_of[n], _coord(spec.parameters[n]), {"key_path": n})
              for n in names}
    coords["seed"] = ("seed", np.array(spec.seeds, dtype=np.int64))
    coords["chain"] = ("chain", np.array(spec.chains, dtype=object))
    data = {m: (dims, arrays[m], {"units": metric_unit(m)}) for m in POINT_METRICS}
    data["point_done"] = (dims[:-1], done, {"long_name": "point finished and stored"})
    data["warnings"] = (dims, warns, {"long_name": "guard warnings of the compensation, one "
                                                   "per line ('' for none)"})
    base = spec.base.to_dict()
    base.pop("output", None)
    return xr.Dataset(data, coords=coords, attrs={
        "scenario_json": json.dumps(base, sort_keys=True), "scenario_name": spec.base.name,
        "parameters": json.dumps(names), "dimensions": json.dumps(dim_of),
        "points_total": len(points),
        "points_done": int(done.sum())})


def _manifest(spec: SweepSpec) -> dict:
    """The spec as written to ``sweep.json`` (JSON types)."""
    base = spec.base.to_dict()
    base.pop("output", None)
    return json.loads(json.dumps(_jsonable({
        "base": base, "parameters": spec.parameters, "seeds": list(spec.seeds),
        "chains": list(spec.chains)})))


def _write_manifest(spec: SweepSpec, out_dir: Path) -> None:
    from raysim.io.storage import atomic_write_text

    atomic_write_text(out_dir / "sweep.json", json.dumps(_manifest(spec), indent=1))


def _differences(old, new, prefix: str = "") -> list[str]:
    """Key paths where two JSON values differ (dicts compared key by key)."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for k in sorted(set(old) | set(new), key=str):
            out.extend(_differences(old.get(k), new.get(k), f"{prefix}.{k}" if prefix else k))
        return out
    return [] if old == new else [prefix or "(all)"]


def check_out_dir(spec: SweepSpec, out_dir: str | Path) -> None:
    """Refuse an output folder that cannot hold this sweep, before anything is computed.

    Raises
    ------
    ValueError
        ``out_dir`` is a file, lies under a file, or holds a ``sweep.json``
        of another sweep (a different base scenario, parameters, seeds or
        chains; the message names the keys that differ) or an unreadable one.
    """
    from raysim.io.files import check_output

    out = Path(out_dir)
    check_output(out, "dir", "--out")
    manifest = out / "sweep.json"
    if manifest.exists():
        _check_same_sweep(spec, out, manifest)
    check_output(out, "dir", "--out", names=("sweep.json", "sweep.nc"))


def _check_same_sweep(spec: SweepSpec, out: Path, manifest: Path) -> None:
    """Raise ValueError unless ``manifest`` (a ``sweep.json``) describes ``spec``."""
    try:
        old = json.loads(manifest.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"--out {str(out)!r}: its sweep.json cannot be read ({exc}); expected "
                         f"the manifest of a raysim sweep, or choose another --out") from None
    diff = _differences(old, _manifest(spec))
    if diff:
        shown = ", ".join(diff[:6]) + (f" and {len(diff) - 6} more" if len(diff) > 6 else "")
        raise ValueError(f"--out {str(out)!r} holds another sweep (its sweep.json differs in "
                         f"{shown}); choose another --out, or remove that folder to start "
                         f"this sweep there")


def run_sweep(spec: SweepSpec, out_dir: str | Path, *, scheduler: str | None = None,
              n_workers: int = 1, threads_per_worker: int = 2, processes: bool = False,
              limit: int | None = None, progress: bool = False,
              client=None) -> SweepResult:
    """Run (or resume) a sweep on Dask and gather its results.

    Parameters
    ----------
    spec : SweepSpec
    out_dir : path
        Folder of the point records, the manifest and ``sweep.nc``.
    scheduler : str, optional
        Address of a running Dask scheduler; default starts a LocalCluster.
    n_workers, threads_per_worker, processes
        LocalCluster layout (default: one in-process worker with 2 threads).
    limit : int, optional
        Compute at most this many missing points (the rest stay missing).
    progress : bool
        Print a tqdm progress bar on stderr.
    client : distributed.Client, optional
        Use this client instead of creating one.

    Returns
    -------
    SweepResult

    Raises
    ------
    ValueError
        A bad point, or an ``out_dir`` that is a file, cannot be created or
        holds another sweep (:func:`check_out_dir`); nothing is computed then.
    """
    from raysim.io.store_guard import remove_debris, remove_tmp_files, writer_lock

    out_dir = Path(out_dir)
    points = sweep_points(spec)
    check_out_dir(spec, out_dir)
    with writer_lock(out_dir):      # one writer per sweep folder; debris of a killed one
        removed = remove_debris(out_dir) + remove_tmp_files(out_dir) \
            + remove_tmp_files(out_dir / "points")
        try:
            (out_dir / "points").mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ValueError(f"--out {str(out_dir)!r}: cannot create the results folder "
                             f"({exc.strerror or exc}); expected a writable folder") from None
        _write_manifest(spec, out_dir)
        todo = [p for p in points if load_point(out_dir, p.key) is None]
        result = SweepResult(None, skipped=[p.key for p in points if p not in todo])
        if limit is not None:
            todo = todo[: max(0, int(limit))]
        if todo:
            from raysim.io.storage import atomic_write_text
            from raysim.pipeline.tasks import dask_client, run_tasks

            bar = None
            if progress:
                from tqdm import tqdm

                bar = tqdm(total=len(points), initial=len(result.skipped), unit="point",
                           desc="sweep")
            base_json = spec.base.model_dump_json()

            def done(key: str, rec: dict) -> None:
                if "error" in rec:
                    result.failed[rec["key"]] = rec["error"]
                else:
                    path = _point_path(out_dir, rec["key"])
                    if not path.is_file():
                        atomic_write_text(path, json.dumps(rec, indent=1))
                    result.computed.append(rec["key"])
                if bar is not None:
                    bar.update(1)

            try:
                with dask_client(client, scheduler=scheduler, n_workers=n_workers,
                                 threads_per_worker=threads_per_worker, processes=processes) as cl:
                    run_tasks(_run_point, [(f"point-{p.key}", (base_json, p.values, p.seed,
                                                               list(spec.chains), p.key,
                                                               str(out_dir)))
                                           for p in todo], done, client=cl)
            finally:
                if bar is not None:
                    bar.close()
        result.dataset = gather_results(spec, out_dir, points)
        nc = out_dir / "sweep.nc"
        _export(result.dataset, nc)
        result.path = str(nc)
        result.removed = [str(p) for p in removed]
    return result


def _export(ds, path: Path) -> None:
    from raysim.io.storage import export_netcdf

    out = ds.copy()
    out["chain"] = out["chain"].astype(str)
    for name in list(out.coords):
        if out[name].dtype == object:
            out[name] = out[name].astype(str)
    out["point_done"] = out["point_done"].astype(np.int8)
    out["warnings"] = out["warnings"].astype(str)
    export_netcdf(out, path)


def warning_summary(ds) -> list[str]:
    """One line per chain and warning kind of a sweep Dataset.

    Warnings are grouped by their stable key (the text before the first
    colon, e.g. ``small-angle``, see :mod:`compensation.guards`).

    Parameters
    ----------
    ds : xarray.Dataset
        Output of :func:`gather_results` (variable ``warnings``).

    Returns
    -------
    list of str
        ``"<chain>: <key> at <n>/<done> points (e.g. <first text>)"``; empty
        when no point raised a warning.
    """
    if "warnings" not in ds:
        return []
    done = int(np.asarray(ds["point_done"].values).sum())
    lines = []
    for chain in [str(c) for c in ds["chain"].values]:
        texts = np.asarray(ds["warnings"].sel(chain=chain).values, dtype=object).ravel()
        groups: dict[str, list[str]] = {}
        for cell in texts:
            keys_here = {}
            for w in str(cell).split("\n") if cell else []:
                keys_here.setdefault(w.split(":", 1)[0], w)
            for k, w in keys_here.items():
                groups.setdefault(k, []).append(w)
        lines.extend(f"{chain}: {k} at {len(ws)}/{done} points (e.g. {ws[0]})"
                     for k, ws in groups.items())
    return lines
