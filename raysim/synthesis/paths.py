"""The compact description of many echo paths: :class:`PathDelays`.

Vertex positions and lengths, not delays: ``tau[path, chirp, channel]`` is
computed one chirp and one block of channels at a time from the element
positions of every chirp (:func:`element_positions`) and never stored whole.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.radar.arrays import VirtualArray
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

__all__ = ["PathDelays", "element_positions", "pose_gains", "GAIN_MODES"]

#: Poses at which :meth:`PathDelays.from_pathset` evaluates the element gain.
GAIN_MODES = ("mid_frame", "per_chirp")


# --------------------------------------------------------------------------- sources
@dataclass(frozen=True, eq=False)
class PathDelays:
    """Compact description of propagation paths between moving array elements.

    The delay of path ``p`` at chirp ``n`` and channel ``m`` is::

        tau[p, n, m] = (|x_tx[n, m] - v_first[p, n]| + L[p, n]
                        + |v_last[p, n] - x_rx[n, m]|) / c

    i.e. the exact spherical distance from the transmit element to the first
    interaction point, the length of the path between its first and last
    interaction points, and the distance from the last one back to the receive
    element. A point target is ``v_first = v_last`` and ``L = 0``. Memory is
    ``O(path + chirp * channel)``; the ``[path, chirp, channel]`` delays are
    produced block by block by :meth:`delays`.

    Attributes
    ----------
    first_vertex : ndarray, shape ``[path, 3]`` or ``[path, chirp, 3]``
        First interaction point in the world frame W [m].
    last_vertex : ndarray, shape ``[path, 3]`` or ``[path, chirp, 3]``
        Last interaction point in W [m].
    interior_length : ndarray, shape ``[path]`` or ``[path, chirp]``
        Path length between the first and the last interaction point [m].
    amplitude : ndarray, shape ``[path]`` or ``[path, chirp]``, complex
        Complex IF amplitude of each path [sqrt(W)], without the propagation
        phase (the delay supplies it); the same for every channel.
    tx_positions : ndarray, shape ``[chirp, channel, 3]``
        World position of each channel's transmit phase centre at each chirp [m].
    rx_positions : ndarray, shape ``[chirp, channel, 3]`` or None
        Receive phase centres [m]; ``None`` means the same as ``tx_positions``
        (a monostatic-equivalent virtual array).
    velocity : ndarray, shape ``[path, 3]``, or None
        Velocity of the scattering points [m/s] (moving clutter, targets). The
        vertices then move as ``v + velocity (t - reference_time)`` with ``t``
        the channel's transmit instant, so TDM slots are exact; the vertices
        must be given as ``[path, 3]``.
    element_times : ndarray, shape ``[chirp, channel]``, or None
        Transmit instant of every (chirp, channel) [s]; required with ``velocity``.
    reference_time : float
        Time at which the vertices are given [s].
    """

    first_vertex: np.ndarray
    last_vertex: np.ndarray
    interior_length: np.ndarray
    amplitude: np.ndarray
    tx_positions: np.ndarray
    rx_positions: np.ndarray | None = None
    velocity: np.ndarray | None = None
    element_times: np.ndarray | None = None
    reference_time: float = 0.0

    def __post_init__(self) -> None:
        tx = np.asarray(self.tx_positions, dtype=np.float64)
        if tx.ndim != 3 or tx.shape[2] != 3 or 0 in tx.shape:
            raise ValueError(f"tx_positions must have shape [chirp, channel, 3], got {tx.shape}")
        n_chirp = tx.shape[0]
        rx = None
        if self.rx_positions is not None:
            rx = np.asarray(self.rx_positions, dtype=np.float64)
            if rx.shape != tx.shape:
                raise ValueError(
                    f"rx_positions shape {rx.shape} must equal tx_positions shape {tx.shape}")
        first = np.asarray(self.first_vertex, dtype=np.float64)
        last = np.asarray(self.last_vertex, dtype=np.float64)
        for name, v in (("first_vertex", first), ("last_vertex", last)):
            if not (v.ndim in (2, 3) and v.shape[-1] == 3 and v.shape[0] >= 1
                    and (v.ndim == 2 or v.shape[1] == n_chirp)):
                raise ValueError(
                    f"{name} must have shape [path, 3] or [path, {n_chirp}, 3], got {v.shape}")
        n_path = first.shape[0]
        if last.shape[0] != n_path:
            raise ValueError(
                f"last_vertex has {last.shape[0]} paths but first_vertex has {n_path}")
        length = np.asarray(self.interior_length, dtype=np.float64)
        amp = np.asarray(self.amplitude)
        if not np.iscomplexobj(amp):
            amp = amp.astype(np.complex128)
        for name, v in (("interior_length", length), ("amplitude", amp)):
            if v.shape not in ((n_path,), (n_path, n_chirp)):
                raise ValueError(
                    f"{name} must have shape [{n_path}] or [{n_path}, {n_chirp}], got {v.shape}")
        for name, v in (("first_vertex", first), ("last_vertex", last), ("tx_positions", tx),
                        ("interior_length", length), ("amplitude", amp)):
            if not np.all(np.isfinite(v)):
                raise ValueError(f"{name} contains NaN or inf values")
        if rx is not None and not np.all(np.isfinite(rx)):
            raise ValueError("rx_positions contains NaN or inf values")
        if np.any(length < 0):
            raise ValueError(f"interior_length must be >= 0 m, got min {length.min()!r}")
        vel = times = None
        if self.velocity is not None:
            vel = np.asarray(self.velocity, dtype=np.float64)
            if vel.shape != (n_path, 3) or not np.all(np.isfinite(vel)):
                raise ValueError(f"velocity must be finite with shape [{n_path}, 3] [m/s], "
                                 f"got shape {vel.shape}")
            if first.ndim != 2 or last.ndim != 2:
                raise ValueError("with velocity, first_vertex and last_vertex must have shape "
                                 f"[path, 3], got {first.shape} and {last.shape}")
            if self.element_times is None:
                raise ValueError("element_times [chirp, channel] is required with velocity")
            if not math.isfinite(self.reference_time):
                raise ValueError(f"reference_time must be finite, got {self.reference_time!r}")
        if self.element_times is not None:
            times = np.asarray(self.element_times, dtype=np.float64)
            if times.shape != tx.shape[:2] or not np.all(np.isfinite(times)):
                raise ValueError(f"element_times must be finite with shape {tx.shape[:2]} [s], "
                                 f"got shape {times.shape}")
        for name, v in (("first_vertex", first), ("last_vertex", last),
                        ("interior_length", length), ("amplitude", amp),
                        ("tx_positions", tx), ("rx_positions", rx), ("velocity", vel),
                        ("element_times", times)):
            object.__setattr__(self, name, v)

    @classmethod
    def for_array(cls, first_vertex, last_vertex, interior_length, amplitude,
                  config: RadarConfig, array: VirtualArray, trajectory=None, *,
                  lever_arm=(0.0, 0.0, 0.0), frame: int = 0, t0: float = 0.0,
                  velocity=None, reference_time: float = 0.0) -> PathDelays:
        """Paths seen by ``array`` on a moving platform (element poses per chirp).

        Parameters
        ----------
        first_vertex, last_vertex, interior_length, amplitude
            As the attributes of the class.
        config : RadarConfig
        array : VirtualArray
        trajectory : Trajectory, optional
            Body motion; stationary if omitted.
        lever_arm : array_like, shape ``[3]``
            Radar phase centre in the body frame B [m].
        frame : int
            Frame index (chirp times ``config.chirp_times(frame, t0)``).
        t0 : float
            Time of the first chirp of frame 0 [s].
        velocity : array_like, shape ``[path, 3]``, optional
            Velocity of the scattering points [m/s].
        reference_time : float
            Time at which the vertices are given [s].
        """
        from raysim.platform.kinematics import element_times

        tx, rx = element_positions(config, array, trajectory, lever_arm=lever_arm,
                                   frame=frame, t0=t0)
        times = None if velocity is None else element_times(config, array, frame, t0)
        return cls(first_vertex, last_vertex, interior_length, amplitude, tx, rx,
                   velocity=velocity, element_times=times, reference_time=reference_time)

    @classmethod
    def from_pathset(cls, paths, config: RadarConfig, array: VirtualArray, trajectory=None, *,
                     lever_arm=(0.0, 0.0, 0.0), frame: int = 0, t0: float = 0.0,
                     if_band: str = "cull", gain: str = "mid_frame",
                     pattern=None) -> PathDelays:
        """Compact form of a ray-traced :class:`raysim.echoes.rt.trace.PathSet`.

        Same delays as :func:`raysim.echoes.rt.reproject.reproject` (frozen scattering
        points, first and last legs re-measured from the moving elements,
        ``interior_length = length - |v_f - x_tx,0| - |v_l - x_rx,0|``, moving
        scattering points at each channel's transmit instant), without
        materialising ``[path, chirp, channel]``. The two-way element gain
        (``config.pattern``) is taken at the pose of every chirp as ``reproject``
        does (``gain="per_chirp"``, amplitudes ``[path, chirp]``) or at the pose of
        the frame's middle chirp (``gain="mid_frame"``, one amplitude per path,
        which slow-time decimation needs; under hover jitter of ``d theta`` a
        ``cos^q`` element changes the gain by about ``q tan(theta) d theta``).

        Parameters
        ----------
        paths : PathSet
        config, array, trajectory, lever_arm, frame, t0
            As for :meth:`for_array`.
        if_band : {"cull", "none"}
            ``"cull"`` drops paths whose one-way range leaves ``[0, max_range)``
            at the first or last chirp of the frame on any channel.
        gain : {"mid_frame", "per_chirp"}
            Pose(s) at which the element gain is evaluated (see above).
        pattern : raysim.radar.pattern.ElementPattern, optional
            Element pattern (default ``config.pattern``).
        """
        if if_band not in ("cull", "none"):
            raise ValueError(f"if_band must be 'cull' or 'none', got {if_band!r}")
        if gain not in GAIN_MODES:
            raise ValueError(f"gain must be one of {GAIN_MODES}, got {gain!r}")
        pattern = config.pattern if pattern is None else pattern
        first = np.asarray(paths.first_vertex, dtype=np.float64)
        last = np.asarray(paths.last_vertex, dtype=np.float64)
        base = (paths.length - np.linalg.norm(first - paths.tx_position, axis=-1)
                - np.linalg.norm(last - paths.rx_position, axis=-1))
        base = np.maximum(base, 0.0)
        vel = np.asarray(paths.velocity, dtype=np.float64)
        gains = _chirp_gains(paths, pattern, config, array, trajectory, lever_arm, frame, t0,
                             mid_frame=gain == "mid_frame")
        amplitude = paths.amplitude[:, None] * gains
        if gain == "mid_frame":
            amplitude = amplitude[:, 0]
        pd = cls.for_array(first, last, base, amplitude, config, array, trajectory,
                           lever_arm=lever_arm, frame=frame, t0=t0,
                           velocity=vel if np.any(vel) else None,
                           reference_time=float(paths.trace_time))
        if if_band == "none" or pd.num_paths == 0:
            return pd
        ok = np.ones(pd.num_paths, dtype=bool)
        step = max(1, 2**22 // max(pd.num_paths, 1))
        for n in sorted({0, pd.num_chirps - 1}):
            for m0 in range(0, pd.num_channels, step):
                r = 0.5 * SPEED_OF_LIGHT * pd.delays(n, slice(m0, m0 + step))
                ok &= np.all((r >= 0) & (r < config.max_range), axis=0)
        if ok.all():
            return pd
        return pd.select(ok)

    def select(self, mask: np.ndarray) -> PathDelays:
        """The paths where ``mask`` [path] (bool) is True."""
        mask = np.asarray(mask)
        if mask.shape != (self.num_paths,) or mask.dtype != bool:
            raise ValueError(f"mask must be bool of shape ({self.num_paths},), "
                             f"got {mask.dtype} {mask.shape}")
        return PathDelays(self.first_vertex[mask], self.last_vertex[mask],
                          self.interior_length[mask], self.amplitude[mask], self.tx_positions,
                          self.rx_positions,
                          None if self.velocity is None else self.velocity[mask],
                          self.element_times, self.reference_time)

    # ---------------------------------------------------------------- sizes
    @property
    def num_paths(self) -> int:
        """Number of paths."""
        return self.first_vertex.shape[0]

    @property
    def num_chirps(self) -> int:
        """Number of chirps described."""
        return self.tx_positions.shape[0]

    @property
    def num_channels(self) -> int:
        """Number of channels."""
        return self.tx_positions.shape[1]

    @property
    def shape(self) -> tuple[int, int, int]:
        """``(path, chirp, channel)`` extent of the delays described."""
        return (self.num_paths, self.num_chirps, self.num_channels)

    @property
    def nbytes(self) -> int:
        """Memory held by the description [bytes]."""
        arrays = (self.first_vertex, self.last_vertex, self.interior_length, self.amplitude,
                  self.tx_positions, self.rx_positions, self.velocity, self.element_times)
        return int(sum(a.nbytes for a in arrays if a is not None))

    # ---------------------------------------------------------------- blocks
    def _vertex(self, v: np.ndarray, n: int) -> np.ndarray:
        return v if v.ndim == 2 else v[:, n]

    def delays(self, chirp: int, channels: slice = slice(None)) -> np.ndarray:
        """Exact delays of one chirp, shape ``[channel, path]`` [s] (channel-major).

        Parameters
        ----------
        chirp : int
            Chirp index.
        channels : slice
            Channels to compute.
        """
        return self._delays(chirp, channels, _fresh)

    def _delays(self, chirp: int, channels: slice, alloc) -> np.ndarray:
        """:meth:`delays` with its arrays from ``alloc(key, shape)`` (reusable scratch)."""
        centre = self.tx_positions[chirp].mean(axis=0)       # array centroid at this chirp
        x_tx = self.tx_positions[chirp, channels] - centre           # [channel, 3]
        x_rx = x_tx if self.rx_positions is None else self.rx_positions[chirp, channels] - centre
        shape = (x_tx.shape[0], self.num_paths)
        if self.velocity is None:
            tau = self._two_way(x_tx, x_rx, chirp, None, centre, alloc("tau", shape))
        else:
            times = self.element_times[chirp, channels]
            tau = alloc("tau", shape)
            for t in np.unique(times):                               # one group per TDM slot
                idx = np.flatnonzero(times == t)
                tau[idx] = self._two_way(x_tx[idx], x_rx[idx], chirp, float(t), centre,
                                         alloc("group", (idx.size, self.num_paths)))
        length = self.interior_length if self.interior_length.ndim == 1 \
            else self.interior_length[:, chirp]
        tau += length
        tau *= 1.0 / SPEED_OF_LIGHT
        return tau

    def _prepared(self, chirp: int, t: float | None, centre: np.ndarray):
        """Vertices of one chirp relative to the array centroid, prepared for
        :func:`_distances` (cached: every channel block of a chirp reuses them).

        Returns ``(first, last, twin, back)``: ``first``/``last`` are
        ``(-2 v^T [3, path] contiguous, |v|^2 [path])`` and ``back`` indexes the
        paths whose last vertex differs from the first (``twin`` is their complement).
        """
        key = (chirp, t)
        cache = self.__dict__.setdefault("_prep_cache", {})
        hit = cache.get(key)
        if hit is not None:
            return hit
        first = self._vertex(self.first_vertex, chirp) - centre
        last = self._vertex(self.last_vertex, chirp) - centre
        if t is not None:
            shift = self.velocity * (t - self.reference_time)
            first = first + shift
            last = last + shift
        twin = np.all(first == last, axis=-1)
        back = np.flatnonzero(~twin)

        def prep(v):
            return np.ascontiguousarray(-2.0 * v.T), np.einsum("ij,ij->i", v, v)

        hit = (prep(first), prep(last[back]), twin, back)
        if len(cache) >= 4:
            cache.clear()
        cache[key] = hit
        return hit

    def _two_way(self, x_tx, x_rx, chirp, t, centre, out) -> np.ndarray:
        """``|x_tx - v_first| + |v_last - x_rx|`` [m], shape ``[channel, path]``.

        Element positions are relative to ``centre``. With a monostatic-
        equivalent array the return leg is reused for every path whose last
        vertex is its first (single-bounce paths).
        """
        first, last, twin, back = self._prepared(chirp, t, centre)
        d = _distances(x_tx, *first, out=out)
        if self.rx_positions is None:
            if back.size:
                d_back = d[:, back]
                d_back += _distances(x_rx, *last)
                d *= 2.0
                d[:, back] = d_back
            else:
                d *= 2.0
            return d
        if back.size == self.num_paths:
            d += _distances(x_rx, *last)
            return d
        d += _distances(x_rx, *self._prepared_all_last(chirp, t, centre))
        return d

    def _prepared_all_last(self, chirp, t, centre):
        key = ("last", chirp, t)
        cache = self.__dict__.setdefault("_prep_cache", {})
        hit = cache.get(key)
        if hit is None:
            last = self._vertex(self.last_vertex, chirp) - centre
            if t is not None:
                last = last + self.velocity * (t - self.reference_time)
            hit = (np.ascontiguousarray(-2.0 * last.T), np.einsum("ij,ij->i", last, last))
            if len(cache) >= 4:
                cache.clear()
            cache[key] = hit
        return hit

    def amplitudes(self, chirp: int) -> np.ndarray:
        """Complex amplitude of every path at one chirp, shape ``[path]`` [sqrt(W)]."""
        return self.amplitude if self.amplitude.ndim == 1 else self.amplitude[:, chirp]

    def dense(self) -> tuple[np.ndarray, np.ndarray]:
        """Materialise ``tau, amplitude``, each of shape ``[path, chirp, channel]``.

        Only for small descriptions (tests, references): the result has
        ``path * chirp * channel`` elements.
        """
        tau = np.stack([self.delays(n) for n in range(self.num_chirps)], axis=0)
        amp = np.stack([np.broadcast_to(self.amplitudes(n)[None, :], (self.num_channels,
                                                                      self.num_paths))
                        for n in range(self.num_chirps)], axis=0)
        return tau.transpose(2, 0, 1).copy(), amp.transpose(2, 0, 1).copy()


def _fresh(key: str, shape: tuple, dtype=np.float64) -> np.ndarray:
    """Allocator that always returns a new array (public results)."""
    return np.empty(shape, dtype)


def _distances(elements: np.ndarray, minus_2vt: np.ndarray, v2: np.ndarray,
               out: np.ndarray | None = None) -> np.ndarray:
    """``|vertex - element|`` for every pair, shape ``[element, vertex]`` [m].

    ``minus_2vt`` is ``-2 v^T`` (shape ``[3, vertex]``, contiguous) and ``v2`` is
    ``|v|^2``. Uses ``|v|^2 - 2 e.v + |e|^2`` with coordinates relative to the
    array centroid (``|e|`` a few cm), so the cancellation error is ~1e-16 of
    the range.
    """
    # three broadcast multiply-adds instead of a K=3 matrix product: BLAS would wake
    # its thread pool for every block, and the spinning threads steal the cores
    d2 = np.multiply(elements[:, 0:1], minus_2vt[0], out=out)         # [element, vertex]
    d2 += v2[None, :]
    for i in (1, 2):
        d2 += elements[:, i:i + 1] * minus_2vt[i]
    d2 += np.einsum("ij,ij->i", elements, elements)[:, None]
    np.abs(d2, out=d2)                 # rounding can leave -1e-16 |v|^2 for |v| ~ |e|
    return np.sqrt(d2, out=d2)


def element_positions(config: RadarConfig, array: VirtualArray, trajectory=None, *,
                      lever_arm=(0.0, 0.0, 0.0), frame: int = 0,
                      t0: float = 0.0) -> tuple[np.ndarray, np.ndarray | None]:
    """World positions of the transmit and receive phase centres at every chirp.

    Returns
    -------
    tx : ndarray, shape ``[chirp, channel, 3]`` [m]
    rx : ndarray, shape ``[chirp, channel, 3]`` [m], or None when the array is a
        single-slot virtual array with ``p_tx = p_rx`` (monostatic-equivalent).
    """
    from raysim.platform.kinematics import element_times, element_world_positions
    from raysim.platform.motion import stationary

    trajectory = stationary() if trajectory is None else trajectory
    lever_arm = np.asarray(lever_arm, dtype=float)
    if lever_arm.shape != (3,) or not np.all(np.isfinite(lever_arm)):
        raise ValueError(f"lever_arm must be 3 finite numbers [m], got {lever_arm!r}")
    times = element_times(config, array, frame, t0)
    tx = element_world_positions(trajectory, times, array.tx_positions, lever_arm)
    if array.num_slots == 1 and np.array_equal(array.tx_positions, array.rx_positions):
        return tx, None
    return tx, element_world_positions(trajectory, times, array.rx_positions, lever_arm)


def pose_gains(paths, pattern, trajectory, lever_arm, times) -> np.ndarray:
    """Two-way element amplitude gain ``sqrt(G_t G_r)`` of frozen paths at given poses.

    Parameters
    ----------
    paths : raysim.echoes.rt.trace.PathSet
        ``first_vertex``, ``last_vertex``, ``velocity`` (scatterers move to each
        instant) and ``trace_time`` are used.
    pattern : raysim.radar.pattern.ElementPattern
        Transmit and receive element pattern (frame A).
    trajectory : raysim.platform.motion.Trajectory
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    times : array_like, shape ``[chirp]``
        Pose instants [s].

    Returns
    -------
    ndarray, shape ``[path, chirp]``
        Directions from the radar phase centre to the first and last vertex, in frame A.
    """
    from raysim.radar.pattern import path_gain

    t = np.asarray(times, dtype=float)
    pos, rot = trajectory.pose(t)
    mats = rot.as_matrix()                                             # [chirp, 3, 3] A -> W
    origin = pos + mats @ np.asarray(lever_arm, dtype=float)           # [chirp, 3]
    shift = (np.asarray(paths.velocity, dtype=float)[:, None, :]
             * (t - paths.trace_time)[None, :, None])
    return path_gain(pattern, mats, origin,
                     np.asarray(paths.first_vertex, dtype=float)[:, None, :] + shift,
                     np.asarray(paths.last_vertex, dtype=float)[:, None, :] + shift)


def _chirp_gains(paths, pattern, config: RadarConfig, array: VirtualArray, trajectory,
                 lever_arm, frame: int, t0: float, *, mid_frame: bool) -> np.ndarray:
    """:func:`pose_gains` at every chirp's first transmit instant, shape ``[path, chirp]``
    (as :func:`raysim.echoes.rt.reproject.reproject`); with ``mid_frame`` only the middle
    chirp, shape ``[path, 1]``."""
    from raysim.platform.kinematics import element_times
    from raysim.platform.motion import stationary

    trajectory = stationary() if trajectory is None else trajectory
    t = element_times(config, array, frame, t0)[:, 0]
    if mid_frame:
        t = t[config.num_chirps // 2:config.num_chirps // 2 + 1]
    return pose_gains(paths, pattern, trajectory, lever_arm, t)
