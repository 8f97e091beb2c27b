"""Fidelity ladder: per geometry target, the cheapest echo model within a stated tolerance.

A geometry target (a scene object traced by PO + SBR, :mod:`raysim.echoes.po.paths`)
can be handed to the synthesis at three levels of detail:

0. ``"point"``: one scattering point carrying the coherent sum of the object's
   centres (its monostatic RCS at this aspect), at their power-weighted mean point;
1. ``"centres"``: the mesh level's scattering centres merged where two lie
   closer than :data:`MERGE_CELLS` of a resolution cell, then pruned to the
   strongest that carry all but ``(tolerance / 2)^2`` of their power (99.94 %
   at the default tolerance: an error of ``tolerance / 2`` if the dropped
   centres' echoes are orthogonal to the rest);
2. ``"mesh"``: every scattering centre of the full PO + SBR trace (today's model,
   :func:`~raysim.echoes.po.paths.cluster_terms` at the range resolution).

Levels 0 and 1 are derived from level 2 once per object and aspect and re-used
while the radar stays within ``reuse_distance`` of the pose they were made for:
only then is the PO + SBR trace of the object skipped. The saving is that trace
(seconds per car) and the synthesis of the dropped paths.

**Prediction.** A centre ``i`` moved by ``dr_i`` along the line of sight and by
``dx_i`` across it changes its echo phase by ``2 pi dr_i / dR`` over the sampled
sweep and by ``2 pi dx_i / (R theta)`` over the virtual aperture (``dR = c / 2B``
the range cell, ``R theta`` the cross-range cell, ``theta = lambda / D``); their
RMS over a uniform sweep and aperture is ``2 pi / sqrt(12)`` times the offset in
cells. To first order, and with the centres' echoes treated as orthogonal, the
relative l2 error of a reduced model is::

    e_pred^2 = sum_i |A_i|^2 (2 pi / sqrt 12)^2 ((dr_i / dR)^2 + (dx_i / (R theta))^2)
               / sum_i |A_i|^2  +  P_dropped / sum_i |A_i|^2

An object whose centres all fit well inside one cell is predicted to need only a
point; one spread over many cells needs its centres or the mesh.

**Check.** The prediction is not trusted: every level is synthesised by a direct
sum on one chirp (all samples, up to :data:`CHECK_CHANNELS` channels spread over
the array) at the trace pose and at the pose moved by ``reuse_distance`` across
the line of sight (where a re-used model still serves), and its relative l2
error against level 2 at the same pose is measured; the larger of the two
counts. ``"auto"`` keeps the cheapest level (point, then centres) whose measured
error is within the tolerance, else the mesh.

What the check cannot see: the change of the object's own scattering with
aspect. At the moved pose both models are the trace pose's centres re-projected
as frozen points, as re-projection does within a frame (level 2's own error,
:func:`~raysim.echoes.po.paths.reprojection_error`); a re-traced level 2 would
also change its centres' amplitudes, which a re-used reduced model does not.

Sionna RT 2.x has a scattering-point model of its own
(``sionna.rt.rcs.ScatteringModel``: points with an RCS and a polarisation
matrix each, traced by its ``RCSSolver``). The reduced models here are kept as
frozen complex centres instead, so that all three levels share the re-projection
and synthesis of level 2 and the check compares like with like.
"""

from __future__ import annotations

import math
import time as _time
from dataclasses import asdict, dataclass, field

import numpy as np

from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.tones import synthesize_if

__all__ = ["FIDELITY_LEVELS", "FIDELITY_MODES", "DEFAULT_FIDELITY_TOLERANCE", "CHECK_CHANNELS",
           "MERGE_CELLS", "REUSE_DISTANCE", "FidelityChoice", "FidelityLadder", "point_model",
           "centres_model", "predicted_error", "check_echo", "choose_level", "resolve_fidelity"]

#: Echo models from cheapest to fullest.
FIDELITY_LEVELS = ("point", "centres", "mesh")
#: Accepted settings: a level forced for every object, or ``"auto"``.
FIDELITY_MODES = ("auto",) + FIDELITY_LEVELS
#: Default relative l2 error of an object's echo against its mesh level (-26 dB).
DEFAULT_FIDELITY_TOLERANCE = 0.05
#: Largest number of channels the check synthesises (spread over the array).
CHECK_CHANNELS = 16
#: Centres closer than this share of a resolution cell (range and cross-range)
#: are merged into one by level 1: a phase change of at most
#: ``2 pi MERGE_CELLS = 0.063`` rad across the cube, about 1 % of amplitude.
MERGE_CELLS = 0.01
#: Default radar displacement [m] within which a reduced model is re-used
#: without tracing its object again: 0.3 deg of aspect at 10 m.
REUSE_DISTANCE = 0.05
_CELL_RMS = 2 * math.pi / math.sqrt(12.0)


def _basis(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    a = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(u, a)
    e1 /= np.linalg.norm(e1)
    return e1, np.cross(u, e1)


def _cells(offset: np.ndarray, u: np.ndarray, range_cell: float,
           cross_cell: float) -> np.ndarray:
    """Offsets ``[n, 3]`` [m] in cells: ``sqrt((dr / dR)^2 + (dx / (R theta))^2)``, ``[n]``."""
    e1, e2 = _basis(u)
    return np.sqrt((offset @ u / range_cell) ** 2
                   + ((offset @ e1) ** 2 + (offset @ e2) ** 2) / cross_cell**2)


def _merge(centre: np.ndarray, amp: np.ndarray, label: np.ndarray, radar: np.ndarray,
           wavelength: float) -> tuple[np.ndarray, np.ndarray]:
    """Centres of each label merged at their ``|A|^2``-weighted mean point.

    The echo of a centre at two-way length ``l`` carries ``A exp(+j k l)``
    (the IF convention of :mod:`raysim.synthesis`), so the merged amplitude
    ``A_g = sum_i A_i exp(j k (l_i - l_g))`` reproduces the members' sum at the
    trace pose; ``k`` of the sweep's centre frequency (``wavelength``) leaves
    the residual phase ramp over the sweep centred on zero.
    """
    m = int(label.max()) + 1
    w = np.abs(amp) ** 2 + 1e-300
    point = (np.stack([np.bincount(label, w * centre[:, i], m) for i in range(3)], 1)
             / np.bincount(label, w, m)[:, None])
    k = 2 * math.pi / wavelength
    l_i = 2 * np.linalg.norm(centre - radar, axis=1)
    l_g = 2 * np.linalg.norm(point - radar, axis=1)
    ph = amp * np.exp(1j * k * (l_i - l_g[label]))
    return point, np.bincount(label, ph.real, m) + 1j * np.bincount(label, ph.imag, m)


def point_model(centre, amplitude, radar_w, wavelength: float):
    """Level 0: one point with the coherent sum of the centres.

    Parameters
    ----------
    centre : ndarray, shape ``[centre, 3]``
        Mesh-level centres in W [m].
    amplitude : ndarray of complex, shape ``[centre]``
        Their amplitudes (any common normalisation).
    radar_w : ndarray, shape ``[3]``
        Radar phase centre in W [m].
    wavelength : float
        Of the sweep's centre frequency (``config.center_wavelength``) [m].

    Returns
    -------
    point : ndarray, shape ``[1, 3]``
    amplitude : ndarray of complex, shape ``[1]``
    label : ndarray of int, shape ``[centre]``
        All zeros (every centre goes to the point).
    """
    centre = np.asarray(centre, float)
    label = np.zeros(len(centre), np.int64)
    p, a = _merge(centre, np.asarray(amplitude, complex), label, np.asarray(radar_w, float),
                  wavelength)
    return p, a, label


def centres_model(centre, amplitude, radar_w, wavelength: float, *, range_cell: float,
                  cross_cell: float, power_share: float):
    """Level 1: the strongest centres, weak ones dropped and near ones merged.

    Centres closer than :data:`MERGE_CELLS` of a cell are merged (greedy, from the
    strongest); the weakest merged centres are dropped while their power stays
    within ``1 - power_share`` of the total ``sum |A_i|^2`` (an error of
    ``sqrt(1 - power_share)`` if their echoes are orthogonal).

    Parameters
    ----------
    centre, amplitude, radar_w, wavelength
        As :func:`point_model`.
    range_cell, cross_cell : float
        Range cell ``dR`` and cross-range cell ``R theta`` [m].
    power_share : float
        Share of the power kept, in (0, 1].

    Returns
    -------
    point : ndarray, shape ``[kept, 3]``
    amplitude : ndarray of complex, shape ``[kept]``
    label : ndarray of int, shape ``[centre]``
        Kept centre of each input centre, ``-1`` for a dropped one.
    """
    centre = np.asarray(centre, float)
    amp = np.asarray(amplitude, complex)
    radar = np.asarray(radar_w, float)
    n = len(centre)
    if n == 0:
        return np.zeros((0, 3)), np.zeros(0, complex), np.zeros(0, np.int64)
    u = np.mean(centre, axis=0) - radar
    u /= np.linalg.norm(u)
    label = np.full(n, -1, np.int64)
    groups = 0
    for i in np.argsort(-np.abs(amp)):
        if label[i] >= 0:
            continue
        near = (label < 0) & (_cells(centre - centre[i], u, range_cell, cross_cell)
                              <= MERGE_CELLS)
        label[near] = groups
        groups += 1
    point, merged = _merge(centre, amp, label, radar, wavelength)
    power = np.abs(merged) ** 2
    order = np.argsort(power)                     # weakest first
    budget = (1.0 - power_share) * float(np.sum(np.abs(amp) ** 2))
    dropped = order[np.cumsum(power[order]) <= budget]
    keep = np.ones(groups, bool)
    keep[dropped] = False
    if not keep.any():
        keep[order[-1]] = True
    new = np.cumsum(keep) - 1
    label = np.where(keep[label], new[label], -1)
    return point[keep], merged[keep], label


def predicted_error(centre, amplitude, point, label, *, range_cell: float,
                    cross_cell: float, radar_w) -> float:
    """First-order relative l2 error of a reduced model (module docstring, *Prediction*).

    Parameters
    ----------
    centre, amplitude
        Mesh-level centres ``[centre, 3]`` [m] and amplitudes ``[centre]``.
    point : ndarray, shape ``[kept, 3]``
        Reduced model's points [m].
    label : ndarray of int, shape ``[centre]``
        Reduced point of each centre, ``-1`` where dropped.
    range_cell, cross_cell : float
        ``dR`` and ``R theta`` [m].
    radar_w : ndarray, shape ``[3]``
        [m].

    Returns
    -------
    float
    """
    centre = np.asarray(centre, float)
    w = np.abs(np.asarray(amplitude)) ** 2
    total = float(np.sum(w))
    if total == 0:
        return 0.0
    u = np.mean(centre, axis=0) - np.asarray(radar_w, float)
    u /= np.linalg.norm(u)
    kept = label >= 0
    cells = _cells(centre[kept] - point[label[kept]], u, range_cell, cross_cell)
    err2 = (np.sum(w[kept] * (_CELL_RMS * cells) ** 2) + np.sum(w[~kept])) / total
    return float(math.sqrt(err2))


def check_echo(centre, amplitude, radar_w, r_wb, config: RadarConfig, array,
               channels=None) -> np.ndarray:
    """IF echo of points on one chirp at the trace pose, their tone sum (``synthesize_if``).

    ``s[m, k] = sum_p A_p exp(j 2 pi (f_c tau + mu tau t_k - mu tau^2 / 2))`` with
    ``tau = (|x_tx,m - c_p| + |x_rx,m - c_p|) / c`` (exact spherical legs, 0 dBi
    elements: the element pattern scales both models alike).

    Parameters
    ----------
    centre : ndarray, shape ``[point, 3]``
        Points in W [m].
    amplitude : ndarray of complex, shape ``[point]``
    radar_w : ndarray, shape ``[3]``
        Radar phase centre in W [m].
    r_wb : ndarray, shape ``[3, 3]``
        Attitude (A is parallel to B).
    config : RadarConfig
    array : raysim.radar.arrays.VirtualArray
    channels : array_like of int, optional
        Channels to synthesise (default: up to :data:`CHECK_CHANNELS` spread over
        the array).

    Returns
    -------
    ndarray of complex64, shape ``[channel, sample]``
    """
    if channels is None:
        channels = np.unique(np.linspace(0, array.num_channels - 1,
                                         min(CHECK_CHANNELS, array.num_channels)).round()
                             ).astype(int)
    radar = np.asarray(radar_w, float)
    tx = radar + array.tx_positions[channels] @ np.asarray(r_wb).T    # [channel, 3]
    rx = radar + array.rx_positions[channels] @ np.asarray(r_wb).T
    c = np.asarray(centre, float)
    tau = (np.linalg.norm(tx[:, None] - c[None], axis=2)
           + np.linalg.norm(rx[:, None] - c[None], axis=2)) / SPEED_OF_LIGHT   # [channel, point]
    amp = np.asarray(amplitude, complex)[:, None, None]                   # [point, 1, 1]
    return synthesize_if(tau.T[:, None, :], amp, config, workers=1)[0]


def _relative(a: np.ndarray, ref: np.ndarray) -> float:
    den = float(np.linalg.norm(ref))
    return float(np.linalg.norm(a - ref) / den) if den > 0 else 0.0


@dataclass(frozen=True)
class FidelityChoice:
    """The level chosen for one object at one trace pose, and why.

    Attributes
    ----------
    name : str
        Object (target) name.
    mode : str
        The setting (``"auto"`` or a forced level).
    level : str
        Level used.
    predicted_level : str
        Cheapest level whose predicted error is within the tolerance.
    tolerance : float
        Relative l2 error allowed.
    range_m : float
        Range of the object's reference point [m].
    extent_cells : tuple of float
        Power-weighted RMS spread of the mesh centres about their mean, along
        the line of sight in range cells and across it in cross-range cells.
    paths : dict
        Level -> number of paths.
    predicted_error, measured_error : dict
        Level -> relative l2 error of the object's echo against the mesh level.
    trace_seconds : float
        Wall time of the object's PO + SBR trace (0 when re-used) [s].
    choice_seconds : float
        Wall time of building and checking the levels [s].
    reused : bool
        Whether the model was re-used from an earlier trace pose.
    """

    name: str
    mode: str
    level: str
    predicted_level: str
    tolerance: float
    range_m: float
    extent_cells: tuple
    paths: dict
    predicted_error: dict
    measured_error: dict
    trace_seconds: float
    choice_seconds: float
    reused: bool = False

    def as_dict(self) -> dict:
        """JSON-ready copy."""
        d = asdict(self)
        d["extent_cells"] = list(self.extent_cells)
        return d


def choose_level(name: str, centre, amplitude, radar_w, r_wb, config: RadarConfig, array, *,
                 mode: str = "auto", tolerance: float = DEFAULT_FIDELITY_TOLERANCE,
                 reuse_distance: float = REUSE_DISTANCE, range_m: float | None = None,
                 trace_seconds: float = 0.0):
    """Build the three levels of one object, check them and pick one.

    Parameters
    ----------
    name : str
        Object name (for the record).
    centre : ndarray, shape ``[centre, 3]``
        Mesh-level scattering centres in W [m].
    amplitude : ndarray of complex, shape ``[centre]``
        Their amplitudes (normalised as :func:`~raysim.echoes.po.paths.cluster_terms`).
    radar_w, r_wb
        Radar phase centre in W [m] and attitude ``[3, 3]``.
    config : RadarConfig
    array : raysim.radar.arrays.VirtualArray
        Sets the cross-range cell ``R lambda / D`` and the checked channels.
    mode : {"auto", "point", "centres", "mesh"}
    tolerance : float
        Relative l2 error allowed, > 0.
    reuse_distance : float
        Radar displacement of the second checked pose [m] (0: trace pose only).
    range_m : float, optional
        Range of the reference point [m] (default: of the centres' mean).
    trace_seconds : float
        Time of the object's trace, for the record [s].

    Returns
    -------
    point : ndarray, shape ``[path, 3]``
    amplitude : ndarray of complex, shape ``[path]``
    choice : FidelityChoice
    """
    from raysim.echoes.rt.trace_plan import aperture_resolution

    if mode not in FIDELITY_MODES:
        raise ValueError(f"fidelity must be one of {FIDELITY_MODES}, got {mode!r}")
    if not (isinstance(tolerance, (int, float)) and math.isfinite(tolerance) and tolerance > 0):
        raise ValueError(f"fidelity_tolerance must be a relative error > 0, got {tolerance!r}")
    start = _time.perf_counter()
    centre = np.asarray(centre, float).reshape(-1, 3)
    amp = np.asarray(amplitude, complex).reshape(-1)
    radar = np.asarray(radar_w, float)
    mean = np.mean(centre, axis=0) if len(centre) else radar + np.array([0.0, 0.0, 1.0])
    r = float(np.linalg.norm(mean - radar)) if range_m is None else float(range_m)
    d_r = config.range_resolution
    cross = max(r, d_r) * aperture_resolution(array, config.wavelength, math.pi / 2)
    if len(centre) == 0:
        levels = {lv: (centre, amp, np.zeros(0, np.int64)) for lv in FIDELITY_LEVELS}
    else:
        levels = {"point": point_model(centre, amp, radar, config.center_wavelength),
                  "centres": centres_model(centre, amp, radar, config.center_wavelength,
                                           range_cell=d_r, cross_cell=cross,
                                           power_share=1.0 - (tolerance / 2) ** 2),
                  "mesh": (centre, amp, np.arange(len(centre)))}
    pred = {lv: predicted_error(centre, amp, p, lab, range_cell=d_r, cross_cell=cross,
                                radar_w=radar) if len(centre) else 0.0
            for lv, (p, _, lab) in levels.items()}
    poses = [radar]
    if reuse_distance > 0:
        poses.append(radar + reuse_distance * _basis((mean - radar)
                                                     / np.linalg.norm(mean - radar))[0])
    meas = dict.fromkeys(FIDELITY_LEVELS, 0.0)
    for pose in poses:
        ref = check_echo(centre, amp, pose, r_wb, config, array)
        for lv in FIDELITY_LEVELS[:-1]:
            p, a, _ = levels[lv]
            meas[lv] = max(meas[lv], _relative(check_echo(p, a, pose, r_wb, config, array),
                                               ref))
    paths = {lv: int(len(v[1])) for lv, v in levels.items()}
    predicted_level = next(lv for lv in FIDELITY_LEVELS if pred[lv] <= tolerance)
    if mode == "auto":
        level = next(lv for lv in FIDELITY_LEVELS if meas[lv] <= tolerance)
    else:
        level = mode
    spread = (0.0, 0.0)
    if len(centre):
        w = np.abs(amp) ** 2 + 1e-300
        u = (mean - radar) / np.linalg.norm(mean - radar)
        off = centre - np.average(centre, axis=0, weights=w)
        e1, e2 = _basis(u)
        spread = (float(np.sqrt(np.average((off @ u) ** 2, weights=w)) / d_r),
                  float(np.sqrt(np.average((off @ e1) ** 2 + (off @ e2) ** 2, weights=w))
                        / cross))
    choice = FidelityChoice(name, mode, level, predicted_level, float(tolerance), r, spread,
                            paths, pred, meas, float(trace_seconds),
                            _time.perf_counter() - start)
    p, a, _ = levels[level]
    return p, a, choice


@dataclass(eq=False)
class FidelityLadder:
    """Per-object echo model of the geometry targets, chosen once per object and aspect.

    Pass one instance to every trace of one scene (``MonostaticTracer(fidelity=...)``,
    ``render_scene(fidelity=...)``) so that reduced models are re-used; models
    are kept by object name and radar position (not attitude: a yaw turns the
    polarisation, which a re-used model does not follow).

    Parameters
    ----------
    array : raysim.radar.arrays.VirtualArray
        The radar's virtual array (cross-range cell and checked channels).
    mode : {"auto", "point", "centres", "mesh"}
        ``"mesh"`` is today's model for every object (nothing is checked or cached).
    tolerance : float
        Relative l2 error allowed to each object's echo against its mesh level.
    reuse_distance : float
        Radar displacement [m] within which an object's reduced model is re-used
        without tracing the object again; ``0`` traces it every time.

    Attributes
    ----------
    choices : list of FidelityChoice
        One per object and trace, in order.
    """

    array: object
    mode: str = "auto"
    tolerance: float = DEFAULT_FIDELITY_TOLERANCE
    reuse_distance: float = REUSE_DISTANCE
    choices: list = field(default_factory=list)
    _cache: dict = field(default_factory=dict, repr=False)

    def __post_init__(self) -> None:
        from raysim.radar.arrays import VirtualArray

        if not isinstance(self.array, VirtualArray):
            raise ValueError(f"array must be a VirtualArray, got {type(self.array)}")
        if self.mode not in FIDELITY_MODES:
            raise ValueError(f"fidelity must be one of {FIDELITY_MODES}, got {self.mode!r}")
        t = self.tolerance
        if not (isinstance(t, (int, float)) and math.isfinite(t) and t > 0):
            raise ValueError(f"fidelity_tolerance must be a relative error > 0, got {t!r}")
        d = self.reuse_distance
        if not (isinstance(d, (int, float)) and math.isfinite(d) and d >= 0):
            raise ValueError(f"reuse_distance must be a distance >= 0 m, got {d!r}")

    @property
    def active(self) -> bool:
        """False for ``"mesh"``: the tracer then runs exactly as without a ladder."""
        return self.mode != "mesh"

    def lookup(self, name: str, radar_w):
        """``(point, amplitude)`` of a re-usable reduced model of ``name``, else None."""
        hit = self._cache.get(name)
        if hit is None or np.linalg.norm(np.asarray(radar_w, float) - hit[0]) \
                > self.reuse_distance:
            return None
        choice = hit[3]
        self.choices.append(FidelityChoice(**{**choice.__dict__, "trace_seconds": 0.0,
                                              "choice_seconds": 0.0, "reused": True}))
        return hit[1], hit[2]

    def choose(self, name: str, centre, amplitude, radar_w, r_wb, config: RadarConfig, *,
               range_m: float, trace_seconds: float = 0.0):
        """:func:`choose_level` for one freshly traced object; records and caches the result."""
        p, a, choice = choose_level(name, centre, amplitude, radar_w, r_wb, config, self.array,
                                    mode=self.mode, tolerance=self.tolerance,
                                    reuse_distance=self.reuse_distance, range_m=range_m,
                                    trace_seconds=trace_seconds)
        self.choices.append(choice)
        if choice.level != "mesh":
            self._cache[name] = (np.asarray(radar_w, float).copy(), p, a, choice)
        else:
            self._cache.pop(name, None)
        return p, a

    def report(self) -> list[dict]:
        """The choices as JSON-ready dicts."""
        return [c.as_dict() for c in self.choices]


def resolve_fidelity(fidelity, array, tolerance: float | None = None):
    """A :class:`FidelityLadder` from a setting, or None for today's mesh model.

    Parameters
    ----------
    fidelity : str, FidelityLadder or None
        ``"mesh"`` / None (no ladder), ``"auto"``, ``"point"``, ``"centres"``, or a
        ladder (returned as is; ``tolerance`` must then be None).
    array : raysim.radar.arrays.VirtualArray
    tolerance : float, optional
        Default :data:`DEFAULT_FIDELITY_TOLERANCE`.
    """
    if isinstance(fidelity, FidelityLadder):
        if tolerance is not None:
            raise ValueError("give fidelity_tolerance to the FidelityLadder, not both")
        return fidelity if fidelity.active else None
    if fidelity is None or fidelity == "mesh":
        return None
    if fidelity not in FIDELITY_MODES:
        raise ValueError(f"fidelity must be one of {FIDELITY_MODES} or a FidelityLadder, "
                         f"got {fidelity!r}")
    return FidelityLadder(array, fidelity, DEFAULT_FIDELITY_TOLERANCE if tolerance is None
                          else tolerance)
