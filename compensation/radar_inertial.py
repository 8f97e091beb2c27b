"""Radar-inertial estimation over a record: the IMU propagated, the radar Doppler as update.

One error state over the whole record, defined at the reference time (the
record's first chirp) as a correction to a strapdown integration
(:func:`compensation.integrate_imu`, velocity given):

============  =====  =======================================================
name          unit   correction of
============  =====  =======================================================
velocity_*    m/s    initial body velocity in W (north, east, down)
tilt_n/e      rad    initial attitude, rotation about W north / east (roll
                     and pitch at zero heading), ``R = exp([phi]x) R_est``
heading       rad    the same about W down
accel_bias_*  m/s^2  accelerometer bias in B (subtracted from the samples)
gyro_bias_*   rad/s  gyro bias in B (subtracted from the samples)
clock_offset  s      IMU clock minus radar clock
clock_drift   1      IMU clock rate minus radar clock rate
============  =====  =======================================================

The radar measures, per frame or per block of chirps, the residual range rate
of every stationary scatterer after a compensation with the current motion:
``v_r = -u . dv_R`` with ``u`` its direction (W) and ``dv_R`` the error of the
radar phase-centre velocity (Kellner et al., ITSC 2013, eq. 3-5). Over the
record ``dv_R(t)`` is linear in the state: the Jacobian ``H`` of the
least-squares slope of ``-u . p_R(t)`` over each block is taken by central
differences of the strapdown integration itself (the same model as the
compensation, lever arm, rotation of the biases, clock mapping included). The
estimate is the Gauss-Newton solution of prior plus measurements, iterated
with the measurements retaken at the corrected motion (a batch smoother over
the frames, as radar-inertial odometry does: Doer and Trommer, "An EKF based
approach to radar inertial odometry", MFI 2020, with the whole record in one
window). IMU white noise enters as a correlated measurement noise: the
velocity error it leaves is a random walk (accelerometer, ``N_a^2 min(s, s')``)
plus an integrated one through gravity (gyro, ``g^2 N_g^2 s^2 (3 s' - s) / 6``,
``s <= s'``, horizontal axes), ``s`` the time since the reference.

Observability: in prior-whitened coordinates ``w = L^-1 x`` (``P0 = L L^T``)
the Fisher information of the radar is ``L^T H^T C^-1 H L``; along an
eigenvector of eigenvalue ``lambda`` the posterior spread is
``1 / sqrt(1 + lambda)`` of the prior's. A component or direction whose
posterior spread stays above :data:`compensation.observability.UNCONSTRAINED_RATIO` of the prior is
unconstrained: the scene leaves it at the prior (the IMU's value), and it is
named in the result. Typical: the tilt and the horizontal accelerometer bias
give the same horizontal acceleration error (``g x phi + R b_a``), so the
radar constrains their sum only; scatterers in one row or a narrow cone leave
the velocity across them to the prior. The unconstrained attitude, gyro-bias
and clock components are held at the prior and their spread carried into the
others' covariance (:func:`solve_batch`, consider analysis), so the given
attitude is not turned by a split the radar cannot make; unconstrained is judged
again on the spreads scaled by the Doppler's reduced chi-square (model error), one
per group of measurements where the ground clutter joins the detected scatterers
(:func:`compensation.batch_solve.group_scales`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from ._checks import finite_array, positive
from .batch_solve import DETECTED_GROUP, GROUND_GROUP, group_scales, solve_batch
from .block_velocity import block_covariance, block_velocity_variance
from .ego_velocity import MIN_CONSENSUS, block_misfit, fit_ego_velocity
from .guards import CompensationWarning
from .multiframe import integrate_record
from .observability import (
    STATE_NAMES,
    ObservabilityWarning,
    held_mask,
    observability,
    observability_warnings,
)
from .strapdown import STANDARD_GRAVITY, PlatformMotion
from .velocity_signal import imu_noise_terms, smoothed_motions

__all__ = ["DETECTED_GROUP", "GROUND_GROUP", "STATE_NAMES", "DopplerMeasurements", "ImuErrors",
           "ObservabilityWarning", "RadarInertialResult", "estimate_radar_inertial",
           "prior_sigmas", "solve_batch"]

#: Groups of :data:`STATE_NAMES` by slice.
VELOCITY, ATTITUDE, ACCEL_BIAS, GYRO_BIAS = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)
CLOCK_OFFSET, CLOCK_DRIFT = 12, 13
#: Central-difference steps of the Jacobian, per component (units of the state): small
#: against the state's reach, large against the integration's rounding.
JACOBIAN_STEPS = np.array([1e-3] * 3 + [1e-4] * 3 + [1e-3] * 3 + [1e-5] * 3 + [1e-5, 1e-6])
#: Most Doppler measurements of one estimate: their covariance is dense (the IMU's
#: random walks correlate every block), 4000^2 float64 is 128 MB and a solve takes seconds.
MAX_MEASUREMENTS = 4000
#: Default Gauss-Newton passes (measure, linearise, solve, integrate).
ITERATIONS = 3
#: Huber threshold of the measurement residuals [standard deviations] (Huber 1964).
HUBER_K = 3.0
#: Reweighting passes of the Huber estimate within one Gauss-Newton pass.
HUBER_PASSES = 4
#: Default prior spread of the velocity correction on each axis [m/s] (the hover guess
#: misses the platform's mean velocity over its window).
VELOCITY_PRIOR_SIGMA = 1.0
#: Default prior spread of roll and pitch when the attitude is given [rad] (a flight
#: controller's attitude estimate, about 1 deg).
GIVEN_TILT_SIGMA = float(np.deg2rad(1.0))
#: Default prior spread of roll and pitch when it is not given [rad] (the nominal hover
#: attitude, about 5 deg off).
DEFAULT_TILT_SIGMA = float(np.deg2rad(5.0))
#: Spread of a flight controller's roll and pitch error common to the frames of a record
#: [rad]: over a record of a second its error hardly changes (the accelerometer's
#: horizontal bias left after the level calibration: 2 mg is 0.11 deg).
TRACK_COMMON_SIGMA = float(np.deg2rad(0.1))
#: Spread of its error independent from frame to frame [rad] (the filter's wander).
TRACK_FRAME_SIGMA = float(np.deg2rad(0.03))
#: Default prior spread of the heading [rad].
HEADING_PRIOR_SIGMA = float(np.deg2rad(10.0))
#: Default prior spread of the clock offset when nothing estimated it [s].
CLOCK_OFFSET_PRIOR_SIGMA = 1e-3
#: Default prior spread of the clock drift [1] (100 ppm: uncompensated crystals).
CLOCK_DRIFT_PRIOR_SIGMA = 100e-6


@dataclass(frozen=True)
class ImuErrors:
    """IMU error figures the estimator needs, as numbers (one sigma, per axis).

    Attributes
    ----------
    accel_noise_density : float
        Velocity random walk [m/s^2/sqrt(Hz)].
    gyro_noise_density : float
        Angle random walk [rad/s/sqrt(Hz)].
    accel_bias_sigma : float
        Accelerometer bias (turn-on plus instability) [m/s^2].
    gyro_bias_sigma : float
        Gyro bias (turn-on plus instability) [rad/s].
    accel_scale_sigma : float
        Scale-factor and misalignment error of the accelerometer, each entry
        of its error matrix [1]: on the vibration and manoeuvre accelerations
        it looks like a tilt, so it bounds what they tell of the attitude.
    """

    accel_noise_density: float
    gyro_noise_density: float
    accel_bias_sigma: float
    gyro_bias_sigma: float
    accel_scale_sigma: float = 0.0

    def __post_init__(self) -> None:
        for name in ("accel_noise_density", "gyro_noise_density", "accel_bias_sigma",
                     "gyro_bias_sigma", "accel_scale_sigma"):
            v = float(getattr(self, name))
            if not np.isfinite(v) or v < 0:
                raise ValueError(f"ImuErrors.{name}: got {v!r}, expected a finite number >= 0")
            object.__setattr__(self, name, v)


def prior_sigmas(imu: ImuErrors, *, velocity: float = VELOCITY_PRIOR_SIGMA,
                 tilt: float = GIVEN_TILT_SIGMA, heading: float = HEADING_PRIOR_SIGMA,
                 clock_offset: float = CLOCK_OFFSET_PRIOR_SIGMA,
                 clock_drift: float = CLOCK_DRIFT_PRIOR_SIGMA) -> np.ndarray:
    """One-sigma prior spreads of :data:`STATE_NAMES`, shape ``[14]`` (their units).

    Biases from the IMU figures; a zero figure (an ideal IMU) gets a spread of a
    millionth of the unit, so the prior stays invertible.
    """
    s = np.array([velocity] * 3 + [tilt, tilt, heading] + [imu.accel_bias_sigma] * 3
                 + [imu.gyro_bias_sigma] * 3 + [clock_offset, clock_drift], dtype=float)
    if not np.all(np.isfinite(s)) or np.any(s < 0):
        raise ValueError(f"prior spreads must be finite and >= 0, got {s.tolist()}")
    return np.maximum(s, 1e-6 * np.where(np.arange(14) == CLOCK_OFFSET, 1e-3, 1.0))


@dataclass(frozen=True)
class DopplerMeasurements:
    """Residual range rates of stationary scatterers, one per scatterer and block.

    Attributes
    ----------
    directions : ndarray, shape ``[measurement, 3]``
        Unit direction to the scatterer in W [1].
    range_rate : ndarray, shape ``[measurement]``
        Residual range rate after compensation with the current motion [m/s]
        (positive receding).
    sigma : ndarray, shape ``[measurement]``
        Its one-sigma spread [m/s].
    frame : ndarray of int, shape ``[measurement]``
        Frame of the measurement.
    window : ndarray, shape ``[measurement, 2]``
        First and last chirp time of its block [s, radar clock].
    direction_cov : ndarray, shape ``[measurement, 3, 3]``, optional
        Covariance of the direction's error [1], the same for every block of
        one scatterer (an axis the array does not resolve has a large one);
        default none. Its effect ``-du . v`` on the range rate is constant
        over the record: correlated across the scatterer's blocks.
    group : ndarray of int, shape ``[measurement]``, optional
        Source of the measurement, :data:`DETECTED_GROUP` (default) or
        :data:`GROUND_GROUP`: each group's spreads get their own scale
        (:func:`compensation.batch_solve.group_scales`).
    """

    directions: np.ndarray
    range_rate: np.ndarray
    sigma: np.ndarray
    frame: np.ndarray
    window: np.ndarray
    direction_cov: np.ndarray | None = None
    group: np.ndarray | None = None

    def __post_init__(self) -> None:
        u = finite_array("directions", self.directions, ndim=2)
        m = u.shape[0]
        if u.shape[1] != 3:
            raise ValueError(f"directions must have shape [measurement, 3], got {u.shape}")
        object.__setattr__(self, "directions", u)
        object.__setattr__(self, "range_rate", finite_array("range_rate", self.range_rate,
                                                            shape=(m,)))
        s = finite_array("sigma", self.sigma, shape=(m,))
        if np.any(s <= 0):
            raise ValueError(f"sigma must be > 0 m/s, got minimum {s.min()!r}")
        object.__setattr__(self, "sigma", s)
        object.__setattr__(self, "frame", np.asarray(self.frame, dtype=int).reshape(m))
        object.__setattr__(self, "window", finite_array("window", self.window, shape=(m, 2)))
        if self.direction_cov is not None:
            object.__setattr__(self, "direction_cov", finite_array(
                "direction_cov", self.direction_cov, shape=(m, 3, 3)))
        g = np.full(m, DETECTED_GROUP) if self.group is None else np.asarray(self.group)
        if g.shape != (m,) or not np.all(np.isin(g, (DETECTED_GROUP, GROUND_GROUP))):
            raise ValueError(f"group must hold {m} of {DETECTED_GROUP} (detected) or "
                             f"{GROUND_GROUP} (ground), got shape {g.shape}, values "
                             f"{np.unique(g).tolist()}")
        object.__setattr__(self, "group", g.astype(int))

    def select(self, keep) -> DopplerMeasurements:
        """The measurements where ``keep`` (bool ``[measurement]``) is true."""
        k = np.asarray(keep, dtype=bool)
        return DopplerMeasurements(self.directions[k], self.range_rate[k], self.sigma[k],
                                   self.frame[k], self.window[k],
                                   None if self.direction_cov is None else self.direction_cov[k],
                                   self.group[k])


@dataclass(frozen=True)
class RadarInertialResult:
    """Radar-inertial estimate of a record, its uncertainty and what the scene constrains.

    Attributes
    ----------
    state : ndarray, shape ``[14]``
        Correction of the integration's inputs (:data:`STATE_NAMES`, SI units).
    covariance : ndarray, shape ``[14, 14]``
        Posterior covariance of ``state``.
    prior_covariance : ndarray, shape ``[14, 14]``
    unconstrained : tuple of str
        Components whose posterior spread stays above
        :data:`compensation.observability.UNCONSTRAINED_RATIO` of the prior's
        (left at the prior by the scene).
    weak_directions : tuple of str
        Unconstrained directions of the state, as combinations of the
        components in units of their prior spreads (largest terms).
    motions : tuple of PlatformMotion
        Per-frame motion integrated with the corrected inputs, plus the IMU noise's
        velocity error estimated from the Doppler residuals (``noise_velocity_mps``).
    initial_velocity : ndarray, shape ``[3]``
        Body velocity in W at the reference time [m/s].
    initial_attitude : ndarray, shape ``[3, 3]``
        ``R_WB`` at the reference time, corrected.
    time_offset : float
        IMU clock minus radar clock at the reference time [s].
    gyro_bias : ndarray, shape ``[3]``
        Total gyro bias removed [rad/s] (the one given plus the correction).
    chi2 : float
        Reduced chi-square of the measurements at the solution (above one and one
        group of measurements: the radar spreads were scaled up by it).
    measurements : int
        Doppler measurements used (inliers).
    rejected : int
        Doppler measurements rejected as moving or spurious.
    warnings : tuple of str
        Observability and geometry warnings (also issued as
        :class:`ObservabilityWarning`).
    misfit_sigma : float
        Spread of the Doppler model's misfit added to every range rate's
        [m/s] (:func:`compensation.ego_velocity.block_misfit`).
    group_scale : tuple of float
        Factor of the spreads' variance of each group of measurements (detected,
        ground) [1], at least one: ``max(chi2, 1)`` with one group, their own
        reduced chi-squares with both (:func:`compensation.batch_solve.group_scales`).
    block_velocity_sigma : tuple of float
        Spread of the velocity error common to each block's rows along W's
        axes [m/s] (:mod:`compensation.block_velocity`), at the last pass.
    noise_velocity_mps : float
        Largest correction of ``motions`` by the IMU noise's velocity error the Doppler
        residuals show [m/s] (:mod:`compensation.velocity_signal`; 0 unsmoothed).
    """

    state: np.ndarray
    covariance: np.ndarray
    prior_covariance: np.ndarray
    unconstrained: tuple[str, ...]
    weak_directions: tuple[str, ...]
    motions: tuple[PlatformMotion, ...]
    initial_velocity: np.ndarray
    initial_attitude: np.ndarray
    time_offset: float
    gyro_bias: np.ndarray
    chi2: float
    measurements: int
    rejected: int
    warnings: tuple[str, ...] = field(default_factory=tuple)
    misfit_sigma: float = 0.0
    group_scale: tuple[float, ...] = ()
    block_velocity_sigma: tuple[float, ...] = ()
    noise_velocity_mps: float = 0.0

    @property
    def sigma(self) -> np.ndarray:
        """Posterior one-sigma spread of every component, shape ``[14]``."""
        return np.sqrt(np.diag(self.covariance))

    @property
    def initial_velocity_covariance(self) -> np.ndarray:
        """Covariance of :attr:`initial_velocity`, shape ``[3, 3]`` [m^2/s^2]."""
        return self.covariance[VELOCITY, VELOCITY]

    def report(self) -> dict:
        """Estimates, one-sigma spreads and the unconstrained components (SI units)."""
        prior = np.sqrt(np.diag(self.prior_covariance))
        return {"state_names": list(STATE_NAMES), "state": self.state.tolist(),
                "sigma": self.sigma.tolist(), "prior_sigma": prior.tolist(),
                "unconstrained": list(self.unconstrained),
                "weak_directions": list(self.weak_directions), "chi2": self.chi2,
                "measurements": self.measurements, "rejected": self.rejected,
                "misfit_sigma": self.misfit_sigma, "group_scale": list(self.group_scale),
                "block_velocity_sigma_mps": list(self.block_velocity_sigma),
                "noise_velocity_mps": self.noise_velocity_mps, "warnings": list(self.warnings)}


def _ls_slope(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Least-squares slope of ``y [time, ...]`` against ``t [time]``."""
    tc = t - t.mean()
    return np.tensordot(tc, y - y.mean(axis=0), axes=(0, 0)) / np.sum(tc ** 2)


def _noise_cov(meas: DopplerMeasurements, imu: ImuErrors, t_ref: float, gravity: float,
               dv: np.ndarray, v_radar: np.ndarray, v_cov: np.ndarray) -> np.ndarray:
    """Measurement covariance: radar spreads, the velocity errors the IMU's noise and
    scale errors leave, and the scatterers' direction errors.

    ``dv [measurement, 3]``: the IMU's velocity change since the reference over
    each block [m/s]; an error matrix of iid entries of spread ``s`` on the
    acceleration leaves ``dM dv``, of covariance ``s^2 (dv_m . dv_n) I``. A
    direction error ``du`` (covariance ``D``) of a scatterer leaves ``-du . v``
    in each of its blocks: covariance ``v_m^T D v_n + tr(D V)`` between them,
    ``v`` the current radar velocity ``[measurement, 3]`` and ``V`` the
    covariance of the velocity estimate ``[3, 3]`` (the true velocity's spread
    about it).
    """
    s = meas.window.mean(axis=1) - t_ref
    q_iso, q_tilt = imu_noise_terms(s, s, dv, dv, imu, gravity)     # the IMU's, as smoothed
    u = meas.directions
    out = np.diag(meas.sigma ** 2) + q_iso * (u @ u.T) + q_tilt * (u[:, :2] @ u[:, :2].T)
    if meas.direction_cov is not None:
        same = np.all(np.abs(u[:, None, :] - u[None, :, :]) < 1e-12, axis=2)
        d = meas.direction_cov
        q_dir = (np.einsum("mi,mij,nj->mn", v_radar, d, v_radar)
                 + np.einsum("mij,ji->m", d, v_cov)[:, None])
        out += np.where(same, q_dir, 0.0)
    return out


def _block_velocity(motions, meas: DopplerMeasurements) -> np.ndarray:
    """Least-squares slope of the radar position over each measurement's block, ``[m, 3]``
    [m/s] (what the slow-time phase slope of a block measures)."""
    blocks, which = np.unique(np.column_stack([meas.frame, meas.window]), axis=0,
                              return_inverse=True)
    out = np.empty((blocks.shape[0], 3))
    for b, (k, lo, hi) in enumerate(blocks):
        m = motions[int(k)]
        sel = (m.time >= lo - 1e-12) & (m.time <= hi + 1e-12)
        out[b] = _ls_slope(m.time[sel], m.radar_position[sel])
    return out[which.ravel()]


def _velocity_change(meas: DopplerMeasurements, motions, v_ref: np.ndarray) -> np.ndarray:
    """Mean body velocity over each measurement's block minus ``v_ref``, ``[measurement, 3]``."""
    out = np.empty((meas.frame.size, 3))
    for j, (k, (a, b)) in enumerate(zip(meas.frame, meas.window, strict=True)):
        m = motions[int(k)]
        sel = (m.time >= a - 1e-12) & (m.time <= b + 1e-12)
        out[j] = m.velocity[sel].mean(axis=0) - v_ref
    return out


def estimate_radar_inertial(imu_time, gyro, accel, frame_times: Sequence,
                            measure: Callable[[list], DopplerMeasurements], *,
                            imu_errors: ImuErrors, initial_velocity, initial_attitude=None,
                            time_offset: float = 0.0, gyro_bias=(0.0, 0.0, 0.0),
                            prior_sigma=None, gyro_bias_cov=None,
                            clock_offset_sigma: float | None = None,
                            tilt_covariance=None, attitude_track=None,
                            attitude_given: bool = True,
                            reference_time: float | None = None,
                            iterations: int = ITERATIONS, gravity: float = STANDARD_GRAVITY,
                            warn: bool = True, smooth: bool = True,
                            **options) -> RadarInertialResult:
    """Velocity, attitude, IMU biases and clock of a record from its IMU log and radar.

    Parameters
    ----------
    imu_time, gyro, accel
        IMU log (:func:`compensation.integrate_imu`) [s, IMU clock; rad/s; m/s^2].
    frame_times : sequence of array_like
        Times of every frame (chirps or TDM slots) [s, radar clock].
    measure : callable
        ``measure(motions) -> DopplerMeasurements``: residual range rates of the
        stationary scatterers after a compensation with ``motions`` (one
        :class:`PlatformMotion` per frame).
    imu_errors : ImuErrors
        Noise densities and bias spreads of the IMU.
    initial_velocity : array_like, shape ``[3]``
        Body velocity in W at the reference time of the first guess [m/s]
        (the hover guess, or the flight controller's).
    initial_attitude : array_like ``[3, 3]``, optional
        ``R_WB`` at the reference time of the first guess; default identity.
    time_offset : float
        IMU clock minus radar clock of the first guess [s].
    gyro_bias : array_like, shape ``[3]``
        Gyro bias already removed [rad/s].
    prior_sigma : array_like, shape ``[14]``, optional
        Prior spreads; default :func:`prior_sigmas` of ``imu_errors`` with the
        tilt spread of ``attitude_given``.
    gyro_bias_cov : array_like ``[3, 3]``, optional
        Covariance of ``gyro_bias`` when it was estimated (replaces the IMU's).
    clock_offset_sigma : float, optional
        Spread of ``time_offset`` when it was estimated [s].
    tilt_covariance : array_like ``[2, 2]``, optional
        Covariance of ``initial_attitude``'s roll and pitch (``tilt_n, tilt_e``)
        when they were measured, e.g. from the ground plane
        (:mod:`compensation.ground_plane`) [rad^2]; replaces the prior's.
    attitude_track : (array_like, array_like), optional
        A flight controller's attitude: times ``[sample]`` [s, IMU clock] and ``R_WB``
        ``[sample, 3, 3]``, spanning the record; its roll and pitch at the first time
        of every frame (on the IMU clock of the state) measure the integrated
        attitude's there (errors
        :data:`TRACK_COMMON_SIGMA` common to the frames and
        :data:`TRACK_FRAME_SIGMA` per frame), which keeps a gyro's drift out of
        the tilt over the record.
    attitude_given : bool
        Whether ``initial_attitude`` is a real estimate (a flight controller's,
        levelled) rather than the nominal hover attitude: sets the default tilt
        prior, and a warning names the tilt when it stays unconstrained.
    reference_time : float, optional
        Time of the state [s, radar clock]; default the first time.
    iterations : int
        Gauss-Newton passes.
    gravity : float
        [m/s^2].
    warn : bool
        Issue the warnings as :class:`ObservabilityWarning` (they are in the
        result either way).
    smooth : bool
        Add the IMU noise's velocity error the Doppler residuals show to the motions
        (:mod:`compensation.velocity_signal`).
    **options
        For :func:`compensation.integrate_imu` (``lever_arm``,
        ``initial_position`` ...); not ``velocity`` nor ``initial_velocity``.

    Returns
    -------
    RadarInertialResult
    """
    t_imu = finite_array("imu_time", imu_time, ndim=1)
    w = finite_array("gyro", gyro, shape=(t_imu.size, 3))
    f = finite_array("accel", accel, shape=(t_imu.size, 3))
    frames = [finite_array("frame_times", ft, ndim=1) for ft in frame_times]
    v0 = finite_array("initial_velocity", initial_velocity, shape=(3,))
    r0 = np.eye(3) if initial_attitude is None else finite_array(
        "initial_attitude", initial_attitude, shape=(3, 3))
    bg0 = finite_array("gyro_bias", gyro_bias, shape=(3,))
    tau0 = float(finite_array("time_offset", time_offset, shape=()))
    g = positive("gravity", gravity)
    if int(iterations) < 1:
        raise ValueError(f"iterations: got {iterations!r}, expected an integer >= 1")
    for k in ("velocity", "initial_velocity", "time_offset", "reference_time"):
        options.pop(k, None)
    t_ref = float(frames[0][0]) if reference_time is None else float(reference_time)
    sig0 = prior_sigmas(imu_errors, tilt=GIVEN_TILT_SIGMA if attitude_given
                        else DEFAULT_TILT_SIGMA) if prior_sigma is None else finite_array(
        "prior_sigma", prior_sigma, shape=(14,))
    if tilt_covariance is not None:
        tc = finite_array("tilt_covariance", tilt_covariance, shape=(2, 2))
        sig0 = sig0.copy()
        sig0[3:5] = np.sqrt(np.diag(tc))
    if np.any(sig0 <= 0):
        raise ValueError(f"prior_sigma must be > 0, got {sig0.tolist()}")
    track = None
    if attitude_track is not None:
        from scipy.spatial.transform import Slerp

        t_track = finite_array("attitude_track times", attitude_track[0], ndim=1)
        track = Slerp(t_track, Rotation.from_matrix(finite_array(
            "attitude_track", attitude_track[1], shape=(t_track.size, 3, 3))))
        n2 = 2 * len(frames)                      # (tilt_n, tilt_e) per frame
        first = np.array([f[0] for f in frames]) + tau0
        if first.min() < t_track[0] or first.max() > t_track[-1]:
            raise ValueError(f"attitude_track spans {t_track[0]:.6f} .. {t_track[-1]:.6f} s "
                             f"(IMU clock); the frames' first times on it span "
                             f"{first.min():.6f} .. {first.max():.6f} s")
        c_track = (TRACK_COMMON_SIGMA ** 2 * np.kron(np.ones((len(frames),) * 2), np.eye(2))
                   + TRACK_FRAME_SIGMA ** 2 * np.eye(n2))
    p0 = np.diag(sig0 ** 2)
    if tilt_covariance is not None:
        p0[3:5, 3:5] = tc
    if gyro_bias_cov is not None:
        p0[GYRO_BIAS, GYRO_BIAS] = finite_array("gyro_bias_cov", gyro_bias_cov, shape=(3, 3))
    if clock_offset_sigma is not None and np.isfinite(clock_offset_sigma):
        p0[CLOCK_OFFSET, CLOCK_OFFSET] = positive("clock_offset_sigma", clock_offset_sigma) ** 2

    def integrate(x: np.ndarray) -> list[PlatformMotion]:
        tau = tau0 + x[CLOCK_OFFSET]
        t_ref_imu = t_ref + tau
        # IMU clock rate 1 + d: radar time t is IMU time t + tau + d (t - t_ref)
        times = t_ref_imu + (t_imu - t_ref_imu) / (1.0 + x[CLOCK_DRIFT])
        att = Rotation.from_rotvec(x[ATTITUDE]).as_matrix() @ r0
        with warnings.catch_warnings():          # the first integration already warned
            warnings.simplefilter("ignore", CompensationWarning)
            return integrate_record(times, w - bg0 - x[GYRO_BIAS], f - x[ACCEL_BIAS], frames,
                                    time_offset=tau, velocity="given",
                                    initial_velocity=v0 + x[VELOCITY], initial_attitude=att,
                                    reference_time=t_ref, **options)

    def track_tilt(ms, x: np.ndarray) -> np.ndarray:
        """Roll and pitch of the track against the motions' attitude at every frame's first
        time, ``[2 frame]`` [rad] (``R_track = exp([d]x) R``, ``d`` in W), the track read
        at those times on the IMU clock of ``x``."""
        t = np.array([m.time[0] for m in ms])
        t_imu = t_ref + tau0 + x[CLOCK_OFFSET] + (t - t_ref) * (1.0 + x[CLOCK_DRIFT])
        r_track = track(t_imu).as_matrix()
        return np.concatenate([Rotation.from_matrix(r_track[k] @ m.attitude[0].T).as_rotvec()[
            :2] for k, m in enumerate(ms)])

    def jacobians(x: np.ndarray, meas: DopplerMeasurements):
        """``d(block radar velocity)/dx`` ``[measurement, 3, 14]`` and, with a track,
        ``d(track tilt)/dx`` ``[2 frame, 14]``, by central differences."""
        out = np.empty((meas.frame.size, 3, 14))
        att = None if track is None else np.empty((2 * len(frames), 14))
        for i, step in enumerate(JACOBIAN_STEPS):
            e = np.zeros(14)
            e[i] = step
            hi, lo = integrate(x + e), integrate(x - e)
            out[:, :, i] = (_block_velocity(hi, meas) - _block_velocity(lo, meas)) / (2 * step)
            if att is not None:
                att[:, i] = (track_tilt(hi, x + e) - track_tilt(lo, x - e)) / (2 * step)
        return out, att

    x = np.zeros(14)
    cov = p0
    motions = integrate(x)
    chi2, kept, rejected, fisher, misfit, scale = 1.0, 0, 0, np.zeros((14, 14)), 0.0, ()
    block_q = np.zeros(3)
    keep = held = dvdx = h_track = None
    for _ in range(int(iterations)):
        meas = measure(motions)
        if meas.frame.size > MAX_MEASUREMENTS:
            raise ValueError(f"the record gives {meas.frame.size} Doppler measurements (frames "
                             f"x blocks x scatterers); the radar-inertial estimate takes at "
                             f"most {MAX_MEASUREMENTS}: select fewer frames or scatterers")
        # the Doppler model's misfit and the static-world consensus once: later passes
        # measure the same scatterers and blocks
        if keep is None or keep.size != meas.frame.size:
            blocks = np.unique(np.column_stack([meas.frame, meas.window]), axis=0,
                               return_inverse=True)[1].ravel()
            misfit = block_misfit(meas.directions, meas.range_rate, meas.sigma, blocks)
            meas = _with_misfit(meas, misfit)
            keep = _consensus(meas)
        else:
            meas = _with_misfit(meas, misfit)
        rejected = int(np.count_nonzero(~keep))
        meas = meas.select(keep)
        kept = meas.frame.size
        if kept == 0:
            break
        # directions measured through the first-guess attitude, turned by its correction
        u = meas.directions @ Rotation.from_rotvec(x[ATTITUDE]).as_matrix().T
        v_radar = _block_velocity(motions, meas)
        if dvdx is None:     # the same blocks each pass: one linearisation (chord method)
            dvdx, h_track = jacobians(x, meas)
        # the radar velocity's change, and for the attitude also the direction's turn (u
        # was measured through the attitude: the two cancel but for gravity and the
        # velocity given in W)
        h = -np.einsum("mi,mij->mj", u, dvdx)
        h[:, ATTITUDE] -= np.cross(u, v_radar)
        c = _noise_cov(meas, imu_errors, t_ref, g,
                       _velocity_change(meas, motions, motions[0].velocity[0]), v_radar,
                       cov[VELOCITY, VELOCITY])
        # the beams looked along the measured directions, the model along the turned ones
        r = meas.range_rate - np.einsum("mi,mi->m", meas.directions - u, v_radar)
        if track is not None:        # the flight controller's roll and pitch per frame
            h, r = np.vstack([h, h_track]), np.concatenate([r, -track_tilt(motions, x)])
            c = np.block([[c, np.zeros((kept, n2))], [np.zeros((n2, kept)), c_track]])
        if held is None:            # the attitude, gyro and clock the scene leaves alone
            held = held_mask(p0, h.T @ np.linalg.solve(c, h))
        # a velocity error common to each block's rows (vibration the log misses)
        blocks = np.unique(np.column_stack([meas.frame, meas.window]), axis=0,
                           return_inverse=True)[1].ravel()
        block_q = block_velocity_variance(h, r, c, p0, x, u, blocks, held)
        c = c + block_covariance(u, blocks, block_q, rows=r.size)
        wts = np.ones(r.size)
        for _ in range(HUBER_PASSES):             # iteratively reweighted (Huber)
            cw = c / np.sqrt(np.outer(wts, wts))
            x_new, cov = solve_batch(h, r, cw, p0, x, held)
            z = (r - h @ (x_new - x)) / np.sqrt(np.diag(c))
            wts = np.minimum(1.0, HUBER_K / np.maximum(np.abs(z), 1e-12))
        res = r - h @ (x_new - x)
        fisher = h.T @ np.linalg.solve(cw, h)
        hat = np.trace(np.linalg.solve(np.linalg.inv(p0) + fisher, fisher))
        # the Doppler's reduced chi-square (the track's spreads are the controller's own)
        chi2 = float(res[:kept] @ np.linalg.solve(cw[:kept, :kept], res[:kept])) / max(
            kept - hat, 1.0)
        both = np.unique(meas.group).size > 1
        if both:                  # each group's spreads by its own reduced chi-square
            scale = group_scales(h, r, cw, p0, x, meas.group, held)
        else:
            scale = np.ones(meas.group.max() + 1)
            scale[meas.group[0]] = max(chi2, 1.0)
        if np.any(scale > 1.0):   # spreads understated (model error): scale the radar's
            if both:
                root = np.sqrt(scale[meas.group])
                cw[:kept, :kept] *= np.outer(root, root)
            else:
                cw[:kept, :kept] *= chi2
            fisher = h.T @ np.linalg.solve(cw, h)
        # what the (scaled) spreads leave unconstrained is held too: reported as kept at
        # the prior, it must not move with the model error (nor keep an earlier pass's
        # move: it goes back to the first guess, the residuals with it)
        newly = held_mask(p0, fisher) & ~held
        if np.any(scale > 1.0) or np.any(newly):
            held, r, x = held | newly, r + h[:, newly] @ x[newly], np.where(newly, 0.0, x)
            x_new, cov = solve_batch(h, r, cw, p0, x, held)
        res, x = r - h @ (x_new - x), x_new               # the residuals at the solution
        motions = integrate(x)
    smoothed = 0.0
    if kept and smooth:      # the IMU noise's velocity error the Doppler residuals show
        motions, smoothed = smoothed_motions(
            motions, t_ref, meas.window.mean(axis=1), h[:kept, VELOCITY],
            np.linalg.solve(cw, res)[:kept],
            _velocity_change(meas, motions, motions[0].velocity[0]), imu_errors, g)
    cov = _tilt_leak(cov, r0, g)
    names, dirs = observability(p0, fisher)
    notes = observability_warnings(names, np.sqrt(np.diag(cov)), sig0, attitude_given,
                                   meas.directions if kept else None)
    if warn:
        for text in notes:
            warnings.warn(text, ObservabilityWarning, stacklevel=2)
    att = Rotation.from_rotvec(x[ATTITUDE]).as_matrix() @ r0
    return RadarInertialResult(x, cov, p0, names, dirs, tuple(motions), v0 + x[VELOCITY], att,
                               tau0 + float(x[CLOCK_OFFSET]), bg0 + x[GYRO_BIAS], chi2, kept,
                               rejected, notes, misfit, tuple(float(v) for v in scale),
                               tuple(float(v) for v in np.sqrt(block_q)), smoothed)


def _tilt_leak(cov: np.ndarray, r0: np.ndarray, g: float) -> np.ndarray:
    """Covariance with the second-order gravity leak of the tilt in the accelerometer bias.

    A tilt error ``phi`` leaves ``g (1 - cos|phi|) ~ g |phi|^2 / 2`` of vertical
    acceleration, which the linear model gives to the vertical accelerometer
    bias; with ``phi`` zero-mean of spreads ``s_n, s_e`` its mean is
    ``g (s_n^2 + s_e^2) / 2`` and its variance ``g^2 (s_n^4 + s_e^4) / 2``
    (Gaussian fourth moments). Both are added to the variance along the body
    axis that points down.
    """
    sn2, se2 = cov[3, 3], cov[4, 4]
    leak = (0.5 * g * (sn2 + se2)) ** 2 + 0.5 * g ** 2 * (sn2 ** 2 + se2 ** 2)
    down = r0.T @ np.array([0.0, 0.0, 1.0])
    out = cov.copy()
    out[ACCEL_BIAS, ACCEL_BIAS] += leak * np.outer(down, down)
    return out


def _with_misfit(meas: DopplerMeasurements, misfit: float) -> DopplerMeasurements:
    """``meas`` with the misfit spread added to every range rate's in quadrature."""
    return DopplerMeasurements(meas.directions, meas.range_rate, np.hypot(meas.sigma, misfit),
                               meas.frame, meas.window, meas.direction_cov, meas.group)


def _consensus(meas: DopplerMeasurements) -> np.ndarray:
    """Inliers of a static world, block by block (RANSAC of :func:`fit_ego_velocity`)."""
    keep = np.ones(meas.frame.size, dtype=bool)
    blocks = np.unique(np.column_stack([meas.frame, meas.window]), axis=0)
    for b in blocks:
        idx = np.flatnonzero((meas.frame == b[0]) & (meas.window[:, 0] == b[1]))
        if idx.size > MIN_CONSENSUS:
            fit = fit_ego_velocity(meas.directions[idx], meas.range_rate[idx], meas.sigma[idx])
            keep[idx] = fit.inliers
    return keep
