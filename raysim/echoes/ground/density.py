"""Relative two-way element pattern that sets how densely the clutter field is sampled.

The field places more scatterers where the radar sees more: the density
follows the radar's own element pattern (``RadarConfig.pattern``,
:mod:`raysim.radar.pattern`). It only sets the density; the scatterers'
amplitudes carry no pattern (the re-projection applies the two-way element
gain to every path alike).
"""

from __future__ import annotations

import numpy as np

from raysim.radar.pattern import ElementPattern, two_way_gain

__all__ = ["two_way_pattern"]


def two_way_pattern(pattern: ElementPattern, u_a) -> np.ndarray:
    """Two-way power gain relative to its peak, ``G(u)^2 / G_peak^2``, in ``[0, 1]``.

    Parameters
    ----------
    pattern : ElementPattern
        The transmit and receive element pattern.
    u_a : array_like, shape ``[..., 3]``
        Directions from the radar in frame A (not necessarily unit).

    Returns
    -------
    ndarray, shape ``[...]``
    """
    u = np.asarray(u_a, dtype=float)
    return two_way_gain(pattern, u, u) / pattern.peak_gain**2
