"""Strapdown IMU simulation: gyroscope and accelerometer with datasheet error models.

An :class:`Imu` is configured once (error specification, sample rate, clock
errors) and called with a truth :class:`~raysim.platform.motion.Trajectory`; it returns
:class:`ImuSamples`, which carry their own time axis and the realised errors.

Measured quantities (body frame B, forward-right-down):

* gyroscope: body angular rate ``omega_B`` [rad/s]
  (:meth:`Trajectory.angular_rate <raysim.platform.motion.Trajectory.angular_rate>`);
* accelerometer: specific force ``f_B = R_WB^T (a_W - g_W)`` [m/s^2], with
  ``g_W = (0, 0, +9.80665)`` in NED, so a level sensor at rest reads
  ``(0, 0, -9.80665)``.

Error model, per sensor triad (gyro and accel alike)::

    y_k = quantise( clip( M @ u(t_k) + b_0 + b_gm(t_k) + b_rw(t_k) + n_k ) )

* ``M = I + diag(s) + N``: scale-factor errors ``s`` (3) and axis
  misalignment / non-orthogonality ``N`` (6 off-diagonal terms), drawn once;
* ``b_0``: turn-on (constant) bias, drawn once;
* ``b_gm``: bias instability, modelled as a first-order Gauss-Markov process
  whose Allan-deviation peak equals the specified bias instability;
* ``b_rw``: bias (rate) random walk;
* ``n_k``: white noise of density ``N`` (angle / velocity random walk); the
  per-sample standard deviation is ``N sqrt(rate)`` so that the Allan
  deviation is ``N / sqrt(tau)``;
* quantisation to the output resolution, saturation at the full-scale range.

Samples are instantaneous values at the sample epochs (no anti-alias filter,
no integration over the sample interval).

Clock: the IMU time stamps samples on its own clock,
``t_imu = time_offset + (1 + clock_drift_ppm 1e-6) t``, with ``t`` the truth
(trajectory / radar) time, and samples at the ticks ``t_imu = k / rate``.

Units: SI inside. Datasheet figures are converted with the named constants
in :mod:`raysim.platform.imu_spec` (``DEG``, ``SQRT_HOUR``, ``MILLI_G`` ...),
e.g. an angle random walk of ``0.125 deg/sqrt(h)`` is ``0.125 * DEG / SQRT_HOUR`` rad/sqrt(s).
"""


from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.platform.imu_spec import (  # noqa: F401  (re-exported: the IMU's public names)
    CONSUMER_MEMS,
    DEG,
    FOOT,
    GRAVITY_W,
    HOUR,
    IDEAL,
    MICRO_G,
    MILLI_G,
    PPM,
    PRESETS,
    SQRT_HOUR,
    STANDARD_GRAVITY,
    TACTICAL,
    ImuSpec,
    SensorErrors,
    _resolve_spec,
    get_preset,
)

__all__ = [
    "STANDARD_GRAVITY", "GRAVITY_W", "DEG", "HOUR", "SQRT_HOUR", "MILLI_G", "MICRO_G", "PPM",
    "FOOT", "SensorErrors", "ImuSpec", "IDEAL", "TACTICAL", "CONSUMER_MEMS", "PRESETS",
    "get_preset", "ImuErrorState", "ImuSamples", "Imu", "simulate_imu", "specific_force",
    "allan_deviation",
]

# ---------------------------------------------------------------------- results
@dataclass(frozen=True, eq=False)
class ImuErrorState:
    """Realised errors and truth timing of one simulated run.

    Attributes
    ----------
    true_time : ndarray, shape ``[sample]``
        Truth (trajectory / radar) time of each sample [s].
    gyro_matrix, accel_matrix : ndarray, shape ``[3, 3]``
        ``M = I + diag(scale) + misalignment`` applied to the truth [1].
    gyro_bias : ndarray, shape ``[sample, 3]``
        Total gyro bias (turn-on + instability + random walk) [rad/s].
    accel_bias : ndarray, shape ``[sample, 3]``
        Total accelerometer bias [m/s^2].
    time_offset : float
        IMU clock reading at truth time 0 [s].
    clock_drift_ppm : float
        IMU clock rate error [ppm].
    seed : int or None
        Seed the run was drawn from (None when a Generator was passed).
    """

    true_time: np.ndarray
    gyro_matrix: np.ndarray
    accel_matrix: np.ndarray
    gyro_bias: np.ndarray
    accel_bias: np.ndarray
    time_offset: float = 0.0
    clock_drift_ppm: float = 0.0
    seed: int | None = None


@dataclass(frozen=True, eq=False)
class ImuSamples:
    """IMU output: time-stamped gyroscope and accelerometer samples.

    Attributes
    ----------
    time : ndarray, shape ``[sample]``
        Sample time stamps on the IMU clock [s], strictly increasing.
    gyro : ndarray, shape ``[sample, 3]``
        Angular rate in B (FRD) [rad/s].
    accel : ndarray, shape ``[sample, 3]``
        Specific force in B (FRD) [m/s^2]; ``(0, 0, -9.80665)`` level at rest.
    spec : ImuSpec or None
        Error specification (None for recorded data).
    truth : ImuErrorState or None
        Realised errors and truth times (simulation only).
    source : str
        Where the samples come from (preset name, file path).
    rate : float or None
        Nominal output rate on the IMU clock [Hz] (None when unknown).
    interval : float
        Averaging interval of each sample [s] (a flight controller's boxcar or
        integrated output, each sample stamped at its interval's middle); 0 for
        instantaneous samples.
    """

    time: np.ndarray
    gyro: np.ndarray
    accel: np.ndarray
    spec: ImuSpec | None = None
    truth: ImuErrorState | None = None
    source: str = ""
    rate: float | None = None
    interval: float = 0.0

    def __post_init__(self) -> None:
        t = np.asarray(self.time, dtype=float)
        w = np.asarray(self.gyro, dtype=float)
        f = np.asarray(self.accel, dtype=float)
        if t.ndim != 1:
            raise ValueError(f"time must have shape [sample], got {t.shape}")
        for name, arr in (("gyro", w), ("accel", f)):
            if arr.shape != (t.size, 3):
                raise ValueError(f"{name} must have shape [sample, 3] = ({t.size}, 3), "
                                 f"got {arr.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(w)) and np.all(np.isfinite(f))):
            raise ValueError("IMU time, gyro and accel must be finite")
        if t.size > 1 and not np.all(np.diff(t) > 0):
            k = int(np.argmin(np.diff(t) > 0))
            raise ValueError(f"IMU time must be strictly increasing; sample {k + 1} "
                             f"({t[k + 1]!r} s) does not follow sample {k} ({t[k]!r} s)")
        object.__setattr__(self, "time", t)
        object.__setattr__(self, "gyro", w)
        object.__setattr__(self, "accel", f)

    @property
    def num_samples(self) -> int:
        """Number of samples."""
        return int(self.time.size)

    @property
    def mean_rate(self) -> float:
        """Mean sample rate on the IMU clock [Hz] (NaN with fewer than 2 samples)."""
        if self.time.size < 2:
            return math.nan
        return (self.time.size - 1) / (self.time[-1] - self.time[0])

    def to_arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Plain writable copies ``(time [sample], gyro [sample, 3], accel [sample, 3])``.

        Units s, rad/s, m/s^2; this is the form the ``compensation`` package takes.
        """
        return self.time.copy(), self.gyro.copy(), self.accel.copy()


# ------------------------------------------------------------------ simulation
def specific_force(trajectory, t) -> np.ndarray:
    """Closed-form specific force ``f_B = R_WB^T (a_W - g_W)``.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
    t : array_like, shape ``[time]``
        Truth times [s].

    Returns
    -------
    ndarray, shape ``[time, 3]``
        Specific force in B [m/s^2].
    """
    t = np.atleast_1d(np.asarray(t, dtype=float))
    acc = trajectory.acceleration(t) - GRAVITY_W
    return trajectory.attitude(t).apply(acc, inverse=True)


def _finite(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return value


def _check_matrix(name: str, m) -> np.ndarray:
    m = np.asarray(m, dtype=float)
    if m.shape != (3, 3) or not np.all(np.isfinite(m)):
        raise ValueError(f"{name} must be a finite [3, 3] matrix, got shape {m.shape}")
    return m


def _check_vector(name: str, v) -> np.ndarray:
    v = np.asarray(v, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{name} must be a finite vector of shape [3], got {v!r}")
    return v


#: Peak memory of the simulation per IMU sample [bytes]: time, truth rate and force,
#: eight error streams of three axes and the outputs, in float64 (an upper bound).
IMU_BYTES_PER_SAMPLE = 512

# Independent random streams, one per error source (order fixed: adding a
# source at the end never changes the others).
_STREAMS = ("gyro_static", "gyro_gm", "gyro_rw", "gyro_white",
            "accel_static", "accel_gm", "accel_rw", "accel_white")


@dataclass(frozen=True)
class Imu:
    """IMU simulator: error specification, sample rate and clock.

    Parameters
    ----------
    spec : ImuSpec or str
        Error specification or preset name (``"ideal"``, ``"tactical"``,
        ``"consumer_mems"``).
    rate : float
        Nominal output rate on the IMU clock [Hz], independent of the radar.
    time_offset : float
        IMU clock reading at truth time 0 [s].
    clock_drift_ppm : float
        IMU clock rate error [ppm]: ``t_imu = time_offset + (1 + 1e-6 ppm) t``.

    Examples
    --------
    >>> from raysim.platform.motion import sinusoid
    >>> imu = Imu("tactical", rate=2000.0)
    >>> s = imu(sinusoid("roll", 0.01, 2.0), start=0.0, end=0.1, seed=1)
    >>> s.gyro.shape
    (201, 3)
    """

    spec: ImuSpec | str = "ideal"
    rate: float = 1000.0
    time_offset: float = 0.0
    clock_drift_ppm: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "spec", _resolve_spec(self.spec))
        rate = float(self.rate)
        if not math.isfinite(rate) or rate <= 0.0:
            raise ValueError(f"rate must be a finite positive number of Hz, got {self.rate!r}")
        object.__setattr__(self, "rate", rate)
        object.__setattr__(self, "time_offset", _finite("time_offset", self.time_offset))
        drift = _finite("clock_drift_ppm", self.clock_drift_ppm)
        if abs(drift) >= 1e5:
            raise ValueError(f"clock_drift_ppm must satisfy |drift| < 1e5 ppm, got {drift!r}")
        object.__setattr__(self, "clock_drift_ppm", drift)

    # ---------------------------------------------------------------- clock
    @property
    def clock_scale(self) -> float:
        """IMU clock seconds per truth second ``1 + 1e-6 clock_drift_ppm``."""
        return 1.0 + self.clock_drift_ppm * PPM

    def to_imu_time(self, t) -> np.ndarray:
        """Truth time [s] -> IMU clock reading [s]."""
        return self.time_offset + self.clock_scale * np.asarray(t, dtype=float)

    def to_true_time(self, t_imu) -> np.ndarray:
        """IMU clock reading [s] -> truth time [s]."""
        return (np.asarray(t_imu, dtype=float) - self.time_offset) / self.clock_scale

    def sample_times(self, start: float, end: float) -> np.ndarray:
        """IMU-clock ticks ``k / rate`` with truth time in ``[start, end]``, ``[sample]`` [s]."""
        start = _finite("start", start)
        end = _finite("end", end)
        if end < start:
            raise ValueError(f"end ({end!r} s) must not precede start ({start!r} s)")
        eps = 1e-9
        k0 = math.ceil(float(self.to_imu_time(start)) * self.rate - eps)
        k1 = math.floor(float(self.to_imu_time(end)) * self.rate + eps)
        if k1 < k0:
            raise ValueError(
                f"no IMU sample falls in [{start!r}, {end!r}] s at rate {self.rate!r} Hz")
        from raysim.resources import check_memory

        n = k1 - k0 + 1
        check_memory(IMU_BYTES_PER_SAMPLE * n, f"an IMU record of {n} samples ({self.rate:g} Hz "
                                               f"over {end - start:g} s)",
                     "imu.rate_hz or the length of the record")
        return np.arange(k0, k1 + 1, dtype=float) / self.rate

    # ----------------------------------------------------------- simulation
    def __call__(self, trajectory, start: float, end: float, *,
                 seed: int | np.random.Generator | None = None,
                 gyro_matrix=None, accel_matrix=None,
                 gyro_turn_on_bias=None, accel_turn_on_bias=None) -> ImuSamples:
        """Sample the IMU along a truth trajectory.

        Parameters
        ----------
        trajectory : raysim.platform.motion.Trajectory
            Truth motion of the body origin (where the IMU sits).
        start, end : float
            Truth-time interval [s]; every IMU tick inside it is returned.
        seed : int, numpy.random.Generator or None
            Seed of all random error draws (one independent stream per source).
        gyro_matrix, accel_matrix : array_like, shape ``[3, 3]``, optional
            Fixed ``M`` (scale factor and misalignment) instead of a random draw.
        gyro_turn_on_bias, accel_turn_on_bias : array_like, shape ``[3]``, optional
            Fixed turn-on bias [rad/s], [m/s^2] instead of a random draw.

        Returns
        -------
        ImuSamples
            ``time [sample]`` (IMU clock), ``gyro [sample, 3]``,
            ``accel [sample, 3]`` and the realised errors in ``truth``.
        """
        if not hasattr(trajectory, "angular_rate") or not hasattr(trajectory, "acceleration"):
            raise ValueError(f"trajectory must be a raysim.platform.motion.Trajectory, "
                             f"got {trajectory!r}")
        if isinstance(seed, np.random.Generator):
            children = seed.spawn(len(_STREAMS))
            seed_value = None
        else:
            if seed is not None and (not isinstance(seed, (int, np.integer)) or seed < 0):
                raise ValueError(f"seed must be a non-negative int, a Generator or None, "
                                 f"got {seed!r}")
            ss = np.random.SeedSequence(None if seed is None else int(seed))
            children = [np.random.default_rng(s) for s in ss.spawn(len(_STREAMS))]
            seed_value = None if seed is None else int(seed)
        rngs = dict(zip(_STREAMS, children, strict=True))

        t_imu = self.sample_times(start, end)
        t_true = self.to_true_time(t_imu)
        omega = trajectory.angular_rate(t_true)
        force = specific_force(trajectory, t_true)

        gyro, m_g, b_g = self._corrupt(omega, self.spec.gyro, "gyro", rngs,
                                       gyro_matrix, gyro_turn_on_bias)
        accel, m_a, b_a = self._corrupt(force, self.spec.accel, "accel", rngs,
                                        accel_matrix, accel_turn_on_bias)
        truth = ImuErrorState(true_time=t_true, gyro_matrix=m_g, accel_matrix=m_a,
                              gyro_bias=b_g, accel_bias=b_a, time_offset=self.time_offset,
                              clock_drift_ppm=self.clock_drift_ppm, seed=seed_value)
        return ImuSamples(t_imu, gyro, accel, spec=self.spec, truth=truth,
                          source=f"simulated {self.spec.name} IMU at {self.rate:g} Hz",
                          rate=self.rate)

    def _corrupt(self, u: np.ndarray, err: SensorErrors, what: str, rngs: dict,
                 matrix, turn_on) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        n = u.shape[0]
        dt = 1.0 / self.rate
        static = rngs[f"{what}_static"]
        draws = static.standard_normal(3 + 3 + 6)  # bias, scale, misalignment (fixed order)
        if matrix is None:
            m = np.eye(3) + np.diag(err.scale_factor_sigma * draws[3:6])
            off = ~np.eye(3, dtype=bool)
            m[off] += err.misalignment_sigma * draws[6:12]
        else:
            m = _check_matrix(f"{what}_matrix", matrix)
        b0 = (err.bias_sigma * draws[0:3] if turn_on is None
              else _check_vector(f"{what}_turn_on_bias", turn_on))

        bias = np.broadcast_to(b0, (n, 3)).copy()
        if err.bias_instability > 0:
            phi = math.exp(-dt / err.bias_correlation_time)
            sigma = err.gauss_markov_sigma
            drive = rngs[f"{what}_gm"].standard_normal((n, 3)) * (sigma * math.sqrt(1 - phi**2))
            init = rngs[f"{what}_gm"].standard_normal(3) * sigma  # stationary start
            drive[0] = init
            from scipy.signal import lfilter

            bias += lfilter([1.0], [1.0, -phi], drive, axis=0)
        if err.bias_random_walk > 0:
            steps = rngs[f"{what}_rw"].standard_normal((n, 3)) * (err.bias_random_walk
                                                                  * math.sqrt(dt))
            steps[0] = 0.0
            bias += np.cumsum(steps, axis=0)

        y = u @ m.T + bias
        if err.noise_density > 0:
            y += rngs[f"{what}_white"].standard_normal((n, 3)) * (err.noise_density
                                                                  * math.sqrt(self.rate))
        if err.resolution > 0:
            y = np.round(y / err.resolution) * err.resolution
        if math.isfinite(err.full_scale):
            y = np.clip(y, -err.full_scale, err.full_scale)
        return y, m, bias


def simulate_imu(trajectory, spec: ImuSpec | str = "ideal", *, rate: float, start: float,
                 end: float, seed: int | np.random.Generator | None = None,
                 time_offset: float = 0.0, clock_drift_ppm: float = 0.0) -> ImuSamples:
    """Sample an IMU along ``trajectory``; shorthand for ``Imu(...)(trajectory, ...)``.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
    spec : ImuSpec or str
        Error specification or preset name.
    rate : float
        Output rate on the IMU clock [Hz].
    start, end : float
        Truth-time interval [s].
    seed : int, Generator or None
        Seed of the error draws.
    time_offset : float
        IMU clock reading at truth time 0 [s].
    clock_drift_ppm : float
        IMU clock rate error [ppm].

    Returns
    -------
    ImuSamples
    """
    imu = Imu(spec, rate=rate, time_offset=time_offset, clock_drift_ppm=clock_drift_ppm)
    return imu(trajectory, start, end, seed=seed)


# ------------------------------------------------------------------ analysis
def allan_deviation(x, rate: float, tau) -> np.ndarray:
    """Overlapping Allan deviation of a rate-type record.

    Parameters
    ----------
    x : array_like, shape ``[sample]`` or ``[sample, axis]``
        Uniformly sampled rate signal (rad/s or m/s^2).
    rate : float
        Sample rate [Hz].
    tau : array_like, shape ``[tau]``
        Cluster times [s]; each is rounded to a whole number ``m`` of samples.

    Returns
    -------
    ndarray, shape ``[tau]`` or ``[tau, axis]``
        Allan deviation in the unit of ``x``.

    Notes
    -----
    With ``theta_k = sum_{i<k} x_i / rate`` and ``tau = m / rate``:
    ``AVAR(tau) = sum_k (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2
    / (2 tau^2 (n - 2m + 1))``.
    """
    x = np.asarray(x, dtype=float)
    rate = float(rate)
    if not math.isfinite(rate) or rate <= 0:
        raise ValueError(f"rate must be a finite positive number of Hz, got {rate!r}")
    if not np.all(np.isfinite(x)):
        raise ValueError("x must be finite")
    tau = np.atleast_1d(np.asarray(tau, dtype=float))
    n = x.shape[0]
    theta = np.concatenate([np.zeros((1,) + x.shape[1:]), np.cumsum(x, axis=0)]) / rate
    out = np.empty(tau.shape + x.shape[1:])
    for i, ti in enumerate(tau):
        m = int(round(ti * rate))
        if m < 1 or 2 * m > n:
            raise ValueError(f"tau {ti!r} s needs 1 <= tau*rate <= n/2 samples "
                             f"(rate {rate!r} Hz, n = {n})")
        d = theta[2 * m:] - 2.0 * theta[m:-m] + theta[:-2 * m]
        out[i] = np.sqrt(np.mean(d * d, axis=0) / (2.0 * (m / rate) ** 2))
    return out
