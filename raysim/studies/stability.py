"""Stability maps: where IMU-driven motion compensation holds and where it fails.

A *stability map* sweeps one or two scenario parameters (rotation amplitude,
target angle, motion frequency, frame length, IMU errors, clock errors, lever
arm error, hover-jitter level) and records, for every compensation chain, the
CONVENTIONS.md metrics of a single static point target:

* residual pseudo-velocity [m/s] (and in Doppler velocity bins),
* Doppler mainlobe width [Hz],
* instantaneous angle error [deg]: worst over :data:`ANGLE_CHIRPS` chirps
  spread over the frame and the chirps of extreme true roll, pitch and yaw,
  each beam-scanned on its own (as the paper's single-chirp RA map),
* entropy [nats] of the azimuth-elevation map integrated coherently over the
  frame on a fixed global grid (the paper's yaw metric); the sum runs over at
  most :data:`MAP_CHIRPS` evenly strided chirps (a 4 kHz slow-time rate for
  the paper's radar, far above any hover motion).

Chains (:data:`CHAINS`):

``none``
    No compensation (the baseline).
``paper``
    The paper's chain: slow-time phase ``exp(-j 4 pi / lambda v_r(nT) nT)`` for
    the lever-arm velocity ``v_r = (omega x r_IR) . u`` plus the integrated
    translation ``Delta p . u``; element-wise small-angle spatial correction
    ``exp(-j 2 pi / lambda (beta x_m - alpha y_m))`` for pitch ``beta`` and roll
    ``alpha``; chirp-wise beam projection for yaw.
``paper_integrated``
    The paper's chain with the rotation phase integrated: the lever-arm
    displacement ``(R_n - I) r_IR`` instead of ``v_r(nT) nT``.
``exact``
    Rigid-body chain: per chirp the full attitude ``R_n`` (beam projection
    ``a(R_n^T u)``) and the exact range change of the radar phase centre
    ``|P - x_n| - |P - x_ref|``.

Speed: the slow-time and angle physics of one target need only its range
gate. :func:`gated_cube` evaluates the Hann-windowed range FFT of the exact IF
tones at the target's range bin in closed form, so a point costs
``[chirp, channel]`` work instead of ``[chirp, channel, sample]`` (it equals
``range_compress(synthesize_if(...))[:, :, bin]`` to float precision; see the
tests). Rotations use the separable UPA steering ``a = a_x (x) a_y``.

The navigation solution comes from ``compensation.integrate_imu`` when the
:mod:`compensation` package is importable, else from :func:`reference_pose`;
the chains' corrections (:func:`chain_corrections`) follow the formulas of
``compensation.paper`` and ``compensation.exact`` and are re-derived here on
the range gate (tests compare them with the package on full cubes).
``strapdown`` in the result attributes says which solution was used.

Failure criteria (:class:`Criteria`): residual pseudo-velocity above one
Doppler velocity bin ``lambda_c / (2 N T_rep)``, or angle error above half the
3 dB beamwidth ``0.886 lambda_c / (2 L)`` of the array aperture ``L``.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import json
import math
import os
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from raysim.echoes.oracle import PointTarget, direction, point_target_delays
from raysim.io.files import atomic_write
from raysim.platform.motion import HoverJitterSpec, Trajectory, hover_jitter, sinusoid
from raysim.processing.maps import Map
from raysim.processing.metrics import (
    doppler_mainlobe_width,
    image_entropy,
    map_peak,
    pseudo_velocity,
)
from raysim.radar.arrays import VirtualArray, upa
from raysim.radar.config import RadarConfig

__all__ = [
    "CHAINS", "ANGLE_CHIRPS", "GRAVITY", "Scenario", "Criteria", "PoseEstimate", "MapSpec",
    "MAPS", "gated_cube", "compensated_slow_time", "estimate_pose", "reference_pose",
    "chain_corrections", "evaluate", "run_map", "plot_map", "atomic_write", "write_stability",
    "write_netcdf", "read_netcdf", "criteria_for", "fails", "failing_values",
]

#: Compensation chains compared in every map.
CHAINS = ("none", "paper", "paper_integrated", "exact")
#: Chirps (evenly spread) whose single-chirp angle error is evaluated; the worst counts.
ANGLE_CHIRPS = 8
#: Gravity in the world NED frame [m/s^2] (CONVENTIONS.md).
GRAVITY = np.array([0.0, 0.0, 9.80665])
#: Half-width of the coherent azimuth-elevation map around the target [rad].
MAP_HALF_WIDTH = np.deg2rad(24.0)
#: Step of the coherent azimuth-elevation map [rad].
MAP_STEP = np.deg2rad(1.5)
#: At most this many chirps (evenly strided) enter the coherent azimuth-elevation map.
MAP_CHIRPS = 64
#: Coarse beam-scan step for single-chirp angle estimates [rad].
COARSE_STEP = np.deg2rad(2.0)
#: Field of view of the coarse beam scan (|az|, |el| below this) [rad].
COARSE_FOV = np.deg2rad(80.0)
#: Fine beam-scan half-width and step around the coarse peak [rad].
FINE_HALF_WIDTH, FINE_STEP = np.deg2rad(2.0), np.deg2rad(0.1)

_PHASE_FORMS = ("paper", "integrated")
_INITS = ("truth", "hover")
#: Axes whose values are integers (passed to the builders as int).
_INT_AXES = ("num_chirps", "term_index", "error_axis_index", "init_index")
#: Version of the per-point record format and of the chains (part of the point key).
POINT_VERSION = 2
#: Hover-assumption window either side of the frame for ``init="hover"`` [s].
HOVER_WINDOW = 0.25


# ---------------------------------------------------------------- scenario
@dataclass(frozen=True, eq=False)
class Scenario:
    """One stability-map point: radar, motion, target and IMU.

    Parameters
    ----------
    config : RadarConfig
        Waveform; one frame starting at ``t0``.
    array : VirtualArray
        Virtual UPA (needs ``grid_shape``).
    trajectory : Trajectory
        Truth body motion.
    target_range : float
        Target range from the nominal radar phase centre [m].
    target_az, target_el : float
        Target direction at the nominal attitude [rad].
    lever_arm : ndarray, shape ``[3]``
        True radar phase centre in B [m].
    lever_arm_error : ndarray, shape ``[3]``
        Error of the lever arm the chains are given [m].
    imu_spec : str or raysim.platform.imu.ImuSpec
        IMU error model (preset name or spec).
    imu_rate : float
        IMU output rate [Hz].
    imu_time_offset : float
        IMU clock reading at radar time 0 [s]; the chains assume 0.
    imu_clock_drift_ppm : float
        IMU clock rate error [ppm]; the chains assume 0.
    init : {"truth", "hover"}
        Initial state of the strapdown at the frame start: the truth (an
        aligned navigation solution) or the hover assumption (nominal
        attitude, velocity averaging to zero over the IMU record).
    t0 : float
        Radar time of the first chirp [s].
    seed : int
        Seed of the IMU error draws.
    """

    config: RadarConfig
    array: VirtualArray
    trajectory: Trajectory
    target_range: float = 15.0
    target_az: float = 0.0
    target_el: float = 0.0
    lever_arm: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.10]))
    lever_arm_error: np.ndarray = field(default_factory=lambda: np.zeros(3))
    imu_spec: object = "ideal"
    imu_rate: float = 2000.0
    imu_time_offset: float = 0.0
    imu_clock_drift_ppm: float = 0.0
    init: str = "truth"
    t0: float = 0.0
    seed: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.config, RadarConfig):
            raise ValueError(f"config must be a RadarConfig, got {type(self.config).__name__}")
        if not isinstance(self.array, VirtualArray) or self.array.grid_shape is None:
            raise ValueError(f"array must be a gridded VirtualArray (UPA), got {self.array!r}")
        for name in ("lever_arm", "lever_arm_error"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be 3 finite numbers [m], got {v!r}")
            object.__setattr__(self, name, v)
        if not math.isfinite(self.target_range) or self.target_range <= 0:
            raise ValueError(f"target_range must be a positive distance [m], "
                             f"got {self.target_range!r}")
        self.config.check_range(self.target_range, "target_range")
        for name in ("target_az", "target_el"):
            v = getattr(self, name)
            if not math.isfinite(v) or abs(v) >= np.pi / 2:
                raise ValueError(f"{name} must be a finite angle in (-pi/2, pi/2) rad, got {v!r}")
        if not math.isfinite(self.imu_rate) or self.imu_rate <= 0:
            raise ValueError(f"imu_rate must be a finite positive rate [Hz], got {self.imu_rate!r}")
        for name in ("imu_time_offset", "imu_clock_drift_ppm", "t0"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")
        if self.init not in _INITS:
            raise ValueError(f"init must be one of {_INITS}, got {self.init!r}")
        if not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {self.seed!r}")
        if isinstance(self.imu_spec, str):
            from raysim.platform.imu import get_preset

            get_preset(self.imu_spec)            # raises naming the unknown preset

    @property
    def target(self) -> PointTarget:
        """The static target, placed from the nominal radar phase centre."""
        return PointTarget.at(self.target_range, self.target_az, self.target_el,
                              radar_origin=self.lever_arm)

    @property
    def direction(self) -> np.ndarray:
        """True target direction from the nominal radar phase centre, shape ``[3]``."""
        return direction(self.target_az, self.target_el)

    def with_(self, **changes) -> Scenario:
        """Copy with some fields changed (validated again)."""
        return replace(self, **changes)


@dataclass(frozen=True)
class Criteria:
    """Failure thresholds of a configuration.

    Attributes
    ----------
    velocity_bin : float
        Doppler velocity bin ``lambda_c / (2 N T_rep)`` [m/s].
    doppler_bin_hz : float
        Doppler bin ``1 / (N T_rep)`` [Hz].
    half_beamwidth_deg : float
        Half of the 3 dB beamwidth at broadside [deg].
    """

    velocity_bin: float
    doppler_bin_hz: float
    half_beamwidth_deg: float


def criteria_for(config: RadarConfig, array: VirtualArray) -> Criteria:
    """Thresholds of :class:`Criteria` for a radar and a UPA.

    The 3 dB beamwidth of a uniform aperture of length ``L = n d`` is
    ``0.886 lambda / L`` rad at broadside; the smaller of the two UPA axes'
    beamwidths is used (largest aperture).
    """
    p = array.virtual_positions
    nx, ny = array.grid_shape
    lam = config.center_wavelength
    # p_virt spacing d_v corresponds to a one-way phase k u.p_virt: aperture n * d_v
    spans = []
    for axis, n in ((0, nx), (1, ny)):
        coords = np.unique(np.round(p[:, axis], 12))
        if n > 1:
            spans.append(n * float(np.min(np.diff(coords))))
    aperture = max(spans) if spans else lam / 2.0
    half_bw = 0.5 * np.rad2deg(0.886 * lam / aperture)
    return Criteria(config.velocity_resolution, config.doppler_resolution, float(half_bw))


def fails(metrics: dict, criteria: Criteria) -> bool:
    """True when a metrics record breaks a criterion of :class:`Criteria`.

    Parameters
    ----------
    metrics : dict
        Needs ``pseudo_velocity`` [m/s] and ``angle_error_deg`` [deg].
    """
    return bool(abs(metrics["pseudo_velocity"]) > criteria.velocity_bin
                or metrics["angle_error_deg"] > criteria.half_beamwidth_deg)


# ----------------------------------------------------------- range gating
def _dirichlet(nu: np.ndarray, k: int) -> np.ndarray:
    """``sum_{k'<k} exp(j 2 pi nu k')`` in closed form (``k`` at ``nu`` integer)."""
    nu = nu - np.round(nu)                       # the sum has period 1 in nu
    s = np.sin(np.pi * nu)
    small = np.abs(s) < 1e-12
    ratio = np.where(small, float(k), np.sin(np.pi * nu * k) / np.where(small, 1.0, s))
    return np.exp(1j * np.pi * nu * (k - 1)) * ratio


def gated_cube(scenario: Scenario, *, window_name: str = "hann") -> tuple[np.ndarray, int]:
    """Range-compressed samples of the target's range gate, exactly and cheaply.

    Parameters
    ----------
    scenario : Scenario
    window_name : {"hann"}
        Fast-time window of the (virtual) range FFT, normalised by its sum as in
        :func:`raysim.processing.maps.range_compress`.

    Returns
    -------
    gate : ndarray, shape ``[chirp, channel]``, complex128
        ``range_compress(IF)[:, :, bin]`` [sqrt(W)].
    bin : int
        Index of the range bin nearest ``target_range`` (unpadded FFT).

    Notes
    -----
    A stop-and-hop tone ``a exp(j (phi0 + 2 pi f_b k / f_s))`` windowed by the
    periodic Hann window ``w_k = 1/2 - 1/4 (e^{j2pi k/K} + e^{-j2pi k/K})`` has
    at FFT bin ``m``, with ``nu = f_b / f_s - m / K`` and the Dirichlet sum
    ``D(nu) = sum_k e^{j 2 pi nu k}``::

        X_m = a e^{j phi0} [D(nu)/2 - D(nu + 1/K)/4 - D(nu - 1/K)/4] / (K/2)
    """
    if window_name != "hann":
        raise ValueError(f"window_name must be 'hann', got {window_name!r}")
    cfg = scenario.config
    tau, amp = point_target_delays(cfg, scenario.array, scenario.trajectory, [scenario.target],
                                   lever_arm=scenario.lever_arm, t0=scenario.t0)
    tau, amp = tau[0], amp[0]                                   # [chirp, channel]
    k = cfg.num_samples
    r_axis = cfg.range_axis(k)
    m = int(np.argmin(np.abs(r_axis - scenario.target_range)))
    fb = cfg.chirp_rate * tau
    phi0 = 2 * np.pi * (cfg.carrier_frequency * tau - 0.5 * cfg.chirp_rate * tau * tau)
    nu = fb / cfg.sample_rate - m / k
    if not cfg.complex_sampling:
        raise ValueError("gated_cube needs complex_sampling=True")
    g = (0.5 * _dirichlet(nu, k) - 0.25 * _dirichlet(nu + 1.0 / k, k)
         - 0.25 * _dirichlet(nu - 1.0 / k, k)) / (k / 2.0)
    return amp * np.exp(1j * phi0) * g, m


# ---------------------------------------------------------------- strapdown
@dataclass(frozen=True, eq=False)
class PoseEstimate:
    """Navigation solution at the chirp times, as a chain believes it.

    Attributes
    ----------
    attitude : ndarray, shape ``[chirp, 3, 3]``
        ``R_WB`` estimate [1].
    position : ndarray, shape ``[chirp, 3]``
        Body-origin position in W [m].
    omega : ndarray, shape ``[chirp, 3]``
        Body angular rate at the chirp times, in B [rad/s].
    source : str
        Which strapdown produced it.
    warnings : tuple of str
        Assumptions the estimate found broken.
    """

    attitude: np.ndarray
    position: np.ndarray
    omega: np.ndarray
    source: str = ""
    warnings: tuple = ()


def _simulate_imu(scenario: Scenario, start: float, end: float):
    from raysim.platform.imu import Imu

    imu = Imu(scenario.imu_spec, rate=scenario.imu_rate, time_offset=scenario.imu_time_offset,
              clock_drift_ppm=scenario.imu_clock_drift_ppm)
    return imu(scenario.trajectory, start, end, seed=scenario.seed)


def _imu_record(scenario: Scenario, chirp_times: np.ndarray):
    """IMU samples covering the frame (plus the hover window for ``init="hover"``)."""
    dt = 1.0 / scenario.imu_rate
    t_first, t_last = float(chirp_times[0]), float(chirp_times[-1])
    clock = abs(scenario.imu_time_offset) + 1e-6 * abs(scenario.imu_clock_drift_ppm) * (
        abs(t_first) + abs(t_last))
    margin = 3 * dt + clock
    pre = HOVER_WINDOW if scenario.init == "hover" else 0.0
    return _simulate_imu(scenario, t_first - margin - pre, t_last + margin + pre)


def _initial_state(scenario: Scenario, t: float):
    q, qd, _ = scenario.trajectory.states(np.array([t]))
    return Rotation.from_euler("ZYX", q[0, [5, 4, 3]]), q[0, :3], qd[0, :3]


def estimate_pose(scenario: Scenario, chirp_times: np.ndarray, *,
                  strapdown: str = "auto") -> PoseEstimate:
    """Navigation solution the chains use, from a simulated IMU.

    The chains treat IMU time stamps as radar time (``imu_time_offset`` and
    ``imu_clock_drift_ppm`` are errors they do not know about) and are given
    the believed lever arm. Initial state (``scenario.init``): ``"truth"``
    gives the true attitude, position and velocity at the first chirp (an
    aligned navigation solution); ``"hover"`` gives the nominal attitude and
    position and assumes the velocity averages to zero over the record
    (:data:`HOVER_WINDOW` either side of the frame).

    Parameters
    ----------
    scenario : Scenario
    chirp_times : ndarray, shape ``[chirp]``
        Radar time of each chirp [s].
    strapdown : {"auto", "compensation", "reference"}
        ``compensation.integrate_imu`` (``"auto"`` when importable) or
        :func:`reference_pose`.

    Returns
    -------
    PoseEstimate
    """
    if strapdown not in ("auto", "compensation", "reference"):
        raise ValueError(f"strapdown must be 'auto', 'compensation' or 'reference', "
                         f"got {strapdown!r}")
    samples = _imu_record(scenario, chirp_times)
    t, gyro, accel = samples.to_arrays()
    integrate = None
    if strapdown != "reference":
        try:
            from compensation import integrate_imu as integrate
        except ImportError:
            if strapdown == "compensation":
                raise
    if integrate is None:
        return reference_pose(scenario, chirp_times, samples)
    r0, p0, v0 = _initial_state(scenario, float(chirp_times[0]))
    kw = dict(lever_arm=scenario.lever_arm + scenario.lever_arm_error, time_offset=0.0)
    if scenario.init == "truth":
        kw.update(initial_attitude=r0.as_matrix(), initial_position=p0, velocity="given",
                  initial_velocity=v0)
    else:
        kw.update(velocity="hover")
    m = integrate(t, gyro, accel, chirp_times, **kw)
    warnings = tuple(getattr(m, "warnings", ()) or ())
    return PoseEstimate(m.attitude, m.position, m.angular_rate, "compensation.integrate_imu",
                        warnings)


def reference_pose(scenario: Scenario, chirp_times: np.ndarray, samples=None) -> PoseEstimate:
    """Second-order strapdown (used when the compensation package is absent).

    Starts at the last IMU sample at or before the first chirp with the initial
    state of ``scenario.init`` (``"hover"``: level, zero velocity), integrates
    the gyro with the rotation vector of the trapezoidal rate and the specific
    force ``a = R f + g`` with the trapezoidal rule, and interpolates (slerp
    for the attitude, linear otherwise) to the chirp times.

    Parameters
    ----------
    scenario : Scenario
    chirp_times : ndarray, shape ``[chirp]`` [s]
    samples : raysim.platform.imu.ImuSamples, optional
        IMU record; simulated from the scenario when omitted.

    Returns
    -------
    PoseEstimate
    """
    if samples is None:
        samples = _imu_record(scenario, chirp_times)
    t, gyro, accel = samples.to_arrays()
    t_first, t_last = float(chirp_times[0]), float(chirp_times[-1])
    warnings = []
    if t[0] > t_first or t[-1] < t_last:
        warnings.append(f"IMU samples [{t[0]:.6f}, {t[-1]:.6f}] s do not cover the frame "
                        f"[{t_first:.6f}, {t_last:.6f}] s")
    k0 = max(int(np.searchsorted(t, t_first, side="right")) - 1, 0)
    t, gyro, accel = t[k0:], gyro[k0:], accel[k0:]
    if scenario.init == "truth":
        r0, p0, v0 = _initial_state(scenario, float(t[0]))
    else:
        r0, p0, v0 = Rotation.identity(), np.zeros(3), np.zeros(3)
    rots = [r0]
    for i in range(t.size - 1):
        rots.append(rots[-1] * Rotation.from_rotvec(0.5 * (gyro[i] + gyro[i + 1])
                                                    * (t[i + 1] - t[i])))
    rot = Rotation.concatenate(rots)
    acc_w = rot.apply(accel) + GRAVITY
    h = np.diff(t)[:, None]
    vel = np.vstack([v0, v0 + np.cumsum(0.5 * (acc_w[1:] + acc_w[:-1]) * h, axis=0)])
    pos = np.vstack([p0, p0 + np.cumsum(0.5 * (vel[1:] + vel[:-1]) * h, axis=0)])
    tc = np.clip(chirp_times, t[0], t[-1])
    attitude = (Slerp(t, rot)(tc).as_matrix() if t.size >= 2
                else np.repeat(rot.as_matrix(), tc.size, axis=0))

    def lin(y):
        return np.stack([np.interp(tc, t, y[:, j]) for j in range(3)], axis=-1)

    return PoseEstimate(attitude, lin(pos), lin(gyro), "raysim.studies.stability.reference_pose",
                        tuple(warnings))


# ---------------------------------------------------------------- chains
@dataclass(frozen=True, eq=False)
class _Corrections:
    """Per-chirp corrections of one chain (internal)."""

    element_phase: np.ndarray | None      # [chirp, channel] rad, applied as exp(-j .)
    beam_rotation: np.ndarray | None      # [chirp, 3, 3]: steer a(R^T u)
    range_change: Callable[[np.ndarray], np.ndarray]  # u [U,3] -> [chirp, U] m
    parallax: Callable[[np.ndarray], np.ndarray] | None  # u [U,3] -> [chirp, U, 3]


def chain_corrections(chain: str, scenario: Scenario, pose: PoseEstimate | None,
                      chirp_times: np.ndarray) -> _Corrections:
    """Corrections a chain applies, from its pose estimate.

    Parameters
    ----------
    chain : str
        One of :data:`CHAINS`.
    scenario : Scenario
        Supplies the lever arm the chain believes (true + error) and the gate range.
    pose : PoseEstimate or None
        Navigation solution (unused for ``"none"``).
    chirp_times : ndarray, shape ``[chirp]`` [s]
    """
    if chain not in CHAINS:
        raise ValueError(f"chain must be one of {CHAINS}, got {chain!r}")
    n = chirp_times.size
    if chain == "none":
        return _Corrections(None, None, lambda u: np.zeros((n, np.shape(u)[0])), None)
    lever = scenario.lever_arm + scenario.lever_arm_error
    p_virt = scenario.array.virtual_positions
    lam = scenario.config.center_wavelength
    if chain in ("paper", "paper_integrated"):
        euler = Rotation.from_matrix(pose.attitude).as_euler("ZYX")      # yaw, pitch, roll
        yaw, pitch, roll = euler[:, 0], euler[:, 1], euler[:, 2]
        k = 2 * np.pi / lam
        elem = k * (pitch[:, None] * p_virt[None, :, 0] - roll[:, None] * p_virt[None, :, 1])
        rz = Rotation.from_euler("Z", yaw[:, None]).as_matrix()
        dt = chirp_times - chirp_times[0]
        if chain == "paper":
            # published form: radial velocity of the lever arm times elapsed time
            disp_rot = np.cross(pose.omega, lever) * dt[:, None]
        else:
            # integrated: the lever-arm displacement (R_n - I) r_IR
            disp_rot = np.einsum("nij,j->ni", pose.attitude, lever) - lever
        disp = disp_rot + pose.position

        def range_change(u):
            return -(disp @ np.asarray(u).T)

        return _Corrections(elem, rz, range_change, None)
    # exact rigid body
    x_ref = lever                                              # nominal radar phase centre in W
    x_n = pose.position + np.einsum("nij,j->ni", pose.attitude, lever)
    r0 = scenario.target_range

    def target_points(u):
        return x_ref + r0 * np.asarray(u)                      # [U, 3]

    def range_change(u):
        d = target_points(u)[None, :, :] - x_n[:, None, :]
        return np.linalg.norm(d, axis=-1) - r0

    def parallax(u):
        d = target_points(u)[None, :, :] - x_n[:, None, :]
        return d / np.linalg.norm(d, axis=-1, keepdims=True)

    return _Corrections(None, pose.attitude, range_change, parallax)


def _upa_axes(array: VirtualArray) -> tuple[np.ndarray, np.ndarray]:
    nx, ny = array.grid_shape
    p = array.virtual_positions.reshape(nx, ny, 3)
    return p[:, 0, 0], p[0, :, 1]


def _beam(x: np.ndarray, array: VirtualArray, wavelength: float, w: np.ndarray) -> np.ndarray:
    """Delay-and-sum ``sum_m x[n, m] exp(+j k w[n, u] . p_m) / M`` for a UPA.

    Parameters
    ----------
    x : ndarray, shape ``[chirp, channel]``
    w : ndarray, shape ``[chirp, U, 3]`` or ``[U, 3]`` (same for every chirp)
        Look direction in frame A.

    Returns
    -------
    ndarray, shape ``[chirp, U]``
    """
    nx, ny = array.grid_shape
    xs, ys = _upa_axes(array)
    k = 2 * np.pi / wavelength
    ex = np.exp(1j * k * w[..., 0:1] * xs)                    # [(chirp,) U, nx]
    ey = np.exp(1j * k * w[..., 1:2] * ys)                    # [(chirp,) U, ny]
    if w.ndim == 2:
        steer = (ex[:, :, None] * ey[:, None, :]).reshape(w.shape[0], nx * ny)
        return (x @ steer.T) / (nx * ny)
    z = np.matmul(ex, x.reshape(x.shape[0], nx, ny))          # [chirp, U, ny]
    return (z * ey).sum(axis=-1) / (nx * ny)


def _look(corr: _Corrections, u: np.ndarray, n: int) -> np.ndarray:
    """Look directions in frame A for global directions ``u [U, 3]``.

    Returns ``[U, 3]`` when every chirp looks the same way, else ``[chirp, U, 3]``.
    """
    if corr.parallax is None:
        rot = corr.beam_rotation
        if rot is None or np.allclose(rot, np.eye(3), rtol=0.0, atol=1e-13):
            return u
        return np.einsum("nji,uj->nui", rot, u)               # R^T u
    w = corr.parallax(u)
    if corr.beam_rotation is not None:
        w = np.einsum("nji,nuj->nui", corr.beam_rotation, w)
    return w


def _grid(az0: float, el0: float, half: float, step: float) -> tuple[np.ndarray, np.ndarray]:
    m = int(round(half / step))
    off = np.arange(-m, m + 1) * step
    return az0 + off, el0 + off


def _dirs(az: np.ndarray, el: np.ndarray) -> np.ndarray:
    aa, ee = np.meshgrid(az, el, indexing="ij")
    return direction(aa, ee).reshape(-1, 3)


def _subset(corr: _Corrections, sel: np.ndarray) -> _Corrections:
    """Corrections restricted to the chirps ``sel``."""
    return _Corrections(
        None if corr.element_phase is None else corr.element_phase[sel],
        None if corr.beam_rotation is None else corr.beam_rotation[sel],
        lambda v: corr.range_change(v)[sel],
        None if corr.parallax is None else (lambda v: corr.parallax(v)[sel]))


def _single_chirp_direction(xc: np.ndarray, corr: _Corrections, idx: np.ndarray,
                            array: VirtualArray, lam: float) -> np.ndarray:
    """Interpolated beam-scan peak (az, el) [rad] of chirps ``idx``, shape ``[len(idx), 2]``."""
    def scan(az, el, sel):
        u = _dirs(az, el)
        sub = _subset(corr, sel)
        y = _beam(xc[sel], array, lam, _look(sub, u, len(sel)))
        return np.abs(y) ** 2

    coarse_az, coarse_el = _grid(0.0, 0.0, COARSE_FOV, COARSE_STEP)
    out = np.empty((idx.size, 2))
    pw = scan(coarse_az, coarse_el, idx)
    for j, n in enumerate(idx):
        i = int(np.argmax(pw[j]))
        a0, e0 = coarse_az[i // coarse_el.size], coarse_el[i % coarse_el.size]
        faz, fel = _grid(a0, e0, FINE_HALF_WIDTH, FINE_STEP)
        p = scan(faz, fel, np.array([n]))[0].reshape(faz.size, fel.size)
        pk = map_peak(Map(p, ("azimuth", "elevation"), {"azimuth": faz, "elevation": fel}))
        out[j] = pk["azimuth"], pk["elevation"]
    return out


def _angle_between_deg(az, el, u_true) -> np.ndarray:
    return np.rad2deg(np.arccos(np.clip(direction(az, el) @ u_true, -1.0, 1.0)))


def _slow_time(x: np.ndarray, corr: _Corrections, scenario: Scenario) -> np.ndarray:
    """Compensated slow time towards the true direction, shape ``[chirp]``."""
    lam = scenario.config.center_wavelength
    ut = scenario.direction[None, :]
    s = _beam(x, scenario.array, lam, _look(corr, ut, x.shape[0]))[:, 0]
    return s * np.exp(-1j * 4 * np.pi / lam * corr.range_change(ut)[:, 0])


def compensated_slow_time(scenario: Scenario, chain: str,
                          pose: PoseEstimate | None = None) -> np.ndarray:
    """Slow-time signal of the target's range gate after a chain, beamformed at the target.

    Parameters
    ----------
    scenario : Scenario
    chain : str
        One of :data:`CHAINS`.
    pose : PoseEstimate, optional
        Navigation solution; :func:`estimate_pose` when omitted.

    Returns
    -------
    ndarray, shape ``[chirp]``, complex128
        ``y_n(u)`` [sqrt(W)]: channel-averaged beam output towards the true
        direction with the chain's spatial and slow-time corrections.
    """
    gate, _ = gated_cube(scenario)
    times = scenario.config.chirp_times(0, scenario.t0)
    if pose is None and chain != "none":
        pose = estimate_pose(scenario, times)
    corr = chain_corrections(chain, scenario, pose, times)
    x = gate if corr.element_phase is None else gate * np.exp(-1j * corr.element_phase)
    return _slow_time(x, corr, scenario)


def _angle_chirps(scenario: Scenario, chirp_times: np.ndarray) -> np.ndarray:
    """Chirps whose single-chirp angle error is measured, shape ``[k]`` (sorted, unique).

    :data:`ANGLE_CHIRPS` chirps evenly spread over the frame plus, for each
    true Euler angle (roll, pitch, yaw), the chirps where it is largest and
    smallest, so the worst attitude of the frame is always included.
    """
    n = chirp_times.size
    even = np.linspace(0, n - 1, ANGLE_CHIRPS + 2).round().astype(int)[1:-1]
    q = scenario.trajectory.states(chirp_times)[0][:, 3:]
    extremes = np.concatenate([np.argmax(q, axis=0), np.argmin(q, axis=0)])
    return np.unique(np.concatenate([even, extremes]))


def _chain_metrics(gate: np.ndarray, corr: _Corrections, scenario: Scenario,
                   chirp_times: np.ndarray, coherent_map: bool = True) -> dict:
    cfg, array = scenario.config, scenario.array
    lam = cfg.center_wavelength
    n = chirp_times.size
    x = gate if corr.element_phase is None else gate * np.exp(-1j * corr.element_phase)
    u_true = scenario.direction
    s = _slow_time(x, corr, scenario)
    pv = pseudo_velocity(s, cfg.chirp_interval, lam)
    width = doppler_mainlobe_width(s, cfg.chirp_interval)
    idx = _angle_chirps(scenario, chirp_times)
    ae = _single_chirp_direction(x, corr, idx, array, lam)
    errs = _angle_between_deg(ae[:, 0], ae[:, 1], u_true)
    out = {"pseudo_velocity": float(pv), "doppler_width_hz": float(width),
           "angle_error_deg": float(errs.max()),
           "angle_error_mid_deg": float(errs[np.argmin(np.abs(idx - n // 2))]),
           "focused_angle_error_deg": math.nan, "entropy": math.nan}
    if not coherent_map:
        return out
    # coherent azimuth-elevation map over the frame
    gaz, gel = _grid(scenario.target_az, scenario.target_el, MAP_HALF_WIDTH, MAP_STEP)
    u = _dirs(gaz, gel)
    sel = np.arange(0, n, max(1, -(-n // MAP_CHIRPS)))
    sub = _subset(corr, sel)
    y = _beam(x[sel], array, lam, _look(sub, u, sel.size))
    y = y * np.exp(-1j * 4 * np.pi / lam * sub.range_change(u))
    img = np.abs(y.sum(axis=0)) ** 2
    pk = map_peak(Map(img.reshape(gaz.size, gel.size), ("azimuth", "elevation"),
                      {"azimuth": gaz, "elevation": gel}))
    out["focused_angle_error_deg"] = float(_angle_between_deg(pk["azimuth"], pk["elevation"],
                                                              u_true))
    out["entropy"] = float(image_entropy(img))
    return out


def evaluate(scenario: Scenario, chains: Sequence[str] = CHAINS, *,
             strapdown: str = "auto", coherent_map: bool = True) -> dict:
    """Metrics of every chain at one scenario.

    Parameters
    ----------
    scenario : Scenario
    chains : sequence of str
        Subset of :data:`CHAINS`.
    strapdown : {"auto", "compensation", "reference"}
        Navigation solution, see :func:`estimate_pose`.
    coherent_map : bool
        Also form the coherent azimuth-elevation map (``entropy`` and
        ``focused_angle_error_deg``; NaN when False). The failure criteria
        need only the pseudo-velocity and the angle error.

    Returns
    -------
    dict
        ``chain -> {"pseudo_velocity" [m/s], "doppler_width_hz" [Hz],
        "angle_error_deg" [deg] (worst single chirp), "angle_error_mid_deg",
        "focused_angle_error_deg" (coherent map peak), "entropy" [nats]}``,
        plus ``"warnings"`` (list of str) from the navigation solution.
    """
    for c in chains:
        if c not in CHAINS:
            raise ValueError(f"chain must be one of {CHAINS}, got {c!r}")
    gate, _ = gated_cube(scenario)
    times = scenario.config.chirp_times(0, scenario.t0)
    pose = None
    if any(c != "none" for c in chains):
        pose = estimate_pose(scenario, times, strapdown=strapdown)
    out: dict = {}
    for c in chains:
        out[c] = _chain_metrics(gate, chain_corrections(c, scenario, pose, times), scenario,
                                times, coherent_map)
    out["warnings"] = list(pose.warnings) if pose is not None else []
    out["strapdown"] = pose.source if pose is not None else ""
    return out


# ------------------------------------------------------------------ maps
METRICS = ("pseudo_velocity", "doppler_width_hz", "angle_error_deg", "angle_error_mid_deg",
           "focused_angle_error_deg", "entropy")


@dataclass(frozen=True)
class MapSpec:
    """A stability map: scenario builder and the axes swept.

    Attributes
    ----------
    name : str
    title : str
    axes : tuple of (name, unit, values, quick_values)
        One or two swept parameters; values in the unit named (deg, Hz, ...).
    build : callable
        ``build(**{axis: value}, seed=int) -> Scenario``.
    seeds : int
        Seeds per point (full run); ``quick_seeds`` in quick mode.
    log_axes : tuple of str
        Axes drawn on a log scale.
    """

    name: str
    title: str
    axes: tuple
    build: Callable
    seeds: int = 1
    quick_seeds: int = 1
    log_axes: tuple = ()
    note: str = ""


def _radar(num_chirps: int = 256) -> RadarConfig:
    return RadarConfig(num_chirps=int(num_chirps))


def _array(cfg: RadarConfig) -> VirtualArray:
    return upa(20, 20, wavelength=cfg.wavelength)


_R = _radar()
_A = _array(_R)


def _b_rotation_angle(*, rotation_deg, target_deg, seed, axis="pitch"):
    tgt = {"target_az": np.deg2rad(target_deg)} if axis == "pitch" else \
        {"target_el": np.deg2rad(target_deg)}
    return Scenario(_R, _A, sinusoid(axis, np.deg2rad(rotation_deg), 20.0), 15.0, seed=seed,
                    **tgt)


def _b_freq_chirps(*, frequency_hz, num_chirps, seed):
    cfg = _radar(num_chirps)
    return Scenario(cfg, _A, sinusoid("pitch", np.deg2rad(10.0), frequency_hz), 15.0,
                    np.deg2rad(20.0), seed=seed)


def _rot_y_case(seed, **kw):
    return Scenario(_R, _A, sinusoid("pitch", np.deg2rad(10.0), 20.0), 15.0, np.deg2rad(20.0),
                    seed=seed, **kw)


def _trans_z_case(seed, **kw):
    cfg = _radar(512)
    return Scenario(cfg, _A, sinusoid("z", 0.05, 5.0), 15.0, np.deg2rad(10.0),
                    np.deg2rad(10.0), seed=seed, **kw)


def _imu_term(term: str, scale: float):
    """Consumer-MEMS IMU with only one error term, scaled by ``scale``."""
    from raysim.platform.imu import CONSUMER_MEMS, ImuSpec, SensorErrors

    def one(e):
        kw = {"bias_correlation_time": e.bias_correlation_time}
        if term == "noise":
            kw["noise_density"] = e.noise_density * scale
        elif term == "bias":
            kw["bias_sigma"] = e.bias_sigma * scale
        elif term == "bias_instability":
            kw["bias_instability"] = e.bias_instability * scale
        elif term == "scale_factor":
            kw["scale_factor_sigma"] = e.scale_factor_sigma * scale
        elif term == "misalignment":
            kw["misalignment_sigma"] = e.misalignment_sigma * scale
        else:
            raise ValueError(f"unknown IMU error term {term!r}")
        return SensorErrors(**kw)

    return ImuSpec(f"consumer_mems {term} x{scale:g}", one(CONSUMER_MEMS.gyro),
                   one(CONSUMER_MEMS.accel))


IMU_TERMS = ("noise", "bias", "bias_instability", "scale_factor", "misalignment")


def _b_imu_grade(*, term_index, scale, seed):
    # pitch 10 deg at 20 Hz and Z 5 cm at 5 Hz together: gyro and accelerometer both matter
    traj = sinusoid("pitch", np.deg2rad(10.0), 20.0) + sinusoid("z", 0.05, 5.0)
    return Scenario(_R, _A, traj, 15.0, np.deg2rad(20.0), np.deg2rad(10.0),
                    imu_spec=_imu_term(IMU_TERMS[int(term_index)], scale), seed=seed)


def _b_imu_rate(*, imu_rate_hz, frequency_hz, seed):
    return Scenario(_R, _A, sinusoid("pitch", np.deg2rad(10.0), frequency_hz), 15.0,
                    np.deg2rad(20.0), imu_rate=imu_rate_hz, seed=seed)


def _b_clock(*, time_offset_ms, clock_drift_ppm, seed):
    return _rot_y_case(seed, imu_time_offset=time_offset_ms * 1e-3,
                       imu_clock_drift_ppm=clock_drift_ppm, t0=0.5)


def _b_lever(*, lever_error_cm, error_axis_index, seed):
    err = np.zeros(3)
    err[int(error_axis_index)] = lever_error_cm * 1e-2
    return _rot_y_case(seed, lever_arm_error=err)


def _b_jitter(*, jitter_scale, init_index, seed):
    base = HoverJitterSpec()
    spec = replace(base, attitude_rms=tuple(a * jitter_scale for a in base.attitude_rms),
                   position_rms=tuple(p * jitter_scale for p in base.position_rms),
                   vibration_rms=base.vibration_rms * jitter_scale)
    return Scenario(_R, _A, hover_jitter(seed, spec), 15.0, np.deg2rad(20.0), np.deg2rad(10.0),
                    init=_INITS[int(init_index)], t0=1.0 + 0.37 * seed, seed=seed)


MAPS: dict[str, MapSpec] = {m.name: m for m in (
    MapSpec("rotation_azimuth", "pitch amplitude (20 Hz) x target azimuth",
            (("rotation_deg", "deg", (1, 2, 5, 10, 15, 20, 30), (2, 10, 30)),
             ("target_deg", "deg", (0, 10, 20, 30, 40, 50, 60), (0, 30, 60))),
            _b_rotation_angle,
            note="small-angle spatial correction vs target azimuth; lever arm 10 cm"),
    MapSpec("rotation_elevation", "roll amplitude (20 Hz) x target elevation",
            (("rotation_deg", "deg", (1, 2, 5, 10, 15, 20, 30), (2, 10, 30)),
             ("target_deg", "deg", (0, 10, 20, 30, 40, 50, 60), (0, 30, 60))),
            lambda **kw: _b_rotation_angle(axis="roll", **kw)),
    MapSpec("frequency_chirps", "pitch 10 deg: motion frequency x chirps per frame",
            (("frequency_hz", "Hz", (1, 2, 5, 10, 20, 40), (2, 20)),
             ("num_chirps", "", (64, 128, 256, 512, 1024), (128, 512))),
            _b_freq_chirps, log_axes=("frequency_hz", "num_chirps"),
            note="paper v_r(nT) nT phase form vs the integrated one"),
    MapSpec("imu_grade", "consumer-MEMS error terms, one at a time, scaled",
            (("term_index", "", tuple(range(len(IMU_TERMS))), tuple(range(len(IMU_TERMS)))),
             ("scale", "x consumer", (1, 10, 100, 1000, 10000), (1, 100, 10000))),
            _b_imu_grade, seeds=3, quick_seeds=1, log_axes=("scale",),
            note="terms: " + ", ".join(f"{i}={t}" for i, t in enumerate(IMU_TERMS))),
    MapSpec("imu_rate", "IMU rate x motion frequency (pitch 10 deg)",
            (("imu_rate_hz", "Hz", (50, 100, 200, 400, 1000, 2000), (50, 400)),
             ("frequency_hz", "Hz", (2, 5, 10, 20, 40), (10, 40))),
            _b_imu_rate, log_axes=("imu_rate_hz", "frequency_hz")),
    MapSpec("clock", "IMU-radar time offset x clock drift (rotation_y case)",
            (("time_offset_ms", "ms", (0, 0.05, 0.1, 0.2, 0.5, 1, 2), (0, 0.2, 2)),
             ("clock_drift_ppm", "ppm", (0, 100, 1000, 10000), (0, 10000))),
            _b_clock, note="frame starts at t0 = 0.5 s, so drift acts as an extra offset"),
    MapSpec("lever_arm", "lever-arm error x error axis (rotation_y case)",
            (("lever_error_cm", "cm", (0, 0.5, 1, 2, 5, 10, 20), (0, 2, 20)),
             ("error_axis_index", "", (0, 1, 2), (0, 2))),
            _b_lever, note="axis 0=X (forward), 1=Y (right), 2=Z (down); true arm 10 cm on Z"),
    MapSpec("hover_jitter", "hover jitter level x initial state",
            (("jitter_scale", "x default", (0.5, 1, 2, 4, 8), (1, 4)),
             ("init_index", "", (0, 1), (0, 1))),
            _b_jitter, seeds=6, quick_seeds=2, log_axes=("jitter_scale",),
            note="init 0=truth (aligned), 1=hover (nominal attitude, zero-mean velocity); "
                 "default jitter: 1 deg RMS roll/pitch, 3 cm RMS horizontal"),
)}


def _point_key(spec: MapSpec, kw: dict, seed: int, chains: Sequence[str]) -> str:
    blob = json.dumps({"map": spec.name, "values": kw, "seed": int(seed),
                       "chains": list(chains), "version": POINT_VERSION},
                      sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def _evaluate_point(spec: MapSpec, kw: dict, seed: int, chains: Sequence[str]) -> dict:
    """One map point: scenario, metrics and thresholds (a plain, JSON-ready dict)."""
    scn = spec.build(seed=seed, **kw)
    res = evaluate(scn, chains)
    crit = criteria_for(scn.config, scn.array)
    return {"values": kw, "seed": int(seed),
            "metrics": {c: res[c] for c in chains}, "criteria": asdict(crit),
            "warnings": res["warnings"], "strapdown": res["strapdown"]}


def _load_record(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None                             # missing or unreadable: compute again


def _have_distributed() -> bool:
    return importlib.util.find_spec("distributed") is not None


@contextlib.contextmanager
def _dask_client(client=None):
    """The given ``distributed.Client``, or an in-process one (1 worker, 2 threads)."""
    if client is not None:
        yield client
        return
    from distributed import Client, LocalCluster

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)       # dashboard port already in use
        cluster = LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                               dashboard_address=None)
    try:
        with Client(cluster) as cl:
            yield cl
    finally:
        cluster.close()


def run_map(spec: MapSpec | str, *, quick: bool = False, chains: Sequence[str] = CHAINS,
            progress: bool = True, points_dir: str | os.PathLike | None = None,
            executor: str = "auto", client=None):
    """Evaluate a stability map, point by point, resumably.

    Parameters
    ----------
    spec : MapSpec or str
        Map or its name in :data:`MAPS`.
    quick : bool
        Use the quick axis values and seeds.
    chains : sequence of str
    progress : bool
        Show a progress bar (tqdm, on stderr).
    points_dir : path-like, optional
        Folder of per-point records (``<key>.json``, written atomically as each
        point finishes); points already recorded there are not computed again,
        so an interrupted map resumes where it stopped.
    executor : {"auto", "dask", "serial"}
        ``"dask"``: one task per point on an in-process ``distributed``
        LocalCluster (one worker, two threads); ``"serial"``: a plain loop;
        ``"auto"``: Dask when ``distributed`` is importable.
    client : distributed.Client, optional
        Run the points on this client (any scheduler whose workers import raysim).

    Returns
    -------
    xarray.Dataset
        Variables of :data:`METRICS` with dims ``(chain, <axis 0>, <axis 1>, seed)``,
        ``fail`` (bool, :func:`fails`), ``worse_than_none`` (bool: residual
        pseudo-velocity or angle error above the baseline's), and the
        thresholds ``velocity_bin`` [m/s], ``half_beamwidth_deg``,
        ``doppler_bin_hz`` per grid point.
    """
    import xarray as xr

    if isinstance(spec, str):
        if spec not in MAPS:
            raise ValueError(f"unknown stability map {spec!r}; expected one of {sorted(MAPS)}")
        spec = MAPS[spec]
    if executor not in ("auto", "dask", "serial"):
        raise ValueError(f"executor must be 'auto', 'dask' or 'serial', got {executor!r}")
    for c in chains:
        if c not in CHAINS:
            raise ValueError(f"chain must be one of {CHAINS}, got {c!r}")
    names = [a[0] for a in spec.axes]
    values = [np.asarray(a[3] if quick else a[2], dtype=float) for a in spec.axes]
    n_seed = spec.quick_seeds if quick else spec.seeds
    shape = (len(chains),) + tuple(v.size for v in values) + (n_seed,)
    grid = list(np.ndindex(*shape[1:-1]))
    todo = []
    for g in grid:
        kw = {name: (int(v[i]) if name in _INT_AXES else float(v[i]))
              for name, v, i in zip(names, values, g, strict=True)}
        for s in range(n_seed):
            todo.append((g, s, kw, _point_key(spec, kw, s, chains)))
    pdir = None if points_dir is None else Path(points_dir)
    records: dict[str, dict] = {}
    if pdir is not None:
        pdir.mkdir(parents=True, exist_ok=True)
        for *_, key in todo:
            rec = _load_record(pdir / f"{key}.json")
            if rec is not None:
                records[key] = rec
    missing = [t for t in todo if t[3] not in records]
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(todo), initial=len(todo) - len(missing), desc=spec.name,
                   unit="point", leave=False)

    def done(key: str, rec: dict) -> None:
        records[key] = rec
        if pdir is not None:
            atomic_write(pdir / f"{key}.json", lambda p: p.write_text(json.dumps(rec)))
        if bar is not None:
            bar.update(1)

    use_dask = client is not None or executor == "dask" or (
        executor == "auto" and len(missing) > 1 and _have_distributed())
    try:
        if missing and use_dask:
            from distributed import as_completed

            with _dask_client(client) as cl:
                futures = {cl.submit(_evaluate_point, spec, kw, s, tuple(chains),
                                     pure=False): key for _, s, kw, key in missing}
                try:
                    for fut in as_completed(futures):
                        done(futures[fut], fut.result())
                except BaseException:
                    cl.cancel(list(futures))
                    raise
        else:
            for _, s, kw, key in missing:
                done(key, _evaluate_point(spec, kw, s, chains))
    finally:
        if bar is not None:
            bar.close()

    data = {m: np.full(shape, np.nan) for m in METRICS}
    thresholds = {k: np.full(shape[1:-1], np.nan)
                  for k in ("velocity_bin", "half_beamwidth_deg", "doppler_bin_hz")}
    warn: list[str] = []
    source = set()
    for g, s, kw, key in todo:
        rec = records[key]
        for ci, c in enumerate(chains):
            for m in METRICS:
                data[m][(ci,) + g + (s,)] = rec["metrics"][c][m]
        for k in thresholds:
            thresholds[k][g] = rec["criteria"][k]
        warn.extend(f"{kw}: {w}" for w in rec["warnings"])
        source.add(rec["strapdown"])
    dims = ("chain",) + tuple(names) + ("seed",)
    coords = {"chain": list(chains), "seed": np.arange(n_seed)}
    coords.update({n: v for n, v in zip(names, values, strict=True)})
    ds = xr.Dataset({m: (dims, data[m]) for m in METRICS}, coords=coords)
    for k, v in thresholds.items():
        ds[k] = (tuple(names), v)
    ds["fail"] = ((np.abs(ds.pseudo_velocity) > ds.velocity_bin)
                  | (ds.angle_error_deg > ds.half_beamwidth_deg))
    if "none" in chains:
        base = ds.sel(chain="none")
        ds["worse_than_none"] = ((np.abs(ds.pseudo_velocity) > np.abs(base.pseudo_velocity))
                                 | (ds.angle_error_deg > base.angle_error_deg + 1e-9))
    ds.attrs.update({"map": spec.name, "title": spec.title, "note": spec.note,
                     "quick": int(quick), "strapdown": ", ".join(sorted(source - {""})),
                     "units": json.dumps({a[0]: a[1] for a in spec.axes}),
                     "warnings": json.dumps(sorted(set(warn))[:50])})
    for a in spec.axes:
        ds[a[0]].attrs["units"] = a[1]
    return ds


# --------------------------------------------------------------- outputs
def _netcdf_engine() -> str:
    """``netcdf4`` (NetCDF-4) when netCDF4 imports, as :func:`raysim.io.storage.netcdf_engine`.

    Falls back to ``h5netcdf``, then to ``scipy`` (NetCDF-3) only in an
    installation without netCDF4 (a raysim dependency). Files of any of them
    are read by the netcdf4 engine.
    """
    from raysim.io.storage import netcdf_engine

    return netcdf_engine() or "scipy"


def write_netcdf(ds, path: str | os.PathLike) -> Path:
    """Write a stability dataset to NetCDF atomically (booleans stored as int8)."""
    out = ds.copy()
    for name in list(out.data_vars):
        if out[name].dtype == bool:
            out[name] = out[name].astype(np.int8)
            out[name].attrs["dtype"] = "bool"
    return atomic_write(path, lambda p: out.to_netcdf(p, engine=_netcdf_engine()))


def read_netcdf(path: str | os.PathLike):
    """Read a dataset written by :func:`write_netcdf` (booleans restored)."""
    import xarray as xr

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"stability NetCDF file {str(path)!r} does not exist")
    try:
        with xr.open_dataset(path, engine=_netcdf_engine()) as f:
            ds = f.load()
    except (OSError, ValueError, TypeError) as exc:
        raise ValueError(f"stability NetCDF file {str(path)!r} is unreadable or truncated: "
                         f"{exc}") from None
    for name in list(ds.data_vars):
        if ds[name].attrs.get("dtype") == "bool":
            ds[name] = ds[name].astype(bool)
    return ds


def failing_values(fail_fraction) -> dict:
    """The failure boundary as a table: failing values of axis 0 per value of axis 1.

    Parameters
    ----------
    fail_fraction : xarray.DataArray
        Fraction of seeds failing, dims ``(<axis 0>, <axis 1>)`` (one chain).

    Returns
    -------
    dict
        ``{f"{axis-1 value:g}": [axis-0 values where fraction >= 0.5]}``.
    """
    a0, a1 = fail_fraction.dims
    out = {}
    for v1 in fail_fraction[a1].values:
        col = fail_fraction.sel({a1: v1}).values >= 0.5
        out[f"{v1:g}"] = [float(v) for v in fail_fraction[a0].values[col]]
    return out


def _summary(ds) -> dict:
    """JSON-ready summary: metric arrays (seed median) and failure flags per chain."""
    out = {"map": ds.attrs["map"], "title": ds.attrs["title"], "note": ds.attrs["note"],
           "quick": bool(ds.attrs["quick"]), "strapdown": ds.attrs.get("strapdown", ""),
           "axes": {}, "chains": {}}
    axes = [d for d in ds.pseudo_velocity.dims if d not in ("chain", "seed")]
    for a in axes:
        out["axes"][a] = {"units": ds[a].attrs.get("units", ""), "values": ds[a].values.tolist()}
    out["velocity_bin"] = ds.velocity_bin.values.tolist()
    out["half_beamwidth_deg"] = ds.half_beamwidth_deg.values.tolist()
    for c in ds.chain.values.tolist():
        sub = ds.sel(chain=c)
        rec = {m: np.round(sub[m].median("seed").values, 6).tolist() for m in METRICS}
        rec["fail_fraction"] = sub.fail.mean("seed").values.tolist()
        rec["failing"] = failing_values(sub.fail.mean("seed"))
        if "worse_than_none" in ds:
            rec["worse_than_none_fraction"] = sub.worse_than_none.mean("seed").values.tolist()
        out["chains"][c] = rec
    out["warnings"] = json.loads(ds.attrs.get("warnings", "[]"))
    return out


def _tick_labels(axis: str, values) -> list[str]:
    names = {"init_index": _INITS, "term_index": IMU_TERMS, "error_axis_index": ("X", "Y", "Z")}
    if axis in names:
        return [names[axis][int(v)] for v in values]
    return [f"{v:g}" for v in values]


def plot_map(ds, path: str | os.PathLike) -> Path:
    """Figure of a stability map with the failure boundary drawn (matplotlib Agg).

    Rows: residual pseudo-velocity [Doppler bins] and angle error [half
    beamwidths]; columns: chains. Colour is log10 of the normalised metric, so
    the failure boundary of each criterion is the 0 contour (drawn black), the
    boundary of the combined criterion (either fails, majority of seeds) is
    dotted white, and where a chain is worse than no compensation the boundary
    of that region is drawn dashed red.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    axes = [d for d in ds.pseudo_velocity.dims if d not in ("chain", "seed")]
    chains = ds.chain.values.tolist()
    pv = (np.abs(ds.pseudo_velocity) / ds.velocity_bin).median("seed")
    ae = (ds.angle_error_deg / ds.half_beamwidth_deg).median("seed")
    worse = ds.worse_than_none.mean("seed") if "worse_than_none" in ds else None
    fail = ds.fail.mean("seed")
    fig, grid = plt.subplots(2, len(chains), figsize=(3.6 * len(chains), 6.4), squeeze=False)
    fig.subplots_adjust(left=0.08, right=0.9, bottom=0.09, top=0.9, wspace=0.42, hspace=0.42)
    for row, (metric, label) in enumerate(((pv, "|v| / Doppler bin"),
                                           (ae, "angle error / half beamwidth"))):
        for col, c in enumerate(chains):
            ax = grid[row, col]
            z = np.log10(np.maximum(metric.sel(chain=c).values, 1e-3))
            if len(axes) == 1:
                z = z[:, None]
                xs, ys = np.arange(ds[axes[0]].size), np.array([0.0])
            else:
                xs, ys = np.arange(ds[axes[1]].size), np.arange(ds[axes[0]].size)
            mesh = ax.pcolormesh(xs, ys, z if len(axes) > 1 else z.T, vmin=-2, vmax=2,
                                 cmap="RdYlGn_r", shading="nearest")
            if min(z.shape) > 1:
                ax.contour(xs, ys, z, levels=[0.0], colors="k", linewidths=2)
                f = fail.sel(chain=c).values.astype(float)
                if 0 < f.max() and f.min() < 1:
                    ax.contour(xs, ys, f, levels=[0.5], colors="w", linestyles=":",
                               linewidths=1.5)
                if worse is not None and c != "none":
                    w = worse.sel(chain=c).values.astype(float)
                    if 0 < w.max() and w.min() < 1:
                        ax.contour(xs, ys, w, levels=[0.5], colors="r", linestyles="--")
            if len(axes) > 1:
                ax.set_xticks(xs, _tick_labels(axes[1], ds[axes[1]].values), fontsize=7)
                ax.set_yticks(ys, _tick_labels(axes[0], ds[axes[0]].values), fontsize=7)
                ax.set_xlabel(f"{axes[1]} [{ds[axes[1]].attrs.get('units', '')}]", fontsize=8)
            if col == 0:
                ax.set_ylabel(f"{axes[0]} [{ds[axes[0]].attrs.get('units', '')}]", fontsize=8)
            ax.set_title(f"{c}: {label}", fontsize=8)
        cax = fig.add_axes([0.92, 0.56 - 0.47 * row, 0.012, 0.34])
        fig.colorbar(mesh, cax=cax, label="log10 (fail above 0)")
    fig.suptitle(f"{ds.attrs['title']}  (black: boundary of this criterion; white dotted: "
                 f"either criterion fails; red dashed: worse than none)", fontsize=9)
    path = Path(path)

    def write(tmp: Path) -> None:
        fig.savefig(tmp, format="png", dpi=100)

    try:
        return atomic_write(path, write)
    finally:
        plt.close(fig)


def write_stability(out_dir: str | os.PathLike, *, quick: bool = False,
                    maps: Sequence[str] | None = None, progress: bool = True,
                    executor: str = "auto") -> dict:
    """Produce every stability map: NetCDF, JSON and PNG per map plus ``summary.json``.

    Each file is written atomically; a map already finished in ``out_dir``
    (its ``.nc`` exists with the same ``quick`` flag) is reused, and every
    finished point of an unfinished map is kept under ``points/<map>/``, so an
    interrupted run resumes where it stopped.

    Parameters
    ----------
    out_dir : path-like
    quick : bool
        Small axes and fewer seeds (a few minutes on 2 cores).
    maps : sequence of str, optional
        Subset of :data:`MAPS` (default all).
    progress : bool
        Progress bars on stderr.
    executor : {"auto", "dask", "serial"}
        See :func:`run_map`.

    Returns
    -------
    dict
        ``map name -> summary`` (also written to ``summary.json``).
    """
    out = Path(out_dir)
    names = list(MAPS) if maps is None else list(maps)
    for n in names:
        if n not in MAPS:
            raise ValueError(f"unknown stability map {n!r}; expected one of {sorted(MAPS)}")
    if executor not in ("auto", "dask", "serial"):
        raise ValueError(f"executor must be 'auto', 'dask' or 'serial', got {executor!r}")
    out.mkdir(parents=True, exist_ok=True)
    with contextlib.ExitStack() as stack:
        client = None
        if executor == "dask" or (executor == "auto" and _have_distributed()):
            client = stack.enter_context(_dask_client())
        return _write_maps(out, names, quick, progress, client)


def _same_axes(ds, spec: MapSpec, quick: bool) -> bool:
    """Whether a stored map was computed on the axes (and seeds) the spec asks for now."""
    if int(ds.attrs.get("quick", -1)) != int(quick):
        return False
    for name, _, full, short in spec.axes:
        want = np.asarray(short if quick else full, dtype=float)
        if name not in ds.coords or ds[name].size != want.size or not np.allclose(
                ds[name].values, want):
            return False
    return ds.sizes.get("seed", 0) == (spec.quick_seeds if quick else spec.seeds)


def _write_maps(out: Path, names: list, quick: bool, progress: bool, client) -> dict:
    summary = {}
    for n in names:
        nc = out / f"{n}.nc"
        ds = None
        if nc.exists():
            try:
                old = read_netcdf(nc)
            except ValueError:
                old = None                     # unreadable: recompute and replace
            if old is not None and _same_axes(old, MAPS[n], quick):
                ds = old
        if ds is None:
            t = time.perf_counter()
            ds = run_map(n, quick=quick, progress=progress, client=client,
                         executor="serial" if client is None else "dask",
                         points_dir=out / "points" / f"{n}{'_quick' if quick else ''}")
            ds.attrs["seconds"] = round(time.perf_counter() - t, 2)
            write_netcdf(ds, nc)
        summ = _summary(ds)
        atomic_write(out / f"{n}.json", lambda p, s=summ: p.write_text(json.dumps(s, indent=1)))
        plot_map(ds, out / f"{n}.png")
        summary[n] = summ
    atomic_write(out / "summary.json",
                 lambda p: p.write_text(json.dumps(summary, indent=1)))
    return summary
