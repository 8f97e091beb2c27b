"""Speed versus accuracy of the SBR ray-tube density on a trihedral reflector.

A triangular trihedral of edge ``a`` seen on its axis from ``range_m`` is traced
by :func:`raysim.echoes.po.paths.scattering_terms` at several tube densities;
each point gives the tubes launched, the wall and CPU seconds, and the error
of the RCS against the closed form ``4 pi a^4 / (3 lambda^2)`` (Knott,
Shaeffer & Tuley, *Radar Cross Section*, 2nd ed., table 6.1). The points are
meant for the speed chart (tubes or seconds against error).
"""

from __future__ import annotations

import math
import time

from raysim.radar.config import SPEED_OF_LIGHT

__all__ = ["TUBE_DENSITIES", "tube_density_points"]

#: Default tube densities [tubes per wavelength per transverse axis].
TUBE_DENSITIES = (0.5, 1.0, 2.0, 4.0, 10.0)


def tube_density_points(densities=TUBE_DENSITIES, *, edge: float = 0.1,
                        range_m: float = 15.0, frequency: float = 77e9,
                        repeats: int = 1) -> list[dict]:
    """One point per tube density.

    Parameters
    ----------
    densities : sequence of float
        Tubes per wavelength along each transverse axis (> 0).
    edge : float
        Trihedral edge [m].
    range_m : float
        Radar distance from the apex along the axis [m] (the closed form is a
        far-field value: keep ``range_m`` above ``2 D^2 / lambda``, ``D = a sqrt 2``).
    frequency : float
        Carrier [Hz].
    repeats : int
        Timings are the best of this many runs.

    Returns
    -------
    list of dict
        ``tubes_per_wavelength``, ``tubes``, ``terms``, ``seconds`` (wall),
        ``cpu_seconds``, ``rcs_dbsm``, ``closed_form_dbsm``, ``error_db`` (signed).

    Raises
    ------
    ValueError
        Empty or non-positive densities, a non-positive edge, range or repeats.
    """
    from raysim.echoes.po.paths import scattering_terms
    from raysim.echoes.po.targets import trihedral, trihedral_rcs

    dens = [float(d) for d in densities]
    if not dens or not all(math.isfinite(d) and d > 0 for d in dens):
        raise ValueError(f"densities must be a non-empty list of positive numbers, "
                         f"got {densities!r}")
    for name, value in (("edge", edge), ("range_m", range_m), ("frequency", frequency)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be > 0, got {value!r}")
    if int(repeats) != repeats or repeats < 1:
        raise ValueError(f"repeats must be an integer >= 1, got {repeats!r}")
    mesh = trihedral(edge)
    closed = 10 * math.log10(trihedral_rcs(edge, SPEED_OF_LIGHT / frequency))
    points = []
    for d in dens:
        best_wall = best_cpu = math.inf
        for _ in range(int(repeats)):
            wall, cpu = time.perf_counter(), time.process_time()
            terms = scattering_terms(mesh, "metal", [0.0, 0.0, range_m], [0.0, 0.0, 0.0],
                                     frequency=frequency, tubes_per_wavelength=d)
            best_wall = min(best_wall, time.perf_counter() - wall)
            best_cpu = min(best_cpu, time.process_time() - cpu)
        rcs = 10 * math.log10(max(terms.rcs_m2, 1e-30))
        points.append({"tubes_per_wavelength": d, "tubes": terms.tubes,
                       "terms": len(terms.amplitude), "seconds": best_wall,
                       "cpu_seconds": best_cpu, "rcs_dbsm": rcs, "closed_form_dbsm": closed,
                       "error_db": rcs - closed})
    return points
