"""Input and output of the compensate stage: cubes, captures and the compensated store.

The readers and writers of :func:`raysim.pipeline.compensate.compensate` (and
so of ``raysim compensate``). Inputs, all turned into one
:class:`CompensateInput`:

* a frame store (Zarr, or NetCDF ``.nc``) of :mod:`raysim.io.storage`;
* an ``.npz`` cube (keys in :mod:`raysim.pipeline.compensate`);
* a DCA1000 capture (``.bin``, :mod:`raysim.io.ti_dca1000`) with its radar
  configuration (mmWave SDK ``.cfg`` or mmWave Studio ``.json``,
  :mod:`raysim.io.mmwave_config`), which sets the waveform, the TDM slot order
  of the virtual array and the binary layout.

Output: a labelled Zarr store (:func:`write_compensated_store`), or for one
frame the ``.npz`` of earlier versions (:func:`write_compensated_npz`);
:func:`check_compensated_output` refuses, before any computation, a path that
holds something else.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field

import numpy as np

from raysim.io.files import atomic_write, check_output
from raysim.platform.kinematics import slot_times
from raysim.radar.config import RadarConfig
from raysim.resources import check_memory
from raysim.vocabulary import AXIS_UNITS

__all__ = ["CompensateInput", "load_input", "frame_selection", "write_compensated_store",
           "write_compensated_npz", "check_compensated_output", "COMPENSATED_FORMAT",
           "COMPENSATED_FORMAT_ATTR"]

#: Format version of the compensated store (attribute :data:`COMPENSATED_FORMAT_ATTR`).
COMPENSATED_FORMAT = 1
#: Group attribute that marks a store written by :func:`write_compensated_store`.
COMPENSATED_FORMAT_ATTR = "raysim_compensated"
#: Bytes per element of MATLAB's numeric classes (``scipy.io.whosmat``).
MAT_CLASS_BYTES = {"double": 8, "single": 4, "int8": 1, "uint8": 1, "int16": 2, "uint16": 2,
                   "int32": 4, "uint32": 4, "int64": 8, "uint64": 8}
_NPZ_NEED = ("data", "chirp_times", "element_positions", "carrier_frequency", "bandwidth",
             "chirp_duration", "sample_rate")


@dataclass(frozen=True, eq=False)
class CompensateInput:
    """What the compensate stage needs of its input, whatever the file.

    Attributes
    ----------
    frames : list of int
        Frame numbers within the source (capture or store) of the selected frames.
    read : callable
        ``read(k) -> array [chirp, channel, sample]`` IF samples of the
        ``k``-th selected frame (read when needed: captures are not loaded whole;
        a store's frame is a lazy array whose ``shape`` is known and whose chirp
        blocks load when sliced and passed to ``np.asarray``).
    slot_times : ndarray, shape ``[frame, chirp, slot]``
        Start time of every transmit slot's ramp on the radar clock [s].
    config : RadarConfig
        Waveform and sampling (range axis, wavelength).
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual positions in A [m].
    tx_slot : ndarray of int, shape ``[channel]``
        TDM slot of each channel.
    grid_shape : tuple of int or None
    lever_arm : ndarray, shape ``[3]``, or None
        ``r_IR`` in B [m] if the source knows it.
    imu : ndarray, shape ``[sample, 7]``, or None
        IMU log held by a store: time, gyro, accel.
    mounting_deg : tuple of float or None
        Radar mounting ``R_BA`` (yaw, pitch, roll) [deg] a rendered store was
        simulated with (its ``mounting_deg`` attribute); None: not known (down).
    units : str
        Unit of the samples (``"V"`` for simulated stores, ``"ADC counts"``).
    source : dict
        Provenance written to the output's attributes.
    """

    frames: list
    read: object
    slot_times: np.ndarray
    config: RadarConfig
    element_positions: np.ndarray
    tx_slot: np.ndarray
    grid_shape: tuple | None = None
    lever_arm: np.ndarray | None = None
    imu: np.ndarray | None = None
    units: str = "V"
    source: dict = field(default_factory=dict)
    mounting_deg: tuple | None = None

    @property
    def num_slots(self) -> int:
        """TDM transmit slots per chirp loop."""
        return int(self.slot_times.shape[-1])


def frame_selection(text: str | None, total: int, option: str = "--frames") -> list[int]:
    """Frames ``LO:HI`` (HI excluded, either may be left out) or one ``K`` of ``total``.

    Raises
    ------
    ValueError
        Naming ``option``, the value and the frames available.
    """
    if text is None:
        return list(range(total))
    try:
        if ":" in text:
            lo_s, hi_s = text.split(":", 1)
            lo = int(lo_s) if lo_s.strip() else 0
            hi = int(hi_s) if hi_s.strip() else total
        else:
            lo = int(text)
            hi = lo + 1
    except ValueError:
        raise ValueError(f"{option}: got {text!r}, expected LO:HI or K (frame numbers)") \
            from None
    if not 0 <= lo < hi <= total:
        raise ValueError(f"{option}: got {text!r}, expected frames within 0:{total} (the input "
                         f"holds {total} frame(s))")
    return list(range(lo, hi))


#: Suffixes of file formats an output path may not carry: the output is a Zarr folder
#: or an .npz file, never what these promise.
OTHER_FORMAT_SUFFIXES = frozenset({".nc", ".h5", ".hdf5", ".mat", ".npy", ".txt", ".csv",
                                   ".json", ".toml", ".cfg", ".bin", ".ulg", ".bag", ".mcap",
                                   ".zip", ".png", ".pdf"})


def _check_file(path: str, what: str) -> None:
    """A ValueError naming ``what`` unless ``path`` is a file: absent, or a folder."""
    if os.path.isdir(path):
        raise ValueError(f"{what} {path!r} is a folder; expected a file")
    if not os.path.isfile(path):
        raise ValueError(f"{what} {path!r} does not exist")


def _load_capture(path: str, radar_config: str, frames: str | None, layout: str | None,
                  t0: float, board: str | None = None, antenna_positions=None,
                  drop_incomplete: bool = False) -> CompensateInput:
    from raysim.io.mmwave_config import read_mmwave_config
    from raysim.io.ti_dca1000 import check_capture_fits, read_dca1000

    if radar_config is None:
        raise ValueError(f"{path!r} is a raw capture: give its radar configuration with "
                         f"--radar-config FILE (mmWave SDK .cfg or mmWave Studio .json)")
    _check_file(path, "capture")
    if not np.isfinite(t0):
        raise ValueError(f"--capture-t0 must be a finite time in seconds, got {t0!r}")
    if antenna_positions is not None:
        _check_file(os.fspath(antenna_positions), "--antenna-positions")
    m = read_mmwave_config(radar_config, layout=layout, t0=t0, board=board,
                           antenna_positions=antenna_positions)
    fmt = m.fmt
    try:
        total = check_capture_fits(path, fmt, m.num_frames, drop_incomplete)
    except ValueError as exc:
        raise ValueError(f"{exc} (--radar-config {radar_config!r})") from None
    dropped = os.path.getsize(path) - total * fmt.bytes_per_frame      # --drop-incomplete
    sel = frame_selection(frames, total)
    sign = (None if m.channel_sign is None or np.all(m.channel_sign == 1)
            else m.channel_sign.astype(np.float32)[:, None])

    def read(k: int) -> np.ndarray:
        f = sel[k]
        cube = read_dca1000(path, fmt, frames=slice(f, f + 1),
                            drop_incomplete=drop_incomplete).cube[0]
        return cube if sign is None else cube * sign    # the board's RX feed signs

    times = np.concatenate([fmt.chirp_times(1, f) for f in sel])
    return CompensateInput(sel, read, times, m.config, m.array.virtual_positions,
                           m.array.tx_slot, m.array.grid_shape, units="ADC counts",
                           source={"capture": os.path.abspath(path),
                                   "radar_config": os.path.abspath(radar_config),
                                   "tx_order": list(m.tx_order), "layout": fmt.layout,
                                   "board": m.board, "dropped_bytes": dropped})


def _load_store(path: str, frames: str | None, frame: int) -> CompensateInput:
    from raysim.io import storage

    if path.endswith(".nc") and not os.path.isdir(path):
        ds = storage.read_netcdf(path)
    else:
        ds = storage.open_store(path)
    n = int(ds.sizes.get("frame", 0))
    if frames is None:
        if not -n <= frame < n:
            raise ValueError(f"--frame {frame} is outside the store {path!r}, which holds {n} "
                             f"frame(s)")
        sel = [frame % n]
    else:
        sel = frame_selection(frames, n)
    # One frame's samples in memory at a time: metadata now, each frame's IF data when read.
    cfg = storage.config_from_attrs(ds.attrs)
    arr = storage.array_from_dataset(ds)
    if not np.issubdtype(ds["if_data"].dtype, np.complexfloating):
        raise ValueError(f"store {path!r}: if_data must be complex IF samples, got "
                         f"{ds['if_data'].dtype}")
    times = np.stack([np.asarray(ds["chirp_time"].isel(frame=f).values, dtype=float)
                      for f in sel])
    imu = None
    if all(k in ds.variables for k in ("imu_time", "imu_gyro", "imu_accel")):
        imu = np.column_stack([np.asarray(ds["imu_time"].values, dtype=float),
                               np.asarray(ds["imu_gyro"].values, dtype=float),
                               np.asarray(ds["imu_accel"].values, dtype=float)])
    lever = np.asarray(ds.attrs.get("lever_arm_m", [0, 0, 0]), dtype=float)
    # read(k) stays lazy (shape known, samples loaded by the chirp blocks a caller takes)
    return CompensateInput(sel, lambda k: ds["if_data"].isel(frame=sel[k]),
                           slot_times(times, arr.num_slots, cfg.slot_interval),
                           cfg, arr.virtual_positions, arr.tx_slot, arr.grid_shape,
                           lever, imu, source={"store": os.path.abspath(path)},
                           mounting_deg=(tuple(float(v) for v in ds.attrs["mounting_deg"])
                                         if "mounting_deg" in ds.attrs else None))


def _mat_keys(path: str) -> dict:
    """The variables of a MATLAB ``.mat`` file (v4 to v7): MATLAB's ``1 x n`` vectors and
    ``1 x 1`` scalars as numpy's ``[n]`` and ``()``; ``data`` and ``element_positions``
    keep their axes (a single channel stays an axis)."""
    from scipy.io import loadmat, matlab

    try:
        raw = loadmat(path, squeeze_me=False)
    except NotImplementedError:           # scipy reads up to v7; v7.3 is HDF5
        raise ValueError(f"cube file {path!r} is a MATLAB v7.3 (HDF5) file; save it with "
                         f"save(..., '-v7') or as .npz") from None
    except (ValueError, matlab.MatReadError) as exc:
        raise ValueError(f"cube file {path!r} is not a readable MATLAB file: {exc}") from None
    out = {}
    for k, v in raw.items():
        if k.startswith("__"):
            continue
        v = np.asarray(v)
        out[k] = v if k in ("data", "element_positions") else (
            v.reshape(()) if v.size == 1 and k not in ("chirp_times", "tx_slot") else v.ravel())
    return out


def _unpacked_bytes(path: str) -> int:
    """Bytes the arrays of an ``.npz`` or ``.mat`` file take once read (before reading)."""
    if path.endswith(".mat"):
        from scipy.io import whosmat

        try:
            # complex arrays are not flagged here: counted at twice their class's size
            return sum(2 * MAT_CLASS_BYTES.get(cls, 8) * int(np.prod(shape))
                       for _, shape, cls in whosmat(path))
        except Exception:  # noqa: BLE001 - unreadable: _mat_keys names the file's problem
            return 0
    import zipfile

    try:
        with zipfile.ZipFile(path) as z:
            return sum(i.file_size for i in z.infolist())
    except zipfile.BadZipFile:
        raise ValueError(f"cube file {path!r} is not an .npz archive") from None


def _load_npz(path: str) -> CompensateInput:
    """An ``.npz`` or MATLAB ``.mat`` cube (the keys of :mod:`raysim.pipeline.compensate`)."""
    _check_file(path, "cube file")
    check_memory(2 * _unpacked_bytes(path), f"cube file {path!r} (read whole, then range "
                 f"compressed)", "the cube: write its frames to a Zarr store and select "
                 "--frames")
    if path.endswith(".mat"):
        c = _mat_keys(path)
    else:
        with np.load(path) as z:
            c = {k: z[k] for k in z.files}
    missing = [k for k in _NPZ_NEED if k not in c]
    if missing:
        raise ValueError(f"cube file {path!r} lacks keys {missing}; expected "
                         f"{list(_NPZ_NEED)}")
    data = c["data"]
    if data.ndim != 3 or not (np.iscomplexobj(data) or np.issubdtype(data.dtype, np.number)):
        raise ValueError(f"cube 'data' must be [chirp, channel, sample] samples, complex (I/Q) "
                         f"or real (real-only ADC), got {data.dtype} {data.shape}")
    tc, fs = float(c["chirp_duration"]), float(c["sample_rate"])
    t = np.asarray(c["chirp_times"], dtype=float)
    if t.shape != (data.shape[0],):
        raise ValueError(f"cube file {path!r}: chirp_times has shape {t.shape}, expected one "
                         f"time per chirp of 'data' ({data.shape[0]},)")
    slot = np.asarray(c.get("tx_slot", np.zeros(data.shape[1], dtype=int)), dtype=int)
    n_slot = int(slot.max()) + 1 if slot.size else 1
    slot_interval = float(c.get("slot_interval", tc))
    cfg = RadarConfig(carrier_frequency=float(c["carrier_frequency"]),
                      bandwidth=float(c["bandwidth"]), chirp_duration=tc, sample_rate=fs,
                      num_chirps=int(data.shape[0]), num_tx_slots=n_slot,
                      idle_time=max(slot_interval - tc, 0.0),
                      complex_sampling=bool(np.iscomplexobj(data)))
    grid = tuple(int(v) for v in c["grid_shape"]) if "grid_shape" in c else None
    lever = np.asarray(c["lever_arm"], dtype=float) if "lever_arm" in c else None
    return CompensateInput([0], lambda k: data, slot_times(t[None], n_slot, slot_interval),
                           cfg, np.asarray(c["element_positions"], dtype=float), slot, grid,
                           lever, source={"cube": os.path.abspath(path)})


def load_input(path: str, *, radar_config: str | None = None, frames: str | None = None,
               frame: int | None = None, layout: str | None = None,
               capture_t0: float = 0.0, board: str | None = None,
               antenna_positions=None, drop_incomplete: bool = False) -> CompensateInput:
    """Open the input of the compensate stage (``raysim compensate``).

    Parameters
    ----------
    path : str
        Zarr store, NetCDF ``.nc``, ``.npz`` cube, or DCA1000 capture (any
        other file; needs ``radar_config``).
    radar_config : str, optional
        mmWave SDK ``.cfg`` or Studio ``.json`` of a capture.
    frames : str, optional
        ``LO:HI`` or ``K``: frames of a capture or store (default: all frames of
        a capture, ``frame`` of a store).
    frame : int, optional
        One frame of a store (negative: from the end); None: the first, or ``frames``.
        Refused with ``frames``, and for a capture or a one-frame cube.
    layout : {"2lane", "4lane"}, optional
        LVDS layout of a capture (default from the configuration or the
        board). A capture whose size or zero-filled lanes do not fit it is
        refused (:func:`raysim.io.ti_dca1000.check_capture_fits`).
    capture_t0 : float
        Radar-clock time of the first ramp of a capture [s].
    board : str, optional
        TI board of a capture (:mod:`raysim.io.ti_boards`): its antenna layout,
        RX feed signs (applied to the channels) and LVDS lanes.
    antenna_positions : str or path-like, optional
        Antenna file of a capture (:func:`raysim.io.ti_boards.read_antenna_positions`).
    drop_incomplete : bool
        Read the whole frames of a capture that ends inside a frame (warned).

    Raises
    ------
    ValueError
        Missing files, bad selections, invalid configurations (named).
    """
    from raysim.io import storage

    if frame is not None and frames is not None:
        raise ValueError(f"--frame {frame} and --frames {frames!r}: give one (a frame of a "
                         f"store, or a range of frames)")
    is_store = not path.endswith((".npz", ".mat")) and (
        storage.store_exists(path) or (path.endswith(".nc") and os.path.isfile(path)))
    if frame is not None and not is_store:
        raise ValueError(f"--frame {frame} selects a frame of a Zarr or NetCDF store; "
                         f"{path!r} is not one (a capture takes --frames K:K+1, a cube "
                         f"holds one frame)")
    if radar_config is not None or path.endswith(".bin"):
        return _load_capture(path, radar_config, frames, layout, capture_t0, board,
                             antenna_positions, drop_incomplete)
    if drop_incomplete:
        raise ValueError(f"--drop-incomplete applies to a raw capture; {path!r} is a cube")
    if board is not None or antenna_positions is not None:
        raise ValueError("--board / --antenna-positions describe a raw capture's antennas; "
                         f"{path!r} carries its own element positions")
    if is_store:
        return _load_store(path, frames, 0 if frame is None else frame)
    if frames is not None:
        raise ValueError(f"--frames {frames!r}: an .npz or .mat cube holds one frame")
    return _load_npz(path)


def write_compensated_store(path: str, inp: CompensateInput, beams: list, *, chain: str,
                            warnings, azimuth_deg, elevation_deg, extra_attrs=None) -> None:
    """Write the compensated beams and Doppler maps of every frame as a Zarr store.

    Layout (dimension names and units of :data:`raysim.vocabulary.AXIS_UNITS`):

    =================  =============================================  ==============
    variable           dimensions                                     unit
    =================  =============================================  ==============
    ``beams``          ``frame, chirp, range, azimuth, elevation``    input units
    ``doppler_power``  ``frame, doppler, range, azimuth, elevation``  input units^2
    ``chirp_time``     ``frame, chirp``                               s (slot 0)
    ``slot_time``      ``frame, chirp, slot``                         s
    =================  =============================================  ==============

    Coordinates: ``frame`` (frame number in the source), ``range`` [m],
    ``azimuth``, ``elevation`` [deg], ``doppler`` (range rate) [m/s], ``slot``.
    Attributes: ``chain``, ``warnings`` (JSON list), the source files,
    ``raysim_compensated`` (:data:`COMPENSATED_FORMAT`) and the store marker
    ``raysim_format`` of :mod:`raysim.io.store_guard` (a raysim store that
    a later run may replace). Written aside and
    renamed into place (:func:`raysim.io.zarr_store.write_store`), replacing
    an earlier compensated store at ``path``.

    Parameters
    ----------
    beams : list of compensation.BeamCube
        One per selected frame, ``data [chirp, range, azimuth, elevation]``.
    """
    import xarray as xr

    from raysim.io.storage import FORMAT_VERSION
    from raysim.io.store_guard import STORE_MARKER
    from raysim.io.zarr_store import write_store

    data = np.stack([b.data for b in beams]).astype(np.complex64)
    doppler = np.stack([np.abs(b.doppler()) ** 2 for b in beams]).astype(np.float32)
    b0 = beams[0]

    def coord(name, values, **attrs):
        return (name, np.asarray(values), {"units": AXIS_UNITS.get(name, ""), **attrs})

    ds = xr.Dataset(
        {"beams": (("frame", "chirp", "range", "azimuth", "elevation"), data,
                   {"units": inp.units, "long_name": f"beams of chain {chain}"}),
         "doppler_power": (("frame", "doppler", "range", "azimuth", "elevation"), doppler,
                           {"units": f"({inp.units})^2",
                            "long_name": "power of the Doppler FFT of the beams over chirp"}),
         "chirp_time": (("frame", "chirp"), np.stack([b.chirp_time for b in beams]),
                        {"units": "s", "long_name": "start of each chirp loop (slot 0), "
                                                    "radar clock"}),
         "slot_time": (("frame", "chirp", "slot"), inp.slot_times,
                       {"units": "s", "long_name": "start of each TDM slot's ramp, "
                                                   "radar clock"})},
        coords={"frame": coord("frame", inp.frames),
                "range": coord("range", b0.range),
                "azimuth": coord("azimuth", azimuth_deg),
                "elevation": coord("elevation", elevation_deg),
                "doppler": coord("doppler", b0.velocity(), long_name="range rate"),
                "slot": coord("slot", np.arange(inp.num_slots))},
        attrs={COMPENSATED_FORMAT_ATTR: COMPENSATED_FORMAT, STORE_MARKER: FORMAT_VERSION,
               "chain": chain, "warnings": json.dumps(list(warnings)),
               "source": json.dumps(inp.source), **(extra_attrs or {})})
    write_store(path, ds, overwrite=os.path.exists(path))


def write_compensated_npz(path: str, beams, chain: str, azimuth_deg, elevation_deg,
                          calibration: dict | None = None) -> None:
    """Write the single-frame ``.npz`` output, atomically.

    Keys: ``beams [chirp, range, azimuth, elevation]`` (input units),
    ``doppler_power [doppler, range, azimuth, elevation]`` (float32, input
    units^2), ``chirp_times [chirp]`` [s], ``range_m``, ``azimuth_deg``,
    ``elevation_deg``, ``velocity_mps`` (Doppler axis, range rate), ``chain``,
    ``warnings`` and, with a self-calibration, ``self_calibration`` (its
    report as JSON).

    Parameters
    ----------
    path : str
        Output file (written aside, then renamed into place).
    beams : compensation.BeamCube
        The frame's beams.
    chain : str
        Chain key of :mod:`raysim.vocabulary`.
    azimuth_deg, elevation_deg : array_like
        Grid axes [deg].
    calibration : dict, optional
        Self-calibration report.
    """
    doppler = beams.doppler()

    def write(tmp):
        with open(tmp, "wb") as fh:  # a file object: np.savez would append ".npz" to a name
            np.savez(fh, beams=beams.data,
                     doppler_power=(np.abs(doppler) ** 2).astype(np.float32),
                     chirp_times=beams.chirp_time, range_m=beams.range,
                     azimuth_deg=np.asarray(azimuth_deg, dtype=float),
                     elevation_deg=np.asarray(elevation_deg, dtype=float),
                     velocity_mps=beams.velocity(), chain=np.array(chain),
                     warnings=np.array(beams.warnings, dtype=str),
                     **({} if calibration is None else
                        {"self_calibration": np.array(json.dumps(calibration))}))

    atomic_write(path, write)


def check_compensated_output(path, option: str = "--out", inputs=()) -> bool:
    """Check, before any computation, that the compensated output may be written at ``path``.

    A path ending in ``.npz`` (any case) is a file; one ending in the suffix of
    another format (:data:`OTHER_FORMAT_SUFFIXES`) is refused; any other a Zarr
    store, which may replace only an earlier store of
    :func:`write_compensated_store` (never a frame store or another folder).

    Parameters
    ----------
    path : str or path-like
        The output.
    option : str
        The option or parameter named in the messages.
    inputs : iterable of path or (label, path)
        The command's inputs; the output may be none of them.

    Returns
    -------
    bool
        True for the single-frame ``.npz`` layout, False for a store.

    Raises
    ------
    ValueError
        Naming ``option`` and ``path``.
    """
    import zarr

    from raysim.io.zarr_store import store_exists

    path = os.fspath(path)
    as_npz = path.lower().endswith(".npz")
    suffix = os.path.splitext(path.rstrip("/"))[1]
    if suffix.lower() in OTHER_FORMAT_SUFFIXES:
        # a Zarr folder named beams.nc would not be the file its name promises
        raise ValueError(f"{option}: got {path!r}, whose suffix {suffix!r} names a format "
                         f"not written here; expected a Zarr store (.zarr, or no suffix) or, "
                         f"for one frame, .npz")
    check_output(path, "file" if as_npz else "dir", option, inputs=inputs)
    if not as_npz and os.path.isdir(path):
        if not store_exists(path):
            raise ValueError(f"{option}: cannot write {path!r}: it is an existing directory "
                             f"that is not a Zarr store (expected a new store path, or .npz "
                             f"for one frame)")
        if COMPENSATED_FORMAT_ATTR not in zarr.open_group(path, mode="r").attrs:
            raise ValueError(f"{option}: cannot write {path!r}: it is an existing Zarr store "
                             f"not written by raysim compensate (a frame store?); expected a "
                             f"new path or an earlier compensated store to replace")
    return as_npz
