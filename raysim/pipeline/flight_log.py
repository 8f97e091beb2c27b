"""The flight-controller log of a simulated flight: IMU output, logger gaps and attitude.

:func:`flight_log` samples the IMU along the flight's trajectory as a flight
controller logs it:

* ``boxcar`` False: samples at ``rate`` straight from the IMU model (the PX4
  FIFO topics, or an IMU logged at its own rate);
* ``boxcar`` True: the IMU sampled at ``fast_rate`` and averaged into ``rate``
  (:func:`raysim.platform.imu_output.boxcar_output`, what PX4's
  ``sensor_combined`` and ArduPilot's ``IMU`` carry: a 250 Hz log passes
  ``|sinc(f / 250)|`` and folds the 100-200 Hz rotor band);
* ``gaps`` logger gaps of 50-160 ms (:data:`GAP_LENGTH_S`), seeded, outside
  the capture window (its chirps on the IMU clock plus
  :data:`compensation.ingestion.WINDOW_MARGIN`) unless ``gaps_in_capture``
  places the first one inside it (:func:`raysim.platform.imu_output.drop_gaps`;
  the attitude loses the same stretches);
* the flight controller's attitude ``R_WB`` at :data:`ATTITUDE_RATE` on the IMU
  clock: the truth turned by the estimator's roll and pitch error
  (:func:`controller_tilt_error`: a constant of :data:`CONTROLLER_TILT_SIGMA_DEG`
  per axis, seeded, and a slow wander of :data:`CONTROLLER_WANDER_DEG`).

Clock: ``t_imu = time_offset + (1 + 1e-6 clock_drift_ppm) t`` for truth time
``t`` (:class:`raysim.platform.imu.Imu`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["flight_log", "check_flight_log", "place_gaps", "controller_tilt_error", "ATTITUDE_RATE",
           "CONTROLLER_TILT_SIGMA_DEG", "CONTROLLER_WANDER_DEG", "GAP_LENGTH_S"]

#: Rate of the written attitude [Hz] (PX4 logs ``vehicle_attitude`` at about 200 Hz).
ATTITUDE_RATE = 200.0
#: Spread of the flight controller's roll and pitch error, constant over a flight, per
#: axis [deg]: a hovering controller cannot tell a tilt from the accelerometer's
#: horizontal bias; what its level calibration leaves of that bias (a couple of mg of
#: thermal drift: 2 mg is 0.11 deg) tilts its attitude by as much.
CONTROLLER_TILT_SIGMA_DEG = 0.1
#: Amplitude of the slow wander of that error about its constant [deg] and its period
#: [s] (the estimator's filter following the accelerometer's low frequencies).
CONTROLLER_WANDER_DEG, CONTROLLER_WANDER_PERIOD_S = 0.03, 5.0
#: Shortest and longest logger gap [s] (real logs: tens to a couple of hundred ms).
GAP_LENGTH_S = (0.05, 0.16)
#: Tries to place the gaps apart from each other before giving up.
_TRIES = 1000


def place_gaps(count: int, record: tuple, capture: tuple, *, inside=None,
               seed: int) -> list[tuple[float, float]]:
    """``count`` seeded, non-overlapping logger gaps ``(start, length)`` [s, IMU clock].

    Parameters
    ----------
    count : int
        Gaps (>= 0).
    record : (float, float)
        First and last IMU stamp [s].
    capture : (float, float)
        Capture window on the IMU clock, margins included [s]: kept free of
        gaps, except the first one when ``inside`` is given.
    inside : (float, float), optional
        Window [s, IMU clock] the first gap starts in (the capture's chirps).
    seed : int

    Raises
    ------
    ValueError
        ``count`` negative, or the gaps do not fit the record (the message
        names ``--log-gaps``).
    """
    if not (isinstance(count, (int, np.integer)) and count >= 0):
        raise ValueError(f"--log-gaps: got {count!r}, expected a number of gaps >= 0")
    if inside is not None and count < 1:
        raise ValueError("--gaps-in-capture needs --log-gaps N with N >= 1")
    rng = np.random.default_rng([int(seed), 0x6A9])
    lo, hi = (float(v) for v in record)
    c0, c1 = (float(v) for v in capture)
    gaps: list = []
    for k in range(int(count)):
        for _ in range(_TRIES):
            length = float(rng.uniform(*GAP_LENGTH_S))
            if k == 0 and inside is not None:
                s = float(rng.uniform(inside[0], max(inside[0], inside[1] - length)))
            else:
                s = float(rng.uniform(lo + 0.01, hi - length - 0.01))
                if s < c1 and s + length > c0:       # keep the capture window whole
                    continue
            if all(s + length < g0 or s > g0 + g1 for g0, g1 in gaps):
                gaps.append((s, length))
                break
        else:
            raise ValueError(f"--log-gaps {count}: cannot place {count} gaps of "
                             f"{GAP_LENGTH_S[0] * 1e3:.0f}-{GAP_LENGTH_S[1] * 1e3:.0f} ms "
                             f"apart in a record of {hi - lo:.3f} s outside the capture "
                             f"window; ask for fewer")
    return sorted(gaps)


def controller_tilt_error(t, seed: int) -> np.ndarray:
    """The flight controller's roll and pitch error at truth times ``t [time]`` [s]:
    rotation vectors about W north and east, ``[time, 3]`` [rad] (the logged attitude is
    ``exp([e]x) R_WB``): a seeded constant of :data:`CONTROLLER_TILT_SIGMA_DEG` per axis
    plus a sine of amplitude :data:`CONTROLLER_WANDER_DEG`, period
    :data:`CONTROLLER_WANDER_PERIOD_S` and seeded phase."""
    rng = np.random.default_rng([int(seed), 0xA77])
    const = rng.normal(0.0, CONTROLLER_TILT_SIGMA_DEG, 2)
    phase = rng.uniform(0.0, 2 * np.pi, 2)
    t = np.asarray(t, dtype=float)
    wander = CONTROLLER_WANDER_DEG * np.sin(2 * np.pi * t[:, None] / CONTROLLER_WANDER_PERIOD_S
                                            + phase)
    return np.column_stack([np.deg2rad(const + wander), np.zeros(t.size)])


def check_flight_log(seed: int, time_offset: float, clock_drift_ppm: float, rate: float,
                     fast_rate: float, boxcar: bool) -> None:
    """Check the log's settings before anything is rendered; a ValueError names each by the
    ``raysim flight`` option that sets it."""
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise ValueError(f"--seed: got {seed!r}, expected a non-negative integer")
    for option, value in (("--time-offset", time_offset),
                          ("--clock-drift-ppm", clock_drift_ppm)):
        if not np.isfinite(value):
            raise ValueError(f"{option}: got {value!r}, expected a finite number")
    if not (np.isfinite(rate) and rate > 0):
        raise ValueError(f"--imu-rate: got {rate!r}, expected a positive rate [Hz]")
    if boxcar:
        m = fast_rate / rate if np.isfinite(fast_rate) else np.nan
        if not (np.isfinite(m) and m >= 1 and abs(m - round(m)) < 1e-6):
            raise ValueError(f"--imu-fast-rate: got {fast_rate!r} Hz, expected a whole "
                             f"multiple of --imu-rate {rate:g} Hz")


def flight_log(trajectory, imu: str, *, rate: float, times, seed: int, time_offset: float,
               clock_drift_ppm: float = 0.0, boxcar: bool = False, fast_rate: float = 2000.0,
               gaps: int = 0, gaps_in_capture: bool = False, attitude: bool = True,
               capture=None) -> tuple:
    """IMU samples, the attitude log (or None) and the gaps of a flight (module docstring).

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
    imu : str
        IMU preset.
    rate : float
        Logged IMU rate [Hz].
    times : (float, float)
        Truth times the record must cover [s]; it starts at truth time 0, or where
        the IMU clock reads 0 if it runs behind (a negative ``time_offset``: a log's
        stamps count from boot and are never negative).
    seed : int
        Seed of the IMU errors (and, offset, of the gaps).
    time_offset, clock_drift_ppm : float
        IMU clock at truth time 0 [s] and its rate error [ppm].
    boxcar : bool
        Average ``fast_rate`` samples into ``rate`` (a multiple of it).
    fast_rate : float
        Internal IMU rate of the boxcar [Hz].
    gaps : int
        Logger gaps.
    gaps_in_capture : bool
        The first gap inside the capture window.
    attitude : bool
        Also return the flight controller's attitude at :data:`ATTITUDE_RATE` (its
        error: :func:`controller_tilt_error` of ``seed``).
    capture : (float, float), optional
        Truth times of the first and last ramp [s]; default ``times``.

    Returns
    -------
    (ImuSamples, AttitudeLog or None, list of (float, float))
    """
    from compensation.ingestion import WINDOW_MARGIN
    from raysim.io.flight_logs.attitude import AttitudeLog
    from raysim.pipeline.sensors import imu_record
    from raysim.platform.imu import Imu
    from raysim.platform.imu_output import boxcar_output, drop_gaps

    check_flight_log(seed, time_offset, clock_drift_ppm, rate, fast_rate, boxcar)
    clock = Imu("ideal", rate=rate, time_offset=time_offset, clock_drift_ppm=clock_drift_ppm)
    # an IMU clock behind the radar's starts the log 1 us after its own zero, so that
    # rounding to whole microseconds never gives a negative stamp
    boot = 0.0 if float(clock.to_imu_time(0.0)) >= 0 else float(clock.to_true_time(0.0)) + 1e-6
    if boxcar:
        fast = imu_record(trajectory, imu, rate=fast_rate, times=times, seed=seed,
                          time_offset=time_offset, clock_drift_ppm=clock_drift_ppm, start=boot)
        samples = boxcar_output(fast, rate)
    else:
        samples = imu_record(trajectory, imu, rate=rate, times=times, seed=seed,
                             time_offset=time_offset, clock_drift_ppm=clock_drift_ppm,
                             start=boot)
    att = None
    if attitude:
        t_true = np.arange(boot, clock.to_true_time(samples.time[-1]), 1.0 / ATTITUDE_RATE)
        from scipy.spatial.transform import Rotation

        est = Rotation.from_rotvec(controller_tilt_error(t_true, seed)) * trajectory.attitude(
            t_true)
        att = AttitudeLog(clock.to_imu_time(t_true), est, "simulated flight controller "
                          "attitude")
    c0, c1 = (float(v) for v in (times if capture is None else capture))
    chirps = (float(clock.to_imu_time(c0)), float(clock.to_imu_time(c1)))
    placed = place_gaps(gaps, (float(samples.time[0]), float(samples.time[-1])),
                        (chirps[0] - WINDOW_MARGIN, chirps[1] + WINDOW_MARGIN),
                        inside=chirps if gaps_in_capture else None, seed=seed)
    if placed:
        samples = drop_gaps(samples, placed)
        if att is not None:
            keep = np.ones(att.time.size, dtype=bool)
            for s, n in placed:
                keep &= ~((att.time >= s) & (att.time < s + n))
            att = AttitudeLog(att.time[keep], att.rotation[keep], att.source)
    return samples, att, placed
