"""Edge diffraction: the fringe wave of the physical theory of diffraction (PTD) on mesh wedges.

Physical optics (:mod:`~raysim.echoes.po.integral`) puts on every lit facet the
current of an infinite plane; near an edge the true current differs from it.
Ufimtsev's PTD adds the field of that difference, the *fringe* (non-uniform)
current, which an infinite wedge tangent to the edge gives in closed form. In
the monostatic case it is radiated by equivalent edge currents: per unit length
of edge the fringe coefficient is Keller's diffraction coefficient of the wedge
minus the edge-diffraction coefficient of the PO current on its lit faces, and
the coefficients are integrated exactly along each straight edge segment (a
``sinc`` factor, as in Gordon's facet integral). Facing parallel half-plane
edges (a plate's opposite sides) may add their multiple diffraction, the wave
that grazes across the face from one to the other (:func:`pair_amplitude`).

Conventions (those of :mod:`~raysim.echoes.po.integral`): time ``exp(+j omega t)``,
the radar in the unit direction ``u``, co-polar scattering amplitude ``F`` [m],
``sigma = 4 pi |F|^2``. A wedge has its exterior between face 0 (angle 0) and
face n (angle ``n pi``), ``n = 2`` for a half-plane (a plate's boundary edge),
``n = 3/2`` for a cube's edge. In the plane normal to the edge (unit ``t``) the
radar direction has the angle ``phi`` from face 0 towards the exterior. Keller's
monostatic coefficients (soft: electric field along the edge; hard: magnetic
field along the edge),

``d_s,h = (sin(pi/n) / n) [1 / (cos(pi/n) - 1) -+ 1 / (cos(pi/n) - cos(2 phi / n))]``,

and PO's, ``f_s = tan(phi) / 2`` for a lit face 0 (``0 < phi < pi``) and
``tan(n pi - phi) / 2`` for a lit face n, ``g_h = -f_s`` (Ufimtsev 2007; Knott,
Shaeffer & Tuley 1993, ch. 5). Both are singular at a face's specular
direction (``phi = pi/2``); their difference is finite there. For the half-plane
it is ``d_s - f_s = -sin(phi/2) / (cos(phi/2) + sin(phi/2))`` and
``d_h - g_h = -cos(phi/2) / (cos(phi/2) + sin(phi/2))``.

With the polarisation ``e`` and ``beta`` the angle between ``t`` and ``u``, the
equivalent currents (Knott ch. 5; Michaeli 1984, 1986) give

``F = 1/(2 pi) sum_segments [w_s (d_s - f_s) - w_h (d_h - g_h)] int exp(2 j k u.r) dl``,

``w_s = (e.t)^2 / sin^2 beta``, ``w_h = (e.(u x t))^2 / sin^2 beta``; with the
fringe coefficients replaced by PO's, this reproduces the edge terms of Gordon's
facet integral at ``beta = 90 deg`` (tested), and with Keller's the first-order
GTD of a plate (Ross 1966). Away from ``beta = 90 deg`` the coefficients are
evaluated at the angle ``phi`` of ``u`` projected on the normal plane (an
approximation off the Keller cone); Michaeli's off-cone expressions are not used.

References
----------
P. Ya. Ufimtsev, *Fundamentals of the Physical Theory of Diffraction*, Wiley 2007.
A. Michaeli, "Equivalent edge currents for arbitrary aspects of observation",
IEEE TAP 32(3), 252-258, 1984; "Elimination of infinities in equivalent edge
currents, part I", IEEE TAP 34(7), 912-918, 1986.
E. F. Knott, J. F. Shaeffer, M. T. Tuley, *Radar Cross Section*, 2nd ed., 1993, ch. 5.
R. A. Ross, "Radar cross section of rectangular flat plates as a function of
aspect angle", IEEE TAP 14(3), 329-335, 1966.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.echoes.po.mesh import TriangleMesh

__all__ = ["MeshEdges", "sharp_edges", "wedge_coefficients", "fringe_coefficients",
           "edge_amplitude", "edge_terms_near", "SHARP_EDGE_DEG", "MIN_SIN_BETA",
           "EdgePairs", "facing_edge_pairs", "pair_amplitude"]

#: Default: an edge is sharp when the normals of its two facets differ by more than this [deg]
#: (a faceted sphere's or a car body's smooth curvature stays below it).
SHARP_EDGE_DEG = 30.0
#: Edges seen within this sine of end-on (``u`` along the edge) radiate nothing here: their
#: weights ``w_s, w_h`` are 0/0 there and their line integral is ``O(1/k)``.
MIN_SIN_BETA = 1e-6
#: Half-width of the window about a face's specular direction where the fringe is taken as
#: the mean of its values at ``phi +- 2 SPECULAR_WINDOW`` (both terms are singular there,
#: their difference is analytic) [rad].
SPECULAR_WINDOW = 1e-3
#: Vertices closer than this share of the mesh size are one vertex when edges are paired.
MERGE_FRACTION = 1e-9


@dataclass(frozen=True)
class MeshEdges:
    """The sharp edges of a mesh, each the edge of a local wedge.

    Attributes
    ----------
    start, end : ndarray, shape ``[edge, 3]``
        End points [m].
    face_dir : ndarray, shape ``[edge, 3]``
        Unit vector in face 0, normal to the edge, pointing into the face.
    normal : ndarray, shape ``[edge, 3]``
        Unit normal of face 0 on the wedge's exterior side.
    n : ndarray, shape ``[edge]``
        Exterior angle of the wedge over pi (2: half-plane).
    """

    start: np.ndarray
    end: np.ndarray
    face_dir: np.ndarray
    normal: np.ndarray
    n: np.ndarray

    def __len__(self) -> int:
        return len(self.n)

    @property
    def lengths(self) -> np.ndarray:
        """Edge lengths, shape ``[edge]`` [m]."""
        return np.linalg.norm(self.end - self.start, axis=1)

    def split(self, max_length: float) -> MeshEdges:
        """The same edges cut into segments no longer than ``max_length`` [m]."""
        if not max_length > 0:
            raise ValueError(f"max_length must be > 0 m, got {max_length!r}")
        pieces = np.maximum(1, np.ceil(self.lengths / max_length)).astype(int)
        idx = np.repeat(np.arange(len(self)), pieces)
        first = np.repeat(np.cumsum(pieces) - pieces, pieces)
        j = (np.arange(len(idx)) - first)[:, None]
        step = (self.end - self.start)[idx] / pieces[idx, None]
        s = self.start[idx] + j * step
        return MeshEdges(s, s + step, self.face_dir[idx], self.normal[idx], self.n[idx])


def sharp_edges(mesh: TriangleMesh, threshold_deg: float = SHARP_EDGE_DEG) -> MeshEdges:
    """The wedges of ``mesh``: fold edges sharper than ``threshold_deg``, and boundary edges.

    An edge shared by two facets whose planes meet at more than the threshold is
    a wedge of exterior angle ``pi + delta`` (``delta`` the angle between the
    normals), opened on its convex side; on a closed (watertight, consistently
    wound) mesh an edge concave for the solid is left out (its corner returns
    are the SBR's). An edge of one facet is a half-plane (``n = 2``). Edges of
    more than two facets are left out.

    Parameters
    ----------
    mesh : TriangleMesh
        The target [m].
    threshold_deg : float
        Fold angle [deg] in ``(0, 180)``.

    Returns
    -------
    MeshEdges

    Raises
    ------
    ValueError
        ``threshold_deg`` outside ``(0, 180)``.
    """
    if not (isinstance(threshold_deg, (int, float)) and 0 < threshold_deg < 180):
        raise ValueError(f"threshold_deg must be an angle in (0, 180) deg, got {threshold_deg!r}")
    v = mesh.vertices
    tol = MERGE_FRACTION * max(float(np.ptp(v)), 1e-12)
    _, vid = np.unique(np.round(v / tol).astype(np.int64), axis=0, return_inverse=True)
    f = vid.reshape(-1)[mesh.faces]
    normals = mesh.normals
    # directed edges (a -> b) of each facet, corner c opposite
    a, b, c = f.reshape(-1), np.roll(f, -1, axis=1).reshape(-1), np.roll(f, -2, axis=1).reshape(-1)
    face = np.repeat(np.arange(len(f)), 3)
    key = np.stack([np.minimum(a, b), np.maximum(a, b)], axis=1)
    _, inv, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    order = np.argsort(inv, kind="stable")
    first = np.searchsorted(inv[order], np.arange(len(counts)))
    # vertex positions by merged id (any representative)
    pos = np.zeros((vid.max() + 1, 3))
    pos[vid.reshape(-1)] = v
    watertight = bool(np.all(counts == 2))
    starts, ends, fdirs, norms, ns = [], [], [], [], []

    def add(e0, e1, opposite, normal, n):
        t = pos[e1] - pos[e0]
        t = t / np.linalg.norm(t, axis=1, keepdims=True)
        d = pos[opposite] - pos[e0]
        d = d - np.einsum("ei,ei->e", d, t)[:, None] * t
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        starts.append(pos[e0])
        ends.append(pos[e1])
        fdirs.append(d)
        norms.append(normal)
        ns.append(n)

    one = first[counts == 1]
    if len(one):
        i = order[one]
        add(a[i], b[i], c[i], normals[face[i]], np.full(len(i), 2.0))
    two = first[counts == 2]
    if len(two):
        i, j = order[two], order[two + 1]
        na, nb = normals[face[i]], normals[face[j]]
        consistent = b[i] == a[j]                  # the two facets run the edge both ways
        nb = np.where(consistent[:, None], nb, -nb)
        delta = np.arccos(np.clip(np.einsum("ei,ei->e", na, nb), -1.0, 1.0))
        # facet j's opposite corner behind facet i's plane: convex for these normals
        behind = np.einsum("ei,ei->e", pos[c[j]] - pos[a[i]], na) < 0
        sign = np.where(behind, 1.0, -1.0)
        keep = delta > math.radians(threshold_deg)
        if watertight:
            keep &= behind | ~consistent
        i, delta, sign = i[keep], delta[keep], sign[keep]
        if len(i):
            add(a[i], b[i], c[i], sign[:, None] * na[keep], 1.0 + delta / math.pi)
    if not starts:
        z = np.zeros((0, 3))
        return MeshEdges(z, z, z, z, np.zeros(0))
    return MeshEdges(*(np.concatenate(x) for x in (starts, ends, fdirs, norms, ns)))


def wedge_coefficients(phi, n) -> tuple[np.ndarray, ...]:
    """Monostatic Keller and PO edge coefficients of a wedge (dimensionless).

    Parameters
    ----------
    phi : array_like, shape ``[edge]``
        Angle of the radar from face 0 in the plane normal to the edge [rad],
        in ``(0, n pi)``.
    n : array_like, shape ``[edge]``
        Exterior angle over pi, in ``(1, 2]``.

    Returns
    -------
    d_s, d_h, f_s, g_h : ndarray, shape ``[edge]``
        Keller's soft and hard coefficients and PO's (see the module docstring).
    """
    phi, n = np.broadcast_arrays(np.asarray(phi, float), np.asarray(n, float))
    cn = np.cos(np.pi / n)
    pre = np.sin(np.pi / n) / n
    t1 = 1.0 / (cn - 1.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        t2 = 1.0 / (cn - np.cos(2 * phi / n))
        po = np.where(phi < np.pi, np.tan(phi) / 2, 0.0)
        po = po + np.where(phi > (n - 1) * np.pi, np.tan(n * np.pi - phi) / 2, 0.0)
    return pre * (t1 - t2), pre * (t1 + t2), po, -po


def fringe_coefficients(phi, n) -> tuple[np.ndarray, np.ndarray]:
    """Monostatic PTD fringe coefficients ``(d_s - f_s, d_h - g_h)`` of a wedge.

    Finite at the faces' specular directions (the mean of the values at
    ``phi +- 2 SPECULAR_WINDOW`` within ``SPECULAR_WINDOW`` of them).

    Parameters
    ----------
    phi, n : array_like, shape ``[edge]``
        As in :func:`wedge_coefficients`.

    Returns
    -------
    fringe_s, fringe_h : ndarray, shape ``[edge]``
    """
    phi, n = np.broadcast_arrays(np.asarray(phi, float), np.asarray(n, float))

    def raw(p):
        d_s, d_h, f_s, g_h = wedge_coefficients(p, n)
        return d_s - f_s, d_h - g_h

    near = ((np.abs(phi - np.pi / 2) < SPECULAR_WINDOW)
            | (np.abs(n * np.pi - phi - np.pi / 2) < SPECULAR_WINDOW))
    s, h = raw(np.where(near, phi + 2 * SPECULAR_WINDOW, phi))
    s2, h2 = raw(np.where(near, phi - 2 * SPECULAR_WINDOW, phi))
    return np.where(near, (s + s2) / 2, s), np.where(near, (h + h2) / 2, h)


def _segment_fringe(edges: MeshEdges, u: np.ndarray, e_pol: np.ndarray) -> np.ndarray:
    """Fringe coefficient per unit length ``[w_s F_s - w_h F_h] / (2 pi)``, shape ``[edge]``.

    ``u``, ``e_pol``: shape ``[3]`` or ``[edge, 3]``. Zero where the radar is inside
    the wedge or end-on.
    """
    t = edges.end - edges.start
    t = t / np.linalg.norm(t, axis=1, keepdims=True)
    u = np.broadcast_to(u, t.shape)
    e = np.broadcast_to(e_pol, t.shape)
    ut = np.einsum("ei,ei->e", u, t)
    sin2 = 1.0 - ut**2
    ok = sin2 > MIN_SIN_BETA**2
    safe = np.where(ok, sin2, 1.0)
    w_s = np.einsum("ei,ei->e", e, t) ** 2 / safe
    w_h = np.einsum("ei,ei->e", e, np.cross(u, t)) ** 2 / safe
    phi = np.mod(np.arctan2(np.einsum("ei,ei->e", u, edges.normal),
                            np.einsum("ei,ei->e", u, edges.face_dir)), 2 * np.pi)
    inside = (phi <= 0) | (phi >= edges.n * np.pi)
    fs, fh = fringe_coefficients(np.where(inside, np.pi / 2 + 0.1, phi), edges.n)
    coef = (w_s * fs - w_h * fh) / (2 * np.pi)
    return np.where(ok & ~inside, coef, 0.0)


def _visible(scene, edges: MeshEdges, points: np.ndarray, toward: np.ndarray,
             dist: np.ndarray) -> np.ndarray:
    """Whether each segment's midpoint (pulled off the edge into the wedge's exterior)
    sees the radar, shape ``[edge]``."""
    if scene is None or len(points) == 0:
        return np.ones(len(points), bool)
    rot = np.pi * edges.n / 2                       # exterior bisector
    out = np.cos(rot)[:, None] * edges.face_dir + np.sin(rot)[:, None] * edges.normal
    start = points + scene.epsilon * (out + toward)
    return scene.unoccluded(start, toward, dist)


def edge_amplitude(edges: MeshEdges, u: np.ndarray, e_pol: np.ndarray, k: float,
                   scene=None) -> complex:
    """Far-field co-polar fringe amplitude ``F`` [m] of the edge segments.

    Parameters
    ----------
    edges : MeshEdges
        Edge segments (:meth:`MeshEdges.split` so that a partly hidden edge is
        resolved; each visible segment counts whole).
    u, e_pol : ndarray, shape ``[3]``
        Unit direction to the radar and polarisation.
    k : float
        Wavenumber [rad/m].
    scene : RayScene, optional
        Shadow test of each segment's midpoint; ``None``: all visible.

    Returns
    -------
    complex
        ``F`` [m], phase referred to the origin (``exp(2 j k u.r)``).
    """
    if len(edges) == 0:
        return 0j
    coef = _segment_fringe(edges, u, e_pol)
    a = edges.end - edges.start
    mid = edges.start + a / 2
    live = coef != 0
    if not live.any():
        return 0j
    seen = np.zeros(len(edges), bool)
    seen[live] = _visible(scene, _take(edges, live), mid[live],
                          np.broadcast_to(u, mid[live].shape), np.full(int(live.sum()), np.inf))
    w = 2 * k * u
    line = np.linalg.norm(a, axis=1) * np.exp(1j * mid @ w) * np.sinc(a @ w / (2 * np.pi))
    return complex(np.sum(np.where(seen, coef * line, 0.0)))


def edge_terms_near(edges: MeshEdges, u: np.ndarray, e_pol: np.ndarray, k: float,
                    range_m: float, scene=None) -> tuple[np.ndarray, np.ndarray]:
    """Fringe terms of the edge segments for a radar at ``range_m * u`` (spherical wave).

    Each segment (shorter than the near-field facet size) uses its own direction
    to the radar, path ``R_i`` and spreading ``(R / R_i)^2``, as the facets of
    :func:`~raysim.echoes.po.rcs.facet_terms_near`.

    Returns
    -------
    terms : ndarray of complex, shape ``[segment]``
        Each segment's share of ``F`` [m] (normalised to ``range_m``, phase
        referred to ``2 range_m``).
    midpoints : ndarray, shape ``[segment, 3]``
        Segment midpoints [m].
    """
    a = edges.end - edges.start
    mid = edges.start + a / 2
    if len(edges) == 0:
        return np.zeros(0, complex), mid
    rel = range_m * u - mid
    ri = np.linalg.norm(rel, axis=1)
    ui = rel / ri[:, None]
    e = e_pol - (ui @ e_pol)[:, None] * ui
    e = e / np.linalg.norm(e, axis=1, keepdims=True)
    coef = _segment_fringe(edges, ui, e)
    live = coef != 0
    seen = np.zeros(len(edges), bool)
    if live.any():
        seen[live] = _visible(scene, _take(edges, live), mid[live], ui[live], ri[live])
    w = 2 * k * ui
    line = np.linalg.norm(a, axis=1) * np.sinc(np.einsum("ei,ei->e", a, w) / (2 * np.pi))
    amp = (range_m / ri) ** 2 * np.exp(-2j * k * (ri - range_m))
    return np.where(seen, coef * line * amp, 0.0), mid


def _take(edges: MeshEdges, mask: np.ndarray) -> MeshEdges:
    return MeshEdges(edges.start[mask], edges.end[mask], edges.face_dir[mask],
                     edges.normal[mask], edges.n[mask])


# ---- multiple diffraction between the facing edges of a flat face ----------------------


@dataclass(frozen=True)
class EdgePairs:
    """Facing, parallel half-plane edges of one flat face (a plate's opposite sides).

    Each pair is described on its midline, the segment halfway between the two
    edges over the length where they face each other.

    Attributes
    ----------
    start, end : ndarray, shape ``[pair, 3]``
        Midline end points [m].
    face_dir : ndarray, shape ``[pair, 3]``
        Unit vector from the first edge across the face to the second.
    normal : ndarray, shape ``[pair, 3]``
        Unit normal of the face (the side the angles are measured towards).
    width : ndarray, shape ``[pair]``
        Distance between the two edges [m].
    """

    start: np.ndarray
    end: np.ndarray
    face_dir: np.ndarray
    normal: np.ndarray
    width: np.ndarray

    def __len__(self) -> int:
        return len(self.width)

    def split(self, max_length: float) -> EdgePairs:
        """The same pairs cut along their midlines into pieces no longer than ``max_length`` [m]."""
        if not max_length > 0:
            raise ValueError(f"max_length must be > 0 m, got {max_length!r}")
        mid = MeshEdges(self.start, self.end, self.face_dir, self.normal, self.width)
        cut = mid.split(max_length)
        return EdgePairs(cut.start, cut.end, cut.face_dir, cut.normal, cut.n)


#: Most half-plane edges compared pairwise when looking for facing pairs (the test is
#: ``[edge, edge]`` arrays, 200 bytes per pair).
MAX_PAIR_EDGES = 4000
#: Parallel, coplanar and opposite within this (1 - cosine; and share of the edge length).
PAIR_TOLERANCE = 1e-9


def facing_edge_pairs(edges: MeshEdges) -> EdgePairs:
    """Pairs of half-plane edges that face each other across one flat face.

    Two boundary edges (``n = 2``) pair when they are parallel, lie in one plane
    with normals along its normal, their faces point at each other
    (``face_dir`` opposite, each towards the other edge) and their projections
    on the edge direction overlap. Each pair is listed once. The face between
    them is assumed continuous (a plate's opposite sides), not checked.

    Raises
    ------
    ValueError
        More than ``MAX_PAIR_EDGES`` half-plane edges.
    """
    half = np.flatnonzero(edges.n == 2.0)
    empty = EdgePairs(*(np.zeros((0, 3)),) * 4, np.zeros(0))
    if len(half) < 2:
        return empty
    if len(half) > MAX_PAIR_EDGES:
        raise ValueError(f"{len(half)} boundary edges to pair, expected at most {MAX_PAIR_EDGES}: "
                         f"leave multiple diffraction off for this mesh")
    a, b = edges.start[half], edges.end[half]
    f, nrm = edges.face_dir[half], edges.normal[half]
    length = np.linalg.norm(b - a, axis=1)
    t = (b - a) / length[:, None]
    rel = a[None] - a[:, None]                                        # [i, j, 3]: a_j - a_i
    w = np.einsum("ijk,ik->ij", rel, f)
    scale = max(float(length.max()), 1e-12)
    ok = ((np.abs(np.abs(t @ t.T) - 1) < PAIR_TOLERANCE)
          & (np.abs(np.abs(nrm @ nrm.T) - 1) < PAIR_TOLERANCE)
          & (np.abs(f @ f.T + 1) < PAIR_TOLERANCE)
          & (np.abs(np.einsum("ijk,ik->ij", rel, nrm)) < PAIR_TOLERANCE * scale)
          & (w > PAIR_TOLERANCE * scale))
    ok &= np.triu(np.ones_like(ok), 1)
    i, j = np.nonzero(ok)
    if len(i) == 0:
        return empty
    # overlap of edge j's projection with edge i, along t_i from a_i
    s1 = np.einsum("pk,pk->p", a[j] - a[i], t[i])
    s2 = np.einsum("pk,pk->p", b[j] - a[i], t[i])
    lo = np.maximum(0.0, np.minimum(s1, s2))
    hi = np.minimum(length[i], np.maximum(s1, s2))
    keep = hi - lo > PAIR_TOLERANCE * scale
    i, j, lo, hi = i[keep], j[keep], lo[keep], hi[keep]
    if len(i) == 0:
        return empty
    width = w[i, j]
    shift = a[i] + (width / 2)[:, None] * f[i]
    return EdgePairs(shift + lo[:, None] * t[i], shift + hi[:, None] * t[i], f[i], nrm[i], width)


def _fresnel_transition(x: np.ndarray) -> np.ndarray:
    """Kouyoumjian-Pathak transition function of ``X >= 0`` (time ``exp(+j omega t)``).

    ``F(X) = 2 j sqrt(X) exp(j X) int_sqrt(X)^oo exp(-j tau^2) d tau``, ``-> 1`` as ``X -> oo``.
    """
    from scipy.special import fresnel

    v = np.sqrt(x)
    s, c = fresnel(v * math.sqrt(2 / math.pi))
    tail = math.sqrt(math.pi / 2) * ((0.5 - c) - 1j * (0.5 - s))
    return 2j * v * np.exp(1j * x) * tail


def pair_amplitude(pairs: EdgePairs, u: np.ndarray, e_pol: np.ndarray, k: float,
                   scene=None, *, orders: str = "all") -> complex:
    """Far-field co-polar amplitude ``F`` [m] of the multiple diffraction across edge pairs.

    The field one edge diffracts along the face, grazing, is diffracted again by
    the other edge, towards the radar (double diffraction) or back across the
    face, and so on. In the 2-D problem of the plane normal to the edges
    (wavenumber ``k_t = k sin beta``, the radar's projected direction), with
    Keller's half-plane coefficient, the factor 1/2 of grazing incidence, the
    uniform (UTD) transition function ``F`` of the shadow boundary of the wave
    that grazes the face (Kouyoumjian & Pathak, Proc. IEEE 62(11), 1974;
    Balanis, *Advanced Engineering Electromagnetics*, 2nd ed., ch. 13) and
    both sides of the sheet: an edge X lit at the angle ``a_X`` (from its face,
    towards the face normal) sends ``s_X = -2 c F(2 k_t w cos^2(a_X/2)) / cos(a_X/2)``
    across, ``c = exp(-j pi/4) / (2 sqrt(2 pi k_t))``; the crossing is
    ``G = exp(-j k_t w) / sqrt(w)``; an edge returns a grazing wave with
    ``R = -2 c G`` and radiates one with ``s_X``. Summing the paths (the
    ``orders="all"`` geometric series in closed form),

    ``S = G / (1 - R^2) [2 s_A s_B + R (s_A^2 e_A + s_B^2 e_B)]``,

    ``e_X = exp(2 j k u.(r_X - r_mid))`` (``orders="double"``: ``S = 2 G s_A s_B``),
    and per unit length of the pair's midline ``C = -exp(j pi/4) sqrt(2 pi k_t) S``,
    ``F = 1/(2 pi) sum w_h C int exp(2 j k u.r) dl``, ``w_h`` as for single
    diffraction. Only the hard part (magnetic field along the edges): a grazing
    soft wave is zero to this order (slope diffraction is left out). Exactly
    at grazing (the radar in the face's plane) it fails: see docs/rcs.md.

    Parameters
    ----------
    pairs : EdgePairs
        From :func:`facing_edge_pairs`, split to a wavelength at most.
    u, e_pol : ndarray, shape ``[3]``
        Unit direction to the radar and polarisation.
    k : float
        Wavenumber [rad/m].
    scene : RayScene, optional
        Both edge points must see the radar; ``None``: all visible.
    orders : {"all", "double"}
        Every number of crossings, or the double diffraction alone.

    Returns
    -------
    complex
        ``F`` [m], phase referred to the origin.
    """
    if orders not in ("all", "double"):
        raise ValueError(f"orders must be 'all' or 'double', got {orders!r}")
    if len(pairs) == 0:
        return 0j
    a = pairs.end - pairs.start
    length = np.linalg.norm(a, axis=1)
    t = a / length[:, None]
    ut = t @ u
    sin2 = 1.0 - ut**2
    ok = sin2 > MIN_SIN_BETA**2
    safe = np.where(ok, sin2, 1.0)
    w_h = (np.cross(u, t) @ e_pol) ** 2 / safe
    k_t = k * np.sqrt(safe)
    un, uf = pairs.normal @ u, pairs.face_dir @ u
    ang_a = np.mod(np.arctan2(un, uf), 2 * np.pi)          # at the first edge, face towards +f
    ang_b = np.mod(np.arctan2(un, -uf), 2 * np.pi)         # at the second, face towards -f
    kw = k_t * pairs.width
    c = np.exp(-1j * np.pi / 4) / (2 * np.sqrt(2 * np.pi * k_t))
    send = []
    for ang in (ang_a, ang_b):
        half = np.cos(ang / 2)
        # F(X)/cos(a/2) -> sqrt(2 pi k_t w) exp(j pi/4) as cos(a/2) -> 0
        tiny = np.abs(half) < 1e-12
        lim = np.sqrt(2 * np.pi * kw) * np.exp(1j * np.pi / 4)
        ratio = _fresnel_transition(2 * kw * half**2) / np.where(tiny, 1.0, half)
        send.append(-2 * c * np.where(tiny, lim, ratio))
    s_a, s_b = send
    g = np.exp(-1j * kw) / np.sqrt(pairs.width)
    if orders == "double":
        total = 2 * g * s_a * s_b
    else:
        r = -2 * c * g
        back = k * uf * pairs.width                      # 2 k u.(r_B - r_mid)
        total = g / (1 - r**2) * (2 * s_a * s_b + r * (s_a**2 * np.exp(-1j * back)
                                                     + s_b**2 * np.exp(1j * back)))
    c2 = -np.exp(1j * np.pi / 4) * np.sqrt(2 * np.pi * k_t) * total
    mid = pairs.start + a / 2
    live = ok & (w_h > 0)
    if scene is not None and live.any():
        half = (pairs.width / 2)[:, None] * pairs.face_dir
        for side, fdir in ((-half, pairs.face_dir), (half, -pairs.face_dir)):
            pts = (mid + side)[live]
            edge = MeshEdges(pts, pts + t[live], fdir[live], pairs.normal[live],
                             np.full(len(pts), 2.0))
            live[live] = _visible(scene, edge, pts, np.broadcast_to(u, pts.shape),
                                  np.full(len(pts), np.inf))
    w = 2 * k * u
    line = length * np.exp(1j * mid @ w) * np.sinc(a @ w / (2 * np.pi))
    return complex(np.sum(np.where(live, w_h * c2 * line, 0.0)) / (2 * np.pi))
