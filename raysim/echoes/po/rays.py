"""Ray intersection against a target mesh with Mitsuba (Dr.Jit LLVM on CPU, CUDA on GPU).

The Mitsuba variant is the project's: :func:`raysim.echoes.rt.backend.configure`
selects it explicitly (``llvm_ad_mono_polarized`` by default, overridable with
``RAYSIM_RT_VARIANT``) before anything is traced, so this solver and Sionna RT
share one process and one variant. Mitsuba intersects in single precision;
hit points are then recomputed in double precision on the hit facet's plane.
"""

from __future__ import annotations

import numpy as np

from raysim.echoes.po.mesh import TriangleMesh

__all__ = ["RayScene"]

#: Rays per Dr.Jit launch (bounds the memory of one batch).
BATCH = 1 << 21


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
