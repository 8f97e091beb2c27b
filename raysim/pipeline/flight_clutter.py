"""Ground clutter of a bundled scene for a simulated flight, as point scatterers for the oracle.

:func:`clutter_points` builds the persistent clutter field of a bundled scene's
ground (:class:`raysim.echoes.ground.field.ClutterField`: seeded scatterers, each
a ground patch ``dA_i`` with the backscatter ``sigma0(theta_i)`` of its material)
for the radar at the nominal hover pose, and returns the scatterers as stationary
point targets of RCS ``sigma0 dA_i |z_i|^2`` (the field's own amplitude, so a
resolution cell sums to Rayleigh clutter), rendered by the exact oracle like the
flight's targets, with the element pattern (the field's density and the
re-projection assume it).

The field is built for the radar frame's own pose
(:func:`raysim.platform.mounting.mount_trajectory`): attitude ``R_BA`` at the
hover point, so its scatterers are drawn where the mounted radar points (a
forward radar sees the ground ahead at low grazing, an oblique one the ground
ahead and below), with the density and the element pattern of that pointing.

What is left out: the scene's parked cars and reflectors (traced by PO + SBR in
``raysim render``), the shadowing rays (they need Mitsuba) and the ground's
specular mirror. Scatterers beyond the radar's unambiguous range less
:data:`RANGE_MARGIN_M` are dropped (a real radar's anti-alias filter removes
them).
"""

from __future__ import annotations

import numpy as np

__all__ = ["clutter_points", "RANGE_MARGIN_M"]

#: Scatterers farther than the unambiguous range less this are dropped [m] (the
#: platform's motion must not carry them past it).
RANGE_MARGIN_M = 0.5


def clutter_points(scene: str, cfg, array, lever_arm, *, altitude: float | None = None,
                   seed: int = 0, max_scatterers: int = 200_000,
                   mounting_deg=None) -> tuple[list, str]:
    """The clutter field of ``scene``'s ground as point targets, and a one-line summary.

    Parameters
    ----------
    scene : str
        Bundled scene name (:data:`raysim.echoes.rt.scenes.SCENES`).
    cfg : raysim.radar.config.RadarConfig
    array : raysim.radar.arrays.VirtualArray
        The flight's array in A (angular resolution of the field's cells).
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    altitude : float, optional
        Hover height above the scene's ground [m]; default the scene's own.
    seed : int
        Seed of the field's positions and amplitudes.
    max_scatterers : int
        Bound on the field's expected scatterers (cost; density scaled down).
    mounting_deg : str or (float, float, float), optional
        Radar mounting (:mod:`raysim.platform.mounting`); default ``down``.

    Returns
    -------
    (list of raysim.echoes.oracle.PointTarget, str)

    Raises
    ------
    ValueError
        Unknown scene (the names listed), a bad altitude, or no scatterer in range
        and beam.
    """
    from raysim.echoes.ground.field import ClutterField, FieldSettings, radar_scale
    from raysim.echoes.ground.surface import GroundSurface
    from raysim.echoes.oracle import PointTarget
    from raysim.echoes.rt.scenes import SCENES, RadarScene, get_scene
    from raysim.platform.mounting import mounting_deg as mounting_ypr
    from raysim.platform.mounting import mounting_matrix

    if scene not in SCENES:
        raise ValueError(f"--clutter-scene: got {scene!r}, expected one of {sorted(SCENES)}")
    desc = get_scene(scene)
    if not desc.path.exists():
        raise ValueError(f"--clutter-scene {scene}: its file {desc.path} is missing")
    h = float(desc.metadata().get("hover_altitude", 15.0) if altitude is None else altitude)
    if not (np.isfinite(h) and h > 0):
        raise ValueError(f"--clutter-altitude: got {altitude!r}, expected a height > 0 m")
    ground = GroundSurface.from_scene(RadarScene(desc, None, h, []))
    lever = np.asarray(lever_arm, dtype=float)
    r_wa = mounting_matrix(mounting_deg)     # the radar frame at the hover point
    field = ClutterField.build(ground, cfg, array, lever, r_wa,
                               FieldSettings(shadowing=False, seed=int(seed),
                                             max_scatterers=int(max_scatterers)))
    paths = field.paths(cfg, lever, r_wa)
    r = 0.5 * paths.length
    keep = r < cfg.max_range - RANGE_MARGIN_M
    if not np.any(keep):
        raise ValueError(f"--clutter-scene {scene}: no ground within the radar's range "
                         f"{cfg.max_range:.1f} m and beam from {h:g} m up (mounting "
                         f"{mounting_ypr(mounting_deg)} deg); lower --clutter-altitude")
    rcs = np.abs(paths.amplitude[keep]) ** 2 * r[keep] ** 4 / radar_scale(cfg)
    points = [PointTarget(p, np.zeros(3), float(10 * np.log10(max(s, 1e-25))))
              for p, s in zip(paths.first_vertex[keep], rcs, strict=True)]
    summary = (f"ground clutter of {scene} from {h:g} m: {len(points)} scatterers at "
               f"{r[keep].min():.1f}-{r[keep].max():.1f} m")
    return points, summary
