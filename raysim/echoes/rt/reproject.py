r"""Per-chirp, per-channel delays of frozen ray-traced paths (re-projection).

A trace gives each path's first and last interaction points for one radar
position. Re-tracing for every chirp and every virtual channel would be
expensive and, worse, incoherent: Sionna re-samples the diffuse hit points at
every trace, so clutter would decorrelate from chirp to chirp. Instead the
scattering points are frozen and only the first and last legs are re-measured
from the actual transmit and receive positions:

.. math::

    L' = L - |v_f - x_{t,0}| - |v_l - x_{r,0}| + |v_f(t) - x_t| + |v_l(t) - x_r|

with ``x_t = T(t) + R(t) (r_IR + p_tx)`` and ``x_r = T(t) + R(t) (r_IR + p_rx)``
the element world positions at the channel's transmit instant (docs/conventions.md)
and ``v(t) = v + velocity (t - t_trace)`` for moving scatterers. The middle
of a multi-bounce path is kept. For point scatterers (targets, frozen diffuse
points) this is exact.

Specular reflections are not point scatterers: the reflection point slides
over the facet as the radar moves. The frozen point is stationary to first
order (Fermat), so the frozen-vertex error is second order, about
``d^2 / h`` for a horizontal displacement ``d`` at height ``h`` above a plane
(0.17 mm, 15 deg of carrier phase at 77 GHz, for ``d = 5 cm``, ``h = 15 m``).
Single-bounce specular paths are therefore re-projected with the image
method by default (``specular="image"``):

.. math::

    L' = |x_t - M(x_r)|,\qquad M(x) = x - 2 ((x - v) \cdot n) n

with ``v`` the traced reflection point (moved with the facet's velocity) and
``n`` the facet normal. For a specular reflection the normal bisects the
traced incident and reflected legs, ``n \propto (x_{t,0} - v)/|x_{t,0} - v| +
(x_{r,0} - v)/|x_{r,0} - v|``, so it is recovered from the trace itself
(:func:`specular_normals`); for the monostatic trace it is the direction
from the reflection point to the radar. This is exact for any motion as long
as the reflection point stays on the facet's plane. Multi-bounce, diffuse and
target paths keep the frozen-vertex formula.

Element pattern: every path is weighted by the two-way amplitude gain
``sqrt(G_t(u_dep) G_r(u_arr))`` of the radar's element pattern
(``config.pattern``, :mod:`raysim.radar.pattern`), with ``u_dep`` the
direction from the radar to the first vertex and ``u_arr`` the one to the last
vertex, in frame A at each chirp's pose (the radar phase centre at the
chirp's first transmit instant). This is the only place element gains enter
a ray-traced or point-path echo: a :class:`PathSet` carries isotropic
(0 dBi) amplitudes. One direction per chirp serves all channels; the
aperture ``D`` seen from range ``R`` changes it by ``D / R`` (2 mrad for 2 cm at
10 m), a gain change of ``|d ln G / d theta| D / R`` (``cos^4`` at 60 deg:
``4 tan 60 deg * 2e-3`` = 0.06 dB).

IF band: the complex ADC only resolves beat frequencies in ``[0, f_s)``, i.e.
one-way ranges below ``RadarConfig.max_range``. Energy beyond it would alias
into the cube, so each path is either culled (``if_band="cull"``, the default:
dropped if any of its chirps/channels falls outside) or weighted by a
raised-cosine model of the anti-alias filter (``if_band="taper"``).

Many frozen-vertex paths (a clutter field) are synthesised without
materialising their ``[path, chirp, channel]`` delays
(:func:`synthesize_paths`, ``compact``), and by default with slow-time
decimation (``decimate="auto"``: exact rows on a subset of the chirps, the others
interpolated within ``decimate_tolerance``; docs/speed.md). Wind-blown clutter
keeps its frozen points but multiplies its amplitudes chirp by chirp
(``modulation``, the internal clutter motion of :mod:`raysim.echoes.ground.icm`);
such paths vary within a frame at the clutter's Doppler bandwidth and are
rendered at every chirp (no decimation).
"""

from __future__ import annotations

import functools
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from raysim.echoes.rt.trace import SPECULAR, PathSet
from raysim.platform.kinematics import element_times, element_world_positions
from raysim.platform.motion import Trajectory, stationary
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.radar.pattern import ElementPattern
from raysim.synthesis.paths import PathDelays, pose_gains
from raysim.synthesis.select import check_decimate, check_decimate_tolerance, synthesize

IF_BAND_MODES = ("cull", "taper", "none")
#: Re-projection of single-bounce specular paths: image method or frozen vertex.
SPECULAR_MODES = ("image", "frozen")
#: Frozen-vertex paths from which :func:`synthesize_paths` takes the compact way by
#: default (dense re-projection costs ``O(path x chirp x channel)`` memory traffic).
COMPACT_MIN_PATHS = 1024
#: Paths whose amplitude modulation (wind-blown clutter) is evaluated at once: bounds the
#: ``[path, chirp]`` factors to 16384 x chirps x 16 B (33 MB at 128 chirps).
MODULATION_CHUNK = 16384


@dataclass(frozen=True)
class ReprojectedPaths:
    """Delays and amplitudes of frozen paths on the ``[chirp, channel]`` grid.

    Attributes
    ----------
    tau : ndarray, shape ``[path, chirp, channel]``
        Two-way delay [s].
    amplitude : ndarray, shape ``[path, 1, 1]`` or ``[path, chirp, channel]``, complex128
        IF amplitude [sqrt(W)] (broadcastable to ``tau``).
    kept : ndarray of int, shape ``[path]``
        Indices of these paths in the source :class:`PathSet`.
    dropped_if_band : int
        Paths removed because their beat frequency left the sampled band.
    """

    tau: np.ndarray
    amplitude: np.ndarray
    kept: np.ndarray
    dropped_if_band: int = 0


def _check_common(paths: PathSet, array: VirtualArray, lever_arm) -> np.ndarray:
    if not isinstance(paths, PathSet):
        raise ValueError(f"paths must be a PathSet, got {type(paths)}")
    if not isinstance(array, VirtualArray):
        raise ValueError(f"array must be a VirtualArray, got {type(array)}")
    lever = np.asarray(lever_arm, dtype=float)
    if lever.shape != (3,) or not np.all(np.isfinite(lever)):
        raise ValueError(f"lever_arm must be 3 finite numbers [m], got {lever_arm!r}")
    return lever


def element_positions(config: RadarConfig, array: VirtualArray, trajectory: Trajectory,
                      lever_arm, *, frame: int = 0, t0: float = 0.0, chirps=None):
    """Transmit instants and tx/rx element world positions of every (chirp, channel).

    Returns
    -------
    times : ndarray, shape ``[chirp, channel]`` [s]
    x_tx, x_rx : ndarray, shape ``[chirp, channel, 3]`` [m]
    """
    times = element_times(config, array, frame, t0)
    if chirps is not None:
        times = times[np.asarray(chirps)]
    x_tx = element_world_positions(trajectory, times, array.tx_positions, lever_arm)
    if np.array_equal(array.tx_positions, array.rx_positions):
        x_rx = x_tx
    else:
        x_rx = element_world_positions(trajectory, times, array.rx_positions, lever_arm)
    return times, x_tx, x_rx


def single_bounce_specular(paths: PathSet) -> np.ndarray:
    """Mask of paths with exactly one interaction, a specular reflection, shape ``[path]``."""
    return (paths.depth == 1) & (paths.kind == SPECULAR)


def specular_normals(paths: PathSet) -> np.ndarray:
    """Facet normals of the paths' first reflection points, from the traced legs.

    The normal of a specular reflection bisects the directions from the
    reflection point ``v`` to the transmitter and to the receiver of the trace:
    ``n = (a + b) / |a + b|`` with ``a = (x_{t,0} - v) / |x_{t,0} - v|``,
    ``b = (x_{r,0} - v) / |x_{r,0} - v|``. It points to the radar's side of
    the facet. Meaningful only for specular reflections.

    Parameters
    ----------
    paths : PathSet

    Returns
    -------
    ndarray, shape ``[path, 3]``
        Unit normals in W.
    """
    a = paths.tx_position - paths.first_vertex
    b = paths.rx_position - paths.last_vertex
    n = (a / np.linalg.norm(a, axis=-1, keepdims=True)
         + b / np.linalg.norm(b, axis=-1, keepdims=True))
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def path_lengths(paths: PathSet, times: np.ndarray, x_tx: np.ndarray,
                 x_rx: np.ndarray, *, specular: str = "image") -> np.ndarray:
    """Re-projected path lengths ``L'`` for given element positions.

    Parameters
    ----------
    paths : PathSet
    times : ndarray, shape ``[chirp, channel]``
        Transmit instants [s] (moves scattering points with their velocity).
    x_tx, x_rx : ndarray, shape ``[chirp, channel, 3]``
        Transmit / receive element world positions [m].
    specular : {"image", "frozen"}
        Single-bounce specular paths: exact image method across the facet
        plane (default) or the frozen-vertex formula (second-order error).

    Returns
    -------
    ndarray, shape ``[path, chirp, channel]`` [m]
    """
    if specular not in SPECULAR_MODES:
        raise ValueError(f"specular must be one of {SPECULAR_MODES}, got {specular!r}")
    vf = paths.first_vertex[:, None, None, :]
    vl = paths.last_vertex[:, None, None, :]
    base = (paths.length - np.linalg.norm(paths.first_vertex - paths.tx_position, axis=-1)
            - np.linalg.norm(paths.last_vertex - paths.rx_position, axis=-1))
    if np.any(paths.velocity):
        dt = (times - paths.trace_time)[None, :, :, None]
        shift = paths.velocity[:, None, None, :] * dt
        vf = vf + shift
        vl = vl + shift
    out = (base[:, None, None] + np.linalg.norm(vf - x_tx[None], axis=-1)
           + np.linalg.norm(vl - x_rx[None], axis=-1))
    spec = single_bounce_specular(paths) if specular == "image" else None
    if spec is not None and np.any(spec):
        n = specular_normals(paths)[spec][:, None, None, :]            # [s, 1, 1, 3]
        v = vf[spec]                                                   # [s, 1|chirp, 1|ch, 3]
        mirrored = x_rx[None] - 2.0 * np.sum((x_rx[None] - v) * n, axis=-1,
                                             keepdims=True) * n
        out[spec] = np.linalg.norm(x_tx[None] - mirrored, axis=-1)
    return out


def pattern_amplitude(paths: PathSet, pattern: ElementPattern, trajectory: Trajectory,
                      lever_arm, chirp_times: np.ndarray) -> np.ndarray:
    """Two-way element amplitude gain of every path at every chirp's pose.

    Parameters
    ----------
    paths : PathSet
    pattern : ElementPattern
        Pattern of the transmit and of the receive elements (frame A).
    trajectory : Trajectory
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    chirp_times : ndarray, shape ``[chirp]``
        Pose instants [s] (scatterers move with their velocity to them).

    Returns
    -------
    ndarray, shape ``[path, chirp, 1]``
        ``sqrt(G_t(u_dep) G_r(u_arr))`` (linear amplitude factor).
    """
    return pose_gains(paths, pattern, trajectory, lever_arm, chirp_times)[..., None]


def if_band_weight(range_m: np.ndarray, config: RadarConfig, *, taper: float = 0.1) -> np.ndarray:
    """Raised-cosine anti-alias filter model over one-way range.

    Unity up to ``(1 - taper) max_range``, a half-cosine roll-off to zero at
    ``max_range`` and zero beyond (and for negative ranges).

    Parameters
    ----------
    range_m : ndarray
        One-way equivalent range ``L / 2`` [m].
    taper : float
        Roll-off width as a fraction of ``config.max_range``, in (0, 1).
    """
    if not 0 < taper < 1:
        raise ValueError(f"taper must be a fraction in (0, 1), got {taper!r}")
    r = np.asarray(range_m, dtype=float) / config.max_range
    x = np.clip((r - (1 - taper)) / taper, 0.0, 1.0)
    w = 0.5 * (1 + np.cos(np.pi * x))
    return np.where((r < 0) | (r >= 1), 0.0, w)


def reproject(paths: PathSet, config: RadarConfig, array: VirtualArray,
              trajectory: Trajectory | None = None, lever_arm=(0.0, 0.0, 0.0), *,
              frame: int = 0, t0: float = 0.0, chirps=None, if_band: str = "cull",
              taper: float = 0.1, specular: str = "image",
              pattern: ElementPattern | None = None) -> ReprojectedPaths:
    """Delays and element-weighted amplitudes of frozen paths for every chirp and channel.

    Parameters
    ----------
    paths : PathSet
        From :class:`raysim.echoes.rt.trace.MonostaticTracer`.
    config : RadarConfig
    array : VirtualArray
        ``tx_positions`` / ``rx_positions`` in frame A [m]; TDM slots shift the
        transmit instants by ``slot * (T_c + idle)``.
    trajectory : Trajectory, optional
        Platform motion; stationary if omitted.
    lever_arm : array_like, shape ``[3]``
        Radar origin in the body frame B [m].
    frame : int
        Frame index (chirp times ``config.chirp_times(frame, t0)``).
    t0 : float
        First chirp of frame 0 [s].
    chirps : array_like of int, optional
        Subset of chirp indices (default: all ``config.num_chirps``).
    if_band : {"cull", "taper", "none"}
        Treatment of beat frequencies outside ``[0, f_s)``: drop the path,
        weight it with :func:`if_band_weight`, or keep it (aliases).
    taper : float
        Roll-off width for ``if_band="taper"`` (fraction of ``max_range``).
    specular : {"image", "frozen"}
        Re-projection of single-bounce specular paths (see :func:`path_lengths`).
    pattern : ElementPattern, optional
        Element pattern (default ``config.pattern``); see :func:`pattern_amplitude`.

    Returns
    -------
    ReprojectedPaths
        ``tau`` of shape ``[path, chirp, channel]`` [s], ``amplitude`` of shape
        ``[path, chirp, 1]``.
    """
    lever = _check_common(paths, array, lever_arm)
    if if_band not in IF_BAND_MODES:
        raise ValueError(f"if_band must be one of {IF_BAND_MODES}, got {if_band!r}")
    trajectory = stationary() if trajectory is None else trajectory
    times, x_tx, x_rx = element_positions(config, array, trajectory, lever, frame=frame, t0=t0,
                                           chirps=chirps)
    length = path_lengths(paths, times, x_tx, x_rx, specular=specular)
    pattern = config.pattern if pattern is None else pattern
    if not isinstance(pattern, ElementPattern):
        raise ValueError(f"pattern must be an ElementPattern or None, got {type(pattern)}")
    amp = paths.amplitude[:, None, None] * pattern_amplitude(paths, pattern, trajectory, lever,
                                                             times[:, 0])
    kept = np.arange(paths.num_paths)
    dropped = 0
    if if_band == "cull" and paths.num_paths:
        r = 0.5 * length
        ok = np.all((r >= 0) & (r < config.max_range), axis=(1, 2))
        dropped = int(np.sum(~ok))
        length, amp, kept = length[ok], amp[ok], kept[ok]
    elif if_band == "taper":
        amp = amp * if_band_weight(0.5 * length, config, taper=taper)
    return ReprojectedPaths(length / SPEED_OF_LIGHT, amp, kept, dropped)


def iter_reprojected(paths: PathSet, config: RadarConfig, array: VirtualArray,
                     trajectory: Trajectory | None = None, lever_arm=(0.0, 0.0, 0.0), *,
                     path_chunk: int = 256, **options) -> Iterator[ReprojectedPaths]:
    """:func:`reproject` in chunks of ``path_chunk`` paths (bounds memory)."""
    if int(path_chunk) != path_chunk or path_chunk < 1:
        raise ValueError(f"path_chunk must be a positive integer, got {path_chunk!r}")
    for p0 in range(0, paths.num_paths, path_chunk):
        idx = np.arange(p0, min(p0 + path_chunk, paths.num_paths))
        mask = np.zeros(paths.num_paths, dtype=bool)
        mask[idx] = True
        part = reproject(paths.select(mask), config, array, trajectory, lever_arm, **options)
        yield ReprojectedPaths(part.tau, part.amplitude, idx[part.kept], part.dropped_if_band)


def synthesize_paths(paths: PathSet, config: RadarConfig, array: VirtualArray,
                     trajectory: Trajectory | None = None, lever_arm=(0.0, 0.0, 0.0), *,
                     out: np.ndarray | None = None, chirps=None, path_chunk: int = 256,
                     synthesizer=None, compact="auto", eps: float = 1e-6,
                     modulation=None, decimate="auto",
                     decimate_tolerance: float | None = None,
                     **options) -> tuple[np.ndarray, int]:
    """IF cube of frozen paths via :func:`raysim.synthesis.select.synthesize`.

    Paths whose re-projection is the frozen-vertex formula (all but the
    single-bounce specular paths of ``specular="image"``) can go the compact
    way: :meth:`raysim.synthesis.paths.PathDelays.from_pathset` with the
    element gain at every chirp's pose, rendered by ``synthesize(method="auto")``
    (the fused kernel where built), which never materialises
    ``[path, chirp, channel]`` delays. The delays and gains are those of
    :func:`reproject`; the IF-band cull tests the first and last chirp only.

    Parameters
    ----------
    paths, config, array, trajectory, lever_arm
        As for :func:`reproject`.
    out : ndarray, shape ``[chirp, channel, sample]``, complex64, optional
        Buffer added into (``chirp`` = ``len(chirps)`` when a subset is given).
    chirps : array_like of int, optional
        Chirp subset.
    path_chunk : int
        Paths re-projected at once.
    synthesizer : callable, optional
        ``f(tau, amplitude, config, out=cube)`` adding tones into ``cube`` for the
        re-projected paths; default :func:`raysim.synthesis.select.synthesize`
        (``method="auto"`` at ``eps``: tone sum for a few paths, NUFFT beyond).
    compact : "auto", bool
        Compact way for the frozen-vertex paths: always (True), never (False), or
        where at least :data:`COMPACT_MIN_PATHS` of them and no ``synthesizer``
        is given, ``if_band`` is not ``"taper"`` and ``chirps`` is a run ("auto").
    eps : float
        Requested relative error of the default synthesis and of the compact way.
    modulation : callable, optional
        ``f(first_vertex [path, 3], chirp_times [chirp]) -> (rows [n], m [n, chirp])``
        or None: complex per-chirp factors of the amplitudes of paths ``rows``
        (the wind's internal clutter motion,
        :meth:`raysim.echoes.ground.field.ClutterField.modulation`), evaluated
        at each chirp's start time; these amplitudes change from chirp to chirp,
        so the compact way renders them at every chirp (``decimate`` ignored).
    decimate : {"auto", "off"} or int
        Slow-time decimation of the compact way
        (:func:`raysim.synthesis.select.synthesize`): ``"auto"`` (default)
        interpolates chirps where the motion's spectrum and an a-posteriori check
        allow it, ``"off"`` renders every chirp exactly.
    decimate_tolerance : float, optional
        Relative error (l2 and worst chirp row) allowed to that interpolation
        against the undecimated render; default ``DECIMATION_EPS_SHARE * eps``.
    **options
        ``frame``, ``t0``, ``if_band``, ``taper``, ``specular``, ``pattern`` of
        :func:`reproject`.

    Returns
    -------
    cube : ndarray, shape ``[chirp, channel, sample]``, complex64
    dropped_if_band : int
        Paths culled for leaving the sampled beat band.
    """
    n_chirp = config.num_chirps if chirps is None else len(np.atleast_1d(chirps))
    shape = (n_chirp, array.num_channels, config.num_samples)
    if out is None:
        out = np.zeros(shape, dtype=np.complex64)
    elif out.shape != shape or out.dtype != np.complex64:
        raise ValueError(f"out must be complex64 of shape {shape}, got {out.dtype} {out.shape}")
    synth = functools.partial(synthesize, eps=eps) if synthesizer is None else synthesizer
    if not callable(synth):
        raise ValueError(f"synthesizer must be callable, got {synthesizer!r}")
    if compact not in ("auto", True, False):
        raise ValueError(f"compact must be 'auto', True or False, got {compact!r}")
    decimate = check_decimate(decimate)
    check_decimate_tolerance(decimate_tolerance, eps)
    frozen = np.ones(paths.num_paths, bool)
    if options.get("specular", "image") == "image":
        frozen = ~single_bounce_specular(paths)
    run = _chirp_run(chirps, config.num_chirps)
    if compact == "auto":
        compact = (synthesizer is None and run is not None
                   and options.get("if_band", "cull") != "taper"
                   and int(frozen.sum()) >= COMPACT_MIN_PATHS)
    dropped = 0
    times = config.chirp_times(options.get("frame", 0), options.get("t0", 0.0))
    times = times if chirps is None else times[np.asarray(chirps)]
    if compact and frozen.any():
        dropped += _synthesize_compact(paths.select(frozen), config, array, trajectory,
                                       lever_arm, out, run, eps, options,
                                       modulation=modulation, decimate=decimate,
                                       decimate_tolerance=decimate_tolerance)
        paths = paths.select(~frozen)
    for part in iter_reprojected(paths, config, array, trajectory, lever_arm,
                                 path_chunk=path_chunk, chirps=chirps, **options):
        dropped += part.dropped_if_band
        amp = part.amplitude
        if modulation is not None and part.tau.shape[0]:
            amp = np.broadcast_to(amp, part.tau.shape[:2] + (1,)).copy()
            _modulate(amp[..., 0], paths.first_vertex[part.kept], modulation, times)
        if part.tau.shape[0]:
            synth(part.tau, amp, config, out=out)
    return out, dropped


def _modulate(amplitude: np.ndarray, vertices: np.ndarray, modulation, times) -> bool:
    """``amplitude`` [path, chirp] times ``modulation``'s factors, in place, by path blocks.

    Returns whether any path was modulated."""
    modulated = False
    for a in range(0, vertices.shape[0], MODULATION_CHUNK):
        found = modulation(vertices[a:a + MODULATION_CHUNK], times)
        if found is not None and found[0].size:
            amplitude[a + found[0]] *= found[1]
            modulated = True
    return modulated


def _chirp_run(chirps, num_chirps: int) -> range | None:
    """``chirps`` as a ``range`` of consecutive chirps, or None where it is not one."""
    if chirps is None:
        return range(num_chirps)
    c = np.atleast_1d(np.asarray(chirps))
    if c.size == 0 or c.dtype.kind not in "iu" or np.any(np.diff(c) != 1) \
            or c[0] < 0 or c[-1] >= num_chirps:
        return None
    return range(int(c[0]), int(c[-1]) + 1)


def _synthesize_compact(paths: PathSet, config: RadarConfig, array: VirtualArray, trajectory,
                        lever_arm, out: np.ndarray, run: range | None, eps: float,
                        options: dict, *, modulation=None, decimate="off",
                        decimate_tolerance: float | None = None) -> int:
    """Add the frozen-vertex ``paths`` into ``out`` the compact way; return the culled count."""
    unknown = set(options) - {"frame", "t0", "if_band", "specular", "pattern", "taper"}
    if unknown:
        raise ValueError(f"unknown options {sorted(unknown)}")
    if_band = options.get("if_band", "cull")
    if if_band not in ("cull", "none"):
        raise ValueError(f"the compact way needs if_band 'cull' or 'none', got {if_band!r}")
    if run is None:
        raise ValueError("the compact way needs chirps as consecutive indices in the frame")
    src = PathDelays.from_pathset(paths, config, array, trajectory, lever_arm=lever_arm,
                                  frame=options.get("frame", 0), t0=options.get("t0", 0.0),
                                  if_band=if_band, gain="per_chirp",
                                  pattern=options.get("pattern"))
    if modulation is not None and src.num_paths:
        # wind-blown scatterers: their per-chirp amplitudes (src's own array) times the process;
        # a random process has no motion spectrum to bound a decimation by: every chirp exact
        if _modulate(src.amplitude, src.first_vertex, modulation,
                     config.chirp_times(options.get("frame", 0), options.get("t0", 0.0))):
            decimate = "off"
    if src.num_paths:
        synthesize(src, None, config, method="auto", eps=eps, out=out, chirps=run,
                   decimate=decimate, decimate_tolerance=decimate_tolerance)
    return paths.num_paths - src.num_paths
