"""Ray intersection against a target mesh with Mitsuba (Dr.Jit LLVM on CPU, CUDA on GPU).

The Mitsuba variant is the project's: :func:`raysim.echoes.rt.backend.configure`
selects it explicitly (``llvm_ad_mono_polarized`` by default, overridable with
``RAYSIM_RT_VARIANT``) before anything is traced, so this solver and Sionna RT
share one process and one variant. Mitsuba intersects in single precision;
hit points are then recomputed in double precision on the hit facet's plane.

Shading normals: a faceted curved surface reflects rays as the smooth surface
it samples when the normal at a hit is interpolated between the facet's
corners (Phong). A corner's normal averages the normals (area-weighted) of
the facets around its vertex that fold by less than
:data:`~raysim.echoes.po.edges.SHARP_EDGE_DEG` from the facet's own, so a flat
face keeps its normal exactly and a fold (a dihedral's) stays sharp.
"""

from __future__ import annotations

import numpy as np

from raysim.echoes.po.edges import SHARP_EDGE_DEG
from raysim.echoes.po.mesh import TriangleMesh

__all__ = ["RayScene", "corner_normals"]

#: Rays per Dr.Jit launch (bounds the memory of one batch).
BATCH = 1 << 21


def corner_normals(mesh: TriangleMesh, threshold_deg: float = SHARP_EDGE_DEG) -> np.ndarray:
    """Smoothed normal at each facet corner, shape ``[facet, corner, 3]`` (unit).

    The area-weighted mean of the normals of the facets sharing the corner's
    vertex whose normal lies within ``threshold_deg`` of the facet's own (the
    facet itself always counts): a flat face keeps its normal, a fold sharper
    than ``threshold_deg`` is not smoothed across.
    """
    faces = mesh.faces
    t = mesh.triangles
    weighted = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])        # 2 area n
    unit = mesh.normals
    vertex = faces.ravel()                                          # corner -> vertex
    facet = np.repeat(np.arange(len(faces)), 3)                     # corner -> facet
    order = np.argsort(vertex, kind="stable")
    degree = np.bincount(vertex, minlength=len(mesh.vertices))
    start = np.concatenate([[0], np.cumsum(degree)[:-1]])
    # every (corner, facet around its vertex) pair
    reps = degree[vertex]
    corner = np.repeat(np.arange(len(vertex)), reps)
    within = np.arange(len(corner)) - np.repeat(np.cumsum(reps) - reps, reps)
    other = facet[order[start[vertex[corner]] + within]]
    near = (np.einsum("pi,pi->p", unit[facet[corner]], unit[other])
            >= np.cos(np.radians(threshold_deg)))
    acc = np.zeros((len(vertex), 3))
    np.add.at(acc, corner[near], weighted[other[near]])
    norm = np.linalg.norm(acc, axis=1, keepdims=True)
    out = np.where(norm > 0, acc / np.where(norm > 0, norm, 1.0), unit[facet])
    return out.reshape(len(faces), 3, 3)


class RayScene:
    """A Mitsuba scene holding one mesh, for visibility and specular bounces.

    Parameters
    ----------
    mesh : TriangleMesh
        The target [m].
    variant : str, optional
        Backend passed to :func:`raysim.echoes.rt.backend.configure` when no
        backend is configured yet (``"cpu"``, ``"gpu"`` or a variant name).
    """

    def __init__(self, mesh: TriangleMesh, variant: str | None = None):
        from raysim.echoes.rt import backend

        if backend.info() is None:
            backend.configure(variant)
        import mitsuba as mi

        self._mi = mi
        self.mesh = mesh
        m = mi.Mesh("target", len(mesh.vertices), len(mesh.faces))
        params = mi.traverse(m)
        params["vertex_positions"] = mi.Float(mesh.vertices.astype(np.float32).ravel())
        params["faces"] = mi.UInt32(mesh.faces.astype(np.uint32).ravel())
        params.update()
        self._scene = mi.load_dict({"type": "scene", "target": m})
        self.normals = mesh.normals
        self._v0 = mesh.triangles[:, 0]
        #: Offset of secondary ray origins along the facet normal [m].
        self.epsilon = 1e-6 * max(mesh.radius, 1e-3)
        self._corner_normals = None
        self._curved = None

    @property
    def corner_normals(self) -> np.ndarray:
        """Smoothed corner normals, shape ``[facet, corner, 3]`` (:func:`corner_normals`)."""
        if self._corner_normals is None:
            self._corner_normals = corner_normals(self.mesh)
        return self._corner_normals

    @property
    def curved(self) -> bool:
        """Whether any facet's corner normals differ from its own (a smoothed surface)."""
        if self._curved is None:
            dots = np.einsum("fci,fi->fc", self.corner_normals, self.normals)
            self._curved = bool(np.any(dots < 1.0 - 1e-9))
        return self._curved

    def shading_normals(self, facet: np.ndarray, x: np.ndarray) -> np.ndarray:
        """Interpolated (Phong) unit normals at points on facets, shape ``[ray, 3]``.

        Parameters
        ----------
        facet : ndarray of int, shape ``[ray]``
            Hit facets.
        x : ndarray, shape ``[ray, 3]``
            Points on those facets [m].
        """
        t = self.mesh.triangles[facet]
        e1, e2, r = t[:, 1] - t[:, 0], t[:, 2] - t[:, 0], x - t[:, 0]
        d11, d12, d22 = (np.einsum("ri,ri->r", p, q) for p, q in ((e1, e1), (e1, e2), (e2, e2)))
        r1, r2 = np.einsum("ri,ri->r", r, e1), np.einsum("ri,ri->r", r, e2)
        det = d11 * d22 - d12 * d12
        w1 = np.clip((d22 * r1 - d12 * r2) / det, 0.0, 1.0)
        w2 = np.clip((d11 * r2 - d12 * r1) / det, 0.0, 1.0)
        w0 = np.clip(1.0 - w1 - w2, 0.0, 1.0)
        c = self.corner_normals[facet]
        n = w0[:, None] * c[:, 0] + w1[:, None] * c[:, 1] + w2[:, None] * c[:, 2]
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def intersect(self, origins: np.ndarray, directions: np.ndarray,
                  max_t: np.ndarray | float = np.inf) -> tuple[np.ndarray, np.ndarray]:
        """First hit of each ray.

        Parameters
        ----------
        origins, directions : ndarray, shape ``[ray, 3]``
            Ray origins [m] and unit directions.
        max_t : float or ndarray, shape ``[ray]``
            Longest distance searched [m].

        Returns
        -------
        t : ndarray, shape ``[ray]``
            Distance to the hit on the hit facet's plane (float64) [m]; ``inf`` for a miss.
        facet : ndarray of int, shape ``[ray]``
            Hit facet index, ``-1`` for a miss.
        """
        mi = self._mi
        o = np.asarray(origins, dtype=float)
        d = np.asarray(directions, dtype=float)
        max_t = np.broadcast_to(np.asarray(max_t, dtype=float), (len(o),))
        t = np.full(len(o), np.inf)
        facet = np.full(len(o), -1, dtype=np.int64)
        for s in range(0, len(o), BATCH):
            sl = slice(s, s + BATCH)
            oo, dd = o[sl].astype(np.float32), d[sl].astype(np.float32)
            mt = np.minimum(max_t[sl], np.finfo(np.float32).max).astype(np.float32)
            ray = mi.Ray3f(mi.Point3f(oo[:, 0], oo[:, 1], oo[:, 2]),
                           mi.Vector3f(dd[:, 0], dd[:, 1], dd[:, 2]))
            ray.maxt = mi.Float(mt)
            pi = self._scene.ray_intersect_preliminary(ray)
            valid = np.asarray(pi.is_valid(), dtype=bool)
            prim = np.asarray(pi.prim_index, dtype=np.int64)
            facet[sl] = np.where(valid, prim, -1)
        hit = facet >= 0
        if hit.any():
            n = self.normals[facet[hit]]
            t[hit] = (np.einsum("ri,ri->r", n, self._v0[facet[hit]] - o[hit])
                      / np.einsum("ri,ri->r", n, d[hit]))
        return t, facet

    def unoccluded(self, origins: np.ndarray, directions: np.ndarray,
                   max_t: np.ndarray | float = np.inf) -> np.ndarray:
        """Whether nothing lies within ``max_t`` [m] along each ray, shape ``[ray]``."""
        _, facet = self.intersect(origins, directions, max_t)
        return facet < 0
