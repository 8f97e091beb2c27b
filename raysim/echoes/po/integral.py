"""The physical-optics integral: Gordon's closed form over flat triangles, PO currents.

Conventions: time dependence ``exp(+j omega t)``, a wave travelling along
``d`` has phase ``exp(-j k d.r)``. A far-field scattered wave is
``E_s = exp(-j k R) / R * F`` with the scattering amplitude ``F`` [m], and the
RCS is ``sigma = 4 pi |F . e_rx|^2`` [m^2].

References
----------
W. B. Gordon, "Far-field approximations to the Kirchhoff-Helmholtz
representations of scattered fields", IEEE TAP 23(4), 590-592, 1975.
E. F. Knott, J. F. Shaeffer, M. T. Tuley, *Radar Cross Section*, 2nd ed.,
Artech House 1993, ch. 5 (PO) and 6.
C. A. Balanis, *Antenna Theory*, 3rd ed., eqs. 12-10 (far field of the
equivalent currents ``N`` and ``L``).
"""

from __future__ import annotations

import numpy as np

from raysim.echoes.po.mesh import PoMaterial, fresnel

__all__ = ["polygon_phase_integral", "po_vector", "reflect"]

#: Below this value of ``|p| * (longest edge)`` the Taylor limit ``A exp(j p.c)``
#: replaces Gordon's sum (its cancellation error grows as ``1 / (|p| L)``).
SMALL_PHASE = 1e-4


def polygon_phase_integral(triangles: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``I = int_T exp(j w . r) dS`` over each flat triangle, in closed form.

    Gordon (1975): with ``p`` the component of ``w`` in the facet plane, ``n``
    the facet normal, edges ``a_m = v_{m+1} - v_m`` with midpoints ``c_m``,

    ``I = exp(j (w.n)(n.v_0)) / (j |p|^2) * sum_m p.(a_m x n) exp(j p.c_m) sinc(p.a_m / 2)``

    (divergence theorem in the plane; ``sinc x = sin x / x``), and
    ``I = A exp(j w.c)`` when ``|p| -> 0``.

    Parameters
    ----------
    triangles : ndarray, shape ``[facet, 3, 3]``
        Corner positions [m].
    w : ndarray, shape ``[3]`` or ``[facet, 3]``
        Phase gradient [rad/m] (``2 k u`` for monostatic backscatter).

    Returns
    -------
    ndarray of complex, shape ``[facet]``
        The integral [m^2].
    """
    t = np.asarray(triangles, dtype=float)
    w = np.broadcast_to(np.asarray(w, dtype=float), (len(t), 3))
    cr = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    area = 0.5 * np.linalg.norm(cr, axis=1)
    n = cr / (2 * area[:, None])
    wn = np.einsum("fi,fi->f", w, n)
    p = w - wn[:, None] * n
    edges = np.roll(t, -1, axis=1) - t                      # [facet, edge, 3]
    mids = t + 0.5 * edges
    pa = np.einsum("fi,fei->fe", p, edges)
    pc = np.einsum("fi,fei->fe", p, mids)
    pm = np.einsum("fi,fei->fe", p, np.cross(edges, n[:, None, :]))
    p2 = np.einsum("fi,fi->f", p, p)
    size = np.linalg.norm(edges, axis=2).max(axis=1)
    small = np.sqrt(p2) * size < SMALL_PHASE
    safe = np.where(small, 1.0, p2)
    tangential = (pm * np.exp(1j * pc) * np.sinc(pa / (2 * np.pi))).sum(axis=1) / (1j * safe)
    centroid = t.mean(axis=1)
    limit = area * np.exp(1j * np.einsum("fi,fi->f", p, centroid))
    offset = np.exp(1j * wn * np.einsum("fi,fi->f", n, t[:, 0]))
    return np.where(small, limit, tangential) * offset


def reflect(material: PoMaterial, d: np.ndarray, e: np.ndarray, n: np.ndarray):
    """Specular reflection of a local plane wave on a facet.

    Parameters
    ----------
    d : ndarray, shape ``[ray, 3]``
        Unit propagation direction of the incident wave.
    e : ndarray of complex, shape ``[ray, 3]``
        Incident electric field (transverse to ``d``).
    n : ndarray, shape ``[ray, 3]``
        Unit facet normal facing the incident wave (``n.d < 0``).

    Returns
    -------
    d_r : ndarray, shape ``[ray, 3]``
        Reflected direction ``d - 2 (d.n) n``.
    e_r : ndarray of complex, shape ``[ray, 3]``
        Reflected field: ``-e + 2 (e.n) n`` for a PEC, else the TE/TM
        decomposition weighted by :func:`~raysim.echoes.po.mesh.fresnel`.
    """
    dn = np.einsum("ri,ri->r", d, n)
    d_r = d - 2 * dn[:, None] * n
    if material.is_pec:
        return d_r, -e + 2 * np.einsum("ri,ri->r", e, n)[:, None] * n
    s = np.cross(d, n)
    norm = np.linalg.norm(s, axis=1)
    helper = np.where(np.abs(d[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    s = np.where(norm[:, None] > 1e-9, s, np.cross(d, helper))
    s /= np.linalg.norm(s, axis=1, keepdims=True)
    p_i, p_r = np.cross(s, d), np.cross(s, d_r)
    g_te, g_tm = fresnel(material, -dn)
    e_s = np.einsum("ri,ri->r", e, s)
    e_p = np.einsum("ri,ri->r", e, p_i)
    return d_r, (g_te * e_s)[:, None] * s + (g_tm * e_p)[:, None] * p_r


def po_vector(material: PoMaterial, d: np.ndarray, e: np.ndarray, n: np.ndarray,
              o: np.ndarray) -> np.ndarray:
    """Integrand vector of the PO far field towards ``o`` (per unit area, unit phase).

    ``F = -j k / (4 pi) int V exp(j phase) dS`` with
    ``V = eta n x (H_i + H_r) + (-n x (E_i + E_r)) x o`` (Balanis eq. 12-10,
    equivalent currents ``J = n x H``, ``M = -n x E`` of the total PO field);
    ``eta H = d x E``. For a PEC ``V = 2 n x (d x e)``, and for backscatter
    ``e . V = 2 (n . o)``.

    Parameters
    ----------
    d, e, n : ndarray, shape ``[ray, 3]``
        As in :func:`reflect`.
    o : ndarray, shape ``[3]`` or ``[ray, 3]``
        Unit observation direction.

    Returns
    -------
    ndarray of complex, shape ``[ray, 3]``
    """
    if material.is_pec:
        return 2 * np.cross(n, np.cross(d, e))
    d_r, e_r = reflect(material, d, e, n)
    h_tot = np.cross(d, e) + np.cross(d_r, e_r)
    e_tot = e + e_r
    o = np.broadcast_to(o, d.shape)
    return np.cross(n, h_tot) + np.cross(-np.cross(n, e_tot), o)
