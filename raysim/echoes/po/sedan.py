"""A detailed procedural passenger car (sedan) for PO + SBR: arches, wheels, mirrors, plates.

Frame: ``x`` forward, ``y`` left, ``z`` up, ground at ``z = 0``, the car's
footprint centred on the origin [m] (as :func:`raysim.echoes.po.car.car_parts`).

The body is lofted along ``x`` through cross-sections of a fixed number of
points, each section (left half, mirrored) running from the floor's centre line

* along the floor, over the **undercarriage tunnel** (a 0.4 m wide, 0.12 m
  deep channel between the axles: an open cavity under the car),
* into the **wheel house** (a notch: inner wall ``0.30 m`` inside the body's
  side, top on the arch circle of radius ``ARCH_RADIUS`` about the axle: an
  open cavity around the tyre),
* up the **side**, crowned with a vertical radius of curvature ``SIDE_RADIUS``
  and in plan view with ``PLAN_RADIUS`` (doors are doubly curved),
* over the shoulder, the **side glass** (tumblehome) and the roof rail, to the
  **roof** (or the hood and the boot lid, where the greenhouse collapses),
  crowned across with ``ROOF_RADIUS``.

Ends: elliptic in plan view (nose radius about 1.6 m, tail about 2.0 m) and
set back above and below the bumper line (vertical radius ``NOSE_RADIUS``), so
no flat panel faces the front or the rear. The roof line (hood, raked
windscreen, roof, rear window, boot) and the belt line are monotone cubic
(PCHIP) curves through fixed points, so the panels have no creases but the
designed ones (arch edges, shoulder, roof rail).

Materials: ``body`` metal (painted steel), ``glass`` (windscreen, side and rear
windows; ITU-R P.2040 glass, a dielectric: ``|Gamma| = -7.3 dB`` at normal
incidence), ``tyres`` rubber, ``rims`` metal (a dish recessed 7 cm into the
tyre: a ring-shaped cavity), ``bumpers`` metal (a rub strip round each end,
standing 3 cm proud: the bumper beam that a plastic fascia hides is what
reflects at 77 GHz), ``plates`` metal (aluminium licence plates, 520 x 110 mm,
tilted 5 deg back), ``mirrors`` metal (housings and their silvered glass).

Nose (``openings``): two **grille** openings (``GRILLE_Y`` x ``GRILLE_Z``
either side of a 12 cm centre bar) cut in the body, each a recess whose walls
are the plastic air **ducts** and whose back is the **radiator**, a flat metal
plate ``RADIATOR_DEPTH`` behind the opening, with two round-edged metal (chromed)
**slats** across it; two **headlamp** openings at the nose's corners, each a
recess whose walls are the plastic **lamp housing** and whose back is a metal
**paraboloid reflector** of focal length ``HEADLAMP_FOCAL``, axis forward (the
polycarbonate lens in front, nearly transparent at 77 GHz, is left out: the
tracer does not transmit). The recesses close the body again: ``body``,
``glass``, ``radiator``, ``ducts``, ``headlamps`` and ``lamp_housings`` are one
closed surface. The radiator core is fins and tubes, part of which the wave
enters; a flat plate is the upper bound of its reflection.

Facets: about ``facet`` along the body and across its sections (default
:data:`SEDAN_FACET`, 5 cm, below the Fresnel size ``sqrt(lambda r)`` of panels
of radius ``r > 0.7 m`` at 77 GHz: the facets do not glint on their own); the
default car has about 41 000 facets (7 000 of them the headlamp reflectors, faceted
at 6 mm), a 0.15 m car about 8 500 (for fast tests; above
``OPENINGS_MAX_FACET`` the loft has too few quads for the openings and the nose
stays closed).
The mesh is deterministic (no random numbers). Each part is closed (the lofted
body, revolved tyres and rims, swept bumpers, boxes) except where two parts
touch.
"""

from __future__ import annotations

import math

import numpy as np

from raysim.echoes.po.mesh import TriangleMesh

__all__ = ["sedan_parts", "SEDAN_FACET", "ARCH_RADIUS", "TYRE_RADIUS", "SIDE_RADIUS",
           "PLAN_RADIUS", "ROOF_RADIUS", "NOSE_RADIUS", "GRILLE_Y", "GRILLE_Z", "RADIATOR_DEPTH",
           "HEADLAMP_Y", "HEADLAMP_Z", "HEADLAMP_FOCAL", "OPENINGS_MAX_FACET"]

#: Default facet size of the detailed car [m].
SEDAN_FACET = 0.05
#: Tyre outer radius [m] (205/55 R16: 0.316 m).
TYRE_RADIUS = 0.316
#: Tyre width [m].
TYRE_WIDTH = 0.205
#: Wheel-arch radius about the axle [m] (tyre plus a 6 cm gap).
ARCH_RADIUS = 0.38
#: Vertical radius of curvature of the sides (door crown) [m].
SIDE_RADIUS = 3.0
#: Plan-view radius of curvature of the sides between the wheels [m].
PLAN_RADIUS = 30.0
#: Transverse radius of curvature of the roof, hood and boot lid [m].
ROOF_RADIUS = 4.0
#: Vertical radius of curvature of the nose and the tail about the bumper line [m].
NOSE_RADIUS = 1.0
#: Height of the bumper line (most forward point of the nose) [m].
BUMPER_Z = 0.50
#: Floor height under the sills [m].
FLOOR_Z = 0.16
#: Inward depth of the wheel houses from the side [m].
WHEEL_HOUSE_DEPTH = 0.30
#: Undercarriage tunnel: half-width and depth [m].
TUNNEL_HALF_WIDTH, TUNNEL_DEPTH = 0.20, 0.12
#: Grille openings in the nose, left of the centre line (the right one is the mirror
#: image; a 12 cm bar stays between them): bounds of ``y`` and ``z`` [m].
GRILLE_Y, GRILLE_Z = (0.06, 0.40), (0.44, 0.66)
#: Depth of the radiator (a flat metal plate) behind the grille opening's rim, from the
#: rim's rearmost point [m].
RADIATOR_DEPTH = 0.25
#: Height of the grille slats (round-edged bars across each opening) [m].
SLAT_Z = (0.51, 0.59)
#: Headlamp openings at the nose's corners, left (the right is the mirror image) [m].
HEADLAMP_Y, HEADLAMP_Z = (0.50, 0.74), (0.56, 0.70)
#: Focal length of the headlamp reflectors (metal paraboloids, axis forward) [m].
HEADLAMP_FOCAL = 0.025
#: Coarsest facet that still cuts the openings [m]: a coarser loft has too few quads in
#: the windows, and its nose stays closed (a car for quick checks only).
OPENINGS_MAX_FACET = 0.08
#: Facet of the reflectors [m]: below the Fresnel size ``sqrt(lambda 2 F)`` (1.4 cm at
#: 77 GHz) of their curvature.
REFLECTOR_FACET = 0.006


def _pchip(xp, yp):
    from scipy.interpolate import PchipInterpolator

    return PchipInterpolator(np.asarray(xp, float), np.asarray(yp, float))


def _segment(p0, p1, n: int) -> np.ndarray:
    """``n`` points ``[n, 2]`` from ``p0`` towards ``p1``, ``p1`` left out (the next segment's)."""
    t = np.linspace(0.0, 1.0, n + 1)[:-1]
    return np.asarray(p0)[None] + t[:, None] * (np.asarray(p1) - np.asarray(p0))[None]


class _Design:
    """Lines of the car (plan, belt, roof, arches) for one size."""

    def __init__(self, length: float, width: float, height: float, facet: float):
        self.length, self.width, self.height, self.facet = length, width, height, facet
        h = self.h = length / 2
        s = length / 4.5                                   # control points scale with length
        self.front_end, self.rear_end = h - 0.50 * s, -h + 0.40 * s
        self.axles = (h - 0.90 * s, -h + 0.90 * s)
        # roof line (centre of the roof, hood and boot lid) and belt line
        self.top = _pchip([-h, -h + 0.45 * s, -1.05 * s, -0.35 * s, 0.25 * s, 0.95 * s,
                           h - 0.35 * s, h],
                          [0.98, 1.02, height - 0.36, height - 0.01, height, 0.96, 0.86, 0.76])
        self.belt = _pchip([-h, -h + 0.5 * s, 0.0, h - 0.6 * s, h],
                           [0.88, 0.92, 0.90, 0.84, 0.70])
        self.cabin = (-1.45 * s, 0.95 * s)                 # rear window foot .. windscreen foot
        self.roof_span = (-0.45 * s, 0.30 * s)
        self.b_pillar = -0.10 * s

    def plan(self, x: np.ndarray) -> np.ndarray:
        """Plan-view half-width factor in (0, 1]: elliptic ends, crowned between."""
        x = np.asarray(x, float)
        u = np.where(x > self.front_end, (x - self.front_end) / (self.h - self.front_end),
                     np.where(x < self.rear_end, (self.rear_end - x) / (self.rear_end + self.h),
                              0.0))
        crown = 1.0 - np.minimum(x**2, self.front_end**2) / (2 * PLAN_RADIUS * self.width / 2)
        return crown * np.sqrt(np.clip(1.0 - np.clip(u, 0, 1) ** 2, 0.0025, 1.0))

    def floor(self, x: np.ndarray) -> np.ndarray:
        """Floor height: rises towards the ends (approach and departure angles) [m]."""
        x = np.asarray(x, float)
        u = np.clip(np.maximum((x - self.axles[0]) / (self.h - self.axles[0]),
                               (self.axles[1] - x) / (self.axles[1] + self.h)), 0, 1)
        return FLOOR_Z + 0.18 * u**2

    def arch(self, x: np.ndarray) -> np.ndarray:
        """Top of the wheel house [m]: the arch circle near an axle, else the floor."""
        x = np.asarray(x, float)
        z = self.floor(x)
        for ax in self.axles:
            dx = np.abs(x - ax)
            inside = dx <= ARCH_RADIUS
            z = np.where(inside, TYRE_RADIUS + np.sqrt(np.clip(ARCH_RADIUS**2 - dx**2, 0, None)), z)
        return z

    def tunnel(self, x: np.ndarray) -> np.ndarray:
        """Depth of the undercarriage tunnel (between the axles, fading over 0.3 m) [m]."""
        x = np.asarray(x, float)
        lo, hi = self.axles[1] + ARCH_RADIUS, self.axles[0] - ARCH_RADIUS
        ramp = np.clip(np.minimum(x - lo, hi - x) / 0.3, 0, 1)
        return TUNNEL_DEPTH * ramp

    def stations(self) -> np.ndarray:
        """Loft stations: about ``facet`` apart, denser at the ends, exact at the arch edges."""
        h, f = self.h, self.facet
        mid = np.linspace(self.rear_end, self.front_end,
                          max(3, int(math.ceil((self.front_end - self.rear_end) / f)) + 1))
        ends = []
        for a, b in ((self.front_end, h), (self.rear_end, -h)):
            n = max(4, int(math.ceil(abs(b - a) * math.pi / 2 / f)))
            ends.append(a + (b - a) * np.sin(np.linspace(0, np.pi / 2, n + 1))[1:])
        arch = [ax + d for ax in self.axles for d in (-ARCH_RADIUS - 0.01, -ARCH_RADIUS,
                                                      ARCH_RADIUS, ARCH_RADIUS + 0.01)]
        x = np.unique(np.round(np.concatenate([mid, *ends, arch]), 6))
        # drop stations closer than 5 mm to an arch edge (the edges are kept)
        keep = np.ones(len(x), bool)
        for a in arch:
            keep &= ~((np.abs(x - a) < 0.005) & (np.abs(x - a) > 1e-9))
        return x[keep]

    def section(self, x: float, counts: dict) -> tuple[np.ndarray, list]:
        """Left half of the section at ``x``: points ``[p, 2]`` (y, z) and segment labels."""
        w2 = self.width / 2 * float(self.plan(x))
        zf, za = float(self.floor(x)), float(self.arch(x))
        zb = float(self.belt(x))
        zt = float(self.top(x))
        z_tunnel = float(self.floor(x)) + float(self.tunnel(x))

        def side_y(z):
            return w2 - (z - 0.55) ** 2 / (2 * SIDE_RADIUS)

        y_in = max(0.05, min(w2 - WHEEL_HOUSE_DEPTH, side_y(za) - 0.02))
        y_tun = min(TUNNEL_HALF_WIDTH, 0.6 * y_in)
        pts, labels = [], []

        def add(p, label):
            pts.append(np.atleast_2d(p))
            labels.extend([label] * len(np.atleast_2d(p)))

        add(_segment((0.0, z_tunnel), (y_tun, z_tunnel), counts["tunnel"]), "floor")
        add(_segment((y_tun, z_tunnel), (y_tun + 0.04, zf), 1), "floor")
        add(_segment((y_tun + 0.04, zf), (y_in, zf), counts["floor"]), "floor")
        add(_segment((y_in, zf), (y_in, za), counts["house"]), "house")
        add(_segment((y_in, za), (side_y(za), za), 2), "house")
        z_side = np.linspace(za, zb, counts["side"] + 1)[:-1]
        add(np.stack([side_y(z_side), z_side], 1), "side")
        y_b = side_y(zb)
        add((y_b, zb), "side")
        y_gb, z_gb = y_b - 0.05, zb + 0.03
        y_rail = y_gb - 0.22 * max(0.0, zt - zb - 0.1)
        y_rail = min(y_rail, y_gb)
        z_edge = max(zt - y_rail**2 / (2 * ROOF_RADIUS), z_gb + 0.005)
        zt = z_edge + y_rail**2 / (2 * ROOF_RADIUS)
        add((y_b - 0.025, zb + 0.02), "shoulder")
        add(_segment((y_gb, z_gb), (y_rail + 0.01, z_edge - 0.02), counts["glass"]), "glass")
        add((y_rail, z_edge), "rail")
        y_roof = np.linspace(y_rail, 0.0, counts["roof"] + 1)[1:]
        add(np.stack([y_roof, zt - y_roof**2 / (2 * ROOF_RADIUS)], 1), "roof")
        return np.concatenate(pts), labels


def _ring_faces(n_st: int, m: int) -> np.ndarray:
    idx = np.arange(n_st * m).reshape(n_st, m)
    a, b = idx[:-1], np.roll(idx[:-1], -1, axis=1)
    c, d = np.roll(idx[1:], -1, axis=1), idx[1:]
    return np.concatenate([np.stack([a.ravel(), b.ravel(), c.ravel()], 1),
                           np.stack([a.ravel(), c.ravel(), d.ravel()], 1)])


def _outward(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Faces of a closed surface turned so that its signed volume is positive."""
    t = v[f]
    vol = np.einsum("fi,fi->f", t[:, 0], np.cross(t[:, 1], t[:, 2])).sum()
    return f if vol > 0 else f[:, ::-1]


def _body(design: _Design, openings: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lofted body: vertices, faces and each face's label (``"metal"``, ``"glass"``, and
    with ``openings`` ``"ducts"``, ``"radiator"``, ``"lamp_housings"``, ``"headlamps"``)."""
    f = design.facet
    w = design.width
    counts = {"tunnel": max(2, math.ceil(TUNNEL_HALF_WIDTH / f)),
              "floor": max(2, math.ceil((w / 2 - WHEEL_HOUSE_DEPTH - TUNNEL_HALF_WIDTH) / f)),
              "house": max(2, math.ceil(0.5 / f)),
              "side": max(4, math.ceil(0.8 / f)),
              "glass": max(3, math.ceil(0.45 / f)),
              "roof": max(4, math.ceil(0.75 / f))}
    xs = design.stations()
    halves = [design.section(x, counts) for x in xs]
    labels = np.array(halves[0][1])
    half = np.stack([h[0] for h in halves])                 # [station, p, 2]
    # full ring: left half (floor centre to roof centre), then the right half
    # mirrored back from the roof to the floor, without the two centre-line points
    right = half[:, -2:0:-1] * np.array([-1.0, 1.0])
    ring = np.concatenate([half, right], axis=1)           # [station, m, 2]
    ring_labels = np.concatenate([labels, labels[-2:0:-1]])
    m = ring.shape[1]
    v = np.concatenate([np.repeat(xs, m)[:, None], ring.reshape(-1, 2)], axis=1)
    # nose and tail set back above and below the bumper line (vertical curvature)
    weight = np.clip(np.maximum((v[:, 0] - design.front_end) / (design.h - design.front_end),
                                (design.rear_end - v[:, 0]) / (design.rear_end + design.h)),
                     0, 1) ** 2
    v[:, 0] -= np.sign(v[:, 0]) * weight * (v[:, 2] - BUMPER_Z) ** 2 / (2 * NOSE_RADIUS)
    faces = _ring_faces(len(xs), m)
    # end caps: fans to each end ring's centroid
    n_v = len(v)
    caps_v, caps_f = [], []
    for k, st in enumerate((0, len(xs) - 1)):
        ids = np.arange(st * m, (st + 1) * m)
        caps_v.append(v[ids].mean(axis=0))
        centre = n_v + k
        caps_f.append(np.stack([np.full(m, centre), np.roll(ids, -1), ids], 1))
    v = np.concatenate([v, np.array(caps_v)])
    faces = np.concatenate([faces] + caps_f)                # turned outward below
    # materials: each loft face by its section segment and station
    n_loft = (len(xs) - 1) * m * 2
    j = np.concatenate([np.tile(np.arange(m), len(xs) - 1)] * 2)
    i = np.concatenate([np.repeat(np.arange(len(xs) - 1), m)] * 2)
    x_mid = (xs[i] + xs[i + 1]) / 2
    seg = ring_labels[j]
    tall = design.top(x_mid) - design.belt(x_mid) > 0.25
    cabin = (x_mid > design.cabin[0]) & (x_mid < design.cabin[1])
    pillar = np.abs(x_mid - design.b_pillar) < 0.05
    y_abs = np.abs(ring[i, j, 0])
    roof_metal = (x_mid > design.roof_span[0]) & (x_mid < design.roof_span[1])
    glass_side = (seg == "glass") & tall & cabin & ~pillar
    rail_y = half[:, list(labels).index("rail"), 0]                  # [station]
    screen = (seg == "roof") & cabin & ~roof_metal & (y_abs < np.minimum(
        rail_y[i], rail_y[i + 1]) - 0.08)                              # A/C pillars 8 cm
    material = np.full(len(faces), "metal", dtype=object)
    material[:n_loft][glass_side | screen] = "glass"
    # openings in the nose: the loft's quads inside each window are cut and the
    # hole's rim is extruded back to the radiator or to a headlamp reflector
    grid = v[:len(xs) * m].reshape(len(xs), m, 3)
    side_seg = ring_labels == "side"
    keep = np.ones(len(faces), bool)
    new_v, new_f, new_mat = [], [], []
    windows = [(GRILLE_Y, GRILLE_Z, ("ducts", "radiator"), None),
               (HEADLAMP_Y, HEADLAMP_Z, ("lamp_housings", "headlamps"), HEADLAMP_FOCAL)]
    for (y_rng, z_rng, names, focal) in windows if openings and f <= OPENINGS_MAX_FACET else ():
        for sign in (1.0, -1.0):
            quads = _window(grid, side_seg, sign, y_rng, z_rng)
            if not quads.any():
                continue
            keep[:n_loft] &= ~np.tile(quads.ravel(), 2)
            loop = _rim(quads, m)
            rv, walls, back = _recess(v[loop], loop, len(v) + sum(len(a) for a in new_v),
                                      focal)
            new_v.append(rv)
            new_f += [walls, back]
            new_mat += [np.full(len(walls), names[0], dtype=object),
                        np.full(len(back), names[1], dtype=object)]
    v = np.concatenate([v, *new_v])
    faces = _outward(v, np.concatenate([faces[keep], *new_f]))
    material = np.concatenate([material[keep], *new_mat])
    return v, faces, material


def _window(grid: np.ndarray, side_seg: np.ndarray, sign: float, y_rng, z_rng) -> np.ndarray:
    """Loft quads ``[station - 1, m]`` of the nose's sides whose corners all lie in a window."""
    y, z, x = sign * grid[..., 1], grid[..., 2], grid[..., 0]
    inside = (y >= y_rng[0]) & (y <= y_rng[1]) & (z >= z_rng[0]) & (z <= z_rng[1]) & (x > 0)
    nxt = np.roll(inside, -1, axis=1)
    seg = side_seg & np.roll(side_seg, -1)
    return inside[:-1] & nxt[:-1] & inside[1:] & nxt[1:] & seg[None]


def _rim(quads: np.ndarray, m: int) -> np.ndarray:
    """Vertex ids of the rim of a set of loft quads, in the quads' winding (one loop)."""
    n_st = quads.shape[0] + 1
    idx = np.arange(n_st * m).reshape(n_st, m)
    edges = set()
    for i, j in zip(*np.nonzero(quads), strict=True):
        a, b = idx[i, j], idx[i, (j + 1) % m]
        c, d = idx[i + 1, (j + 1) % m], idx[i + 1, j]
        edges |= {(a, b), (b, c), (c, d), (d, a)}
    nxt = {p: q for p, q in edges if (q, p) not in edges}
    start = min(nxt)
    loop = [start]
    while nxt[loop[-1]] != start:
        loop.append(nxt[loop[-1]])
        if len(loop) > len(nxt):
            break
    if len(loop) != len(nxt):
        raise RuntimeError("a nose opening's rim is not one loop; change its window")
    return np.array(loop)


def _recess(front: np.ndarray, loop: np.ndarray, base: int,
            focal: float | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A recess behind a rim: walls along ``-x`` and a back, flat or a paraboloid.

    ``front`` ``[k, 3]`` are the rim's points (ids ``loop``, in the winding of the
    cut quads); new vertices get ids from ``base``. ``focal`` None: a flat back
    :data:`RADIATOR_DEPTH` behind the rim's rearmost point; else a paraboloid of
    that focal length [m], axis ``+x`` through the rim's centre, its rim behind the
    opening. Returns the new vertices, the walls' faces and the back's faces.
    """
    yz = front[:, 1:]
    centre = yz.mean(axis=0)
    if focal is None:
        pieces = np.ones(len(front), int)
    else:
        step = np.linalg.norm(np.roll(yz, -1, axis=0) - yz, axis=1)
        pieces = np.maximum(1, np.ceil(step / REFLECTOR_FACET).astype(int))
    # the back's rim: each rim edge split into ``pieces`` (rim point k at ring[first[k]])
    first = np.concatenate([[0], np.cumsum(pieces)[:-1]])
    ring = np.concatenate([yz[k] + np.linspace(0, 1, p, endpoint=False)[:, None]
                           * (yz[(k + 1) % len(yz)] - yz[k]) for k, p in enumerate(pieces)])
    r2_max = np.max(np.sum((ring - centre) ** 2, axis=1))
    if focal is None:
        n_rings = 1

        def depth(q):
            return np.full(len(q), front[:, 0].min() - RADIATOR_DEPTH)
    else:
        n_rings = max(1, int(math.ceil(math.sqrt(r2_max) / REFLECTOR_FACET)))
        vertex = front[:, 0].min() - 0.01 - r2_max / (4 * focal)

        def depth(q):
            return vertex + np.sum((q - centre) ** 2, axis=1) / (4 * focal)
    n = len(ring)
    # rings of the back from its rim (k = n_rings) in to the centre, then the centre
    rings = [centre + (ring - centre) * (k / n_rings) for k in range(n_rings, 0, -1)]
    pts = np.concatenate(rings + [centre[None]])
    verts = np.concatenate([depth(pts)[:, None], pts], axis=1)
    faces = []
    for k, p in enumerate(pieces):                        # walls: fan from the front point
        b = base + first[k] + np.arange(p + 1)
        b[-1] = base + (first[k] + p) % n
        faces.append([loop[k], loop[(k + 1) % len(loop)], b[-1]])
        faces.extend([loop[k], b[t + 1], b[t]] for t in range(p))
    walls, faces = np.asarray(faces, dtype=np.int64), []
    for k in range(n_rings - 1):                          # back: ring k (outer) to k + 1
        o = base + k * n + np.arange(n)
        i = o + n
        o1, i1 = np.roll(o, -1), np.roll(i, -1)
        faces.extend(np.stack([o, o1, i1], 1).tolist())
        faces.extend(np.stack([o, i1, i], 1).tolist())
    last = base + (n_rings - 1) * n + np.arange(n)
    faces.extend(np.stack([last, np.roll(last, -1), np.full(n, base + n_rings * n)],
                          1).tolist())
    return verts, walls, np.asarray(faces, dtype=np.int64)


def _revolve(profile: np.ndarray, sections: int) -> tuple[np.ndarray, np.ndarray]:
    """Closed solid of revolution of a closed ``(r, a)`` profile about the ``a`` axis (trimesh)."""
    import trimesh

    loop = np.concatenate([profile, profile[:1]])
    m = trimesh.creation.revolve(loop, sections=sections)
    return np.asarray(m.vertices), np.asarray(m.faces)


def _wheels(design: _Design) -> tuple[tuple, tuple]:
    """Four tyres (rubber) and rims (metal): ``((v, f), (v, f))``."""
    r, half = TYRE_RADIUS, TYRE_WIDTH / 2
    bead, c = 0.205, 0.035
    arc = np.linspace(0, np.pi / 2, 4)
    # tyre cross-section (r, a): tread with rounded shoulders, sidewalls down to the bead
    out_sh = np.stack([r - c + c * np.cos(arc), half - c + c * np.sin(arc)], 1)
    in_sh = np.stack([r - c + c * np.cos(arc), -(half - c) - c * np.sin(arc)], 1)[::-1]
    tyre = np.concatenate([[[bead, -half + 0.01]], in_sh, out_sh, [[bead, half - 0.01]]])
    tyre = tyre[::-1]
    # rim: a dish recessed into the tyre (hub face 7 cm in from the outer sidewall)
    rim = np.array([[0.0, half - 0.075], [0.06, half - 0.07], [0.15, half - 0.045],
                    [bead, half - 0.012], [bead, -half + 0.012], [0.0, -half + 0.04]])
    sections = max(24, int(math.ceil(2 * math.pi * r / (1.5 * design.facet))))
    sections = min(sections, 48)
    tv, tf = _revolve(tyre, sections)
    rv, rf = _revolve(rim[::-1], sections)
    out_t, out_r = [], []
    for ax in design.axles:
        for side in (1.0, -1.0):
            y0 = side * (design.width / 2 * float(design.plan(ax)) - half - 0.035)
            for (vv, ff), out in (((tv, tf), out_t), ((rv, rf), out_r)):
                # revolve axis z -> y (outer face towards +-y), centre at the axle
                p = np.stack([vv[:, 0], side * vv[:, 2], vv[:, 1]], 1) + [ax, y0, r]
                fo = ff if side > 0 else ff[:, ::-1]
                out.append((p, _outward(p, fo)))
    return _join(out_t), _join(out_r)


def _join(items) -> tuple[np.ndarray, np.ndarray]:
    v, f, off = [], [], 0
    for vv, ff in items:
        v.append(vv)
        f.append(ff + off)
        off += len(vv)
    return np.concatenate(v), np.concatenate(f)


def _box(centre, size, rot=None) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    m = trimesh.creation.box(extents=size)
    v = np.asarray(m.vertices)
    if rot is not None:
        v = v @ np.asarray(rot).T
    return v + np.asarray(centre), np.asarray(m.faces)


def _rot_y(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _sweep(path: np.ndarray, half_out: float, half_up: float, z: float,
           m: int = 12) -> tuple[np.ndarray, np.ndarray]:
    """A rounded bar swept along a plan-view path ``[n, 2]`` at height ``z`` (closed ends)."""
    t = np.gradient(path, axis=0)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    nrm = np.stack([t[:, 1], -t[:, 0]], 1)                 # right of the path direction
    a = np.linspace(0, 2 * np.pi, m, endpoint=False)
    cy, cz = np.cos(a), np.sin(a)
    cy = np.sign(cy) * np.abs(cy) ** 0.5
    cz = np.sign(cz) * np.abs(cz) ** 0.5                    # superellipse, exponent 4
    rings = [np.stack([p[0] + half_out * cy * q[0], p[1] + half_out * cy * q[1],
                       z + half_up * cz], 1) for p, q in zip(path, nrm, strict=True)]
    v = np.concatenate(rings)
    f = _ring_faces(len(path), m)
    ends = len(v)
    v = np.concatenate([v, rings[0].mean(0)[None], rings[-1].mean(0)[None]])
    first, last = np.arange(m), np.arange((len(path) - 1) * m, len(path) * m)
    f = np.concatenate([f, np.stack([np.full(m, ends), np.roll(first, -1), first], 1),
                        np.stack([np.full(m, ends + 1), last, np.roll(last, -1)], 1)])
    return v, _outward(v, f)


def _outline(design: _Design, x: np.ndarray, z: float) -> np.ndarray:
    """Plan-view outline of the body's left side at height ``z``: ``[n, 2]`` (x, y) [m]."""
    w2 = design.width / 2 * design.plan(x)
    y = w2 - (z - 0.55) ** 2 / (2 * SIDE_RADIUS)
    weight = np.clip(np.maximum((x - design.front_end) / (design.h - design.front_end),
                                (design.rear_end - x) / (design.rear_end + design.h)), 0, 1) ** 2
    return np.stack([x - np.sign(x) * weight * (z - BUMPER_Z) ** 2 / (2 * NOSE_RADIUS), y], 1)


def _bumpers(design: _Design) -> tuple[np.ndarray, np.ndarray]:
    """Rub strips round the nose and the tail, 3 cm proud of the body."""
    z, proud = 0.36, 0.03
    items = []
    for start, end in ((design.axles[0] + ARCH_RADIUS + 0.05, design.h),
                       (design.axles[1] - ARCH_RADIUS - 0.05, -design.h)):
        n = max(8, int(math.ceil(abs(end - start) * 2.5 / design.facet)))
        x = start + (end - start) * np.sin(np.linspace(0, np.pi / 2, n))
        left = _outline(design, x, z)
        path = np.concatenate([left, (left * [1, -1])[-2::-1]])
        # offset outwards (away from the car's centre line in plan) by the strip's half-depth
        t = np.gradient(path, axis=0)
        t /= np.linalg.norm(t, axis=1, keepdims=True)
        out = np.stack([t[:, 1], -t[:, 0]], 1)
        out *= np.sign(np.einsum("ij,ij->i", out, path - [0.0, 0.0]))[:, None]
        items.append(_sweep(path + (proud - 0.02) * out, 0.02, 0.06, z))
    return _join(items)


def _slats(design: _Design) -> tuple[np.ndarray, np.ndarray]:
    """Grille slats: round-edged bars (8 x 20 mm) across each opening, 2 cm inside it."""
    x = np.linspace(design.front_end, design.h, 600)
    items = []
    for z in SLAT_Z:
        o = _outline(design, x, z)
        o = o[(o[:, 1] > GRILLE_Y[0] + 0.03) & (o[:, 1] < GRILLE_Y[1] - 0.03)][::-1]
        step = np.linalg.norm(np.diff(o, axis=0), axis=1).sum() / min(design.facet, 0.025)
        o = o[np.round(np.linspace(0, len(o) - 1, max(4, int(step) + 1))).astype(int)]
        o = o - [0.02, 0.0]
        for sign in (1.0, -1.0):
            items.append(_sweep(o * [1.0, sign], 0.004, 0.01, z))
    return _join(items)


def _plates(design: _Design) -> tuple[np.ndarray, np.ndarray]:
    """Front and rear licence plates (520 x 110 x 5 mm), tilted 5 deg back."""
    items = []
    for sign in (1.0, -1.0):
        x = sign * (design.h + 0.006)
        rot = _rot_y(sign * math.radians(-5.0))
        items.append(_box((x, 0.0, BUMPER_Z + 0.06), (0.005, 0.52, 0.11), rot))
    return _join(items)


def _mirrors(design: _Design) -> tuple[np.ndarray, np.ndarray]:
    """Door mirrors: housing, stalk and a rear-facing mirror plate on each side."""
    import trimesh

    x = design.cabin[1] - 0.12
    zb = float(design.belt(x))
    w2 = design.width / 2 * float(design.plan(x)) - (zb - 0.55) ** 2 / (2 * SIDE_RADIUS)
    items = []
    for side in (1.0, -1.0):
        centre = np.array([x, side * (w2 + 0.13), zb + 0.12])
        shell = trimesh.creation.icosphere(subdivisions=2)
        v = np.asarray(shell.vertices) * [0.08, 0.11, 0.07] + centre
        items.append((v, np.asarray(shell.faces)))
        items.append(_box(centre + [-0.075, 0.0, 0.0], (0.01, 0.17, 0.10)))      # mirror face
        items.append(_box((x + 0.01, side * (w2 + 0.01), zb + 0.08), (0.06, 0.06, 0.04)))
    return _join(items)


def sedan_parts(length: float = 4.5, width: float = 1.8, height: float = 1.45, *,
                facet: float = SEDAN_FACET,
                openings: bool = False) -> list[tuple[str, TriangleMesh, str]]:
    """The parts of the detailed car: ``(name, mesh, material)``.

    Parameters
    ----------
    length, width, height : float
        Overall size [m] (3.5-5.5, 1.5-2.1, 1.2-1.9).
    facet : float
        Facet size along and across the body [m], 0.02-0.3 (default
        :data:`SEDAN_FACET`; coarser meshes for fast checks).
    openings : bool
        Cut the grille and headlamp openings in the nose, with their recesses,
        radiator, slats and reflectors (the RCS study's and ``raysim rcs
        car:sedan``'s car). Off, the nose is closed: the car of the bundled
        ``parking_lot`` scene, generated before the openings.

    Returns
    -------
    list of (str, TriangleMesh, str)
        ``body`` (metal), ``glass`` (glass), ``radiator`` (metal: the backs of
        the grille recesses), ``ducts`` (plastic: their walls), ``headlamps``
        (metal: the paraboloid reflectors), ``lamp_housings`` (plastic: the lamp
        recesses' walls), ``tyres`` (rubber), ``rims`` (metal), ``bumpers``
        (metal), ``plates`` (metal), ``mirrors`` (metal), ``slats`` (metal).
        The first six are one closed surface. ``radiator``, ``ducts``,
        ``headlamps``, ``lamp_housings`` and ``slats`` come only with
        ``openings`` and ``facet`` at most :data:`OPENINGS_MAX_FACET`.

    Raises
    ------
    ValueError
        A size or ``facet`` outside the ranges above.
    """
    for name, value, lo, hi in (("length", length, 3.5, 5.5), ("width", width, 1.5, 2.1),
                                ("height", height, 1.2, 1.9), ("facet", facet, 0.02, 0.3)):
        if not (isinstance(value, (int, float)) and lo <= value <= hi):
            raise ValueError(f"car {name} must lie in [{lo}, {hi}] m, got {value!r}")
    design = _Design(float(length), float(width), float(height), float(facet))
    v, f, mat = _body(design, bool(openings))
    parts = [(name, TriangleMesh(v, f[mat == label]), material)
             for name, label, material in (
                 ("body", "metal", "metal"), ("glass", "glass", "glass"),
                 ("radiator", "radiator", "metal"), ("ducts", "ducts", "plastic"),
                 ("headlamps", "headlamps", "metal"),
                 ("lamp_housings", "lamp_housings", "plastic")) if np.any(mat == label)]
    (tv, tf), (rv, rf) = _wheels(design)
    parts.append(("tyres", TriangleMesh(tv, tf), "rubber"))
    parts.append(("rims", TriangleMesh(rv, rf), "metal"))
    extra = [("bumpers", _bumpers), ("plates", _plates), ("mirrors", _mirrors)]
    if np.any(mat == "radiator"):
        extra.append(("slats", _slats))
    for name, make in extra:
        parts.append((name, TriangleMesh(*make(design)), "metal"))
    return parts
