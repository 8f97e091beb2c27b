"""Ground clutter and multipath of one scene, kept across the chirps and frames of a render.

:class:`SceneClutter` is what :func:`raysim.echoes.rt.render.render_scene`
takes as ``clutter``: per trace it

* switches Sionna's diffuse reflection off (the field replaces it) and keeps
  Sionna's target paths direct-only (the ghosts are added here, exactly),
* removes Sionna's single-bounce specular paths that lie on the ground and adds
  the rough-surface mirror (:mod:`raysim.echoes.ground.specular`),
* adds the persistent clutter field (:mod:`raysim.echoes.ground.field`),
  building it at the first pose and again only when the radar has moved more
  than ``settings.reuse_distance`` from the pose it was built for; in wind its
  vegetation scatterers are modulated at every chirp (:meth:`SceneClutter.modulation`,
  passed to the synthesis),
* returns the ghosts of the scene's point targets and the moving objects as
  :class:`raysim.echoes.moving.scatterers.Tracks`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from raysim.echoes.ground.field import ClutterField, FieldSettings
from raysim.echoes.ground.specular import rough_specular_path
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.moving.scatterers import MovingObject, Tracks, ground_ghosts
from raysim.echoes.rt.trace import PathSet

__all__ = ["SceneClutter", "CLUTTER_MODES", "ON_GROUND_TOL"]

#: Values of ``render_scene(clutter=...)`` besides a SceneClutter.
CLUTTER_MODES = ("field", "sionna", "none")
#: Height tolerance for a Sionna specular vertex to count as on the ground [m].
ON_GROUND_TOL = 0.02


class SceneClutter:
    """Persistent clutter field, rough specular, ghosts and movers of a scene.

    Parameters
    ----------
    settings : FieldSettings, optional
        Field options (density, cost bound, re-use distance, seed).
    specular : bool
        Replace Sionna's ground mirror by the rough-surface mirror.
    ghosts : bool
        Add target-ground-radar ghosts of the scene's point targets.
    movers : sequence of MovingObject, CarMover or Rotor
        Objects driving through the scene (a CarMover is traced by PO + SBR
        at every trace, from the radar's pose then, with the ground under it)
        and rotating parts.
    ground : GroundSurface, optional
        Ground to use (default: read from the scene at the first trace).
    """

    def __init__(self, settings: FieldSettings | None = None, *, specular: bool = True,
                 ghosts: bool = True, movers=(), ground: GroundSurface | None = None):
        self.settings = FieldSettings() if settings is None else settings
        if not isinstance(self.settings, FieldSettings):
            raise ValueError(f"settings must be a FieldSettings, got {type(settings)}")
        from raysim.echoes.moving.cars import CarMover
        from raysim.echoes.moving.rotors import Rotor

        for m in movers:
            if not isinstance(m, (MovingObject, CarMover, Rotor)):
                raise ValueError(f"movers must be MovingObject, CarMover or Rotor instances, "
                                 f"got {type(m)}")
        self.specular, self.ghosts, self.movers = bool(specular), bool(ghosts), tuple(movers)
        self.ground = ground
        self.field: ClutterField | None = None
        #: Number of fields built so far (1 while the platform stays near its first pose).
        self.builds = 0
        self._rays = None
        self._scene_name = None
        self._wanted = (True, True, True)          # (field, specular, ghosts), see tracer()

    def tracer(self, tracer):
        """The tracer to use with this model: no Sionna diffuse, direct target legs only.

        The given tracer's switches say which kinds of path are wanted: the field
        only where ``tracer.diffuse``, the rough mirror and the ghosts only where
        ``tracer.specular`` (ghosts also need ``tracer.targets``).
        """
        self._wanted = (tracer.diffuse, tracer.specular, tracer.specular and tracer.targets)
        return dataclasses.replace(tracer, diffuse=False,
                                   target_depth=1 if self.ghosts else tracer.target_depth)

    def _ground_for(self, scene) -> GroundSurface:
        if self.ground is None or (self._scene_name is not None
                                   and self._scene_name != scene.name):
            self.ground = GroundSurface.from_scene(scene)
            self.field, self._rays = None, None
        self._scene_name = scene.name
        return self.ground

    def _occluders(self):
        if self._rays is None and self.settings.shadowing and self.ground.occluders is not None:
            from raysim.echoes.po.rays import RayScene

            self._rays = RayScene(self.ground.occluders)
        return self._rays

    def field_for(self, config, array, radar_w, r_wb) -> ClutterField:
        """The current field, built again when ``radar_w`` is beyond its re-use distance."""
        if self.field is None or not self.field.covers(radar_w):
            self.field = ClutterField.build(self.ground, config, array, radar_w, r_wb,
                                            self.settings)
            self.builds += 1
        return self.field

    def paths(self, scene, traced: PathSet, config, array, trajectory, lever_arm, *,
              time: float) -> tuple[PathSet, list[Tracks]]:
        """Frozen paths and moving-point tracks of one trace.

        Parameters
        ----------
        scene : RadarScene
        traced : PathSet
            The tracer's paths at ``time`` (from :meth:`tracer`).
        config, array, trajectory, lever_arm
            As for ``render_scene``.
        time : float
            Trace instant [s].

        Returns
        -------
        (PathSet, list of Tracks)
        """
        ground = self._ground_for(scene) if scene is not None else self.ground
        if ground is None:
            raise ValueError("SceneClutter needs a scene or a ground surface")
        lever = np.asarray(lever_arm, dtype=float)
        radar_w = trajectory.point_world([time], lever)[0, 0]
        r_wb = trajectory.attitude([time]).as_matrix()[0]
        fov = self.settings.fov(config)
        want_field, want_specular, want_ghosts = self._wanted
        sets = [traced]
        if self.specular and want_specular:
            sets = [self._drop_ground_mirror(traced)]
            sets.append(rough_specular_path(ground, config, radar_w, r_wb, time=time,
                                            polarisation=self.settings.polarisation,
                                            fov_half_angle=fov))
        if want_field:
            field = self.field_for(config, array, radar_w, r_wb)
            sets.append(field.paths(config, radar_w, r_wb, time=time,
                                    occluders=self._occluders()))
        sets = [s for s in sets if s.num_paths] or [sets[0]]
        paths = PathSet.concatenate(sets) if len(sets) > 1 else sets[0]
        tracks = []
        targets = getattr(scene, "targets", None) or []
        if self.ghosts and want_ghosts and targets:
            tracks.append(ground_ghosts(targets, ground, config, radar_w, r_wb, time=time,
                                        polarisation=self.settings.polarisation,
                                        fov_half_angle=fov))
        from raysim.echoes.moving.cars import CarMover

        # a car is traced with the ground under it (its car-ground multipath)
        tracks.extend(m.tracks(config, radar_w, time=time, r_wb=r_wb, ground=ground)
                      if isinstance(m, CarMover) else
                      m.tracks(config, radar_w, time=time, r_wb=r_wb) for m in self.movers)
        return paths, tracks

    def _drop_ground_mirror(self, paths: PathSet) -> PathSet:
        from raysim.echoes.rt.reproject import single_bounce_specular

        spec = single_bounce_specular(paths)
        if not spec.any():
            return paths
        _, z = self.ground.locate(paths.first_vertex[spec])
        on = np.abs(z - paths.first_vertex[spec, 2]) < ON_GROUND_TOL
        drop = np.zeros(paths.num_paths, bool)
        drop[np.nonzero(spec)[0][on]] = True
        return paths.select(~drop)

    def modulation(self, vertices, times):
        """ICM modulation of the current field's wind-blown scatterers among ``vertices``.

        See :meth:`raysim.echoes.ground.field.ClutterField.modulation`; None
        without a field, wind or vegetation.
        """
        return None if self.field is None else self.field.modulation(vertices, times)

    def summary(self) -> dict:
        """Field report plus the number of builds."""
        out = {"builds": self.builds}
        if self.field is not None:
            out.update(self.field.report)
        return out


def resolve_clutter(clutter) -> SceneClutter | None:
    """A SceneClutter for ``render_scene(clutter=...)``; None keeps the tracer's own paths."""
    if isinstance(clutter, SceneClutter):
        return clutter
    if clutter == "field":
        return SceneClutter()
    if clutter in ("sionna", "none"):
        return None
    raise ValueError(f"clutter must be one of {CLUTTER_MODES} or a SceneClutter, "
                     f"got {clutter!r}")

