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
The wavelength cancels. For the 3 x 4 TDM array of the flights (``s_x`` 3.8 mm,
about a wavelength) over 64 loops of 210 us (13.4 ms) and ``v`` = 0.1 m/s it is
0.024 deg per mm/s of velocity error.
"""

from __future__ import annotations

import warnings

import numpy as np

from ._checks import finite_array
from .calibration import doppler_measurements
from .guards import CompensationWarning
from .mounting import world_directions

__all__ = ["AZIMUTH_SHIFT_WARN_DEG", "azimuth_shift", "calibration_azimuth_check",
           "residual_azimuth_shift", "residual_azimuth_warning"]

#: Azimuth shift [deg] of a scatterer above which :func:`residual_azimuth_warning`
#: warns: half the 0.2 deg a compensated target's beam is held to.
AZIMUTH_SHIFT_WARN_DEG = 0.1


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


def residual_azimuth_shift(rcs, element_positions, motions, scatterers, options, *,
                           wavelength: float, channel_times, mounting=None
                           ) -> tuple[np.ndarray, np.ndarray]:
    """The residual range rate the compensated beams leave each scatterer in each frame,
    and the azimuth shift it gives there (:func:`azimuth_shift`).

    Parameters
    ----------
    rcs : sequence of ndarray, each shape ``[chirp, channel, range]``
        Range-compressed frames.
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m].
    motions : sequence of PlatformMotion
        The motion (body, W) of each frame the beams are compensated with.
    scatterers : sequence of compensation.calibration.Scatterer
        Stationary scatterers, directions in W (N of a mounted radar).
    options : dict
        For :func:`compensation.rigid_body_projection` (``range_axis`` included).
    wavelength : float
        [m].
    channel_times : sequence of array_like, each shape ``[chirp, channel]``
        Transmit time of every channel in every chirp loop of each frame [s].
    mounting : array_like, shape ``[3, 3]``, optional
        ``R_BA``; default down-looking.

    Returns
    -------
    (ndarray, ndarray)
        Range rate ``u . (v_used - v_true)`` [m/s] and azimuth shift [rad], both
        ``[frame, scatterer]`` (one Doppler block per frame).
    """
    meas = doppler_measurements(rcs, element_positions, motions, scatterers,
                                {**options, "wavelength": wavelength}, wavelength=wavelength,
                                blocks=1, mounting=mounting)
    rate = meas.range_rate.reshape(len(motions), len(scatterers))
    az = np.array([s.azimuth for s in scatterers])
    el = np.array([s.elevation for s in scatterers])
    across = world_directions(np.stack([np.cos(az), np.zeros_like(az), -np.sin(az)],
                                       axis=-1), mounting)      # increasing azimuth, W
    x = finite_array("element_positions", element_positions, ndim=2)[:, 0]
    shift = np.stack([azimuth_shift(-rate[k], across @ m.radar_velocity.mean(axis=0), x,
                                    times, el)
                      for k, (m, times) in enumerate(zip(motions, channel_times, strict=True))])
    return rate, shift


def residual_azimuth_warning(rate, shift, scatterers, warn: bool = True) -> tuple[str, ...]:
    """The warning of the largest :func:`residual_azimuth_shift` (``rate`` and ``shift``
    ``[frame, scatterer]``) when it exceeds :data:`AZIMUTH_SHIFT_WARN_DEG`, issued as a
    :class:`compensation.guards.CompensationWarning` unless ``warn`` is false; else
    nothing."""
    k, j = np.unravel_index(int(np.argmax(np.abs(shift))), np.shape(shift))
    deg = float(np.rad2deg(abs(shift[k, j])))
    if deg <= AZIMUTH_SHIFT_WARN_DEG:
        return ()
    s = scatterers[j]
    text = (f"azimuth: the compensated beams leave the scatterer at azimuth "
            f"{np.rad2deg(s.azimuth):.1f} deg, elevation {np.rad2deg(s.elevation):.1f} deg a "
            f"range rate of {1e3 * rate[k, j]:+.1f} mm/s in frame {k}, a Doppler the estimated "
            f"motion does not remove (its velocity, where the scene leaves it uncertain); "
            f"while the radar moves across the beam that Doppler moves the scatterer's "
            f"azimuth by {np.rad2deg(shift[k, j]):+.2f} deg (over {AZIMUTH_SHIFT_WARN_DEG:g})")
    if warn:
        warnings.warn(text, CompensationWarning, stacklevel=3)
    return (text,)


def calibration_azimuth_check(result, rcs, element_positions, channel_times, *,
                              wavelength: float, range_axis, grid_shape=None,
                              channel_slot=None, mounting=None, warn: bool = True
                              ) -> tuple[str, ...]:
    """:func:`residual_azimuth_warning` of a self-calibration's scatterers under its motion.

    Parameters
    ----------
    result : compensation.calibration.CalibrationResult
    rcs, element_positions, channel_times, wavelength, mounting
        As :func:`residual_azimuth_shift`.
    range_axis : array_like, shape ``[range]``
        Range of each bin [m].
    grid_shape, channel_slot
        The array's grid and TDM slots (:func:`compensation.rigid_body_projection`).
    warn : bool
        Issue the warning too.

    Returns
    -------
    tuple of str
        The warning, or nothing.
    """
    options = {"range_axis": range_axis, "grid_shape": grid_shape,
               "method": "lattice" if grid_shape is not None else "direct"}
    if channel_slot is not None:
        options["channel_slot"] = channel_slot
    rate, shift = residual_azimuth_shift(rcs, element_positions, result.motions,
                                         result.scatterers, options, wavelength=wavelength,
                                         channel_times=channel_times, mounting=mounting)
    return residual_azimuth_warning(rate, shift, result.scatterers, warn=warn)
