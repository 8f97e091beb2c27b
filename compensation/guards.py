"""Checks of the compensation's assumptions, reported as short warning strings.

The compensation cannot tell from its inputs alone whether its result is
right, but it can tell when an assumption it relies on does not hold. Such
conditions are reported in the ``warnings`` tuple of the result
(:class:`~compensation.PlatformMotion`, :class:`~compensation.BeamCube`)
instead of returning a quietly wrong cube. Every warning starts with one of
these stable keys, followed by a colon and the numbers:

``"hover window"``
    ``velocity="hover"`` (or ``initial_attitude="level"``) over a window
    shorter than :data:`HOVER_MIN_WINDOW` or no longer than the frame: the
    initial velocity (and the levelled attitude) is poorly observable.
``"levelling"``
    The mean specific force over the levelling window differs from gravity by
    more than :data:`LEVELLING_TOL`: the platform was not at rest on average.
``"small-angle"``
    The paper chain's small-angle, boresight tilt correction leaves an angle
    error above half a beamwidth towards the target direction, or the tilt
    exceeds :data:`SMALL_ANGLE_TILT_LIMIT`.
``"paper rotation phase"``
    The published lever-arm phase ``v_r(t_n) (t_n - t_0)`` departs from the
    integrated displacement by more than :data:`ROTATION_PHASE_LIMIT` because
    the radial velocity changes over the frame.
``"azimuth"``
    After a self-calibration, the range rate the beams leave a scatterer moves its
    azimuth by more than :data:`compensation.azimuth_shift.AZIMUTH_SHIFT_WARN_DEG`
    (:func:`compensation.azimuth_shift.calibration_azimuth_check`).

IMU gaps are handled at ingestion (:mod:`compensation.ingestion`): short
ones are interpolated with an ``"imu gaps"`` warning, longer ones raise
``ValueError`` (interpolating across them would give a wrong pose).

Thresholds are those of the measured failure boundaries (docs/stability.md):
failure is a residual pseudo-velocity above one Doppler bin or an angle error
above half the 3 dB beamwidth.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

#: IMU sample interval above which ingestion reports a gap, as a multiple of the median
#: interval (:mod:`compensation.ingestion`).
GAP_FACTOR = 1.5
#: Shortest hover window for which the initial velocity counts as observable [s].
HOVER_MIN_WINDOW = 0.5
#: Tolerated relative difference between the mean specific force and gravity
#: over the levelling window [1].
LEVELLING_TOL = 0.01
#: Roll or pitch beyond which the paper's first-order tilt correction is outside
#: its regime at any direction [rad] (15 deg; the neglected second-order terms
#: exceed 3 %, and the 20 x 20 maps fail from 15 deg at 30-40 deg off boresight).
SMALL_ANGLE_TILT_LIMIT = float(np.deg2rad(15.0))
#: Largest tolerated phase error of the published lever-arm phase against the
#: integrated displacement, ``4 pi max|e_n| / lambda`` [rad] (a quarter
#: wavelength of range).
ROTATION_PHASE_LIMIT = float(np.pi)
#: 3 dB beamwidth factor of a uniform aperture, ``theta_3dB = k lambda / L``.
BEAMWIDTH_FACTOR = 0.886


class CompensationWarning(UserWarning):
    """Python warning category for checks of functions that return a bare array."""


def hover_window_warning(window: tuple[float, float], frame: tuple[float, float],
                         interval: float) -> tuple[str, ...]:
    """``("hover window: ...",)`` when the window cannot observe the initial velocity.

    Parameters
    ----------
    window : (float, float)
        Hover window on the IMU clock [s].
    frame : (float, float)
        First and last chirp on the IMU clock [s].
    interval : float
        Median IMU sample interval [s] (tolerance of the length test).
    """
    length = window[1] - window[0]
    reasons = []
    if length + interval < HOVER_MIN_WINDOW:
        reasons.append(f"shorter than {HOVER_MIN_WINDOW:g} s")
    if length <= frame[1] - frame[0]:
        reasons.append(f"not longer than the frame ({frame[1] - frame[0]:.4g} s)")
    if not reasons:
        return ()
    return (f"hover window: {length:.4g} s is {' and '.join(reasons)}; the initial velocity "
            f"is poorly observable (use a window spanning whole motion periods, or "
            f"velocity='given')",)


def levelling_warning(mean_force: np.ndarray, gravity: float) -> tuple[str, ...]:
    """``("levelling: ...",)`` when the mean specific force is not ``gravity`` in magnitude."""
    mag = float(np.linalg.norm(mean_force))
    rel = abs(mag - gravity) / gravity
    if rel <= LEVELLING_TOL:
        return ()
    return (f"levelling: mean specific force {mag:.4g} m/s^2 differs from gravity by "
            f"{100 * rel:.2g} %; the platform was not at rest on average over the window and "
            f"roll/pitch are biased",)


def aperture_length(element_positions) -> float:
    """Largest extent of a planar aperture along x or y, ``(n - 1)`` gaps plus one [m].

    For ``n`` distinct coordinates spread over ``ptp`` the aperture is
    ``ptp n / (n - 1)`` (``N d`` for a uniform array); 0 for a single element.
    """
    p = np.asarray(element_positions, dtype=float)
    out = 0.0
    for axis in (0, 1):
        c = np.unique(np.round(p[:, axis], 9))
        if c.size > 1:
            out = max(out, float(np.ptp(c)) * c.size / (c.size - 1))
    return out


def half_beamwidth(element_positions, wavelength: float) -> float:
    """Half the 3 dB beamwidth ``0.5 * 0.886 lambda / L`` of the aperture [rad] (inf if none)."""
    length = aperture_length(element_positions)
    return 0.5 * BEAMWIDTH_FACTOR * wavelength / length if length > 0 else float("inf")


def tilt_residual(attitude, direction) -> np.ndarray:
    """Angle error left by the small-angle boresight tilt correction, per chirp [rad].

    Parameters
    ----------
    attitude : ndarray, shape ``[chirp, 3, 3]``
        ``R_WB``; roll ``phi`` and pitch ``theta`` are its Z-Y-X Euler angles.
    direction : array_like, shape ``[3]``
        Target direction ``u`` in W (unit).

    Returns
    -------
    ndarray, shape ``[chirp]``
        Angle between the direction the corrected array sees, with direction
        cosines ``(v_x + theta, v_y - phi)`` of the body-frame direction
        ``v = R^T u``, and the direction an exact roll/pitch removal gives,
        ``Rz(psi)^T u``; ``inf`` where the corrected cosines leave the visible
        region. For a pure pitch and a target in the x-z plane this is
        ``|asin(sin(az - theta) + theta) - az|``.
    """
    att = np.asarray(attitude, dtype=float)
    u = np.asarray(direction, dtype=float)
    ypr = Rotation.from_matrix(att).as_euler("ZYX")
    v = np.einsum("nji,j->ni", att, u)                             # R^T u
    cx = v[:, 0] + ypr[:, 1]
    cy = v[:, 1] - ypr[:, 2]
    s = cx * cx + cy * cy
    visible = s < 1.0
    corrected = np.stack([cx, cy, np.sqrt(np.where(visible, 1.0 - s, 0.0))], axis=-1)
    c, sn = np.cos(ypr[:, 0]), np.sin(ypr[:, 0])
    exact = np.stack([c * u[0] + sn * u[1], -sn * u[0] + c * u[1],
                      np.full_like(c, u[2])], axis=-1)               # Rz(psi)^T u
    cosang = np.clip(np.einsum("ni,ni->n", corrected, exact), -1.0, 1.0)
    return np.where(visible, np.arccos(cosang), np.inf)


def small_angle_warnings(attitude, element_positions, direction=None, *,
                         wavelength: float) -> tuple[str, ...]:
    """``"small-angle: ..."`` warnings of the paper's tilt correction.

    Parameters
    ----------
    attitude : ndarray, shape ``[chirp, 3, 3]``
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual positions in A [m] (they set the beamwidth).
    direction : array_like, shape ``[3]``, optional
        Target direction in W; without it only the tilt limit is checked.
    wavelength : float
        [m].

    Returns
    -------
    tuple of str
        Empty when the tilt stays below :data:`SMALL_ANGLE_TILT_LIMIT` and the
        residual towards ``direction`` (:func:`tilt_residual`) below half the
        3 dB beamwidth at every chirp.
    """
    att = np.asarray(attitude, dtype=float)
    out = []
    ypr = Rotation.from_matrix(att).as_euler("ZYX")
    tilt = np.maximum(np.abs(ypr[:, 1]), np.abs(ypr[:, 2]))
    n = int(np.argmax(tilt))
    if tilt[n] > SMALL_ANGLE_TILT_LIMIT:
        out.append(f"small-angle: tilt {np.rad2deg(tilt[n]):.3g} deg at chirp {n} exceeds the "
                   f"{np.rad2deg(SMALL_ANGLE_TILT_LIMIT):.3g} deg limit of the first-order tilt "
                   f"correction")
    if direction is not None:
        res = tilt_residual(att, direction)
        hbw = half_beamwidth(element_positions, wavelength)
        n = int(np.argmax(res))
        if res[n] > hbw:
            u = np.asarray(direction, dtype=float)
            az = np.rad2deg(np.arctan2(u[0], u[2]))
            el = np.rad2deg(np.arcsin(np.clip(u[1], -1.0, 1.0)))
            what = ("leaves the visible region" if not np.isfinite(res[n])
                    else f"leaves {np.rad2deg(res[n]):.3g} deg of angle error")
            out.append(f"small-angle: at chirp {n} (roll {np.rad2deg(ypr[n, 2]):.3g} deg, pitch "
                       f"{np.rad2deg(ypr[n, 1]):.3g} deg) the tilt correction {what} towards "
                       f"(az {az:.3g}, el {el:.3g}) deg, above half the beamwidth "
                       f"({np.rad2deg(hbw):.3g} deg)")
    return tuple(out)


def rotation_phase_warnings(motion, direction, *, wavelength: float) -> tuple[str, ...]:
    """``"paper rotation phase: ..."`` when ``v_r(t_n) (t_n - t_0)`` misses the displacement.

    Parameters
    ----------
    motion : PlatformMotion
    direction : array_like, shape ``[3]``
        Target direction ``u`` in W (unit).
    wavelength : float
        [m].

    Returns
    -------
    tuple of str
        Empty while ``4 pi max_n |e_n - e_0| / lambda <= ROTATION_PHASE_LIMIT``,
        with ``e_n = v_r(t_n) (t_n - t_0) + ((R_n - I) r_IR) . u`` the
        difference of the published and the integrated lever-arm range
        change and ``v_r = -(omega x r_IR) . u``. The maps fail from about
        0.3 motion cycles per frame; at 0.15 cycles the phase error is 2 rad
        and the pseudo-velocity error 0.13 bin.
    """
    u = np.asarray(direction, dtype=float)
    v_r = -(np.cross(motion.angular_rate, motion.lever_arm) @ u)
    published = v_r * (motion.time - motion.time[0])
    integrated = -(motion.rotation_displacement @ u)
    e = published - integrated
    e = e - e[0]
    phase = 4.0 * np.pi * float(np.abs(e).max()) / wavelength
    if phase <= ROTATION_PHASE_LIMIT:
        return ()
    return (f"paper rotation phase: the lever-arm radial velocity changes by "
            f"{float(np.ptp(v_r)):.3g} m/s over the frame, so v_r(t) t departs from the "
            f"integrated displacement by up to {phase:.3g} rad (limit "
            f"{ROTATION_PHASE_LIMIT:.3g}); use rotation_phase='integrated'",)


def merge(*groups) -> tuple[str, ...]:
    """Concatenate warning tuples, dropping repeats, keeping the order."""
    out: list[str] = []
    for g in groups:
        for w in g:
            if w not in out:
                out.append(str(w))
    return tuple(out)
