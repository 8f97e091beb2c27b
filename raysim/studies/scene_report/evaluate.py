"""One scene or scenario of the report: the stationary reference and every chain, targets matched.

A bundled scene (:func:`evaluate_scene`) or any scenario (:func:`evaluate_scenario`:
point targets, a bundled scene, users' meshes) goes through the pipeline's
stages: the stationary / hover twin (:func:`raysim.pipeline.sources.hover_twin`),
the IMU record (:func:`raysim.pipeline.sensors.imu_record`), the pose estimate
(:mod:`raysim.pipeline.estimate`), the chains (:func:`raysim.pipeline.chains.project`),
the scene measurement (:mod:`raysim.measure.scene`, :mod:`raysim.measure.ridge`)
and, for the scenario's reference target, the point measurement of ``raysim simulate``.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, fields

import numpy as np

from raysim.measure.scene import SCENE_METRICS
from raysim.vocabulary import CHAINS, REFERENCE, chain_order, parse_chains

from .meshes import mesh_boxes, mesh_summary, mesh_targets
from .process import ChainResult, chain_result, point_metrics, report_cube
from .settings import (
    CFAR_THRESHOLD_DB,
    ENTROPY_MARGIN_NATS,
    QUICK,
    REPORT_MAPS,
    RIDGE_HALF_WIDTH_BINS,
    SCENARIO_KEYS,
    ReportSettings,
)
from .simulate import report_trajectory, scene_motion, simulate_scene

__all__ = ["SceneResult", "evaluate_scene", "evaluate_scenario", "settings_dict",
           "mover_truth", "find_mover", "MOVER_CENTRE_SPAN_DB", "object_box", "box_distance"]


def settings_dict(settings: ReportSettings) -> dict:
    """JSON-ready settings: the knobs, the scenario shortcuts and the scenario itself."""
    out = {f.name: getattr(settings, f.name) for f in fields(settings) if f.name != "scenario"}
    out.update({k: getattr(settings, k) for k in SCENARIO_KEYS})
    out["scenario"] = settings.scenario.to_dict()
    return out


def _finite(d: dict) -> dict:
    """Non-finite floats as None (JSON has no NaN)."""
    return {k: (float(v) if isinstance(v, (int, float)) and math.isfinite(v) else None)
            for k, v in d.items()}


@dataclass(frozen=True, eq=False)
class SceneResult:
    """Everything the report shows for one scene.

    Attributes
    ----------
    scene : str
    settings : ReportSettings
    reference : ChainResult
        The stationary platform (:data:`raysim.vocabulary.REFERENCE`), not a chain.
    chains : dict
        Chain key (``none``, ``paper``, ``exact`` ...) -> :class:`ChainResult`
        of the hovering platform, in :data:`raysim.vocabulary.CHAIN_NAMES` order.
    targets : list of dict
        Known reflectors: ``name``, ``position_m`` (W), ``range_m``, ``az_deg``,
        ``el_deg`` from the nominal radar phase centre, ``rcs_dbsm``; an
        extended object (a scene's mesh target: a car) also ``box``
        (:func:`object_box`); the nearest detection of the reference
        (``reference_match``) and of every chain (``match``: chain key ->
        ``detected``, ``error_m`` [m]: distance from the reference point, or
        from the box for an extended object, 0 inside; ``radius_m`` [m],
        ``rule``: ``"point"`` or ``"box"``, ``detection`` index); ``cfar``:
        key (the reference and every chain) -> the CFAR's verdict on the
        reflector's cell (an extended object matched: the matched detection's
        cell) (``status``:
        ``detected`` or the reason of a miss, ``snr_db``, ``threshold_db`` [dB],
        :func:`raysim.measure.scene.explain_detection`).
    num_paths : int
        Traced paths (after culls).
    path_kinds : dict
        Path count per interaction kind (``specular``, ``diffuse``, ``target``).
    motion_rms : dict
        RMS of the radar phase-centre displacement [m] and attitude angles [deg]
        over the frame.
    seconds : dict
        Wall time of tracing, synthesis, the IMU estimate, the reference and
        each chain [s].
    movers : list of dict
        Moving objects: :func:`mover_truth` plus ``match``: key (the reference
        and every chain) -> :func:`find_mover`.
    clutter : dict
        The clutter field's report (:attr:`raysim.echoes.ground.field.ClutterField.report`
        plus ``builds``: count, expected count, density scale, resolution cell,
        build time); empty with Sionna's clutter.
    same_aperture : dict
        Chain key -> :class:`ChainResult` of the stationary platform's frame
        through that chain's own smaller aperture (``dpca``: the elements of
        its sub-aperture, ``DPCAPlan.reference_index``, or a centred block of
        its size where those reach beyond the array; no motion): the
        reference at the chain's resolution, which its margin verdict uses
        (:meth:`margin_reference`), so the report can tell the aperture's price
        from what the motion leaves. Empty without ``dpca``.
    meshes : list of dict
        Users' meshes of a ``[[scene.meshes]]`` scenario: what the radar saw of
        each (:func:`raysim.studies.scene_report.meshes.mesh_summary`: ``name``,
        ``num_paths``, ``power_w``, ``power_dbw``, ``detections``); they are
        also in ``targets`` (``"mesh": True``) as named markers. Empty otherwise.
    fidelity : list of dict
        Echo model chosen per geometry target (``[scene] fidelity``,
        :class:`raysim.echoes.po.fidelity.FidelityChoice`: ``name``, ``level``,
        ``predicted_level``, ``paths``, ``predicted_error`` and
        ``measured_error`` per level, ``trace_seconds``, ``choice_seconds``).
        Empty for ``"mesh"``.
    point : dict
        Point metrics of the scenario's reference target
        (:func:`raysim.pipeline.sources.reference_target`): ``reference``
        (``range_m``, ``az_deg``, ``el_deg``) and ``metrics``: key (the
        reference and every chain) -> metric name -> value
        (:data:`raysim.vocabulary.METRICS`, the point measurement of ``raysim
        simulate``); empty when the scenario has no target.
    """

    scene: str
    settings: ReportSettings
    reference: ChainResult
    chains: dict
    targets: list
    num_paths: int
    path_kinds: dict
    motion_rms: dict
    seconds: dict
    movers: list = field(default_factory=list)
    clutter: dict = field(default_factory=dict)
    point: dict = field(default_factory=dict)
    same_aperture: dict = field(default_factory=dict)
    meshes: list = field(default_factory=list)
    fidelity: list = field(default_factory=list)

    def margin_reference(self, key: str) -> ChainResult:
        """The reference chain ``key``'s margin is judged against.

        The stationary frame through the same aperture: :attr:`same_aperture`
        for a chain that gives up aperture (``dpca``: the elements it holds
        fixed in the world; what it loses against the full array is its price,
        :meth:`aperture_cost`), else :attr:`reference`.
        """
        return self.same_aperture.get(key, self.reference)

    def within_margin(self, key: str) -> bool | None:
        """True when every map entropy of chain ``key`` is within the margin of its reference.

        The margin is :data:`ENTROPY_MARGIN_NATS` on every map of
        :data:`REPORT_MAPS`, against :meth:`margin_reference`; None when the
        chain was not evaluated.
        """
        if key not in self.chains:
            return None
        ex, st = self.chains[key].entropy, self.margin_reference(key).entropy
        return bool(all(abs(ex[m] - st[m]) <= ENTROPY_MARGIN_NATS for m in REPORT_MAPS))

    def aperture_cost(self, key: str) -> dict:
        """Map name -> entropy of the stationary frame through chain ``key``'s aperture minus
        through the full array [nats] (no motion: the aperture's own cost); empty for a
        chain with the full array."""
        if key not in self.same_aperture:
            return {}
        same = self.same_aperture[key].entropy
        return {m: same[m] - self.reference.entropy[m] for m in REPORT_MAPS}

    def exact_within_margin(self) -> bool | None:
        """:meth:`within_margin` of ``exact`` (None when it was not evaluated)."""
        return self.within_margin("exact")

    def warnings(self) -> dict:
        """Chain key -> its guard warnings (list of str; chains without any left out)."""
        return {c: list(r.warnings) for c, r in self.chains.items() if r.warnings}

    def to_dict(self) -> dict:
        """JSON-ready summary (no arrays); metric names from :data:`raysim.vocabulary.METRICS`.

        ``reference``: ``{"key": "stationary", "metrics", "detections"}``;
        ``chains``: chain key -> ``{"metrics", "minus_reference", "detections",
        "within_margin", "warnings"}`` (``dpca`` also ``"price"``:
        :meth:`raysim.measure.scene.SceneMeasurement.price`, the aperture,
        gain and resolution it gives up, and ``"same_aperture_reference"``:
        ``{"metrics", "minus_same_aperture", "aperture_cost_nats"}`` of the
        stationary frame through its sub-aperture, :attr:`same_aperture`, the
        reference its ``within_margin`` is judged against, and the entropy that
        aperture costs against the full array, :meth:`aperture_cost`;
        ``"margin_reference"`` names the reference of ``within_margin``) where
        ``minus_reference`` holds the
        differences of every metric to the reference's; ``point_metrics``:
        ``{"reference": target, "metrics": {key: {name: value}}}`` for a
        scenario with a target (NaN written as null).
        """
        ref = self.reference.metrics()
        chains = {}
        for c, r in self.chains.items():
            m = r.metrics()
            chains[c] = {"metrics": m, "minus_reference": {k: m[k] - ref[k] for k in m},
                         "detections": r.detections, "within_margin": self.within_margin(c),
                         "warnings": list(r.warnings)}
            if r.plan is not None:
                chains[c]["price"] = r.price()
            if c in self.same_aperture:
                sm = self.same_aperture[c].metrics()
                chains[c]["same_aperture_reference"] = {
                    "metrics": sm, "minus_same_aperture": {k: m[k] - sm[k] for k in m},
                    "aperture_cost_nats": {SCENE_METRICS[k]: v
                                           for k, v in self.aperture_cost(c).items()}}
            chains[c]["margin_reference"] = ("same_aperture" if c in self.same_aperture
                                             else REFERENCE)
        return {
            "scene": self.scene,
            "settings": settings_dict(self.settings),
            "num_paths": self.num_paths,
            "path_kinds": self.path_kinds,
            "motion_rms": self.motion_rms,
            "reference": {"key": REFERENCE, "metrics": ref,
                          "detections": self.reference.detections},
            "chains": chains,
            "entropy_margin_nats": ENTROPY_MARGIN_NATS,
            "exact_within_margin": self.exact_within_margin(),
            "targets": self.targets,
            "movers": self.movers,
            "clutter": self.clutter,
            "point_metrics": ({"reference": self.point["reference"],
                               "metrics": {k: _finite(v)
                                           for k, v in self.point["metrics"].items()}}
                              if self.point else {}),
            "meshes": self.meshes,
            "fidelity": self.fidelity,
            "seconds": self.seconds,
        }


def object_box(vertices: np.ndarray) -> dict:
    """The oriented bounding box of a level object's vertices: yaw from its footprint.

    The smallest-area rectangle around the north/east convex hull (one of its
    sides lies on a hull edge), its down extent from the vertices.

    Parameters
    ----------
    vertices : ndarray, shape ``[vertex, 3]``
        Points in W (NED) [m].

    Returns
    -------
    dict
        ``centre_m`` ``[3]`` (W [m]), ``axes`` ``[3, 3]`` (rows: the box's unit
        axes in W, the third one down) and ``half_m`` ``[3]`` (half extents
        along them [m]).
    """
    from scipy.spatial import ConvexHull

    v = np.asarray(vertices, dtype=float)
    ne = v[:, :2]
    hull = ne[ConvexHull(ne).vertices]
    best = None
    for a, b in zip(hull, np.roll(hull, -1, axis=0), strict=True):
        e = (b - a) / np.linalg.norm(b - a)
        rot = np.array([e, [-e[1], e[0]]])                      # [2 axes, 2]
        q = hull @ rot.T
        lo, hi = q.min(axis=0), q.max(axis=0)
        area = float(np.prod(hi - lo))
        if best is None or area < best[0]:
            best = (area, rot, lo, hi)
    _, rot, lo, hi = best
    centre_ne = rot.T @ ((lo + hi) / 2)
    zlo, zhi = float(v[:, 2].min()), float(v[:, 2].max())
    axes = np.zeros((3, 3))
    axes[:2, :2], axes[2, 2] = rot, 1.0
    return {"centre_m": [float(centre_ne[0]), float(centre_ne[1]), (zlo + zhi) / 2],
            "axes": axes.tolist(),
            "half_m": [float((hi - lo)[0] / 2), float((hi - lo)[1] / 2), (zhi - zlo) / 2]}


def box_distance(box: dict, points: np.ndarray) -> np.ndarray:
    """Distance of points from an :func:`object_box` [m]: 0 inside, else to its nearest face.

    ``points`` ``[point, 3]`` in W [m]; returns ``[point]``.
    """
    p = np.atleast_2d(np.asarray(points, dtype=float)) - np.asarray(box["centre_m"])
    local = p @ np.asarray(box["axes"]).T
    out = np.maximum(np.abs(local) - np.asarray(box["half_m"]), 0.0)
    return np.linalg.norm(out, axis=1)


def _mesh_vertices(target, scene) -> np.ndarray:
    """World vertices ``[vertex, 3]`` (W [m]) of a scene's mesh target (its parts together)."""
    import trimesh

    files = [target.mesh] if isinstance(target.mesh, str) else list(target.mesh)
    v = [np.asarray(trimesh.load(f, force="mesh", process=False).vertices, dtype=float)
         for f in files]
    return scene.to_world(np.concatenate(v))


def _targets(scene, settings: ReportSettings) -> list:
    """Known reflectors of a traced scene, or the point targets of a point scenario."""
    from raysim.echoes.oracle import az_el, direction
    from raysim.platform.mounting import mounting_matrix, nominal_direction

    lever = np.asarray(settings.lever_arm, dtype=float)
    mount = settings.scenario.radar.mounting_deg          # directions in N, positions in W
    turn = mounting_matrix(mount)                         # the identity for the default
    if scene is None:
        return [{"name": f"target {i}", "position_m": (lever + t.range_m * (turn @ direction(
                     math.radians(t.az_deg), math.radians(t.el_deg)))).tolist(),
                 "range_m": float(t.range_m), "az_deg": float(t.az_deg),
                 "el_deg": float(t.el_deg), "rcs_dbsm": float(t.rcs_dbsm)}
                for i, t in enumerate(settings.scenario.scene.targets)]
    out = []
    for t in scene.targets:
        v = t.position - lever
        r = float(np.linalg.norm(v))
        a, e = az_el(nominal_direction(v / r, mount))
        out.append({"name": t.name, "position_m": t.position.tolist(), "range_m": r,
                    "az_deg": float(np.rad2deg(a)), "el_deg": float(np.rad2deg(e)),
                    "rcs_dbsm": float(t.rcs_dbsm)})
        if getattr(t, "mesh", None) is not None:           # an extended object: its box
            out[-1]["box"] = object_box(_mesh_vertices(t, scene))
    return out


def _nearest(target: dict, result: ChainResult, radius: float) -> dict:
    """The detection of ``result`` nearest to ``target`` and whether it is within ``radius``.

    A point reflector: distance from its position. An extended object (``box``):
    distance from its oriented bounding box (0 inside), so a detection on any of
    its faces matches, not only one near its reference point.
    """
    if not result.detections:
        return {"detected": False}
    pts = np.array([x["position_m"] for x in result.detections], dtype=float)
    if "box" in target:
        d, rule = box_distance(target["box"], pts), "box"
    else:
        d, rule = np.linalg.norm(pts - np.asarray(target["position_m"]), axis=1), "point"
    i = int(np.argmin(d))
    return {"detected": bool(d[i] <= radius), "error_m": float(d[i]), "radius_m": radius,
            "rule": rule, "detection": i}


def _match(targets: list, reference: ChainResult, chains: dict,
           settings: ReportSettings) -> None:
    """Attach the nearest detection of the reference and of every chain to every reflector,
    and what the CFAR made of it (``cfar``: key -> :func:`raysim.measure.scene.explain_detection`:
    ``status``, ``snr_db``, ``threshold_db``, ``cell``).

    The match radius is one resolution cell at the reflector's range: half the
    null-to-null beamwidth, at least 1 m. An extended object is matched by a
    detection inside its box expanded by that radius and judged at the matched
    detection's cell; a point at its position."""
    from raysim.measure.scene import explain_detection

    beam = 2.0 / settings.array_size                  # ~ null-to-null half width [rad]
    for t in targets:
        radius = max(1.0, t["range_m"] * beam / 2)
        t["reference_match"] = _nearest(t, reference, radius)
        t["match"] = {c: _nearest(t, r, radius) for c, r in chains.items()}
        t["cfar"] = {}
        for k, r in {REFERENCE: reference, **chains}.items():
            m = t["reference_match"] if k == REFERENCE else t["match"][k]
            at = (t["range_m"], t["az_deg"], t["el_deg"])
            if "box" in t and m.get("detected"):           # the object's own detection
                x = r.detections[m["detection"]]
                at = (x["range_m"], x["az_deg"], x["el_deg"])
            t["cfar"][k] = explain_detection(r, *at)


#: Centres of a mover within this of its strongest (``rcs / R^4``) make up its truth [dB].
MOVER_CENTRE_SPAN_DB = 20.0


def mover_truth(mover, settings: ReportSettings, config) -> dict:
    """Range and range rate of a moving object's centres at mid-frame, from the nominal radar.

    Parameters
    ----------
    mover : raysim.echoes.moving.scatterers.MovingObject
    settings : ReportSettings
    config : RadarConfig

    Returns
    -------
    dict
        ``name``; ``range_m``, ``velocity_mps`` of its strongest centre
        (``rcs / R^4``); ``centres``: ``[range_m, velocity_mps, bin]`` of every
        centre within :data:`MOVER_CENTRE_SPAN_DB` of it, where ``bin`` is the
        range rate folded into the Doppler axis ``[-N/2, N/2)`` in bins
        (fractional); ``range_span_m`` ``(low, high)`` of those centres.
    """
    t = config.chirp_times()
    t_mid = 0.5 * (float(t[0]) + float(t[-1]))
    lever = np.asarray(settings.lever_arm, dtype=float)
    p = mover.positions(np.array(t_mid)) - lever                         # [point, 3]
    r = np.linalg.norm(p, axis=-1)
    v = mover.trajectory.velocity(np.array(t_mid))
    # rigid body, no turn within the frame: every centre moves at the body velocity
    rate = (p @ v) / r
    w = mover.rcs_dbsm - 40 * np.log10(r)
    i = int(np.argmax(w))
    near = np.nonzero(w >= w[i] - MOVER_CENTRE_SPAN_DB)[0]
    axis = config.velocity_axis(settings.num_chirps)
    dv, n = float(axis[1] - axis[0]), settings.num_chirps
    bins = (rate / dv + n / 2) % n - n / 2
    return {"name": mover.name, "range_m": float(r[i]), "velocity_mps": float(rate[i]),
            "centres": [[float(r[k]), float(rate[k]), float(bins[k])] for k in near],
            "range_span_m": (float(r[near].min()), float(r[near].max()))}


def find_mover(truth: dict, result: ChainResult, range_resolution: float) -> dict:
    """The strongest RD cell off the clutter ridge within the mover's range span.

    Parameters
    ----------
    truth : dict
        From :func:`mover_truth`.
    result : ChainResult
        Its ``rd`` map ``[range, doppler]`` is searched.
    range_resolution : float
        Range cell [m]; the span is widened by two cells either side.

    Returns
    -------
    dict
        ``range_m``, ``velocity_mps`` and ``bin`` (from zero) of the peak;
        ``error_bins``: circular Doppler distance to the nearest truth centre
        within two range cells of the peak; ``outside_ridge`` (the peak is
        beyond the ridge bins ``+-RIDGE_HALF_WIDTH_BINS``); ``contrast_db``: the
        peak over the median of its Doppler column at the gates outside the
        span (what the rest of the scene leaves at that Doppler);
        ``detected``: off the ridge, within one bin of a centre and
        ``contrast_db`` above the report's CFAR threshold.
    """
    rd = result.maps["rd"]
    rng, vel = rd.coords["range"], rd.coords["doppler"]
    n = vel.size
    centre = n // 2
    lo, hi = truth["range_span_m"]
    gates = (rng >= lo - 2 * range_resolution) & (rng <= hi + 2 * range_resolution)
    off = np.abs(np.arange(n) - centre) > RIDGE_HALF_WIDTH_BINS
    if not gates.any() or gates.all():
        return {"detected": False}
    sub = np.where(off[None, :], rd.values[gates], -np.inf)
    g, d = np.unravel_index(int(np.argmax(sub)), sub.shape)
    background = float(np.median(rd.values[~gates, d]))
    contrast = float(10 * np.log10(sub[g, d] / max(background, np.finfo(float).tiny)))
    b, r_peak = d - centre, float(rng[gates][g])
    c = np.asarray(truth["centres"], dtype=float)
    close = np.abs(c[:, 0] - r_peak) <= 2 * range_resolution
    err = (float(np.min(np.abs((b - c[close, 2] + n / 2) % n - n / 2))) if close.any()
           else float("inf"))
    return {"range_m": r_peak, "velocity_mps": float(vel[d]), "bin": int(b),
            "error_bins": err, "outside_ridge": bool(off[d]), "contrast_db": contrast,
            "detected": bool(off[d] and err <= 1.0 and contrast > CFAR_THRESHOLD_DB)}


def evaluate_scene(scene: str, settings: ReportSettings = QUICK, *, progress: bool = True,
                   chains: Sequence[str] | str = CHAINS) -> SceneResult:
    """Simulate and process one bundled scene: the stationary reference and every chain.

    Parameters
    ----------
    scene : str
        Registry name (``flat_reflectors``, ``parking_lot``, ``rough_terrain``).
    settings : ReportSettings
        Its scenario's scene is replaced by ``scene`` (:meth:`ReportSettings.for_scene`).
    progress : bool
        Show a tqdm bar on stderr.
    chains : sequence of str or str
        Chains of the hovering platform (:func:`raysim.vocabulary.parse_chains`:
        ``none``, ``paper``, ``paper:published``, ``exact``; default all of
        :data:`raysim.vocabulary.CHAINS`). The stationary reference is always
        computed.

    Returns
    -------
    SceneResult
    """
    from raysim.echoes.rt.scenes import SCENES

    if scene not in SCENES:
        raise ValueError(f"unknown scene {scene!r}; expected one of {sorted(SCENES)}")
    return evaluate_scenario(settings.for_scene(scene), progress=progress, chains=chains,
                             label=scene)


def _point_frames(settings: ReportSettings, trajectory, sim: dict):
    """Frames, stationary frames and motion of the point measurement.

    Point scenarios: all frames of the scenario as ``raysim simulate`` renders
    them (:class:`raysim.pipeline.sources.LazyFrames`), and the motion
    :func:`raysim.pipeline.run.evaluate` estimates (the scenario's IMU log over
    every frame, :func:`raysim.pipeline.estimate.scenario_motion` at every TDM
    slot). Traced scenarios: the twin's frames and the report's own estimate.
    """
    from raysim.pipeline.estimate import scenario_motion
    from raysim.pipeline.sensors import imu_log
    from raysim.pipeline.sources import LazyFrames, frame_source
    from raysim.platform.kinematics import slot_times
    from raysim.platform.motion import stationary

    scenario = settings.scenario
    config = settings.radar()
    if scenario.scene.kind != "points":
        return [sim["hover"]], [sim["stationary"]], None
    frames = LazyFrames(frame_source(scenario, trajectory), scenario.frames)
    still = LazyFrames(frame_source(scenario, stationary()), scenario.frames)
    times = slot_times(frames.chirp_times(), frames[0].array.num_slots,
                       config.slot_interval).ravel()
    motion = scenario_motion(scenario, imu_log(scenario, trajectory), times, trajectory)
    return frames, still, motion


def evaluate_scenario(settings: ReportSettings, *, progress: bool = True,
                      chains: Sequence[str] | str = CHAINS, label: str | None = None
                      ) -> SceneResult:
    """Simulate and process the scenario of ``settings``: the stationary reference and every chain.

    Frame 0 of the scenario is seen by a radar at rest and by the moving radar
    (:func:`raysim.studies.scene_report.simulate.report_trajectory`) through the
    pipeline's twin; the pose at every chirp is estimated from the scenario's
    IMU; every chain and the reference are measured over the scene
    (:func:`chain_result`). With a reference target
    (:func:`raysim.pipeline.sources.reference_target`), the point metrics of
    every chain and of the reference follow (:func:`point_metrics`): for a
    point scenario on all its frames with the motion of ``raysim simulate``,
    so they equal that command's values; for a traced scenario on the twin's
    frame.

    Parameters
    ----------
    settings : ReportSettings
    progress : bool
        Show a tqdm bar on stderr.
    chains : sequence of str or str
        Chains of the moving platform (default all of :data:`raysim.vocabulary.CHAINS`).
    label : str, optional
        Name of the result (default the scenario's name).

    Returns
    -------
    SceneResult
    """
    specs = sorted(parse_chains(chains), key=chain_order)
    from tqdm.auto import tqdm

    scenario = settings.scenario
    label = scenario.name if label is None else label
    bar = tqdm(total=4 + len(specs), desc=label, file=sys.stderr, disable=not progress,
               leave=False)
    config, array = settings.radar(), settings.array()
    trajectory = report_trajectory(settings)
    sim = simulate_scene(settings, trajectory,
                         progress=lambda msg: (bar.set_postfix_str(msg), bar.update()))
    if scenario.scene.kind == "points":
        bar.update()                                   # no trace
    t_chirp = config.chirp_times()
    t = time.perf_counter()
    frames, still, point_motion = _point_frames(settings, trajectory, sim)
    slots = array.num_slots
    if point_motion is None:                           # the report's estimate, every slot
        from raysim.platform.kinematics import slot_times

        point_motion = scene_motion(trajectory, slot_times(t_chirp, slots,
                                                           config.slot_interval).ravel(),
                                    settings)
    motion = point_motion.select(np.arange(config.num_chirps * slots))   # frame 0, every slot
    seconds = dict(sim["seconds"], imu=time.perf_counter() - t)
    rc = {k: report_cube(sim[k].data, settings) for k in ("stationary", "hover")}
    bar.set_postfix_str(REFERENCE)
    reference = chain_result(REFERENCE, rc["stationary"], None, settings, config, array)
    seconds[REFERENCE] = reference.seconds
    bar.update()
    results = {}
    for s in specs:
        bar.set_postfix_str(s.key)
        results[s.key] = chain_result(s, rc["hover"], motion, settings, config, array)
        seconds[s.key] = results[s.key].seconds
        for w in results[s.key].warnings:           # guard warnings reach the user
            bar.write(f"warning: {label}: {s.key}: {w}", file=sys.stderr)
        bar.update()
    same = {}
    if "dpca" in results and results["dpca"].plan is not None:   # the reference at its aperture
        from compensation import static_motion

        bar.set_postfix_str(f"{REFERENCE}, dpca sub-aperture")
        plan = results["dpca"].plan
        q = plan.reference_index
        # the very elements dpca holds; a block partly beyond the array (a motion
        # displaced over the whole frame) has no stationary twin: its size, centred
        inside = bool(np.all((q >= 0) & (q < np.asarray(plan.full_shape))))
        same["dpca"] = chain_result("dpca", rc["stationary"], static_motion(motion.time),
                                    settings, config, array,
                                    subaperture=q if inside else plan.sub_shape)
        seconds["dpca_same_aperture"] = same["dpca"].seconds
    point = {}
    target = sim.get("reference")
    if target is not None:
        t = time.perf_counter()
        metrics = {REFERENCE: point_metrics(still, target, "none", None)}
        for s in specs:
            metrics[s.key] = point_metrics(frames, target, s,
                                           point_motion if s.compensated else None)
        point = {"reference": {"range_m": target.range_m, "az_deg": target.az_deg,
                               "el_deg": target.el_deg}, "metrics": metrics}
        seconds["point_metrics"] = time.perf_counter() - t
    bar.close()
    boxes = mesh_boxes(settings.scenario)
    targets = _targets(sim.get("scene"), settings) + mesh_targets(
        boxes, settings.lever_arm, settings.scenario.radar.mounting_deg)
    _match(targets, reference, results, settings)
    meshes = mesh_summary(boxes, sim.get("paths"), {REFERENCE: reference, **results})
    movers = []
    for m in sim.get("movers", []):
        truth = mover_truth(m, settings, config)
        truth["match"] = {k: find_mover(truth, r, config.range_resolution)
                          for k, r in {REFERENCE: reference, **results}.items()}
        movers.append(truth)
    lever = np.asarray(settings.lever_arm, dtype=float)
    truth_disp = trajectory.point_world(t_chirp, lever)[:, 0] - lever
    ypr = np.rad2deg(trajectory.euler(t_chirp))
    motion_rms = {"displacement_m": float(np.sqrt(np.mean(np.sum(truth_disp**2, axis=1)))),
                  "displacement_span_m": float(np.max(np.ptp(truth_disp, axis=0))),
                  "yaw_pitch_roll_deg": np.sqrt(np.mean(ypr**2, axis=0)).tolist(),
                  "velocity_mps": float(np.sqrt(np.mean(np.sum(
                      trajectory.velocity(t_chirp) ** 2, axis=1))))}
    paths = sim.get("paths")
    return SceneResult(label, settings, reference, results, targets,
                       0 if paths is None else paths.num_paths, sim.get("path_kinds", {}),
                       motion_rms, seconds, movers, sim.get("clutter", {}), point, same,
                       meshes, sim.get("fidelity", []))
