"""The array's highest sidelobe, and the autofocus cells it lets through.

Closed form: a uniformly weighted line of ``N`` half-wavelength elements has the
pattern ``|sin(N psi / 2) / (N sin(psi / 2))|^2`` (``psi = pi s``, ``s`` the
direction-cosine difference), whose first sidelobe tends to -13.26 dB as ``N``
grows (the ``sin x / x`` sidelobe at ``x = 4.493``; Van Trees, "Optimum Array
Processing", 2002, sec. 2.4).
"""

from __future__ import annotations

import numpy as np
import pytest

from compensation.sidelobes import (
    MIN_SIDELOBE_MARGIN_DB,
    SIDELOBE_DB,
    main_lobe_cells,
    peak_sidelobe_db,
    sidelobe_margin_db,
)

LAMBDA = 299_792_458.0 / 77e9
#: A grid of +-60 deg in azimuth and one elevation.
AZ = np.deg2rad(np.arange(-60.0, 60.01, 0.5))
EL0 = np.zeros(1)
#: The sin x / x first sidelobe [dB] and the closeness a 64-element line reaches it.
SINC_SIDELOBE_DB = 20 * np.log10(np.abs(np.sin(4.4934) / 4.4934))
SINC_TOL_DB = 0.05


def _line(n: int, axis: int = 0) -> np.ndarray:
    p = np.zeros((n, 3))
    p[:, axis] = np.arange(n) * LAMBDA / 2
    return p


def test_a_long_uniform_line_has_the_sinc_sidelobe():
    assert abs(peak_sidelobe_db(_line(64), LAMBDA, AZ, EL0) - SINC_SIDELOBE_DB) <= SINC_TOL_DB


def _dirichlet_db(n: int, s) -> np.ndarray:
    """The closed-form pattern [dB] of ``n`` uniform half-wavelength elements at ``s``."""
    psi = np.pi * np.asarray(s, dtype=float)
    return 20 * np.log10(np.abs(np.sin(n * psi / 2) / (n * np.sin(psi / 2))))


#: Agreement with the closed form [dB] (the cut's sampling).
CLOSED_FORM_TOL_DB = 0.01


def test_a_short_aperture_comes_closer_and_lowers_the_margin():
    """Four elements: the first sidelobe (-11.30 dB, between the nulls at s = 0.5 and 1)
    on a +-30 deg grid; on +-60 deg a scatterer at one edge reaches the beams at the
    other (s = 2 sin 60 deg), on the way to the grating lobe at s = 2."""
    first = float(_dirichlet_db(4, np.linspace(0.51, 0.99, 20001)).max())
    narrow = peak_sidelobe_db(_line(4), LAMBDA, np.deg2rad(np.arange(-30.0, 30.01, 0.5)), EL0)
    assert abs(narrow - first) <= CLOSED_FORM_TOL_DB, (narrow, first)
    wide = peak_sidelobe_db(_line(4), LAMBDA, AZ, EL0)
    edge = float(_dirichlet_db(4, 2 * np.sin(np.deg2rad(60.0))))
    assert abs(wide - edge) <= CLOSED_FORM_TOL_DB, (wide, edge)
    assert sidelobe_margin_db(first) < SIDELOBE_DB
    assert sidelobe_margin_db(peak_sidelobe_db(_line(64), LAMBDA, AZ, EL0)) == SIDELOBE_DB
    assert sidelobe_margin_db(0.0) == MIN_SIDELOBE_MARGIN_DB


def test_no_sidelobe_where_the_grid_cannot_hold_one():
    assert peak_sidelobe_db(np.zeros((1, 3)), LAMBDA, AZ, EL0) == -np.inf
    # a line along x seen on a grid of one azimuth: its cut is empty
    assert peak_sidelobe_db(_line(12), LAMBDA, np.zeros(1), np.deg2rad([-5.0, 0.0, 5.0])) \
        == -np.inf


def test_cells_within_the_margin_of_their_gate_are_kept():
    x = np.ones((8, 2 * 3), complex)
    x[:, 1] *= np.sqrt(0.2)          # gate 0: -7 dB beside its strongest
    x[:, 2] *= np.sqrt(0.05)         # gate 0: -13 dB
    sel = np.arange(6)
    assert list(main_lobe_cells(x, sel, (2, 3), 10.0)) == [0, 1, 3, 4, 5]
    assert list(main_lobe_cells(x, sel, (2, 3), 5.0)) == [0, 3, 4, 5]


@pytest.mark.parametrize("bad", [np.zeros((3, 2)), np.full((2, 3), np.nan)])
def test_bad_positions_refused(bad):
    with pytest.raises(ValueError, match="element_positions"):
        peak_sidelobe_db(bad, LAMBDA, AZ, EL0)
