"""Cars that drive through a scene: PO + SBR scattering centres of a car mesh on a trajectory.

A :class:`CarMover` is a car mesh (:func:`raysim.echoes.po.car.car_parts`) on a
:class:`raysim.echoes.moving.scatterers.RigidTrajectory`. At every trace it places
the mesh at its pose, traces it by PO + SBR from the radar
(:func:`raysim.echoes.po.paths.scattering_terms`), groups the terms into
scattering centres (:func:`raysim.echoes.po.paths.cluster_terms`) and fixes them
in the car's body frame as a :class:`raysim.echoes.moving.scatterers.MovingObject`:
within a frame the centres ride on the car (Doppler and range walk of a rigid
body); from trace to trace the aspect changes and they are traced again.

Ground: given a :class:`raysim.echoes.ground.surface.GroundSurface`, the car is
traced with its local ground apron (:func:`raysim.echoes.po.paths.ground_apron`,
as the scene's static geometry targets are), so its car-ground multipath
appears: car-ground-radar and ground-car-radar terms (between the car and its
image) and ground-car-ground terms (at the car's image below the ground), with
the ground's Fresnel and Ament factors. These ghost centres are fixed in the
body frame like the direct ones (at or below the ground contact, ``z >= 0``:
car-ground dihedrals at the contact line, images below it). Over a flat ground
this is exact within a frame: the mirror ``M`` across a horizontal plane
commutes with the trajectory's horizontal translation and its yaw (``M v = v``),
so the image of a body point rides on the body, straight or turning. On sloped
ground the apron is the mean plane under the car at the trace instant; within a
frame the image of a point moving at ``v`` would move at ``M v``, which differs
from ``v`` by ``-2 (v . n) n`` (``n`` the plane's normal), so a ghost's range
rate is off by up to ``2 |v . n|`` and the ground under a moving car is only
refitted at the next trace (the car mesh also stays level, as the trajectory is
planar).

Frames: the car mesh is built x forward, y left, z up; the body frame of
:class:`MovingObject` is x forward, y right, z down (FRD), so body =
``(x, -y, -z)``; the body's yaw is the trajectory heading about ``+z_W``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.echoes.moving.scatterers import MovingObject, RigidTrajectory, Tracks
from raysim.radar.config import RadarConfig

__all__ = ["CarMover", "MESH_TO_BODY", "GHOST_LABEL", "GHOST_SHARE"]

#: Car mesh frame (x forward, y left, z up) to the FRD body frame.
MESH_TO_BODY = np.diag([1.0, -1.0, -1.0])
#: ``Tracks.label`` of a centre that returns by the ground (the others are ``"mover"``).
GHOST_LABEL = "mover-ghost"
#: A centre is a ghost when more than this share of its terms' summed magnitude
#: has a hit on the ground apron.
GHOST_SHARE = 0.5
#: Distance of a hit from the apron plane that counts as on the apron [m].
ON_APRON_M = 1e-6


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
    parts : tuple of (TriangleMesh, str), optional
        Meshes and scene materials that replace the car body, in the mesh frame
        (x forward, y left, z up [m], origin on the trajectory), e.g. a
        reflector on a trolley; empty (default) drives the car of ``length``,
        ``width`` and ``height``.
    """

    name: str
    trajectory: RigidTrajectory
    length: float = 4.5
    width: float = 1.8
    height: float = 1.45
    seed: int = 0
    parts: tuple = ()

    def __post_init__(self) -> None:
        if not isinstance(self.trajectory, RigidTrajectory):
            raise ValueError(f"trajectory must be a RigidTrajectory, got {type(self.trajectory)}")
        from raysim.echoes.po.car import car_parts
        from raysim.echoes.po.mesh import TriangleMesh

        car_parts(self.length, self.width, self.height)            # checks the sizes
        object.__setattr__(self, "parts", tuple(self.parts))
        for p in self.parts:
            if not (isinstance(p, tuple) and len(p) == 2 and isinstance(p[0], TriangleMesh)
                    and isinstance(p[1], str)):
                raise ValueError(f"parts must be (TriangleMesh, material name) pairs, got {p!r}")

    def meshes_w(self, time: float) -> tuple[list, list]:
        """The car's parts in W at ``time`` [s]: ``(meshes, materials)``."""
        from raysim.echoes.po.car import car_parts
        from raysim.echoes.po.mesh import TriangleMesh

        c, psi = self.trajectory.pose(np.array(time))
        rot = _yaw(float(psi)) @ MESH_TO_BODY
        parts = (self.parts if self.parts else
                 [(m, mat) for _, m, mat in car_parts(self.length, self.width, self.height)])
        return ([TriangleMesh(np.asarray(c) + m.vertices @ rot.T, m.faces) for m, _ in parts],
                [mat for _, mat in parts])

    def moving_object(self, config: RadarConfig, radar_w, r_wb=None, *,
                      time: float = 0.0, ground=None) -> MovingObject:
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
        ground : GroundSurface, optional
            Ground under the car: traced with its local apron (car-ground
            multipath, see the module docstring); ``None`` traces the car alone
            (as does a car off the ground surface or a radar below its plane).

        Returns
        -------
        MovingObject
            ``rcs_dbsm = 10 log10(4 pi |a|^2)`` and ``phase = arg a`` of each
            centre's PO amplitude ``a`` (normalised to the centre's range).
        """
        return self._trace(config, radar_w, r_wb, time, ground)[0]

    def _trace(self, config: RadarConfig, radar_w, r_wb, time: float,
               ground) -> tuple[MovingObject, np.ndarray]:
        """:meth:`moving_object` and which centres are ghosts, ``bool [centre]``."""
        from raysim.echoes.ground.surface import GroundSurface
        from raysim.echoes.po.paths import cluster_terms, ground_apron, scattering_terms

        if ground is not None and not isinstance(ground, GroundSurface):
            raise ValueError(f"ground must be a GroundSurface or None, got {type(ground)}")
        radar = np.asarray(radar_w, dtype=float)
        pol = np.array([1.0, 0.0, 0.0]) if r_wb is None else np.asarray(r_wb, float)[:, 0]
        meshes, materials = self.meshes_w(time)
        c, psi = self.trajectory.pose(np.array(time))
        c = np.asarray(c, float)
        apron = None
        if ground is not None:
            # the apron covers the shadow of a sphere about the ground point under the
            # body origin (a body above the ground raises its top, hence the shadow)
            _, zg = ground.locate(c[None])
            foot = np.array([c[0], c[1], zg[0] if np.isfinite(zg[0]) else c[2]])
            radius = max(float(np.max(np.linalg.norm(m.vertices - foot, axis=1)))
                         for m in meshes)
            apron = ground_apron(ground, c, radar, radius, config.wavelength)
        terms = scattering_terms(meshes, materials, radar, c,
                                 frequency=config.carrier_frequency, polarisation_w=pol,
                                 ground=apron)
        centre, amp, label = cluster_terms(terms, config.range_resolution)
        # the cluster amplitude is normalised to the reference range R; MovingObject
        # spreads each centre over its own range r_c (radar equation, 1 / r_c^2), so
        # refer it to r_c: a_c = a (r_c / R)^2 (a ground-car-ground ghost lies at the
        # image range, several metres beyond R). sigma = 4 pi |a_c|^2 (Knott, RCS, eq. 5.1)
        amp = amp * (np.linalg.norm(centre - radar, axis=1) / terms.range_m) ** 2
        keep = np.abs(amp) > 0
        if not keep.any():
            raise ValueError(f"car {self.name!r} returns nothing towards the radar at "
                             f"{radar.tolist()}")
        ghost = np.zeros(len(amp), bool)
        if apron is not None:
            v = apron[0].vertices
            n = np.cross(v[1] - v[0], v[2] - v[0])
            n /= np.linalg.norm(n)
            on = ((np.abs((terms.first - v[0]) @ n) < ON_APRON_M)
                  | (np.abs((terms.last - v[0]) @ n) < ON_APRON_M))
            mag = np.abs(terms.amplitude)
            share = (np.bincount(label, mag * on, len(amp))
                     / np.maximum(np.bincount(label, mag, len(amp)), 1e-300))
            ghost = share > GHOST_SHARE
        body = (centre[keep] - c) @ _yaw(float(psi))                 # W -> body (row vectors)
        rcs = 10 * np.log10(4 * math.pi * np.abs(amp[keep]) ** 2)
        return (MovingObject(self.name, body, rcs, self.trajectory, seed=self.seed,
                             phase=np.angle(amp[keep])), ghost[keep])

    def tracks(self, config: RadarConfig, radar_w, *, time: float = 0.0, r_wb=None,
               ground=None) -> Tracks:
        """Paths of the centres traced at ``time`` (:meth:`MovingObject.tracks`).

        With ``ground`` (a GroundSurface, see :meth:`moving_object`) the centres
        that return by the ground are labelled :data:`GHOST_LABEL`.
        """
        obj, ghost = self._trace(config, radar_w, r_wb, time, ground)
        tracks = obj.tracks(config, radar_w, time=time)
        return Tracks(tracks.p_tx, tracks.p_rx, tracks.amplitude,
                      np.where(ghost, GHOST_LABEL, tracks.label))
