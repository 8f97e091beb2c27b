r"""Coherent specular return of a rough ground, independent of the triangulation.

The monostatic mirror return comes from the mean ground plane below the radar
(:meth:`raysim.echoes.ground.surface.GroundSurface.mean_plane`, area-weighted
over :data:`FIT_RADIUS`: the sum of area-weighted facet normals of a surface
patch depends only on its boundary, not on how it is cut into triangles). By
the image method its received power is

.. math::

    P = \frac{P_t G^2 \lambda^2 |\Gamma(0)|^2 \chi^2}{(4\pi)^2 (2d)^2},
    \qquad \chi = e^{-2 (k s)^2}

with ``d`` the radar's distance to the plane, ``Gamma(0)`` the normal-incidence
Fresnel coefficient and ``chi`` the Ament factor of the rms height ``s``
(Beckmann & Spizzichino 1963, eq. 5.29; Ulaby, Moore & Fung Vol. II, eq. 12.57).
The power ``1 - chi^2`` removed from the mirror is the quasi-specular part of
``sigma0`` carried by the clutter field.
"""

from __future__ import annotations

import math

import numpy as np

from raysim.echoes.ground.sigma0 import ament_factor, fresnel_coefficient
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.rt.trace import SPECULAR, PathSet
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

__all__ = ["FIT_RADIUS", "rough_specular_path", "mirror"]

#: Horizontal radius of the mean-plane fit below the radar [m].
FIT_RADIUS = 2.0


def mirror(points: np.ndarray, origin: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Mirror images of ``points`` ``[..., 3]`` across the plane ``(origin, unit normal)``."""
    p = np.asarray(points, dtype=float)
    return p - 2.0 * np.sum((p - origin) * normal, axis=-1, keepdims=True) * normal


def rough_specular_path(ground: GroundSurface, config: RadarConfig, radar_w, r_wb, *,
                        time: float = 0.0, polarisation: str = "VV",
                        fov_half_angle: float = math.radians(70.0),
                        fit_radius: float = FIT_RADIUS) -> PathSet:
    """The single-bounce coherent ground mirror seen from ``radar_w`` (0 or 1 path).

    Parameters
    ----------
    ground : GroundSurface
    config : RadarConfig
        Power, gain, wavelength and range window.
    radar_w : array_like, shape ``[3]``
        Radar phase centre in W [m].
    r_wb : array_like, shape ``[3, 3]``
        Attitude (boresight is the third column).
    time : float
        Trace instant [s].
    polarisation : {"VV", "HH", "HV"}
        Channel of the Fresnel coefficient (``"HV"``: 0, a plane does not depolarise).
    fov_half_angle : float
        Field of view around boresight [rad].
    fit_radius : float
        Radius of the mean-plane fit [m].

    Returns
    -------
    PathSet
        One path of kind SPECULAR at the foot of the perpendicular from the
        radar to the mean plane (re-projected by the image method), or none
        when there is no ground below, the foot lies off the ground, outside the
        field of view or beyond the range window.
    """
    from raysim.echoes.ground.field import radar_scale

    x0 = np.asarray(radar_w, dtype=float)
    empty = _paths(np.zeros((0, 3)), np.zeros(0), np.zeros(0, complex), x0, time)
    _, z = ground.locate(x0[None])
    if not np.isfinite(z[0]):
        return empty
    plane = ground.mean_plane(np.array([x0[0], x0[1], z[0]]), fit_radius)
    if plane is None:
        return empty
    o, n = plane
    d = float((x0 - o) @ n)
    if d <= 0:
        return empty
    foot = x0 - d * n
    facet, _ = ground.locate(foot[None])
    bore = np.asarray(r_wb, dtype=float)[:, 2]
    if facet[0] < 0 or -n @ bore < math.cos(fov_half_angle) or not d < config.max_range:
        return empty
    mat = str(ground.material[facet[0]])
    gamma = complex(fresnel_coefficient(mat, 1.0, polarisation))
    chi = float(ament_factor(mat, 0.0, config.wavelength))
    # image method: |a|^2 = P_t G^2 lambda^2 |Gamma chi|^2 / ((4 pi)^2 (2d)^2)
    amp = math.sqrt(radar_scale(config) * 4 * math.pi) / (2 * d) * gamma * chi
    return _paths(foot[None], np.array([2 * d]), np.array([amp]), x0, time)


def _paths(v, length, amp, x0, time) -> PathSet:
    n = len(length)
    pol = np.zeros((n, 2, 2), complex)
    pol[:, 0, 0] = amp
    return PathSet(v, v.copy(), length, amp, np.zeros((n, 3)), np.zeros(n),
                   np.full((n, 1), SPECULAR, np.uint32), np.full(n, SPECULAR, np.uint32), pol,
                   length / SPEED_OF_LIGHT, x0.copy(), x0.copy(), float(time), {})
