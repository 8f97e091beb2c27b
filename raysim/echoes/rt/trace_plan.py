"""Trace budget: model no more of a scene than the radar can see.

:func:`plan_trace` reads a scene's meshes (frame S, with ``trimesh``) and
decides, before any ray is shot,

* which triangles lie outside the radar's **range window** (closest point
  beyond ``max_range``) or outside its **element-pattern cone** (half-angle
  ``fov_half_angle`` around boresight: by default the angle beyond which the
  element's one-way gain stays ``pattern_floor_db`` below its peak,
  :meth:`raysim.radar.pattern.ElementPattern.cull_angle`), per shape;
* how many rays (``samples_per_src``) sample the illuminated area inside the
  window at a stated number of rays per resolution cell;
* the bounce depth (``max_depth``): 1 or 2, from the surfaces inside the window.

The resulting :class:`TracePlan` is applied by
:meth:`raysim.echoes.rt.trace.MonostaticTracer.for_scene` (or by passing
``plan=`` to :class:`~raysim.echoes.rt.trace.MonostaticTracer`): the tracer then
traces a copy of the scene whose meshes hold only the kept triangles (shapes
with no triangle left are removed entirely).

Why pruning does not change the kept paths
------------------------------------------
* Range: a path whose one-way equivalent range ``length / 2`` is below
  ``max_range`` cannot touch a point farther than ``max_range`` from the radar
  (each vertex ``v`` gives ``length >= 2 |v - radar|`` by the triangle
  inequality), whatever its depth. Removing such triangles removes only paths
  the tracer would cull anyway.
* Element pattern: the tracer drops every path whose two-way element gain
  lies more than ``pattern_floor_db`` below its peak. Outside the cone the
  one-way gain of that leg is already below the floor, and the other leg's
  factor is at most 1, so a path with a first or last leg outside the cone is
  dropped. For ``max_depth <= 2`` every vertex is a first or last vertex, so
  a triangle wholly outside the cone takes part in no kept path. For deeper
  traces interior vertices may lie outside the cone; the field-of-view pruning
  is then switched off (``prune_fov=False``).
* Occlusion: a segment from the radar to a point inside the cone and the
  window stays inside both (the cone is convex, the ball too), so pruned
  geometry cannot shadow kept targets or surfaces.

The tests are conservative (a triangle is dropped only when it is outside
for certain): exact closest-point distance for the range, a bounding sphere
of the triangle (plus ``margin``) for the cone. A triangle that straddles a
boundary is kept whole. Geometry is judged from one radar position
(``radar_position_w``); ``margin`` [m] covers the platform's motion around it.
"""

from __future__ import annotations

import math
import os
import tempfile
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from raysim.echoes.rt.scenes import (
    ENU_FROM_NED,
    MESH_SHAPE_TYPES,
    RadarScene,
    SceneDescriptor,
    _scene_xml,
    _substitute,
    drop_geometry_shapes,
    get_scene,
)
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig
from raysim.radar.pattern import PATTERN_FLOOR_DB

#: Default average rays per resolution cell of the illuminated area.
DEFAULT_RAYS_PER_CELL = 4.0
#: Ray count bounds: below ``MIN_SAMPLES`` Sionna's sampling of small areas gets
#: erratic; above ``MAX_SAMPLES`` (about 150 MB of paths) tracing stops being cheap.
MIN_SAMPLES, MAX_SAMPLES = 2_000, 1_000_000
#: A surface is "vertical" when its normal is within 30 deg of horizontal (``|n_z| < 0.5``).
VERTICAL_NZ = 0.5
#: In-window vertical area [m^2] from which the plan traces double bounces.
DEFAULT_MIN_VERTICAL_AREA = 1.0


@dataclass(frozen=True)
class ShapeBudget:
    """What the plan keeps and drops of one scene shape (triangle counts, areas in m^2).

    Attributes
    ----------
    name : str
        Sionna object name (the XML shape id without its ``mesh-`` prefix).
    num_triangles : int
        Triangles in the mesh.
    area : float
        Mesh area [m^2].
    range_triangles, range_area : int, float
        Triangles (area [m^2]) wholly beyond ``max_range`` (+ margin) from the radar.
    fov_triangles, fov_area : int, float
        Triangles (area [m^2]) inside the range but wholly outside the FoV cone.
    illuminated_area : float
        Kept area whose face normal points towards the radar [m^2].
    vertical_area : float
        Kept area with ``|n_z| < 0.5`` (facades, car sides, posts) [m^2].
    cells : float
        Resolution cells covered by the illuminated area.
    solid_angle : float
        Solid angle of the illuminated triangles seen from the radar [sr].
    """

    name: str
    num_triangles: int
    area: float
    range_triangles: int
    range_area: float
    fov_triangles: int
    fov_area: float
    illuminated_area: float
    vertical_area: float
    cells: float
    solid_angle: float

    @property
    def dropped_triangles(self) -> int:
        """Triangles dropped by either test."""
        return self.range_triangles + self.fov_triangles

    @property
    def kept_triangles(self) -> int:
        """Triangles left for tracing."""
        return self.num_triangles - self.dropped_triangles

    @property
    def removed(self) -> bool:
        """True when no triangle of the shape is left."""
        return self.kept_triangles == 0


@dataclass(frozen=True, eq=False)
class TracePlan:
    """Ray budget, depth and pruned geometry for tracing one scene (see :func:`plan_trace`).

    Attributes
    ----------
    scene : str
        Scene name.
    scene_file : pathlib.Path
        Mitsuba XML the geometry was read from.
    radar_position_w : ndarray, shape ``[3]``
        Radar position the plan was made for, in W [m].
    boresight_w : ndarray, shape ``[3]``
        Unit boresight in W.
    max_range : float
        Range window [m].
    fov_half_angle : float
        Pruning cone half-angle [rad] (from the element pattern unless given).
    pattern_floor_db : float
        Element-pattern floor the cone was derived from [dB] (``nan`` when the
        cone was given explicitly).
    margin : float
        Safety distance added to both tests [m].
    prune_fov : bool
        Whether triangles outside the cone are dropped.
    range_resolution : float
        ``c / 2B`` [m].
    angular_resolution : float
        ``lambda / D`` of the array's virtual aperture ``D`` [rad].
    rays_per_cell : float
        Requested average rays per resolution cell.
    shapes : tuple of ShapeBudget
        Per-shape accounting, in XML order.
    num_cells : float
        Resolution cells covered by the illuminated area in the window.
    illuminated_solid_angle : float
        Solid angle of that area [sr].
    samples_uncapped : int
        Ray count before clipping to ``[MIN_SAMPLES, MAX_SAMPLES]``.
    samples_per_src : int
        Rays to shoot.
    max_depth : int
        Bounces of geometry paths, 1 or 2.
    depth_reason : str
        Why ``max_depth`` was chosen.
    keep : dict
        Shape name -> boolean mask ``[triangle]`` of kept triangles.
    """

    scene: str
    scene_file: Path
    radar_position_w: np.ndarray
    boresight_w: np.ndarray
    max_range: float
    fov_half_angle: float
    margin: float
    prune_fov: bool
    range_resolution: float
    angular_resolution: float
    rays_per_cell: float
    shapes: tuple
    num_cells: float
    illuminated_solid_angle: float
    samples_uncapped: int
    samples_per_src: int
    max_depth: int
    depth_reason: str
    keep: dict = field(repr=False)
    _cache: dict = field(default_factory=dict, repr=False)
    pattern_floor_db: float = math.nan

    # --------------------------------------------------------------- accounting
    @property
    def num_triangles(self) -> int:
        """Triangles of all analysed shapes."""
        return sum(s.num_triangles for s in self.shapes)

    @property
    def dropped_triangles(self) -> int:
        """Triangles dropped by the range and FoV tests together."""
        return sum(s.dropped_triangles for s in self.shapes)

    @property
    def dropped_area(self) -> float:
        """Area dropped by both tests [m^2]."""
        return sum(s.range_area + s.fov_area for s in self.shapes)

    @property
    def removed_shapes(self) -> tuple[str, ...]:
        """Shapes with no triangle left (removed from the traced scene)."""
        return tuple(s.name for s in self.shapes if s.removed)

    @property
    def illuminated_area(self) -> float:
        """Kept area facing the radar [m^2]."""
        return sum(s.illuminated_area for s in self.shapes)

    def shape(self, name: str) -> ShapeBudget:
        """The :class:`ShapeBudget` of shape ``name``."""
        for s in self.shapes:
            if s.name == name:
                return s
        raise ValueError(f"no shape {name!r} in plan of {self.scene!r}; shapes: "
                         f"{', '.join(s.name for s in self.shapes)}")

    def tracer_options(self) -> dict:
        """``max_depth``, ``samples_per_src`` and ``plan`` for :class:`MonostaticTracer`."""
        return {"max_depth": self.max_depth, "samples_per_src": self.samples_per_src,
                "plan": self}

    def summary(self) -> str:
        """Human-readable account of what is traced, what is dropped and why."""
        deg = math.degrees(self.fov_half_angle)
        lines = [
            f"trace plan for {self.scene!r}: radar at W "
            f"{np.round(self.radar_position_w, 3).tolist()} m, range window "
            f"{self.max_range:.1f} m, cone half-angle {deg:.1f} deg"
            + (f" (one-way element gain {self.pattern_floor_db:g} dB below peak beyond it)"
               if math.isfinite(self.pattern_floor_db) else " (given)")
            + f", margin {self.margin:g} m",
            f"  kept {self.num_triangles - self.dropped_triangles} of {self.num_triangles} "
            f"triangles; dropped {self.dropped_triangles} ({self.dropped_area:.1f} m^2)",
        ]
        for s in self.shapes:
            why = []
            if s.range_triangles:
                why.append(f"{s.range_triangles} tri / {s.range_area:.1f} m^2 beyond "
                           f"{self.max_range:.1f} m")
            if s.fov_triangles:
                why.append(f"{s.fov_triangles} tri / {s.fov_area:.1f} m^2 outside the "
                           f"{deg:.0f} deg cone")
            state = "removed" if s.removed else f"{s.kept_triangles}/{s.num_triangles} kept"
            lines.append(f"  - {s.name}: {state}" + (f" ({'; '.join(why)})" if why else ""))
        if not self.prune_fov:
            lines.append("  cone pruning off (depth > 2: interior vertices may leave the cone)")
        lines.append(
            f"  rays: {self.samples_per_src:,} = {self.rays_per_cell:g} rays/cell x "
            f"{self.num_cells:,.0f} cells (dR {self.range_resolution * 100:.1f} cm x "
            f"R x {math.degrees(self.angular_resolution):.2f} deg) over "
            f"{self.illuminated_area:,.0f} m^2 seen in {self.illuminated_solid_angle:.2f} sr"
            + ("" if self.samples_per_src == self.samples_uncapped
               else f" (uncapped {self.samples_uncapped:,})"))
        lines.append(f"  max_depth {self.max_depth}: {self.depth_reason}")
        return "\n".join(lines)

    # ---------------------------------------------------------------- pruning
    def prune(self, scene: RadarScene) -> RadarScene:
        """A copy of ``scene`` whose meshes hold only the kept triangles.

        The copy is loaded once per scene object and cached on the plan. It
        shares the scene's descriptor, hover altitude and targets; shapes with no
        triangle left are left out, partly dropped meshes are rewritten.

        Parameters
        ----------
        scene : RadarScene
            Scene loaded from ``self.scene_file``.

        Returns
        -------
        RadarScene
            ``scene`` itself when nothing is dropped.
        """
        if not isinstance(scene, RadarScene):
            raise ValueError(f"scene must be a RadarScene, got {type(scene)}")
        if Path(scene.descriptor.path).resolve() != self.scene_file:
            raise ValueError(f"plan was made for {str(self.scene_file)!r}, scene is "
                             f"{str(scene.descriptor.path)!r}")
        if self.dropped_triangles == 0:
            return scene
        hit = self._cache.get(id(scene))
        if hit is not None:
            return hit[1]
        pruned = self._load_pruned(scene)
        self._cache[id(scene)] = (scene, pruned)  # holds scene: its id stays unique
        return pruned

    def _load_pruned(self, scene: RadarScene) -> RadarScene:
        import trimesh

        from raysim.echoes.rt.backend import sionna_rt

        rt = sionna_rt()
        root, defaults = _scene_xml(self.scene_file)
        with tempfile.TemporaryDirectory(prefix="raysim-pruned-") as tmp:
            for shape in list(root):
                info = _shape_mesh_file(shape, defaults, self.scene_file)
                if info is None:
                    continue
                name, mesh_file = info
                keep = self.keep.get(name)
                fname = next(c for c in shape.findall("string") if c.get("name") == "filename")
                if keep is None or keep.all():
                    fname.set("value", str(mesh_file))
                elif not keep.any():
                    root.remove(shape)
                else:
                    mesh = trimesh.load(mesh_file, force="mesh", process=False)
                    sub = trimesh.Trimesh(np.asarray(mesh.vertices),
                                          np.asarray(mesh.faces)[keep], process=False)
                    sub.remove_unreferenced_vertices()
                    out = Path(tmp) / f"{name}.ply"
                    sub.export(out)
                    fname.set("value", str(out))
            xml = Path(tmp) / "pruned.xml"
            ET.ElementTree(root).write(xml)
            sc = rt.load_scene(str(xml), merge_shapes=False)
        drop_geometry_shapes(sc, scene.descriptor)
        sc.frequency = float(scene.sionna_scene.frequency[0])
        return RadarScene(scene.descriptor, sc, scene.hover_altitude, list(scene.targets))


def _shape_mesh_file(shape, defaults: dict, scene_file: Path):
    """``(object name, mesh path)`` of a plain mesh shape, else None (kept untouched)."""
    if shape.tag != "shape" or shape.get("type") not in MESH_SHAPE_TYPES:
        return None
    if shape.find("transform") is not None:
        return None  # transformed meshes are not analysed: kept whole
    files = [c for c in shape.findall("string") if c.get("name") == "filename"]
    if len(files) != 1:
        return None
    value = _substitute(files[0].get("value", ""), defaults)
    if "$" in value:
        return None
    sid = shape.get("id", "")
    name = sid[len("mesh-"):] if sid.startswith("mesh-") else sid
    return name, (scene_file.parent / value).resolve()


def aperture_resolution(array: VirtualArray, wavelength: float, fov: float) -> float:
    """``lambda / D`` [rad], ``D`` the virtual aperture along its widest axis of A's X-Y plane."""
    p = array.virtual_positions[:, :2]
    best = 0.0
    for k in range(2):
        u = np.unique(np.round(p[:, k], 12))
        if u.size > 1:
            best = max(best, float(u[-1] - u[0]) * u.size / (u.size - 1))
    return min(wavelength / best, 2.0 * fov) if best > 0 else 2.0 * fov


def _solid_angles(tri: np.ndarray) -> np.ndarray:
    """Solid angle [sr] of triangles ``[n, 3, 3]`` (vertices relative to the apex)."""
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    la, lb, lc = (np.linalg.norm(v, axis=1) for v in (a, b, c))
    num = np.abs(np.einsum("ij,ij->i", a, np.cross(b, c)))
    den = (la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", a, c) * lb
           + np.einsum("ij,ij->i", b, c) * la)
    return 2.0 * np.arctan2(num, den)


def plan_trace(scene: str | os.PathLike | SceneDescriptor | RadarScene, config: RadarConfig,
               array: VirtualArray, *, radar_position_w=None, boresight_w=None,
               fov_half_angle: float | None = None,
               pattern_floor_db: float = PATTERN_FLOOR_DB,
               rays_per_cell: float = DEFAULT_RAYS_PER_CELL, max_range: float | None = None,
               margin: float = 0.5, prune_fov: bool = True,
               min_vertical_area: float = DEFAULT_MIN_VERTICAL_AREA,
               hover_altitude: float | None = None) -> TracePlan:
    """Decide what of a scene to trace, how many rays and how many bounces.

    Geometry (frame S meshes of the scene's XML) is placed in W with the
    scene's hover altitude and judged from ``radar_position_w``.

    **Pruning.** A triangle is dropped for *range* when its closest point lies
    farther than ``max_range + margin`` from the radar, and for *FoV* when its
    bounding sphere (radius + ``margin``) lies wholly outside the cone of
    half-angle ``fov_half_angle`` around ``boresight_w``. Both tests are
    conservative; see the module docstring for why no kept path changes.

    **Ray count.** A resolution cell on a surface at range ``R`` covers about
    ``A_cell = dR * R * dtheta`` [m^2], with ``dR = config.range_resolution``
    and ``dtheta = lambda / D`` the angular resolution of the array's virtual
    aperture ``D``. The kept triangles that face the radar cover
    ``N = sum(A_i / A_cell(R_i))`` cells and the solid angle
    ``Omega = sum(Omega_i)``. Sionna shoots ``samples_per_src`` rays
    uniformly over ``4 pi`` sr, of which ``samples * Omega / (4 pi)`` land on
    that area; to average ``rays_per_cell`` rays per cell::

        samples_per_src = rays_per_cell * N * 4 pi / Omega

    clipped to ``[MIN_SAMPLES, MAX_SAMPLES]``. Near cells (small ``R``) get
    more rays than far ones (density per solid angle is uniform), so the
    count is an average, not a minimum. Shadowing is ignored (the count errs high).

    **Depth.** A single bounce captures every surface's direct (specular and
    diffuse) return. A second bounce matters only with a dihedral: a surface
    at a steep angle to the ground (or to another) inside the window, which
    returns energy via ground -> wall -> radar. Ground, gentle terrain and
    point reflectors (constant-RCS targets, traced separately) form none,
    since a near-horizontal surface sends a second leg upwards, away from
    other horizontal surfaces. The rule: ``max_depth = 2`` when the kept
    area of "vertical" faces (normal within 30 deg of horizontal,
    ``|n_z| < 0.5``) is at least ``min_vertical_area``, else 1.

    Parameters
    ----------
    scene : str, path-like, SceneDescriptor or RadarScene
        Registry name, XML path, descriptor or loaded scene.
    config : RadarConfig
        Waveform: ``range_resolution``, ``wavelength``, ``max_range``.
    array : VirtualArray
        Virtual channels; its aperture sets ``lambda / D``.
    radar_position_w : array_like, shape ``[3]``, optional
        Radar phase centre in W [m]; default the hover point ``(0, 0, 0)``.
    boresight_w : array_like, shape ``[3]``, optional
        Boresight in W; default straight down ``(0, 0, 1)`` (nominal attitude).
    fov_half_angle : float, optional
        Cone half-angle [rad], in (0, pi]; default
        ``config.pattern.cull_angle(pattern_floor_db)`` (84.4 deg for the
        default ``patch`` element at -40 dB).
    pattern_floor_db : float
        Two-way element-gain floor of the tracer [dB], < 0 (default
        :data:`raysim.radar.pattern.PATTERN_FLOOR_DB`).
    rays_per_cell : float
        Average rays per resolution cell, > 0.
    max_range : float, optional
        Range window [m]; default ``config.max_range``.
    margin : float
        Distance added to both tests for platform motion [m], >= 0.
    prune_fov : bool
        Drop triangles outside the cone (exact only for ``max_depth <= 2``).
    min_vertical_area : float
        Vertical area [m^2] from which double bounces are traced, >= 0.
    hover_altitude : float, optional
        Overrides the scene's hover altitude [m] (not for a loaded scene).

    Returns
    -------
    TracePlan

    Raises
    ------
    ValueError
        Bad parameter values (named in the message) or an unreadable scene.
    """
    import trimesh

    if not isinstance(config, RadarConfig):
        raise ValueError(f"config must be a RadarConfig, got {type(config)}")
    if not isinstance(array, VirtualArray):
        raise ValueError(f"array must be a VirtualArray, got {type(array)}")
    if not isinstance(pattern_floor_db, (int, float)) or math.isnan(pattern_floor_db) \
            or pattern_floor_db >= 0:
        raise ValueError(f"pattern_floor_db must be a level below the peak (< 0 dB), "
                         f"got {pattern_floor_db!r}")
    if fov_half_angle is None:
        fov_half_angle = (config.pattern.cull_angle(pattern_floor_db)
                          if math.isfinite(pattern_floor_db) else math.pi)
    else:
        pattern_floor_db = math.nan
    if not (math.isfinite(fov_half_angle) and 0 < fov_half_angle <= math.pi):
        raise ValueError(f"fov_half_angle must be in (0, pi] rad, got {fov_half_angle!r}")
    if not (math.isfinite(rays_per_cell) and rays_per_cell > 0):
        raise ValueError(f"rays_per_cell must be a positive number, got {rays_per_cell!r}")
    if not (math.isfinite(margin) and margin >= 0):
        raise ValueError(f"margin must be a finite distance >= 0 m, got {margin!r}")
    if not (math.isfinite(min_vertical_area) and min_vertical_area >= 0):
        raise ValueError(f"min_vertical_area must be >= 0 m^2, got {min_vertical_area!r}")
    r_max = config.max_range if max_range is None else max_range
    if not (math.isfinite(r_max) and r_max > 0):
        raise ValueError(f"max_range must be a positive range in metres, got {max_range!r}")
    radar = np.zeros(3) if radar_position_w is None else np.asarray(radar_position_w, float)
    if radar.shape != (3,) or not np.all(np.isfinite(radar)):
        raise ValueError(f"radar_position_w must be 3 finite numbers [m], "
                         f"got {radar_position_w!r}")
    bore = np.array([0.0, 0.0, 1.0]) if boresight_w is None else np.asarray(boresight_w, float)
    if bore.shape != (3,) or not np.all(np.isfinite(bore)) or np.linalg.norm(bore) == 0:
        raise ValueError(f"boresight_w must be a non-zero finite 3-vector, got {boresight_w!r}")
    bore = bore / np.linalg.norm(bore)

    if isinstance(scene, RadarScene):
        if hover_altitude is not None:
            raise ValueError("hover_altitude cannot override a loaded RadarScene's "
                             f"({scene.hover_altitude} m); got {hover_altitude!r}")
        desc, altitude = scene.descriptor, scene.hover_altitude
    else:
        desc = get_scene(scene)
        if not desc.path.exists():
            raise ValueError(f"scene file {desc.path} is missing; run `python scenes/generate.py`")
        altitude = float(desc.metadata().get("hover_altitude", 15.0)
                         if hover_altitude is None else hover_altitude)
        if not (math.isfinite(altitude) and altitude > 0):
            raise ValueError(f"hover_altitude must be a positive height in metres, "
                             f"got {hover_altitude!r}")
    scene_file = Path(desc.path).resolve()
    root, defaults = _scene_xml(scene_file)
    hover_s = np.array([0.0, 0.0, altitude])
    d_r = config.range_resolution
    d_theta = aperture_resolution(array, config.wavelength, fov_half_angle)

    shapes, keep_masks = [], {}
    n_cells, omega = 0.0, 0.0
    for shape in root:
        info = _shape_mesh_file(shape, defaults, scene_file)
        if info is None:
            continue
        name, mesh_file = info
        mesh = trimesh.load(mesh_file, force="mesh", process=False)
        tri_s = np.asarray(mesh.triangles, dtype=float)              # [tri, 3, 3] in S
        tri = (tri_s - hover_s) @ ENU_FROM_NED.T - radar              # relative to radar, W
        area = np.asarray(trimesh.triangles.area(tri_s), dtype=float)
        normal_s = np.asarray(trimesh.triangles.normals(tri_s)[0], dtype=float)
        if normal_s.shape[0] != tri.shape[0]:   # degenerate faces: trimesh skips them
            normal_s = np.cross(tri_s[:, 1] - tri_s[:, 0], tri_s[:, 2] - tri_s[:, 0])
            normal_s /= np.maximum(np.linalg.norm(normal_s, axis=1, keepdims=True), 1e-300)
        normal = normal_s @ ENU_FROM_NED.T
        # range: exact closest point of each triangle to the radar (origin)
        closest = trimesh.triangles.closest_point(tri, np.zeros_like(tri[:, 0]))
        far = np.linalg.norm(closest, axis=1) > r_max + margin
        # FoV: bounding sphere wholly outside the cone
        centre = tri.mean(axis=1)
        radius = np.max(np.linalg.norm(tri - centre[:, None], axis=2), axis=1) + margin
        dist = np.linalg.norm(centre, axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            ang = np.arccos(np.clip((centre @ bore) / dist, -1.0, 1.0))
            half = np.arcsin(np.clip(radius / dist, 0.0, 1.0))
        outside = (dist > radius) & (ang - half > fov_half_angle)
        out_fov = ~far & outside if prune_fov else np.zeros_like(far)
        keep = ~far & ~out_fov
        r_c = np.maximum(dist, d_r)
        facing = keep & (np.einsum("ij,ij->i", normal, -centre) > 0)
        cells = np.sum(area[facing] / (d_r * r_c[facing] * d_theta))
        om = float(np.sum(_solid_angles(tri[facing])))
        vertical = keep & (np.abs(normal[:, 2]) < VERTICAL_NZ)
        shapes.append(ShapeBudget(
            name, int(tri.shape[0]), float(area.sum()), int(far.sum()), float(area[far].sum()),
            int(out_fov.sum()), float(area[out_fov].sum()), float(area[facing].sum()),
            float(area[vertical].sum()), float(cells), om))
        keep_masks[name] = keep
        n_cells += cells
        omega += om

    if omega > 0 and n_cells > 0:
        uncapped = int(math.ceil(rays_per_cell * n_cells * 4.0 * math.pi / omega))
    else:
        uncapped = 0
    samples = int(min(max(uncapped, MIN_SAMPLES), MAX_SAMPLES))
    vertical_area = sum(s.vertical_area for s in shapes)
    if vertical_area >= min_vertical_area and vertical_area > 0:
        big = sorted(shapes, key=lambda s: -s.vertical_area)
        names = ", ".join(s.name for s in big if s.vertical_area > 0)
        depth, reason = 2, (f"{vertical_area:.1f} m^2 of vertical faces (|n_z| < {VERTICAL_NZ}) "
                            f"in the window ({names}) form dihedrals with the ground")
    else:
        depth, reason = 1, (f"{vertical_area:.1f} m^2 of vertical faces in the window (< "
                            f"{min_vertical_area:g} m^2): no surface pair forms a double bounce")
    return TracePlan(desc.name, scene_file, radar, bore, float(r_max), float(fov_half_angle),
                     float(margin), bool(prune_fov), float(d_r), float(d_theta),
                     float(rays_per_cell), tuple(shapes), float(n_cells), float(omega),
                     uncapped, samples, depth, reason, keep_masks,
                     pattern_floor_db=float(pattern_floor_db))
