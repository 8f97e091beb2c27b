"""One frame's ground points with the attitude that turned them into W.

The ground points of a frame (:func:`compensation.ground_plane.dense_points`) are
directions measured in the array turned into W by one integration's attitude at one
instant (the snapshot); kept with that attitude, they can be turned by another
integration of the same record without being found again
(:mod:`compensation.ground_refit`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["GroundLook"]


@dataclass(frozen=True)
class GroundLook:
    """One frame's ground points and the pose of the integration that turned them into W.

    Attributes
    ----------
    frame : int
        Frame of the record.
    pose : int
        Pose (slot) of the frame's motion at the snapshot.
    attitude : ndarray, shape ``[3, 3]``
        ``R_WB`` of that pose: the points are ``attitude`` times directions in B.
    points : ndarray, shape ``[point, 3]``
        Points in W as ``attitude`` has it [m].
    covariance : ndarray, shape ``[point, 3, 3]``
        Their covariances [m^2].
    """

    frame: int
    pose: int
    attitude: np.ndarray
    points: np.ndarray
    covariance: np.ndarray

    def turned(self, attitude) -> tuple[np.ndarray, np.ndarray]:
        """Points ``[point, 3]`` and covariances ``[point, 3, 3]`` with ``attitude``
        ``[3, 3]`` in place of :attr:`attitude` (``R' R^T p``, ``R' R^T C R R'^T``)."""
        turn = np.asarray(attitude, dtype=float) @ self.attitude.T
        return self.points @ turn.T, turn @ self.covariance @ turn.T
