"""Strapdown integration of gyroscope and accelerometer samples to the radar's pose.

Frames and symbols follow docs/conventions.md: world W is north-east-down with
gravity ``g_W = (0, 0, +g)``, body B is forward-right-down with the IMU at its
origin, the radar phase centre sits at the lever arm ``r_IR`` in B, and the
attitude ``R_WB`` maps body vectors to world. The accelerometer measures the
specific force ``f_B = R_WB^T (a_W - g_W)``, the gyroscope the body rate
``omega_B``.

Two quantities are not observable from an IMU alone and must be supplied:

* the initial attitude (heading in particular), default identity, i.e. the
  nominal hover attitude at the reference time; ``initial_attitude="level"``
  takes roll and pitch from accelerometer levelling over the hover window
  (heading stays unobservable and is set to zero);
* the initial velocity. Either it is ``"given"`` (from the flight controller:
  GNSS, optical flow, visual odometry), or the ``"hover"`` assumption sets it
  so that the velocity averages to zero over a window (the platform holds its
  position). Under the hover assumption a non-zero true mean velocity over the
  window leaves a constant velocity error, which shifts the Doppler of every
  static scatterer by ``2 (dv . u) / lambda`` but does not broaden it.

IMU gaps of up to two dropped samples, timestamp jitter and an IMU rate below
2.5 times the vibration band are tolerated with a warning, larger gaps raise
``ValueError`` (:mod:`compensation.ingestion`); a hover window too short to
observe the initial velocity, or a levelling window over which the platform
was not at rest on average, is reported in :attr:`PlatformMotion.warnings`
(:mod:`compensation.guards`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.spatial.transform import Rotation

from ._checks import choice, finite_array, positive, rotation_matrices, strictly_increasing
from .guards import hover_window_warning, levelling_warning
from .ingestion import (
    check_frame_times,
    check_imu_timing,
    grade_hover_window,
    imu_rate_warning,
    is_frame_list,
    warn,
)

#: Standard gravity [m/s^2]; ``g_W = (0, 0, +STANDARD_GRAVITY)`` in NED.
STANDARD_GRAVITY = 9.80665

_SQRT3 = np.sqrt(3.0)


@dataclass(frozen=True, eq=False)
class PlatformMotion:
    """Body pose and rates at the radar's chirp times.

    Attributes
    ----------
    time : ndarray, shape ``[chirp]``
        Chirp start times on the radar clock [s].
    attitude : ndarray, shape ``[chirp, 3, 3]``
        ``R_WB`` (body to world) [1].
    position : ndarray, shape ``[chirp, 3]``
        Body-origin (IMU) position in W, origin at the nominal hover point [m].
    velocity : ndarray, shape ``[chirp, 3]``
        Body-origin velocity in W [m/s].
    angular_rate : ndarray, shape ``[chirp, 3]``
        Body angular rate ``omega_B`` [rad/s].
    lever_arm : ndarray, shape ``[3]``
        Radar phase centre ``r_IR`` in B [m].
    warnings : tuple of str
        Assumptions of the integration that did not hold (keys ``"hover
        window"``, ``"levelling"``; see :mod:`compensation.guards`); empty when
        none. Carried on to the beams computed from this motion.
    """

    time: np.ndarray
    attitude: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    angular_rate: np.ndarray
    lever_arm: np.ndarray
    warnings: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        t = finite_array("time", self.time, ndim=1)
        n = t.size
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "attitude", rotation_matrices("attitude", self.attitude, n))
        for name in ("position", "velocity", "angular_rate"):
            object.__setattr__(self, name, finite_array(name, getattr(self, name),
                                                        shape=(n, 3)))
        object.__setattr__(self, "lever_arm", finite_array("lever_arm", self.lever_arm,
                                                           shape=(3,)))
        if isinstance(self.warnings, str):
            raise ValueError(f"warnings must be a sequence of strings, got {self.warnings!r}")
        object.__setattr__(self, "warnings", tuple(str(w) for w in self.warnings))

    dims = ("chirp",)

    @property
    def num_chirps(self) -> int:
        """Number of chirp times."""
        return int(self.time.size)

    @property
    def radar_position(self) -> np.ndarray:
        """Radar phase centre ``T + R_WB r_IR`` in W, shape ``[chirp, 3]`` [m]."""
        return self.position + self.attitude @ self.lever_arm

    @property
    def radar_displacement(self) -> np.ndarray:
        """Radar phase centre minus its nominal position ``r_IR``, shape ``[chirp, 3]`` [m].

        The nominal pose is the body at the hover point with identity attitude.
        """
        return self.radar_position - self.lever_arm

    @property
    def translation_displacement(self) -> np.ndarray:
        """Part of :attr:`radar_displacement` due to body translation ``T``, ``[chirp, 3]`` [m]."""
        return self.position.copy()

    @property
    def rotation_displacement(self) -> np.ndarray:
        """Part due to rotation of the lever arm ``(R_WB - I) r_IR``, ``[chirp, 3]`` [m]."""
        return self.attitude @ self.lever_arm - self.lever_arm

    @property
    def radar_velocity(self) -> np.ndarray:
        """Radar phase-centre velocity ``v + R_WB (omega_B x r_IR)`` in W, ``[chirp, 3]`` [m/s]."""
        return self.velocity + np.einsum("nij,nj->ni", self.attitude,
                                         np.cross(self.angular_rate, self.lever_arm))

    def euler(self) -> np.ndarray:
        """Euler angles ``(yaw, pitch, roll)`` (scipy ``"ZYX"``), shape ``[chirp, 3]`` [rad]."""
        return Rotation.from_matrix(self.attitude).as_euler("ZYX")

    def select(self, index) -> PlatformMotion:
        """Motion at a subset of chirps (any NumPy index along ``chirp``)."""
        return PlatformMotion(self.time[index], self.attitude[index], self.position[index],
                              self.velocity[index], self.angular_rate[index], self.lever_arm,
                              self.warnings)


def static_motion(time, *, lever_arm=(0.0, 0.0, 0.0)) -> PlatformMotion:
    """A platform at rest at the nominal hover pose at every time ``[chirp]`` [s]."""
    t = finite_array("time", time, ndim=1)
    z = np.zeros((t.size, 3))
    return PlatformMotion(t, np.broadcast_to(np.eye(3), (t.size, 3, 3)).copy(), z, z.copy(),
                          z.copy(), np.asarray(lever_arm, dtype=float))


def _magnus_step(rate: CubicSpline, t0: np.ndarray, t1: np.ndarray) -> np.ndarray:
    """Rotation vectors of the fourth-order Magnus step from ``t0`` to ``t1`` ``[..., 3]``.

    For ``R' = R [omega]_x`` and two Gauss-Legendre nodes
    ``c -+ h sqrt(3) / 6``: ``theta = h/2 (w1 + w2) + sqrt(3)/12 h^2 (w1 x w2)``,
    and ``R(t1) = R(t0) exp([theta]_x)``.
    """
    h = t1 - t0
    c = 0.5 * (t0 + t1)
    w1 = rate(c - h * _SQRT3 / 6.0)
    w2 = rate(c + h * _SQRT3 / 6.0)
    return (0.5 * h)[..., None] * (w1 + w2) + (_SQRT3 / 12.0 * h * h)[..., None] * np.cross(
        w1, w2)


#: Absolute tolerance [s] of the IMU record's coverage of the chirps: above float64
#: rounding of epoch-clock seconds (2.4e-7 s at 1.7e9 s), far below an IMU interval.
COVERAGE_TOLERANCE = 1e-6
#: Largest plausible angular rate [rad/s]: the full scale of the widest common MEMS
#: gyroscopes, 2000 deg/s (a larger value is a rate in deg/s).
GYRO_FULL_SCALE = np.deg2rad(2000.0)
#: Smallest accepted ratio of the mean specific-force magnitude to gravity over a
#: record: a flying, hovering or resting platform holds itself up against gravity
#: (ratio near 1 or above, under vibration); an accelerometer in g gives about 0.1.
MIN_SPECIFIC_FORCE_RATIO = 0.3


def check_imu_units(gyro: np.ndarray, accel: np.ndarray, gravity: float) -> tuple[str, ...]:
    """Check that IMU magnitudes fit rad/s and m/s^2; returns warnings.

    Returns
    -------
    tuple of str
        A ``"gyro units: ..."`` warning when ``max |gyro|`` exceeds
        :data:`GYRO_FULL_SCALE` (a rate in deg/s, or a motion no gyroscope
        measures).

    Raises
    ------
    ValueError
        The mean ``|accel|`` is below :data:`MIN_SPECIFIC_FORCE_RATIO` times
        ``gravity`` (an accelerometer in g).
    """
    mean = float(np.mean(np.linalg.norm(accel, axis=1)))
    if mean < MIN_SPECIFIC_FORCE_RATIO * gravity:
        raise ValueError(f"accel has a mean magnitude of {mean:.4g} m/s^2 over the record; "
                         f"expected about gravity ({gravity:.4g} m/s^2) for a platform that "
                         f"flies, hovers or rests (in g? multiply by 9.80665)")
    peak = float(np.max(np.linalg.norm(gyro, axis=1)))
    if peak > GYRO_FULL_SCALE:
        return (f"gyro units: the angular rate peaks at {peak:.4g} rad/s, beyond a "
                f"gyroscope's usual full scale ({GYRO_FULL_SCALE:.4g} rad/s = 2000 deg/s); "
                f"expected rad/s (deg/s given? multiply by pi/180)",)
    return ()


def integrate_imu(imu_time, gyro, accel, chirp_times, *, lever_arm=(0.0, 0.0, 0.0),
                  time_offset: float = 0.0, reference_time: float | None = None,
                  initial_attitude=None, initial_position=(0.0, 0.0, 0.0),
                  velocity: Literal["hover", "given"] = "hover", initial_velocity=None,
                  hover_window: tuple[float, float] | None = None,
                  gravity: float = STANDARD_GRAVITY,
                  max_gap: float | None = None, imu_grade: str | None = None,
                  vibration_hz: float | None = None) -> PlatformMotion:
    """Integrate IMU samples to the body pose at the radar's chirp times.

    Parameters
    ----------
    imu_time : array_like, shape ``[sample]``
        IMU time stamps on the IMU clock [s], strictly increasing, at least 4,
        without gaps above ``max_gap`` (smaller gaps and jitter: warnings).
    gyro : array_like, shape ``[sample, 3]``
        Body angular rate ``omega_B`` [rad/s].
    accel : array_like, shape ``[sample, 3]``
        Specific force ``f_B = R_WB^T (a_W - g_W)`` [m/s^2].
    chirp_times : array_like ``[chirp]``, or a list of them
        Times on the radar clock [s]: increasing query times (chirp or TDM
        slot start times), or a list of frames, each uniform (``ValueError``
        otherwise), separated by any idle time
        (:func:`compensation.ingestion.check_frame_times`); the result then
        holds the frames concatenated.
    lever_arm : array_like, shape ``[3]``
        Radar phase centre ``r_IR`` in B [m].
    time_offset : float
        IMU clock reading minus radar clock reading [s]: chirp ``n`` happens
        at IMU time ``chirp_times[n] + time_offset``.
    reference_time : float, optional
        Radar-clock time at which the initial conditions hold [s]; default
        the first chirp time.
    initial_attitude : array_like ``[3, 3]``, scipy Rotation or "level", optional
        ``R_WB`` at the reference time; default identity (nominal hover
        attitude). ``"level"``: roll and pitch from accelerometer levelling
        over ``hover_window`` (the mean specific force, rotated by the gyro to
        one epoch, points against gravity when the platform is at rest on
        average), heading zero (unobservable).
    initial_position : array_like, shape ``[3]``
        Body-origin position in W at the reference time [m]; default the
        hover point.
    velocity : {"hover", "given"}
        How the unobservable initial velocity is set: ``"given"`` uses
        ``initial_velocity`` (flight controller); ``"hover"`` makes the mean
        velocity over ``hover_window`` zero.
    initial_velocity : array_like, shape ``[3]``, optional
        Body-origin velocity in W at the reference time [m/s]; required with
        ``velocity="given"``.
    hover_window : (float, float), optional
        Radar-clock interval [s] of the hover assumption (zero mean velocity,
        and for ``initial_attitude="level"`` zero mean acceleration); default
        the span of the IMU samples, or with ``imu_grade`` the grade's window
        centred on the chirps. A window shorter than 0.5 s or no longer
        than the frame leaves the initial velocity poorly observable: a
        ``"hover window: ..."`` entry in ``warnings``.
    gravity : float
        Magnitude of ``g_W`` [m/s^2].
    max_gap : float, optional
        Largest tolerated IMU sample interval [s] (tolerated silently); default
        3.5 times the median interval with an ``"imu gaps"`` warning above 1.5
        times (:data:`compensation.ingestion.GAP_LIMIT_FACTOR`).
    imu_grade : {"ideal", "tactical", "consumer_mems"}, optional
        Grade of the IMU; sets the default hover window
        (:data:`compensation.ingestion.HOVER_WINDOW_BY_GRADE`: 1 s for
        consumer MEMS, whose accelerometer bias makes a long window worse than
        a short one).
    vibration_hz : float, optional
        Upper edge of the vibration band [Hz]; default found in the gyro
        spectrum. An IMU rate below 2.5 times it gives an ``"imu rate"``
        warning.

    Returns
    -------
    PlatformMotion
        Pose, velocity and rates at ``chirp_times``; ``warnings`` lists the
        assumptions that did not hold (IMU timing, hover window, levelling),
        the timing ones also issued as :class:`compensation.CompensationWarning`.

    Raises
    ------
    ValueError
        On NaN/inf samples, unsorted times, a gap in the IMU record above
        ``max_gap``, chirp times not uniform within a frame, mismatched
        shapes, or chirp times (shifted by ``time_offset``) outside the IMU
        record.

    Notes
    -----
    Attitude: the gyro samples are interpolated by a cubic spline and the
    attitude is propagated interval by interval with the fourth-order Magnus
    (two-node Gauss-Legendre) rotation vector
    ``theta = h/2 (w1 + w2) + sqrt(3)/12 h^2 (w1 x w2)`` composed on the right,
    ``R_{k+1} = R_k exp([theta]_x)``; chirp times inside an interval take one
    partial step. Translation: ``a_W = R_WB f_B + g_W`` at the IMU epochs is
    interpolated by a cubic spline whose first and second antiderivatives give
    velocity and position exactly for that spline. With a sampled rate above
    about 20 times the motion bandwidth the pose errors are well below a
    micrometre for the paper's motions.

    Levelling (``initial_attitude="level"``): with ``R_rel(t)`` the
    gyro-propagated attitude relative to the first IMU sample, the mean
    ``f_0 = mean_k R_rel(t_k) f_k`` over the window equals
    ``R_0^T (mean(a_W) - g_W)``; for a platform at rest on average
    (``mean(a_W) = 0``) the body-frame down direction at the first sample is
    ``d = -f_0 / |f_0|``, giving pitch ``asin(-d_x)`` and roll
    ``atan2(d_y, d_z)``. A mean horizontal acceleration ``a_h`` over the
    window tilts the result by ``a_h / g`` (an accelerometer bias ``b`` by
    ``b / g``: 20 mg give 1.1 deg); heading is set to zero at the reference
    time.

    Examples
    --------
    >>> import numpy as np
    >>> t = np.arange(0.0, 0.05, 1e-3)
    >>> gyro = np.zeros((t.size, 3)); gyro[:, 2] = 0.1
    >>> accel = np.tile([0.0, 0.0, -STANDARD_GRAVITY], (t.size, 1))
    >>> m = integrate_imu(t, gyro, accel, np.array([0.0, 0.04]), velocity="given",
    ...                   initial_velocity=np.zeros(3))
    >>> round(float(m.euler()[1, 0]), 6)
    0.004
    """
    t = finite_array("imu_time", imu_time, ndim=1)
    strictly_increasing("imu_time", t)
    if t.size < 4:
        raise ValueError(f"imu_time must hold at least 4 samples, got {t.size}")
    timing = warn(check_imu_timing(t, None if max_gap is None else float(
        finite_array("max_gap", max_gap, shape=()))))
    w = finite_array("gyro", gyro, shape=(t.size, 3), what="(one row per IMU sample, rad/s)")
    f = finite_array("accel", accel, shape=(t.size, 3),
                     what="(one row per IMU sample, m/s^2)")
    if is_frame_list(chirp_times):
        tc = np.concatenate(check_frame_times(chirp_times))
    else:    # query times: any increasing times (the pose at arbitrary instants)
        tc = finite_array("chirp_times", chirp_times, ndim=1)
        if tc.size < 1:
            raise ValueError("chirp_times must hold at least one time")
        if tc.size > 1 and np.any(np.diff(tc) < 0):
            raise ValueError("chirp_times must be sorted in increasing order")
    lever = finite_array("lever_arm", lever_arm, shape=(3,))
    offset = float(finite_array("time_offset", time_offset, shape=()))
    choice("velocity", velocity, ("hover", "given"))
    g = positive("gravity", gravity)
    unit_warnings = check_imu_units(w, f, g)
    timing += warn(imu_rate_warning(t, w, vibration_hz))

    tq = tc + offset
    span = (t[0], t[-1])
    tol = COVERAGE_TOLERANCE
    if tq[0] < span[0] - tol or tq[-1] > span[1] + tol:
        raise ValueError(
            f"chirp_times + time_offset span [{tq[0]!r}, {tq[-1]!r}] s (IMU clock) but "
            f"imu_time only covers [{span[0]!r}, {span[1]!r}] s; the IMU record must cover "
            f"every chirp")
    tq = np.clip(tq, span[0], span[1])
    t_ref = tq[0] if reference_time is None else float(
        finite_array("reference_time", reference_time, shape=())) + offset
    if not span[0] - tol <= t_ref <= span[1] + tol:
        raise ValueError(f"reference_time {t_ref - offset!r} s is outside the IMU record "
                         f"[{span[0] - offset!r}, {span[1] - offset!r}] s (radar clock)")
    t_ref = float(np.clip(t_ref, span[0], span[1]))

    level = isinstance(initial_attitude, str)
    if level:
        choice("initial_attitude", initial_attitude, ("level",))
        r0 = None
    else:
        r0 = np.eye(3) if initial_attitude is None else rotation_matrices(
            "initial_attitude", initial_attitude, 1)[0]
    p0 = finite_array("initial_position", initial_position, shape=(3,))
    if velocity == "given":
        if initial_velocity is None:
            raise ValueError('velocity="given" needs initial_velocity (3 values, m/s in W); '
                             'use velocity="hover" to assume a zero-mean velocity instead')
        v0 = finite_array("initial_velocity", initial_velocity, shape=(3,))
    elif initial_velocity is not None:
        raise ValueError('initial_velocity is only used with velocity="given", got '
                         f'{initial_velocity!r} with velocity="hover"')

    # --- attitude relative to the first IMU sample, fourth-order Magnus
    rate = CubicSpline(t, w, axis=0)
    steps = Rotation.from_rotvec(_magnus_step(rate, t[:-1], t[1:])).as_matrix()
    rel = np.empty((t.size, 3, 3))
    rel[0] = np.eye(3)
    for k in range(t.size - 1):
        rel[k + 1] = rel[k] @ steps[k]

    def attitude_at(times: np.ndarray) -> np.ndarray:
        k = np.clip(np.searchsorted(t, times, side="right") - 1, 0, t.size - 2)
        part = Rotation.from_rotvec(_magnus_step(rate, t[k], times)).as_matrix()
        return rel[k] @ part

    warnings: tuple[str, ...] = timing + unit_warnings
    if hover_window is None and imu_grade is not None:
        hover_window = grade_hover_window(imu_grade, (tc[0], tc[-1]),
                                          (span[0] - offset, span[1] - offset))
    lo, hi = span if hover_window is None else (
        float(hover_window[0]) + offset, float(hover_window[1]) + offset)
    if velocity == "hover" or level:
        if not (span[0] - tol <= lo < hi <= span[1] + tol):
            raise ValueError(f"hover_window must be an increasing interval inside the IMU "
                             f"record, got {hover_window!r}")
        warnings += hover_window_warning((lo, hi), (tq[0], tq[-1]), float(np.median(np.diff(t))))
    rel_ref = attitude_at(np.array([t_ref]))[0]
    if level:
        r0, found = _level(t, rel, f, (lo, hi), rel_ref, g)
        warnings += found
    rebase = r0 @ rel_ref.T                               # R(t) = r0 R_rel(ref)^T R_rel(t)
    att_nodes = rebase @ rel
    att_q = rebase @ attitude_at(tq)

    # --- translation: spline of a_W, integrated analytically
    g_w = np.array([0.0, 0.0, g])
    acc_w = np.einsum("kij,kj->ki", att_nodes, f) + g_w
    a_spl = CubicSpline(t, acc_w, axis=0)
    vel_int = a_spl.antiderivative(1)          # V(t) = int_{t0}^t a
    pos_int = a_spl.antiderivative(2)          # P(t) = int_{t0}^t V
    v_ref_int = vel_int(t_ref)
    if velocity == "hover":
        v0 = -((pos_int(hi) - pos_int(lo)) / (hi - lo) - v_ref_int)
    dt = (tq - t_ref)[:, None]
    vel = v0 + vel_int(tq) - v_ref_int
    pos = p0 + (v0 - v_ref_int) * dt + pos_int(tq) - pos_int(t_ref)
    return PlatformMotion(tc, att_q, pos, vel, rate(tq), lever, warnings)


def _level(t: np.ndarray, rel: np.ndarray, f: np.ndarray, window: tuple[float, float],
           rel_ref: np.ndarray, g: float) -> tuple[np.ndarray, tuple[str, ...]]:
    """Levelled ``R_WB`` at the reference time (heading zero) and its warnings.

    ``rel [sample, 3, 3]``: attitude relative to the first IMU sample; ``f``:
    specific force ``[sample, 3]``; ``window``: IMU-clock interval of the
    average; ``rel_ref``: relative attitude at the reference time.
    """
    sel = (t >= window[0] - 1e-12) & (t <= window[1] + 1e-12)
    if np.count_nonzero(sel) < 2:
        raise ValueError(f'initial_attitude="level" needs at least 2 IMU samples in the '
                         f'window [{window[0]!r}, {window[1]!r}] s (IMU clock)')
    rotated = np.einsum("kij,kj->ki", rel[sel], f[sel])          # R_rel f in the first-sample frame
    ts = t[sel]
    dt = np.diff(ts)[:, None]
    mean_f = (0.5 * dt * (rotated[1:] + rotated[:-1])).sum(axis=0) / (ts[-1] - ts[0])
    down = -mean_f / np.linalg.norm(mean_f)
    pitch = np.arcsin(np.clip(-down[0], -1.0, 1.0))
    roll = np.arctan2(down[1], down[2])
    first = Rotation.from_euler("ZYX", [0.0, pitch, roll]).as_matrix()
    at_ref = first @ rel_ref
    yaw = Rotation.from_matrix(at_ref).as_euler("ZYX")[0]
    c, s = np.cos(-yaw), np.sin(-yaw)
    rz = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    return rz @ at_ref, levelling_warning(mean_f, g)
