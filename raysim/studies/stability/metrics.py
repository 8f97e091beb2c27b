"""Metrics of one stability point: the gated cube through every chain, via the pipeline.

Every chain is applied by :func:`raysim.pipeline.chains.project` (the one
place a chain name becomes beams) to the target's range gate
``[chirp, channel, 1]`` from :func:`raysim.echoes.gated.gated_cube`, with
``range_axis = [gate range]`` and the motion of
:func:`raysim.studies.stability.motion.point_motion`. Metric names and units
are those of :data:`raysim.vocabulary.METRICS`:

``pseudo_velocity_mps``, ``pseudo_velocity_bins``, ``doppler_width_hz``
    Slow-time signal of the gate in the beam towards the true direction.
``angle_error_worst_deg``
    Worst single-chirp angle error over :data:`ANGLE_CHIRPS` chirps spread
    over the frame and the chirps of extreme true roll, pitch and yaw (each
    chirp beam-scanned on its own: coarse scan, then a fine scan around its
    peak, interpolated peak).
``angle_error_deg``
    The same single-chirp error at chirp :func:`raysim.pipeline.analysis.angle_chirp`
    (``N/2 - 1``, the paper's chirp 128).
``map_angle_error_deg``, ``entropy_ae_nats``
    Peak error and image entropy of the accumulated AE map: the beams summed
    coherently over at most :data:`MAP_CHIRPS` evenly strided chirps on a
    fixed grid around the target (the paper's yaw metric).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from raysim.echoes.gated import gated_cube, nearest_range_bin
from raysim.echoes.oracle import direction
from raysim.measure.point import angle_chirp
from raysim.pipeline.chains import project
from raysim.processing.maps import Map
from raysim.processing.metrics import (
    doppler_mainlobe_width,
    image_entropy,
    map_peak,
    pseudo_velocity,
)
from raysim.studies.stability.motion import point_motion
from raysim.studies.stability.point import StabilityPoint
from raysim.vocabulary import ChainSpec, parse_chain, parse_chains

__all__ = ["MAP_CHAINS", "STABILITY_METRICS", "ANGLE_CHIRPS", "STRAPDOWN", "point_gate",
           "compensated_slow_time", "evaluate"]

#: Chains compared in every map (keys of :class:`raysim.vocabulary.ChainSpec`).
MAP_CHAINS = tuple(s.key for s in parse_chains(("none", "paper", "paper:published", "exact")))
#: Metrics of every chain at every point (names of :data:`raysim.vocabulary.METRICS`).
STABILITY_METRICS = ("pseudo_velocity_mps", "pseudo_velocity_bins", "doppler_width_hz",
                     "angle_error_worst_deg", "angle_error_deg", "map_angle_error_deg",
                     "entropy_ae_nats")
#: Chirps (evenly spread) whose single-chirp angle error is evaluated; the worst counts.
ANGLE_CHIRPS = 8
#: Half-width of the accumulated azimuth-elevation map around the target [rad].
MAP_HALF_WIDTH = np.deg2rad(24.0)
#: Step of the accumulated azimuth-elevation map [rad].
MAP_STEP = np.deg2rad(1.5)
#: At most this many chirps (evenly strided) enter the accumulated azimuth-elevation map.
MAP_CHIRPS = 64
#: Coarse beam-scan step for single-chirp angle estimates [rad].
COARSE_STEP = np.deg2rad(2.0)
#: Field of view of the coarse beam scan (|az|, |el| below this) [rad].
COARSE_FOV = np.deg2rad(80.0)
#: Fine beam-scan half-width and step around the coarse peak [rad].
FINE_HALF_WIDTH, FINE_STEP = np.deg2rad(2.0), np.deg2rad(0.1)
#: Which strapdown produced the navigation solution (``strapdown`` of the results).
STRAPDOWN = "raysim.pipeline.estimate.estimate_motion"


def point_gate(point: StabilityPoint) -> tuple[np.ndarray, int, float]:
    """The target's range gate of a point.

    Returns
    -------
    gate : ndarray, shape ``[chirp, channel]``, complex128
        Range-compressed samples at the gate [sqrt(W)].
    bin : int
        Range bin nearest ``target_range_m`` (unpadded FFT).
    range_m : float
        Range of that bin [m].
    """
    cfg = point.config
    m = nearest_range_bin(cfg, point.target_range_m)
    gate = gated_cube(cfg, point.array, point.trajectory, [point.target], range_bin=m,
                      lever_arm=point.lever_arm_m, t0=point.t0_s)
    return gate, m, float(cfg.range_axis(cfg.num_samples)[m])


class _Beams:
    """``beams(chirps, az, el) -> [chirp, azimuth, elevation]`` of one chain on the gate."""

    def __init__(self, spec: ChainSpec, gate: np.ndarray, gate_range: float,
                 point: StabilityPoint, motion) -> None:
        self.spec, self.rc, self.r = spec, gate[:, :, None], [gate_range]
        self.point, self.motion = point, motion

    def __call__(self, chirps: np.ndarray, az, el) -> np.ndarray:
        arr = self.point.array
        mot = None if self.motion is None or not self.spec.compensated else \
            self.motion.select(chirps)
        out = project(self.spec, self.rc[chirps], arr.virtual_positions,
                      wavelength=self.point.config.center_wavelength, range_axis=self.r,
                      azimuth=np.atleast_1d(az), elevation=np.atleast_1d(el), motion=mot,
                      direction=self.point.direction, grid_shape=arr.grid_shape)
        return out.data[:, 0].astype(np.complex128)


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


def _slow_time(beams: _Beams) -> np.ndarray:
    n = beams.rc.shape[0]
    return beams(np.arange(n), beams.point.target_az, beams.point.target_el)[:, 0, 0]


def compensated_slow_time(point: StabilityPoint, chain: str | ChainSpec,
                          motion=None) -> np.ndarray:
    """Slow-time signal of the target's range gate after a chain, beamformed at the target.

    Parameters
    ----------
    point : StabilityPoint
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``.
    motion : compensation.PlatformMotion, optional
        Navigation solution; :func:`~raysim.studies.stability.motion.point_motion`
        when omitted.

    Returns
    -------
    ndarray, shape ``[chirp]``, complex128
        ``y_n(u)`` [sqrt(W)]: channel-averaged beam output towards the true
        direction through the chain (:func:`raysim.pipeline.chains.project`).
    """
    spec = parse_chain(chain)
    gate, _, r = point_gate(point)
    if motion is None and spec.compensated:
        motion = point_motion(point)
    return _slow_time(_Beams(spec, gate, r, point, motion))


def _chain_metrics(beams: _Beams, chirp_times: np.ndarray, coherent_map: bool) -> dict:
    point = beams.point
    cfg = point.config
    lam = cfg.center_wavelength
    n = chirp_times.size
    u_true = point.direction
    s = _slow_time(beams)
    pv = float(pseudo_velocity(s, cfg.chirp_interval, lam))
    width = float(doppler_mainlobe_width(s, cfg.chirp_interval))
    idx = _angle_chirps(point, chirp_times)
    mid = angle_chirp(n)
    scan = np.union1d(idx, [mid])
    ae = _single_chirp_direction(beams, scan)
    errs = _angle_between_deg(ae[:, 0], ae[:, 1], u_true)
    out = {"pseudo_velocity_mps": pv, "pseudo_velocity_bins": pv / cfg.velocity_resolution,
           "doppler_width_hz": width,
           "angle_error_worst_deg": float(errs[np.isin(scan, idx)].max()),
           "angle_error_deg": float(errs[int(np.searchsorted(scan, mid))]),
           "map_angle_error_deg": math.nan, "entropy_ae_nats": math.nan}
    if not coherent_map:
        return out
    gaz, gel = _grid(point.target_az, point.target_el, MAP_HALF_WIDTH, MAP_STEP)
    sel = np.arange(0, n, max(1, -(-n // MAP_CHIRPS)))
    img = np.abs(beams(sel, gaz, gel).sum(axis=0)) ** 2             # [azimuth, elevation]
    pk = map_peak(Map(img, ("azimuth", "elevation"), {"azimuth": gaz, "elevation": gel}))
    out["map_angle_error_deg"] = float(_angle_between_deg(pk["azimuth"], pk["elevation"],
                                                          u_true))
    out["entropy_ae_nats"] = float(image_entropy(img))
    return out


def evaluate(point: StabilityPoint, chains: Sequence[str] = MAP_CHAINS, *,
             coherent_map: bool = True) -> dict:
    """Metrics of every chain at one point.

    Parameters
    ----------
    point : StabilityPoint
    chains : sequence of str
        Chain keys (``none``, ``paper``, ``paper:published``, ``exact``).
    coherent_map : bool
        Also form the accumulated AE map (``map_angle_error_deg``,
        ``entropy_ae_nats``; NaN when False). The failure criteria need only
        ``pseudo_velocity_mps`` and ``angle_error_worst_deg``.

    Returns
    -------
    dict
        ``chain key -> {metric: value}`` with the metrics of
        :data:`STABILITY_METRICS` (units in :data:`raysim.vocabulary.METRICS`),
        plus ``"warnings"`` (list of str, from the navigation solution) and
        ``"strapdown"`` (:data:`STRAPDOWN`, or ``""`` without a compensated chain).
    """
    specs = parse_chains(chains)
    gate, _, r = point_gate(point)
    times = point.chirp_times()
    motion = point_motion(point, times) if any(s.compensated for s in specs) else None
    out: dict = {}
    for spec in specs:
        out[spec.key] = _chain_metrics(_Beams(spec, gate, r, point, motion), times,
                                       coherent_map)
    out["warnings"] = list(motion.warnings) if motion is not None else []
    out["strapdown"] = STRAPDOWN if motion is not None else ""
    return out
