"""The IMU record of a run (stage 2 of the run path): one builder for every command.

:func:`imu_record` is the only place a simulated IMU record is cut out of a
trajectory: it covers the given radar times with one margin rule, so every
command and study that simulates the same scenario sees the same samples.
:func:`imu_log` wraps it as the ``imu_time`` Dataset of a store.
"""

from __future__ import annotations

import numpy as np

__all__ = ["IMU_MARGIN_S", "imu_margin_s", "imu_record", "imu_log"]

#: Least IMU record margin before the first and after the last radar time [s].
IMU_MARGIN_S = 0.02


def imu_margin_s(rate: float, times, *, time_offset: float = 0.0,
                 clock_drift_ppm: float = 0.0) -> float:
    """Record margin either side of the radar times [s].

    ``max(IMU_MARGIN_S, 4 / rate)`` (the strapdown's interpolation needs samples
    either side of every chirp) plus the largest IMU clock error over the times,
    ``|time_offset| + 1e-6 |clock_drift_ppm| max|t|``, so a record stamped on a
    wrong clock still covers them.

    Parameters
    ----------
    rate : float
        IMU output rate [Hz].
    times : array_like, shape ``[time]``
        Radar times to cover [s].
    """
    t = np.asarray(times, dtype=float)
    clock = abs(time_offset) + 1e-6 * abs(clock_drift_ppm) * float(np.max(np.abs(t)))
    return max(IMU_MARGIN_S, 4.0 / rate) + clock


def imu_record(trajectory, spec, *, rate: float, times, seed=None, time_offset: float = 0.0,
               clock_drift_ppm: float = 0.0, lead_s: float = 0.0, start: float | None = None):
    """Simulated IMU samples along ``trajectory`` covering the radar ``times``.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
        Truth motion.
    spec : raysim.platform.imu_spec.ImuSpec or str
        Error specification or preset name.
    rate : float
        Output rate on the IMU clock [Hz].
    times : array_like, shape ``[time]``
        Radar times the record must cover (chirp or slot times) [s].
    seed : int, numpy.random.Generator or None
        Seed of the error draws.
    time_offset, clock_drift_ppm : float
        IMU clock reading at truth time 0 [s] and its rate error [ppm].
    lead_s : float
        Extra record before the first and after the last time [s] (a hover
        window for the hover initial condition).
    start : float, optional
        Truth time the record starts [s] (a flight log that starts at power-up);
        default the first time less the margin (:func:`imu_margin_s`) and ``lead_s``.

    Returns
    -------
    raysim.platform.imu.ImuSamples
        Time stamps on the IMU clock [s], gyro [rad/s], accelerometer [m/s^2] (FRD).
    """
    from raysim.platform.imu import simulate_imu

    t = np.asarray(times, dtype=float).ravel()
    if t.size == 0 or not np.all(np.isfinite(t)):
        raise ValueError(f"times must be finite radar times [s], got {t.size} value(s)")
    if not (np.isfinite(lead_s) and lead_s >= 0):
        raise ValueError(f"lead_s must be >= 0 s, got {lead_s!r}")
    margin = imu_margin_s(rate, t, time_offset=time_offset,
                          clock_drift_ppm=clock_drift_ppm) + lead_s
    first = float(t.min()) - margin if start is None else float(start)
    return simulate_imu(trajectory, spec, rate=rate, start=first, end=float(t.max()) + margin,
                        seed=seed, time_offset=time_offset, clock_drift_ppm=clock_drift_ppm)


def imu_log(scenario, trajectory=None):
    """Simulate the scenario's IMU over all frames as an ``imu_time`` Dataset.

    Parameters
    ----------
    scenario : raysim.scenario.Scenario
    trajectory : raysim.platform.motion.Trajectory, optional
        Default ``scenario.trajectory()``.

    Returns
    -------
    xarray.Dataset
        See :func:`raysim.io.storage.imu_dataset`.
    """
    from raysim.io.storage import imu_dataset

    traj = scenario.trajectory() if trajectory is None else trajectory
    s = imu_record(traj, scenario.imu_spec(), rate=scenario.imu.rate_hz,
                   times=np.asarray(scenario.time_span(), dtype=float), seed=scenario.imu_seed,
                   time_offset=scenario.imu.time_offset_s,
                   clock_drift_ppm=scenario.imu.clock_drift_ppm)
    t, w, a = s.to_arrays()
    ds = imu_dataset(t, w, a, source=f"simulated, preset {scenario.imu.preset}")
    ds.attrs.update({"imu_rate_hz": float(scenario.imu.rate_hz),
                     "imu_seed": int(scenario.imu_seed),
                     "imu_time_offset_s": float(scenario.imu.time_offset_s),
                     "imu_clock_drift_ppm": float(scenario.imu.clock_drift_ppm)})
    return ds
