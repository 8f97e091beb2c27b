"""The detailed car mesh (raysim.echoes.po.sedan): closed parts, its features, its size."""

from __future__ import annotations

import numpy as np
import pytest

#: Coarse facet of the fast checks [m].
COARSE_FACET = 0.15
#: "A few thousand facets" for the coarse car, and the default car's range.
COARSE_FACETS = (2_000, 10_000)
DEFAULT_FACETS = (15_000, 40_000)
#: Enclosed volume of the body of a 4.5 x 1.8 x 1.45 m sedan [m^3]: between a third and
#: two thirds of its bounding box (11.7 m^3).
BODY_VOLUME_M3 = (3.9, 7.8)
#: Glazing of a passenger car (windscreen about 1.1 m^2, side and rear windows) [m^2].
GLASS_AREA_M2 = (2.0, 5.0)
#: Mirrors stand at least this far out of the body [m].
MIRROR_OUT_M = 0.1
#: Tyres touch the ground: lowest point within this of z = 0 [m].
GROUND_TOL_M = 0.005


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


def test_parts_materials_and_facets(coarse):
    from raysim.echoes.po.sedan import sedan_parts

    assert {k: v[1] for k, v in coarse.items()} == {
        "body": "metal", "glass": "glass", "tyres": "rubber", "rims": "metal",
        "bumpers": "metal", "plates": "metal", "mirrors": "metal"}
    n = sum(len(m.faces) for m, _ in coarse.values())
    assert COARSE_FACETS[0] <= n <= COARSE_FACETS[1]
    default = sum(len(m.faces) for _, m, _ in sedan_parts())
    assert DEFAULT_FACETS[0] <= default <= DEFAULT_FACETS[1]


def test_deterministic(coarse):
    from raysim.echoes.po.sedan import sedan_parts

    again = sedan_parts(facet=COARSE_FACET)
    for name, mesh, _ in again:
        assert np.array_equal(mesh.vertices, coarse[name][0].vertices), name
        assert np.array_equal(mesh.faces, coarse[name][0].faces), name


def test_parts_are_closed_and_sized(coarse):
    body = _trimesh([coarse["body"][0], coarse["glass"][0]])
    assert body.is_watertight
    assert BODY_VOLUME_M3[0] < body.volume < BODY_VOLUME_M3[1]
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
