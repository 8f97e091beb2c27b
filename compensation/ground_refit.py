"""The ground's roll and pitch again with another integration of the record.

The ground's points are found once, with the first guess of the integration
(:func:`compensation.ground_plane.ground_tilt`); the calibration then finds the
clock offset and the gyro bias, which turn every later frame's attitude relative to
the first (a clock error ``d`` by about ``(omega(t_k) - omega(t_0)) d``). One plane
through frames turned by a wrong integration gives the tilt averaged over those
turns, not the first ramp's: the points are turned with the calibrated integration
and fitted again.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from scipy.linalg import eigh
from scipy.spatial.transform import Rotation

from .ground_plane import GroundPlane, fit_looks

__all__ = ["GroundRetilt", "refit_ground"]


def refit_ground(fit: GroundPlane, motions, *, gyro_bias_sigma: float = 0.0) -> GroundPlane:
    """The ground's tilt again, its points turned into W by another integration of the record.

    Every look's points were turned into W by the attitude of one integration at its
    snapshot; an integration with another clock offset or gyro bias turns each frame
    by another angle (a clock error ``d`` by about ``(omega(t_k) - omega(t_0)) d``:
    6.5 ms at the tens of deg/s of a hover's jitter is a quarter of a degree), which
    one plane through every frame averages into the tilt. The looks are turned by
    ``R'_k R_k^T`` (:meth:`compensation.ground_looks.GroundLook.turned`) and fitted
    again: no ground point is found again, so it costs a fit.

    Parameters
    ----------
    fit : GroundPlane
        A fit of :func:`compensation.ground_plane.ground_tilt` with its :attr:`GroundPlane.looks` (a
        down-looking radar's).
    motions : sequence of PlatformMotion
        The record's frames integrated again (the same times); the tilt returned
        corrects the attitude of ``motions[0]`` at its first chirp.
    gyro_bias_sigma : float
        Spread of the gyro bias left in ``motions`` [rad/s].

    Returns
    -------
    GroundPlane
        As :func:`compensation.ground_plane.ground_tilt` (not warned; its warnings in the result).
    """
    if not fit.looks:
        raise ValueError("fit: holds no looks (only a down-looking radar's ground_tilt keeps "
                         "them); nothing to turn")
    if max(k.frame for k in fit.looks) >= len(motions):
        raise ValueError(f"motions: {len(motions)} frame(s), the looks need frame "
                         f"{max(k.frame for k in fit.looks)}")
    looks = []
    for k in fit.looks:
        att = np.asarray(motions[k.frame].attitude[k.pose], dtype=float)
        points, cov = k.turned(att)
        looks.append(replace(k, attitude=att, points=points, covariance=cov))
    return replace(fit_looks(looks, motions, gyro_bias_sigma=gyro_bias_sigma),
                   source=fit.source)


class GroundRetilt:
    """The initial roll and pitch from the ground with the integration a calibration found.

    :func:`compensation.calibration.self_calibrate` (``ground=``) calls it with its
    motions once the clock offset and gyro bias are estimated, before the
    radar-inertial estimate takes the initial attitude: the ground's points were
    turned into W with the first guess (:func:`refit_ground`).

    Parameters
    ----------
    fit : GroundPlane
        The first fit (:func:`compensation.ground_plane.ground_tilt`, its looks kept).
    reference : array_like, shape ``[3, 3]``
        The initial attitude the first fit's tilt corrects (of the first guess).
    gyro_bias_sigma : float
        Spread of the gyro bias left [rad/s].

    Attributes
    ----------
    fit : GroundPlane
        The latest fit, its tilt the correction of ``reference`` (the first fit until
        called, and when the new fit is not usable).
    """

    def __init__(self, fit: GroundPlane, reference, gyro_bias_sigma: float = 0.0):
        self.fit, self._first = fit, fit
        self._reference = np.asarray(reference, dtype=float)
        self._sigma = float(gyro_bias_sigma)

    def __call__(self, motions, tilt_covariance):
        """``(initial attitude [3, 3], tilt covariance [2, 2] [rad^2])`` from the ground
        with ``motions``; ``motions[0]``'s first attitude and ``tilt_covariance``
        unchanged when its fit is not usable."""
        att = np.asarray(motions[0].attitude[0], dtype=float)
        new = refit_ground(self._first, motions, gyro_bias_sigma=self._sigma)
        if new.source != "range" and new.usable:
            # the range-Doppler points of a dense ground are few a jackknife sector: the
            # same points turned by a few tenths of a degree state no less than they did
            # (a refit of 14 such points stated 0.8 deg where the first stated 17 and
            # both erred by 9)
            scale = max(1.0, float(np.max(eigh(self._first.tilt_covariance,
                                                new.tilt_covariance, eigvals_only=True))))
            new = replace(new, tilt_covariance=new.tilt_covariance * scale)
        if not new.usable:
            return att, tilt_covariance
        att = Rotation.from_rotvec([*new.tilt, 0.0]).as_matrix() @ att
        total = Rotation.from_matrix(att @ self._reference.T).as_rotvec()[:2]
        self.fit = replace(new, tilt=total)
        return att, new.tilt_covariance
