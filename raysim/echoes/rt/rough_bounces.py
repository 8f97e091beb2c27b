r"""Ament factor of every specular bounce on a rough material of a traced path.

Sionna reflects specularly off a rough ground with the smooth Fresnel
coefficient (times ``sqrt(1 - S^2)``, its diffuse share ``S``), whatever the
surface's rms height. The coherent part of a rough-surface reflection is
smaller by the Ament factor (Ament, J. Appl. Phys. 24, 1953; Beckmann &
Spizzichino 1963, eq. 5.29)

.. math::

    \chi(\theta_i) = \exp\bigl(-2 (k s \cos\theta_i)^2\bigr)

with ``s`` the material's rms height (:data:`raysim.echoes.ground.sigma0.CLUTTER_MATERIALS`)
and ``theta_i`` the local incidence angle. The incidence angle of a specular
bounce follows from its two legs alone: with unit directions ``a`` (incoming)
and ``b`` (outgoing), ``b = a - 2 (a . n) n``, so ``|b - a| = 2 cos(theta_i)``;
no facet normal is needed. Materials without an entry there (metal, glass,
rubber) are smooth: factor 1.
"""

from __future__ import annotations

import numpy as np

from raysim.echoes.ground.sigma0 import CLUTTER_MATERIALS, ament_factor

__all__ = ["object_materials", "rough_bounce_factor"]

#: Sionna interaction bit of a specular reflection (``InteractionType.SPECULAR``).
_SPECULAR = 1


def object_materials(sionna_scene) -> dict:
    """Rough material of each Sionna object id of a scene.

    Returns
    -------
    dict
        ``object_id -> ClutterMaterial`` for the objects whose radio material
        has a roughness model (a key of ``CLUTTER_MATERIALS`` with ``s > 0``);
        the others are smooth.
    """
    out = {}
    for obj in sionna_scene.objects.values():
        mat = CLUTTER_MATERIALS.get(obj.radio_material.name)
        if mat is not None and mat.rms_height > 0:
            out[int(obj.object_id)] = mat
    return out


def rough_bounce_factor(interactions: np.ndarray, objects: np.ndarray, vertices: np.ndarray,
                        radar_w, materials: dict, wavelength: float) -> np.ndarray:
    """Product over a path's specular bounces on rough materials of the Ament factor.

    Parameters
    ----------
    interactions : ndarray of uint, shape ``[path, depth]``
        Sionna interaction type of each bounce (0 past the path's end).
    objects : ndarray of uint, shape ``[path, depth]``
        Sionna object id hit at each bounce.
    vertices : ndarray, shape ``[depth, path, 3]``
        Interaction points [m] (any Cartesian frame, the same as ``radar_w``).
    radar_w : array_like, shape ``[3]``
        Co-located transmitter and receiver [m].
    materials : dict
        ``object_id -> ClutterMaterial`` (:func:`object_materials`).
    wavelength : float
        Carrier wavelength [m].

    Returns
    -------
    ndarray, shape ``[path]``
        Real amplitude factor in ``(0, 1]``; 1 for paths with no rough specular bounce.
    """
    inter = np.asarray(interactions)
    obj = np.asarray(objects)
    verts = np.asarray(vertices, dtype=float)
    if inter.ndim != 2 or obj.shape != inter.shape \
            or verts.shape != (inter.shape[1], inter.shape[0], 3):
        raise ValueError(f"objects {obj.shape} must match interactions [path, depth] "
                         f"{inter.shape} and vertices {verts.shape} must be [depth, path, 3]")
    n_path, depth = inter.shape
    factor = np.ones(n_path)
    if not materials or n_path == 0:
        return factor
    radar = np.broadcast_to(np.asarray(radar_w, dtype=float), (n_path, 3))
    n_bounce = np.count_nonzero(inter, axis=1)
    for j in range(depth):
        hit = np.flatnonzero((inter[:, j] == _SPECULAR) & np.isin(obj[:, j], list(materials)))
        if hit.size == 0:
            continue
        prev = radar[hit] if j == 0 else verts[j - 1, hit]
        last = (n_bounce[hit] == j + 1)[:, None]
        nxt = radar[hit] if j + 1 == depth else np.where(last, radar[hit], verts[j + 1, hit])
        a = verts[j, hit] - prev
        b = nxt - verts[j, hit]
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        b /= np.linalg.norm(b, axis=-1, keepdims=True)
        cos_i = np.clip(0.5 * np.linalg.norm(b - a, axis=-1), 0.0, 1.0)
        # a grazing bounce (cos_i -> 0) must stay inside ament_factor's [0, pi/2) domain
        theta = np.minimum(np.arccos(cos_i), np.nextafter(np.pi / 2, 0.0))
        for oid, mat in materials.items():
            sel = obj[hit, j] == oid
            if sel.any():
                factor[hit[sel]] *= ament_factor(mat, theta[sel], wavelength)
    return factor
