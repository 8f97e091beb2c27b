"""Canonical radar targets as triangle meshes, and their closed-form RCS.

Every target is in the frame of ``raysim rcs``: its boresight (the aspect of the
closed form) is ``+z``, seen by a radar at ``range * (0, 0, 1)`` (azimuth 0,
elevation 0). Closed forms: Knott, Shaeffer & Tuley, *Radar Cross Section*, 2nd
ed. (1993), table 6.1.
"""

from __future__ import annotations

import math

import numpy as np

from raysim.echoes.po.mesh import TriangleMesh

__all__ = ["square_plate", "dihedral", "trihedral", "sphere", "canonical_target",
           "CANONICAL_SPECS", "plate_rcs", "dihedral_rcs", "trihedral_rcs", "sphere_rcs",
           "paraboloid", "paraboloid_double_bounce_rcs"]

#: Canonical target spellings accepted by :func:`canonical_target`.
CANONICAL_SPECS = ("plate:A", "dihedral:AxB", "trihedral:A", "sphere:R")


def _rect(corner, du, dv) -> tuple[np.ndarray, np.ndarray]:
    c = np.asarray(corner, dtype=float)
    v = np.array([c, c + du, c + du + dv, c + dv])
    return v, np.array([[0, 1, 2], [0, 2, 3]])


def square_plate(side: float) -> TriangleMesh:
    """Square plate of side ``side`` [m] in the plane ``z = 0``, centred, normal ``+z``."""
    _positive(side, "side")
    h = side / 2
    v, f = _rect([-h, -h, 0.0], [side, 0.0, 0.0], [0.0, side, 0.0])
    return TriangleMesh(v, f)


def dihedral(a: float, b: float) -> TriangleMesh:
    """Right dihedral: two ``a x b`` [m] plates meeting at 90 deg along the ``y`` axis.

    Faces of width ``a`` open towards ``+z`` at +-45 deg; the fold of length
    ``b`` is centred on the origin. Boresight ``+z`` gives the double bounce.
    """
    _positive(a, "a")
    _positive(b, "b")
    s = a / math.sqrt(2)
    v1, f1 = _rect([0.0, -b / 2, 0.0], [0.0, b, 0.0], [s, 0.0, s])
    v2, f2 = _rect([0.0, -b / 2, 0.0], [-s, 0.0, s], [0.0, b, 0.0])
    return TriangleMesh(np.vstack([v1, v2]), np.vstack([f1, f2 + 4]))


def trihedral(a: float) -> TriangleMesh:
    """Triangular trihedral of edge ``a`` [m], apex at the origin, symmetry axis ``+z``.

    Three right isosceles triangles (legs ``a``) in the coordinate planes,
    rotated so that their symmetry axis ``(1, 1, 1) / sqrt 3`` becomes ``+z``.
    """
    _positive(a, "a")
    o, x, y, z = np.zeros(3), np.array([a, 0, 0.0]), np.array([0, a, 0.0]), np.array([0, 0, a])
    v = np.array([o, x, y, o, y, z, o, z, x])
    f = np.arange(9).reshape(3, 3)
    axis = np.ones(3) / math.sqrt(3)
    e1 = np.array([1.0, -1.0, 0.0]) / math.sqrt(2)
    e2 = np.cross(axis, e1)
    rot = np.array([e1, e2, axis])          # rows: new x, y, z in old coordinates
    return TriangleMesh(v @ rot.T, f)


def sphere(radius: float, *, subdivisions: int = 4) -> TriangleMesh:
    """Icosphere of ``radius`` [m] at the origin (trimesh), ``20 * 4**subdivisions`` facets."""
    import trimesh

    _positive(radius, "radius")
    m = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    return TriangleMesh(np.asarray(m.vertices), np.asarray(m.faces))


def paraboloid(focal: float, a: float, b: float, facet: float) -> TriangleMesh:
    """Metal dish ``z = (x^2 + y^2) / (4 focal)`` [m] with an elliptic rim, open towards ``+z``.

    The rim is the ellipse of semi-axes ``a`` (along ``x``) and ``b`` (along
    ``y``) [m] seen along the axis; ``facet`` [m] is the target edge length
    (rings of points, Delaunay-triangulated in the aperture plane).
    """
    from scipy.spatial import Delaunay

    for value, name in ((focal, "focal"), (a, "a"), (b, "b"), (facet, "facet")):
        _positive(value, name)
    rings = max(2, math.ceil(max(a, b) / facet))
    pts = [np.zeros((1, 2))]
    for s in np.arange(1, rings + 1) / rings:
        m = max(6, math.ceil(2 * math.pi * s * max(a, b) / facet))
        phi = 2 * math.pi * np.arange(m) / m
        pts.append(np.stack([s * a * np.cos(phi), s * b * np.sin(phi)], axis=1))
    xy = np.concatenate(pts)
    faces = Delaunay(xy).simplices
    v = np.column_stack([xy, np.sum(xy**2, axis=1) / (4 * focal)])
    t = v[faces]
    up = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])[:, 2] > 0
    faces = np.where(up[:, None], faces, faces[:, ::-1])             # normals towards +z
    return TriangleMesh(v, faces)


def paraboloid_double_bounce_rcs(focal: float, a: float, b: float, wavelength: float,
                                 polarisation_deg: float = 0.0, samples: int = 20001) -> float:
    """Geometric-optics double bounce of :func:`paraboloid` on its axis [m^2].

    A ray parallel to the axis at ``(r, phi)`` reflects through the focus to
    ``(4 F^2 / r, phi + pi)`` and leaves parallel to the axis, after an unfolded
    path independent of ``r``; it takes two bounces when both points lie inside
    the rim ``rho(phi)``. The tube's cross-section is scaled by
    ``J = (r2 / r1)^2`` (and inverted through the focus), its field by
    ``1 / sqrt J``, so the exit aperture radiates ``sqrt J dA_1``. The two
    reflections in the meridian plane act as a dihedral whose fold is the
    azimuthal direction: the co-polar share is ``cos 2 (phi - psi)`` for the
    polarisation at ``psi`` from ``x``. Integrating ``r`` out,

    ``F = k / (2 pi) 4 F^2 int cos 2(phi - psi) max(0, ln(rho(phi) rho(phi + pi) / (4 F^2))) dphi``

    and ``sigma = 4 pi |F|^2``: zero for a round rim (the polarisation twist
    sends the return into a pattern with a null on the axis), non-zero for an
    elliptic one. Aperture radiation: Knott, Shaeffer & Tuley, *Radar Cross
    Section*, 2nd ed. (1993), ch. 6; ray-tube spreading: Deschamps, Proc. IEEE
    60(9), 1022-1035, 1972.
    """
    phi = np.linspace(0.0, 2 * math.pi, samples, endpoint=False)     # periodic: rectangle rule
    rho = 1.0 / np.sqrt((np.cos(phi) / a) ** 2 + (np.sin(phi) / b) ** 2)   # = rho(phi + pi)
    weight = np.cos(2 * (phi - math.radians(polarisation_deg)))
    log = np.maximum(0.0, 2 * np.log(rho / (2 * focal)))
    f = 4 * focal**2 * np.sum(weight * log) * (2 * math.pi / samples) / wavelength
    return 4 * math.pi * f**2


def plate_rcs(side: float, wavelength: float, angle: float = 0.0) -> float:
    """PO square plate, rotated by ``angle`` [rad] about a side's axis: ``4 pi A^2 / lambda^2
    cos^2(angle) sinc^2(k side sin angle)`` [m^2] (Knott table 6.1)."""
    k = 2 * math.pi / wavelength
    x = k * side * math.sin(angle)
    sinc = 1.0 if x == 0 else math.sin(x) / x
    return 4 * math.pi * side**4 / wavelength**2 * (math.cos(angle) * sinc) ** 2


def dihedral_rcs(a: float, b: float, wavelength: float) -> float:
    """Right dihedral at boresight: ``8 pi a^2 b^2 / lambda^2`` [m^2] (Knott table 6.1)."""
    return 8 * math.pi * a**2 * b**2 / wavelength**2


def trihedral_rcs(a: float, wavelength: float) -> float:
    """Triangular trihedral on its axis: ``4 pi a^4 / (3 lambda^2)`` [m^2] (Knott table 6.1)."""
    return 4 * math.pi * a**4 / (3 * wavelength**2)


def sphere_rcs(radius: float) -> float:
    """Optical-region sphere: ``pi r^2`` [m^2] (Knott table 6.1)."""
    return math.pi * radius**2


def canonical_target(spec: str) -> TriangleMesh:
    """Mesh of ``plate:A``, ``dihedral:AxB``, ``trihedral:A`` or ``sphere:R`` (sizes in m).

    Raises
    ------
    ValueError
        Unknown shape or unreadable sizes, naming the accepted spellings.
    """
    kind, _, size = str(spec).partition(":")
    try:
        nums = [float(s) for s in size.lower().split("x")] if size else []
    except ValueError:
        nums = []
    makers = {"plate": (square_plate, 1), "dihedral": (dihedral, 2),
              "trihedral": (trihedral, 1), "sphere": (sphere, 1)}
    if kind not in makers or len(nums) != makers[kind][1]:
        raise ValueError(f"target: got {spec!r}, expected one of {list(CANONICAL_SPECS)} "
                         "with sizes in metres, e.g. 'plate:0.1' or 'dihedral:0.1x0.05'")
    return makers[kind][0](*nums)


def _positive(value: float, name: str) -> None:
    if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
        raise ValueError(f"{name} must be a positive size in metres, got {value!r}")
