"""Doppler ridge leakage of a scene's range-Doppler map: the one definition of ``ridge_leakage_db``.

A stationary platform sees static clutter on the zero-Doppler ridge; platform
motion spreads it over Doppler. :func:`ridge_leakage_db` is the RD-map power
outside the ridge (Doppler bins ``-RIDGE_HALF_WIDTH_BINS .. +RIDGE_HALF_WIDTH_BINS``
around zero, the Hann mainlobe) relative to the map's total, in dB
(:data:`raysim.vocabulary.METRICS` ``ridge_leakage_db``; docs/conventions.md).
"""

from __future__ import annotations

import numpy as np

__all__ = ["RIDGE_HALF_WIDTH_BINS", "ridge_bins", "ridge_leakage_db"]

#: Doppler bins either side of zero counted as the stationary clutter ridge
#: (the Hann mainlobe: bins -1, 0, +1).
RIDGE_HALF_WIDTH_BINS = 1


def ridge_bins(num_doppler: int, half_width: int = RIDGE_HALF_WIDTH_BINS) -> slice:
    """Doppler bins of the zero-Doppler ridge on a centred Doppler axis of ``num_doppler`` bins.

    Zero Doppler is bin ``num_doppler // 2`` (the axis of
    :func:`raysim.processing.maps.doppler_fft`).
    """
    if not (isinstance(num_doppler, (int, np.integer)) and num_doppler >= 2 * half_width + 2):
        raise ValueError(f"num_doppler must be an integer >= {2 * half_width + 2} (the ridge "
                         f"+-{half_width} bins and some bins off it), got {num_doppler!r}")
    centre = int(num_doppler) // 2
    return slice(centre - half_width, centre + half_width + 1)


def ridge_leakage_db(rd, half_width: int = RIDGE_HALF_WIDTH_BINS) -> float:
    """RD power outside the zero-Doppler ridge relative to the total [dB].

    Parameters
    ----------
    rd : array_like, shape ``[range, doppler]``
        Non-negative RD power [W] on a centred Doppler axis (zero at bin
        ``doppler // 2``), e.g. the ``rd`` map of :func:`raysim.measure.scene.measure_scene`.
    half_width : int
        Ridge half-width [Doppler bins] (default :data:`RIDGE_HALF_WIDTH_BINS`).

    Returns
    -------
    float
        ``10 log10((P_total - P_ridge) / P_total)`` [dB]; about -3000 dB when
        all power lies on the ridge.
    """
    p = np.asarray(rd, dtype=float)
    if p.ndim != 2 or p.size == 0 or np.any(p < 0) or not np.all(np.isfinite(p)):
        raise ValueError(f"rd must be a finite non-negative [range, doppler] power map, got "
                         f"shape {p.shape}")
    total = p.sum()
    if not total > 0:
        raise ValueError("rd holds no power (all zeros): the ridge leakage is undefined")
    ridge = p[:, ridge_bins(p.shape[1], half_width)].sum()
    return float(10 * np.log10(max(total - ridge, 0.0) / total + 1e-300))
