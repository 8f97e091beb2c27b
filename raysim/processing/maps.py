"""Range, Doppler and angle processing of IF cubes.

Indexing: IF cubes are ``[chirp, channel, sample]``; range-compressed cubes
``[chirp, channel, range]``. Maps are :class:`Map` objects carrying their axes
(``range`` [m], ``doppler`` [m/s range rate], ``azimuth``/``elevation`` [rad]).

Sign conventions (docs/conventions.md): the IF phase grows with delay, so a forward
FFT over samples puts range at positive beat frequency and a forward FFT over
chirps puts a receding target (positive range rate) at positive Doppler. The
array response is ``exp(-j 2 pi / lambda u . p_virt)``; the beamformer applies
its conjugate. Range-compressed data is processed at the mid-chirp wavelength
``RadarConfig.center_wavelength`` (see its docstring).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.fft

from raysim.processing.metrics import image_entropy, parabolic_offset
from raysim.processing.windows import window
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig

#: Axis name -> (CF unit, long name) of a map coordinate (SI, as stored in ``Map.coords``).
AXIS_COORDS = {"range": ("m", "range from the radar phase centre"),
               "doppler": ("m s-1", "range rate of the Doppler bin"),
               "azimuth": ("rad", "azimuth (docs/conventions.md)"),
               "elevation": ("rad", "elevation (docs/conventions.md)")}

#: Worker threads for scipy.fft (the machine has 2 cores).
FFT_WORKERS = -1


@dataclass(frozen=True, eq=False)
class Map:
    """A real-valued map (power) with named, physical axes.

    Attributes
    ----------
    values : ndarray
        Power (|.|^2, linear) with one axis per entry of ``dims``.
    dims : tuple of str
        Axis names from docs/conventions.md (``range, doppler, azimuth, elevation``).
    coords : dict
        Axis name -> 1-D coordinate array (m, m/s, rad).
    """

    values: np.ndarray
    dims: tuple[str, ...]
    coords: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.values.ndim != len(self.dims):
            raise ValueError(f"values has {self.values.ndim} axes but dims is {self.dims}")
        for d, n in zip(self.dims, self.values.shape, strict=True):
            if d in self.coords and len(self.coords[d]) != n:
                raise ValueError(f"coordinate {d!r} has {len(self.coords[d])} points, axis has {n}")

    def db(self, floor_db: float = -120.0) -> np.ndarray:
        """Power in dB relative to the map maximum, clipped at ``floor_db``."""
        v = self.values / max(float(self.values.max()), np.finfo(float).tiny)
        return np.maximum(10 * np.log10(np.maximum(v, 1e-30)), floor_db)

    def peak(self) -> dict[str, float]:
        """Interpolated peak position per axis (see :func:`map_peak`)."""
        return map_peak(self)

    def entropy(self) -> float:
        """Shannon entropy of the normalised intensity [nats]."""
        return image_entropy(self.values)

    def to_xarray(self, name: str = "power"):
        """The map as a labelled :class:`xarray.DataArray`.

        Dimensions are :attr:`dims` (``range``, ``doppler``, ``azimuth``,
        ``elevation`` of docs/conventions.md) with :attr:`coords` as their
        coordinates, in SI (``range`` [m], ``doppler`` range rate [m/s],
        ``azimuth`` / ``elevation`` [rad]); each coordinate's ``units`` and
        ``long_name`` are in its attrs. The values are not copied.

        Returns
        -------
        xarray.DataArray
            Shape ``values.shape``, named ``name``.
        """
        import xarray as xr

        coords = {}
        for d in self.dims:
            if d in self.coords:
                unit, long_name = AXIS_COORDS.get(d, ("1", d))
                coords[d] = (d, np.asarray(self.coords[d]),
                             {"units": unit, "long_name": long_name})
        return xr.DataArray(self.values, dims=self.dims, coords=coords, name=name,
                            attrs={"long_name": "power, linear (|.|^2 of the processed "
                                                "samples)"})


def map_peak(m: Map) -> dict[str, float]:
    """Interpolated peak of a map: coordinate per axis, parabola on dB values.

    Returns
    -------
    dict
        Axis name -> peak coordinate (in the axis unit), plus ``"value"`` (linear peak power).
    """
    v = m.values
    idx = np.unravel_index(int(np.argmax(v)), v.shape)
    db = 10 * np.log10(np.maximum(v, 1e-300))
    out: dict[str, float] = {}
    for ax, name in enumerate(m.dims):
        coord = np.asarray(m.coords[name], dtype=float)
        i = idx[ax]
        frac = 0.0
        if 0 < i < v.shape[ax] - 1:
            lo = list(idx)
            hi = list(idx)
            lo[ax] -= 1
            hi[ax] += 1
            frac = parabolic_offset(db[tuple(lo)], db[idx], db[tuple(hi)])
        step = coord[1] - coord[0] if coord.size > 1 else 0.0
        out[name] = float(coord[i] + frac * step)
    out["value"] = float(v[idx])
    return out


def range_compress(data: np.ndarray, *, window_name: str | None = "hann",
                   n_fft: int | None = None) -> np.ndarray:
    """Range FFT over the last (``sample``) axis.

    Parameters
    ----------
    data : ndarray, shape ``[..., sample]``
        IF samples.
    window_name : str or None
        Fast-time window; the result is divided by its sum (coherent gain) so a
        tone of amplitude ``a`` peaks at ``a``.
    n_fft : int, optional
        FFT length (zero padding).

    Returns
    -------
    ndarray, shape ``[..., range]``, complex64
        ``range = n_fft`` bins for complex samples; for real samples (a
        real-sampled ADC) the ``n_fft // 2`` bins of positive beat frequency,
        doubled so that a real tone ``a cos(...)`` peaks at ``a`` as its complex
        counterpart ``a exp(j ...)`` does (:meth:`RadarConfig.range_axis`
        gives their ranges).
    """
    k = data.shape[-1]
    w = window(window_name, k)
    w = (w / w.sum()).astype(np.float32)
    if not np.iscomplexobj(data):
        n = k if n_fft is None else int(n_fft)
        half = scipy.fft.rfft(data * w, n=n, axis=-1, workers=FFT_WORKERS)[..., : n // 2]
        return (2.0 * half).astype(np.complex64, copy=False)
    return scipy.fft.fft(data * w, n=n_fft, axis=-1, workers=FFT_WORKERS).astype(
        np.complex64, copy=False)


def doppler_fft(x: np.ndarray, *, axis: int = 0, window_name: str | None = "hann",
                n_fft: int | None = None) -> np.ndarray:
    """Slow-time FFT (fft-shifted) along ``axis`` (``chirp`` -> ``doppler``), gain-normalised."""
    n = x.shape[axis]
    w = window(window_name, n)
    w = w / w.sum()
    shape = [1] * x.ndim
    shape[axis] = n
    y = scipy.fft.fft(x * w.reshape(shape), n=n_fft, axis=axis, workers=FFT_WORKERS)
    return np.fft.fftshift(y, axes=axis)


def steering_matrix(array: VirtualArray, wavelength: float, u: np.ndarray) -> np.ndarray:
    """Steering vectors ``exp(-j 2 pi / lambda u . p_virt)``, shape ``[direction, channel]``."""
    return array.steering_vector(np.asarray(u).reshape(-1, 3), wavelength)


def beamform(x: np.ndarray, array: VirtualArray, wavelength: float, u: np.ndarray) -> np.ndarray:
    """Conventional (delay-and-sum) beamformer ``y = a(u)^H x / M``.

    Parameters
    ----------
    x : ndarray, shape ``[..., channel]``
        Channel snapshots.
    u : ndarray, shape ``[direction, 3]``
        Look directions in frame A.

    Returns
    -------
    ndarray, shape ``[..., direction]``
    """
    a = steering_matrix(array, wavelength, u)
    return (x @ a.conj().T.astype(np.complex64 if x.dtype == np.complex64 else complex)) / (
        array.num_channels)


def az_el_grid(az: np.ndarray, el: np.ndarray) -> np.ndarray:
    """Directions of an (azimuth, elevation) grid, shape ``[azimuth * elevation, 3]`` (az major)."""
    from compensation.geometry import direction

    aa, ee = np.meshgrid(az, el, indexing="ij")
    return direction(aa, ee).reshape(-1, 3)


def range_doppler_map(rc: np.ndarray, config: RadarConfig, *, window_name: str | None = "hann",
                      n_fft: int | None = None) -> Map:
    """Range-Doppler power map, non-coherently summed over channels.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube.

    Returns
    -------
    Map with dims ``(range, doppler)``; doppler coordinate is range rate [m/s].
    """
    spec = doppler_fft(rc, axis=0, window_name=window_name, n_fft=n_fft)
    power = np.sum(np.abs(spec) ** 2, axis=1).T
    n_range = rc.shape[-1]
    return Map(power, ("range", "doppler"),
               {"range": config.bin_ranges(n_range),
                "doppler": config.velocity_axis(spec.shape[0])})


def range_azimuth_map(rc_chirp: np.ndarray, array: VirtualArray, config: RadarConfig,
                      az: np.ndarray, *, el: float = 0.0) -> Map:
    """Range-azimuth power map of one chirp by beam scan at a fixed elevation.

    Parameters
    ----------
    rc_chirp : ndarray, shape ``[channel, range]``
    az : ndarray, shape ``[azimuth]`` [rad]

    Returns
    -------
    Map with dims ``(range, azimuth)``.
    """
    u = az_el_grid(az, np.array([el]))
    y = beamform(rc_chirp.T, array, config.center_wavelength, u)          # [range, azimuth]
    n_range = rc_chirp.shape[-1]
    return Map(np.abs(y) ** 2, ("range", "azimuth"),
               {"range": config.bin_ranges(n_range), "azimuth": np.asarray(az)})


def azimuth_elevation_map(snapshots: np.ndarray, array: VirtualArray, wavelength: float,
                          az: np.ndarray, el: np.ndarray) -> Map:
    """Azimuth-elevation power map, accumulated non-coherently over snapshots.

    Parameters
    ----------
    snapshots : ndarray, shape ``[snapshot, channel]`` or ``[channel]``
        Channel vectors at one range gate (one per chirp or frame).
    az, el : ndarray
        Grid axes [rad].

    Returns
    -------
    Map with dims ``(azimuth, elevation)``.
    """
    x = np.atleast_2d(snapshots)
    y = beamform(x, array, wavelength, az_el_grid(az, el))         # [snapshot, az*el]
    power = np.sum(np.abs(y) ** 2, axis=0).reshape(len(az), len(el))
    return Map(power, ("azimuth", "elevation"), {"azimuth": np.asarray(az),
                                                 "elevation": np.asarray(el)})


def upa_angle_fft(snapshot: np.ndarray, array: VirtualArray, wavelength: float,
                  n_fft: int = 64) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """2-D spatial FFT of a UPA snapshot in direction-cosine space.

    Parameters
    ----------
    snapshot : ndarray, shape ``[..., channel]`` (x index major, y minor)

    Returns
    -------
    power : ndarray, shape ``[..., n_fft, n_fft]`` over ``(u_x, u_y)``
    ux, uy : ndarray, shape ``[n_fft]``
        Direction cosines ``u . X_A`` and ``u . Y_A`` of the bins.
    """
    if array.grid_shape is None:
        raise ValueError(f"upa_angle_fft needs a gridded array, got {array.name!r}")
    nx, ny = array.grid_shape
    p = array.virtual_positions
    dx = p[ny, 0] - p[0, 0] if nx > 1 else wavelength / 2
    dy = p[1, 1] - p[0, 1] if ny > 1 else wavelength / 2
    x = snapshot.reshape(snapshot.shape[:-1] + (nx, ny))
    # response exp(-j 2 pi ux dx i / lambda): an inverse FFT puts it at +ux
    spec = np.fft.fftshift(np.fft.ifft2(x, s=(n_fft, n_fft)), axes=(-2, -1))
    f = np.fft.fftshift(np.fft.fftfreq(n_fft))
    return np.abs(spec) ** 2, f * wavelength / dx, f * wavelength / dy


def target_slow_time(rc: np.ndarray, array: VirtualArray, config: RadarConfig,
                     range_m: float, u: np.ndarray) -> np.ndarray:
    """Slow-time signal of the range gate nearest ``range_m``, beamformed towards ``u``.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
    u : ndarray, shape ``[3]``
        Look direction in frame A.

    Returns
    -------
    ndarray, shape ``[chirp]``, complex
    """
    r_axis = config.range_axis(rc.shape[-1])
    idx = int(np.argmin(np.abs(r_axis - range_m)))
    return beamform(rc[:, :, idx], array, config.center_wavelength, np.reshape(u, (1, 3)))[:, 0]
