"""The 2-D method of moments (raysim.echoes.po.mom2d) against closed forms.

Closed forms: a wide strip's broadside echo width ``k w^2`` (physical optics,
exact as ``w / lambda -> oo``; the edges' first-order fringe wave, relative
amplitude ``1 / (k w)``, bounds the difference: Ufimtsev, *Fundamentals of the
Physical Theory of Diffraction*, 2007); a circular cylinder's eigenfunction
series (Balanis, *Advanced Engineering Electromagnetics*, 2nd ed., 2012, ch. 11,
scattering by a circular cylinder:
``sigma_2D = (4/k) |sum_n (-1)^n J_n(ka) / H_n^(2)(ka)|^2`` for TM, ``J_n'`` and
``H_n^(2)'`` for TE) for a polygon of many facets.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.special as sp

from raysim.echoes.po import mom2d as M

LAM = 1.0
K = 2 * math.pi / LAM
#: Strip of 10 wavelengths at broadside vs ``k w^2`` [dB]: the two edges' first-order
#: fringe, ``2 (1/2) / (2 pi)`` per unit length against PO's ``w / lambda``, i.e. a
#: relative amplitude ``1 / (k w)``.
STRIP_WIDTH = 10.0
STRIP_BROADSIDE_DB = 20 * math.log10(1 + 1 / (K * STRIP_WIDTH))
#: Faceted circle (facets and segments of lambda / 20) vs the exact series [dB]: the
#: polygon's area and the currents' discretisation, both O((segment / lambda)^2).
CYLINDER_DB = 0.03
#: Error ratio per halving of the segment length: at least first order (second expected).
CONVERGENCE_RATIO = 2.0
#: Rounding only (mirror image, translation, matrix symmetry) [dB, relative].
SYMMETRY_DB = 1e-6
SYMMETRY_REL = 1e-10
#: A thin closed rectangle with segments of lambda/20 vs lambda/40 [dB] (the
#: convergence measured on the circle, about 0.01 dB, with margin for the thin body).
SEGMENT_DB = 0.05


def db(x):
    return 10 * np.log10(x)


def ref_cylinder(ka: float, pol: str, terms: int = 60) -> float:
    """Exact monostatic echo width of a PEC circular cylinder [m] (Balanis ch. 11)."""
    n = np.arange(-terms, terms + 1)
    if pol == "TM":
        c = sp.jv(n, ka) / sp.hankel2(n, ka)
    else:
        c = sp.jvp(n, ka) / sp.h2vp(n, ka)
    return 4 / K * abs(np.sum((-1.0) ** n * c)) ** 2


def test_series_reference_reaches_geometric_optics():
    """The series itself: ``sigma_2D -> pi a`` for a large cylinder (both polarisations)."""
    a = 20 * LAM
    for pol in ("TM", "TE"):
        assert abs(db(ref_cylinder(K * a, pol, terms=300) / (math.pi * a))) < 0.1


@pytest.mark.parametrize("pol", ["TM", "TE"])
def test_wide_strip_broadside_is_k_w2(pol):
    errs = []
    for w in (5.0, STRIP_WIDTH, 20.0):
        res = M.echo_width(M.strip(w * LAM, LAM / M.SEGMENTS_PER_WAVELENGTH), LAM, [0.0], pol)
        errs.append(abs(db(res.echo_width_m[0] / (K * (w * LAM) ** 2))))
    assert errs[1] < STRIP_BROADSIDE_DB
    # the edge terms fade as the strip widens
    assert errs[0] > errs[1] > errs[2]


@pytest.mark.parametrize("pol", ["TM", "TE"])
@pytest.mark.parametrize("radius", [0.5, 1.0])
def test_faceted_cylinder_matches_series(pol, radius):
    """ka = pi and 2 pi, away from the interior resonances (J_0, J_1 of ka not small)."""
    ka = K * radius
    assert min(abs(sp.j0(ka)), abs(sp.j1(ka))) > 0.2
    sides = round(2 * math.pi * radius * M.SEGMENTS_PER_WAVELENGTH)
    res = M.echo_width(M.regular_polygon(radius, sides), LAM, [0.0, 7.0, 90.0], pol)
    np.testing.assert_allclose(db(res.echo_width_m / ref_cylinder(ka, pol)), 0.0,
                               atol=CYLINDER_DB)


@pytest.mark.parametrize("pol", ["TM", "TE"])
def test_converges_with_segments_per_wavelength(pol):
    radius = 0.5
    exact = ref_cylinder(K * radius, pol)
    errs = [abs(db(M.echo_width(M.regular_polygon(radius, round(math.pi * spl)), LAM, [0.0],
                                pol).echo_width_m[0] / exact)) for spl in (10, 20, 40)]
    assert errs[0] > CONVERGENCE_RATIO * errs[1] > CONVERGENCE_RATIO**2 * errs[2]


@pytest.mark.parametrize("pol", ["TM", "TE"])
def test_strip_symmetries(pol):
    """Mirror aspects and a shifted strip give the same echo width; Z is symmetric."""
    angles = [20.0, 55.0]
    base = M.echo_width(M.strip(3 * LAM, LAM / 20), LAM, angles + [-a for a in angles], pol)
    np.testing.assert_allclose(db(base.echo_width_m[:2]), db(base.echo_width_m[2:]),
                               atol=SYMMETRY_DB)
    moved = M.polyline([[-1.2 * LAM, 0.7 * LAM], [1.8 * LAM, 0.7 * LAM]], LAM / 20)
    shifted = M.echo_width(moved, LAM, angles, pol)
    np.testing.assert_allclose(db(shifted.echo_width_m), db(base.echo_width_m[:2]),
                               atol=1e-6)
    z = M._impedance(M.strip(3 * LAM, LAM / 20), K, pol)
    np.testing.assert_allclose(z, z.T, rtol=SYMMETRY_REL, atol=SYMMETRY_REL * abs(z).max())


@pytest.mark.parametrize("pol", ["TM", "TE"])
def test_winding_does_not_matter(pol):
    """The same polygon run clockwise and anticlockwise (the TE rooftops' direction)."""
    square = np.array([[-0.8, -0.8], [0.8, -0.8], [0.8, 0.8], [-0.8, 0.8]]) * LAM
    angles = [0.0, 25.0, 45.0]
    one = M.echo_width(M.polyline(square, LAM / 20, closed=True), LAM, angles, pol)
    other = M.echo_width(M.polyline(square[::-1], LAM / 20, closed=True), LAM, angles, pol)
    np.testing.assert_allclose(db(one.echo_width_m), db(other.echo_width_m), atol=SYMMETRY_DB)


def test_thin_closed_rectangle_tends_to_the_strip_tm():
    """A closed rectangle around a strip (TM) tends to the zero-thickness strip as it thins.

    Slowly (the end faces and the edge-singular current: measured 0.33 dB at
    ``t = lambda/100``, 1.3 dB at ``lambda/20`` at 60 deg), and independently of the
    segment length once segments are below ``lambda/20``.
    """
    w = 3 * LAM
    angles = [10.8, 30.0, 60.0]
    thin = db(M.echo_width(M.strip(w, LAM / 20), LAM, angles, "TM").echo_width_m)

    def box(t, seg):
        c = M.polyline([[-w / 2, -t / 2], [w / 2, -t / 2], [w / 2, t / 2], [-w / 2, t / 2]],
                       seg, closed=True)
        return db(M.echo_width(c, LAM, angles, "TM").echo_width_m)

    diffs = [np.abs(box(t, LAM / 20) - thin) for t in (LAM / 20, LAM / 50, LAM / 100)]
    assert np.all(diffs[0] > diffs[1]) and np.all(diffs[1] > diffs[2])
    np.testing.assert_allclose(box(LAM / 100, LAM / 40), box(LAM / 100, LAM / 20),
                               atol=SEGMENT_DB)


def test_te_strip_edge_on_is_dark():
    """TE at exactly edge-on: the incident E is normal to the sheet, nothing drives a current."""
    res = M.echo_width(M.strip(2 * LAM, LAM / 20), LAM, [90.0, 0.0], "TE")
    assert res.echo_width_m[0] < 1e-20 * res.echo_width_m[1]


def test_bad_input():
    s = M.strip(LAM, LAM / 10)
    with pytest.raises(ValueError, match="polarisation"):
        M.echo_width(s, LAM, [0.0], "VV")
    with pytest.raises(ValueError, match="wavelength"):
        M.echo_width(s, 0.0, [0.0])
    with pytest.raises(ValueError, match="phi_deg"):
        M.echo_width(s, LAM, [np.nan])
    with pytest.raises(ValueError, match="Contour"):
        M.echo_width([[0, 0], [1, 0]], LAM, [0.0])
    with pytest.raises(ValueError, match="unknowns"):
        M.echo_width(M.strip(100 * LAM, LAM / 20), LAM, [0.0])
    with pytest.raises(ValueError, match="TE unknowns"):
        M.echo_width(M.strip(LAM, 2 * LAM), LAM, [0.0], "TE")
    with pytest.raises(ValueError, match="distinct"):
        M.polyline([[0, 0], [0, 0], [1, 0]], 0.1)
    with pytest.raises(ValueError, match="vertices"):
        M.polyline([[0, 0], [1, 0]], 0.1, closed=True)
    with pytest.raises(ValueError, match="max_segment"):
        M.strip(LAM, -1.0)
    with pytest.raises(ValueError, match="sides"):
        M.regular_polygon(LAM, 2)
    with pytest.raises(ValueError, match="nodes"):
        M.Contour(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="distinct"):
        M.Contour(np.array([[0.0, 0.0], [0.0, 0.0]]))
