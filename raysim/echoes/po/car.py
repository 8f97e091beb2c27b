"""A reproducible passenger-car mesh for PO + SBR: curved panels, glass, tyres.

Frame: ``x`` forward, ``y`` left, ``z`` up, ground at ``z = 0``, the car's
footprint centred on the origin [m]. The body is lofted from superellipse
cross-sections (rounded corners, tumblehome) along the length, so its panels
are curved in both directions; the cabin's windscreen, side and rear windows
are glass and its roof metal; four tyres (rubber) with metal wheel discs.
Facets are about 5 cm: below ``sqrt(lambda r)`` of the body's crowned panels
(radii of curvature above 1 m at 77 GHz), so facet glints do not replace the
panels' specular points; the PO solver subdivides further to its Fresnel length.

RCS at 77 GHz (``raysim.echoes.po.paths.scattering_terms``, docs/scattering.md)
is compared with published measurements of passenger cars: 10-20 dBsm typical
over aspect and up to about 30 dBsm at broadside and the front/rear specular
aspects (Schipper et al., "Simulative prediction of the RCS of vehicles at
77 GHz", 2015; Kamel, Peden & Pitts, "RCS modeling and measurements of
automotive targets at 77 GHz", IEEE RadarConf 2017; Buddendick & Eibert,
"Bistatic image formation from shooting and bouncing rays simulated current
distributions", PIER 2010).
"""

from __future__ import annotations

import math

import numpy as np

from raysim.echoes.po.mesh import TriangleMesh

__all__ = ["car_parts", "CAR_FACET"]

#: Target facet size of the generated car [m].
CAR_FACET = 0.05


def _superellipse(m: int, exponent: float) -> tuple[np.ndarray, np.ndarray]:
    """Unit superellipse ``|y|^e + |z|^e = 1`` sampled at ``m`` angles (counter-clockwise)."""
    t = np.linspace(0.0, 2 * np.pi, m, endpoint=False)
    c, s = np.cos(t), np.sin(t)
    return (np.sign(c) * np.abs(c) ** (2 / exponent), np.sign(s) * np.abs(s) ** (2 / exponent))


def _loft(x: np.ndarray, half_w: np.ndarray, z_lo: np.ndarray, z_hi: np.ndarray, m: int,
          exponent: float, top_scale: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Closed loft through superellipse rings at stations ``x``; ends closed by fans.

    ``top_scale`` [station] narrows the upper half of each ring (tumblehome).
    Returns vertices ``[v, 3]`` and faces ``[f, 3]`` with outward normals.
    """
    cy, cz = _superellipse(m, exponent)
    rings = []
    for i, xi in enumerate(x):
        zc, hz = (z_lo[i] + z_hi[i]) / 2, (z_hi[i] - z_lo[i]) / 2
        scale = np.ones(m) if top_scale is None else np.where(cz > 0, 1 - (1 - top_scale[i])
                                                              * cz, 1.0)
        rings.append(np.stack([np.full(m, xi), half_w[i] * scale * cy, zc + hz * cz], axis=1))
    v = np.concatenate(rings + [np.array([[x[0], 0.0, (z_lo[0] + z_hi[0]) / 2],
                                          [x[-1], 0.0, (z_lo[-1] + z_hi[-1]) / 2]])])
    n = len(x)
    idx = np.arange(n * m).reshape(n, m)
    a, b = idx[:-1], np.roll(idx[:-1], -1, axis=1)
    c, d = np.roll(idx[1:], -1, axis=1), idx[1:]
    faces = [np.stack([a.ravel(), b.ravel(), c.ravel()], 1),
             np.stack([a.ravel(), c.ravel(), d.ravel()], 1)]
    back, front = n * m, n * m + 1
    ring0, ring1 = idx[0], idx[-1]
    faces.append(np.stack([np.full(m, back), np.roll(ring0, -1), ring0], 1))
    faces.append(np.stack([np.full(m, front), ring1, np.roll(ring1, -1)], 1))
    f = np.concatenate(faces)
    # outward: the signed volume of the closed surface must be positive
    t = v[f]
    vol = np.einsum("fi,fi->f", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum()
    return v, (f if vol > 0 else f[:, ::-1])


def _stations(lo: float, hi: float, step: float) -> np.ndarray:
    """Stations from ``lo`` to ``hi``, at most ``step`` apart."""
    return np.linspace(lo, hi, max(3, int(math.ceil((hi - lo) / step)) + 1))


def car_parts(length: float = 4.5, width: float = 1.8, height: float = 1.45) -> list[tuple[
        str, TriangleMesh, str]]:
    """The parts of a hatchback/sedan-like car: ``(name, mesh, material)``.

    Parameters
    ----------
    length, width, height : float
        Overall size [m] (about 3.5-5.5, 1.5-2.1, 1.2-1.9).

    Returns
    -------
    list of (str, TriangleMesh, str)
        ``body`` (metal), ``roof`` (metal), ``glass`` (glass), ``tyres``
        (rubber), ``wheels`` (metal).

    Raises
    ------
    ValueError
        Sizes outside the ranges above.
    """
    for name, value, lo, hi in (("length", length, 3.5, 5.5), ("width", width, 1.5, 2.1),
                                ("height", height, 1.2, 1.9)):
        if not (isinstance(value, (int, float)) and lo <= value <= hi):
            raise ValueError(f"car {name} must lie in [{lo}, {hi}] m, got {value!r}")
    h = length / 2
    step = CAR_FACET
    ring = int(math.ceil(2 * (width + height) / step / 8)) * 8
    # lower body: bumper to bumper, rounded in plan view and side view
    x = _stations(-h, h, step)
    s = np.abs(x) / h
    round_end = np.sqrt(np.clip(1 - np.clip((s - 0.85) / 0.15, 0, 1) ** 2, 0.05, 1))
    half_w = width / 2 * round_end
    z_lo = np.full_like(x, 0.22)
    belt = 0.62 * height
    z_hi = np.where(x > 0, belt - 0.10 * (x / h) ** 2, belt - 0.04 * (x / h) ** 2)
    z_hi = np.maximum(z_lo + 0.1, z_lo + (z_hi - z_lo) * np.sqrt(round_end))
    body_v, body_f = _loft(x, half_w, z_lo, z_hi, ring, 5.0)
    # cabin: windscreen, roof, rear window over the belt line; tumblehome 15 %
    xc = _stations(-0.62 * h, 0.45 * h, step)
    front, rear = 0.45 * h, -0.62 * h
    roof_front, roof_rear = 0.0, -0.35 * h
    top = np.interp(xc, [rear, roof_rear, roof_front, front],
                    [belt + 0.05, height, height, belt + 0.05])
    top = top + 0.03 * np.cos(np.pi * np.clip((xc - (roof_front + roof_rear) / 2)
                                              / (roof_front - roof_rear), -0.5, 0.5))
    cab_v, cab_f = _loft(xc, np.full_like(xc, width / 2 * 0.92), np.full_like(xc, belt - 0.1),
                         top, ring, 4.0, top_scale=np.full_like(xc, 0.80))
    cab_tri = cab_v[cab_f]
    cent = cab_tri.mean(axis=1)
    nrm = np.cross(cab_tri[:, 1] - cab_tri[:, 0], cab_tri[:, 2] - cab_tri[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    is_roof = ((nrm[:, 2] > 0.9) & (cent[:, 0] > roof_rear - 0.05)
               & (cent[:, 0] < roof_front + 0.05))
    is_glass = ~is_roof & (cent[:, 2] > belt + 0.02)
    parts = [("body", TriangleMesh(body_v, body_f), "metal")]
    parts.append(("roof", TriangleMesh(cab_v, cab_f[is_roof | ~is_glass]), "metal"))
    parts.append(("glass", TriangleMesh(cab_v, cab_f[is_glass]), "glass"))
    # tyres (rubber) and wheel discs (metal) on the outer face of each tyre
    import trimesh

    tyres, discs = [], []
    radius, tyre_w = 0.32, 0.21
    for wx in (0.62 * h, -0.62 * h):
        for side in (1.0, -1.0):
            centre = np.array([wx, side * (width / 2 - tyre_w / 2 - 0.02), radius])
            cyl = trimesh.creation.cylinder(radius=radius, height=tyre_w, sections=40)
            cyl.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
            cyl.apply_translation(centre)
            tyres.append(cyl)
            disc = trimesh.creation.cylinder(radius=0.2, height=0.01, sections=40)
            disc.apply_transform(trimesh.transformations.rotation_matrix(np.pi / 2, [1, 0, 0]))
            disc.apply_translation(centre + [0.0, side * (tyre_w / 2 + 0.005), 0.0])
            discs.append(disc)
    ty, di = trimesh.util.concatenate(tyres), trimesh.util.concatenate(discs)
    parts.append(("tyres", TriangleMesh(np.asarray(ty.vertices), np.asarray(ty.faces)), "rubber"))
    parts.append(("wheels", TriangleMesh(np.asarray(di.vertices), np.asarray(di.faces)),
                  "metal"))
    return parts
