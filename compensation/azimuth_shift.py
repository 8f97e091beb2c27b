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

import numpy as np

from ._checks import finite_array

__all__ = ["azimuth_shift"]


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
