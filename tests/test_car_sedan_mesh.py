"""The detailed car mesh (raysim.echoes.po.sedan): closed parts, its features, its size."""

from __future__ import annotations

import numpy as np
import pytest

#: Coarse facet of the fast checks [m].
COARSE_FACET = 0.15
#: "A few thousand facets" for the coarse car, and the default car's range.
COARSE_FACETS = (2_000, 10_000)
#: The default car: about 33 000 facets of body, wheels and fittings and 7 000 of the
#: headlamp reflectors (6 mm facets).
DEFAULT_FACETS = (15_000, 45_000)
#: Enclosed volume of the body of a 4.5 x 1.8 x 1.45 m sedan [m^3]: between a third and
#: two thirds of its bounding box (11.7 m^3).
BODY_VOLUME_M3 = (3.9, 7.8)
#: Glazing of a passenger car (windscreen about 1.1 m^2, side and rear windows) [m^2].
GLASS_AREA_M2 = (2.0, 5.0)
#: Mirrors stand at least this far out of the body [m].
MIRROR_OUT_M = 0.1
#: Tyres touch the ground: lowest point within this of z = 0 [m].
GROUND_TOL_M = 0.005
#: A ray parallel to a paraboloid's axis reflects through its focus (the
#: paraboloid's defining property); the faceted reflector's reflected ray passes the
#: focus within this [m] (6 mm facets tilt the normal by up to about facet / (2 x
#: curvature radius), 0.03 rad, over the 2.5-5 cm from the wall to the focus).
FOCUS_TOL_M = 0.004


def _trimesh(meshes):
    import trimesh

    v, f, off = [], [], 0
    for m in meshes:
        v.append(m.vertices)
        f.append(m.faces + off)
        off += len(m.vertices)
    t = trimesh.Trimesh(np.concatenate(v), np.concatenate(f), process=True)
    t.merge_vertices()
    return t


def _inside(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Points ``[p, 3]`` inside a closed surface ``[f, 3, 3]``: parity of a ray's crossings
    (Moller-Trumbore, a ray slightly off vertical so that it misses edges)."""
    d = np.array([0.013, 0.017, 1.0])
    d /= np.linalg.norm(d)
    e1, e2 = triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0]
    h = np.cross(d, e2)
    a = np.einsum("fi,fi->f", e1, h)
    ok = np.abs(a) > 1e-12
    e1, e2, h, a, t0 = e1[ok], e2[ok], h[ok], a[ok], triangles[ok, 0]
    out = np.zeros(len(points), bool)
    for i, p in enumerate(points):
        s = p - t0
        u = np.einsum("fi,fi->f", s, h) / a
        q = np.cross(s, e1)
        v = (q @ d) / a
        t = np.einsum("fi,fi->f", e2, q) / a
        out[i] = np.count_nonzero((u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)) % 2 == 1
    return out


@pytest.fixture(scope="module")
def coarse():
    from raysim.echoes.po.sedan import sedan_parts

    return {name: (mesh, mat) for name, mesh, mat in sedan_parts(facet=COARSE_FACET)}


@pytest.fixture(scope="module")
def default():
    from raysim.echoes.po.sedan import sedan_parts

    return {name: (mesh, mat) for name, mesh, mat in sedan_parts(openings=True)}


def test_parts_materials_and_facets(coarse, default):
    from raysim.echoes.po.sedan import sedan_parts

    closed_nose = {"body": "metal", "glass": "glass", "tyres": "rubber", "rims": "metal",
                   "bumpers": "metal", "plates": "metal", "mirrors": "metal"}
    # the coarse car (facet above OPENINGS_MAX_FACET) keeps a closed nose, and so does
    # the car without openings (the bundled scene's)
    assert {k: v[1] for k, v in coarse.items()} == closed_nose
    assert {k: v for k, _, v in sedan_parts(facet=COARSE_FACET, openings=True)} == closed_nose
    assert {k: v for k, _, v in sedan_parts(facet=0.08)} == closed_nose
    assert {k: v[1] for k, v in default.items()} == {
        **closed_nose, "radiator": "metal", "ducts": "plastic", "headlamps": "metal",
        "lamp_housings": "plastic", "slats": "metal"}
    n = sum(len(m.faces) for m, _ in coarse.values())
    assert COARSE_FACETS[0] <= n <= COARSE_FACETS[1]
    n = sum(len(m.faces) for m, _ in default.values())
    assert DEFAULT_FACETS[0] <= n <= DEFAULT_FACETS[1]


def test_deterministic(coarse):
    from raysim.echoes.po.sedan import sedan_parts

    again = sedan_parts(facet=COARSE_FACET)
    for name, mesh, _ in again:
        assert np.array_equal(mesh.vertices, coarse[name][0].vertices), name
        assert np.array_equal(mesh.faces, coarse[name][0].faces), name


def test_parts_are_closed_and_sized(coarse, default):
    body = _trimesh([coarse["body"][0], coarse["glass"][0]])
    assert body.is_watertight
    assert BODY_VOLUME_M3[0] < body.volume < BODY_VOLUME_M3[1]
    # the openings' recesses close the body again: one closed surface, less volume
    nose = _trimesh([default[k][0] for k in ("body", "glass", "radiator", "ducts",
                                             "headlamps", "lamp_housings")])
    assert nose.is_watertight
    assert BODY_VOLUME_M3[0] < nose.volume < body.volume
    assert _trimesh([default["slats"][0]]).is_watertight
    for name in ("tyres", "rims", "bumpers", "plates", "mirrors"):
        assert _trimesh([coarse[name][0]]).is_watertight, name
    glass = coarse["glass"][0].areas.sum()
    assert GLASS_AREA_M2[0] < glass < GLASS_AREA_M2[1]
    # two 520 x 110 mm plates (boxes of 5 mm)
    assert coarse["plates"][0].areas.sum() == pytest.approx(
        2 * 2 * (0.52 * 0.11 + 0.52 * 0.005 + 0.11 * 0.005), rel=1e-9)


def test_wheel_houses_hold_the_tyres(coarse):
    """No tyre point lies inside the body: the arches and wheel houses leave room for them."""
    body = _trimesh([coarse["body"][0], coarse["glass"][0]])
    tyres = coarse["tyres"][0]
    assert tyres.vertices[:, 2].min() == pytest.approx(0.0, abs=GROUND_TOL_M)
    assert tyres.vertices[:, 2].max() > body.vertices[:, 2].min() + 0.3    # tyres reach up
    tri = np.asarray(body.triangles)
    # the check sees a point inside the body (the cabin's centre) as inside
    assert _inside(np.array([[0.0, 0.0, 0.8]]), tri).all()
    assert not _inside(tyres.vertices, tri).any()
    assert not _inside(coarse["rims"][0].vertices, tri).any()


def test_mirrors_and_bumpers_stand_out(coarse):
    body_y = np.abs(coarse["body"][0].vertices[:, 1]).max()
    assert np.abs(coarse["mirrors"][0].vertices[:, 1]).max() > body_y + MIRROR_OUT_M
    body_x = np.abs(coarse["body"][0].vertices[:, 0]).max()
    assert np.abs(coarse["bumpers"][0].vertices[:, 0]).max() > body_x


@pytest.mark.parametrize("kwargs,match", [({"length": 9.0}, "length"),
                                          ({"facet": 1.0}, "facet"),
                                          ({"height": float("nan")}, "height")])
def test_bad_sizes(kwargs, match):
    from raysim.echoes.po.sedan import sedan_parts

    with pytest.raises(ValueError, match=match):
        sedan_parts(**kwargs)


def _first_hit(parts, origin, direction):
    """Part name, point and unit normal of a ray's first hit on ``parts`` ({name: mesh})
    (Moller-Trumbore over every facet)."""
    best = None
    for name, mesh in parts.items():
        tri = mesh.vertices[mesh.faces]
        e1, e2 = tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
        h = np.cross(direction, e2)
        a = np.einsum("fi,fi->f", e1, h)
        ok = np.abs(a) > 1e-15
        a = np.where(ok, a, 1.0)
        s = origin - tri[:, 0]
        u = np.einsum("fi,fi->f", s, h) / a
        q = np.cross(s, e1)
        v = (q @ direction) / a
        t = np.einsum("fi,fi->f", e2, q) / a
        hit = ok & (u >= 0) & (v >= 0) & (u + v <= 1) & (t > 0)
        if hit.any():
            f = np.flatnonzero(hit)[np.argmin(t[hit])]
            if best is None or t[f] < best[0]:
                n = np.cross(e1[f], e2[f])
                best = (t[f], name, origin + t[f] * direction, n / np.linalg.norm(n))
    return best[1], best[2], best[3]


def test_grille_opens_on_the_radiator(default):
    """A ray from ahead through a grille opening (clear of the plate and slats) meets the
    radiator, a plate facing forward RADIATOR_DEPTH behind the opening's rearmost rim
    point, where the ducts' walls end."""
    from raysim.echoes.po.sedan import GRILLE_Y, RADIATOR_DEPTH

    parts = {k: v[0] for k, v in default.items()}
    for y in (0.30, -0.30):
        name, p, n = _first_hit(parts, np.array([10.0, y, 0.55]), np.array([-1.0, 0, 0]))
        assert name == "radiator"
        assert abs(n[0]) == pytest.approx(1.0)                 # the radiator faces forward
        ducts = default["ducts"][0]
        used = ducts.vertices[np.unique(ducts.faces)]
        used = used[used[:, 1] * np.sign(y) >= GRILLE_Y[0]]
        assert used[:, 0].min() == pytest.approx(p[0], abs=1e-9)
        rim = used[used[:, 0] > p[0] + 0.01]
        assert rim[:, 0].min() - p[0] == pytest.approx(RADIATOR_DEPTH, abs=1e-9)


def test_headlamp_reflectors_focus_forward_rays(default):
    """Rays parallel to the lamp axis (+x) reflect through the paraboloid's focus."""
    from raysim.echoes.po.sedan import HEADLAMP_FOCAL

    parts = {k: v[0] for k, v in default.items()}
    lamp = default["headlamps"][0].vertices[np.unique(default["headlamps"][0].faces)]
    for side in (1.0, -1.0):
        own = lamp[lamp[:, 1] * side > 0]
        vertex = own[np.argmin(own[:, 0])]                     # the paraboloid's vertex
        focus = vertex + [HEADLAMP_FOCAL, 0.0, 0.0]
        for dy, dz in ((0.04, 0.0), (-0.05, 0.0), (0.0, 0.03), (0.03, -0.03)):
            origin = np.array([10.0, vertex[1] + dy, vertex[2] + dz])
            d = np.array([-1.0, 0.0, 0.0])
            name, p, n = _first_hit(parts, origin, d)
            assert name == "headlamps"
            r = d - 2 * np.dot(d, n) * n
            miss = np.linalg.norm(np.cross(focus - p, r))       # distance of focus to the ray
            assert miss < FOCUS_TOL_M, (side, dy, dz, miss)
