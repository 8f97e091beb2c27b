"""Frames on disk: xarray Datasets in Zarr stores (appendable, resumable) and NetCDF.

A real-sampled radar (``radar_complex_sampling`` False) stores ``if_data`` as float32.

Layout of a frame Dataset (axis names of docs/conventions.md; ``units`` are
UDUNITS strings, the attribute ``Conventions`` is ``CF-1.10``):

=====================  =================================  =========  ==========================
variable               dims                               dtype      units
=====================  =================================  =========  ==========================
``if_data``            ``frame, chirp, channel, sample``  complex64  V (sqrt(W) into 1 ohm)
``chirp_time``         ``frame, chirp``                   float64    seconds since <epoch>
``pose_position``      ``frame, chirp, vector``           float64    m (body origin in W, NED)
``pose_attitude``      ``frame, chirp, euler``            float64    rad (roll, pitch, yaw)
``frame``              ``frame``                          int64      1
``vector``             ``vector``                         str        ``x, y, z``
``euler``              ``euler``                          str        ``roll, pitch, yaw``
``sample``             ``sample``                         float64    s (fast time)
``fast_time``          ``sample``                         float64    s (same values as sample)
``tx_index``           ``channel``                        int64      1
``rx_index``           ``channel``                        int64      1
``channel_label``      ``channel``                        str        ``tx<i> rx<j>``
``tx_position``        ``channel, vector``                float64    m (frame A)
``rx_position``        ``channel, vector``                float64    m (frame A)
``tx_slot``            ``channel``                        int64      1
``imu_time``           ``imu_time``                       float64    s (IMU clock)
``imu_gyro``           ``imu_time, vector``               float64    rad s-1 (frame B)
``imu_accel``          ``imu_time, vector``               float64    m s-2 (frame B)
=====================  =================================  =========  ==========================

``vector`` is ``(x, y, z)``; ``euler`` is ``(roll, pitch, yaw)`` of the Z-Y-X
sequence. ``tx_index`` / ``rx_index`` number the distinct transmit / receive
phase centres in the order they first appear along ``channel``. The pose is
sampled at each chirp start (slot 0). The IMU log has its own time axis and is
optional. The frame layout has no range dimension: range bin ``k`` of the
range FFT along ``sample`` lies at ``k * radar_range_resolution_m``
(:func:`range_axis`). Radar parameters live in the attributes
(``radar_carrier_frequency_hz`` ...), with the lever arm, the array name and
grid, the scenario (JSON) and the software versions.

Time: the truth clock counts seconds since the attribute ``time_epoch_utc``
(ISO 8601, default the Unix epoch ``1970-01-01T00:00:00Z``, so a flight log
on Unix time aligns directly); ``chirp_time`` carries the CF units
``seconds since <epoch>``, so a plain ``xarray.open_zarr`` decodes it to
datetimes, while :func:`open_store` keeps float seconds.

Zarr stores (:mod:`raysim.io.zarr_store`, re-exported here) have consolidated
metadata, are chunked per frame and grow along ``frame``; stores written
before these attributes (``raysim_format`` 1) still open.
Files written whole (NetCDF exports) are written to a temporary name and
moved into place with :func:`os.replace`.

NetCDF has no complex type: ``if_data`` is exported as the float32 pair
``if_data_real`` / ``if_data_imag`` and recombined by :func:`read_netcdf`,
which gives back exactly (bit for bit) the Dataset that was exported.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import xarray as xr

from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig
from raysim.synthesis.frame import RadarFrame

__all__ = [
    "IF_DIMS", "FORMAT_VERSION", "radar_attrs", "config_from_attrs", "array_from_dataset",
    "frames_to_dataset", "dataset_to_frames", "frame_from_dataset", "imu_dataset",
    "write_store", "append_frames", "frames_complete", "repair_store", "open_store",
    "store_exists", "consolidate", "channel_indices", "range_axis", "CF_CONVENTIONS",
    "scenario_of", "export_netcdf", "read_netcdf", "netcdf_engine", "atomic_write",
    "atomic_write_bytes", "atomic_write_text",
]

#: Dimensions of the IF cube, in order.
IF_DIMS = ("frame", "chirp", "channel", "sample")
#: Version of this on-disk layout (attribute ``raysim_format``): 2 added consolidated
#: metadata, coordinate values, CF units and the time epoch.
FORMAT_VERSION = 2
#: CF version the attributes follow (global attribute ``Conventions``).
CF_CONVENTIONS = "CF-1.10"
#: Default epoch of the truth clock (attribute ``time_epoch_utc``).
DEFAULT_EPOCH = "1970-01-01T00:00:00Z"
#: Labels of the ``vector`` and ``euler`` axes.
VECTOR_LABELS = ("x", "y", "z")
EULER_LABELS = ("roll", "pitch", "yaw")

_RADAR_FIELDS = {  # RadarConfig field -> attribute suffix (unit in the name)
    "carrier_frequency": "carrier_frequency_hz", "bandwidth": "bandwidth_hz",
    "chirp_duration": "chirp_duration_s", "idle_time": "idle_time_s",
    "sample_rate": "sample_rate_hz", "num_chirps": "num_chirps",
    "num_frames": "num_frames", "complex_sampling": "complex_sampling",
    "tx_power_dbm": "tx_power_dbm", "antenna_gain_dbi": "antenna_gain_dbi",
    "noise_figure_db": "noise_figure_db", "frame_period": "frame_period_s",
    "num_tx_slots": "num_tx_slots", "element_pattern": "element_pattern",
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
        out[f"radar_{key}"] = v if isinstance(v, (int, str)) else float(v)
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
            elif field == "element_pattern":
                v = str(v)
            else:
                v = float(v)
            kw[field] = v
        elif field == "element_pattern":
            kw[field] = "constant"      # stores from before element patterns: constant gain
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
                      {"units": "rad s-1", "long_name": "gyroscope angular rate, body frame B"}),
         "imu_accel": (("imu_time", "vector"), np.asarray(accel, dtype=float),
                       {"units": "m s-2", "long_name": "accelerometer specific force, body "
                        "frame B"})},
        coords={"imu_time": ("imu_time", t, {"units": "s", "long_name": "IMU clock time"}),
                "vector": ("vector", _labels(VECTOR_LABELS), {"long_name": "vector component"})},
        attrs={"imu_source": str(source)})


def _labels(values) -> np.ndarray:
    """String labels as an object array (stored as Zarr's variable-length ``string`` type)."""
    return np.array(list(values), dtype=object)


def channel_indices(positions: np.ndarray) -> np.ndarray:
    """Index of each channel's phase centre among the distinct ones, shape ``[channel]``.

    Distinct positions are numbered 0, 1, ... in the order they first appear.

    Parameters
    ----------
    positions : ndarray, shape ``[channel, 3]``
        Transmit (or receive) phase centres [m].
    """
    pos = np.asarray(positions, dtype=float).reshape(-1, 3)
    _, first, inverse = np.unique(pos, axis=0, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first)] = np.arange(len(first))
    return rank[np.asarray(inverse).ravel()]


def range_axis(ds: xr.Dataset, num_bins: int | None = None) -> xr.DataArray:
    """Range [m] of the range-FFT bins of a frame Dataset's ``sample`` axis.

    Parameters
    ----------
    ds : xarray.Dataset
        Frame Dataset (its radar attributes).
    num_bins : int, optional
        Number of range bins (default: the samples per chirp for complex
        sampling, half of them for real sampling).

    Returns
    -------
    xarray.DataArray, shape ``[range]``
        Coordinate ``range`` [m] (units ``m``).
    """
    cfg = config_from_attrs(ds.attrs)
    n = int(num_bins) if num_bins is not None else (
        cfg.num_samples if cfg.complex_sampling else cfg.num_samples // 2)
    r = np.arange(n) * cfg.range_resolution
    return xr.DataArray(r, dims=("range",), coords={"range": ("range", r)},
                        attrs={"units": "m", "long_name": "range of the range-FFT bin"})


def frames_to_dataset(frames: Sequence[RadarFrame], trajectory=None, *, imu: xr.Dataset | None
                      = None, attrs: dict | None = None,
                      epoch: str | None = None) -> xr.Dataset:
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
    epoch : str, optional
        ISO 8601 UTC instant at which the truth clock reads 0 s (attribute
        ``time_epoch_utc``, units of ``chirp_time``); default ``attrs
        ["time_epoch_utc"]`` if given, else :data:`DEFAULT_EPOCH`.

    Returns
    -------
    xarray.Dataset
        ``if_data`` of shape ``[frame, chirp, channel, sample]``, complex64 (float32
        for a real-sampled radar).

    Raises
    ------
    ValueError
        For no frames, frames of different shapes or an epoch that is not an
        ISO 8601 instant.
    """
    frames = list(frames)
    if not frames:
        raise ValueError("frames is empty: give at least one RadarFrame")
    epoch = _check_epoch(epoch or (attrs or {}).get("time_epoch_utc") or DEFAULT_EPOCH)
    cfg, arr = frames[0].config, frames[0].array
    for fr in frames[1:]:
        if fr.data.shape != frames[0].data.shape:
            raise ValueError(f"frame {fr.frame_index} has shape {fr.data.shape}, expected "
                             f"{frames[0].data.shape}")
    # complex64 IQ samples, or float32 from a real-sampled ADC (complex_sampling False)
    dtype = np.complex64 if frames[0].config.complex_sampling else np.float32
    data = np.stack([np.asarray(fr.data, dtype=dtype) for fr in frames])
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
    tx_i, rx_i = channel_indices(arr.tx_positions), channel_indices(arr.rx_positions)
    fast = cfg.fast_time()
    ds = xr.Dataset(
        {
            "if_data": (IF_DIMS, data, {
                "units": "V", "long_name": "dechirped complex IF samples s_tx conj(s_rx)",
                "comment": "amplitude in sqrt(W), i.e. volts into a 1 ohm load: |if_data|^2 "
                           "is the power in W"}),
            "pose_position": (("frame", "chirp", "vector"), position,
                              {"units": "m", "long_name": "truth body-origin position in W (NED) "
                               "at chirp start", "components": "x y z"}),
            "pose_attitude": (("frame", "chirp", "euler"), attitude,
                              {"units": "rad", "long_name": "truth attitude R_WB, Euler Z-Y-X, "
                               "at chirp start", "components": "roll pitch yaw"}),
        },
        coords={
            "frame": ("frame", np.array([fr.frame_index for fr in frames], dtype=np.int64),
                      {"units": "1", "long_name": "frame index"}),
            "vector": ("vector", _labels(VECTOR_LABELS), {"long_name": "vector component"}),
            "euler": ("euler", _labels(EULER_LABELS),
                      {"long_name": "Euler angle of the Z-Y-X sequence"}),
            "sample": ("sample", fast, {"units": "s", "standard_name": "time",
                                        "long_name": "fast time: sample time within the chirp"}),
            "chirp_time": (("frame", "chirp"), times, {
                "units": f"seconds since {epoch}", "calendar": "proleptic_gregorian",
                "standard_name": "time", "long_name": "chirp start time, truth clock"}),
            "fast_time": ("sample", fast, {"units": "s",
                                           "long_name": "sample time within chirp"}),
            "tx_index": ("channel", tx_i, {"units": "1", "long_name": "transmit element index"}),
            "rx_index": ("channel", rx_i, {"units": "1", "long_name": "receive element index"}),
            "channel_label": ("channel", _labels(f"tx{t} rx{r}" for t, r in zip(
                tx_i, rx_i, strict=True)), {"long_name": "virtual channel"}),
            "tx_position": (("channel", "vector"), arr.tx_positions,
                            {"units": "m", "long_name": "transmit phase centre in A"}),
            "rx_position": (("channel", "vector"), arr.rx_positions,
                            {"units": "m", "long_name": "receive phase centre in A"}),
            "tx_slot": ("channel", arr.tx_slot.astype(np.int64),
                        {"units": "1", "long_name": "TDM transmit slot"}),
        },
        attrs={
            "Conventions": CF_CONVENTIONS,
            "title": "raysim FMCW radar frames",
            "source": "raysim ray-traced FMCW MIMO radar simulation",
            "raysim_format": FORMAT_VERSION,
            "raysim_conventions": "raysim docs/conventions.md (raysim/data/conventions.md in "
                                  "the package): NED world, FRD body, boresight +Z_A",
            "time_epoch_utc": epoch,
            "channel_order": ("x index major, y index minor" if arr.num_slots == 1
                              else "tx major, rx minor"),
            "array_name": arr.name,
            "lever_arm_m": lever.tolist(),
            "radar_range_resolution_m": float(cfg.range_resolution),
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
    ds.attrs["time_epoch_utc"] = epoch
    return ds


def _check_epoch(epoch) -> str:
    """``epoch`` as given when it is an ISO 8601 UTC instant (``...Z`` or without zone)."""
    from datetime import datetime

    text = str(epoch).strip()
    try:
        when = datetime.fromisoformat(text.replace("Z", "+00:00"))
    except ValueError:
        raise ValueError(f"time epoch {epoch!r}: expected an ISO 8601 UTC instant such as "
                         f"{DEFAULT_EPOCH!r}") from None
    if when.utcoffset() not in (None,) and when.utcoffset().total_seconds() != 0:
        raise ValueError(f"time epoch {epoch!r}: expected UTC (suffix Z), got offset "
                         f"{when.utcoffset()}")
    return text


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
# the Zarr store functions live in raysim.io.zarr_store; re-exported here
from raysim.io.zarr_store import (  # noqa: E402,F401
    MAX_CHUNK_BYTES,
    OPEN_RETRIES,
    append_frames,
    consolidate,
    frames_complete,
    open_store,
    repair_store,
    store_exists,
    strings_as_object,
    write_store,
)


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
    with xr.open_dataset(path, engine=_netcdf_engine(), decode_times=False) as f:
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
    ds = strings_as_object(ds)
    for name in ds.variables:
        ds[name].encoding = {}
    return ds


def scenario_of(ds: xr.Dataset):
    """The :class:`~raysim.scenario.Scenario` stored in a dataset's attributes, or None."""
    text = ds.attrs.get("scenario_json")
    if not text:
        return None
    from raysim.scenario import validate_scenario

    return validate_scenario(json.loads(text), source="stored scenario")
