"""Motion estimate of a stability point: simulated IMU -> ``estimate_motion`` of the pipeline.

The chains treat IMU time stamps as radar time (``imu_time_offset_s`` and
``imu_clock_drift_ppm`` are errors they do not know about) and are given the
believed lever arm ``lever_arm_m + lever_arm_error_m``. The IMU sits on the
body; a mounted radar's chains get the navigation solution in its nominal
radar frame N (:func:`raysim.platform.mounting.mount_motion`), where its beams
are formed.
"""

from __future__ import annotations

import numpy as np

from raysim.pipeline.estimate import estimate_motion
from raysim.studies.stability.point import StabilityPoint

__all__ = ["HOVER_WINDOW_S", "point_imu_record", "point_motion"]

#: Hover-assumption window either side of the frame for ``init="hover"`` [s].
HOVER_WINDOW_S = 0.25


def point_imu_record(point: StabilityPoint, chirp_times: np.ndarray):
    """IMU samples covering the frame (plus :data:`HOVER_WINDOW_S` either side for ``hover``).

    Parameters
    ----------
    point : StabilityPoint
    chirp_times : ndarray, shape ``[chirp]``
        Radar time of each chirp [s].

    Returns
    -------
    raysim.platform.imu.ImuSamples
        Seeded by ``point.seed``; time stamps on the IMU clock [s].
    """
    from raysim.pipeline.sensors import imu_record

    return imu_record(point.trajectory, point.imu_spec, rate=point.imu_rate_hz,
                      times=chirp_times, seed=point.seed, time_offset=point.imu_time_offset_s,
                      clock_drift_ppm=point.imu_clock_drift_ppm,
                      lead_s=HOVER_WINDOW_S if point.init == "hover" else 0.0)


def point_motion(point: StabilityPoint, chirp_times: np.ndarray | None = None):
    """Navigation solution the chains use, at every chirp of the point's frame.

    Initial state (``point.init``): ``"truth"`` gives the true attitude,
    position and velocity at the first chirp (an aligned navigation
    solution); ``"hover"`` gives the nominal attitude and position and assumes
    the velocity averages to zero over the IMU record.

    Parameters
    ----------
    point : StabilityPoint
    chirp_times : ndarray, shape ``[chirp]``, optional
        Radar time of each chirp [s] (default ``point.chirp_times()``).

    Returns
    -------
    compensation.PlatformMotion
        Pose at every chirp, in the nominal radar frame N of ``point.mounting_deg``
        (W itself for the default ``down``); ``lever_arm`` is the believed one.
    """
    from raysim.platform.mounting import mount_motion

    times = point.chirp_times() if chirp_times is None else np.asarray(chirp_times, dtype=float)
    t, gyro, accel = point_imu_record(point, times).to_arrays()
    options = {}
    if point.init == "hover":
        options = dict(initial_attitude=np.eye(3), initial_position=np.zeros(3))
    motion = estimate_motion(t, gyro, accel, times, lever_arm=point.believed_lever_arm_m,
                             trajectory=point.trajectory, time_offset=0.0,
                             velocity="given" if point.init == "truth" else "hover", **options)
    return mount_motion(motion, point.mounting_deg)          # beams in N
