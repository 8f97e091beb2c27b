"""Metrics of one stability point: the gated cube through every chain, via the pipeline.

The target's range gate ``[chirp, channel]`` from
:func:`raysim.pipeline.sources.gated_source` (the gated oracle) and the motion of
:func:`raysim.studies.stability.motion.point_motion` (pose at every TDM slot of
every chirp) are measured by :func:`raysim.measure.point.gate_metrics`, the
definition every command uses, through
:class:`raysim.pipeline.beams.Beamformer`. Metric names and units are those of
:data:`raysim.vocabulary.METRICS`:

``pseudo_velocity_mps``, ``pseudo_velocity_bins``, ``doppler_width_hz``,
``angle_error_deg``, ``map_angle_error_deg``, ``entropy_ae_nats``
    As :func:`raysim.measure.point.gate_metrics` defines them (parameters in
    docs/conventions.md); the accumulated AE map (``map_angle_error_deg``,
    ``entropy_ae_nats``) is optional.
``angle_error_worst_deg``
    The study's own metric: worst single-chirp angle error over
    :data:`ANGLE_CHIRPS` chirps spread over the frame and the chirps of
    extreme true roll, pitch and yaw (each chirp beam-scanned on its own:
    coarse scan over :data:`COARSE_FOV`, then a fine scan around its peak,
    interpolated peak).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from raysim.echoes.oracle import direction
from raysim.measure.point import PointGate, gate_metrics
from raysim.pipeline.beams import Beamformer
from raysim.pipeline.sources import Reference, gated_source
from raysim.platform.kinematics import slot_times
from raysim.processing.maps import Map, map_peak
from raysim.studies.stability.motion import point_motion
from raysim.studies.stability.point import StabilityPoint
from raysim.vocabulary import CHAIN_KEYS, ChainSpec, parse_chain, parse_chains

__all__ = ["MAP_CHAINS", "STABILITY_METRICS", "ANGLE_CHIRPS", "STRAPDOWN", "point_gate",
           "compensated_slow_time", "evaluate"]

#: Chains compared in every map (keys of :class:`raysim.vocabulary.ChainSpec`).
MAP_CHAINS = CHAIN_KEYS
#: Metrics of every chain at every point (names of :data:`raysim.vocabulary.METRICS`).
STABILITY_METRICS = ("pseudo_velocity_mps", "pseudo_velocity_bins", "doppler_width_hz",
                     "angle_error_worst_deg", "angle_error_deg", "map_angle_error_deg",
                     "entropy_ae_nats")
#: Chirps (evenly spread) whose single-chirp angle error is evaluated; the worst counts.
ANGLE_CHIRPS = 8
#: Coarse beam-scan step for the worst single-chirp angle error [rad].
COARSE_STEP = np.deg2rad(2.0)
#: Field of view of the coarse beam scan (|az|, |el| below this) [rad].
COARSE_FOV = np.deg2rad(80.0)
#: Fine beam-scan half-width and step around the coarse peak [rad].
FINE_HALF_WIDTH, FINE_STEP = np.deg2rad(2.0), np.deg2rad(0.1)
#: Which strapdown produced the navigation solution (``strapdown`` of the results).
STRAPDOWN = "raysim.pipeline.estimate.estimate_motion"


def point_gate(point: StabilityPoint) -> tuple[np.ndarray, int, float]:
    """The target's range gate of a point (its companion scatterer included).

    The radar is placed by :meth:`StabilityPoint.radar_pose` (its mounting).

    Returns
    -------
    gate : ndarray, shape ``[chirp, channel]``, complex128
        Range-compressed samples at the gate [sqrt(W)].
    bin : int
        Range bin nearest ``target_range_m`` (unpadded FFT).
    range_m : float
        Range of that bin [m].
    """
    trajectory, lever = point.radar_pose()       # the radar frame A (mounting)
    return gated_source(point.config, point.array, trajectory, point.targets,
                        range_m=point.target_range_m, lever_arm=lever, t0=point.t0_s)


def _reference(point: StabilityPoint) -> Reference:
    return Reference(point.target_range_m, point.target_az_deg, point.target_el_deg)


def _motion_times(point: StabilityPoint, chirp_times: np.ndarray) -> np.ndarray:
    """Every TDM slot of every chirp [s], chirp major (``chirp_times`` for one slot)."""
    return slot_times(chirp_times, point.array.num_slots, point.config.slot_interval).ravel()


class _Beams:
    """``beams(chirps, az, el) -> [chirp, azimuth, elevation]`` of one chain on the gate."""

    def __init__(self, spec: ChainSpec, gate: np.ndarray, gate_range: float,
                 point: StabilityPoint, motion) -> None:
        self.rc, self.r, self.point = gate[:, :, None], [gate_range], point
        self.bf = Beamformer(spec, point.array, point.config.center_wavelength,
                             motion=motion)

    def __call__(self, chirps: np.ndarray, az, el) -> np.ndarray:
        out = self.bf(self.rc[chirps], chirps, self.r, az, el, self.point.direction)
        return out[:, 0].astype(np.complex128)


def _grid(az0: float, el0: float, half: float, step: float) -> tuple[np.ndarray, np.ndarray]:
    m = int(round(half / step))
    off = np.arange(-m, m + 1) * step
    return az0 + off, el0 + off


def _single_chirp_direction(beams: _Beams, idx: np.ndarray) -> np.ndarray:
    """Interpolated beam-scan peak (az, el) [rad] of chirps ``idx``, shape ``[len(idx), 2]``."""
    coarse_az, coarse_el = _grid(0.0, 0.0, COARSE_FOV, COARSE_STEP)
    pw = np.abs(beams(idx, coarse_az, coarse_el)).reshape(idx.size, -1) ** 2
    out = np.empty((idx.size, 2))
    for j, n in enumerate(idx):
        i = int(np.argmax(pw[j]))
        a0, e0 = coarse_az[i // coarse_el.size], coarse_el[i % coarse_el.size]
        faz, fel = _grid(a0, e0, FINE_HALF_WIDTH, FINE_STEP)
        p = np.abs(beams(np.array([n]), faz, fel)[0]) ** 2
        pk = map_peak(Map(p, ("azimuth", "elevation"), {"azimuth": faz, "elevation": fel}))
        out[j] = pk["azimuth"], pk["elevation"]
    return out


def _angle_between_deg(az, el, u_true) -> np.ndarray:
    return np.rad2deg(np.arccos(np.clip(direction(az, el) @ u_true, -1.0, 1.0)))


def _angle_chirps(point: StabilityPoint, chirp_times: np.ndarray) -> np.ndarray:
    """Chirps whose worst single-chirp angle error counts, shape ``[k]`` (sorted, unique).

    :data:`ANGLE_CHIRPS` chirps evenly spread over the frame plus, for each
    true Euler angle (roll, pitch, yaw), the chirps where it is largest and
    smallest, so the worst attitude of the frame is always included.
    """
    n = chirp_times.size
    even = np.linspace(0, n - 1, ANGLE_CHIRPS + 2).round().astype(int)[1:-1]
    q = point.trajectory.states(chirp_times)[0][:, 3:]
    extremes = np.concatenate([np.argmax(q, axis=0), np.argmin(q, axis=0)])
    return np.unique(np.concatenate([even, extremes]))


def compensated_slow_time(point: StabilityPoint, chain: str | ChainSpec,
                          motion=None) -> np.ndarray:
    """Slow-time signal of the target's range gate after a chain, beamformed at the target.

    Parameters
    ----------
    point : StabilityPoint
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``.
    motion : compensation.PlatformMotion, optional
        Navigation solution at every TDM slot of every chirp;
        :func:`~raysim.studies.stability.motion.point_motion` when omitted.

    Returns
    -------
    ndarray, shape ``[chirp]``, complex128
        ``y_n(u)`` [sqrt(W)]: channel-averaged beam output towards the true
        direction through the chain, the paper chain correcting towards the
        true direction (:class:`raysim.pipeline.beams.Beamformer`).
    """
    spec = parse_chain(chain)
    gate, _, r = point_gate(point)
    if motion is None and spec.compensated:
        motion = point_motion(point, _motion_times(point, point.chirp_times()))
    beams = _Beams(spec, gate, r, point, motion)
    return beams(np.arange(gate.shape[0]), [point.target_az], [point.target_el])[:, 0, 0]


def _chain_metrics(spec: ChainSpec, gate: np.ndarray, gate_range: float, point: StabilityPoint,
                   motion, chirp_times: np.ndarray, coherent_map: bool,
                   found: list[str]) -> dict:
    if spec.name == "dpca":
        try:
            return _measure_chain(spec, gate, gate_range, point, motion, chirp_times,
                                  coherent_map, found)
        except ValueError as exc:            # displacement beyond the spare aperture
            if not str(exc).startswith("dpca:"):
                raise
            found.append(str(exc))
            return {m: float("nan") for m in STABILITY_METRICS}
    return _measure_chain(spec, gate, gate_range, point, motion, chirp_times, coherent_map,
                          found)


def _measure_chain(spec: ChainSpec, gate: np.ndarray, gate_range: float,
                   point: StabilityPoint, motion, chirp_times: np.ndarray, coherent_map: bool,
                   found: list[str]) -> dict:
    shared = gate_metrics(PointGate(gate[None], gate_range, point.config, point.array),
                          _reference(point), chain=spec, motion=motion, warnings=found,
                          accumulate=coherent_map)
    idx = _angle_chirps(point, chirp_times)
    ae = _single_chirp_direction(_Beams(spec, gate, gate_range, point, motion), idx)
    errs = _angle_between_deg(ae[:, 0], ae[:, 1], point.direction)
    out = {m: shared[m] for m in STABILITY_METRICS if m in shared}
    out["angle_error_worst_deg"] = float(errs.max())
    return {m: float(out[m]) for m in STABILITY_METRICS}


def evaluate(point: StabilityPoint, chains: Sequence[str] = MAP_CHAINS, *,
             coherent_map: bool = True) -> dict:
    """Metrics of every chain at one point.

    Parameters
    ----------
    point : StabilityPoint
    chains : sequence of str
        Chain keys (``none``, ``paper``, ``paper:published``, ``exact``, ``dpca``).
    coherent_map : bool
        Also form the accumulated AE map (``map_angle_error_deg``,
        ``entropy_ae_nats``; NaN when False). The failure criteria need only
        ``pseudo_velocity_mps`` and ``angle_error_worst_deg``.

    Returns
    -------
    dict
        ``chain key -> {metric: value}`` with the metrics of
        :data:`STABILITY_METRICS` (units in :data:`raysim.vocabulary.METRICS`;
        all NaN for ``dpca`` where the displacement over the frame exceeds the
        spare aperture), plus ``"warnings"`` (list of str, from the navigation
        solution, then ``dpca``'s price, aperture warnings and failure) and
        ``"strapdown"`` (:data:`STRAPDOWN`, or ``""`` without a compensated chain).
    """
    specs = parse_chains(chains)
    gate, _, r = point_gate(point)
    times = point.chirp_times()
    motion = point_motion(point, _motion_times(point, times)) \
        if any(s.compensated for s in specs) else None
    out: dict = {}
    chain_warnings: list[str] = []
    for spec in specs:
        found: list[str] = []
        out[spec.key] = _chain_metrics(spec, gate, r, point, motion, times, coherent_map,
                                       found)
        if spec.name == "dpca":               # its price, aperture and failure reach the map
            chain_warnings += found                # each starts with "dpca"
    out["warnings"] = (list(motion.warnings) if motion is not None else []) + chain_warnings
    out["strapdown"] = STRAPDOWN if motion is not None else ""
    return out
