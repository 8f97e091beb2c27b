"""Users' meshes in the report: where each one is, what the radar saw of it, a top view.

A scenario with ``[[scene.meshes]]`` names its meshes by file name. Each mesh is
placed in the world frame W (NED, docs/conventions.md) as the ray tracer places
it (:meth:`raysim.echoes.rt.user_meshes.UserMesh.to_world`); the report marks its
centre (the centre of its bounding box in W) on the RA and AE maps
(:func:`mesh_targets`), attributes every traced path to the mesh nearest its
first interaction point (:func:`mesh_summary`: paths, their total power, CFAR
detections within the mesh's footprint) and draws a top view of the meshes and
the radar (:func:`plot_placement`) before any tracing.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

__all__ = ["mesh_boxes", "mesh_targets", "mesh_summary", "plot_placement",
           "NEAR_MESH_M"]

#: A detection or a path vertex this far outside a mesh's bounding box still counts as on it [m].
NEAR_MESH_M = 1.0


def _mesh_name(spec, taken) -> str:
    base = os.path.basename(str(spec.file))
    name, k = base, 2
    while name in taken:
        name, k = f"{base} ({k})", k + 1
    return name


def mesh_boxes(scenario) -> list[dict]:
    """Each user mesh of the scenario: its name, world vertices' footprint and bounding box.

    Parameters
    ----------
    scenario : raysim.scenario.Scenario
        A scenario with ``[[scene.meshes]]`` (other scenes give ``[]``).

    Returns
    -------
    list of dict
        ``name`` (file name, made unique), ``lower_m`` and ``upper_m`` (bounding
        box corners in W, NED [m], ``[3]`` each), ``centre_m`` (``[3]``, W [m]) and
        ``footprint_m`` (convex hull of the vertices in the north/east plane,
        ``[k, 2]`` [m]).
    """
    scene = scenario.scene
    if scene.kind != "meshes":
        return []
    import trimesh
    from scipy.spatial import ConvexHull

    from raysim.echoes.rt.user_meshes import UserMesh, with_declared_scale
    from raysim.io.mesh_files import read_mesh_file

    out, taken = [], set()
    for m in scene.meshes:
        spec = UserMesh(**m.placement())
        loaded = read_mesh_file(spec.file, process=False)
        spec = with_declared_scale(spec, loaded)
        if isinstance(loaded, trimesh.Scene):
            loaded = loaded.to_mesh()            # every node's geometry at its place
        v = np.asarray(getattr(loaded, "vertices", np.empty((0, 3))), dtype=float)
        if v.size == 0:
            raise ValueError(f"mesh file {spec.file}: no vertices")
        tf = spec.to_world()
        w = v @ tf[:3, :3].T + tf[:3, 3]
        ne = w[:, :2]
        try:
            hull = ne[ConvexHull(ne).vertices]
        except Exception:                      # degenerate footprint (a line or a point)
            hull = np.array([ne.min(axis=0), ne.max(axis=0)])
        name = _mesh_name(spec, taken)
        taken.add(name)
        lo, hi = w.min(axis=0), w.max(axis=0)
        out.append({"name": name, "lower_m": lo.tolist(), "upper_m": hi.tolist(),
                    "centre_m": ((lo + hi) / 2).tolist(), "footprint_m": hull.tolist()})
    return out


def mesh_targets(boxes: list[dict], lever_arm, mounting_deg=None) -> list[dict]:
    """Each mesh as a named marker: its centre's range [m], azimuth and elevation [deg].

    The centre of a mesh under the radar (a ground plane) is taken at the point of
    its top face nearest the radar's nadir-to-boresight line: the bounding-box point
    nearest the radar, so that a ground's marker is where the radar sees it.

    Parameters
    ----------
    boxes : list of dict
        :func:`mesh_boxes`.
    lever_arm : sequence of float
        Radar phase centre, shape ``[3]`` (B at the hover point, so in W) [m].
    mounting_deg : str or (float, float, float), optional
        Radar mounting: azimuth and elevation in its nominal radar frame N
        (:mod:`raysim.platform.mounting`); default ``down``.

    Returns
    -------
    list of dict
        As the report's known reflectors (``name``, ``position_m``, ``range_m``,
        ``az_deg``, ``el_deg``) plus ``"mesh": True``.
    """
    from raysim.echoes.oracle import az_el
    from raysim.platform.mounting import nominal_direction

    lever = np.asarray(lever_arm, dtype=float)
    out = []
    for b in boxes:
        lo, hi = np.asarray(b["lower_m"]), np.asarray(b["upper_m"])
        c = np.asarray(b["centre_m"])
        if np.all(lo[:2] <= lever[:2]) and np.all(lever[:2] <= hi[:2]):
            c = np.clip(lever, lo, hi)          # under the radar: the nearest point
        v = c - lever
        r = float(np.linalg.norm(v))
        if r == 0:
            continue
        a, e = az_el(nominal_direction(v / r, mounting_deg))
        out.append({"name": b["name"], "position_m": c.tolist(), "range_m": r,
                    "az_deg": float(np.rad2deg(a)), "el_deg": float(np.rad2deg(e)),
                    "mesh": True})
    return out


def _box_distance(points: np.ndarray, lo, hi) -> np.ndarray:
    """Distance of ``points`` ``[n, 3]`` from the box ``[lo, hi]`` (0 inside) [m]."""
    d = np.maximum(np.maximum(np.asarray(lo) - points, points - np.asarray(hi)), 0.0)
    return np.sqrt(np.sum(d * d, axis=1))


def mesh_summary(boxes: list[dict], paths, results: dict) -> list[dict]:
    """What the radar saw of each mesh: paths traced on it, their power, detections near it.

    A path belongs to the mesh whose bounding box is nearest its first interaction
    point (ties: the smaller box, so a car on a ground plane keeps its paths),
    when that distance is at most :data:`NEAR_MESH_M`; the clutter field's and
    the movers' scatterers are not traced paths and are not counted.

    Parameters
    ----------
    boxes : list of dict
        :func:`mesh_boxes`.
    paths : raysim.echoes.rt.trace.PathSet or None
        The frozen paths of the trace (``first_vertex`` ``[path, 3]`` W [m],
        ``amplitude`` ``[path]`` [sqrt(W)]).
    results : dict
        Key (reference or chain) -> :class:`raysim.measure.scene.SceneMeasurement`;
        its ``detections`` (``position_m`` in W) within :data:`NEAR_MESH_M` of a
        box are counted for that mesh.

    Returns
    -------
    list of dict
        Per mesh: ``name``, ``num_paths``, ``power_w`` (sum of ``|amplitude|^2``
        [W], isotropic elements), ``power_dbw`` and ``detections`` (key -> count).
    """
    if not boxes:
        return []

    owner = None
    if paths is not None and paths.num_paths:
        p = np.asarray(paths.first_vertex, dtype=float)
        d = np.stack([_box_distance(p, b["lower_m"], b["upper_m"]) for b in boxes])
        vol = np.array([np.prod(np.maximum(np.subtract(b["upper_m"], b["lower_m"]), 1e-3))
                        for b in boxes])
        order = np.lexsort((np.broadcast_to(vol[:, None], d.shape), d), axis=0)[0]
        owner = np.where(d[order, np.arange(d.shape[1])] <= NEAR_MESH_M, order, -1)
        power = np.abs(np.asarray(paths.amplitude)) ** 2
    out = []
    for i, b in enumerate(boxes):
        on = (owner == i) if owner is not None else np.zeros(0, bool)
        pw = float(power[on].sum()) if owner is not None else 0.0
        det = {}
        for key, r in results.items():
            pos = np.array([x["position_m"] for x in r.detections], dtype=float).reshape(-1, 3)
            det[key] = int(np.sum(_box_distance(pos, b["lower_m"], b["upper_m"])
                                  <= NEAR_MESH_M)) if len(pos) else 0
        out.append({"name": b["name"], "num_paths": int(on.sum()), "power_w": pw,
                    "power_dbw": float(10 * np.log10(pw)) if pw > 0 else None,
                    "detections": det})
    return out


def plot_placement(jobs: list, path: str | os.PathLike) -> Path | None:
    """Top view (east right, north up) of every scenario's meshes and the radar.

    Parameters
    ----------
    jobs : list of (str, list of dict, ReportSettings)
        Label, :func:`mesh_boxes` and settings of each scenario with meshes.
    path : path-like
        The PNG written (atomically).

    Returns
    -------
    pathlib.Path or None
        ``path``, or None when no job has meshes.
    """
    jobs = [j for j in jobs if j[1]]
    if not jobs:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from raysim.io.files import atomic_savefig

    fig, axes = plt.subplots(1, len(jobs), figsize=(5.0 * len(jobs), 5.0),
                             constrained_layout=True, squeeze=False)
    for ax, (label, boxes, st) in zip(axes[0], jobs, strict=True):
        for b in boxes:
            fp = np.asarray(b["footprint_m"])
            ax.fill(fp[:, 1], fp[:, 0], alpha=0.35)
            ax.annotate(b["name"], (b["centre_m"][1], b["centre_m"][0]), ha="center",
                        fontsize=8)
        lever = np.asarray(st.lever_arm, dtype=float)
        ax.plot(lever[1], lever[0], "k^", ms=9)
        ax.annotate("radar", (lever[1], lever[0]), xytext=(4, 4),
                    textcoords="offset points", fontsize=8)
        ax.set_xlabel("east [m] (W, NED)")
        ax.set_ylabel("north [m] (W, NED)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
        ax.set_title(f"{label}: placement (top view)")
    out = Path(path)
    atomic_savefig(fig, out, dpi=90)
    plt.close(fig)
    return out
