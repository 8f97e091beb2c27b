"""Elevation of a scatterer by phase comparison across a short vertical baseline.

The TI xWR18xx / IWR6843 boards raise one TX by half a wavelength: their virtual
array is an azimuth row plus a row above it, ``d = lambda/2`` apart. That extent is
far too short for an elevation beam, but the phase between the rows measures the
elevation (phase-comparison monopulse, an interferometer; Skolnik, Introduction to
Radar Systems, 3rd ed., sec. 9.3): the whole array's beam power at the scatterer's
azimuth is

    P(el) = |A|^2 + |B|^2 + 2 |A B| cos(k d (sin el - sin el0)),

``A`` the azimuth row's beam, ``B`` the raised row's, ``k = 2 pi / lambda``. Its
one maximum over +-90 deg (``k d = pi``: one cosine period across ``sin el`` in
[-1, 1], no ambiguity) is the estimate ``el0``. Each beam is formed with the
platform's motion (:func:`compensation.rigid_body_projection`), so ``el0`` is in the
world frame W like the azimuth.
"""

from __future__ import annotations

import numpy as np

from .exact import rigid_body_projection
from .strapdown import PlatformMotion

__all__ = ["ELEVATION_AXIS", "ELEVATION_SIGMA_FLOOR", "measure_elevation",
           "vertical_baseline"]

#: Elevation grid of the comparison [rad]: +-88 deg in 1 deg steps (the ambiguity-free
#: range less the last steps, where ``sin el`` hardly changes).
ELEVATION_AXIS = np.deg2rad(np.arange(-88.0, 88.5, 1.0))
#: Floor of a measured elevation's spread [rad]: the phase error the per-chirp scatter
#: does not show (multipath, clutter in the same range cell and beam, the channels'
#: phase mismatch of a few degrees: 10 deg of phase is 3.2 deg of elevation at
#: broadside for ``d = lambda/2``, reduced by the rows' coherent sums).
ELEVATION_SIGMA_FLOOR = float(np.deg2rad(1.0))
#: Smallest height difference [wavelengths] that counts as a vertical baseline.
MIN_BASELINE_WAVELENGTHS = 0.1


def vertical_baseline(positions, wavelength: float, beam_wavelengths: float) -> bool:
    """Whether the array has elements at two heights (y), at least
    :data:`MIN_BASELINE_WAVELENGTHS` apart, but spans fewer than ``beam_wavelengths``
    wavelengths along y (too few to resolve elevation as a beam)."""
    y = np.asarray(positions, dtype=float)[:, 1]
    return bool(MIN_BASELINE_WAVELENGTHS * wavelength <= np.ptp(y)
                < beam_wavelengths * wavelength)


def _vertex(q: np.ndarray, axis: np.ndarray) -> float:
    """Position [rad] of the maximum of ``q [el]``, refined by the parabola through it and
    its neighbours (``P`` is a cosine: near-quadratic at its peak); NaN when the maximum
    is on the grid's edge (no peak inside it)."""
    e = int(np.argmax(q))
    if not 0 < e < axis.size - 1:
        return float("nan")
    lo, mid, hi = q[e - 1], q[e], q[e + 1]
    den = lo - 2.0 * mid + hi
    f = 0.0 if den >= 0 else float(np.clip(0.5 * (lo - hi) / den, -0.5, 0.5))
    return float(axis[e] + f * (axis[1] - axis[0]))


def measure_elevation(rc, positions, motion: PlatformMotion, azimuth: float, options
                      ) -> tuple[float, float] | None:
    """Elevation of the scatterer at ``azimuth`` in a range gate (module docstring).

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, gate]``
        The range-compressed frame at the scatterer's range gate(s).
    positions : array_like, shape ``[channel, 3]``
        Virtual element positions in A [m] (a vertical baseline, :func:`vertical_baseline`).
    motion : PlatformMotion
        Motion of the frame.
    azimuth : float
        The scatterer's azimuth in W [rad].
    options : dict
        For :func:`compensation.rigid_body_projection` (``wavelength`` and
        ``range_axis`` of the gate(s) included).

    Returns
    -------
    (float, float) or None
        Elevation in W [rad], from the chirps' mean power in the first gate, and its
        spread [rad]: the chirps' scatter over the root of their number with
        :data:`ELEVATION_SIGMA_FLOOR` added in quadrature. None (not measured) when
        the power of the mean or of a chirp peaks on the grid's edge (no maximum in
        it: several scatterers in the cell, or one beyond +-88 deg) or the frame
        has one chirp.
    """
    b = rigid_body_projection(rc, positions, motion, azimuth=[float(azimuth)],
                              elevation=ELEVATION_AXIS, **options)
    p = np.abs(b.data[:, 0, 0, :]) ** 2                      # [chirp, el]
    est = _vertex(p.mean(axis=0), ELEVATION_AXIS)
    each = np.array([_vertex(q, ELEVATION_AXIS) for q in p])
    if not np.isfinite(est) or not np.all(np.isfinite(each)) or each.size < 2:
        return None
    stat = float(np.std(each, ddof=1) / np.sqrt(each.size))
    return est, float(np.hypot(stat, ELEVATION_SIGMA_FLOOR))
