"""Ground facets of a scene in the world frame W, with their clutter materials.

The clutter field is anchored to the ground: the up-facing triangles (normal
within :data:`MAX_TILT` of the upward vertical ``-z_W``) of every mesh whose
material has a backscatter model (:data:`raysim.echoes.ground.sigma0.CLUTTER_MATERIALS`).
The steeper facets of those meshes (walls, facades, embankments) are kept
apart as *walls*: they return diffuse clutter too, but the mirror, the ghosts
and the ground height (:meth:`GroundSurface.locate`, :meth:`GroundSurface.mean_plane`)
use the ground alone. A wall of a closed mesh faces the way its winding says
(outward); a steep facet of an open mesh is kept with both faces, and the
field keeps the one that faces the radar. Meshes of other materials (cars,
glass, poles) only occlude.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from raysim.echoes.ground.sigma0 import CLUTTER_MATERIALS
from raysim.echoes.po.mesh import TriangleMesh

__all__ = ["GroundSurface", "MAX_TILT", "scene_meshes", "target_meshes"]

#: Steepest facet still counted as ground [rad] (60 deg from the vertical).
MAX_TILT = math.radians(60.0)
#: Upward unit vector in W (NED).
UP_W = np.array([0.0, 0.0, -1.0])


@dataclass(frozen=True, eq=False)
class GroundSurface:
    """Ground triangles in W and the meshes that occlude them.

    Attributes
    ----------
    triangles : ndarray, shape ``[facet, corner, 3]``
        Ground triangles in W [m].
    normals : ndarray, shape ``[facet, 3]``
        Upward unit normals in W (``n . UP_W > 0``).
    material : ndarray of str, shape ``[facet]``
        Clutter material id of each facet.
    occluders : TriangleMesh or None
        Every triangle of the scene in W (ground included), for shadowing rays.
    wall_triangles : ndarray, shape ``[wall facet, corner, 3]``, optional
        Facets steeper than :data:`MAX_TILT` with a clutter material, in W [m].
    wall_normals : ndarray, shape ``[wall facet, 3]``, optional
        Their unit normals in W (the face that scatters).
    wall_material : ndarray of str, shape ``[wall facet]``, optional
        Their clutter material ids.
    """

    triangles: np.ndarray
    normals: np.ndarray
    material: np.ndarray
    occluders: TriangleMesh | None = None
    wall_triangles: np.ndarray | None = None
    wall_normals: np.ndarray | None = None
    wall_material: np.ndarray | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.triangles, dtype=float)
        if t.ndim != 3 or t.shape[1:] != (3, 3) or len(t) == 0:
            raise ValueError(f"triangles must have shape [facet >= 1, 3, 3], got {t.shape}")
        walls = [self.wall_triangles, self.wall_normals, self.wall_material]
        if any(w is None for w in walls):
            if any(w is not None for w in walls):
                raise ValueError("wall_triangles, wall_normals and wall_material go together: "
                                 "give all three or none")
            object.__setattr__(self, "wall_triangles", np.zeros((0, 3, 3)))
            object.__setattr__(self, "wall_normals", np.zeros((0, 3)))
            object.__setattr__(self, "wall_material", np.zeros(0, dtype="<U1"))
        w = np.asarray(self.wall_triangles, dtype=float)
        if (w.ndim != 3 or w.shape[1:] != (3, 3) or np.shape(self.wall_normals) != (len(w), 3)
                or np.shape(self.wall_material) != (len(w),)):
            raise ValueError(f"wall_triangles [facet, 3, 3], wall_normals [facet, 3] and "
                             f"wall_material [facet] must agree, got {w.shape}, "
                             f"{np.shape(self.wall_normals)}, {np.shape(self.wall_material)}")
        mats = {*np.asarray(self.material).tolist(), *np.asarray(self.wall_material).tolist()}
        bad = sorted(mats - set(CLUTTER_MATERIALS))
        if bad:
            raise ValueError(f"material ids {bad} have no backscatter model; expected "
                             f"{sorted(CLUTTER_MATERIALS)}")

    def clutter_facets(self, walls: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Facets that return diffuse clutter: the ground, then (``walls``) the walls.

        Returns
        -------
        triangles : ndarray, shape ``[facet, corner, 3]`` [m]
        normals : ndarray, shape ``[facet, 3]``
        material : ndarray of str, shape ``[facet]``
        """
        if not walls or len(self.wall_triangles) == 0:
            return self.triangles, self.normals, self.material
        return (np.concatenate([self.triangles, self.wall_triangles]),
                np.concatenate([self.normals, self.wall_normals]),
                np.concatenate([np.asarray(self.material), np.asarray(self.wall_material)]))

    @classmethod
    def from_meshes(cls, meshes: list[tuple[TriangleMesh, str]], *,
                    occluders: list[TriangleMesh] = ()) -> GroundSurface:
        """Ground and walls from ``(mesh in W, material id)`` pairs.

        Facets within :data:`MAX_TILT` of horizontal are ground, steeper ones
        walls (module notes); the facets of a closed mesh that face downwards
        and meshes whose material has no backscatter model only occlude.
        """
        tris, norms, mats, all_meshes = [], [], [], list(occluders)
        wt, wn, wm = [], [], []
        cos_tilt = math.cos(MAX_TILT)
        for mesh, material in meshes:
            all_meshes.append(mesh)
            if material not in CLUTTER_MATERIALS:
                continue
            n = mesh.normals
            up = n @ UP_W
            if _is_closed(mesh):                                   # outward faces only
                n = n * _outward_sign(mesh)
                up = n @ UP_W
                keep, steep = up >= cos_tilt, np.abs(up) < cos_tilt
                walls_t, walls_n = mesh.triangles[steep], n[steep]
            else:
                n = np.where(up[:, None] < 0, -n, n)                # ground faces the sky
                keep = np.abs(up) >= cos_tilt
                steep = ~keep
                walls_t = np.concatenate([mesh.triangles[steep]] * 2)
                walls_n = np.concatenate([n[steep], -n[steep]])    # both faces of a sheet
            tris.append(mesh.triangles[keep])
            norms.append(n[keep])
            mats.extend([material] * int(keep.sum()))
            wt.append(walls_t)
            wn.append(walls_n)
            wm.extend([material] * len(walls_t))
        if not mats:
            raise ValueError(f"no ground facet found: no mesh has one of the materials "
                             f"{sorted(CLUTTER_MATERIALS)} with facets within "
                             f"{math.degrees(MAX_TILT):.0f} deg of horizontal")
        occ = None
        if all_meshes:
            verts, faces, off = [], [], 0
            for m in all_meshes:
                verts.append(m.vertices)
                faces.append(m.faces + off)
                off += len(m.vertices)
            occ = TriangleMesh(np.concatenate(verts), np.concatenate(faces))
        return cls(np.concatenate(tris), np.concatenate(norms), np.array(mats), occ,
                   np.concatenate(wt).reshape(-1, 3, 3), np.concatenate(wn).reshape(-1, 3),
                   np.array(wm, dtype=np.asarray(mats).dtype if wm else "<U1"))

    @classmethod
    def from_scene(cls, scene) -> GroundSurface:
        """Ground of a loaded :class:`raysim.echoes.rt.scenes.RadarScene` (meshes read again).

        The geometry targets' meshes (cars, reflectors: traced by PO + SBR and
        absent from Sionna's copy of the scene) occlude too, so the ground behind
        a car lies in its shadow (:func:`target_meshes`).
        """
        return cls.from_meshes(scene_meshes(scene), occluders=target_meshes(scene))

    @property
    def areas(self) -> np.ndarray:
        """Facet areas, shape ``[facet]`` [m^2]."""
        t = self.triangles
        return 0.5 * np.linalg.norm(np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0]), axis=-1)

    def locate(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Ground facet vertically below or above each point, and the ground height there.

        Parameters
        ----------
        points : ndarray, shape ``[point, 3]``
            Points in W [m] (only north and east are used).

        Returns
        -------
        facet : ndarray of int, shape ``[point]``
            Facet index, ``-1`` where no ground facet covers the point.
        z : ndarray, shape ``[point]``
            Ground ``z_W`` there [m] (NaN where none); the highest facet wins.
        """
        p = np.atleast_2d(np.asarray(points, dtype=float))
        t = self.triangles
        a, b, c = t[:, 0, :2], t[:, 1, :2], t[:, 2, :2]
        facet = np.full(len(p), -1)
        z = np.full(len(p), np.nan)
        lo, hi = t[:, :, :2].min(axis=1), t[:, :, :2].max(axis=1)
        for i, q in enumerate(p[:, :2]):
            cand = np.nonzero(np.all((q >= lo - 1e-9) & (q <= hi + 1e-9), axis=1))[0]
            if cand.size == 0:
                continue
            v0, v1, v2 = b[cand] - a[cand], c[cand] - a[cand], q - a[cand]
            den = v0[:, 0] * v1[:, 1] - v0[:, 1] * v1[:, 0]
            ok = np.abs(den) > 1e-12
            den = np.where(ok, den, 1.0)
            u = (v2[:, 0] * v1[:, 1] - v2[:, 1] * v1[:, 0]) / den
            w = (v0[:, 0] * v2[:, 1] - v0[:, 1] * v2[:, 0]) / den
            inside = ok & (u >= -1e-9) & (w >= -1e-9) & (u + w <= 1 + 1e-9)
            if not inside.any():
                continue
            tri = t[cand[inside]]
            zz = tri[:, 0, 2] + u[inside] * (tri[:, 1, 2] - tri[:, 0, 2]) + w[inside] * (
                tri[:, 2, 2] - tri[:, 0, 2])
            j = int(np.argmin(zz))                                 # highest: smallest z_W
            facet[i], z[i] = int(cand[inside][j]), float(zz[j])
        return facet, z

    def mean_plane(self, point, radius: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Area-weighted mean plane of the ground within ``radius`` of ``point`` (horizontally).

        The plane through the area-weighted centroid with the area-weighted mean
        facet normal: independent of how a surface is triangulated, up to the
        facets cut by the circle.

        Parameters
        ----------
        point : array_like, shape ``[3]``
            Point in W [m].
        radius : float
            Horizontal radius [m], > 0.

        Returns
        -------
        (origin, normal) : ndarray, shape ``[3]`` each, or None when no ground is there.
        """
        if not radius > 0:
            raise ValueError(f"radius must be > 0 m, got {radius!r}")
        q = np.asarray(point, dtype=float)
        centroid = self.triangles.mean(axis=1)
        near = np.linalg.norm(centroid[:, :2] - q[:2], axis=-1) <= radius
        if not near.any():
            f, _ = self.locate(q[None])
            if f[0] < 0:
                return None
            near = np.zeros(len(centroid), bool)
            near[f[0]] = True
        w = self.areas[near]
        origin = (centroid[near] * w[:, None]).sum(axis=0) / w.sum()
        n = (self.normals[near] * w[:, None]).sum(axis=0)
        return origin, n / np.linalg.norm(n)


def _is_closed(mesh: TriangleMesh) -> bool:
    """Whether every edge of ``mesh`` is shared by exactly two facets (a closed surface)."""
    f = np.asarray(mesh.faces)
    edges = np.sort(np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges, axis=0, return_counts=True)
    return bool(np.all(counts == 2))


def _outward_sign(mesh: TriangleMesh) -> float:
    """+1 when the winding of a closed mesh gives outward normals (positive volume), else -1."""
    t = mesh.triangles
    volume = np.sum(np.einsum("ij,ij->i", t[:, 0], np.cross(t[:, 1], t[:, 2]))) / 6.0
    return 1.0 if volume >= 0 else -1.0


def target_meshes(scene) -> list[TriangleMesh]:
    """Meshes in W of the geometry targets of a loaded scene that its XML does not hold.

    A bundled scene's XML lists its cars and reflectors too (the tracer removes
    them from Sionna's copy), so :func:`scene_meshes` already has them; targets
    added when loading (``extra_targets``, scenarios' geometry targets) are
    only here. One mesh per part.
    """
    in_xml = {f.resolve() for f in _xml_mesh_files(scene)}
    out = []
    for t in getattr(scene, "targets", None) or []:
        if not t.is_geometry:
            continue
        for f in [t.mesh] if isinstance(t.mesh, str) else list(t.mesh):
            if Path(f).resolve() in in_xml:
                continue
            m = TriangleMesh.load(f)
            out.append(TriangleMesh(scene.to_world(m.vertices), m.faces))
    return out


def _xml_mesh_files(scene) -> list[Path]:
    """Mesh files named by the scene XML's ``ply``/``obj`` shapes."""
    from raysim.echoes.rt.scenes import MESH_SHAPE_TYPES, _scene_xml, _substitute

    path = Path(scene.descriptor.path)
    root, defaults = _scene_xml(path)
    out = []
    for shape in root.iter("shape"):
        fname = next((s.get("value") for s in shape.iter("string")
                      if s.get("name") == "filename"), None)
        if shape.get("type") in MESH_SHAPE_TYPES and fname is not None:
            out.append(path.parent / _substitute(fname, defaults))
    return out


def scene_meshes(scene) -> list[tuple[TriangleMesh, str]]:
    """``(mesh in W, material id)`` of every ``ply``/``obj`` shape of a loaded scene."""
    from raysim.echoes.rt.scenes import MESH_SHAPE_TYPES, _scene_xml, _substitute

    path = Path(scene.descriptor.path)
    root, defaults = _scene_xml(path)
    out = []
    for shape in root.iter("shape"):
        if shape.get("type") not in MESH_SHAPE_TYPES:
            continue
        fname = next((s.get("value") for s in shape.iter("string")
                      if s.get("name") == "filename"), None)
        ref = next((r.get("id") for r in shape.iter("ref")), None)
        if fname is None:
            continue
        mesh = TriangleMesh.load(path.parent / _substitute(fname, defaults))
        out.append((TriangleMesh(scene.to_world(mesh.vertices), mesh.faces),
                    _substitute(ref or "", defaults)))
    return out
