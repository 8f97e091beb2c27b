"""A mounted radar: its beams formed in the nominal radar frame, its directions in W.

The radar frame A is turned from the body frame B by the mounting rotation
``R_BA`` (A vectors to B vectors; docs/conventions.md); the IMU, the motion
(:class:`compensation.PlatformMotion`) and the Doppler model live in B and W.
Beams of the array (element positions in A) are formed in the nominal radar
frame N, the radar frame at the body's nominal pose (``u_W = R_BA u_N``), with
the motion expressed in N (:func:`radar_frame_motion`); a direction measured
there is turned back into W (:func:`world_directions`) before the Doppler model,
whose radar velocity and lever arm are the body's. A down-looking radar
(``R_BA = I``) leaves everything as it is.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .strapdown import PlatformMotion

__all__ = ["MOUNTING_ORTHONORMAL_TOL", "mounting_rotation", "radar_frame_motion",
           "world_directions"]

#: Largest deviation of ``R_BA^T R_BA`` from the identity (and of its determinant
#: from 1) accepted for a mounting rotation [1].
MOUNTING_ORTHONORMAL_TOL = 1e-6


def mounting_rotation(value) -> np.ndarray | None:
    """``R_BA`` [3, 3] checked, or None for no mounting (or the identity: down-looking).

    Raises
    ------
    ValueError
        Not a 3 x 3 proper rotation matrix of finite numbers.
    """
    if value is None:
        return None
    m = np.asarray(value, dtype=float)
    if (m.shape != (3, 3) or not np.all(np.isfinite(m))
            or np.max(np.abs(m.T @ m - np.eye(3))) > MOUNTING_ORTHONORMAL_TOL
            or abs(np.linalg.det(m) - 1.0) > MOUNTING_ORTHONORMAL_TOL):
        raise ValueError(f"mounting: got {value!r}, expected the rotation R_BA as a 3 x 3 "
                         f"orthonormal matrix of determinant +1")
    return None if np.array_equal(m, np.eye(3)) else m


def radar_frame_motion(motion: PlatformMotion, mounting) -> PlatformMotion:
    """The motion expressed in the nominal radar frame N of the mounting ``R_BA = M``.

    Attitude ``M^T R_WB M``, position and velocity ``M^T x``, angular rate
    ``M^T omega`` and lever arm ``M^T r_IR``: every element ``T + R_WB (r_IR + M p)``
    is then ``M^T`` times its world position, so beams formed with the element
    positions ``p`` in A look along directions of N (the transform of
    ``raysim.platform.mounting.mount_motion``). ``mounting`` None returns ``motion``.
    """
    m = mounting_rotation(mounting)
    if m is None:
        return motion
    return replace(motion, attitude=m.T @ motion.attitude @ m, position=motion.position @ m,
                   velocity=motion.velocity @ m, angular_rate=motion.angular_rate @ m,
                   lever_arm=m.T @ motion.lever_arm)


def world_directions(u_n, mounting, covariance=None):
    """Directions (or points from the radar) ``[..., 3]`` of N turned into W, ``R_BA u_N``;
    with ``covariance`` ``[..., 3, 3]`` also it, ``R_BA C R_BA^T``. ``mounting`` None
    returns them unchanged."""
    m = mounting_rotation(mounting)
    u = np.asarray(u_n, dtype=float)
    if m is not None:
        u = u @ m.T
        if covariance is not None:
            covariance = m @ np.asarray(covariance, dtype=float) @ m.T
    return u if covariance is None else (u, covariance)
