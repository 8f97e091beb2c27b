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

With ``specular=True`` the ground's coherent specular mirror is added
(:func:`raysim.echoes.ground.specular.rough_specular_path`: Fresnel ``Gamma(0)``
times the Ament factor of the material's rms height at the carrier) as one
stationary point at the foot of the perpendicular from the hovering radar to the
mean ground plane, of the RCS ``pi d^2 |Gamma chi|^2`` that gives the image
method's power at the distance ``d``. A stationary point follows the mirror's
range to first order in the radar's displacement (along the normal both change
by the same amount; sideways the point is farther by ``delta^2 / 2d``, 0.3 mm for
10 cm at 15 m).

What is left out: the scene's parked cars and reflectors (traced by PO + SBR in
``raysim render``) and the shadowing rays (they need Mitsuba). Scatterers beyond
the radar's unambiguous range less :data:`RANGE_MARGIN_M` are dropped (a real
radar's anti-alias filter removes them).
"""

from __future__ import annotations

import numpy as np

__all__ = ["clutter_points", "specular_point", "RANGE_MARGIN_M"]

#: Scatterers farther than the unambiguous range less this are dropped [m] (the
#: platform's motion must not carry them past it).
RANGE_MARGIN_M = 0.5


def clutter_points(scene: str, cfg, array, lever_arm, *, altitude: float | None = None,
                   seed: int = 0, max_scatterers: int = 200_000,
                   mounting_deg=None, specular: bool = False) -> tuple[list, str]:
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
    specular : bool
        Add the ground's coherent specular mirror below the radar (when it lies in the
        field of view and the range window), the last point returned.

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
    if specular:
        mirror = specular_point(ground, cfg, lever, r_wa)
        if mirror is not None:
            points.append(mirror)
            summary += (f", specular mirror {mirror.rcs_dbsm:.1f} dBsm at "
                        f"{np.linalg.norm(mirror.position - lever):.1f} m")
    return points, summary


def specular_point(ground, cfg, radar_w, r_wa):
    """The ground's coherent specular mirror seen from ``radar_w`` as a stationary point.

    Parameters
    ----------
    ground : raysim.echoes.ground.surface.GroundSurface
    cfg : raysim.radar.config.RadarConfig
    radar_w : array_like, shape ``[3]``
        Radar phase centre in W [m].
    r_wa : array_like, shape ``[3, 3]``
        Radar attitude in W (boresight the third column).

    Returns
    -------
    raysim.echoes.oracle.PointTarget or None
        At the mirror point (the foot of the perpendicular to the mean ground plane),
        RCS ``pi d^2 |Gamma(0) chi|^2`` [dBsm] (the image method's power at the range
        ``d``: ``P_t G^2 lambda^2 |Gamma chi|^2 / ((4 pi)^2 (2d)^2)``); None when the
        mirror is out of view, off the ground or past the range window less
        :data:`RANGE_MARGIN_M`.
    """
    from raysim.echoes.ground.field import radar_scale
    from raysim.echoes.ground.specular import rough_specular_path
    from raysim.echoes.oracle import PointTarget

    x0 = np.asarray(radar_w, dtype=float)
    path = rough_specular_path(ground, cfg, x0, r_wa)
    if len(path.length) == 0:
        return None
    d = 0.5 * float(path.length[0])
    if not d < cfg.max_range - RANGE_MARGIN_M:
        return None
    # the oracle's point of RCS s at range d returns |a|^2 = radar_scale s / d^4
    rcs = float(np.abs(path.amplitude[0]) ** 2 * d ** 4 / radar_scale(cfg))
    return PointTarget(path.first_vertex[0].copy(), np.zeros(3),
                       float(10 * np.log10(max(rcs, 1e-25))))
