"""Shooting and bouncing rays (SBR): multiple-bounce PO contributions by ray tubes.

A grid of ray tubes of side ``spacing`` covers the target's projection on
the plane through the origin normal to the radar direction ``u``. Each tube is
traced through specular bounces (Mitsuba, :class:`~raysim.echoes.po.rays.RayScene`);
its field is reflected at each facet (PEC, or Fresnel TE/TM). At every hit
after the first (the first is the facet PO integral of
:mod:`raysim.echoes.po.rcs`), the tube's footprint radiates back to the radar
by the PO integral of Ling, Chou & Lee (IEEE TAP 37(2), 194-205, 1989): the
footprint is the tube cross-section ``spacing^2 / |n.d|`` with the exact
integral of the linear phase over the parallelogram (``sinc`` factors), and
the return path is tested for blockage.

Far field: parallel tubes, unit incident field at the plane through the
origin. Near field (radar at ``P = R u``): tubes diverge from ``P``; the field
of a tube after bounces on flat facets is a spherical wave from the image of
``P`` (amplitude ``R / s`` at unfolded path length ``s``, cross-section
``dOmega s^2``), and the return to ``P`` carries ``R / R_b`` and
``exp(-j k R_b)``.

Curved surfaces: a tube reflects on the interpolated normal of the smooth
surface the facets sample (:meth:`RayScene.shading_normals`), and its term is
scaled by its spreading since launch, measured from its neighbours in the
launch grid (:func:`_spreading`): a concave reflector's exit aperture then
radiates with the geometric-optics weight, and a caustic (a focus) turns the
phase. After flat facets only the factor is 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from raysim.echoes.po.edges import SHARP_EDGE_DEG
from raysim.echoes.po.integral import po_vector, reflect
from raysim.echoes.po.mesh import PoMaterial
from raysim.echoes.po.rays import RayScene
from raysim.resources import check_memory

__all__ = ["sbr_amplitude", "sbr_contributions", "TubeTerms", "launch_grid"]


#: Peak memory per ray tube while tracing [bytes]: about a dozen ``[ray, 3]`` float64 or
#: complex128 arrays (origins, directions, hit points, normals, fields) at once.
SBR_BYTES_PER_RAY = 512


def launch_grid(scene: RayScene, u: np.ndarray, e_h: np.ndarray, e_v: np.ndarray,
                spacing: float, range_m: float | None,
                cover: np.ndarray | None = None) -> np.ndarray:
    """Tube centres on the plane ``u.r = 0`` covering the target, shape ``[ray, 3]`` [m].

    Far field: orthographic projection of the vertices (or of the points
    ``cover``, shape ``[point, 3]``, when given); near field: their central
    projection from the radar at ``range_m * u``. Tube ``i ny + j`` lies at
    column ``i`` (along ``e_h``) and row ``j`` (along ``e_v``) of ``ny`` rows.
    """
    return _grid(*_launch_axes(scene, u, e_h, e_v, spacing, range_m, cover), e_h, e_v)


def _grid(xs, ys, e_h, e_v):
    """Tube centres of columns ``xs`` and rows ``ys`` [m], shape ``[ray, 3]`` (``i ny + j``)."""
    gx, gy = np.meshgrid(xs, ys, indexing="ij")
    return gx.reshape(-1, 1) * e_h + gy.reshape(-1, 1) * e_v


def _launch_axes(scene, u, e_h, e_v, spacing, range_m, cover):
    """Columns and rows of :func:`launch_grid`: coordinates along ``e_h`` and ``e_v`` [m]."""
    v = scene.mesh.vertices if cover is None else np.asarray(cover, dtype=float)
    if range_m is not None:
        depth = range_m - v @ u
        if np.any(depth <= 0):
            raise ValueError(f"range_m={range_m!r} puts the radar inside the target "
                             f"(radius {scene.mesh.radius:.3g} m)")
        v = range_m * u + (v - range_m * u) * (range_m / depth)[:, None]
    x, y = v @ e_h, v @ e_v
    pad = spacing
    xs = np.arange(x.min() - pad, x.max() + pad, spacing)
    ys = np.arange(y.min() - pad, y.max() + pad, spacing)
    n = xs.size * ys.size
    check_memory(SBR_BYTES_PER_RAY * n, f"{n} SBR ray tubes ({xs.size} x {ys.size} at "
                 f"{spacing:.3g} m)", "--rays-per-wavelength, the target size or "
                 "--max-bounces 1")
    return xs, ys


def _spreading(tube, ny, x, d, a, b, normal, smooth, width):
    """Divergence and caustic factor of the tubes at one hit, shape ``[ray]`` (complex).

    The tube's cross-section at this hit is spanned by the hit points of its
    neighbours in the launch grid (forward, else backward), projected normal to
    ``d`` and measured in the tube's reflected frame ``(a, b)`` [m]: the matrix
    ``M`` (``2 x 2``, over ``width``) is the identity after flat facets only.
    The field scales as ``1 / sqrt|det M|`` and the footprint as ``|det M|``:
    the term by ``sqrt|det M|`` (Deschamps' GO spreading), times ``j`` per
    caustic crossed (negative eigenvalue of ``M``; Kouyoumjian & Pathak 1974).
    A tube without a neighbour on the same smooth surface at every hit
    (``smooth``, shape ``[grid, 2]``) keeps the factor 1.
    """
    n_grid = len(smooth)
    pos = np.full((n_grid, 3), np.nan)
    pos[tube] = x
    nrm = np.zeros((n_grid, 3))
    nrm[tube] = normal
    live = np.zeros(n_grid, bool)
    live[tube] = True
    cos_max = np.cos(np.radians(SHARP_EDGE_DEG))
    col, row = tube // ny, tube % ny
    nx = n_grid // ny
    span = []
    for axis, (step, lo, hi) in enumerate(((ny, col, nx), (1, row, ny))):
        fwd = np.where(lo + 1 < hi, tube + step, tube)
        bwd = np.where(lo > 0, tube - step, tube)
        ok_f = (fwd != tube) & live[fwd] & (np.einsum("ri,ri->r", nrm[fwd], normal) >= cos_max)
        ok_b = (bwd != tube) & live[bwd] & (np.einsum("ri,ri->r", nrm[bwd], normal) >= cos_max)
        smooth[tube, axis] &= ok_f | ok_b
        delta = np.where(ok_f[:, None], pos[fwd] - x, x - pos[bwd])
        delta = delta - np.einsum("ri,ri->r", delta, d)[:, None] * d
        span.append((delta, ok_f | ok_b))
    (dx, okx), (dy, oky) = span
    w = np.broadcast_to(width, (len(tube),))
    m11, m12 = np.einsum("ri,ri->r", dx, a) / w, np.einsum("ri,ri->r", dy, a) / w
    m21, m22 = np.einsum("ri,ri->r", dx, b) / w, np.einsum("ri,ri->r", dy, b) / w
    det, trace = m11 * m22 - m12 * m21, m11 + m22
    caustics = np.where(det < 0, 1, np.where(trace < 0, 2, 0))
    factor = np.sqrt(np.abs(det)) * 1j ** caustics
    good = okx & oky & smooth[tube].all(axis=1) & np.isfinite(factor)
    return np.where(good, factor, 1.0 + 0j)


def _tube_integral(q, a, b, n, d, spacing):
    """``int exp(j q.(r - x)) dS`` over a tube footprint (parallelogram), shape ``[ray]``."""
    nd = np.einsum("ri,ri->r", n, d)
    qd = np.einsum("ri,ri->r", q, d)
    ga = np.einsum("ri,ri->r", q, a) - qd * np.einsum("ri,ri->r", a, n) / nd
    gb = np.einsum("ri,ri->r", q, b) - qd * np.einsum("ri,ri->r", b, n) / nd
    h = spacing / (2 * np.pi)
    return spacing**2 / np.abs(nd) * np.sinc(ga * h) * np.sinc(gb * h)


def sbr_amplitude(scene: RayScene, material: PoMaterial, u: np.ndarray, e_pol: np.ndarray,
                  e_h: np.ndarray, e_v: np.ndarray, wavelength: float, *,
                  spacing: float, max_bounces: int, range_m: float | None = None) -> complex:
    """Co-polar scattering amplitude [m] of the hits 2..``max_bounces`` of every tube.

    Parameters
    ----------
    u : ndarray, shape ``[3]``
        Unit direction from the target origin to the radar.
    e_pol, e_h, e_v : ndarray, shape ``[3]``
        Transmit/receive polarisation and the transverse basis (all ``_|_ u``).
    spacing : float
        Tube side [m] on the plane through the origin.
    max_bounces : int
        Deepest hit traced (>= 2 for any contribution).
    range_m : float, optional
        Radar range [m]; ``None`` for the far field.

    Returns
    -------
    complex
        ``F_co`` such that ``sigma = 4 pi |F_co|^2``, from multiple bounces only.
    """
    terms = sbr_contributions(scene, material, u, e_pol, e_h, e_v, wavelength,
                              spacing=spacing, max_bounces=max_bounces, range_m=range_m)
    return complex(np.sum(terms.amplitude))


@dataclass(frozen=True)
class TubeTerms:
    """Multiple-bounce contributions of single ray tubes (target frame).

    Attributes
    ----------
    amplitude : ndarray of complex, shape ``[term]``
        Each tube's share of ``F_co`` [m] (far field; near field: normalised to
        the range ``R`` as in :func:`sbr_amplitude`, phase referred to ``2 R``).
    first, last : ndarray, shape ``[term, 3]``
        First and last hit points [m].
    length : ndarray, shape ``[term]``
        Unfolded two-way length radar -> hits -> radar [m] (near field); far
        field: the length past the plane ``u.r = 0`` and back to it.
    back : ndarray, shape ``[term, 3]``
        Unit direction from the last hit towards the radar.
    bounces : ndarray of int, shape ``[term]``
        Hit number of the contribution (2 = double bounce, ...).
    tubes : int
        Tubes launched.
    """

    amplitude: np.ndarray
    first: np.ndarray
    last: np.ndarray
    length: np.ndarray
    back: np.ndarray
    bounces: np.ndarray
    tubes: int


def _per_material(materials, which, fn, *arrays):
    """``fn(material, *arrays)`` evaluated on the rays of each material, shape ``[ray, ...]``."""
    if which is None:
        return fn(materials, *arrays)
    out = None
    for m, mat in enumerate(materials):
        sel = which == m
        if not sel.any():
            continue
        res = fn(mat, *(a[sel] for a in arrays))
        res = res if isinstance(res, tuple) else (res,)
        if out is None:
            out = tuple(np.zeros((len(which),) + r.shape[1:], r.dtype) for r in res)
        for o, r in zip(out, res, strict=True):
            o[sel] = r
    return out if len(out) > 1 else out[0]


def _via_ground(scene, material, facet_material, ground, coherence, mirror, radar, range_m,
                k, e_pol, radiate, hit, first, x, lifted, d, e, n, a, b, which, width, path,
                spread):
    """Terms of target hits that return to the radar by a ground bounce (image method).

    The tube footprint radiates towards the radar's image ``mirror`` (its far
    field, as the direct return does towards the radar; the ground is not a
    radiating footprint, whose near-field weight would be wrong when the
    reflected beam is narrower than a Fresnel zone); the field is reflected by
    the ground material at the crossing point ``s`` (Fresnel, times
    ``coherence``), which must lie on the apron, with both legs unoccluded.
    """
    sel = np.flatnonzero(radiate)
    xs, ls = x[sel], lifted[sel]
    to_img = mirror - xs
    r_b = np.linalg.norm(to_img, axis=1)
    back = to_img / r_b[:, None]
    t, facet = scene.intersect(ls, back, r_b)
    ok = facet >= 0
    ok[ok] = ground[facet[ok]]
    sel, xs, ls, back, r_b, t, facet = (v[ok] for v in (sel, xs, ls, back, r_b, t, facet))
    s = ls + t[:, None] * back
    n_g = scene.normals[facet]
    n_g = n_g * -np.sign(np.einsum("ri,ri->r", n_g, back))[:, None]
    up = radar - s
    r_up = np.linalg.norm(up, axis=1)
    ok = scene.unoccluded(s + scene.epsilon * n_g, up / r_up[:, None], r_up)
    sel, back, r_b, facet, s, n_g = (v[ok] for v in (sel, back, r_b, facet, s, n_g))
    if not len(sel):
        return TubeTerms(np.zeros(0, complex), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0),
                         np.zeros((0, 3)), np.zeros(0, np.int64), 0)
    d_, e_, n_, a_, b_ = (v[sel] for v in (d, e, n, a, b))
    w = None if which is None else which[sel]
    vec = _per_material(material, w, po_vector, d_, e_, n_, np.ascontiguousarray(back))
    vec = vec - np.einsum("ri,ri->r", vec, back)[:, None] * back     # transverse far field
    gw = None if facet_material is None else facet_material[facet]
    _, vec = _per_material(material, gw, reflect, back, vec, n_g)
    if coherence is not None:
        vec = vec * coherence(np.abs(np.einsum("ri,ri->r", n_g, back)))[:, None]
    total = path[sel] + r_b
    amp = (range_m / path[sel]) * (range_m / r_b) * np.exp(-1j * k * (total - 2 * range_m))
    term = ((-1j * k / (4 * np.pi)) * (vec @ e_pol) * amp
            * _tube_integral(k * (back - d_), a_, b_, n_, d_, width[sel]) * spread[sel])
    return TubeTerms(term, first[sel], s, total, up[ok] / r_up[ok][:, None],
                     np.full(len(sel), hit + 1), 0)


def sbr_contributions(scene: RayScene, material, u: np.ndarray, e_pol: np.ndarray,
                      e_h: np.ndarray, e_v: np.ndarray, wavelength: float, *,
                      spacing: float, max_bounces: int, range_m: float | None = None,
                      facet_material: np.ndarray | None = None,
                      ground: np.ndarray | None = None, coherence=None,
                      cover: np.ndarray | None = None) -> TubeTerms:
    """The terms of :func:`sbr_amplitude`, one per tube and hit (same parameters).

    ``material`` is one :class:`PoMaterial`, or a sequence of them indexed by
    ``facet_material`` (shape ``[facet]`` of ``scene.mesh``) for a mesh of parts.

    ``ground`` (bool, shape ``[facet]``) marks facets of a ground apron: a term
    radiates nothing itself (its own bounces are the clutter's); tubes may hit it
    once before ``max_bounces`` target hits, and every target hit also returns
    to the radar by a ground bounce (:func:`_via_ground`: target-ground and
    ground-target-ground paths, ``bounces`` one more than the hit). Every
    reflection on it carries ``coherence(cos_i)`` (shape ``[ray]`` -> ``[ray]``,
    the rough surface's coherent share, e.g. the Ament factor; ``None`` = 1).
    ``cover`` (shape ``[point, 3]``) bounds the launch grid instead of the
    whole mesh (:func:`launch_grid`): a target and its ground image.
    """
    empty = TubeTerms(np.zeros(0, complex), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0),
                      np.zeros((0, 3)), np.zeros(0, np.int64), 0)
    if max_bounces < 2:
        return empty
    k = 2 * np.pi / wavelength
    xs, ys = _launch_axes(scene, u, e_h, e_v, spacing, range_m, cover)
    grid = _grid(xs, ys, e_h, e_v)
    ny = len(ys)
    lift = 2 * scene.mesh.radius + 1.0
    if range_m is None:
        d = np.broadcast_to(-u, grid.shape).copy()
        o = grid + lift * u
        path = np.full(len(grid), -lift)                     # unfolded length past u.r = 0
        domega = None
    else:
        radar = range_m * u
        rel = grid - radar
        rho = np.linalg.norm(rel, axis=1)
        d = rel / rho[:, None]
        o = np.broadcast_to(radar, grid.shape).copy()
        path = np.zeros(len(grid))                           # unfolded length from P
        domega = spacing**2 * (range_m / rho) / rho**2       # tube solid angle [sr]
    e = np.broadcast_to(e_pol.astype(complex), grid.shape).copy()
    tube = np.arange(len(grid))
    smooth = np.ones((len(grid), 2), bool)
    a = np.broadcast_to(e_h, grid.shape).copy()
    b = np.broadcast_to(e_v, grid.shape).copy()
    first = None
    out = []
    deepest = max_bounces
    if ground is not None:
        if range_m is None:
            raise ValueError("a ground apron needs the near field: give range_m")
        g0 = int(np.flatnonzero(ground)[0])
        n_g = scene.normals[g0]
        mirror = radar - 2 * ((radar - scene.mesh.triangles[g0][0]) @ n_g) * n_g
        hits = np.zeros(len(grid), np.int64)          # hits on the target so far
        deepest = max_bounces + 1                     # one ground hit before the target
    for hit in range(1, deepest + 1):
        t, facet = scene.intersect(o, d)
        keep = facet >= 0
        if not keep.any():
            break
        o, d, e, a, b, t, facet, path, tube = (x[keep] for x in (o, d, e, a, b, t, facet, path,
                                                                 tube))
        if domega is not None:
            domega = domega[keep]
        x = o + t[:, None] * d
        first = x if first is None else first[keep]
        path = path + t
        flat = scene.normals[facet]
        side = -np.sign(np.einsum("ri,ri->r", flat, d))[:, None]
        flat = flat * side
        lifted = x + scene.epsilon * flat
        n, spread = flat, np.ones(len(x), complex)
        if scene.curved:     # reflect as the smooth surface the facets sample
            n = scene.shading_normals(facet, x) * side
            n = np.where((np.einsum("ri,ri->r", n, d) < 0)[:, None], n, flat)
            spread = _spreading(tube, ny, x, d, a, b, flat, smooth,
                                spacing if domega is None else np.sqrt(domega) * path)
        which = None if facet_material is None else facet_material[facet]
        on_ground = None
        if ground is not None:
            on_ground = ground[facet]
            hits = hits[keep] + ~on_ground
        if hit >= 2 or ground is not None:
            if range_m is None:
                back = np.broadcast_to(u, x.shape)
                seen = scene.unoccluded(lifted, back)
                amp = np.exp(-1j * k * path) * np.exp(1j * k * (x @ u))
                width = spacing
                total = path - x @ u
            else:
                to_radar = radar - x
                r_b = np.linalg.norm(to_radar, axis=1)
                back = to_radar / r_b[:, None]
                seen = scene.unoccluded(lifted, back, r_b)
                amp = (range_m / path) * (range_m / r_b) * np.exp(-1j * k * (path + r_b
                                                                            - 2 * range_m))
                width = np.sqrt(domega) * path
                total = path + r_b
            if on_ground is not None:    # the ground radiates nothing itself
                radiate = ~on_ground & (hits <= max_bounces)
                seen &= radiate & (hit >= 2)
            if seen.any():
                vec = _per_material(material, which, po_vector, d, e, n,
                                    np.ascontiguousarray(np.broadcast_to(back, d.shape)))
                term = ((-1j * k / (4 * np.pi)) * (vec @ e_pol) * amp
                        * _tube_integral(k * (back - d), a, b, n, d, width) * spread)
                out.append(TubeTerms(term[seen], first[seen], x[seen], total[seen],
                                     np.array(back)[seen], np.full(int(seen.sum()), hit), 0))
            if on_ground is not None and radiate.any():
                out.append(_via_ground(scene, material, facet_material, ground, coherence,
                                       mirror, radar, range_m, k, e_pol, radiate, hit,
                                       first, x, lifted, d, e, n, a, b, which,
                                       np.sqrt(domega) * path, path, spread))
        d_new, e = _per_material(material, which, reflect, d, e, n)
        if on_ground is not None and coherence is not None and on_ground.any():
            rough = np.ones(len(facet))
            rough[on_ground] = coherence(np.abs(np.einsum("ri,ri->r", n[on_ground],
                                                          d[on_ground])))
            e = e * rough[:, None]
        a = a - 2 * np.einsum("ri,ri->r", a, n)[:, None] * n
        b = b - 2 * np.einsum("ri,ri->r", b, n)[:, None] * n
        d, o = d_new, lifted
    if not out:
        return TubeTerms(*(getattr(empty, f) for f in ("amplitude", "first", "last", "length",
                                                        "back", "bounces")), len(grid))
    return TubeTerms(*(np.concatenate([getattr(t, f) for t in out]) for f in (
        "amplitude", "first", "last", "length", "back", "bounces")), len(grid))
