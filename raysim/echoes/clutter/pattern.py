"""Two-way element power pattern used to thin the clutter field where the radar sees little.

One function, :func:`two_way_pattern`, so that the stand-in (``cos^q`` per
element, Balanis, *Antenna Theory*, 4th ed., sec. 2.5 example patterns) can be
swapped for the project's element pattern in one place. It only sets how
densely scatterers are placed; their amplitudes carry no pattern (the element
pattern, where modelled, applies to every path alike at re-projection).
"""

from __future__ import annotations

import numpy as np

__all__ = ["two_way_pattern", "COS_EXPONENT"]

#: Exponent ``q`` of the one-way ``cos^q`` power pattern stand-in (about +-60 deg at -3 dB for q=1).
COS_EXPONENT = 1.0


def two_way_pattern(cos_off_boresight, q: float = COS_EXPONENT) -> np.ndarray:
    """Two-way power pattern ``cos^(2q)`` of the angle off boresight, in ``[0, 1]``.

    Parameters
    ----------
    cos_off_boresight : array_like
        Cosine of the angle between the direction and boresight ``+z_A``.
    q : float
        One-way power exponent, >= 0.

    Returns
    -------
    ndarray, shape of ``cos_off_boresight``
    """
    if not q >= 0:
        raise ValueError(f"q must be >= 0, got {q!r}")
    c = np.clip(np.asarray(cos_off_boresight, dtype=float), 0.0, 1.0)
    return c ** (2.0 * q)
