"""Edge diffraction (PTD fringe wave) of the PO engine against closed forms.

Closed forms: the half-plane's exact (Sommerfeld) monostatic diffraction
coefficients and their PO parts (Ufimtsev, *Fundamentals of the Physical Theory
of Diffraction*, 2007, ch. 2); the square plate in its principal planes, whose
PO + fringe on the edges normal to the plane of incidence is Keller's
first-order GTD (Ross, IEEE TAP 14(3), 1966; Knott, Shaeffer & Tuley, *Radar
Cross Section*, 1993, ch. 5), edge-on ``sigma = b^2 / pi`` where PO gives 0.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.echoes.po import monostatic_rcs, po_material
from raysim.echoes.po import targets as T
from raysim.echoes.po.edges import fringe_coefficients, sharp_edges, wedge_coefficients
from raysim.echoes.po.mesh import TriangleMesh

FREQ = 77e9
LAM = 299_792_458.0 / FREQ
K = 2 * math.pi / LAM
SIDE = 0.05
#: Fringe coefficients vs the half-plane closed form (the specular window's mean of
#: two points 2e-3 rad away errs by O(4e-6)); absolute, dimensionless.
FRINGE_ABS = 1e-4
#: Keller's coefficient vs Sommerfeld's exact half-plane form (same algebra, rounding only).
KELLER_REL = 1e-9
#: Plate PO + PTD vs the NumPy reference of the same closed forms [dB] (PO by Gordon's
#: exact facet integral, edges by exact segment integrals: only rounding differs).
PLATE_PTD_DB = 0.01
#: Mirror-image aspects, flipped windings, or the near field at 10 km vs the far field [dB].
SYMMETRY_DB = 0.01
NEAR_FAR_DB = 0.05


def db(x):
    return 10 * np.log10(x)


@pytest.fixture(scope="module")
def metal():
    return po_material("metal", FREQ)


def ref_half_plane_fringe(phi):
    """Half-plane (n = 2) monostatic fringe: exact minus PO of the lit face."""
    x = np.where(phi > np.pi, 2 * np.pi - phi, phi) / 2
    c, s = np.cos(x), np.sin(x)
    return -s / (c + s), -c / (c + s)


def ref_plate_ptd(side, theta, soft):
    """Square plate rotated by ``theta`` about a side's axis: PO + PTD amplitude ``F`` [m].

    The two edges normal to the plane of incidence give Keller's exact half-plane
    coefficients (PO + fringe), ``d_s = sin^2(phi/2)/cos(phi)``,
    ``d_h = -cos^2(phi/2)/cos(phi)`` at ``phi = pi/2 +- theta`` (Ross's first order);
    the two edges in the plane of incidence add their fringe at ``phi = pi/2``,
    ``-1/2`` per unit length, over ``side sinc(k side sin theta)``.
    """
    x = K * side * math.sin(theta)
    lead, trail = math.pi / 2 + theta, math.pi / 2 - theta
    sinc = math.sin(x) / x
    if soft:
        d = [math.sin(p / 2) ** 2 / math.cos(p) for p in (lead, trail)]
        main = side / (2 * math.pi) * (d[0] * np.exp(1j * x) + d[1] * np.exp(-1j * x))
        return main + side * sinc / (2 * math.pi)
    d = [-math.cos(p / 2) ** 2 / math.cos(p) for p in (lead, trail)]
    main = -side / (2 * math.pi) * (d[0] * np.exp(1j * x) + d[1] * np.exp(-1j * x))
    return main - side * sinc / (2 * math.pi)


def test_half_plane_fringe_matches_closed_form():
    phi = np.concatenate([np.linspace(0.01, 2 * np.pi - 0.01, 397), [np.pi / 2, 1.5 * np.pi]])
    fs, fh = fringe_coefficients(phi, 2.0)
    rs, rh = ref_half_plane_fringe(phi)
    np.testing.assert_allclose(fs, rs, atol=FRINGE_ABS)
    np.testing.assert_allclose(fh, rh, atol=FRINGE_ABS)
    # edge-on: the leading edge (phi = pi) gives -1 for soft and 0 for hard, PO gives 0
    fs, fh = fringe_coefficients(np.array([np.pi - 1e-9]), 2.0)
    assert abs(fs[0] + 1) < FRINGE_ABS and abs(fh[0]) < FRINGE_ABS


def test_keller_half_plane_is_sommerfeld():
    phi = np.linspace(0.05, np.pi - 0.05, 50)
    phi = phi[np.abs(phi - np.pi / 2) > 0.05]
    d_s, d_h, f_s, g_h = wedge_coefficients(phi, 2.0)
    np.testing.assert_allclose(d_s, np.sin(phi / 2) ** 2 / np.cos(phi), rtol=KELLER_REL)
    np.testing.assert_allclose(d_h, -np.cos(phi / 2) ** 2 / np.cos(phi), rtol=KELLER_REL)
    np.testing.assert_allclose(f_s, np.tan(phi) / 2, rtol=KELLER_REL)
    np.testing.assert_allclose(g_h, -np.tan(phi) / 2, rtol=KELLER_REL)


@pytest.mark.parametrize("n", [1.5, 1.25, 2.0])
def test_wedge_fringe_is_smooth_across_the_specular_directions(n):
    h = 0.02
    for p in (np.pi / 2, n * np.pi - np.pi / 2):
        mid = np.array(fringe_coefficients(np.array([p]), n))[:, 0]
        side = np.array(fringe_coefficients(np.array([p - h, p + h]), n))
        # finite and continuous (both terms alone grow as 1 / h): within O(h) of the
        # neighbours (a kink where n = 3/2 lights face n at face 0's specular direction)
        np.testing.assert_allclose(side, np.repeat(mid[:, None], 2, axis=1), atol=h)
        assert np.all(np.isfinite(mid))
    # symmetric wedge: phi and n pi - phi are mirror images
    phi = np.linspace(0.1, n * np.pi - 0.1, 31)
    np.testing.assert_allclose(np.array(fringe_coefficients(phi, n)),
                               np.array(fringe_coefficients(n * np.pi - phi, n)), atol=1e-9)


def test_sharp_edges_of_canonical_meshes():
    plate = sharp_edges(T.square_plate(SIDE))
    assert len(plate) == 4 and np.all(plate.n == 2.0)
    np.testing.assert_allclose(plate.lengths, SIDE)
    assert len(sharp_edges(T.sphere(0.03, subdivisions=3))) == 0     # 1280 facets, no wedge
    import trimesh

    box = trimesh.creation.box((0.03, 0.03, 0.03))
    cube = sharp_edges(TriangleMesh(box.vertices, box.faces))
    assert len(cube) == 12 and np.allclose(cube.n, 1.5)
    tri = sharp_edges(T.trihedral(SIDE))
    assert sorted(tri.n) == [1.5, 1.5, 1.5, 2.0, 2.0, 2.0]            # folds and rims
    seg = plate.split(LAM)
    assert len(seg) == 4 * math.ceil(SIDE / LAM)
    np.testing.assert_allclose(seg.lengths.sum(), 4 * SIDE)


def test_plate_edge_on_soft_is_b2_over_pi(metal):
    """Edge-on, E along the leading edge: PO gives 0, PTD the half-plane's sigma = b^2/pi."""
    po = monostatic_rcs(T.square_plate(SIDE), metal, [90.0], [0.0], max_bounces=1)
    ptd = monostatic_rcs(T.square_plate(SIDE), metal, [90.0], [0.0], max_bounces=1,
                         diffraction=True)
    assert po.rcs_m2[0, 0] < 1e-20
    assert abs(ptd.rcs_dbsm[0, 0] - db(SIDE**2 / math.pi)) < PLATE_PTD_DB
    assert ptd.info["edges"] == 4 and ptd.info["edge_seconds"] <= ptd.info["seconds"]


@pytest.mark.parametrize("pol,plane,soft", [("VV", "az", True), ("HH", "az", False),
                                            ("HH", "el", True), ("VV", "el", False)])
def test_plate_principal_planes_match_first_order_gtd(metal, pol, plane, soft):
    # first and second sidelobe peaks, wide angles, near grazing
    angles = [math.degrees(math.asin(m * LAM / (2 * SIDE))) for m in (1.5, 2.5)]
    angles += [-20.0, 45.0, 70.0, 85.0]
    if plane == "az":
        res = monostatic_rcs(T.square_plate(SIDE), metal, angles, [0.0], polarisation=pol,
                             max_bounces=1, diffraction=True).rcs_dbsm[:, 0]
    else:
        res = monostatic_rcs(T.square_plate(SIDE), metal, [0.0], angles, polarisation=pol,
                             max_bounces=1, diffraction=True).rcs_dbsm[0]
    ref = [db(4 * math.pi * abs(ref_plate_ptd(SIDE, math.radians(a), soft)) ** 2)
           for a in angles]
    np.testing.assert_array_less(np.abs(res - ref), PLATE_PTD_DB)


def test_diffraction_off_is_unchanged_and_on_changes_only_off_specular(metal):
    angles = [0.0, math.degrees(math.asin(1.5 * LAM / (2 * SIDE))), 60.0]
    plate = T.square_plate(SIDE)
    default = monostatic_rcs(plate, metal, angles, [0.0])
    off = monostatic_rcs(plate, metal, angles, [0.0], diffraction=False)
    np.testing.assert_array_equal(default.rcs_m2, off.rcs_m2)
    ref = [T.plate_rcs(SIDE, LAM, math.radians(a)) for a in angles]
    np.testing.assert_allclose(off.rcs_m2[:, 0], ref, rtol=1e-9)
    on = monostatic_rcs(plate, metal, angles, [0.0], diffraction=True)
    # normal incidence: the edges add O(1 / (k side)) to the specular flash
    assert abs(on.rcs_dbsm[0, 0] - off.rcs_dbsm[0, 0]) < 20 * np.log10(1 + 2 / (K * SIDE))
    assert on.rcs_dbsm[2, 0] - off.rcs_dbsm[2, 0] > 3.0      # 60 deg: PO is far too low


def test_symmetry_winding_and_near_field(metal):
    import trimesh

    box = trimesh.creation.box((0.03, 0.03, 0.03))
    cube = TriangleMesh(box.vertices, box.faces)
    res = monostatic_rcs(cube, metal, [-25.0, 25.0], [10.0], max_bounces=1, diffraction=True)
    assert abs(res.rcs_dbsm[0, 0] - res.rcs_dbsm[1, 0]) < SYMMETRY_DB
    plate = T.square_plate(SIDE)
    flipped = TriangleMesh(plate.vertices, plate.faces[:, ::-1])
    a = monostatic_rcs(plate, metal, [40.0], [5.0], max_bounces=1, diffraction=True)
    b = monostatic_rcs(flipped, metal, [40.0], [5.0], max_bounces=1, diffraction=True)
    assert abs(a.rcs_dbsm[0, 0] - b.rcs_dbsm[0, 0]) < SYMMETRY_DB
    near = monostatic_rcs(plate, metal, [40.0], [5.0], max_bounces=1, diffraction=True,
                          range_m=1e4)
    assert abs(near.rcs_dbsm[0, 0] - a.rcs_dbsm[0, 0]) < NEAR_FAR_DB


def test_bad_input_is_refused(metal, capsys):
    plate = T.square_plate(SIDE)
    with pytest.raises(ValueError, match="diffraction must be True or False"):
        monostatic_rcs(plate, metal, [0.0], [0.0], diffraction="yes")
    with pytest.raises(ValueError, match="not one"):
        monostatic_rcs(plate, po_material("dry-soil", FREQ), [0.0], [0.0], diffraction=True)
    with pytest.raises(ValueError, match="threshold_deg"):
        sharp_edges(plate, 0.0)
    with pytest.raises(ValueError, match="max_length"):
        sharp_edges(plate).split(0.0)
    from raysim.cli import main

    assert main(["rcs", "plate:0.05", "--material", "dry-soil", "--az-deg", "0", "--el-deg",
                 "0", "--diffraction", "--no-progress"]) == 2
    assert main(["rcs", "plate:0.05", "--az-deg", "90", "--el-deg", "0", "--max-bounces", "1",
                 "--diffraction", "--no-progress", "--json"]) == 0
    out = capsys.readouterr()
    assert "4 edges" in out.err and "wall clock" in out.err
    import json

    got = json.loads(out.out)["rcs_dbsm"][0][0]
    assert abs(got - db(SIDE**2 / math.pi)) < PLATE_PTD_DB


#: Scene geometry target at 20 m vs the far-field edge-on closed form [dB] (spherical
#: wave over a 5 cm plate: the leading edge's quadratic phase is below 0.01 rad).
SCENE_EDGE_ON_DB = 0.1


def test_scene_geometry_target_switch():
    from raysim.echoes.po.paths import scattering_terms
    from raysim.echoes.rt.scenes import SceneTarget

    centre = np.array([1.0, 2.0, 0.5])
    plate = T.square_plate(SIDE)
    placed = TriangleMesh(plate.vertices + centre, plate.faces)
    radar = centre + [0.0, 20.0, 0.0]            # edge-on, polarisation along the leading edge
    off = scattering_terms(placed, "metal", radar, centre, frequency=FREQ, max_bounces=1)
    on = scattering_terms(placed, "metal", radar, centre, frequency=FREQ, max_bounces=1,
                          diffraction=True)
    assert len(off.amplitude) == 0
    assert abs(db(on.rcs_m2) - db(SIDE**2 / math.pi)) < SCENE_EDGE_ON_DB
    glass = scattering_terms(placed, "glass", radar, centre, frequency=FREQ, max_bounces=1,
                             diffraction=True)
    assert len(glass.amplitude) == 0                   # no fringe wave off a dielectric
    assert not SceneTarget("t", [0.0, 0.0, 0.0]).diffraction
    with pytest.raises(ValueError, match="diffraction must be true or false"):
        SceneTarget("t", [0.0, 0.0, 0.0], diffraction="yes")


#: Cube seen along the bisector of an edge vs Keller's GTD of its three lit edges normal to
#: the plane of incidence [dB]; the eight edges oblique to the radar add their own fringe
#: wave (0.04 dB in VV, 0.1 dB in HH at this aspect).
CUBE_DB = 0.2


def ref_keller(phi, n, soft):
    """Keller's monostatic wedge coefficient (exterior angle ``n pi``, soft or hard)."""
    cn = math.cos(math.pi / n)
    t2 = 1 / (cn - math.cos(2 * phi / n))
    return math.sin(math.pi / n) / n * (1 / (cn - 1) + (-t2 if soft else t2))


@pytest.mark.parametrize("pol,soft", [("VV", True), ("HH", False)])
def test_cube_edge_is_keller_right_angle_wedge(metal, pol, soft):
    """Radar at az = 45 deg, el = 0 (normal to the edges along y): the front edge seen
    at phi = 3 pi / 4 and the two edges each with one face lit at phi = pi / 4, all
    wedges n = 3/2 (PO of the faces plus their fringe: Keller's coefficient)."""
    import trimesh

    a = 0.03
    box = trimesh.creation.box((a, a, a))
    cube = TriangleMesh(box.vertices, box.faces)
    got = monostatic_rcs(cube, metal, [45.0], [0.0], polarisation=pol, max_bounces=1,
                         diffraction=True).rcs_dbsm[0, 0]
    phase = np.exp(2j * K * math.sqrt(2) * a / 2)             # front edge at (a/2, ., a/2)
    f = a / (2 * math.pi) * (ref_keller(3 * math.pi / 4, 1.5, soft) * phase
                             + 2 * ref_keller(math.pi / 4, 1.5, soft))
    assert abs(got - db(4 * math.pi * abs(f) ** 2)) < CUBE_DB
    po = monostatic_rcs(cube, metal, [45.0], [0.0], polarisation=pol,
                        max_bounces=1).rcs_dbsm[0, 0]
    assert abs(po - db(4 * math.pi * abs(f) ** 2)) > 3.0       # PO alone misses the edge
