"""Directions, angle grids and small rotation helpers (frames of docs/conventions.md).

Azimuth ``az`` is measured from boresight (+Z) towards +X, elevation ``el``
towards +Y: ``u = (cos el sin az, sin el, cos el cos az)``. At the nominal
hover attitude the radar frame A is parallel to the world frame W, so the
same formula gives world ("global") directions.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation


def direction(az, el) -> np.ndarray:
    """Unit vector(s) ``u = (cos el sin az, sin el, cos el cos az)``.

    Parameters
    ----------
    az, el : float or ndarray (broadcastable)
        Azimuth and elevation [rad].

    Returns
    -------
    ndarray, shape ``[..., 3]``
    """
    az, el = np.asarray(az, dtype=float), np.asarray(el, dtype=float)
    return np.stack([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)], axis=-1)


def direction_tangents(az, el) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives ``du/daz`` and ``du/del`` of :func:`direction`, each ``[..., 3]`` [1/rad]:
    ``(cos el cos az, 0, -cos el sin az)`` and ``(-sin el sin az, cos el, -sin el cos az)``.

    Parameters
    ----------
    az, el : float or ndarray (broadcastable)
        Azimuth and elevation [rad].
    """
    az, el = np.broadcast_arrays(np.asarray(az, dtype=float), np.asarray(el, dtype=float))
    d_az = np.stack([np.cos(el) * np.cos(az), np.zeros_like(az), -np.cos(el) * np.sin(az)], -1)
    d_el = np.stack([-np.sin(el) * np.sin(az), np.cos(el), -np.sin(el) * np.cos(az)], -1)
    return d_az, d_el


def az_el(u) -> tuple[np.ndarray, np.ndarray]:
    """Azimuth and elevation [rad] of unit vectors ``u`` of shape ``[..., 3]``."""
    u = np.asarray(u, dtype=float)
    return np.arctan2(u[..., 0], u[..., 2]), np.arcsin(np.clip(u[..., 1], -1.0, 1.0))


def grid_directions(azimuth, elevation) -> np.ndarray:
    """Directions of an azimuth x elevation grid, shape ``[azimuth, elevation, 3]``."""
    aa, ee = np.meshgrid(np.asarray(azimuth, dtype=float), np.asarray(elevation, dtype=float),
                         indexing="ij")
    return direction(aa, ee)


def euler_zyx(attitude) -> np.ndarray:
    """Euler angles ``(yaw, pitch, roll)`` [rad] of ``R_WB`` matrices ``[chirp, 3, 3]``.

    Returns
    -------
    ndarray, shape ``[chirp, 3]``
    """
    return Rotation.from_matrix(np.asarray(attitude)).as_euler("ZYX")


def yaw_matrices(yaw) -> np.ndarray:
    """``Rz(yaw)`` matrices, shape ``[chirp, 3, 3]``, for yaw angles ``[chirp]`` [rad]."""
    yaw = np.atleast_1d(np.asarray(yaw, dtype=float))
    c, s = np.cos(yaw), np.sin(yaw)
    m = np.zeros(yaw.shape + (3, 3))
    m[..., 0, 0] = c
    m[..., 0, 1] = -s
    m[..., 1, 0] = s
    m[..., 1, 1] = c
    m[..., 2, 2] = 1.0
    return m
