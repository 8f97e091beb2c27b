"""Zarr frame stores: create, append, repair (writer only) and open (readers).

A store is a Zarr (format 3) group written by :mod:`raysim.io.storage`'s
Datasets. It is chunked per frame (one or a few chunks per frame, never a
chunk spanning two frames) and grows along ``frame``. The group attribute
``frames_complete`` is updated only after a frame's arrays are fully written;
:func:`open_store` and :func:`repair_store` ignore / cut anything beyond it,
so an interrupted render keeps its finished frames and resumes at the next.

Consolidated metadata: the writer consolidates the metadata of every array
into the group's ``zarr.json`` after creating the store and again after each
append (:func:`consolidate`, under the writer's lock), so a plain
``xarray.open_zarr(path)`` opens a store in one read and without a warning,
and sees the frames complete at the last consolidation. The functions here
always read the arrays' own metadata (``use_consolidated=False``): while a
writer appends, the consolidated copy lags behind by design.

Every chunk is written, even one equal to the fill value, so a chunk file
that is missing from a store means damage: :func:`open_store` checks that the
chunks of the numeric variables are all present for the complete frames and
raises :class:`ValueError` naming the store, the variable and the frame
otherwise; a chunk that cannot be decoded (truncated or corrupted file) is
reported the same way. Stores written before consolidation and the CF
attributes (``raysim_format`` 1) open the same way.
"""

from __future__ import annotations

import itertools
import json
import os
import shutil
import time
import uuid
import warnings
from pathlib import Path

import numpy as np
import xarray as xr

from raysim.io.store_guard import check_replaceable, remove_store

__all__ = ["MAX_CHUNK_BYTES", "OPEN_RETRIES", "store_exists", "write_store", "append_frames",
           "frames_complete", "repair_store", "open_store", "consolidate"]

#: Upper bound of one Zarr chunk of ``if_data`` [bytes]; a frame is split along chirp.
MAX_CHUNK_BYTES = 32 * 2**20
#: Attempts to read a store's metadata while a writer may be rewriting it.
OPEN_RETRIES = 5


def _open_group(path: str | Path, mode: str = "r"):
    """The store's Zarr group, read from the arrays' own metadata (not the consolidated copy)."""
    import zarr

    return zarr.open_group(str(path), mode=mode, use_consolidated=False)


def consolidate(path: str | Path) -> None:
    """Write the consolidated metadata of the store at ``path`` (writer only).

    Zarr-Python warns that consolidated metadata is not yet part of the Zarr
    format 3 specification; the warning is silenced here, where it is
    written, and readers (``xarray.open_zarr``) do not warn.
    """
    import zarr

    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*[Cc]onsolidated metadata.*")
        zarr.consolidate_metadata(str(path))


def _zarr_encoding(ds: xr.Dataset) -> dict:
    enc = {}
    for name, var in ds.variables.items():
        e: dict = {}
        if var.dtype.kind in "fc":
            e["_FillValue"] = None
        if "frame" in var.dims:
            chunks = list(var.shape)
            chunks[var.dims.index("frame")] = 1
            if "chirp" in var.dims:
                i = var.dims.index("chirp")
                per_chirp = var.dtype.itemsize * int(np.prod(
                    [n for d, n in zip(var.dims, var.shape, strict=True)
                     if d not in ("frame", "chirp")]))
                chunks[i] = max(1, min(var.shape[i], MAX_CHUNK_BYTES // max(per_chirp, 1)))
            e["chunks"] = tuple(chunks)
        enc[name] = e
    return enc


def store_exists(path: str | Path) -> bool:
    """Whether ``path`` holds a Zarr group written by this module."""
    p = Path(path)
    return (p / "zarr.json").is_file() or (p / ".zgroup").is_file()


def write_store(path: str | Path, ds: xr.Dataset, *, overwrite: bool = False) -> None:
    """Create a Zarr store from ``ds`` atomically (written aside, consolidated, then renamed).

    Raises
    ------
    ValueError
        If ``path`` exists and ``overwrite`` is False.
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise ValueError(f"store {str(path)!r} already exists (overwrite to replace it)")
    check_replaceable(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.parent / f".{path.name}.{uuid.uuid4().hex[:8]}.tmp"
    ds = ds.copy()
    ds.attrs["frames_complete"] = int(ds.sizes.get("frame", 0))
    try:
        ds.to_zarr(tmp, mode="w", consolidated=False, encoding=_zarr_encoding(ds),
                   write_empty_chunks=True)
        consolidate(tmp)
        if path.exists():
            remove_store(path)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


def _frame_arrays(group) -> list:
    out = []
    for name, arr in group.arrays():
        dims = getattr(arr.metadata, "dimension_names", None) or arr.attrs.get(
            "_ARRAY_DIMENSIONS", ())
        if dims and dims[0] == "frame":
            out.append((name, arr))
    return out


def frames_complete(path: str | Path) -> int:
    """Frames fully written to the store at ``path`` (0 if there is no store)."""
    if not store_exists(path):
        return 0
    g = _open_group(path)
    return int(g.attrs.get("frames_complete", 0))


def repair_store(path: str | Path) -> int:
    """Cut arrays back to ``frames_complete`` frames after an interrupted append.

    Only a writer calls this, holding :func:`raysim.io.store_guard.writer_lock`;
    readers never modify a store.

    Returns
    -------
    int
        Number of complete frames kept.
    """
    g = _open_group(path, "r+")
    n = int(g.attrs.get("frames_complete", 0))
    for _, arr in _frame_arrays(g):
        if arr.shape[0] != n:
            arr.resize((n,) + tuple(arr.shape[1:]))
    return n


def append_frames(path: str | Path, ds: xr.Dataset) -> int:
    """Append the frames of ``ds`` to an existing store, then mark them complete.

    Only variables with a ``frame`` dimension are appended; the others (array
    geometry, IMU log) were written when the store was created. The store's
    metadata is consolidated again afterwards (:func:`consolidate`).

    Returns
    -------
    int
        Frames complete after the append.
    """
    n = repair_store(path)
    g = _open_group(path)
    attrs = dict(g.attrs)
    keep = [v for v in ds.variables if "frame" in ds[v].dims]
    part = ds[[v for v in keep if v in ds.data_vars]]
    part = part.drop_vars([c for c in part.coords if "frame" not in part[c].dims])
    part.attrs = attrs  # xarray rewrites the group attributes: keep them (frames_complete = n)
    part.to_zarr(str(path), append_dim="frame", consolidated=False, write_empty_chunks=True)
    n += int(ds.sizes["frame"])
    g = _open_group(path, "r+")
    attrs["frames_complete"] = n
    g.attrs.update(attrs)
    consolidate(path)  # plain readers (xarray.open_zarr) now see the new frames
    return n


def _frame_span(arr, chunk: int, n: int) -> str:
    """Frames covered by chunk number ``chunk`` along axis 0 of ``arr`` (``n`` frames)."""
    lo = chunk * arr.chunks[0]
    hi = min(lo + arr.chunks[0], n) - 1
    return f"frame {lo}" if hi <= lo else f"frames {lo}-{hi}"


def _check_chunks_present(path: Path, group, n_done: int) -> None:
    """Raise ValueError for a missing chunk file of a numeric variable.

    The writers here keep every chunk (``write_empty_chunks=True``), also one
    equal to the fill value, so a missing chunk of any numeric variable is
    damage: a deleted ``tx_slot`` chunk would otherwise read as slot 0.
    """
    for name, arr in group.arrays():
        if arr.dtype.kind not in "fciub" or arr.size == 0:
            continue
        dims = tuple(getattr(arr.metadata, "dimension_names", None)
                     or arr.attrs.get("_ARRAY_DIMENSIONS", ()))
        grid = list(arr.cdata_shape)
        per_frame = bool(dims) and dims[0] == "frame" and n_done >= 0
        if per_frame:
            grid[0] = min(grid[0], -(-n_done // arr.chunks[0]))
        folder = path / arr.path
        for coords in itertools.product(*(range(g) for g in grid)):
            key = arr.metadata.encode_chunk_key(coords)
            if not (folder / key).is_file():
                where, expected = (
                    (f"{_frame_span(arr, coords[0], n_done)}, ",
                     f"all chunk files of the {n_done} complete frames")
                    if per_frame else ("", "all chunk files of the variable"))
                raise ValueError(
                    f"Zarr store {str(path)!r} is damaged: variable {name!r} has no chunk file "
                    f"{key!r} ({where}chunk {coords}); expected {expected} (a missing one "
                    f"would read as the fill value {np.asarray(arr.fill_value).item()!r})")


def _load_checked(path: Path, ds: xr.Dataset, group) -> xr.Dataset:
    """Read every variable into memory; an undecodable chunk becomes a ValueError."""
    for name, var in ds.variables.items():
        try:
            var.load()
        except MemoryError:
            raise
        except Exception as exc:
            raise ValueError(
                f"Zarr store {str(path)!r} is damaged: variable {name!r} cannot be read "
                f"({_bad_chunks(group, str(name), ds.sizes.get('frame', 0))}): "
                f"{type(exc).__name__}: {exc}; expected complete, decodable chunk files "
                f"(a truncated or corrupted file?)") from exc
    return ds


def _bad_chunks(group, name: str, n: int) -> str:
    """Which frames of variable ``name`` fail to decode (error path only)."""
    try:
        arr = group[name]
        dims = tuple(getattr(arr.metadata, "dimension_names", None)
                     or arr.attrs.get("_ARRAY_DIMENSIONS", ()))
        if not dims or dims[0] != "frame":
            return "not a per-frame variable"
        bad = []
        for c in range(-(-n // arr.chunks[0])):
            try:
                arr[c * arr.chunks[0]:min((c + 1) * arr.chunks[0], n)]
            except Exception:
                bad.append(_frame_span(arr, c, n))
        return ", ".join(bad) if bad else "frame unknown"
    except Exception:
        return "frame unknown"


def open_store(path: str | Path, *, load: bool = True) -> xr.Dataset:
    """Open a Zarr frame store, restricted to its complete frames.

    A frame half-written by a running or interrupted append (arrays longer
    than ``frames_complete``) is left out; the store is never modified (only
    its writer repairs it, see :func:`repair_store`). The chunk files of the
    numeric variables must all be present for the complete frames: a deleted
    chunk would otherwise read back silently as the fill value.

    Parameters
    ----------
    load : bool
        Read everything into memory (else variables stay lazy, dask-backed,
        and a chunk that cannot be decoded fails only when it is computed).

    Raises
    ------
    ValueError
        If ``path`` is not a raysim Zarr store, or a chunk file is missing
        or cannot be decoded (truncated, corrupted); the message names the
        store, the variable and the frame.
    """
    if not store_exists(path):
        raise ValueError(f"{str(path)!r} is not a Zarr store (no zarr.json / .zgroup found)")
    path = Path(path)
    for attempt in range(OPEN_RETRIES):
        try:
            g = _open_group(path)
            n_done = int(g.attrs.get("frames_complete", -1))
            _check_chunks_present(path, g, n_done)
            ds = _open_complete(path, g, n_done, load)
            break
        except (json.JSONDecodeError, UnicodeDecodeError):
            if attempt == OPEN_RETRIES - 1:        # metadata caught mid-write by a writer
                raise ValueError(f"Zarr store {str(path)!r}: its metadata cannot be read "
                                 f"(being rewritten by a writer, or damaged); expected JSON "
                                 f"metadata") from None
            time.sleep(0.2)
    return _load_checked(path, ds, g) if load else ds


def strings_as_object(ds: xr.Dataset) -> xr.Dataset:
    """Labels read back as numpy ``StringDType`` / ``<U`` arrays turned into object arrays.

    Frame Datasets hold their string labels (``vector``, ``euler``,
    ``channel_label``) as object arrays; readers return them the same way.
    """
    strings = [k for k, v in ds.variables.items() if v.dtype.kind in "TU"]
    if not strings:
        return ds
    ds = ds.assign_coords({k: ds[k].astype(object) for k in strings if k in ds.coords})
    return ds.assign({k: ds[k].astype(object) for k in strings if k in ds.data_vars})


def _open_complete(path: Path, group, n_done: int, load: bool) -> xr.Dataset:
    """The store's first ``n_done`` frames, without writing to it.

    A writer appends one variable after the other, so while it works (or
    after it was killed) per-frame arrays can be longer than
    ``frames_complete``. Variables of equal length are opened together and cut
    to the complete frames, then merged.
    """
    # load: read through zarr directly (no dask graph); else lazy, dask-backed
    # times stay float seconds (decode_times=False): chirp_time is "seconds since <epoch>"
    kw = {"chunks": None, "decode_times": False} if load else {"decode_times": False}
    lengths = {name: int(a.shape[0]) for name, a in _frame_arrays(group)}
    if n_done < 0 or set(lengths.values()) <= {n_done}:
        ds = xr.open_zarr(str(path), consolidated=False, **kw)
    else:
        parts, coords = [], set()
        for size in sorted(set(lengths.values())):
            drop = [name for name, n in lengths.items() if n != size]
            part = xr.open_zarr(str(path), consolidated=False, drop_variables=drop, **kw)
            coords |= {c for c in part.coords if c not in part.indexes}
            parts.append(part.isel(frame=slice(0, n_done)).reset_coords())
        ds = xr.merge(parts, compat="override", join="outer", combine_attrs="override")
        ds = ds.set_coords(sorted(c for c in coords if c in ds.variables))
    ds = strings_as_object(ds)
    n = int(ds.attrs.get("frames_complete", ds.sizes.get("frame", 0)))
    if ds.sizes.get("frame", 0) != n:
        ds = ds.isel(frame=slice(0, n))
    return ds
