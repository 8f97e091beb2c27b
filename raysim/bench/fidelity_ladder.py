"""Speed against accuracy of the fidelity ladder: the geometry targets of a scene per level.

Settings: every geometry target at the point level, at its reduced centres, at
the level ``"auto"`` picks (tolerance :data:`raysim.echoes.po.fidelity.DEFAULT_FIDELITY_TOLERANCE`)
and at its mesh (the reference and today's default). Time: CPU seconds of one
frame's geometry-target paths (:func:`raysim.echoes.po.paths.geometry_paths`) and
their IF synthesis, in steady state, i.e. with the reduced models re-used from
the frame before (the first frame of a reduced level costs the mesh's trace plus
the choice; ``first_s`` gives it). Error: relative l2 of the targets' IF cube
against the mesh level's, over the whole frame.
"""

from __future__ import annotations

import time

import numpy as np

__all__ = ["LADDER_SCENE", "LADDER_CHIRPS", "LADDER_ARRAY", "fidelity_ladder_points"]

#: Bundled scene of the panel (six car meshes and the facade corner).
LADDER_SCENE = "parking_lot"
#: Chirps per frame (quick, full).
LADDER_CHIRPS = {True: 16, False: 64}
#: Side of the UPA.
LADDER_ARRAY = 8


def fidelity_ladder_points(*, quick: bool, scene: str = LADDER_SCENE,
                           num_chirps: int | None = None, array_size: int | None = None,
                           tolerance: float | None = None) -> list[dict]:
    """Time and error of every fidelity setting on one scene's geometry targets.

    Parameters
    ----------
    quick : bool
        Chirps per frame from :data:`LADDER_CHIRPS`.
    scene : str
        Bundled scene with geometry targets.
    num_chirps, array_size : int, optional
        Override the frame (chirps; UPA side).
    tolerance : float, optional
        Of ``"auto"`` (default the ladder's).

    Returns
    -------
    list of dict
        Per setting (``point``, ``centres``, ``auto``, ``mesh``): ``setting``,
        ``s_per_frame`` (CPU s, steady state), ``first_s`` (CPU s of the first
        frame: trace and choice), ``rel_error``, ``paths``, ``levels`` (objects
        per level), ``reference`` (mesh).
    """
    from raysim.echoes.po.fidelity import DEFAULT_FIDELITY_TOLERANCE, FidelityLadder
    from raysim.echoes.po.paths import geometry_paths
    from raysim.echoes.rt.reproject import synthesize_paths
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import PathSet
    from raysim.radar.arrays import upa
    from raysim.radar.config import RadarConfig
    from raysim.radar.pattern import PATTERN_FLOOR_DB

    cfg = RadarConfig(num_chirps=LADDER_CHIRPS[quick] if num_chirps is None else num_chirps)
    side = LADDER_ARRAY if array_size is None else array_size
    arr = upa(side, side, wavelength=cfg.wavelength)
    tol = DEFAULT_FIDELITY_TOLERANCE if tolerance is None else tolerance
    sc = load_scene(scene, frequency=cfg.carrier_frequency)
    targets = [t for t in sc.targets if t.is_geometry]
    if not targets:
        raise ValueError(f"scene {scene!r} has no geometry targets")
    radar, r_wb = np.zeros(3), np.eye(3)
    fov = cfg.pattern.cull_angle(PATTERN_FLOOR_DB)

    def frame(ladder):
        t0 = time.process_time()
        fields = geometry_paths(sc, targets, cfg, radar, r_wb, 0.0, fov_half_angle=fov,
                                min_range=0.0, max_range=None, fidelity=ladder)
        fields.pop("stats")
        paths = PathSet(**fields)
        data, _ = synthesize_paths(paths, cfg, arr, decimate="off")
        return time.process_time() - t0, data, paths.num_paths

    rows = []
    for setting in ("point", "centres", "auto", "mesh"):
        ladder = None if setting == "mesh" else FidelityLadder(arr, setting, tol)
        first, data, n = frame(ladder)
        steady = first
        if ladder is not None:
            steady, data, n = frame(ladder)            # re-used: no PO + SBR trace
        levels = {}
        for c in [] if ladder is None else ladder.choices[:len(targets)]:
            levels[c.level] = levels.get(c.level, 0) + 1
        rows.append({"setting": setting, "s_per_frame": steady, "first_s": first, "data": data,
                     "paths": int(n), "levels": levels or {"mesh": len(targets)}})
    ref = rows[-1].pop("data")
    for r in rows[:-1]:
        d = r.pop("data")
        r["rel_error"] = float(np.linalg.norm(d - ref) / np.linalg.norm(ref))
    rows[-1].update(rel_error=0.0, reference=True)
    return rows
