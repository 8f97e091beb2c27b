"""How the radar is mounted on the body: the rotation ``R_BA`` of the radar frame A.

The radar frame A (docs/conventions.md) has its origin at the radar phase
centre, at the lever arm ``r_IR`` in B, and its axes turned by the mounting
rotation ``R_BA`` (A vectors to B vectors), given as Z-Y-X Euler angles
``(yaw, pitch, roll)`` [deg] of the same sequence as the attitude. An element
at ``p`` in A is at ``r_IR + R_BA p`` in B; the boresight ``+z_A`` points along
``R_BA (0, 0, 1)`` in B. Named mountings (:data:`MOUNTING_PRESETS`):

===========  ====================  ===============================================
name         (yaw, pitch, roll)    the radar
===========  ====================  ===============================================
``down``     (0, 0, 0)             A parallel to B: looks down, azimuth (+x_A)
                                   forward, elevation (+y_A) right (the default)
``forward``  (90, 0, 90)           looks forward; azimuth right, elevation down
``oblique``  (90, 0, 45)           looks forward and 45 deg down; azimuth right
===========  ====================  ===============================================

Beams of a mounted radar are formed in the *nominal radar frame* N: the radar
frame at the body's nominal pose (B = W), ``u_W = R_BA u_N``; for ``down`` N is
W itself, as before. :func:`mount_motion` expresses an estimated platform motion
in N, so that the projection (with the element positions in A) and the
simulation (:func:`mount_array`: the positions turned into B axes) agree.

Every stage that places the radar (the point oracle, the ray tracer, the clutter
field, the re-projection of traced paths) takes the radar's pose from a
trajectory and a lever arm. :func:`mount_trajectory` gives them the pose of the
radar frame A itself: attitude ``R_WB R_BA`` and lever arm ``R_BA^T r_IR``, so
``T + R_WB R_BA (R_BA^T r_IR + p) = T + R_WB (r_IR + R_BA p)`` places every
element, and boresight and element pattern follow ``+z_A``, with no stage
knowing about the mounting. The IMU stays on the body's own trajectory.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.spatial.transform import Rotation

from raysim.platform.motion import Trajectory

__all__ = ["MOUNTING_PRESETS", "mounting_matrix", "mounting_deg", "is_default_mounting",
           "mount_array", "mount_motion", "mount_pattern", "nominal_target_position",
           "MountedTrajectory", "mount_trajectory", "nominal_direction"]

#: Named mountings: Z-Y-X Euler angles (yaw, pitch, roll) of ``R_BA`` [deg].
MOUNTING_PRESETS = {"down": (0.0, 0.0, 0.0), "forward": (90.0, 0.0, 90.0),
                    "oblique": (90.0, 0.0, 45.0)}


def mounting_deg(value, option: str = "--mounting-deg") -> tuple[float, float, float]:
    """``(yaw, pitch, roll)`` [deg] of a mounting: a preset name, ``"Y,P,R"`` text or 3 numbers.

    Raises
    ------
    ValueError
        Neither a preset name nor three finite angles (the message names ``option``).
    """
    if value is None:
        return MOUNTING_PRESETS["down"]
    if isinstance(value, str):
        key = value.strip().lower()
        if key in MOUNTING_PRESETS:
            return MOUNTING_PRESETS[key]
        value = value.split(",")
    try:
        v = tuple(float(x) for x in value)
    except (TypeError, ValueError):
        v = ()
    if len(v) != 3 or not all(np.isfinite(v)):
        raise ValueError(f"{option}: got {value!r}, expected YAW,PITCH,ROLL [deg] (three "
                         f"finite numbers) or one of {sorted(MOUNTING_PRESETS)}")
    return v


def mounting_matrix(value) -> np.ndarray:
    """``R_BA`` [3, 3] of a mounting (anything :func:`mounting_deg` takes)."""
    return Rotation.from_euler("ZYX", mounting_deg(value), degrees=True).as_matrix()


def is_default_mounting(value) -> bool:
    """Whether the mounting is ``down`` exactly (nothing to turn: results as before)."""
    return mounting_deg(value) == MOUNTING_PRESETS["down"]


def mount_array(array, value):
    """The array with its element positions turned into B axes, ``R_BA p`` [m].

    The simulation (:func:`raysim.platform.kinematics.element_world_positions`)
    then places element ``p`` at ``T + R_WB (r_IR + R_BA p)``. The default
    mounting returns ``array`` itself.
    """
    if is_default_mounting(value):
        return array
    m = mounting_matrix(value)
    return replace(array, tx_positions=array.tx_positions @ m.T,
                   rx_positions=array.rx_positions @ m.T,
                   name=f"{array.name}, mounted {mounting_deg(value)} deg")


def mount_pattern(pattern, value):
    """An element pattern (:class:`raysim.radar.pattern.ElementPattern`) seen in B axes.

    The oracle evaluates a pattern towards directions in the body's axes (the
    attitude of the trajectory); a mounted radar's element looks along
    ``u_A = R_BA^T u_B``, so the returned pattern's gain towards ``u_B`` is
    ``pattern``'s towards ``R_BA^T u_B``. The default mounting returns ``pattern`` itself.
    """
    if is_default_mounting(value):
        return pattern
    from raysim.radar.pattern import MountedPattern

    return MountedPattern(f"{pattern.name}, mounted {mounting_deg(value)} deg", pattern,
                          tuple(map(tuple, mounting_matrix(value))))


def mount_motion(motion, value):
    """A platform motion (``compensation.PlatformMotion``) expressed in the nominal radar frame N.

    With ``M = R_BA``: attitude ``M^T R_WB M``, position and velocity ``M^T x``,
    angular rate ``M^T omega`` and lever arm ``M^T r_IR``; the radar phase
    centre and every element ``T + R_WB (r_IR + M p)`` are then ``M^T`` times
    their world positions, so beams formed with the element positions in A
    look along directions of N (``u_W = M u_N``). The default mounting returns
    ``motion`` itself.
    """
    if is_default_mounting(value):
        return motion
    from compensation.mounting import radar_frame_motion

    return radar_frame_motion(motion, mounting_matrix(value))


def nominal_target_position(range_m: float, az: float, el: float, lever_arm,
                            value) -> np.ndarray:
    """World position [m] of a point at ``range_m`` [m] in direction ``(az, el)`` [rad] of N
    from the radar at the nominal pose: ``r_IR + R_BA u(az, el) range_m``."""
    from compensation.geometry import direction

    u = direction(az, el)
    return np.asarray(lever_arm, dtype=float) + mounting_matrix(value) @ u * float(range_m)


def nominal_direction(vector_w, value) -> np.ndarray:
    """A world vector (shape ``[..., 3]``) expressed in the nominal radar frame N:
    ``R_BA^T v``; the default mounting returns it unchanged (N is W)."""
    v = np.asarray(vector_w, dtype=float)
    return v if is_default_mounting(value) else v @ mounting_matrix(value)


@dataclass(frozen=True)
class MountedTrajectory(Trajectory):
    """The pose of a mounted radar frame A along a body trajectory.

    Position, velocity and acceleration are the body origin's (``body``'s);
    :meth:`attitude`, :meth:`pose`, :meth:`euler` and :meth:`angular_rate`
    are the radar frame's: ``R_WA = R_WB R_BA``, ``omega_A = R_BA^T omega_B``.
    :meth:`states` stays the body's axis values (what an IMU on the body
    senses). Built by :func:`mount_trajectory`.

    Parameters
    ----------
    components : tuple
        The body trajectory's components.
    name : str
    rotation : tuple of tuple of float
        ``R_BA``, 3 rows of 3.
    """

    rotation: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))

    @property
    def _m(self) -> np.ndarray:
        return np.asarray(self.rotation, dtype=float)

    def __add__(self, other: Trajectory) -> MountedTrajectory:
        body = Trajectory(self.components, self.name) + other
        return MountedTrajectory(body.components, body.name, self.rotation)

    def attitude(self, t) -> Rotation:
        """``R_WA = R_WB R_BA`` at each time, a Rotation of length ``time``."""
        return self.pose(t)[1]

    def pose(self, t) -> tuple[np.ndarray, Rotation]:
        """Body-origin position ``T`` [time, 3] (m, in W) and ``R_WA`` at times ``t``."""
        pos, rot = super().pose(t)          # the body's R_WB, from its own Euler angles
        return pos, rot * Rotation.from_matrix(self._m)

    def euler(self, t) -> np.ndarray:
        """Z-Y-X Euler angles of ``R_WA`` (yaw, pitch, roll), shape ``[time, 3]`` [rad]."""
        import warnings

        with warnings.catch_warnings():     # a forward radar at level flight is a gimbal lock
            warnings.simplefilter("ignore", UserWarning)
            return self.attitude(t).as_euler("ZYX")

    def angular_rate(self, t) -> np.ndarray:
        """Angular rate of A in A axes, ``R_BA^T omega_B``, shape ``[time, 3]`` [rad/s]."""
        return super().angular_rate(t) @ self._m


def mount_trajectory(trajectory, lever_arm, value):
    """The radar frame A's trajectory and lever arm for a body trajectory and a mounting.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
        Body motion.
    lever_arm : array_like, shape ``[3]``
        Radar phase centre ``r_IR`` in B [m].
    value
        Mounting (anything :func:`mounting_deg` takes).

    Returns
    -------
    (Trajectory, ndarray)
        :class:`MountedTrajectory` (attitude ``R_WB R_BA``) and ``R_BA^T r_IR``
        [m], shape ``[3]``: element ``p`` of A is at ``T + R_WB (r_IR + R_BA p)``
        when a stage places it as ``T + R_WA (lever + p)``. The default
        mounting returns ``trajectory`` and ``lever_arm`` themselves.
    """
    if is_default_mounting(value):
        return trajectory, lever_arm
    m = mounting_matrix(value)
    mounted = MountedTrajectory(trajectory.components,
                                f"{trajectory.name}, mounted {mounting_deg(value)} deg",
                                tuple(map(tuple, m)))
    return mounted, m.T @ np.asarray(lever_arm, dtype=float)
