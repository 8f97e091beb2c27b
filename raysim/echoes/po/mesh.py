"""Triangle meshes and radio materials for the physical-optics (PO) solver.

A :class:`TriangleMesh` holds vertices ``[vertex, xyz]`` [m] and faces
``[facet, 3]`` (vertex indices, counter-clockwise about the facet normal). A
:class:`PoMaterial` is either a perfect electric conductor (``permittivity is
None``) or a half-space of complex relative permittivity whose polarimetric
Fresnel coefficients (Balanis, *Advanced Engineering Electromagnetics*, 2nd ed.,
eqs. 5-24 and 5-33) weight each reflection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.echoes.rt.scenes import MATERIALS
from raysim.echoes.rt.user_meshes import MM_EXTENT_M
from raysim.io.mesh_files import declared_scale, read_mesh_file

__all__ = ["TriangleMesh", "PoMaterial", "po_material", "PO_MATERIAL_NAMES", "fresnel",
           "LARGE_TARGET_M"]

#: A mesh read as metres and larger than this is reported (a file in millimetres?) [m].
LARGE_TARGET_M = 20.0

#: Vacuum permittivity [F/m].
EPSILON_0 = 8.8541878128e-12


@dataclass(frozen=True)
class TriangleMesh:
    """A triangle mesh in the target frame.

    Attributes
    ----------
    vertices : ndarray, shape ``[vertex, 3]``
        Vertex positions [m].
    faces : ndarray of int, shape ``[facet, 3]``
        Vertex indices of each triangle.
    """

    vertices: np.ndarray
    faces: np.ndarray

    def __post_init__(self) -> None:
        v = np.asarray(self.vertices, dtype=float)
        f = np.asarray(self.faces, dtype=np.int64)
        if v.ndim != 2 or v.shape[1] != 3 or len(v) < 3:
            raise ValueError(f"vertices must have shape [vertex >= 3, 3], got {v.shape}")
        if f.ndim != 2 or f.shape[1] != 3 or len(f) < 1:
            raise ValueError(f"faces must have shape [facet >= 1, 3], got {f.shape}")
        if f.min() < 0 or f.max() >= len(v):
            raise ValueError(f"faces index vertices 0..{len(v) - 1}, got {f.min()}..{f.max()}")
        if not np.all(np.isfinite(v)):
            raise ValueError("vertices must be finite")
        cross = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        keep = np.linalg.norm(cross, axis=1) > 1e-12 * max(1.0, float(np.ptp(v)) ** 2)
        if not keep.any():
            raise ValueError("the mesh has no facet of non-zero area")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "faces", f[keep])

    @classmethod
    def load(cls, path, scale: float | None = None, notes: list | None = None
             ) -> TriangleMesh:
        """Read a mesh file (PLY, OBJ, STL, OFF, GLB/glTF, 3MF, COLLADA; trimesh).

        Parameters
        ----------
        path : path
            The file.
        scale : float, optional
            Metres per file unit (0.001 for millimetres); default the unit the
            file declares (3MF, COLLADA, glTF), else metres, checked as
            ``[[scene.meshes]]`` does: a bounding box over ``MM_EXTENT_M`` (500)
            units is refused as millimetres, one over :data:`LARGE_TARGET_M` is
            reported in ``notes``.
        notes : list, optional
            Receives the report of a large target.

        Returns
        -------
        TriangleMesh
            Vertices in metres.
        """
        import trimesh

        if scale is not None and not (math.isfinite(scale) and scale > 0):
            raise ValueError(f"--scale: got {scale!r}, expected a positive number of metres "
                             f"per file unit (0.001 for millimetres)")
        loaded = read_mesh_file(path)
        if scale is None:
            scale, unit = declared_scale(loaded, path)
            if scale is not None and scale != 1.0 and notes is not None:
                notes.append(f"mesh file {str(path)!r} declares its unit {unit!r}: read at "
                             f"{scale:g} m per unit")
        if isinstance(loaded, trimesh.Scene):
            loaded = loaded.to_mesh()       # every node's geometry at its place
        if not isinstance(loaded, trimesh.Trimesh) or len(loaded.faces) == 0:
            raise ValueError(f"mesh file {str(path)!r}: no triangles found")
        v = np.asarray(loaded.vertices, dtype=float)
        extent = float(np.max(np.ptp(v, axis=0)))
        if scale is None and extent > MM_EXTENT_M:
            raise ValueError(f"mesh file {str(path)!r}: bounding box {extent:g} units across "
                             f"looks like millimetres (over {MM_EXTENT_M:g} m); expected "
                             f"metres: give --scale 0.001 (metres per file unit) or the "
                             f"file's true unit")
        if scale is None and extent > LARGE_TARGET_M and notes is not None:
            notes.append(f"mesh file {str(path)!r} is {extent:g} m across, read as metres; "
                         f"if it is in millimetres give --scale 0.001")
        return cls(v * (1.0 if scale is None else float(scale)), np.asarray(loaded.faces))

    @property
    def triangles(self) -> np.ndarray:
        """Vertex positions per facet, shape ``[facet, corner, 3]`` [m]."""
        return self.vertices[self.faces]

    @property
    def normals(self) -> np.ndarray:
        """Unit facet normals (right-hand rule on the corner order), shape ``[facet, 3]``."""
        t = self.triangles
        c = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
        return c / np.linalg.norm(c, axis=1, keepdims=True)

    @property
    def areas(self) -> np.ndarray:
        """Facet areas, shape ``[facet]`` [m^2]."""
        t = self.triangles
        return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=1)

    @property
    def radius(self) -> float:
        """Largest distance of a vertex from the origin [m]."""
        return float(np.linalg.norm(self.vertices, axis=1).max())

    def max_edge(self) -> float:
        """Longest facet edge [m]."""
        t = self.triangles
        return float(np.linalg.norm(t - np.roll(t, -1, axis=1), axis=2).max())

    def subdivided(self, max_edge: float) -> TriangleMesh:
        """The same surface with every edge shorter than ``max_edge`` [m] (trimesh)."""
        import trimesh

        if not max_edge > 0:
            raise ValueError(f"max_edge must be > 0 m, got {max_edge!r}")
        if self.max_edge() <= max_edge:
            return self
        iters = int(math.ceil(math.log2(self.max_edge() / max_edge))) + 2
        v, f = trimesh.remesh.subdivide_to_size(self.vertices, self.faces, max_edge,
                                                max_iter=iters)
        return TriangleMesh(v, f)


@dataclass(frozen=True)
class PoMaterial:
    """Reflecting material of a whole mesh.

    Attributes
    ----------
    name : str
        Material name.
    permittivity : complex or None
        Complex relative permittivity ``eps_r' - j sigma / (omega eps_0)`` of a
        half-space; ``None`` for a perfect electric conductor (reflection -1 of
        the tangential electric field).
    """

    name: str
    permittivity: complex | None = None

    @property
    def is_pec(self) -> bool:
        """Whether the material is a perfect electric conductor."""
        return self.permittivity is None


#: Material names :func:`po_material` accepts (the scene materials of
#: :mod:`raysim.echoes.rt.scenes`, plus ``pec``).
PO_MATERIAL_NAMES = ("pec", *MATERIALS)


def po_material(name: str, frequency: float) -> PoMaterial:
    """The PO material of a scene material name at ``frequency`` [Hz].

    ``metal`` (ITU-R P.2040, ``sigma = 1e7 S/m``: ``|eps_r| ~ 2e6`` at 77 GHz,
    reflection within 0.01 dB of -1) and ``pec`` are perfect conductors;
    ``concrete`` and ``glass`` take Sionna's ITU-R P.2040 parameters at the
    frequency; ``dry-soil`` and ``asphalt-77ghz`` their custom parameters.
    Slab thickness and diffuse scattering are ignored (a specular half-space).

    Raises
    ------
    ValueError
        Unknown name, or an ITU material undefined at the frequency.
    """
    if name not in PO_MATERIAL_NAMES:
        from raysim.scenario.keys import did_you_mean

        raise ValueError(f"material: unknown name {name!r}; expected one of "
                         f"{sorted(PO_MATERIAL_NAMES)}{did_you_mean(name, PO_MATERIAL_NAMES)}")
    if name in ("pec", "metal"):
        return PoMaterial(name)
    spec = MATERIALS[name]
    if spec.itu_type is None:
        return PoMaterial(name, spec.complex_permittivity(frequency))
    from raysim.echoes.rt.backend import sionna_rt

    sionna_rt()
    import mitsuba as mi
    from sionna.rt.radio_materials.itu import itu_material

    eps_r, sigma = itu_material(spec.itu_type, mi.Float(frequency))
    eps = complex(float(eps_r[0]), -float(sigma[0]) / (2 * math.pi * frequency * EPSILON_0))
    return PoMaterial(name, eps)


def fresnel(material: PoMaterial, cos_i: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Fresnel reflection coefficients ``(Gamma_TE, Gamma_TM)`` at incidence cosines.

    ``Gamma_TE = (cos - sqrt(eps - sin^2)) / (cos + sqrt(eps - sin^2))``,
    ``Gamma_TM = (eps cos - sqrt(eps - sin^2)) / (eps cos + sqrt(eps - sin^2))``
    (Balanis, eqs. 5-24 and 5-33), for TM with the unit vector ``s x k`` on both
    the incident and the reflected wave; a PEC gives ``(-1, +1)``.

    Parameters
    ----------
    cos_i : ndarray, shape ``[ray]``
        Cosine of the incidence angle, in ``[0, 1]``.
    """
    cos_i = np.clip(np.asarray(cos_i, dtype=float), 0.0, 1.0)
    if material.is_pec:
        return -np.ones_like(cos_i, dtype=complex), np.ones_like(cos_i, dtype=complex)
    eps = material.permittivity
    root = np.sqrt(eps - (1.0 - cos_i**2) + 0j)
    return (cos_i - root) / (cos_i + root), (eps * cos_i - root) / (eps * cos_i + root)
