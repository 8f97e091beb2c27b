"""Map extents that hold every object of a scenario: the range window and angle grid widened.

Each object of a scenario (a user mesh of ``[[scene.meshes]]``, a point target, a
bundled scene's known reflector) spans a range [m], an azimuth and an elevation
[deg] seen from the radar phase centre at the hover point (:func:`object_spans`;
angles as on the report's maps: ``u = (cos el sin az, sin el, cos el cos az)``
in W, NED, docs/conventions.md). :func:`covering_extents` widens a range window
and a symmetric angle grid so that all of them lie on the range-azimuth and
azimuth-elevation maps with a margin, within the radar's unambiguous range and
the grid's limit; objects beyond those limits are returned by name (the report
names them as off the maps). :func:`maps_size` sizes the maps of the widened
extents before any tracing.
"""

from __future__ import annotations

import math

import numpy as np

from .meshes import mesh_boxes, mesh_targets

__all__ = ["object_spans", "covering_extents", "maps_size", "COVER_MARGIN_M",
           "COVER_MARGIN_DEG", "MAX_GRID_HALF_WIDTH_DEG", "BOX_FACE_SAMPLES"]

#: Range added beyond the nearest and the farthest object when the window widens [m].
COVER_MARGIN_M = 1.0
#: Angle added beyond the widest object when the grid widens [deg].
COVER_MARGIN_DEG = 2.0
#: Widest angle grid the maps take (:func:`raysim.measure.scene.angle_grid`) [deg].
MAX_GRID_HALF_WIDTH_DEG = 80.0
#: Points per edge of the lattice on each face of a mesh's bounding box whose angles
#: bound the box's azimuth and elevation span (elevation extremes of a box need not lie
#: at its corners). A 60 m face sampled every 3 m keeps the error under 0.1 deg at 15 m
#: for the extreme of a smooth function of the face point.
BOX_FACE_SAMPLES = 21


def _box_surface(lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Points on the six faces of the box ``[lo, hi]``, shape ``[point, 3]`` [m]."""
    t = np.linspace(0.0, 1.0, BOX_FACE_SAMPLES)
    a, b = np.meshgrid(t, t, indexing="ij")
    out = []
    for axis in range(3):
        i, j = [k for k in range(3) if k != axis]
        for side in (lo[axis], hi[axis]):
            p = np.empty((a.size, 3))
            p[:, axis] = side
            p[:, i] = lo[i] + a.ravel() * (hi[i] - lo[i])
            p[:, j] = lo[j] + b.ravel() * (hi[j] - lo[j])
            out.append(p)
    return np.concatenate(out)


def _span(points: np.ndarray, lever: np.ndarray, r_min: float | None = None,
          turn: np.ndarray | None = None) -> dict:
    """Range [m], azimuth and elevation [deg] spans of ``points`` ``[n, 3]`` (W) from ``lever``,
    directions in the nominal radar frame N of the mounting ``turn`` (``R_BA``, default W)."""
    from raysim.echoes.oracle import az_el

    v = np.asarray(points, dtype=float).reshape(-1, 3) - lever
    if turn is not None:
        v = v @ turn
    r = np.linalg.norm(v, axis=1)
    keep = r > 0
    az, el = az_el(v[keep] / r[keep, None])
    az, el = np.rad2deg(az), np.rad2deg(el)
    lo = float(r.min()) if r_min is None else float(r_min)
    return {"range_m": (lo, float(r.max())), "az_deg": (float(az.min()), float(az.max())),
            "el_deg": (float(el.min()), float(el.max()))}


def _scene_targets_w(scenario) -> list[tuple[str, np.ndarray]]:
    """Known reflectors of a bundled scene or a Mitsuba XML scene, from its JSON sidecar
    (none without one): name and position in W [m]."""
    from raysim.echoes.rt.scenes import ENU_FROM_NED, get_scene

    scene = scenario.scene
    meta = get_scene(scene.name if scene.kind == "bundled" else scene.path).metadata()
    h = float(meta.get("hover_altitude", 15.0))
    return [(str(t.get("name", f"target {i}")),
             (np.asarray(t["position"], dtype=float) - [0.0, 0.0, h]) @ ENU_FROM_NED.T)
            for i, t in enumerate(meta.get("targets", []))]


def object_spans(scenario) -> list[dict]:
    """Every object of a scenario with its range, azimuth and elevation span.

    Users' meshes span their placed bounding box (:func:`mesh_boxes`, range from
    the box's nearest point to its farthest corner) and include their map marker
    (:func:`mesh_targets`); point targets and the known reflectors of a bundled
    or Mitsuba XML scene (its JSON sidecar's targets) are points.

    Parameters
    ----------
    scenario : raysim.scenario.Scenario
        Its ``lever_arm_m`` is the radar phase centre at the hover point (W) [m];
        azimuth and elevation are in the nominal radar frame N of its
        ``radar.mounting_deg``.

    Returns
    -------
    list of dict
        ``name``, ``kind`` (``"mesh"`` or ``"target"``), ``range_m``, ``az_deg``,
        ``el_deg``: ``(low, high)`` each [m] / [deg].
    """
    from raysim.echoes.oracle import direction
    from raysim.platform.mounting import is_default_mounting, mounting_matrix

    lever = np.asarray(scenario.lever_arm_m, dtype=float)
    mount = scenario.radar.mounting_deg           # spans in the nominal radar frame N
    turn = None if is_default_mounting(mount) else mounting_matrix(mount)
    scene = scenario.scene
    out = []
    if scene.kind == "points":
        for i, t in enumerate(scene.targets):
            u = direction(math.radians(t.az_deg), math.radians(t.el_deg))
            p = lever + t.range_m * (u if turn is None else turn @ u)
            out.append({"name": f"target {i}", "kind": "target", **_span(p, lever, turn=turn)})
    elif scene.kind in ("bundled", "mesh"):
        for name, p in _scene_targets_w(scenario):
            out.append({"name": name, "kind": "target", **_span(p, lever, turn=turn)})
    boxes = mesh_boxes(scenario)
    for b, marker in zip(boxes, mesh_targets(boxes, lever, mount), strict=True):
        lo, hi = np.asarray(b["lower_m"]), np.asarray(b["upper_m"])
        near = float(np.linalg.norm(np.clip(lever, lo, hi) - lever))
        pts = np.vstack([_box_surface(lo, hi), np.asarray(marker["position_m"])[None]])
        out.append({"name": b["name"], "kind": "mesh",
                    **_span(pts, lever, r_min=near, turn=turn)})
    return out


def covering_extents(spans: list[dict], range_window: tuple[float, float],
                     half_width_deg: float, step_deg: float, max_range_m: float, *,
                     widen_window: bool = True, widen_grid: bool = True) -> dict:
    """The range window and angle grid widened to hold every object of ``spans``.

    The window grows to ``[nearest - margin, farthest + margin]``
    (:data:`COVER_MARGIN_M`), never below 0 nor beyond ``max_range_m``; the
    grid's half-width grows to the widest ``|azimuth|`` or ``|elevation|`` plus
    :data:`COVER_MARGIN_DEG`, in whole ``step_deg`` steps, at most
    :data:`MAX_GRID_HALF_WIDTH_DEG`. Neither ever shrinks.

    Parameters
    ----------
    spans : list of dict
        :func:`object_spans`.
    range_window : (float, float)
        Current window [m].
    half_width_deg, step_deg : float
        Current grid half-width and step [deg].
    max_range_m : float
        Farthest range the window may reach [m] (below the unambiguous range).
    widen_window, widen_grid : bool
        Which extents may change (a user's own window or grid is kept).

    Returns
    -------
    dict
        ``range_window`` ``(low, high)`` [m], ``grid_half_width_deg`` [deg],
        ``widened`` (names of the objects that made an extent grow) and
        ``beyond`` (names of the objects that do not fit within the limits).
    """
    lo, hi = (float(v) for v in range_window)
    half = float(half_width_deg)
    top_half = step_deg * math.floor(MAX_GRID_HALF_WIDTH_DEG / step_deg + 1e-9)
    widened, beyond = [], []
    for s in spans:
        r0, r1 = s["range_m"]
        wide = max(abs(v) for v in (*s["az_deg"], *s["el_deg"]))
        grew = False
        if widen_window and r0 - COVER_MARGIN_M < lo:
            lo, grew = max(0.0, r0 - COVER_MARGIN_M), True
        if widen_window and r1 + COVER_MARGIN_M > hi and hi < max_range_m:
            hi, grew = min(max_range_m, r1 + COVER_MARGIN_M), True
        if widen_grid and wide + COVER_MARGIN_DEG > half and half < top_half:
            need = step_deg * math.ceil((wide + COVER_MARGIN_DEG) / step_deg - 1e-9)
            half, grew = min(top_half, need), True
        if grew:
            widened.append(s["name"])
    for s in spans:       # what still does not fit (a window or grid given, or the limits)
        r0, r1 = s["range_m"]
        wide = max(abs(v) for v in (*s["az_deg"], *s["el_deg"]))
        if r0 < lo or r1 > hi or wide > half:
            beyond.append(s["name"])
    return {"range_window": (lo, hi), "grid_half_width_deg": half, "widened": widened,
            "beyond": beyond}


def maps_size(settings) -> dict:
    """Size of one chain's scene maps on the report's range window and angle grid.

    Parameters
    ----------
    settings : ReportSettings
        Its radar, array, ``range_window``, grid and ``gate_block``.

    Returns
    -------
    dict
        ``gates`` (range bins in the window), ``beams`` (azimuth x elevation grid
        points), ``peak_bytes``: an upper estimate of the step's peak memory [bytes],
        one block of beams ``[chirp, gate, azimuth, elevation]`` complex128 twice
        (the beams and a re-pointed copy), the steering ``[channel, beam]``
        complex128, and the coherent cube ``[gate, azimuth, elevation]`` float64
        three times (the cube, the CFAR's noise and its local-maximum filter).
    """
    cfg = settings.radar()
    r = cfg.range_axis()
    lo, hi = settings.range_window
    gates = int(np.count_nonzero((r >= lo) & (r <= hi)))
    az, el = settings.grid()
    beams = int(az.size * el.size)
    block = cfg.num_chirps * min(settings.gate_block, max(gates, 1)) * beams * 16 * 2
    steering = settings.array().num_channels * beams * 16
    return {"gates": gates, "beams": beams,
            "peak_bytes": int(block + steering + gates * beams * 8 * 3)}
