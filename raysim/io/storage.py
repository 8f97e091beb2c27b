"""Frames on disk: xarray Datasets in Zarr stores (appendable, resumable) and NetCDF.

Layout of a frame Dataset (axis names of docs/conventions.md):

=====================  ==============================  =========  =======================
variable               dims                            dtype      unit
=====================  ==============================  =========  =======================
``if_data``            ``frame, chirp, channel, sample``  complex64  sqrt(W)
``chirp_time``         ``frame, chirp``                float64    s (truth clock)
``pose_position``      ``frame, chirp, vector``        float64    m (body origin in W, NED)
``pose_attitude``      ``frame, chirp, euler``         float64    rad (roll, pitch, yaw)
``fast_time``          ``sample``                      float64    s
``tx_position``        ``channel, vector``             float64    m (frame A)
``rx_position``        ``channel, vector``             float64    m (frame A)
``tx_slot``            ``channel``                     int64      1
``imu_time``           ``imu_time``                    float64    s (IMU clock)
``imu_gyro``           ``imu_time, vector``            float64    rad/s (frame B)
``imu_accel``          ``imu_time, vector``            float64    m/s^2 (frame B)
=====================  ==============================  =========  =======================

``vector`` is ``(x, y, z)``; ``euler`` is ``(roll, pitch, yaw)`` of the Z-Y-X
sequence. The pose is sampled at each chirp start (slot 0). The IMU log has its
own time axis and is optional. Radar parameters live in the attributes
(``radar_carrier_frequency_hz`` ...), with the lever arm, the array name and
grid, the scenario (JSON) and the software versions.

Zarr stores are chunked per frame (one or a few chunks per frame, never a chunk
spanning two frames) and grow along ``frame``. The attribute
``frames_complete`` is updated only after a frame's arrays are fully written;
:func:`open_store` and :func:`repair_store` ignore / cut anything beyond it,
so an interrupted render keeps its finished frames and resumes at the next.
Every chunk is written, even one equal to the fill value, so a chunk file
that is missing from a store means damage: :func:`open_store` checks that the
chunks of the floating-point variables (``if_data``, the pose, the axes) are
all present for the complete frames and raises :class:`ValueError` naming the
store, the variable and the frame otherwise; a chunk that cannot be decoded
(truncated or corrupted file) is reported the same way.
Files written whole (NetCDF exports) are written to a temporary name and
moved into place with :func:`os.replace`.

NetCDF has no complex type: ``if_data`` is exported as the float32 pair
``if_data_real`` / ``if_data_imag`` and recombined by :func:`read_netcdf`,
which gives back exactly (bit for bit) the Dataset that was exported.
"""

from __future__ import annotations

import functools
import itertools
import json
import os
import shutil
import time
import uuid
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from raysim.io.store_guard import check_replaceable, remove_store
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig
from raysim.synthesis.frame import RadarFrame

__all__ = [
    "IF_DIMS", "FORMAT_VERSION", "radar_attrs", "config_from_attrs", "array_from_dataset",
    "frames_to_dataset", "dataset_to_frames", "frame_from_dataset", "imu_dataset",
    "write_store", "append_frames", "frames_complete", "repair_store", "open_store",
    "store_exists", "scenario_of", "export_netcdf", "read_netcdf", "netcdf_engine", "atomic_write",
    "atomic_write_bytes", "atomic_write_text",
]

#: Dimensions of the IF cube, in order.
IF_DIMS = ("frame", "chirp", "channel", "sample")
#: Version of this on-disk layout (attribute ``raysim_format``).
FORMAT_VERSION = 1
#: Upper bound of one Zarr chunk of ``if_data`` [bytes]; a frame is split along chirp.
MAX_CHUNK_BYTES = 32 * 2**20

_RADAR_FIELDS = {  # RadarConfig field -> attribute suffix (unit in the name)
    "carrier_frequency": "carrier_frequency_hz", "bandwidth": "bandwidth_hz",
    "chirp_duration": "chirp_duration_s", "idle_time": "idle_time_s",
    "sample_rate": "sample_rate_hz", "num_chirps": "num_chirps",
    "num_frames": "num_frames", "complex_sampling": "complex_sampling",
    "tx_power_dbm": "tx_power_dbm", "antenna_gain_dbi": "antenna_gain_dbi",
    "noise_figure_db": "noise_figure_db", "frame_period": "frame_period_s",
    "num_tx_slots": "num_tx_slots",
}


# ------------------------------------------------------------------- atomic io
# re-exported: stores, exports and readers use the shared atomic writers
from raysim.io.files import atomic_write, atomic_write_bytes, atomic_write_text  # noqa: E402,F401


# ------------------------------------------------------------------ attributes
def radar_attrs(config: RadarConfig) -> dict:
    """NetCDF-safe attributes ``radar_<field>_<unit>`` of a :class:`RadarConfig`.

    Booleans are stored as 0/1 integers and a ``None`` frame period is left out,
    so the same attributes survive Zarr and NetCDF unchanged.
    """
    out = {}
    for field, key in _RADAR_FIELDS.items():
        v = getattr(config, field)
        if v is None:
            continue
        if isinstance(v, bool):
            v = int(v)
        out[f"radar_{key}"] = v if isinstance(v, int) else float(v)
    return out


def config_from_attrs(attrs: dict) -> RadarConfig:
    """Rebuild the :class:`RadarConfig` from :func:`radar_attrs` attributes."""
    kw = {}
    for field, key in _RADAR_FIELDS.items():
        name = f"radar_{key}"
        if name in attrs:
            v = attrs[name]
            if field in ("num_chirps", "num_frames", "num_tx_slots"):
                v = int(v)
            elif field == "complex_sampling":
                v = bool(int(v))
            else:
                v = float(v)
            kw[field] = v
        elif field != "frame_period":
            raise ValueError(f"dataset attribute {name!r} is missing: not a raysim frame store")
    return RadarConfig(**kw)


def array_from_dataset(ds: xr.Dataset) -> VirtualArray:
    """Rebuild the :class:`VirtualArray` from ``tx_position``, ``rx_position``, ``tx_slot``."""
    grid = ds.attrs.get("array_grid_shape")
    grid = None if grid is None or len(np.atleast_1d(grid)) != 2 else tuple(
        int(g) for g in np.atleast_1d(grid))
    return VirtualArray(np.asarray(ds["tx_position"].values), np.asarray(ds["rx_position"].values),
                        np.asarray(ds["tx_slot"].values), grid,
                        name=str(ds.attrs.get("array_name", "array")))


def _versions() -> dict:
    from importlib import metadata

    out = {}
    for dist in ("raysim", "numpy", "xarray", "zarr"):
        try:
            out[f"version_{dist}"] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            pass
    return out


# -------------------------------------------------------------------- datasets
def imu_dataset(time: np.ndarray, gyro: np.ndarray, accel: np.ndarray,
                source: str = "") -> xr.Dataset:
    """IMU log variables with their own ``imu_time`` dimension.

    Parameters
    ----------
    time : ndarray, shape ``[imu_time]``
        Time stamps on the IMU clock [s].
    gyro : ndarray, shape ``[imu_time, 3]``
        Angular rate in B [rad/s].
    accel : ndarray, shape ``[imu_time, 3]``
        Specific force in B [m/s^2].
    """
    t = np.asarray(time, dtype=float)
    return xr.Dataset(
        {"imu_gyro": (("imu_time", "vector"), np.asarray(gyro, dtype=float),
                      {"units": "rad/s", "long_name": "gyroscope angular rate, body frame B"}),
         "imu_accel": (("imu_time", "vector"), np.asarray(accel, dtype=float),
                       {"units": "m/s^2", "long_name": "accelerometer specific force, body "
                        "frame B"})},
        coords={"imu_time": ("imu_time", t, {"units": "s", "long_name": "IMU clock time"})},
        attrs={"imu_source": str(source)})


def frames_to_dataset(frames: Sequence[RadarFrame], trajectory=None, *, imu: xr.Dataset | None
                      = None, attrs: dict | None = None) -> xr.Dataset:
    """Stack frames (and truth pose, IMU log) into one Dataset.

    Parameters
    ----------
    frames : sequence of RadarFrame
        Same config and array; ``data`` of shape ``[chirp, channel, sample]``.
    trajectory : raysim.platform.motion.Trajectory, optional
        Truth motion; its pose at each chirp start fills ``pose_position``
        ``[frame, chirp, vector]`` [m] and ``pose_attitude`` ``[frame, chirp, euler]``
        [rad]. Zeros (nominal pose) if omitted.
    imu : xarray.Dataset, optional
        From :func:`imu_dataset`.
    attrs : dict, optional
        Extra NetCDF-safe attributes (str, int, float, 1-D numeric lists).

    Returns
    -------
    xarray.Dataset
        ``if_data`` of shape ``[frame, chirp, channel, sample]``, complex64.
    """
    frames = list(frames)
    if not frames:
        raise ValueError("frames is empty: give at least one RadarFrame")
    cfg, arr = frames[0].config, frames[0].array
    for fr in frames[1:]:
        if fr.data.shape != frames[0].data.shape:
            raise ValueError(f"frame {fr.frame_index} has shape {fr.data.shape}, expected "
                             f"{frames[0].data.shape}")
    data = np.stack([np.asarray(fr.data, dtype=np.complex64) for fr in frames])
    times = np.stack([np.asarray(fr.chirp_times, dtype=float) for fr in frames])
    if trajectory is not None:
        pos, rot = trajectory.pose(times.ravel())
        ypr = rot.as_euler("ZYX")
        position = pos.reshape(times.shape + (3,))
        attitude = ypr[:, ::-1].reshape(times.shape + (3,))
    else:
        position = np.zeros(times.shape + (3,))
        attitude = np.zeros(times.shape + (3,))
    lever = np.asarray(frames[0].lever_arm, dtype=float)
    ds = xr.Dataset(
        {
            "if_data": (IF_DIMS, data, {"units": "sqrt(W)", "long_name": "dechirped complex IF "
                                        "samples s_tx conj(s_rx)"}),
            "pose_position": (("frame", "chirp", "vector"), position,
                              {"units": "m", "long_name": "truth body-origin position in W (NED) "
                               "at chirp start", "components": "x y z"}),
            "pose_attitude": (("frame", "chirp", "euler"), attitude,
                              {"units": "rad", "long_name": "truth attitude R_WB, Euler Z-Y-X, "
                               "at chirp start", "components": "roll pitch yaw"}),
        },
        coords={
            "frame": ("frame", np.array([fr.frame_index for fr in frames], dtype=np.int64),
                      {"long_name": "frame index"}),
            "chirp_time": (("frame", "chirp"), times, {"units": "s",
                                                       "long_name": "chirp start time"}),
            "fast_time": ("sample", cfg.fast_time(), {"units": "s",
                                                      "long_name": "sample time within chirp"}),
            "tx_position": (("channel", "vector"), arr.tx_positions,
                            {"units": "m", "long_name": "transmit phase centre in A"}),
            "rx_position": (("channel", "vector"), arr.rx_positions,
                            {"units": "m", "long_name": "receive phase centre in A"}),
            "tx_slot": ("channel", arr.tx_slot.astype(np.int64),
                        {"long_name": "TDM transmit slot"}),
        },
        attrs={
            "raysim_format": FORMAT_VERSION,
            "conventions": "raysim docs/conventions.md: NED world, FRD body, boresight +Z_A",
            "channel_order": ("x index major, y index minor" if arr.num_slots == 1
                              else "tx major, rx minor"),
            "array_name": arr.name,
            "lever_arm_m": lever.tolist(),
            **radar_attrs(cfg), **_versions(),
        },
    )
    if arr.grid_shape:
        ds.attrs["array_grid_shape"] = list(arr.grid_shape)
    if imu is not None:
        imu_attrs = dict(imu.attrs)
        ds = xr.merge([ds, imu], combine_attrs="override")
        ds.attrs.update(imu_attrs)
    if attrs:
        ds.attrs.update(attrs)
    return ds


def frame_from_dataset(ds: xr.Dataset, index: int = 0) -> RadarFrame:
    """The :class:`RadarFrame` at position ``index`` along ``frame``."""
    cfg = config_from_attrs(ds.attrs)
    arr = array_from_dataset(ds)
    sub = ds.isel(frame=index)
    return RadarFrame(np.asarray(sub["if_data"].values), cfg, arr,
                      np.asarray(sub["chirp_time"].values),
                      np.asarray(ds.attrs.get("lever_arm_m", [0, 0, 0]), dtype=float),
                      int(sub["frame"].values), {"source": "dataset"})


def dataset_to_frames(ds: xr.Dataset) -> list[RadarFrame]:
    """All frames of a Dataset as :class:`RadarFrame` objects."""
    return [frame_from_dataset(ds, i) for i in range(ds.sizes["frame"])]


# ------------------------------------------------------------------------ zarr
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
    """Create a Zarr store from ``ds`` atomically (written aside, then renamed).

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
    import zarr

    if not store_exists(path):
        return 0
    g = zarr.open_group(str(path), mode="r")
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
    import zarr

    g = zarr.open_group(str(path), mode="r+")
    n = int(g.attrs.get("frames_complete", 0))
    for _, arr in _frame_arrays(g):
        if arr.shape[0] != n:
            arr.resize((n,) + tuple(arr.shape[1:]))
    return n


def append_frames(path: str | Path, ds: xr.Dataset) -> int:
    """Append the frames of ``ds`` to an existing store, then mark them complete.

    Only variables with a ``frame`` dimension are appended; the others (array
    geometry, IMU log) were written when the store was created.

    Returns
    -------
    int
        Frames complete after the append.
    """
    import zarr

    n = repair_store(path)
    g = zarr.open_group(str(path), mode="r")
    attrs = dict(g.attrs)
    keep = [v for v in ds.variables if "frame" in ds[v].dims]
    part = ds[[v for v in keep if v in ds.data_vars]]
    part = part.drop_vars([c for c in part.coords if "frame" not in part[c].dims])
    part.attrs = attrs  # xarray rewrites the group attributes: keep them (frames_complete = n)
    part.to_zarr(str(path), append_dim="frame", consolidated=False, write_empty_chunks=True)
    n += int(ds.sizes["frame"])
    g = zarr.open_group(str(path), mode="r+")
    attrs["frames_complete"] = n
    g.attrs.update(attrs)
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
    import zarr

    if not store_exists(path):
        raise ValueError(f"{str(path)!r} is not a Zarr store (no zarr.json / .zgroup found)")
    path = Path(path)
    for attempt in range(OPEN_RETRIES):
        try:
            g = zarr.open_group(str(path), mode="r")
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


#: Attempts to read a store's metadata while a writer may be rewriting it.
OPEN_RETRIES = 5


def _open_complete(path: Path, group, n_done: int, load: bool) -> xr.Dataset:
    """The store's first ``n_done`` frames, without writing to it.

    A writer appends one variable after the other, so while it works (or
    after it was killed) per-frame arrays can be longer than
    ``frames_complete``. Variables of equal length are opened together and cut
    to the complete frames, then merged.
    """
    # load: read through zarr directly (no dask graph); else lazy, dask-backed
    kw = {"chunks": None} if load else {}
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
    n = int(ds.attrs.get("frames_complete", ds.sizes.get("frame", 0)))
    if ds.sizes.get("frame", 0) != n:
        ds = ds.isel(frame=slice(0, n))
    return ds


# ---------------------------------------------------------------------- netcdf
@functools.cache
def netcdf_engine() -> str | None:
    """xarray engine for NetCDF-4 files: ``"netcdf4"`` when the netCDF4 library imports.

    ``"h5netcdf"`` (with h5py) is the fallback; None when neither imports.
    netCDF4 is a dependency of raysim, so the fallback only serves stripped
    installations.
    """
    import importlib

    for module, engine in (("netCDF4", "netcdf4"), ("h5netcdf", "h5netcdf")):
        try:
            importlib.import_module(module)
        except Exception:  # ImportError, or a broken shared library (OSError)
            continue
        return engine
    return None


def _netcdf_engine() -> str:
    engine = netcdf_engine()
    if engine is None:
        raise FeatureUnavailableError("NetCDF export needs the netCDF4 package (a raysim "
                                      "dependency) or h5netcdf with h5py; neither imports")
    return engine


class FeatureUnavailableError(RuntimeError):
    """No NetCDF library is installed."""


def export_netcdf(ds: xr.Dataset, path: str | Path) -> None:
    """Write ``ds`` to a NetCDF-4 file (netCDF4 or h5netcdf engine), atomically.

    ``if_data`` (complex64) becomes ``if_data_real`` and ``if_data_imag``
    (float32, exact); every other variable is written as is.
    """
    path = Path(path)
    out = ds.copy()
    for name in list(out.data_vars):
        var = out[name]
        if var.dtype.kind == "c":
            part_dtype = np.float32 if var.dtype == np.complex64 else np.float64
            re_ = var.copy(data=np.ascontiguousarray(var.values.real, dtype=part_dtype))
            im_ = var.copy(data=np.ascontiguousarray(var.values.imag, dtype=part_dtype))
            re_.attrs["complex_part"] = "real"
            im_.attrs["complex_part"] = "imag"
            out = out.drop_vars(name).assign({f"{name}_real": re_, f"{name}_imag": im_})
    for name in out.variables:
        out[name].encoding = {}
    encoding = {name: {"_FillValue": None} for name in out.variables
                if out[name].dtype.kind in "fc"}
    atomic_write(path, lambda tmp: out.to_netcdf(tmp, engine=_netcdf_engine(), format="NETCDF4",
                                                 encoding=encoding))


def read_netcdf(path: str | Path) -> xr.Dataset:
    """Read a file written by :func:`export_netcdf` (complex variables recombined)."""
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"NetCDF file {str(path)!r} does not exist")
    with xr.open_dataset(path, engine=_netcdf_engine()) as f:
        ds = f.load()
    for name in list(ds.data_vars):
        if name.endswith("_real") and ds[name].attrs.get("complex_part") == "real":
            base = name[:-5]
            re_, im_ = ds[name], ds[f"{base}_imag"]
            cdtype = np.complex64 if re_.dtype == np.float32 else np.complex128
            data = np.empty(re_.shape, dtype=cdtype)
            data.real, data.imag = re_.values, im_.values
            attrs = {k: v for k, v in re_.attrs.items() if k != "complex_part"}
            ds = ds.drop_vars([name, f"{base}_imag"]).assign(
                {base: (re_.dims, data, attrs)})
    for name in ds.variables:
        ds[name].encoding = {}
    return ds


def scenario_of(ds: xr.Dataset):
    """The :class:`~raysim.io.scenario.Scenario` stored in a dataset's attributes, or None."""
    text = ds.attrs.get("scenario_json")
    if not text:
        return None
    from raysim.io.scenario import validate_scenario

    return validate_scenario(json.loads(text), source="stored scenario")
