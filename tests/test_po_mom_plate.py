"""The engine's PO, PO + PTD and multiple diffraction on a long plate against the 2-D moments.

A plate 4 wavelengths wide and 200 long, rotated about its long edges, is a
strip: ``sigma_3D = sigma_2D 2 L^2 / lambda`` (Knott, Shaeffer & Tuley, *Radar
Cross Section*, 2nd ed., 1993: the 2-D to 3-D relation). The reference is the method of moments
(raysim.echoes.po.mom2d, itself tested against closed forms in test_po_mom2d.py).
Aspects: the strip's lobe peaks ``k w sin(phi) = (m + 1/2) pi`` (PO's
``cos phi sinc(k w sin phi)``), and near grazing.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.echoes.po import monostatic_rcs, po_material
from raysim.echoes.po import targets as T
from raysim.echoes.po.edges import (
    _fresnel_transition,
    facing_edge_pairs,
    pair_amplitude,
    sharp_edges,
)
from raysim.echoes.po.mesh import TriangleMesh
from raysim.echoes.po.rcs import polarisation_basis, radar_direction
from raysim.echoes.po.strip_reference import compare_long_plate, long_plate

FREQ = 77e9
LAM = 299_792_458.0 / FREQ
K = 2 * math.pi / LAM
WIDTH = 4 * LAM
PEAKS = np.degrees(np.arcsin((np.arange(8) + 0.5) / (2 * WIDTH / LAM)))   # 3.6 .. 69.6 deg
GRAZING = np.array([75.0, 80.0, 85.0, 88.0, 90.0])
#: TM (VV) PO + PTD vs the moment method [dB]: the next (soft, slope) diffraction is
#: O((k w)^-3/2) relative (0.07 dB here), the moment method 0.03 dB, the plate's short
#: edges O(lambda / L).
FIRST_ORDER_TM_DB = 0.2
#: TE (HH) with the multiple diffraction vs the moment method, lobe peaks to 80 deg [dB]: the
#: asymptotic coefficients' next order, relative O(1 / (k w)) (0.34 dB here).
MULTIPLE_TE_DB = 20 * math.log10(1 + 1 / (K * WIDTH))
#: TE first order vs the moment method up to 30 deg [dB] (the missing double diffraction,
#: relative amplitude 1 / sqrt(2 pi k w) = 0.063 here, grows as sec(a/2) off broadside).
FIRST_ORDER_TE_DB = 1.0
#: The plate's short edges' terms against the long edges' [dB]: O(lambda / L), L = 200 lambda.
SHORT_EDGES_DB = 0.02
#: The engine against the NumPy reference of the same closed forms [dB, relative]
#: (rounding only; the segment sinc factors are exact).
FORMULA_DB = 0.01
FORMULA_REL = 1e-9


@pytest.fixture(scope="module")
def comparison():
    return compare_long_plate(WIDTH, np.concatenate([[0.0], PEAKS, GRAZING]))


def _at(comp, angles):
    return np.isin(comp.phi_deg, angles)


def test_tm_first_order_ptd_matches_moments(comparison):
    """VV (E along the edges): PO + PTD holds at every lobe peak and edge-on; PO does not."""
    c = comparison
    pick = _at(c, np.concatenate([PEAKS, GRAZING]))
    np.testing.assert_allclose(c.ptd["TM"][pick], c.mom["TM"][pick], atol=FIRST_ORDER_TM_DB)
    # edge-on: sigma_2D = lambda / (2 pi) (the leading edge, Keller's soft coefficient -1)
    assert abs(c.mom["TM"][-1] - 10 * math.log10(1 / (2 * math.pi))) < FIRST_ORDER_TM_DB
    wide = _at(c, PEAKS[PEAKS > 50])
    assert np.all(c.po["TM"][wide] < c.mom["TM"][wide] - 4.0)
    # multiple diffraction is hard-only: VV changes only by the short edges' pair (across L)
    np.testing.assert_allclose(c.multiple["TM"], c.ptd["TM"], atol=SHORT_EDGES_DB)


def test_te_first_order_fails_off_broadside(comparison):
    """HH (H along the edges): first order holds near broadside only; the error alternates
    in sign from peak to peak (the edge-to-edge interaction) and grows."""
    c = comparison
    near = _at(c, PEAKS[PEAKS < 30])
    np.testing.assert_allclose(c.ptd["TE"][near], c.mom["TE"][near], atol=FIRST_ORDER_TE_DB)
    err = (c.ptd["TE"] - c.mom["TE"])[_at(c, PEAKS)]
    assert np.all(np.sign(err[1:]) != np.sign(err[:-1]))
    assert abs(err[-1]) > 3.0


def test_te_multiple_diffraction_matches_moments_to_80_deg(comparison):
    c = comparison
    pick = _at(c, np.concatenate([PEAKS, [75.0, 80.0]]))
    np.testing.assert_allclose(c.multiple["TE"][pick], c.mom["TE"][pick], atol=MULTIPLE_TE_DB)


def test_te_near_grazing_is_the_known_limit(comparison):
    """In the last degrees the moment method falls to 0 edge-on (a sheet with E normal to
    it); the asymptotic edge waves do not follow: first order stays at lambda / (2 pi),
    the multiple diffraction errs by -1.2 dB at 85 deg and about -19 dB at 88 deg."""
    c = comparison
    at88 = _at(c, [88.0])
    assert abs(c.multiple["TE"][at88] - c.mom["TE"][at88]) > 10.0
    assert c.mom["TE"][-1] < -200                                    # exactly dark edge-on
    assert abs(c.ptd["TE"][-1] - 10 * math.log10(1 / (2 * math.pi))) < FIRST_ORDER_TM_DB


#: Square cylinder 3.7 wavelengths a side (2 a / lambda = 7.4: no interior resonance of the
#: square, sqrt(m^2 + n^2), nearby), its lobe peaks and 30 to 45 deg (corner-on).
BOX = 3.7 * LAM
BOX_ANGLES = np.concatenate([[0.0], np.degrees(np.arcsin((np.arange(5) + 0.5) / 7.4)),
                             [30.0, 40.0, 45.0]])


def test_box_right_angle_wedges_against_moments():
    """A long square box (four right-angle wedges, n = 3/2): PO + PTD within the first-order
    tolerances of the plate (TM 0.2 dB, TE 1 dB, measured 0.09 and 0.81 dB), PO not."""
    c = compare_long_plate(BOX, BOX_ANGLES, shape="box")
    np.testing.assert_allclose(c.ptd["TM"], c.mom["TM"], atol=FIRST_ORDER_TM_DB)
    np.testing.assert_allclose(c.ptd["TE"], c.mom["TE"], atol=FIRST_ORDER_TE_DB)
    assert np.max(np.abs(c.po["TM"] - c.mom["TM"])) > 1.5
    assert np.max(np.abs(c.po["TE"] - c.mom["TE"])) > 2.5
    np.testing.assert_array_equal(c.multiple["TE"], c.ptd["TE"])   # no facing half-planes


def test_fresnel_transition_asymptotes():
    """Kouyoumjian & Pathak (Proc. IEEE 62(11), 1974, eqs. for small and large X):
    ``F ~ [sqrt(pi X) - 2 X exp(j pi/4) - (2/3) X^2 exp(-j pi/4)] exp(j (pi/4 + X))`` and
    ``F ~ 1 + j/(2X) - 3/(4X^2) - 15j/(8X^3)``; each truncation errs by the next term's order."""
    small = np.array([1e-4, 1e-3, 1e-2])
    ref = ((np.sqrt(np.pi * small) - 2 * small * np.exp(1j * np.pi / 4)
            - 2 / 3 * small**2 * np.exp(-1j * np.pi / 4)) * np.exp(1j * (np.pi / 4 + small)))
    assert np.all(np.abs(_fresnel_transition(small) - ref) < small**2.5)
    big = np.array([20.0, 100.0, 1e3])
    ref = 1 + 1j / (2 * big) - 3 / (4 * big**2) - 15j / (8 * big**3)
    # next term 105/(16 X^4); the Fresnel integrals' rounding below 1e-12
    assert np.all(np.abs(_fresnel_transition(big) - ref) < 10 / big**4 + 1e-12)


def ref_plate_pairs(side, theta, orders):
    """Square plate rotated by ``theta`` about its y edges, HH: the y edges' multiple
    diffraction ``side C / (2 pi)`` (the x edges' pair has ``w_h = 0`` in this plane), from
    the 2-D ray sums: edge A at ``x = -side/2`` lit at ``pi/2 - theta``, B at ``pi/2 + theta``."""
    k, w = K, side
    c = np.exp(-1j * np.pi / 4) / (2 * math.sqrt(2 * math.pi * k))
    send = [-2 * c * _fresnel_transition(2 * k * w * math.cos(a / 2) ** 2) / math.cos(a / 2)
            for a in (math.pi / 2 - theta, math.pi / 2 + theta)]
    g = np.exp(-1j * k * w) / math.sqrt(w)
    paths = 2 * send[0] * send[1] * g                       # A -> B and B -> A
    if orders == "all":
        r = -2 * c * g                                      # a grazing wave turned back
        ends = [np.exp(-1j * k * w * math.sin(theta)), np.exp(1j * k * w * math.sin(theta))]
        # odd crossings end at the other edge, even ones at the first
        paths = g * (2 * send[0] * send[1] + r * (send[0] ** 2 * ends[0]
                                                  + send[1] ** 2 * ends[1])) / (1 - r**2)
    return side * (-np.exp(1j * np.pi / 4) * math.sqrt(2 * math.pi * k) * paths) / (2 * math.pi)


@pytest.mark.parametrize("orders", ["double", "all"])
def test_pair_diffraction_matches_its_formula(orders):
    """The plate (HH) against Ross's first order plus the closed-form pair term, in plain
    NumPy (only rounding differs); the engine's option is ``orders="all"``."""
    from test_po_diffraction import ref_plate_ptd

    side = 0.05
    angles = [3.35, 20.0, 45.0, 70.0, 85.0]
    plate = T.square_plate(side)
    edges = sharp_edges(plate)
    pairs = facing_edge_pairs(edges).split(LAM)
    got = []
    for a in np.radians(angles):
        u = radar_direction(a, 0.0)
        e_h, _ = polarisation_basis(a, 0.0)
        f = pair_amplitude(pairs, u, e_h, K, orders=orders)
        got.append(f)
    ref = [ref_plate_pairs(side, a, orders) for a in np.radians(angles)]
    np.testing.assert_allclose(got, ref, rtol=FORMULA_REL)
    if orders == "all":
        engine = monostatic_rcs(plate, po_material("metal", FREQ), angles, [0.0],
                                polarisation="HH", max_bounces=1, diffraction=True,
                                multiple_diffraction=True).rcs_dbsm[:, 0]
        want = [10 * np.log10(4 * math.pi * abs(ref_plate_ptd(side, a, False) + r) ** 2)
                for a, r in zip(np.radians(angles), ref, strict=True)]
        np.testing.assert_allclose(engine, want, atol=FORMULA_DB)


def test_facing_edge_pairs():
    plate = sharp_edges(T.square_plate(0.05))
    pairs = facing_edge_pairs(plate)
    assert len(pairs) == 2
    np.testing.assert_allclose(pairs.width, 0.05)
    np.testing.assert_allclose(np.linalg.norm(pairs.end - pairs.start, axis=1), 0.05)
    np.testing.assert_allclose(np.linalg.norm((pairs.start + pairs.end) / 2, axis=1), 0.0,
                               atol=1e-12)
    # a plate of 2 x 2 squares: collinear pieces pair piece by piece, same total overlap
    g = np.array([[x, y, 0.0] for y in (0.0, 0.5, 1.0) for x in (0.0, 0.5, 1.0)])
    quads = [(0, 1, 4, 3), (1, 2, 5, 4), (3, 4, 7, 6), (4, 5, 8, 7)]
    faces = [f for a, b, c, d in quads for f in ((a, b, c), (a, c, d))]
    grid = facing_edge_pairs(sharp_edges(TriangleMesh(g, np.array(faces))))
    assert len(grid) == 4
    np.testing.assert_allclose(grid.width, 1.0)
    assert np.isclose(np.linalg.norm(grid.end - grid.start, axis=1).sum(), 2.0)
    # closed solids and non-parallel edges: none
    cube_like = T.dihedral(0.05, 0.05)
    assert len(facing_edge_pairs(sharp_edges(cube_like))) == 2   # each face's own sides
    assert len(facing_edge_pairs(sharp_edges(T.trihedral(0.05)))) == 0


def test_multiple_diffraction_bad_input():
    metal = po_material("metal", FREQ)
    plate = long_plate(WIDTH, 10 * LAM)
    with pytest.raises(ValueError, match="multiple_diffraction"):
        monostatic_rcs(plate, metal, [10.0], [0.0], multiple_diffraction=True)
    with pytest.raises(ValueError, match="multiple_diffraction"):
        monostatic_rcs(plate, metal, [10.0], [0.0], diffraction=True, multiple_diffraction=True,
                       range_m=20.0)
    with pytest.raises(ValueError, match="multiple_diffraction"):
        monostatic_rcs(plate, metal, [10.0], [0.0], diffraction=True, multiple_diffraction="on")
    with pytest.raises(ValueError, match="orders"):
        pair_amplitude(facing_edge_pairs(sharp_edges(plate)), np.array([0.0, 0.0, 1.0]),
                       np.array([1.0, 0.0, 0.0]), K, orders="triple")
    with pytest.raises(ValueError, match="width"):
        long_plate(0.0, 1.0)
    with pytest.raises(ValueError, match="phi_deg"):
        compare_long_plate(WIDTH, [95.0])
    with pytest.raises(ValueError, match="shape"):
        compare_long_plate(WIDTH, [5.0], shape="wedge")


def test_cli_multiple_diffraction(capsys):
    import json

    from raysim.cli import main

    base = ["rcs", "plate:0.05", "--az-deg", "70", "--el-deg", "0", "--max-bounces", "1",
            "--pol", "HH", "--no-progress"]
    assert main(base + ["--multiple-diffraction"]) == 2                # without --diffraction
    assert main(base + ["--diffraction", "--multiple-diffraction", "--range-m", "20"]) == 2
    err = capsys.readouterr().err
    assert "--multiple-diffraction" in err
    assert main(base + ["--diffraction", "--multiple-diffraction", "--json"]) == 0
    out = capsys.readouterr()
    assert "edge-pair segments" in out.err
    got = json.loads(out.out)["rcs_dbsm"][0][0]
    want = monostatic_rcs(T.square_plate(0.05), po_material("metal", FREQ), [70.0], [0.0],
                          polarisation="HH", max_bounces=1, diffraction=True,
                          multiple_diffraction=True).rcs_dbsm[0, 0]
    assert abs(got - want) < FORMULA_DB


def test_multiple_diffraction_symmetries():
    """Off the principal plane: mirror aspects, flipped windings and a shifted plate agree
    (the pairs' orientation and the midline phase reference do not matter)."""
    metal = po_material("metal", FREQ)
    plate = T.square_plate(0.05)
    flipped = TriangleMesh(plate.vertices, plate.faces[:, ::-1])
    kw = dict(polarisation="HH", max_bounces=1, diffraction=True, multiple_diffraction=True)
    a = monostatic_rcs(plate, metal, [40.0, -40.0], [5.0], **kw).rcs_dbsm[:, 0]
    b = monostatic_rcs(flipped, metal, [40.0], [5.0], **kw).rcs_dbsm[:, 0]
    assert np.all(np.isfinite(a)) and abs(a[0] - a[1]) < FORMULA_DB
    assert abs(a[0] - b[0]) < FORMULA_DB
    info = monostatic_rcs(plate, metal, [40.0], [5.0], **kw).info
    assert info["edge_pairs"] == 2 and info["pair_segments"] == 2 * math.ceil(0.05 / LAM)
    moved = TriangleMesh(plate.vertices + [0.01, -0.02, 0.003], plate.faces)
    c = monostatic_rcs(moved, metal, [40.0], [5.0], **kw).rcs_dbsm[0, 0]
    assert abs(a[0] - c) < FORMULA_DB
    on = monostatic_rcs(plate, metal, [40.0], [5.0], polarisation="HH", max_bounces=1,
                        diffraction=True).rcs_dbsm[0, 0]
    assert abs(a[0] - on) > 0.1                       # the pair term is there off-plane too
