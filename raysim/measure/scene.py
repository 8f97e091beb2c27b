"""Maps of a whole scene through one chain, their entropies and CFAR detections.

The one definition of the scene-map metrics (``scene_entropy_rd_nats``,
``scene_entropy_ra_nats``, ``scene_entropy_ae_nats``; names and units in
:data:`raysim.vocabulary.METRICS`, maths in docs/conventions.md). They differ
from the point-target metrics of the same map (:mod:`raysim.measure.point`,
``entropy_rd_nats``, ``entropy_ae_nats``): a point target's RD map is the one
beam towards the target and its AE map one range gate, while a scene's maps
cover every beam of a global grid and every gate of a range window.

Procedure (:func:`measure_scene`): the range-compressed cube
``[chirp, channel, range]`` (Hann in fast time, channel taper
:func:`channel_taper` applied) is beamformed through one chain
(:class:`raysim.pipeline.beams.Beamformer` over :func:`raysim.pipeline.chains.project`,
each TDM slot at its own pose) on the gates of the range window and
the global azimuth / elevation grid, block by block of gates
(:func:`beam_blocks`). From the beams ``[chirp, range, azimuth, elevation]``:

* ``rd`` ``[range, doppler]``: Hann-windowed Doppler power summed over all
  beams (Doppler axis as range rate, m/s);
* the coherent cube ``[range, azimuth, elevation]``: zero-Doppler
  (Hann-weighted chirp sum) beam power;
* ``ra`` ``[range, azimuth]``: the coherent cube summed over elevation;
* ``ae`` ``[azimuth, elevation]``: the coherent cube summed over the range window.

Each map's image entropy (:func:`raysim.processing.metrics.image_entropy`) is
its ``scene_entropy_<map>_nats``; ``ridge_leakage_db`` is
:func:`raysim.measure.ridge.ridge_leakage_db` of ``rd``. Discrete scatterers are
found by an ordered-statistic CFAR along range on the coherent cube
(:func:`cfar_detect`, Rohling 1983; parameters :data:`CFAR_TRAIN`,
:data:`CFAR_GUARD`, :data:`CFAR_RANK`, :data:`CFAR_THRESHOLD_DB`; the
:data:`MAX_DETECTIONS` strongest kept; its false-alarm rate in exponential
clutter :func:`cfar_pfa`);
:func:`explain_detection` gives a known point's SNR over the CFAR's noise
estimate and why it was missed (:data:`MISS_REASONS`).

The ``dpca`` chain tapers its sub-aperture, not the array: the channel taper
the cube carries is divided out again and the same window, built for the
sub-aperture's length (:func:`sub_aperture_taper`), is handed to the chain as
its weights; its plan (elements kept, gain and resolution lost) and its
warnings are kept in the measurement.

The ``paper`` chain's slow-time phase is corrected towards one direction; a
scene has no per-target angle estimate, so the correction is re-pointed per
beam: every beam ``(az, el)`` is multiplied by
``exp(-j 4 pi (dR_n(u) - dR_n(u_0)) / lambda)`` (:func:`compensation.range_change`),
i.e. the paper's per-target correction evaluated for every grid direction
``u``, with ``u_0`` :data:`BORESIGHT`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np

from raysim.measure.ridge import ridge_leakage_db
from raysim.pipeline.beams import Beamformer
from raysim.processing.maps import Map, range_compress
from raysim.processing.metrics import image_entropy
from raysim.vocabulary import MAPS, REFERENCE, ChainSpec, parse_chain

__all__ = ["SCENE_MAPS", "SCENE_METRICS", "scene_metric", "CFAR_TRAIN", "CFAR_GUARD",
           "CFAR_RANK", "cfar_noise", "cfar_pfa", "explain_detection", "MISS_REASONS",
           "CFAR_THRESHOLD_DB", "MAX_DETECTIONS", "BORESIGHT", "GRID_HALF_WIDTH_DEG",
           "GRID_STEP_DEG", "RANGE_WINDOW_M", "SPATIAL_WINDOWS", "TAYLOR_SLL_DB",
           "TAYLOR_NBAR", "SceneMeasurement", "angle_grid", "channel_taper", "sub_aperture_taper",
           "range_compressed", "beam_blocks", "cfar_detect", "measure_scene"]

#: The maps of a scene (names and dimensions from :data:`raysim.vocabulary.MAPS`).
SCENE_MAPS = ("rd", "ra", "ae")
#: Map name -> its scene entropy metric (:data:`raysim.vocabulary.METRICS`).
SCENE_METRICS = {m: f"scene_entropy_{m}_nats" for m in SCENE_MAPS}
#: CFAR: training and guard cells on each side along range. The window is wider
#: than a car's range extent (about 20 cells of 15 cm), so that an extended object
#: fills less than a quarter of the training cells and does not raise its own noise
#: estimate.
CFAR_TRAIN, CFAR_GUARD = 48, 3
#: CFAR rank: the noise is the ``CFAR_RANK``-th smallest of the ``2 CFAR_TRAIN``
#: training cells (Rohling 1983's choice, three quarters of them).
CFAR_RANK = 72
#: CFAR threshold over the noise estimate (the ordered statistic scaled to the mean
#: of exponential clutter) [dB].
CFAR_THRESHOLD_DB = 12.0
#: Detections kept per measurement (strongest first). The parking lot has 39-44
#: local maxima over the threshold with QUICK's 8 x 8 array (the cars among the
#: 9th to 32nd strongest, behind the ground's nadir return and its angular
#: sidelobes) and 145-155 with the full report's 12 x 12 array and 3 deg grid (the
#: facade corner about the 125th): all of them kept.
MAX_DETECTIONS = 256
#: Direction in A of the ``paper`` chain's own slow-time correction and tilt check
#: (straight down the radar boresight); re-pointed per beam afterwards.
BORESIGHT = (0.0, 0.0, 1.0)
#: Default global grid: azimuth and elevation ``-w .. +w`` [deg] in steps [deg].
GRID_HALF_WIDTH_DEG, GRID_STEP_DEG = 60.0, 3.0
#: Default processed range window [m].
RANGE_WINDOW_M = (12.0, 45.0)
#: Channel tapers: ``"taylor"`` (:data:`TAYLOR_SLL_DB`, :data:`TAYLOR_NBAR` along x
#: and y) or None (uniform, -13 dB sidelobes).
SPATIAL_WINDOWS = ("taylor", None)
#: Taylor taper: sidelobe level [dB below the peak] and nearly-constant sidelobes.
TAYLOR_SLL_DB, TAYLOR_NBAR = 30, 4


def scene_metric(map_name: str) -> str:
    """``"rd"`` -> ``"scene_entropy_rd_nats"``; errors name the map and the known ones."""
    try:
        return SCENE_METRICS[map_name]
    except KeyError:
        raise ValueError(f"scene map: got {map_name!r}, expected one of "
                         f"{list(SCENE_MAPS)}") from None


@dataclass(frozen=True, eq=False)
class SceneMeasurement:
    """Maps, entropies and detections of one chain (or of the stationary reference).

    Attributes
    ----------
    key : str
        A chain key (:attr:`raysim.vocabulary.ChainSpec.key`: ``none``,
        ``paper``, ``paper:published``, ``exact``) or
        :data:`raysim.vocabulary.REFERENCE` for the stationary platform.
    maps : dict
        ``"rd"`` (dims ``range, doppler``), ``"ra"`` (``range, azimuth``), ``"ae"``
        (``azimuth, elevation``) -> :class:`raysim.processing.maps.Map` of beam power [W]
        (channel-averaged beams of IF amplitudes in sqrt(W)); axes in m, m/s, rad.
    cube : ndarray, shape ``[range, azimuth, elevation]``
        Coherent (zero-Doppler, Hann-weighted) beam power [W].
    entropy : dict
        Map name -> image entropy [nats] (reported as :data:`SCENE_METRICS`).
    detections : list of dict
        CFAR detections, strongest first: ``range_m``, ``az_deg``, ``el_deg``,
        ``velocity_mps`` (range rate at the RD peak of the detection's gate),
        ``power_db`` (relative to the cube's maximum), ``position_m`` (in W, from
        the nominal radar phase centre).
    ridge_leakage_db : float
        RD power outside the zero-Doppler ridge relative to the total [dB].
    seconds : float
        Processing time [s].
    warnings : tuple of str
        The chain's guard warnings (``dpca``: ``dpca aperture``, ``dpca rotation``).
    plan : compensation.DPCAPlan or None
        ``dpca``: its sub-aperture and price; None for the other chains.
    cells : ndarray of int or None, shape ``[detection, 3]``
        Every CFAR detection's ``(range, azimuth, elevation)`` index of ``cube``
        with the default parameters, strongest first, before the
        :data:`MAX_DETECTIONS` kept (:func:`explain_detection` reuses it).
    """

    key: str
    maps: dict
    cube: np.ndarray
    entropy: dict
    detections: list
    ridge_leakage_db: float
    seconds: float
    warnings: tuple = ()
    plan: object = None
    cells: np.ndarray | None = None

    def price(self) -> dict:
        """The ``dpca`` chain's price, JSON-ready; empty for the other chains.

        ``summary`` (:meth:`compensation.DPCAPlan.summary`), ``full_shape`` and
        ``sub_shape`` (elements per axis), ``gain_loss_db`` [dB],
        ``resolution_loss`` (beamwidth growth per axis [1]),
        ``beamwidth_sub_deg`` (boresight 3 dB beamwidth per axis [deg]),
        ``residual_displacement_m`` [m], ``rotation_misplacement``
        [element spacings] and ``overlap`` [1].
        """
        p = self.plan
        if p is None:
            return {}
        return {"summary": p.summary(), "full_shape": list(p.full_shape),
                "sub_shape": list(p.sub_shape), "gain_loss_db": float(p.gain_loss_db),
                "resolution_loss": [float(v) for v in p.resolution_loss],
                "beamwidth_sub_deg": [float(np.rad2deg(v)) for v in p.beamwidth_sub],
                "residual_displacement_m": float(p.residual_displacement),
                "rotation_misplacement": float(p.rotation_misplacement),
                "overlap": float(p.overlap)}

    def metrics(self) -> dict:
        """``{metric name: value}``, names from :data:`raysim.vocabulary.METRICS`.

        ``scene_entropy_rd_nats``, ``scene_entropy_ra_nats``,
        ``scene_entropy_ae_nats`` [nats] and ``ridge_leakage_db`` [dB].
        """
        out = {SCENE_METRICS[m]: float(self.entropy[m]) for m in SCENE_MAPS}
        out["ridge_leakage_db"] = float(self.ridge_leakage_db)
        return out


def angle_grid(half_width_deg: float = GRID_HALF_WIDTH_DEG,
               step_deg: float = GRID_STEP_DEG) -> tuple[np.ndarray, np.ndarray]:
    """Azimuth and elevation axes ``k step`` within ``+-half_width`` [rad].

    Both of shape ``[angle]``; ``half_width_deg`` and ``step_deg`` in degrees.
    """
    if not 0 < step_deg <= half_width_deg <= 80:
        raise ValueError(f"need 0 < grid_step_deg <= grid_half_width_deg <= 80, got "
                         f"grid_step_deg={step_deg!r}, grid_half_width_deg={half_width_deg!r}")
    n = int(round(half_width_deg / step_deg))
    ax = np.deg2rad(np.arange(-n, n + 1) * step_deg)
    return ax, ax.copy()


def channel_taper(array, window: str | None = "taylor") -> np.ndarray:
    """Channel weights of ``array``, shape ``[channel]``, mean 1.

    ``"taylor"``: the outer product of Taylor tapers (:data:`TAYLOR_SLL_DB`,
    :data:`TAYLOR_NBAR`) along x and y of the array's grid (x index major,
    y minor); uniform for an array without a grid (``grid_shape`` None) or
    ``window=None``.
    """
    if window not in SPATIAL_WINDOWS:
        raise ValueError(f"spatial_window must be one of {list(SPATIAL_WINDOWS)}, "
                         f"got {window!r}")
    if window is None or array.grid_shape is None:
        return np.ones(array.num_channels)
    from scipy.signal.windows import taylor

    nx, ny = array.grid_shape
    ww = np.outer(taylor(nx, nbar=TAYLOR_NBAR, sll=TAYLOR_SLL_DB, norm=False),
                  taylor(ny, nbar=TAYLOR_NBAR, sll=TAYLOR_SLL_DB, norm=False)).ravel()
    return ww / ww.mean()


def sub_aperture_taper(window: str | None = "taylor"):
    """The channel taper of :func:`channel_taper`, built for a ``dpca`` sub-aperture.

    Returns None for ``window=None`` (uniform), else ``weights(index) -> [sub]``
    with ``index [sub, 2]`` the lattice indices of the sub-aperture's elements
    counted from its corner: the outer product of Taylor tapers
    (:data:`TAYLOR_SLL_DB`, :data:`TAYLOR_NBAR`) of the sub-aperture's length
    along each axis, mean 1 (the form :func:`compensation.dpca_projection`
    takes as ``weights``).
    """
    if window not in SPATIAL_WINDOWS:
        raise ValueError(f"spatial_window must be one of {list(SPATIAL_WINDOWS)}, "
                         f"got {window!r}")
    if window is None:
        return None
    from scipy.signal.windows import taylor

    def weights(index):
        i = np.asarray(index, dtype=int)
        n = i.max(axis=0) + 1
        wx, wy = (taylor(int(k), nbar=TAYLOR_NBAR, sll=TAYLOR_SLL_DB, norm=False)
                  if k > 1 else np.ones(1) for k in n)
        w = wx[i[:, 0]] * wy[i[:, 1]]
        return w / w.mean()

    return weights


def range_compressed(data: np.ndarray, taper: np.ndarray) -> np.ndarray:
    """Range-compressed cube with the channel taper applied.

    Parameters
    ----------
    data : ndarray, shape ``[chirp, channel, sample]``
        IF cube [sqrt(W)].
    taper : ndarray, shape ``[channel]``
        From :func:`channel_taper`.

    Returns
    -------
    ndarray, shape ``[chirp, channel, range]``, complex64
        :func:`raysim.processing.maps.range_compress` (Hann) times the taper.
    """
    w = np.asarray(taper, dtype=np.float32)
    if w.shape != (data.shape[1],):
        raise ValueError(f"taper must have shape [channel] = ({data.shape[1]},), "
                         f"got {w.shape}")
    return range_compress(data) * w[None, :, None]


def _repointing(spec: ChainSpec, motion, azimuth, elevation, wavelength: float) -> np.ndarray:
    """Per-beam slow-time phase of the ``paper`` chain, shape ``[chirp, 1, az, el]`` complex64.

    ``exp(-j 4 pi (dR_n(u) - dR_n(u_0)) / lambda)`` with ``u`` every grid
    direction and ``u_0`` :data:`BORESIGHT` (the direction
    :func:`raysim.pipeline.chains.project` corrected towards).
    """
    from compensation import range_change
    from compensation.geometry import grid_directions

    u = np.asarray(grid_directions(azimuth, elevation)).reshape(len(azimuth), len(elevation), 3)
    dr0 = range_change(motion, BORESIGHT, rotation_phase=spec.rotation_phase)
    dr = np.stack([np.stack([range_change(motion, u[i, j], rotation_phase=spec.rotation_phase)
                             for j in range(len(elevation))], -1)
                   for i in range(len(azimuth))], -2)                     # [chirp, az, el]
    ddr = dr - dr0[:, None, None]
    return np.exp(-4j * np.pi * ddr / wavelength).astype(np.complex64)[:, None]


def beam_blocks(beamformer, rc: np.ndarray, config, range_axis: np.ndarray,
                gates: np.ndarray, azimuth: np.ndarray, elevation: np.ndarray,
                gate_block: int, weights=None):
    """Beams of one chain over a whole frame, block by block of range gates.

    Parameters
    ----------
    beamformer : raysim.pipeline.beams.Beamformer
        The chain on the frame's array and motion (every TDM slot at its own pose).
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube of every chirp of the frame (complex64, channel
        taper applied; for ``dpca`` without it, the taper given as ``weights``).
    config : raysim.radar.config.RadarConfig
    range_axis : ndarray, shape ``[range]``
        Range of every bin of ``rc`` [m].
    gates : ndarray of int, shape ``[gate]``
        Bins of ``rc`` to beamform.
    azimuth, elevation : ndarray
        Global grid [rad].
    gate_block : int
        Gates per block.
    weights : None, array_like or callable, optional
        Channel weights handed to the chain (``dpca``: its sub-aperture taper,
        :func:`sub_aperture_taper`).

    Yields
    ------
    (ndarray of int, compensation.BeamCube)
        The block's gates and its beams ``[chirp, gate, azimuth, elevation]``.
    """
    spec = beamformer.spec
    if not (isinstance(gate_block, (int, np.integer)) and gate_block >= 1):
        raise ValueError(f"gate_block must be a positive integer, got {gate_block!r}")
    n = rc.shape[0]
    chirps = np.arange(n)
    repoint = None
    if spec.name == "paper":                    # the loop's first slot re-points each beam
        slots = beamformer.array.num_slots
        per_chirp = beamformer.motion.select(chirps * slots)
        repoint = _repointing(spec, per_chirp, azimuth, elevation, config.center_wavelength)
    for g0 in range(0, gates.size, gate_block):
        sel = gates[g0:g0 + gate_block]
        bc = beamformer.cube(rc, chirps, range_axis, azimuth, elevation,
                             direction=BORESIGHT if spec.name == "paper" else None,
                             range_gates=sel, weights=weights)
        if repoint is not None:
            bc = replace(bc, data=bc.data * repoint)
        yield sel, bc


def cfar_detect(cube: np.ndarray, *, train: int = CFAR_TRAIN, guard: int = CFAR_GUARD,
                threshold_db: float = CFAR_THRESHOLD_DB, rank: int | None = CFAR_RANK
                ) -> np.ndarray:
    """Ordered-statistic CFAR along range plus 3 x 3 x 3 local-maximum test.

    Parameters
    ----------
    cube : ndarray, shape ``[range, azimuth, elevation]``
        Non-negative power.
    train, guard : int
        Training and guard cells on each side along range.
    threshold_db : float
        Detection threshold over the noise estimate (:func:`cfar_noise`) [dB].
    rank : int or None
        Ordered statistic of the training cells (1 .. ``2 train``); None: their
        mean (cell-averaging CFAR).

    Returns
    -------
    ndarray of int, shape ``[detection, 3]``
        Indices ``(range, azimuth, elevation)``, strongest first.
    """
    from scipy.ndimage import maximum_filter

    p = np.asarray(cube, dtype=float)
    if p.ndim != 3 or np.any(p < 0):
        raise ValueError(f"cube must be a non-negative [range, azimuth, elevation] array, got "
                         f"shape {p.shape}")
    noise = cfar_noise(p, train=train, guard=guard, rank=rank)
    hit = (p > noise * 10 ** (threshold_db / 10)) & (p == maximum_filter(p, size=3,
                                                                          mode="nearest"))
    idx = np.argwhere(hit)
    order = np.argsort(-p[hit])
    return idx[order]


def _check_cfar(train, guard, rank) -> None:
    if train < 1 or guard < 0:
        raise ValueError(f"need train >= 1 and guard >= 0, got train={train!r}, guard={guard!r}")
    if rank is not None and not 1 <= rank <= 2 * train:
        raise ValueError(f"CFAR rank must be within 1..2*train = 1..{2 * train} or None "
                         f"(cell averaging), got {rank!r}")


def _rank_scale(n: int, rank: int) -> float:
    """Mean of the ``rank``-th smallest of ``n`` unit-mean exponential samples [1]."""
    return float(np.sum(1.0 / np.arange(n - rank + 1, n + 1)))


def cfar_noise(cube: np.ndarray, *, train: int = CFAR_TRAIN, guard: int = CFAR_GUARD,
               rank: int | None = CFAR_RANK) -> np.ndarray:
    """The CFAR's noise estimate of every cell (:func:`cfar_detect`).

    Ordered statistic (Rohling 1983): the ``rank``-th smallest of the ``2 train``
    training cells (``train`` each side along range beyond ``guard`` guard
    cells) divided by its mean in exponential clutter of unit mean,
    ``sum_{i=n-rank+1}^{n} 1/i`` with ``n = 2 train``, so that it estimates the
    clutter's mean power as the cell average does. Strong cells among the
    training ones (an extended object's own cells, a neighbour, a clutter edge)
    do not raise it while they are fewer than ``n - rank``.

    Parameters
    ----------
    cube : ndarray, shape ``[range, azimuth, elevation]``
        Non-negative power [W].
    train, guard : int
        Training and guard cells on each side along range.
    rank : int or None
        Ordered statistic (1 .. ``2 train``); None: the training cells' mean
        (cell-averaging CFAR).

    Returns
    -------
    ndarray, shape of ``cube``
        Noise estimate of each cell [W] (edges: the nearest cell repeated), at
        least the smallest positive float.
    """
    from scipy.ndimage import rank_filter, uniform_filter1d

    p = np.asarray(cube, dtype=float)
    _check_cfar(train, guard, rank)
    if rank is None:
        big = uniform_filter1d(p, 2 * (train + guard) + 1, axis=0, mode="nearest") * (
            2 * (train + guard) + 1)
        small = uniform_filter1d(p, 2 * guard + 1, axis=0, mode="nearest") * (2 * guard + 1)
        est = (big - small) / (2 * train)
    else:
        fp = np.ones((2 * (train + guard) + 1,) + (1,) * (p.ndim - 1), dtype=bool)
        fp[train:train + 2 * guard + 1] = False          # guard cells and the cell itself
        est = rank_filter(p, rank=rank - 1, footprint=fp, mode="nearest") / _rank_scale(
            2 * train, rank)
    return np.maximum(est, np.finfo(float).tiny)


def cfar_pfa(threshold_db: float = CFAR_THRESHOLD_DB, *, train: int = CFAR_TRAIN,
             rank: int | None = CFAR_RANK) -> float:
    """False-alarm probability of one cell in homogeneous exponential clutter [1].

    The power of a cell and of its ``n = 2 train`` independent training cells
    exponential with a common mean (Rayleigh amplitude); the cell is a hit when
    it exceeds ``T = 10^(threshold_db/10)`` times :func:`cfar_noise`. Closed
    forms (Rohling 1983): ordered statistic
    ``prod_{i=0}^{rank-1} (n - i) / (n - i + T / s)`` with ``s`` the rank's
    scale (``sum_{i=n-rank+1}^{n} 1/i``); cell averaging (``rank`` None)
    ``(1 + T/n)^(-n)``. The local-maximum test of :func:`cfar_detect` only
    lowers the rate further.
    """
    _check_cfar(train, 0, rank)
    n, t = 2 * train, 10 ** (threshold_db / 10)
    if rank is None:
        return float((1 + t / n) ** (-n))
    i = np.arange(rank)
    return float(np.prod((n - i) / (n - i + t / _rank_scale(n, rank))))


#: Why a known reflector has no detection (:func:`explain_detection`), beside ``"detected"``.
MISS_REASONS = ("outside the range window", "outside the grid", "below threshold",
                "masked by a stronger neighbour", "beyond the strongest detections kept")


def explain_detection(result: SceneMeasurement, range_m: float, az_deg: float, el_deg: float,
                      *, threshold_db: float = CFAR_THRESHOLD_DB, train: int = CFAR_TRAIN,
                      guard: int = CFAR_GUARD, max_detections: int = MAX_DETECTIONS,
                      rank: int | None = CFAR_RANK) -> dict:
    """What the CFAR of :func:`measure_scene` made of a known point: its SNR and verdict.

    The point's cell is the strongest cell of the coherent cube within one cell
    (each axis) of the grid cell nearest ``(range_m, az_deg, el_deg)``, so a
    point between grid cells is judged on its own peak.

    Parameters
    ----------
    result : SceneMeasurement
        Its ``cube`` ``[range, azimuth, elevation]`` [W] and the maps' axes (range
        [m] of the window's gates, azimuth and elevation [rad]).
    range_m : float
        Range of the point from the nominal phase centre [m].
    az_deg, el_deg : float
        Its direction [deg] (frame A at the nominal attitude).
    threshold_db, train, guard, max_detections, rank
        The CFAR's parameters (:func:`cfar_detect`) and the detections kept.

    Returns
    -------
    dict
        ``status``: ``"detected"`` or one of :data:`MISS_REASONS`;
        ``snr_db``: the cell's power over the CFAR noise estimate [dB] (None
        outside the window or the grid); ``threshold_db`` [dB]; ``cell``: the
        cell's ``(range, azimuth, elevation)`` index (None outside).
    """
    for name, v in (("range_m", range_m), ("az_deg", az_deg), ("el_deg", el_deg)):
        if not np.isfinite(v):
            raise ValueError(f"{name}: got {v!r}, expected a finite number")
    rng = np.asarray(result.maps["ra"].coords["range"], dtype=float)
    az = np.rad2deg(np.asarray(result.maps["ra"].coords["azimuth"], dtype=float))
    el = np.rad2deg(np.asarray(result.maps["ae"].coords["elevation"], dtype=float))
    out = {"status": None, "snr_db": None, "threshold_db": float(threshold_db), "cell": None}

    def half(axis):
        return 0.5 * float(np.abs(np.diff(axis[:2]))[0]) if axis.size > 1 else 0.5

    if not rng[0] - half(rng) <= range_m <= rng[-1] + half(rng):
        out["status"] = "outside the range window"
        return out
    if not (az.min() - half(az) <= az_deg <= az.max() + half(az)
            and el.min() - half(el) <= el_deg <= el.max() + half(el)):
        out["status"] = "outside the grid"
        return out
    near = [int(np.argmin(np.abs(a - v))) for a, v in ((rng, range_m), (az, az_deg),
                                                       (el, el_deg))]
    cube = np.asarray(result.cube, dtype=float)
    box = tuple(slice(max(i - 1, 0), i + 2) for i in near)
    k = np.unravel_index(int(np.argmax(cube[box])), cube[box].shape)
    cell = tuple(int(s.start + j) for s, j in zip(box, k, strict=True))
    column = cube[:, cell[1]:cell[1] + 1, cell[2]:cell[2] + 1]    # the CFAR runs along range
    noise = cfar_noise(column, train=train, guard=guard, rank=rank)[cell[0], 0, 0]
    snr = float(10 * np.log10(max(cube[cell], np.finfo(float).tiny) / noise))
    out.update(snr_db=snr, cell=list(cell))
    if not snr > threshold_db:
        out["status"] = "below threshold"
        return out
    hood = tuple(slice(max(i - 1, 0), i + 2) for i in cell)
    if cube[hood].max() > cube[cell]:
        out["status"] = "masked by a stronger neighbour"
        return out
    default = (train, guard, threshold_db, rank) == (CFAR_TRAIN, CFAR_GUARD,
                                                     CFAR_THRESHOLD_DB, CFAR_RANK)
    found = (result.cells if default and result.cells is not None else
             cfar_detect(cube, train=train, guard=guard, threshold_db=threshold_db, rank=rank))
    rank = np.nonzero(np.all(found == np.asarray(cell), axis=1))[0]
    out["status"] = ("detected" if rank.size and rank[0] < max_detections
                     else "beyond the strongest detections kept")
    return out


def measure_scene(chain, rc: np.ndarray, motion, *, config, array, azimuth: np.ndarray,
                  elevation: np.ndarray, range_window: tuple[float, float], lever_arm,
                  gate_block: int = 16, spatial_window: str | None = None,
                  subaperture=None, mounting_deg=None) -> SceneMeasurement:
    """Beams, maps, entropies, ridge leakage and detections of one chain (or the reference).

    Parameters
    ----------
    chain : str or ChainSpec
        A chain (``none``, ``paper``, ``paper:published``, ``exact``,
        ``dpca``), or :data:`raysim.vocabulary.REFERENCE` for the stationary
        platform's frame (beamformed like ``none``).
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube (:func:`range_compressed`) carrying the channel
        taper ``channel_taper(array, spatial_window)``.
    motion : compensation.PlatformMotion or None
        Pose estimate at every transmit slot of every chirp of the frame, chirp
        major, slot minor (one pose per chirp for a single-slot array); needed by
        the compensated chains, which project each TDM slot's channels with the
        pose of its own transmit instant
        (:class:`raysim.pipeline.beams.Beamformer`).
    config : raysim.radar.config.RadarConfig
    array : raysim.radar.arrays.VirtualArray
    azimuth, elevation : ndarray, shape ``[azimuth]``, ``[elevation]``
        Global grid [rad] (:func:`angle_grid`).
    range_window : (float, float)
        Processed range window [m]; beams are formed on the gates inside it.
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m] (detections are placed from it).
    gate_block : int
        Range gates beamformed at once (bounds memory).
    spatial_window : {"taylor", None}
        The channel taper ``rc`` carries (:func:`channel_taper`); ``dpca``
        divides it out and tapers its sub-aperture with the same window
        (:func:`sub_aperture_taper`). The other chains use ``rc`` as it is.
    subaperture : (int, int) or array_like of int, optional
        ``dpca``: elements per axis of its sub-aperture, or the lattice indices
        ``[sub, 2]`` of its elements (``DPCAPlan.reference_index``); default the
        largest the motion leaves; fix it to compare frames.

    mounting_deg : str or (float, float, float), optional
        Radar mounting (:mod:`raysim.platform.mounting`): the grid's directions
        are in the nominal radar frame N, detections are placed in W along
        ``R_BA u``; default ``down`` (N is W).

    Returns
    -------
    SceneMeasurement

    Raises
    ------
    ValueError
        A compensated chain without motion, a range window without a bin, or
        what the chain refuses (``dpca``: a displacement larger than the
        spare aperture).
    """
    if chain == REFERENCE:
        spec, key = parse_chain("none"), REFERENCE
    else:
        spec = parse_chain(chain)
        key = spec.key
    if spec.compensated and motion is None:
        raise ValueError(f"chain {spec.key!r} needs motion (the platform pose at every chirp)")
    t = time.perf_counter()
    n_range = rc.shape[-1]
    r_axis = config.bin_ranges(n_range)
    lo, hi = range_window
    gates = np.nonzero((r_axis >= lo) & (r_axis <= hi))[0]
    if gates.size == 0:
        raise ValueError(f"range_window {tuple(range_window)!r} m holds no range bin; expected "
                         f"a window within 0..{r_axis[-1]:.1f} m")
    az, el = np.asarray(azimuth), np.asarray(elevation)
    rd = np.zeros((gates.size, rc.shape[0]))
    cube = np.zeros((gates.size, az.size, el.size))
    rc_win = np.ascontiguousarray(rc[:, :, gates])               # the window only
    weights = None
    if spec.name == "dpca":                        # the taper goes on the sub-aperture
        taper = np.asarray(channel_taper(array, spatial_window), dtype=np.float32)
        rc_win /= taper[None, :, None]
        weights = sub_aperture_taper(spatial_window)
    local = np.arange(gates.size)
    warnings: list[str] = []
    plan = None
    bf = Beamformer(spec, array, config.center_wavelength,
                    motion=motion if spec.compensated else None, subaperture=subaperture)
    for k, bc in beam_blocks(bf, rc_win, config, r_axis[gates], local, az, el, gate_block,
                             weights=weights):
        warnings.extend(w for w in bc.warnings if w not in warnings)
        plan = getattr(bc, "plan", None) if plan is None else plan
        spec_d = bc.doppler()                                # [doppler, g, az, el]
        rd[k] = np.einsum("dgae->gd", np.abs(spec_d.astype(np.complex128)) ** 2)
        cube[k] = bc.coherent_power(window="hann")
    vel = config.velocity_axis(rc.shape[0])
    rng = r_axis[gates]
    maps = {
        "rd": Map(rd, MAPS["rd"], {"range": rng, "doppler": vel}),
        "ra": Map(cube.sum(axis=2), MAPS["ra"], {"range": rng, "azimuth": az}),
        "ae": Map(cube.sum(axis=0), MAPS["ae"], {"azimuth": az, "elevation": el}),
    }
    entropy = {m: image_entropy(maps[m].values) for m in SCENE_MAPS}
    leak = ridge_leakage_db(rd)
    detections = []
    lever = np.asarray(lever_arm, dtype=float)
    from compensation.geometry import direction
    from raysim.platform.mounting import is_default_mounting, mounting_matrix

    turn = None if is_default_mounting(mounting_deg) else mounting_matrix(mounting_deg)
    found = cfar_detect(cube)
    for gi, ai, ei in found[:MAX_DETECTIONS]:
        u = direction(az[ai], el[ei]) if turn is None else turn @ direction(az[ai], el[ei])
        d = int(np.argmax(rd[gi]))
        detections.append({
            "range_m": float(rng[gi]), "az_deg": float(np.rad2deg(az[ai])),
            "el_deg": float(np.rad2deg(el[ei])), "velocity_mps": float(vel[d]),
            "power_db": float(10 * np.log10(cube[gi, ai, ei] / cube.max())),
            "position_m": (lever + rng[gi] * u).tolist()})
    return SceneMeasurement(key, maps, cube, entropy, detections, leak,
                            time.perf_counter() - t, tuple(warnings), plan, found)
