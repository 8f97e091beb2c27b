"""Ground facets of a scene in the world frame W, with their clutter materials.

The clutter field is anchored to the ground: the up-facing triangles (normal
within :data:`MAX_TILT` of the upward vertical ``-z_W``) of every mesh whose
material has a backscatter model (:data:`raysim.echoes.ground.sigma0.CLUTTER_MATERIALS`).
Other meshes (cars, facades, poles) only occlude.
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
    """

    triangles: np.ndarray
    normals: np.ndarray
    material: np.ndarray
    occluders: TriangleMesh | None = None

    def __post_init__(self) -> None:
        t = np.asarray(self.triangles, dtype=float)
        if t.ndim != 3 or t.shape[1:] != (3, 3) or len(t) == 0:
            raise ValueError(f"triangles must have shape [facet >= 1, 3, 3], got {t.shape}")
        bad = sorted(set(np.asarray(self.material).tolist()) - set(CLUTTER_MATERIALS))
        if bad:
            raise ValueError(f"material ids {bad} have no backscatter model; expected "
                             f"{sorted(CLUTTER_MATERIALS)}")

    @classmethod
    def from_meshes(cls, meshes: list[tuple[TriangleMesh, str]], *,
                    occluders: list[TriangleMesh] = ()) -> GroundSurface:
        """Ground from ``(mesh in W, material id)`` pairs.

        Facets steeper than :data:`MAX_TILT` and meshes whose material has no
        backscatter model only occlude.
        """
        tris, norms, mats, all_meshes = [], [], [], list(occluders)
        for mesh, material in meshes:
            all_meshes.append(mesh)
            if material not in CLUTTER_MATERIALS:
                continue
            n = mesh.normals
            n = np.where((n @ UP_W)[:, None] < 0, -n, n)          # face the sky
            keep = n @ UP_W >= math.cos(MAX_TILT)
            tris.append(mesh.triangles[keep])
            norms.append(n[keep])
            mats.extend([material] * int(keep.sum()))
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
        return cls(np.concatenate(tris), np.concatenate(norms), np.array(mats), occ)

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
