"""The Doppler a beam grid leaves a scatterer between its beams while the radar moves.

Each beam is compensated at its own direction ``u_b`` (docs/compensation.md); a
stationary scatterer at ``u_s`` between the beams keeps the radar's velocity along
``u_s - u_b``, a pseudo-velocity no estimate removes: at 0.3 m/s across the azimuth
axis a scatterer half a 1 deg step off its beam keeps 2.6 mm/s. Measured on a flight
drifting 0.3 m/s east (5 targets, consumer MEMS, the true attitude given, the
self-calibrating command): 0.094 bin and -32.7 dB with a 1 deg azimuth and 5 deg
elevation grid, 0.023 bin and -41.1 dB with 0.25 and 0.5 deg. Where the worst such
miss over the grid exceeds :data:`GRID_MISS_BINS` the stage warns and names the step
that keeps it under.
"""

from __future__ import annotations

import numpy as np

from compensation.geometry import direction_tangents

__all__ = ["grid_miss_warning", "GRID_MISS_BINS"]

#: Largest pseudo-velocity a half-step miss may leave before a warning [Doppler bins]
#: (the bound the compensated beams are scored against, docs/conventions.md).
GRID_MISS_BINS = 0.05


def grid_miss_warning(azimuth, elevation, velocity, velocity_resolution: float) -> str | None:
    """A warning where half a grid step leaves more than :data:`GRID_MISS_BINS`, else None.

    Parameters
    ----------
    azimuth, elevation : array_like, shape ``[angle]``
        The beam grid [rad] (an axis of one beam is not judged: the scatterers' angle
        along it is not gridded).
    velocity : array_like, shape ``[frame, 3]``
        Mean radar velocity of each frame in the beams' frame [m/s].
    velocity_resolution : float
        One Doppler bin [m/s].
    """
    az, el = (np.asarray(a, dtype=float).ravel() for a in (azimuth, elevation))
    v = np.atleast_2d(np.asarray(velocity, dtype=float))
    d_az, d_el = direction_tangents(*np.meshgrid(az, el, indexing="ij"))
    said = []
    for name, grid, deriv in (("azimuth", az, d_az), ("elevation", el, d_el)):
        if grid.size < 2:
            continue
        step = float(np.max(np.abs(np.diff(grid))))
        rate = float(np.max(np.abs(deriv.reshape(-1, 3) @ v.T)))   # [m/s per rad]
        miss = 0.5 * step * rate / velocity_resolution                # [bin]
        if miss > GRID_MISS_BINS:
            fine = 2 * GRID_MISS_BINS * velocity_resolution / rate
            said.append(f"{name} step {np.rad2deg(step):.3g} deg leaves up to {miss:.2f} bin "
                        f"({1e3 * miss * velocity_resolution:.1f} mm/s) at "
                        f"{np.linalg.norm(v, axis=1).max():.2f} m/s (a step of "
                        f"{np.rad2deg(fine):.2g} deg or finer keeps it under "
                        f"{GRID_MISS_BINS:g} bin)")
    if not said:
        return None
    return ("grid: the radar moves across the beams, and a scatterer half a step off its "
            "beam keeps a pseudo-velocity no estimate removes: " + "; ".join(said))
