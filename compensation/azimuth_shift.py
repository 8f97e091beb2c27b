"""The azimuth shift a radar velocity error leaves in the compensated beams.

A beam formed with a radar velocity that misses the true one by ``dv_r`` along
a stationary target's direction leaves it a residual Doppler. While the radar
also moves across the beam (velocity ``v`` along the azimuth axis), the
elements sweep a short synthetic aperture over the frame, on which that
Doppler reads as a direction: the zero-Doppler peak of the target moves in
azimuth, as a moving target's image moves in a synthetic-aperture radar
(Raney, "Synthetic aperture imaging radar and moving targets", IEEE Trans.
AES-7, 1971). The real array holds the peak back; at second order about the
peak (both apertures' patterns quadratic) the beam power is
``1 - var(phi)`` with the phase of element ``x`` at time ``t``
``phi = k (x + 2 v t) e - 2 k dv_r t`` (``k = 2 pi / lambda``, ``e`` the
beam's offset in direction cosine), least spread at::

    e = dv_r (4 s_t^2 v + 2 c) / (s_x^2 + 4 s_t^2 v^2 + 4 v c)

``s_x^2`` the spread of the virtual positions along the azimuth axis,
``s_t^2`` that of the transmit times over the frame and ``c`` their
covariance (a TDM array's slots fire one after another); the azimuth shift is
``e / cos(el)``. With ``v`` = 0 only the TDM term ``2 c dv_r / s_x^2`` remains.
The wavelength cancels. For a 3 x 4 TDM array (``s_x`` about one wavelength,
3.9 mm at 77 GHz) over 64 loops of 210 us (13.4 ms) and ``v`` = 0.1 m/s it is
0.024 deg per mm/s of velocity error.
"""

from __future__ import annotations

import warnings

import numpy as np

from ._checks import finite_array
from .guards import CompensationWarning
from .mounting import world_directions
from .radar_inertial import ACCEL_BIAS, ATTITUDE, VELOCITY
from .strapdown import STANDARD_GRAVITY, PlatformMotion

__all__ = ["AZIMUTH_SPREAD_WARN_DEG", "azimuth_shift", "azimuth_spread", "azimuth_spread_warning",
           "record_azimuth_warning", "velocity_covariance_at"]

#: One-sigma azimuth spread [deg] above which :func:`azimuth_spread_warning` warns: half
#: the 0.2 deg a compensated target's beam is held to, so that two sigmas reach it.
AZIMUTH_SPREAD_WARN_DEG = 0.1


def azimuth_shift(range_rate_error, cross_range_velocity, element_x, channel_time,
                  elevation=0.0) -> np.ndarray:
    """Azimuth shift [rad] of a stationary target's zero-Doppler peak.

    Parameters
    ----------
    range_rate_error : float or ndarray
        ``u . (v_true - v_used)``: the radar velocity along the target's
        direction ``u`` that the compensation misses [m/s].
    cross_range_velocity : float or ndarray (broadcast with it)
        Radar velocity along the azimuth axis over the frame (the unit vector
        of increasing azimuth at the target) [m/s].
    element_x : array_like, shape ``[channel]``
        Virtual element positions along the azimuth axis of the radar frame [m].
    channel_time : array_like, shape ``[chirp, channel]``
        Transmit time of every channel in every chirp loop [s] (under TDM the
        slot of its transmitter).
    elevation : float or ndarray
        The target's elevation [rad].

    Returns
    -------
    ndarray
        Azimuth of the peak minus the target's [rad], the shape of the broadcast inputs.

    Raises
    ------
    ValueError
        Non-finite inputs, or shapes that do not match.
    """
    x = finite_array("element_x", element_x, ndim=1)
    t = finite_array("channel_time", channel_time, shape=(None, x.size))
    dv = finite_array("range_rate_error", range_rate_error)
    v = finite_array("cross_range_velocity", cross_range_velocity)
    el = finite_array("elevation", elevation)
    xs = np.broadcast_to(x, t.shape)
    s_x2, s_t2 = np.var(xs), np.var(t)
    c = np.mean((xs - xs.mean()) * (t - t.mean()))
    e = dv * (4 * s_t2 * v + 2 * c) / (s_x2 + 4 * s_t2 * v ** 2 + 4 * v * c)
    return e / np.cos(el)


def velocity_covariance_at(covariance, attitude, elapsed: float) -> np.ndarray:
    """Covariance ``[3, 3]`` [m^2/s^2] of the body velocity ``elapsed`` [s] after the
    reference time, from that of a radar-inertial state ``[14, 14]``
    (:data:`compensation.radar_inertial.STATE_NAMES`).

    The velocity error grows with the attitude error on the hover's specific force
    (``phi x f``, ``f = (0, 0, -g)`` in W) and the accelerometer bias (``-R_WB b``),
    ``attitude`` ``R_WB`` [3, 3] of the frame; the gyro bias, of second order over a
    record of frames, is left out.
    """
    p = finite_array("covariance", covariance, shape=(14, 14))
    r = finite_array("attitude", attitude, shape=(3, 3))
    f = np.array([0.0, 0.0, -STANDARD_GRAVITY])
    j = np.zeros((3, 14))
    j[:, VELOCITY] = np.eye(3)
    j[:, ATTITUDE] = -np.array([[0.0, -f[2], f[1]], [f[2], 0.0, -f[0]],
                                [-f[1], f[0], 0.0]]) * elapsed
    j[:, ACCEL_BIAS] = -r * elapsed
    return j @ p @ j.T


def azimuth_spread(velocity_cov, motion: PlatformMotion, element_positions, channel_time,
                   azimuth, elevation, mounting=None) -> tuple[np.ndarray, np.ndarray]:
    """One-sigma azimuth shift [rad] that a velocity spread leaves towards directions.

    Parameters
    ----------
    velocity_cov : array_like, shape ``[3, 3]``
        Covariance of the radar velocity in W over the frame [m^2/s^2].
    motion : PlatformMotion
        The frame's motion (body, W): its mean radar velocity gives the cross-range one.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in the radar frame A [m].
    channel_time : array_like, shape ``[chirp, channel]``
        Transmit time of every channel in every chirp loop [s].
    azimuth, elevation : array_like, shape ``[direction]``
        Directions of the beams' frame (W, or N of a mounted radar) [rad].
    mounting : array_like, shape ``[3, 3]``, optional
        ``R_BA`` (:mod:`compensation.mounting`); default down-looking.

    Returns
    -------
    (ndarray, ndarray)
        The spread ``[direction]`` [rad] and the velocity spread along each
        direction ``[direction]`` [m/s].
    """
    c = finite_array("velocity_cov", velocity_cov, shape=(3, 3))
    az = finite_array("azimuth", azimuth, ndim=1)
    el = finite_array("elevation", elevation, shape=az.shape)
    u = world_directions(np.stack([np.cos(el) * np.sin(az), np.sin(el),
                                   np.cos(el) * np.cos(az)], axis=-1), mounting)
    across = world_directions(np.stack([np.cos(az), np.zeros_like(az), -np.sin(az)],
                                       axis=-1), mounting)
    sigma = np.sqrt(np.maximum(np.einsum("di,ij,dj->d", u, c, u), 0.0))
    v = across @ motion.radar_velocity.mean(axis=0)
    x = finite_array("element_positions", element_positions, ndim=2)[:, 0]
    return np.abs(azimuth_shift(sigma, v, x, channel_time, el)), sigma


def azimuth_spread_warning(spread, sigma, azimuth, elevation, frame: int) -> str | None:
    """The warning of the largest :func:`azimuth_spread` over directions ``[direction]``
    [rad] of a frame when it exceeds :data:`AZIMUTH_SPREAD_WARN_DEG`, or None."""
    k = int(np.argmax(spread))
    deg = float(np.rad2deg(spread[k]))
    if deg <= AZIMUTH_SPREAD_WARN_DEG:
        return None
    return (f"azimuth: the estimated radar velocity is known to +-{1e3 * sigma[k]:.1f} mm/s "
            f"(one sigma) towards azimuth {np.rad2deg(azimuth[k]):.1f} deg, elevation "
            f"{np.rad2deg(elevation[k]):.1f} deg in frame {frame}; with the radar's motion "
            f"across the beam during the frame that moves the azimuth of a target there by "
            f"+-{deg:.2f} deg (over {AZIMUTH_SPREAD_WARN_DEG:g} deg): a Doppler the scene "
            f"leaves unresolved reads as an angle")


def record_azimuth_warning(result, element_positions, channel_times, mounting=None,
                           warn: bool = True) -> tuple[str, ...]:
    """The azimuth spread a self-calibrated record's velocity leaves at its scatterers.

    Parameters
    ----------
    result : compensation.calibration.CalibrationResult
        A self-calibration; without a radar-inertial estimate (no velocity
        estimated) nothing is said.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m].
    channel_times : sequence of array_like, each shape ``[chirp, channel]``
        Transmit time of every channel in every chirp loop of each frame [s].
    mounting : array_like, shape ``[3, 3]``, optional
        ``R_BA``; default down-looking.
    warn : bool
        Also issue it as a :class:`compensation.guards.CompensationWarning`.

    Returns
    -------
    tuple of str
        :func:`azimuth_spread_warning` of the worst frame (the velocity spread
        of each frame's middle by :func:`velocity_covariance_at`), or nothing.
    """
    ri = result.radar_inertial
    if ri is None:
        return ()
    az = np.array([s.azimuth for s in result.scatterers])
    el = np.array([s.elevation for s in result.scatterers])
    worst = None
    for k, (m, times) in enumerate(zip(ri.motions, channel_times, strict=True)):
        mid = m.num_chirps // 2
        cov = velocity_covariance_at(ri.covariance, m.attitude[mid],
                                     float(m.time[mid] - ri.motions[0].time[0]))
        spread, sigma = azimuth_spread(cov, m, element_positions, times, az, el, mounting)
        if worst is None or spread.max() > worst[0].max():
            worst = (spread, sigma, k)
    text = azimuth_spread_warning(*worst[:2], az, el, worst[2])
    if text is None:
        return ()
    if warn:
        warnings.warn(text, CompensationWarning, stacklevel=2)
    return (text,)
