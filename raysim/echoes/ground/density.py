r"""Ground area of one radar resolution cell: what sets how densely the clutter field is sampled.

The field holds ``n_cell`` scatterers per resolution cell wherever the radar
can see the surface, whatever the element pattern there: a cell of
Rayleigh clutter needs several scatterers whatever its gain, and the
re-projection applies the two-way element gain to every path alike. The
count is therefore set by the surface area and the range, not by the pattern.

A cell is one range bin ``dR`` times one angular cell ``du x dv`` (direction
cosines along ``x_A``, ``y_A``). Its footprint on a facet at range ``R``,
incidence ``theta`` (from the facet normal) and boresight angle ``b`` is the
smaller of

* the angular footprint ``R^2 du dv / (cos b cos theta)`` (the solid angle
  ``du dv / cos b`` projected on the facet; it wins near normal incidence,
  where the range shell cuts the facet in a wide disc), and
* the range ring times the cross-range width, ``(dR / sin theta) R sqrt(du dv)``
  (the cross-range cell grows with range).

On flat ground seen from height ``h`` the ring between ``R`` and ``R + dR``
has the area ``2 pi R dR`` exactly (``rho d rho = R dR``), so the second form
splits it into ``2 pi sin(theta) / sqrt(du dv)`` cells of the radar's angular
width.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["resolution_cell_area", "MIN_COS"]

#: Smallest cosine (incidence, boresight angle) and sine (incidence) used in the cell area:
#: it bounds the area of a cell seen edge-on.
MIN_COS = 1e-3


def resolution_cell_area(r, cos_b, cos_i, dr: float, du: float, dv: float) -> np.ndarray:
    """Area of one range x angle resolution cell on a facet [m^2] (module notes).

    Parameters
    ----------
    r : array_like, shape ``[...]``
        Range from the radar [m].
    cos_b : array_like, shape ``[...]``
        Cosine of the angle between the line of sight and boresight.
    cos_i : array_like, shape ``[...]``
        Cosine of the incidence angle from the facet normal.
    dr : float
        Range resolution [m].
    du, dv : float
        Angular resolution in direction cosines
        (:func:`raysim.echoes.ground.field.angular_resolution`).

    Returns
    -------
    ndarray, shape ``[...]``
    """
    r = np.asarray(r, dtype=float)
    ci = np.clip(np.asarray(cos_i, dtype=float), MIN_COS, 1.0)
    cb = np.clip(np.asarray(cos_b, dtype=float), MIN_COS, 1.0)
    si = np.maximum(np.sqrt(1.0 - ci**2), MIN_COS)
    a_ang = r**2 * du * dv / (cb * ci)
    a_rng = dr / si * r * math.sqrt(du * dv)
    return np.minimum(a_ang, a_rng)
