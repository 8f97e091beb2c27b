"""The IMU log of a scenario (stage 2 of the run path): simulated samples as a Dataset."""

from __future__ import annotations

from raysim.io.scenario import Scenario

__all__ = ["IMU_MARGIN_S", "imu_log"]

#: IMU record margin before the first and after the last chirp [s].
IMU_MARGIN_S = 0.02


def imu_log(scenario: Scenario, trajectory=None):
    """Simulate the scenario's IMU over all frames as an ``imu_time`` Dataset.

    Returns
    -------
    xarray.Dataset or None
        See :func:`raysim.io.storage.imu_dataset`; None when :mod:`raysim.platform.imu`
        is not available.
    """
    try:
        from raysim.platform.imu import simulate_imu
    except ImportError:
        return None
    from raysim.io.storage import imu_dataset

    traj = scenario.trajectory() if trajectory is None else trajectory
    start, end = scenario.time_span()
    rate = scenario.imu.rate_hz
    margin = max(IMU_MARGIN_S, 4.0 / rate)
    s = simulate_imu(traj, scenario.imu_spec(), rate=rate, start=start - margin, end=end + margin,
                     seed=scenario.imu_seed, time_offset=scenario.imu.time_offset_s,
                     clock_drift_ppm=scenario.imu.clock_drift_ppm)
    t, w, a = s.to_arrays()
    ds = imu_dataset(t, w, a, source=f"simulated, preset {scenario.imu.preset}")
    ds.attrs.update({"imu_rate_hz": float(rate), "imu_seed": int(scenario.imu_seed),
                     "imu_time_offset_s": float(scenario.imu.time_offset_s),
                     "imu_clock_drift_ppm": float(scenario.imu.clock_drift_ppm)})
    return ds


