"""Cars that drive through a scene: PO + SBR scattering centres of a car mesh on a trajectory.

A :class:`CarMover` is a car mesh (:func:`raysim.echoes.po.car.car_parts`) on a
:class:`raysim.echoes.clutter.tracks.RigidTrajectory`. At every trace it places
the mesh at its pose, traces it by PO + SBR from the radar
(:func:`raysim.echoes.po.paths.scattering_terms`), groups the terms into
scattering centres (:func:`raysim.echoes.po.paths.cluster_terms`) and fixes them
in the car's body frame as a :class:`raysim.echoes.clutter.tracks.MovingObject`:
within a frame the centres ride on the car (Doppler and range walk of a rigid
body); from trace to trace the aspect changes and they are traced again.

Frames: the car mesh is built x forward, y left, z up; the body frame of
:class:`MovingObject` is x forward, y right, z down (FRD), so body =
``(x, -y, -z)``; the body's yaw is the trajectory heading about ``+z_W``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.echoes.clutter.tracks import MovingObject, RigidTrajectory, Tracks
from raysim.radar.config import RadarConfig

__all__ = ["CarMover", "MESH_TO_BODY"]

#: Car mesh frame (x forward, y left, z up) to the FRD body frame.
MESH_TO_BODY = np.diag([1.0, -1.0, -1.0])


def _yaw(psi: float) -> np.ndarray:
    c, s = math.cos(psi), math.sin(psi)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class CarMover:
    """A car mesh driving along a rigid trajectory; traced by PO + SBR at each trace.

    Attributes
    ----------
    name : str
    trajectory : RigidTrajectory
        Body origin on the ground (the mesh's wheels touch ``z = 0`` of the body),
        heading, speed [m/s] and yaw rate.
    length, width, height : float
        Car size [m] (:func:`raysim.echoes.po.car.car_parts` ranges).
    seed : int
        Kept for :class:`MovingObject` (the PO centres carry their own phases).
    """

    name: str
    trajectory: RigidTrajectory
    length: float = 4.5
    width: float = 1.8
    height: float = 1.45
    seed: int = 0

    def __post_init__(self) -> None:
        if not isinstance(self.trajectory, RigidTrajectory):
            raise ValueError(f"trajectory must be a RigidTrajectory, got {type(self.trajectory)}")
        from raysim.echoes.po.car import car_parts

        car_parts(self.length, self.width, self.height)            # checks the sizes

    def meshes_w(self, time: float) -> tuple[list, list]:
        """The car's parts in W at ``time`` [s]: ``(meshes, materials)``."""
        from raysim.echoes.po.car import car_parts
        from raysim.echoes.po.mesh import TriangleMesh

        c, psi = self.trajectory.pose(np.array(time))
        rot = _yaw(float(psi)) @ MESH_TO_BODY
        parts = car_parts(self.length, self.width, self.height)
        return ([TriangleMesh(np.asarray(c) + m.vertices @ rot.T, m.faces) for _, m, _ in parts],
                [mat for _, _, mat in parts])

    def moving_object(self, config: RadarConfig, radar_w, r_wb=None, *,
                      time: float = 0.0) -> MovingObject:
        """Scattering centres seen from ``radar_w`` at ``time``, fixed in the body frame.

        Parameters
        ----------
        config : RadarConfig
            Carrier frequency and range resolution (the centres' cell).
        radar_w : array_like, shape ``[3]``
            Radar phase centre in W [m].
        r_wb : array_like, shape ``[3, 3]``, optional
            Radar attitude; its first column is the transmit polarisation
            (default north).
        time : float
            Trace instant [s].

        Returns
        -------
        MovingObject
            ``rcs_dbsm = 10 log10(4 pi |a|^2)`` and ``phase = arg a`` of each
            centre's PO amplitude ``a`` (normalised to the centre's range).
        """
        from raysim.echoes.po.paths import cluster_terms, scattering_terms

        radar = np.asarray(radar_w, dtype=float)
        pol = np.array([1.0, 0.0, 0.0]) if r_wb is None else np.asarray(r_wb, float)[:, 0]
        meshes, materials = self.meshes_w(time)
        c, psi = self.trajectory.pose(np.array(time))
        terms = scattering_terms(meshes, materials, radar, np.asarray(c, float),
                                 frequency=config.carrier_frequency, polarisation_w=pol)
        centre, amp, _ = cluster_terms(terms, config.range_resolution)
        # the cluster amplitude is normalised to the reference range; per centre, sigma
        # follows from the monostatic PO field, sigma = 4 pi |a|^2 (Knott, RCS, eq. 5.1)
        keep = np.abs(amp) > 0
        if not keep.any():
            raise ValueError(f"car {self.name!r} returns nothing towards the radar at "
                             f"{radar.tolist()}")
        body = (centre[keep] - np.asarray(c)) @ _yaw(float(psi))   # W -> body (row vectors)
        rcs = 10 * np.log10(4 * math.pi * np.abs(amp[keep]) ** 2)
        return MovingObject(self.name, body, rcs, self.trajectory, seed=self.seed,
                            phase=np.angle(amp[keep]))

    def tracks(self, config: RadarConfig, radar_w, *, time: float = 0.0, r_wb=None) -> Tracks:
        """Direct paths of the centres traced at ``time`` (:meth:`MovingObject.tracks`)."""
        return self.moving_object(config, radar_w, r_wb, time=time).tracks(config, radar_w,
                                                                          time=time)
