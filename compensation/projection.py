"""Chirp-wise beam projection onto a fixed global angle grid.

One engine serves three beamformers:

* nominal (no motion): the conventional beam scan;
* the paper's yaw projection: per-chirp steering with ``u_B = Rz(gamma_n)^T u_G``;
* the exact rigid-body projection: per-chirp steering from the full attitude
  and the displacement of the radar phase centre (all six degrees of freedom,
  lever arm included), focused on each range gate, so the slow-time motion
  phase is removed together with the array-manifold change.

Signal model (docs/conventions.md). A static scatterer at world point
``P = R u_G`` (``R`` the gate range, ``u_G`` a grid direction, both from the
nominal radar phase centre) seen from a radar whose phase centre is displaced
by ``d_n`` and whose attitude is ``R_n`` gives, after range compression at the
mid-chirp wavelength ``lambda``::

    x[n, m] ~ exp(+j 2 pi / lambda (2 rho_n - v_n . p_m))
    rho_n = |P - d_n| - R,      v_n = R_n^T (P - d_n) / |P - d_n|

with ``p_m`` the virtual positions (``p_tx + p_rx``) in the radar frame. The
projection is the matched filter ``y[n] = sum_m conj(model[n, m]) x[n, m] / M``:
a static scatterer in the beam gives a slow-time sequence without motion
phase. Only the array aperture is treated in the far field (error
``|p|^2 / (8 R)``, a few micrometres for the paper's 39 mm aperture at 15 m).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

import numpy as np
import scipy.fft

from ._checks import (
    angle_axis,
    choice,
    complex_cube,
    finite_array,
    positive,
    rotation_matrices,
)
from .geometry import grid_directions

#: Grid-alignment tolerance of :func:`lattice_vectors` [m].
LATTICE_TOL = 1e-9
#: Requested relative accuracy of the non-uniform FFT (method ``"nufft"``).
NUFFT_EPS = 1e-6


def _finufft():
    """The finufft module, or None when it is not installed."""
    try:
        import finufft
    except ImportError:  # pragma: no cover - finufft is a project dependency
        return None
    return finufft


@dataclass(frozen=True, eq=False)
class BeamCube:
    """Beam outputs on a fixed global angle grid, per chirp and range gate.

    Attributes
    ----------
    data : ndarray, shape ``[chirp, range, azimuth, elevation]``, complex64
        Beamformed, range-compressed samples (channel-averaged, so a unit
        echo gives 1 in its beam) [same unit as the input cube].
    chirp_time : ndarray, shape ``[chirp]``
        Chirp start times [s].
    range : ndarray, shape ``[range]``
        Range of each gate from the nominal radar phase centre [m].
    azimuth, elevation : ndarray, shapes ``[azimuth]``, ``[elevation]``
        Global grid axes [rad] (directions in W at the nominal attitude).
    wavelength : float
        Wavelength used for the phases [m] (mid-chirp wavelength for
        range-compressed data).
    warnings : tuple of str
        Assumptions of the compensation that did not hold, from the motion
        (``"hover window"``, ``"levelling"``) and the chain
        (``"small-angle"``, ``"paper rotation phase"``); see
        :mod:`compensation.guards`. Empty when none.
    """

    data: np.ndarray
    chirp_time: np.ndarray
    range: np.ndarray
    azimuth: np.ndarray
    elevation: np.ndarray
    wavelength: float
    warnings: tuple[str, ...] = ()

    dims = ("chirp", "range", "azimuth", "elevation")

    def __post_init__(self) -> None:
        expected = (len(self.chirp_time), len(self.range), len(self.azimuth),
                    len(self.elevation))
        if self.data.shape != expected:
            raise ValueError(f"data shape {self.data.shape} does not match the axes "
                             f"[chirp, range, azimuth, elevation] = {expected}")
        if isinstance(self.warnings, str):
            raise ValueError(f"warnings must be a sequence of strings, got {self.warnings!r}")
        object.__setattr__(self, "warnings", tuple(str(w) for w in self.warnings))

    def with_warnings(self, warnings) -> BeamCube:
        """The same beams with ``warnings`` appended (repeats dropped)."""
        from .guards import merge

        return replace(self, warnings=merge(self.warnings, warnings))

    def to_xarray(self):
        """The beams as a labelled :class:`xarray.DataArray` ``beams``.

        Dimensions ``chirp, range, azimuth, elevation`` (docs/conventions.md).
        Coordinates: ``chirp_time`` ``[chirp]`` [s], ``range`` [m],
        ``azimuth`` and ``elevation`` [rad], each with ``units`` and
        ``long_name`` in its attrs. Attributes: ``wavelength_m`` and
        ``warnings`` (the :attr:`warnings`, ``"; "``-joined, empty when none).
        The data is not copied.

        Returns
        -------
        xarray.DataArray
            Shape ``[chirp, range, azimuth, elevation]``, complex64.
        """
        import xarray as xr

        coords = {
            "chirp_time": ("chirp", np.asarray(self.chirp_time, dtype=float),
                           {"units": "s", "long_name": "chirp start time"}),
            "range": ("range", np.asarray(self.range, dtype=float),
                      {"units": "m", "long_name": "range from the nominal radar phase centre"}),
            "azimuth": ("azimuth", np.asarray(self.azimuth, dtype=float),
                        {"units": "rad", "long_name": "azimuth of the global grid"}),
            "elevation": ("elevation", np.asarray(self.elevation, dtype=float),
                          {"units": "rad", "long_name": "elevation of the global grid"}),
        }
        return xr.DataArray(self.data, dims=self.dims, coords=coords, name="beams", attrs={
            "long_name": "beamformed, range-compressed samples (channel-averaged)",
            "wavelength_m": float(self.wavelength), "warnings": "; ".join(self.warnings)})

    @property
    def chirp_interval(self) -> float:
        """Mean slow-time sampling period [s] (NaN for a single chirp)."""
        t = np.asarray(self.chirp_time)
        return float(np.mean(np.diff(t))) if t.size > 1 else float("nan")

    def doppler(self, *, window: str | None = "hann", n_fft: int | None = None) -> np.ndarray:
        """Slow-time FFT (fft-shifted), gain-normalised.

        Returns
        -------
        ndarray, shape ``[doppler, range, azimuth, elevation]``, complex64
        """
        n = self.data.shape[0]
        if window is None:
            w = np.ones(n)
        else:
            from scipy.signal import get_window

            w = get_window(window, n, fftbins=True)
        w = (w / w.sum()).astype(np.float32)
        spec = scipy.fft.fft(self.data * w[:, None, None, None], n=n_fft, axis=0, workers=-1)
        return np.fft.fftshift(spec, axes=0).astype(np.complex64, copy=False)

    def doppler_frequency(self, n_fft: int | None = None) -> np.ndarray:
        """Doppler frequency of each fft-shifted bin, shape ``[doppler]`` [Hz]."""
        n = self.data.shape[0] if n_fft is None else int(n_fft)
        return np.fft.fftshift(np.fft.fftfreq(n, d=self.chirp_interval))

    def velocity(self, n_fft: int | None = None) -> np.ndarray:
        """Range rate of each Doppler bin ``f_D lambda / 2``, shape ``[doppler]`` [m/s]."""
        return self.doppler_frequency(n_fft) * self.wavelength / 2.0

    def coherent_power(self, *, window: str | None = None) -> np.ndarray:
        """Power of the (optionally windowed) sum over chirps, i.e. the zero-Doppler beam.

        Returns
        -------
        ndarray, shape ``[range, azimuth, elevation]``, float64
        """
        n = self.data.shape[0]
        if window is None:
            s = self.data.mean(axis=0)
        else:
            from scipy.signal import get_window

            w = get_window(window, n, fftbins=True)
            s = np.tensordot(w / w.sum(), self.data, axes=(0, 0))
        return np.abs(s.astype(np.complex128)) ** 2

    def chirp_power(self, chirp: int) -> np.ndarray:
        """Power map of one chirp, shape ``[range, azimuth, elevation]``."""
        return np.abs(self.data[chirp].astype(np.complex128)) ** 2


def lattice_vectors(positions, grid_shape) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Origin and steps of a regular planar grid of element positions.

    Parameters
    ----------
    positions : ndarray, shape ``[channel, 3]``
        Element positions, x index major, y index minor [m].
    grid_shape : (int, int)
        ``(nx, ny)``.

    Returns
    -------
    p0, a, b : ndarray, shape ``[3]`` each
        ``positions[ix * ny + iy] = p0 + ix a + iy b`` [m].

    Raises
    ------
    ValueError
        If the positions do not form that grid.
    """
    p = np.asarray(positions, dtype=float)
    nx, ny = (int(v) for v in grid_shape)
    if nx < 1 or ny < 1 or nx * ny != p.shape[0]:
        raise ValueError(f"grid_shape {tuple(grid_shape)} does not match {p.shape[0]} channels")
    p0 = p[0]
    a = p[ny] - p0 if nx > 1 else np.zeros(3)
    b = p[1] - p0 if ny > 1 else np.zeros(3)
    ix, iy = np.divmod(np.arange(nx * ny), ny)
    model = p0 + ix[:, None] * a + iy[:, None] * b
    err = np.abs(model - p).max()
    if err > LATTICE_TOL + 1e-9 * np.abs(p).max():
        raise ValueError(f"element_positions do not form a regular {nx} x {ny} grid "
                         f"(x index major, y minor); deviation {err:.3g} m")
    return p0, a, b


def _powers(z: np.ndarray, n: int) -> np.ndarray:
    """``z ** arange(n)`` along a new leading axis by doubling (complex64, O(log n) passes)."""
    out = np.empty((n,) + z.shape, dtype=np.complex64)
    out[0] = 1.0
    if n > 1:
        out[1] = z
    have = 2
    zp = (z * z).astype(np.complex64)
    while have < n:
        take = min(have, n - have)
        np.multiply(out[:take], zp, out=out[have:have + take])
        have += take
        zp = zp * zp
    return out


def beam_projection(rc, element_positions, *, wavelength: float, range_axis, azimuth,
                    elevation, range_gates=None, chirp_time=None, attitude=None,
                    displacement=None, focus: Literal["near", "far"] = "near",
                    grid_shape: tuple[int, int] | None = None,
                    method: Literal["auto", "nufft", "lattice", "direct"] = "auto",
                    weights=None, chirp_block: int = 32, gate_block: int = 8) -> BeamCube:
    """Project every chirp onto a fixed global angle grid, removing the platform motion.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube (complex).
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual positions ``p_virt = p_tx + p_rx`` in the radar frame A [m]
        (one-way phase convention ``2 pi / lambda u . p_virt``).
    wavelength : float
        Wavelength of the phases [m]; for range-compressed data the mid-chirp
        wavelength ``c / (f_c + B / 2)``.
    range_axis : array_like, shape ``[range]``
        Range of each bin of ``rc`` [m] (only the selected gates are used).
    azimuth, elevation : array_like, shapes ``[azimuth]``, ``[elevation]``
        Global grid [rad].
    range_gates : array_like of int, shape ``[gate]``, optional
        Range bins to process (default all). The cost grows linearly with
        their number; gate the cells of interest.
    chirp_time : array_like, shape ``[chirp]``, optional
        Chirp times [s] carried by the result (default ``arange(chirp)``).
    attitude : array_like, shape ``[chirp, 3, 3]``, optional
        ``R_WB`` per chirp; default identity.
    displacement : array_like, shape ``[chirp, 3]``, optional
        Radar phase-centre displacement from its nominal position, in W [m];
        default zero.
    focus : {"near", "far"}
        ``"near"``: exact range from the displaced phase centre to the focal
        point ``R u_G`` of each gate; ``"far"``: plane-wave phase
        ``-u_G . d_n`` and steering direction ``u_G``.
    grid_shape : (int, int), optional
        ``(nx, ny)`` when the positions form a regular grid (x major, y minor);
        enables the separable ``"lattice"`` method.
    method : {"auto", "nufft", "lattice", "direct"}
        For a regular grid of elements the projection of one chirp is a 2-D
        discrete-time Fourier transform of the ``[nx, ny]`` snapshot evaluated
        at the chirp's own (rotated) direction cosines: ``"nufft"`` evaluates
        it with a type-2 non-uniform FFT (finufft, tolerance
        :data:`NUFFT_EPS`), cost about ``chirp * direction * 50`` per gate;
        ``"lattice"`` factorises the steering into two 1-D geometric sequences
        and uses one matrix product per chirp (cost ``chirp * direction *
        channel``, exact to float32 round-off); ``"direct"`` builds the full
        ``[direction, channel]`` steering per chirp (any geometry). ``"auto"``
        picks ``"nufft"`` when ``grid_shape`` is given and finufft is
        installed, else ``"lattice"``, and ``"direct"`` without ``grid_shape``.
    weights : array_like, shape ``[channel]``, optional
        Real channel taper (e.g. a separable Taylor window) applied before the
        sum; the output is divided by ``sum(weights)`` so a unit echo still
        gives 1 in its beam. Default uniform.
    chirp_block, gate_block : int
        Chirps and gates processed together (bound the temporaries). Within
        a block of gates the steering direction is taken at the block's mean
        range (the direction change across 8 gates of 15 cm is below 1e-5 rad
        for centimetre displacements at 15 m); the range phase ``rho`` is
        exact for every gate.

    Returns
    -------
    BeamCube
        ``data [chirp, range, azimuth, elevation]`` with the selected gates.

    Notes
    -----
    ``y[n, g, d] = exp(-j 4 pi rho / lambda) / M sum_m exp(+j 2 pi / lambda
    v_n . p_m) x[n, m, g]`` (see the module docstring). With no motion this is
    the conventional beamformer ``a(u)^H x / M`` with
    ``a = exp(-j 2 pi / lambda u . p)``.
    """
    x = complex_cube("rc", rc)
    n_chirp, n_chan, n_range = x.shape
    p = finite_array("element_positions", element_positions, shape=(n_chan, 3),
                     what="(one row per channel of rc)")
    lam = positive("wavelength", wavelength)
    r_axis = finite_array("range_axis", range_axis, ndim=1)
    if r_axis.size < n_range:
        raise ValueError(f"range_axis has {r_axis.size} entries but rc has {n_range} range bins")
    az = angle_axis("azimuth", azimuth)
    el = angle_axis("elevation", elevation)
    if az.size < 1 or el.size < 1:
        raise ValueError("azimuth and elevation must each hold at least one angle")
    if range_gates is None:
        gates = np.arange(n_range)
    else:
        gates = np.atleast_1d(np.asarray(range_gates))
        if gates.ndim != 1 or not np.issubdtype(gates.dtype, np.integer) or gates.size < 1 or \
                gates.min() < -n_range or gates.max() >= n_range:
            raise ValueError(f"range_gates must be integer bin indices in [0, {n_range}), "
                             f"got {range_gates!r}")
        gates = gates % n_range
    times = np.arange(n_chirp, dtype=float) if chirp_time is None else finite_array(
        "chirp_time", chirp_time, shape=(n_chirp,))
    rot = None if attitude is None else rotation_matrices("attitude", attitude, n_chirp)
    disp = None if displacement is None else finite_array("displacement", displacement,
                                                          shape=(n_chirp, 3))
    if weights is None:
        taper, norm = None, float(n_chan)
    else:
        taper = finite_array("weights", weights, shape=(n_chan,), what="(one per channel)")
        norm = float(taper.sum())
        if norm <= 0:
            raise ValueError(f"weights must have a positive sum, got {norm!r}")
        taper = taper.astype(np.float32)
    choice("focus", focus, ("near", "far"))
    choice("method", method, ("auto", "nufft", "lattice", "direct"))
    if method == "auto":
        method = "direct" if grid_shape is None else ("nufft" if _finufft() else "lattice")
    if method == "nufft" and not _finufft():
        raise ValueError('method="nufft" needs the finufft package; use method="lattice"')
    if method in ("lattice", "nufft"):
        if grid_shape is None:
            raise ValueError(f'method="{method}" needs grid_shape=(nx, ny)')
        p0, step_a, step_b = lattice_vectors(p, grid_shape)
        nx, ny = (int(v) for v in grid_shape)
    chirp_block = max(1, int(chirp_block))
    gate_block = max(1, int(gate_block))

    u_grid = grid_directions(az, el).reshape(-1, 3)             # [D, 3]
    n_dir = u_grid.shape[0]
    k = 2.0 * np.pi / lam
    out = np.empty((n_chirp, gates.size, n_dir), dtype=np.complex64)
    cdtype = np.complex64

    for g0 in range(0, gates.size, gate_block):
        gsel = gates[g0:g0 + gate_block]
        if method == "nufft":
            plan = _finufft().Plan(2, (nx, ny), n_trans=gsel.size, eps=NUFFT_EPS, isign=1,
                                   dtype="complex64", nthreads=1)
        ranges = r_axis[gsel]                                   # [G]
        r_mid = float(ranges.mean())
        xg = x[:, :, gsel]                                      # [N, M, G]
        if taper is not None:
            xg = xg * taper[None, :, None]
        for n0 in range(0, n_chirp, chirp_block):
            n1 = min(n0 + chirp_block, n_chirp)
            c = n1 - n0
            d = np.zeros((c, 3)) if disp is None else disp[n0:n1]
            # --- range phase rho [c, G, D] and look direction w [c, D, 3]
            if focus == "near":
                fp = ranges[None, :, None, None] * u_grid[None, None] - d[:, None, None, :]
                dist = np.sqrt(np.einsum("cgdi,cgdi->cgd", fp, fp))           # [c, G, D]
                rho = dist - ranges[None, :, None]
                if gsel.size == 1:
                    w = fp[:, 0] / dist[:, 0, :, None]                         # [c, D, 3]
                else:
                    focal = r_mid * u_grid[None] - d[:, None, :]
                    w = focal / np.sqrt(np.einsum("cdi,cdi->cd", focal, focal))[..., None]
            else:
                w = np.broadcast_to(u_grid[None], (c, n_dir, 3))
                rho = np.broadcast_to(-(d @ u_grid.T)[:, None, :], (c, gsel.size, n_dir))
            v = w if rot is None else w @ rot[n0:n1]                       # R^T w
            xb = xg[n0:n1].astype(cdtype, copy=False)                          # [c, M, G]
            if method == "nufft":
                # modes k = i - n//2: sum_i X_i e^{j phi i} = e^{j phi n//2} sum_k X_k e^{j phi k}
                pa = np.mod(k * (v @ step_a) + np.pi, 2 * np.pi) - np.pi          # [c, D]
                pb = np.mod(k * (v @ step_b) + np.pi, 2 * np.pi) - np.pi
                xs = xb.reshape(c, nx, ny, -1).transpose(0, 3, 1, 2)              # [c, G, nx, ny]
                y = np.empty((c, gsel.size, n_dir), dtype=cdtype)
                for i in range(c):
                    plan.setpts(pa[i].astype(np.float32), pb[i].astype(np.float32))
                    y[i] = plan.execute(np.ascontiguousarray(xs[i])).reshape(gsel.size, n_dir)
                base = k * (v @ p0) + pa * (nx // 2) + pb * (ny // 2)
            elif method == "lattice":
                za = np.exp(1j * k * (v @ step_a)).astype(cdtype)                 # [c, D]
                zb = np.exp(1j * k * (v @ step_b)).astype(cdtype)
                ea = _powers(za, nx)                                             # [nx, c, D]
                eb = _powers(zb, ny)                                             # [ny, c, D]
                # X[c, ix, iy, G] -> [c, nx * G, ny]; one BLAS product per chirp
                xr = xb.reshape(c, nx, ny, -1).transpose(0, 1, 3, 2).reshape(c, -1, ny)
                z = np.empty((c, nx * gsel.size, n_dir), dtype=cdtype)
                for i in range(c):
                    np.matmul(xr[i], eb[:, i, :], out=z[i])                      # [nx * G, D]
                z = z.reshape(c, nx, gsel.size, n_dir)
                z *= ea.transpose(1, 0, 2)[:, :, None, :]
                y = z.sum(axis=1)                                                # [c, G, D]
                base = k * (v @ p0)                                              # [c, D]
            else:
                y = np.empty((c, gsel.size, n_dir), dtype=cdtype)
                for i in range(c):
                    steer = np.exp(1j * k * (v[i] @ p.T)).astype(cdtype)          # [D, M]
                    y[i] = (steer @ xb[i]).T                                     # [G, D]
                base = np.zeros((c, n_dir))
            phase = base[:, None, :] - 2.0 * k * rho                             # [c, G, D]
            out[n0:n1, g0:g0 + gsel.size] = y * (np.exp(1j * phase) / norm).astype(cdtype)
    return BeamCube(out.reshape(n_chirp, gates.size, az.size, el.size), times,
                    r_axis[gates].copy(), az.copy(), el.copy(), lam)
