"""Exact point-target echo model: the oracle every other echo source is tested against.

For each chirp ``n`` and virtual channel ``m`` the transmit and receive phase
centres are placed at their world positions
``x(t) = T(t) + R_WB(t) (r_IR + p)`` (docs/conventions.md) and the two-way delay is
the exact bistatic geometry ``tau = (|P - x_tx| + |P - x_rx|) / c``. The IF
phase is ``2 pi (f_c tau + mu tau t - mu tau^2 / 2)``.

Approximations, all documented and all small for a hovering drone:

* stop-and-hop (default): pose and target position are frozen at the start of
  each transmit slot; ``intra_chirp=True`` evaluates them at every sample.
* the target position is taken at the transmit instant, not at the instant
  of reflection (error ``v tau``, under 1 um for 10 m/s at 30 m);
* isotropic element patterns with a constant gain by default (``pattern=None``);
  the amplitude follows the radar equation with the actual one-way ranges of
  each chirp and channel. ``pattern=`` (an
  :class:`raysim.radar.pattern.ElementPattern`, e.g. ``config.pattern``) replaces
  the constant ``G_t G_r`` by the pattern's gains towards the target from each
  transmit and receive element, in frame A at each instant, as the ray-traced
  echoes get them. Every pipeline source passes ``config.pattern`` (the
  scenario's ``[radar] element_pattern``); a ``"constant"`` pattern at
  ``config.antenna_gain_dbi`` takes the constant-gain branch, so such a
  scenario renders bit-identically to ``pattern=None``;
* free space, no multipath (that is the ray tracer's job).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from compensation.geometry import az_el, direction  # noqa: F401  (one definition of u(az, el))
from raysim.platform.kinematics import element_times, element_world_positions
from raysim.platform.motion import Trajectory, stationary
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import (
    BOLTZMANN,
    RCS_DBSM_RANGE,
    SPEED_OF_LIGHT,
    T0_KELVIN,
    RadarConfig,
    check_in_range,
)
from raysim.synthesis.frame import RadarFrame, adc_samples
from raysim.synthesis.tones import synthesize_if, synthesize_if_intrachirp


@dataclass(frozen=True)
class PointTarget:
    """A point scatterer in the world frame W.

    Attributes
    ----------
    position : ndarray, shape ``[3]``
        Position at ``t = 0`` in W (NED) [m].
    velocity : ndarray, shape ``[3]``
        Constant velocity in W [m/s].
    rcs_dbsm : float
        Radar cross-section [dBsm], within
        :data:`raysim.radar.config.RCS_DBSM_RANGE` (-250 to 100 dBsm).
    """

    position: np.ndarray
    velocity: np.ndarray = field(default_factory=lambda: np.zeros(3))
    rcs_dbsm: float = 10.0

    def __post_init__(self) -> None:
        for name in ("position", "velocity"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be 3 finite numbers [m or m/s], got {v!r}")
            object.__setattr__(self, name, v)
        object.__setattr__(self, "rcs_dbsm",
                           check_in_range("rcs_dbsm", self.rcs_dbsm, RCS_DBSM_RANGE, "dBsm"))

    @classmethod
    def at(cls, range_m: float, az: float, el: float, *, velocity=(0.0, 0.0, 0.0),
           rcs_dbsm: float = 10.0, radar_origin=(0.0, 0.0, 0.0)) -> PointTarget:
        """Target at a range [m] and direction (az, el) [rad] from the nominal radar pose.

        At the nominal attitude frame A is parallel to W, so the direction is
        taken in W; ``radar_origin`` is the radar phase centre in W [m].
        """
        if not math.isfinite(range_m) or range_m <= 0:
            raise ValueError(f"range_m must be a positive distance in metres, got {range_m!r}")
        pos = np.asarray(radar_origin, dtype=float) + range_m * direction(az, el)
        return cls(pos, np.asarray(velocity, dtype=float), rcs_dbsm)

    def position_at(self, t: np.ndarray) -> np.ndarray:
        """Position at times ``t`` [s], shape ``t.shape + (3,)`` [m]."""
        t = np.asarray(t, dtype=float)
        return self.position + t[..., None] * self.velocity


def radar_equation_amplitude(config: RadarConfig, range_tx, range_rx, rcs_dbsm: float):
    """IF amplitude ``sqrt(P_r)`` [sqrt(W)] from the bistatic radar equation.

    ``P_r = P_t G_t G_r lambda^2 sigma / ((4 pi)^3 R_tx^2 R_rx^2)``.
    """
    pt = 10 ** (config.tx_power_dbm / 10) * 1e-3
    g = 10 ** (config.antenna_gain_dbi / 10)
    sigma = 10 ** (rcs_dbsm / 10)
    lam = config.wavelength
    pr = pt * g * g * lam**2 * sigma / ((4 * np.pi) ** 3 * np.asarray(range_tx) ** 2
                                        * np.asarray(range_rx) ** 2)
    return np.sqrt(pr)


def noise_power(config: RadarConfig) -> float:
    """Thermal noise power per complex IF sample ``k T0 F f_s`` [W]."""
    return BOLTZMANN * T0_KELVIN * 10 ** (config.noise_figure_db / 10) * config.sample_rate


def _pattern_factor(pattern, trajectory: Trajectory, times: np.ndarray, p: np.ndarray,
                    x_tx: np.ndarray, x_rx: np.ndarray) -> np.ndarray:
    """``sqrt(G_t G_r) / G_const`` towards ``p`` from the elements, frame A at ``times``."""
    from raysim.radar.pattern import two_way_gain

    uniq, inverse = np.unique(times, return_inverse=True)
    mats = trajectory.attitude(uniq).as_matrix()[inverse.reshape(times.shape)]  # A -> W
    u_tx = np.einsum("...ji,...j->...i", mats, p - x_tx)                         # W -> A
    u_rx = np.einsum("...ji,...j->...i", mats, p - x_rx)
    return np.sqrt(two_way_gain(pattern, u_tx, u_rx))


def point_target_delays(config: RadarConfig, array: VirtualArray, trajectory: Trajectory,
                        targets, *, lever_arm=(0.0, 0.0, 0.0), frame: int = 0, t0: float = 0.0,
                        intra_chirp: bool = False, pattern=None):
    """Exact two-way delays and radar-equation amplitudes of point targets.

    ``pattern`` (:class:`raysim.radar.pattern.ElementPattern`, optional) gives
    each transmit and receive element its gain towards the target in frame A;
    ``None``, or a :class:`~raysim.radar.pattern.ConstantGain` at
    ``config.antenna_gain_dbi``, keeps the constant gain (computed without a
    pattern factor, so the two are bit-identical).

    Returns
    -------
    tau : ndarray, shape ``[target, chirp, channel]`` [s]
        With ``intra_chirp`` a trailing ``sample`` axis is added.
    amplitude : ndarray, same shape as ``tau`` [sqrt(W)]
    """
    from raysim.radar.pattern import ConstantGain, ElementPattern

    if pattern is not None and not isinstance(pattern, ElementPattern):
        raise ValueError(f"pattern must be an ElementPattern or None, got {type(pattern)}")
    if isinstance(pattern, ConstantGain) and pattern.gain_dbi == config.antenna_gain_dbi:
        pattern = None               # the radar equation's constant gain, exactly
    targets = list(targets)
    if not targets:
        raise ValueError("targets is empty: give at least one PointTarget")
    lever_arm = np.asarray(lever_arm, dtype=float)
    if lever_arm.shape != (3,) or not np.all(np.isfinite(lever_arm)):
        raise ValueError(f"lever_arm must be 3 finite numbers [m], got {lever_arm!r}")
    times = element_times(config, array, frame, t0)
    if intra_chirp:
        times = times[..., None] + config.fast_time()
    x_tx = element_world_positions(trajectory, times, array.tx_positions, lever_arm)
    virtual = array.num_slots == 1 and np.array_equal(array.tx_positions, array.rx_positions)
    x_rx = x_tx if virtual else element_world_positions(trajectory, times, array.rx_positions,
                                                        lever_arm)
    taus, amps = [], []
    for tgt in targets:
        p = tgt.position_at(times)
        r_tx = np.linalg.norm(p - x_tx, axis=-1)
        r_rx = r_tx if virtual else np.linalg.norm(p - x_rx, axis=-1)
        config.check_range(0.5 * (r_tx + r_rx).max(), "point-target range")
        taus.append((r_tx + r_rx) / SPEED_OF_LIGHT)
        amp = radar_equation_amplitude(config, r_tx, r_rx, tgt.rcs_dbsm)
        if pattern is not None:
            amp = amp / 10 ** (config.antenna_gain_dbi / 10) * _pattern_factor(
                pattern, trajectory, times, p, x_tx, x_rx)
        amps.append(amp)
    return np.stack(taus), np.stack(amps)


#: Peak memory of a frame of the oracle in units of its complex64 cube (tracemalloc on
#: a [64, 64, 600] frame: 1.10 without noise, 1.50 with the blocked noise).
FRAME_PEAK_FACTOR = 1.6
#: Extra peak of intra-chirp motion per cube element [bytes] (tracemalloc, same frame:
#: 129 B, a rotation and a position per (chirp, channel, sample) in float64).
INTRA_CHIRP_BYTES_PER_ELEMENT = 130
#: Chirps of noise drawn at a time (bounds the noise's extra memory).
NOISE_BLOCK_CHIRPS = 16


def check_frame_memory(config: RadarConfig, array, num_targets: int, *,
                       intra_chirp: bool = False) -> None:
    """Refuse, before allocating, a frame whose peak memory exceeds what is available."""
    from raysim.resources import check_memory, cube_bytes

    n = config.num_chirps * array.num_channels * config.num_samples
    peak = FRAME_PEAK_FACTOR * cube_bytes(config.num_chirps, array.num_channels,
                                          config.num_samples)
    peak += 16.0 * max(int(num_targets), 1) * config.num_chirps * array.num_channels
    if intra_chirp:
        peak += INTRA_CHIRP_BYTES_PER_ELEMENT * n
    check_memory(peak, f"a frame [{config.num_chirps}, {array.num_channels}, "
                       f"{config.num_samples}]" + (" with intra-chirp motion" if intra_chirp
                                                    else ""),
                 "radar.num_chirps, the array size or the sample rate")


def add_noise(data: np.ndarray, config: RadarConfig, seed: int | None) -> None:
    """Add complex white thermal noise of power ``k T0 F f_s`` per sample, in place.

    Drawn in float32 blocks of :data:`NOISE_BLOCK_CHIRPS` chirps, so its extra
    memory is a small fraction of the cube; the same seed gives the same noise.
    """
    rng = np.random.default_rng(seed)
    sigma = np.float32(np.sqrt(noise_power(config) / 2.0))
    for c in range(0, data.shape[0], NOISE_BLOCK_CHIRPS):
        blk = data[c:c + NOISE_BLOCK_CHIRPS]
        pair = rng.standard_normal(blk.shape + (2,), dtype=np.float32)
        pair *= sigma
        blk += pair.view(np.complex64)[..., 0]


def simulate_point_targets(config: RadarConfig, array: VirtualArray, targets,
                           trajectory: Trajectory | None = None, *, lever_arm=(0.0, 0.0, 0.0),
                           frame: int = 0, t0: float = 0.0, intra_chirp: bool = False,
                           noise: bool = False, seed: int | None = None,
                           pattern=None) -> RadarFrame:
    """Render the IF frame of point targets seen from a moving platform.

    Parameters
    ----------
    config : RadarConfig
    array : VirtualArray
    targets : sequence of PointTarget
    trajectory : Trajectory, optional
        Body motion; stationary if omitted.
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    frame : int
        Frame index (sets chirp times via ``config.frame_interval``).
    t0 : float
        Time of the first chirp of frame 0 [s].
    intra_chirp : bool
        Evaluate the geometry at every sample instead of stop-and-hop.
    noise : bool
        Add complex white thermal noise of power ``k T0 F f_s`` per sample.
    seed : int, optional
        Seed of the noise generator.
    pattern : raysim.radar.pattern.ElementPattern, optional
        Element pattern (e.g. ``config.pattern``); default: the constant gain
        ``config.antenna_gain_dbi`` in every direction.

    Returns
    -------
    RadarFrame
        ``data`` of shape ``[chirp, channel, sample]``, complex64.
    """
    trajectory = stationary() if trajectory is None else trajectory
    check_frame_memory(config, array, len(targets), intra_chirp=intra_chirp)
    tau, amp = point_target_delays(config, array, trajectory, targets, lever_arm=lever_arm,
                                   frame=frame, t0=t0, intra_chirp=intra_chirp, pattern=pattern)
    if intra_chirp:
        data = synthesize_if_intrachirp(tau, amp, config)
    else:
        data = synthesize_if(tau, amp, config)
    if noise:
        add_noise(data, config, seed)
    return RadarFrame(adc_samples(data, config), config, array, config.chirp_times(frame, t0),
                      np.asarray(lever_arm, dtype=float), frame,
                      {"targets": list(targets), "trajectory": trajectory.name})


def point_target_source(config: RadarConfig, array, targets, trajectory=None, *,
                        lever_arm=(0.0, 0.0, 0.0), t0: float = 0.0, pattern=None):
    """Source of the oracle's exact point-target delays for a frame stream.

    For :func:`raysim.synthesis.streaming.render_stream`; ``pattern`` as in
    :func:`point_target_delays`.

    Returns
    -------
    callable
        ``source(frame) -> (tau, amplitude)``, both ``[target, chirp, channel]``
        from :func:`point_target_delays`.
    """
    trajectory = stationary() if trajectory is None else trajectory
    targets = list(targets)

    def source(frame: int):
        return point_target_delays(config, array, trajectory, targets, lever_arm=lever_arm,
                                   frame=frame, t0=t0, pattern=pattern)

    return source
