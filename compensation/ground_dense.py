"""Dense ground points: every range cell of the ground split into the plane waves it holds.

The ~40 strongest beam maxima of a frame give ground points whose directions
scatter by degrees: most cells beyond the nadir hold two to four clutter
scatterers (the range ring crosses every azimuth beam twice, and the Hann range
kernel spreads each scatterer over three cells), and a beam maximum or a phase
comparison measures their mixture. Here every ground cell of one snapshot (one
chirp loop, all channels) is fitted as a sum of one to :data:`MAX_SOURCES`
plane waves ``y = sum_q c_q a(u_q)`` (least squares over the directions, the
amplitudes solved linearly), taking the fewest that leave less than
``1 - MIN_PURITY`` of the cell's power; cells no few plane waves explain are
left out. A scatterer shows in consecutive cells with one direction and the
amplitudes ``c_b = a K(b - rho)`` of the range kernel ``K`` (the windowed range
FFT of a tone, ``rho`` its range in cells): the cells of one direction are
joined into a track and ``rho`` fitted to them, so a point's range is the
scatterer's, not its cell's centre, and its direction the power-weighted mean of
its cells'. A cell that holds one scatterer gives its direction to a few
hundredths of a degree (the strongest scatterer of the flights' clutter: 4 mm
off the plane at 15 m, docs/self_calibration.md).

TDM MIMO: the channels of transmit slot ``s`` are sampled ``s`` slots after
slot 0, while the platform moves; the raised TX, the only elevation baseline,
is a later slot, and the velocity error of an IMU integration over those tens
of microseconds turns the elevation (0.02 m/s along the line of sight turns it
by about 0.2 deg for the xWR18xx). Every channel is therefore interpolated
linearly in slow time between two consecutive chirp loops to the slot-0 instant
of the later one (exact to first order in the phase advance per loop, whatever
the velocity), and the snapshot is one instant: no motion model enters the
directions but the attitude that turns them into W.

What it cannot do: a cell with more plane waves than :data:`MAX_SOURCES`, or
two scatterers closer than the array resolves, gives no point; the range
kernel is that of the project's range compression (a periodic Hann window over
the FFT length, :func:`range_kernel`); the directions are those of a planar
array in A (element positions with ``z = 0``).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares
from scipy.signal import get_window

from ._checks import channel_slots, finite_array
from .strapdown import PlatformMotion

__all__ = ["DENSE_ANGLE_SIGMA", "DENSE_RANGE_SIGMA_CELLS", "aligned_snapshot",
           "dense_ground_directions", "direction_grid", "range_kernel", "snapshot_points",
           "steering"]

#: Most plane waves fitted to one range cell.
MAX_SOURCES = 3
#: Least fraction of a cell's power its plane waves must explain (purity).
MIN_PURITY = 0.995
#: Dynamic range of the cells fitted below the strongest ground cell [dB].
DENSE_DYNAMIC_RANGE_DB = 50.0
#: Steps of the direction-cosine grid (x, y) that starts every plane wave's fit (the
#: refinement does the rest; the array's y aperture is half a wavelength, its beam wide).
GRID_STEP = (0.04, 0.1)
#: Largest direction-cosine difference of one scatterer in consecutive cells.
TRACK_DU = 0.03
#: Fewest consecutive cells of a track (one cell fixes no range within it).
MIN_TRACK_CELLS = 2
#: Largest relative misfit of a track's amplitudes to the range kernel.
MAX_KERNEL_MISFIT = 0.1
#: Spread of a dense point's azimuth and elevation [rad]: the points of the flights'
#: ``parking_lot`` clutter (60 scatterers, six frames, seeds 1-3) lie about their fitted
#: plane with a reduced chi-square of 0.7-1.5 at 0.3 deg (docs/self_calibration.md).
DENSE_ANGLE_SIGMA = float(np.deg2rad(0.3))
#: Spread of a dense point's range [cells] (the kernel fit of a track).
DENSE_RANGE_SIGMA_CELLS = 0.1
#: Chirp loop of the frame whose slot-aligned snapshot is fitted (the first that has
#: a loop before it).
SNAPSHOT_CHIRP = 1


def range_kernel(offset, fft_size: int, window: str = "hann") -> np.ndarray:
    """Response of the range FFT to a tone, at ``offset = cell - rho`` cells.

    Parameters
    ----------
    offset : array_like
        Cell minus the tone's range [cells].
    fft_size : int
        Samples (and FFT length) of the range compression.
    window : str
        Its window (periodic, normalised to unit sum, as
        :func:`raysim.processing.maps.range_compress` applies).

    Returns
    -------
    ndarray, shape of ``offset``, complex
        ``sum_n w_n exp(-j 2 pi offset n / N)``: 1 at offset 0.
    """
    w = get_window(window, int(fft_size), fftbins=True)
    w = w / w.sum()
    n = np.arange(int(fft_size))
    d = np.asarray(offset, dtype=float)
    return np.exp(-2j * np.pi * d[..., None] * n / int(fft_size)) @ w


def steering(ux, uy, element_positions, wavelength: float) -> np.ndarray:
    """Array response ``exp(-j 2 pi / lambda p . u)`` at direction cosines ``(ux, uy)`` in A.

    Parameters
    ----------
    ux, uy : array_like, shape ``[direction]``
        Direction cosines along the array's x and y (``uz`` the positive rest).
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual positions in A [m] (``z = 0``).
    wavelength : float
        [m].

    Returns
    -------
    ndarray, shape ``[direction, channel]``
    """
    p = np.asarray(element_positions, dtype=float)
    ux, uy = np.atleast_1d(ux), np.atleast_1d(uy)
    return np.exp(-2j * np.pi / wavelength * (np.multiply.outer(ux, p[:, 0])
                                              + np.multiply.outer(uy, p[:, 1])))


def aligned_snapshot(rc, time, channel_slot=None, chirp: int = SNAPSHOT_CHIRP) -> np.ndarray:
    """One instant of every channel: each slot's samples interpolated in slow time.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed frame.
    time : array_like, shape ``[chirp * slot]``
        Transmit instant of every slot, chirp major [s].
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM transmit slot of every channel; None: one slot (no interpolation).
    chirp : int
        Chirp loop whose slot-0 instant the snapshot is at (at least 1).

    Returns
    -------
    ndarray, shape ``[channel, range]``
        ``x_{n-1} f + x_n (1 - f)``, ``f`` the slot's delay over the loop's period.
    """
    x = np.asarray(rc)
    if channel_slot is None:
        return x[chirp]
    slot = channel_slots(channel_slot, x.shape[1])
    ns = int(slot.max()) + 1
    t = np.asarray(time, dtype=float)
    if not (1 <= chirp < x.shape[0]) or t.size != x.shape[0] * ns:
        raise ValueError(f"chirp must lie in 1..{x.shape[0] - 1} and time hold chirp * slots = "
                         f"{x.shape[0] * ns} instants; got chirp {chirp}, {t.size} instants")
    period = t[ns * chirp] - t[ns * (chirp - 1)]
    f = (t[ns * chirp + slot] - t[ns * chirp]) / period               # [channel]
    return x[chirp - 1] * f[:, None] + x[chirp] * (1.0 - f[:, None])


def _cell_sources(y: np.ndarray, grid: np.ndarray, table: np.ndarray, p: np.ndarray,
                  wavelength: float):
    """Fewest plane waves (1..MAX_SOURCES) that explain cell ``y`` ``[channel]``:
    directions ``[q, 2]`` and amplitudes ``[q]``, or None. ``table`` ``[grid, channel]``
    holds the conjugate steering vectors of ``grid``."""
    power = float(np.vdot(y, y).real)
    k = 2.0 * np.pi / wavelength

    def project(x):
        s = steering(x[0::2], x[1::2], p, wavelength).T                 # [channel, q]
        c = np.linalg.lstsq(s, y, rcond=None)[0]
        return s, c, y - s @ c

    def misfit(x):
        d = project(x)[2]
        return np.concatenate([d.real, d.imag])

    def jacobian(x):                # variable projection (Kaufman): -P_perp dS/dx c
        s, c, _ = project(x)
        q, _ = np.linalg.qr(s)
        cols = []
        for i in range(s.shape[1]):
            for axis in (0, 1):
                v = -1j * k * p[:, axis] * s[:, i] * c[i]
                v = v - q @ (q.conj().T @ v)
                cols.append(-v)
        j = np.array(cols).T
        return np.concatenate([j.real, j.imag])

    beams = np.abs(table @ y) ** 2 / (table.shape[1] * power)    # purity on the grid
    for m in range(1, MAX_SOURCES + 1):
        if m == 1 and beams.max() < 1.0 - 20.0 * (1.0 - MIN_PURITY):
            continue                # no refinement of one grid direction gets there
        start, r = [], y.copy()
        for _ in range(m):          # each next one where the rest's beam is strongest
            i = int(np.argmax(np.abs(table @ r)))
            start.extend(grid[i])
            r = r - table[i].conj() * (table[i] @ r) / table.shape[1]
        sol = least_squares(misfit, start, jac=jacobian, method="lm", x_scale=0.01)
        if 1.0 - 2.0 * sol.cost / power >= MIN_PURITY:
            u = sol.x.reshape(-1, 2)
            if np.any(np.sum(u ** 2, axis=1) >= 0.98):
                return None
            return u, project(sol.x)[1]
    return None


def dense_ground_directions(rc, element_positions, motion: PlatformMotion, *,
                            wavelength: float, range_axis, gates, channel_slot=None,
                            fft_size: int | None = None,
                            window: str = "hann") -> tuple[np.ndarray, np.ndarray]:
    """Ranges and directions of a frame's ground scatterers from every cell's plane waves.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        One range-compressed frame.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m] (a planar array, ``z = 0``).
    motion : PlatformMotion
        Motion of the frame, one pose per slot with ``channel_slot`` (its attitude at
        the snapshot turns the directions into W as the motion has it).
    wavelength : float
        [m].
    range_axis : array_like, shape ``[range]``
        Range of every cell [m] (uniform).
    gates : array_like of int
        Cells where the ground lies.
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM slot of every channel.
    fft_size, window : int, str
        The range compression's FFT length (default the cells of ``rc``) and window.

    Returns
    -------
    (ndarray, ndarray)
        Ranges ``[point]`` [m] and unit directions ``[point, 3]`` in W as ``motion`` has
        it (spreads :data:`DENSE_RANGE_SIGMA_CELLS` and :data:`DENSE_ANGLE_SIGMA`).
    """
    x = np.asarray(rc)
    p = finite_array("element_positions", element_positions, shape=(x.shape[1], 3))
    r_axis = np.asarray(range_axis, dtype=float)
    g = np.asarray(gates, dtype=int)
    empty = np.zeros(0), np.zeros((0, 3))
    if g.size == 0 or x.shape[0] < 2:
        return empty
    if r_axis.shape != (x.shape[-1],) or r_axis.size < 2:
        raise ValueError(f"range_axis must hold the {x.shape[-1]} cells of rc (two or more), "
                         f"got shape {r_axis.shape}")
    n_fft = x.shape[-1] if fft_size is None else int(fft_size)
    snap = aligned_snapshot(x, motion.time, channel_slot)[:, g]        # [channel, gate]
    slots = 1 if channel_slot is None else int(np.max(channel_slot)) + 1
    att = motion.attitude[slots * SNAPSHOT_CHIRP]
    r, u = snapshot_points(snap, g, p, wavelength=wavelength, range_axis=r_axis,
                           fft_size=n_fft, window=window)
    if r.size == 0:
        return empty
    u_a = np.column_stack([u, np.sqrt(1.0 - np.sum(u ** 2, axis=1))])
    return r, u_a @ att.T


def direction_grid(element_positions, wavelength: float) -> tuple[np.ndarray, np.ndarray]:
    """Starting directions ``[grid, 2]`` (direction cosines in A) of the plane waves' fit
    and their conjugate steering vectors ``[grid, channel]``."""
    gx, gy = np.meshgrid(np.arange(-0.97, 0.971, GRID_STEP[0]),
                         np.arange(-0.95, 0.951, GRID_STEP[1]), indexing="ij")
    inside = gx ** 2 + gy ** 2 < 0.96
    grid = np.column_stack([gx[inside], gy[inside]])
    return grid, steering(grid[:, 0], grid[:, 1], element_positions, wavelength).conj()


def snapshot_points(snap, gates, element_positions, *, wavelength: float, range_axis,
                    fft_size: int, window: str = "hann", floor: float | None = None,
                    with_power: bool = False) -> tuple[np.ndarray, ...]:
    """Ranges and directions in A of the scatterers in the cells of one snapshot.

    Every cell ``snap[:, j]`` is fitted as one to :data:`MAX_SOURCES` plane waves
    (the fewest that leave less than ``1 - MIN_PURITY`` of its power), the same
    direction in consecutive cells is joined into a track, and the track's
    amplitudes fitted by the range kernel give the scatterer's range.

    Parameters
    ----------
    snap : ndarray, shape ``[channel, gate]``
        One instant of every channel in ``gates`` (or any linear filter of such
        instants over slow time, the same for every cell: a Doppler cell).
    gates : array_like of int, shape ``[gate]``
        Consecutive cells of ``snap``'s columns.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m] (``z = 0``).
    wavelength : float
        [m].
    range_axis : array_like, shape ``[range]``
        Range of every cell [m] (uniform).
    fft_size : int
        The range compression's FFT length.
    window : str
        Its window.
    floor : float, optional
        Least power of a cell fitted [the squared units of ``snap``]; default
        :data:`DENSE_DYNAMIC_RANGE_DB` below the strongest cell of ``snap``.
    with_power : bool
        Also return every point's power (its track's, summed over the cells).

    Returns
    -------
    (ndarray, ndarray[, ndarray])
        Ranges ``[point]`` [m], direction cosines ``(u_x, u_y)`` in A ``[point, 2]``
        [and powers ``[point]``].
    """
    snap = np.asarray(snap)
    p = np.asarray(element_positions, dtype=float)
    r_axis = np.asarray(range_axis, dtype=float)
    g = np.asarray(gates, dtype=int)
    n_fft = int(fft_size)
    cell = float(r_axis[1] - r_axis[0])
    grid, table = direction_grid(p, wavelength)
    power = np.sum(np.abs(snap) ** 2, axis=0)
    if floor is None:
        floor = power.max() * 10 ** (-DENSE_DYNAMIC_RANGE_DB / 10)
    cells = [(_cell_sources(snap[:, j], grid, table, p, wavelength) if power[j] >= floor
              else None) for j in range(g.size)]
    sources = [[] if c is None else list(zip(c[0], c[1], strict=True)) for c in cells]
    used = [set() for _ in sources]
    pts = []
    for j, here in enumerate(sources):
        for q, (u, c) in enumerate(here):
            if q in used[j]:
                continue
            used[j].add(q)
            track = [(j, u, c)]
            while track[-1][0] + 1 < g.size:      # the same direction in the next cell
                k = track[-1][0] + 1
                nxt = [i for i, (v, _) in enumerate(sources[k])
                       if i not in used[k] and np.hypot(*(v - u)) < TRACK_DU]
                if not nxt:
                    break
                used[k].add(nxt[0])
                track.append((k, *sources[k][nxt[0]]))
            if len(track) < MIN_TRACK_CELLS:
                continue
            idx = np.array([t[0] for t in track])
            amp = np.array([t[2] for t in track])

            def kernel_misfit(r, idx=idx, amp=amp):
                k = range_kernel(g[idx] - r[0], n_fft, window)
                d = amp - np.vdot(k, amp) / np.vdot(k, k) * k
                return np.concatenate([d.real, d.imag])

            peak = g[idx[np.argmax(np.abs(amp))]]
            fit = min((least_squares(kernel_misfit, [peak + o]) for o in (-0.3, 0.3)),
                      key=lambda s: s.cost)
            rho = float(fit.x[0])
            if (np.sqrt(2.0 * fit.cost) > MAX_KERNEL_MISFIT * np.linalg.norm(amp)
                    or not g[idx[0]] - 1 <= rho <= g[idx[-1]] + 1):
                continue
            w = np.abs(amp) ** 2
            u_mean = np.sum(np.array([t[1] for t in track]) * w[:, None], axis=0) / w.sum()
            pts.append((r_axis[0] + rho * cell, u_mean, w.sum()))      # rho from cell 0
    out = (np.array([a[0] for a in pts]).reshape(-1), np.array([a[1] for a in pts]).reshape(-1, 2),
           np.array([a[2] for a in pts]).reshape(-1))
    return out if with_power else out[:2]
