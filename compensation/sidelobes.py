"""Which beam cells may be another scatterer's sidelobe: the array's highest sidelobe.

A beam steered at ``u`` sees a scatterer at ``u1`` with the uniformly weighted
virtual array's pattern ``P(u - u1) = |sum_m exp(j k (u - u1) . p_m)|^2 / M^2``
(``k = 2 pi / lambda``, ``p_m`` the virtual element positions, steering of
:func:`compensation.projection.beam_projection`). Beyond the main lobe its
highest value, the peak sidelobe level, bounds what a single scatterer puts in
other beams of its range gate: a local maximum of the beams weaker than the
gate's strongest by less than that level (and a guard) may be a real second
scatterer or that sidelobe, and an autofocus cannot tell. A sidelobe carries
its scatterer's slow-time phase at another direction: the motion removed at
the beam's direction, not at the scatterer's, leaves it a Doppler
``2 k (u - u1) . v`` (the platform's whole velocity ``v`` across the two
directions) that a fit taking it for a stationary scatterer reads as a
velocity error. A four-element aperture (the IWR6843AOP's and ODS's 4 x 4
grids) has sidelobes near -10 dB; a twelve-element line near -13 dB.

The level is found on the two direction-cosine cuts through the main lobe
(along the array's azimuth axis ``x`` and elevation axis ``y``), over the
differences the beam grid can hold (a linear array's elevation main lobe is
wider than any grid's: no sidelobe there); the main lobe ends at the first
minimum on each side.
"""

from __future__ import annotations

import numpy as np

from ._checks import finite_array, positive
from .geometry import direction

__all__ = ["SIDELOBE_DB", "SIDELOBE_GUARD_DB", "MIN_SIDELOBE_MARGIN_DB", "array_margin_db",
           "main_lobe_cells", "peak_sidelobe_db", "sidelobe_margin_db"]

#: A selected cell is kept only within this many dB of the strongest cell of its range
#: gate (where the array's sidelobes are lower still): cells further down are more likely
#: far sidelobes than scatterers, and a weaker scatterer in the same gate goes with them.
SIDELOBE_DB = 10.0
#: A cell must exceed the highest sidelobe the gate's strongest scatterer can put in its
#: beam by this much [dB] (the pattern's own level moves with the look direction and a
#: second scatterer in the gate adds to it).
SIDELOBE_GUARD_DB = 3.0
#: The smallest margin [dB] used, for an array whose sidelobes reach its main lobe.
MIN_SIDELOBE_MARGIN_DB = 1.0
#: Samples of each direction-cosine cut, and the least step of the normalised pattern
#: that counts as a rise (rounding aside).
CUT_SAMPLES = 4001
RISE_TOL = 1e-9


def peak_sidelobe_db(element_positions, wavelength: float, azimuth, elevation) -> float:
    """Highest sidelobe of the uniformly weighted virtual array [dB relative to the main lobe].

    Parameters
    ----------
    element_positions : array_like, shape ``[channel, 3]``
        Virtual element positions in the radar frame [m] (``x`` azimuth, ``y`` elevation).
    wavelength : float
        [m].
    azimuth, elevation : array_like, shapes ``[azimuth]``, ``[elevation]``
        The beam grid [rad]: the differences of direction cosines it spans bound the cuts.

    Returns
    -------
    float
        At most 0; ``-inf`` where no cut has a sidelobe within the grid's span.
    """
    p = finite_array("element_positions", element_positions, ndim=2)
    if p.shape[1] != 3:
        raise ValueError(f"element_positions must have shape [channel, 3], got {p.shape}")
    k = 2 * np.pi / positive("wavelength", wavelength)
    a, e = np.meshgrid(finite_array("azimuth", azimuth, ndim=1),
                       finite_array("elevation", elevation, ndim=1), indexing="ij")
    u = direction(a.ravel(), e.ravel())
    worst = -np.inf
    for axis in (0, 1):
        span = float(np.ptp(u[:, axis]))
        if span <= 0:
            continue
        s = np.linspace(-span, span, CUT_SAMPLES)
        pattern = np.abs(np.exp(1j * k * np.outer(s, p[:, axis])).sum(axis=1)) ** 2
        pattern = pattern / pattern[CUT_SAMPLES // 2]
        # the main lobe runs from the peak down to the first rise on each side
        c, d = CUT_SAMPLES // 2, np.diff(pattern)
        right = np.flatnonzero(d[c:] > RISE_TOL)
        left = np.flatnonzero(d[:c][::-1] < -RISE_TOL)
        outside = np.concatenate([pattern[c + right[0]:] if right.size else [],
                                  pattern[:c - left[0] + 1] if left.size else []])
        if outside.size:
            worst = max(worst, 10 * np.log10(max(float(outside.max()), 1e-30)))
    return min(worst, 0.0)


def sidelobe_margin_db(psl_db: float) -> float:
    """How far [dB] below its gate's strongest a cell may lie and be kept: :data:`SIDELOBE_DB`,
    or less where the array's sidelobes ``psl_db`` come closer than that and the guard."""
    return float(max(MIN_SIDELOBE_MARGIN_DB, min(SIDELOBE_DB, -psl_db - SIDELOBE_GUARD_DB)))


def array_margin_db(element_positions, wavelength: float, azimuth, elevation) -> float:
    """:func:`sidelobe_margin_db` of the array's :func:`peak_sidelobe_db` on the beam grid."""
    return sidelobe_margin_db(peak_sidelobe_db(element_positions, wavelength, azimuth,
                                               elevation))


def main_lobe_cells(x: np.ndarray, sel: np.ndarray, cell_shape: tuple,
                    margin_db: float = SIDELOBE_DB) -> np.ndarray:
    """The selected cells less those ``margin_db`` or more below the strongest of their
    range gate (the first axis of ``cell_shape``).

    Parameters
    ----------
    x : ndarray, shape ``[chirp, cell]``
    sel : ndarray of int
        Flat indices of the selected cells into ``cell_shape``.
    cell_shape : tuple
        ``(range, ...)``.
    margin_db : float
        :func:`sidelobe_margin_db` of the array.
    """
    if sel.size == 0:
        return sel
    p = np.mean(np.abs(x[:, sel]) ** 2, axis=0)
    gate = np.unravel_index(sel, cell_shape)[0]
    top = np.zeros(int(gate.max()) + 1)
    np.maximum.at(top, gate, p)
    return sel[p > top[gate] * 10 ** (-float(margin_db) / 10)]
