"""Dense ground points from range-Doppler cells: the platform's sway splits the range rings.

Over a dense ground every range cell holds a ring of scatterers (the sphere of its
range cut by the ground), more than the one to three plane waves
:mod:`compensation.ground_dense` separates in one snapshot. While the platform
moves at ``v`` the scatterers of a ring spread in Doppler by ``2 v . u / lambda``:
a Doppler filter over the frame's chirp loops (Doppler beam sharpening) keeps in
each range-Doppler cell the scatterers where the ring meets an iso-Doppler cone,
fewer than the ring holds, and the same plane-wave fit and range-kernel tracks
(:func:`compensation.ground_dense.snapshot_points`) give their ranges and
directions. The filter is linear in slow time and the same for every range cell,
so a scatterer's amplitudes over consecutive cells keep the range kernel's shape;
every loop is first aligned to its slot-0 instant
(:func:`compensation.ground_dense.aligned_snapshot`), so the TDM slots' delays
enter no direction. A scatterer leaks into the Doppler cells beside its own (the
window's main lobe): of the points that agree in range and direction only the
strongest is kept.

What it cannot do: split a ring the platform does not sweep. The Doppler
resolution over a frame of ``T`` is ``lambda / (2 T)`` in ``v . u`` (0.14 m/s over
the 13.4 ms of the flights' 64 loops), so a hover's sway of 0.06-0.35 m/s splits a
ring into one to four cells, and a platform at rest not at all; a cell still
holding more scatterers than :data:`compensation.ground_dense.MAX_SOURCES` gives no
point. The array turns within a frame (tens of deg/s over 13 ms: a few tenths of a
degree): the directions are those at the frame's middle loop, whose attitude turns
them into W.
"""

from __future__ import annotations

import numpy as np
from scipy.signal import get_window

from ._checks import finite_array
from .ground_dense import TRACK_DU, aligned_snapshot, snapshot_points

__all__ = ["DOPPLER_BELOW_POINTS", "DOPPLER_DYNAMIC_RANGE_DB", "doppler_ground_directions",
           "doppler_spectra", "unseen"]

#: Window of the Doppler filter over the chirp loops (its sidelobes below the purity
#: the plane-wave fit asks: -31 dB).
DOPPLER_WINDOW = "hann"
#: Doppler cells fitted: those whose strongest ground cell lies within this of the
#: frame's strongest range-Doppler cell [dB].
DOPPLER_DYNAMIC_RANGE_DB = 40.0
#: Points of neighbouring Doppler cells closer than this in range [cells] (and
#: :data:`compensation.ground_dense.TRACK_DU` in direction) are one scatterer.
SAME_RANGE_CELLS = 1.0
#: The range-Doppler cells are added where the range cells of one snapshot give fewer
#: ground points than this a frame (the flights' sparse field of 60 scatterers: 62-98
#: over six frames; the dense fields of 200 and 600: 1-12, docs/self_calibration.md).
DOPPLER_BELOW_POINTS = 5


def unseen(points, known, cell: float) -> np.ndarray:
    """Which ``points`` ``[point, 3]`` [m] are no scatterer of ``known`` ``[known, 3]`` [m]:
    none of those lies within :data:`SAME_RANGE_CELLS` range cells (``cell`` [m]) and
    :data:`compensation.ground_dense.TRACK_DU` in direction (the same scatterer found in
    both counts once: its errors are one)."""
    p = np.asarray(points, dtype=float).reshape(-1, 3)
    q = np.asarray(known, dtype=float).reshape(-1, 3)
    if q.shape[0] == 0 or p.shape[0] == 0:
        return np.ones(p.shape[0], dtype=bool)
    rp, rq = np.linalg.norm(p, axis=1), np.linalg.norm(q, axis=1)
    near = np.abs(rp[:, None] - rq[None, :]) < SAME_RANGE_CELLS * cell
    close = np.linalg.norm(p[:, None, :] / rp[:, None, None] - q[None] / rq[:, None], axis=2)
    return ~np.any(near & (close < TRACK_DU), axis=1)


def doppler_spectra(rc, time, channel_slot=None) -> tuple[np.ndarray, int]:
    """Range-Doppler cells of a frame: every loop aligned to its slot-0 instant, filtered.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        One range-compressed frame (two or more chirp loops).
    time : array_like, shape ``[chirp * slot]``
        Transmit instant of every slot, chirp major [s].
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM transmit slot of every channel; None: one slot.

    Returns
    -------
    (ndarray, int)
        Cells ``[doppler, channel, range]`` (the windowed DFT over loops 1.., each at
        its slot-0 instant) and the middle loop of those (the instant of the
        directions).
    """
    x = np.asarray(rc)
    if x.ndim != 3 or x.shape[0] < 2:
        raise ValueError(f"rc must have shape [chirp, channel, range] with two or more "
                         f"chirps, got {x.shape}")
    loops = np.arange(1, x.shape[0])
    snaps = np.stack([aligned_snapshot(x, time, channel_slot, n) for n in loops])
    w = get_window(DOPPLER_WINDOW, loops.size, fftbins=False)
    return np.fft.fft(snaps * w[:, None, None], axis=0), int(loops[loops.size // 2])


def doppler_ground_directions(rc, element_positions, motion, *, wavelength: float,
                              range_axis, gates, channel_slot=None,
                              fft_size: int | None = None,
                              window: str = "hann") -> tuple[np.ndarray, np.ndarray, int]:
    """Ranges and directions of a frame's ground scatterers from its range-Doppler cells.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        One range-compressed frame.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m] (a planar array, ``z = 0``).
    motion : compensation.strapdown.PlatformMotion
        Motion of the frame, one pose per slot with ``channel_slot`` (its attitude at
        the middle loop turns the directions into W as the motion has it).
    wavelength : float
        [m].
    range_axis : array_like, shape ``[range]``
        Range of every cell [m] (uniform).
    gates : array_like of int
        Consecutive cells where the ground lies.
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM slot of every channel.
    fft_size, window : int, str
        The range compression's FFT length (default the cells of ``rc``) and window.

    Returns
    -------
    (ndarray, ndarray, int)
        Ranges ``[point]`` [m], unit directions ``[point, 3]`` in W as ``motion`` has
        it, and the pose (slot index of ``motion``) whose attitude turned them.
    """
    x = np.asarray(rc)
    p = finite_array("element_positions", element_positions, shape=(x.shape[1], 3))
    r_axis = np.asarray(range_axis, dtype=float)
    g = np.asarray(gates, dtype=int)
    if r_axis.shape != (x.shape[-1],) or r_axis.size < 2:
        raise ValueError(f"range_axis must hold the {x.shape[-1]} cells of rc (two or more), "
                         f"got shape {r_axis.shape}")
    if g.size and (g.min() < 0 or g.max() >= x.shape[-1]):
        raise ValueError(f"gates must lie in 0..{x.shape[-1] - 1}, got {g.min()}..{g.max()}")
    slots = 1 if channel_slot is None else int(np.max(channel_slot)) + 1
    spec, mid = doppler_spectra(x, motion.time, channel_slot)
    pose = slots * mid
    if g.size == 0:
        return np.zeros(0), np.zeros((0, 3)), pose
    spec = spec[..., g]                                          # [doppler, channel, gate]
    power = np.sum(np.abs(spec) ** 2, axis=1)                    # [doppler, gate]
    floor = power.max() * 10 ** (-DOPPLER_DYNAMIC_RANGE_DB / 10)
    n_fft = x.shape[-1] if fft_size is None else int(fft_size)
    found = [snapshot_points(spec[d], g, p, wavelength=wavelength, range_axis=r_axis,
                             fft_size=n_fft, window=window, floor=floor, with_power=True)
             for d in np.flatnonzero(power.max(axis=1) >= floor)]
    r = np.concatenate([f[0] for f in found]) if found else np.zeros(0)
    u = np.concatenate([f[1] for f in found]) if found else np.zeros((0, 2))
    pw = np.concatenate([f[2] for f in found]) if found else np.zeros(0)
    cell = float(r_axis[1] - r_axis[0])
    keep: list[int] = []
    for i in np.argsort(-pw):       # the strongest of a scatterer's Doppler cells
        if not any(abs(r[i] - r[j]) < SAME_RANGE_CELLS * cell
                   and np.hypot(*(u[i] - u[j])) < TRACK_DU for j in keep):
            keep.append(int(i))
    r, u = r[keep], u[keep]
    u_a = np.column_stack([u, np.sqrt(np.clip(1.0 - np.sum(u ** 2, axis=1), 0.0, None))])
    return r, u_a @ np.asarray(motion.attitude[pose]).T, pose
