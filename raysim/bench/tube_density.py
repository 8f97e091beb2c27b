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

__all__ = ["TUBE_DENSITIES", "tube_density_points", "scene_trace_costs"]

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


def scene_trace_costs(scenes=("flat_reflectors", "parking_lot", "rough_terrain"), *,
                      threads: int = 2) -> list[dict]:
    """Time of one trace of each bundled scene and its PO + SBR ray tubes.

    The scene is loaded and traced once to warm the kernels, then traced again
    and timed (the tracer sized by ``MonostaticTracer.for_scene`` for the default
    radar and a 4 x 4 array).

    Returns
    -------
    list of dict
        ``scene``, ``seconds`` (wall), ``cpu_seconds``, ``paths``,
        ``geometry_targets``, ``tubes``, ``po_seconds`` and ``threads``.
    """
    from raysim.echoes.rt import backend
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.radar.arrays import upa
    from raysim.radar.config import RadarConfig

    if backend.info() is None:
        backend.configure("cpu", threads=threads)
    config = RadarConfig()
    array = upa(4, 4, wavelength=config.wavelength)
    out = []
    for name in scenes:
        scene = load_scene(name, frequency=config.carrier_frequency)
        tracer = MonostaticTracer.for_scene(scene, config, array)
        tracer(scene, config)
        wall, cpu = time.perf_counter(), time.process_time()
        paths = tracer(scene, config)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        stats = getattr(tracer, "geometry_stats", None) or {}
        out.append({"scene": name, "seconds": wall, "cpu_seconds": cpu,
                    "paths": paths.num_paths, "geometry_targets": stats.get("targets", 0),
                    "tubes": stats.get("tubes", 0), "po_seconds": stats.get("seconds", 0.0),
                    "threads": backend.info().threads})
    return out


if __name__ == "__main__":      # python -m raysim.bench.tube_density
    import json
    import os

    print(f"load average {os.getloadavg()}")
    print(json.dumps({"scenes": scene_trace_costs(), "tube_density": tube_density_points()},
                     indent=1))
