"""Monostatic ray tracing from the radar's nominal pose into a plain :class:`PathSet`.

One trace places a co-located transmitter and receiver at the radar phase
centre (origin of frame A) at the nominal pose of the trace instant, and runs

* Sionna's ``PathSolver`` for the scene geometry (specular and diffuse
  reflection up to ``max_depth`` bounces, no line of sight, no refraction), and
* Sionna's ``RCSSolver`` for the discrete constant-RCS targets (their
  scattering point, with unobstructed legs, plus ground-bounce legs when
  ``target_depth > 1``), and
* physical optics with shooting and bouncing rays for the geometry targets
  (targets with a mesh, :mod:`raysim.echoes.po.paths`): one path per
  scattering centre, kind ``PO_CENTRE``; the tubes and time of the last such
  trace are in ``tracer.geometry_stats``.

Everything Sionna returns is converted to NumPy in the world frame W (NED,
docs/conventions.md) and scaled to IF amplitudes [sqrt(W)] with the radar's
transmit power for isotropic (0 dBi) elements, so that ``|amplitude|^2`` is
the received power of each path with such elements. The element pattern is
applied once, at re-projection (:mod:`raysim.echoes.rt.reproject`), for every
path source. Paths whose two-way element gain at the trace pose lies more than
``pattern_floor_db`` below its peak are culled here.

Polarisation
------------
The radar is single-polarised, linear along ``X_A``. Two Sionna behaviours
would break the radar equation for such a radar (see the project's Sionna
notes): a sensing target with Sionna's default cross-polarisation matrix
(identity in the ``(theta, phi)`` basis) mirrors linear polarisation on
backscatter (targets off nadir come out up to 15 dB low, with a sign that
depends on the polarisation), and diffuse reflection has the same mirror (a
four-fold azimuth pattern in co-polarised ground clutter). The tracer
therefore

* gives every target the backscatter CPM ``diag(1, -1)``, which is the
  identity for the physical field (a depolarisation-free point scatterer); its
  co-polarised amplitude then equals the radar equation to 0.01 dB at every
  angle;
* traces with dual-polarised (``"VH"``) elements and keeps, for each path, the
  full ``2 x 2`` polarimetric matrix ``H``; specular and target paths use the
  co-polarised entry ``H_VV``; paths with a diffuse bounce use
  ``||H||_F / sqrt(2)``, which is the exact co-polarised magnitude of a
  depolarisation-free diffuse scatterer (``K_x = 0``) whatever the mirror does
  to the individual entries. Their sign is lost; diffuse paths get a seeded
  uniform random phase (sub-wavelength roughness), constant over the frame.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from raysim.echoes.rt.rough_bounces import object_materials, rough_bounce_factor
from raysim.echoes.rt.scenes import ENU_FROM_NED, RadarScene
from raysim.platform.motion import Trajectory, stationary
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.radar.pattern import PATTERN_FLOOR_DB, two_way_gain

#: Sionna interaction-type bits (``sionna.rt.constants.InteractionType``).
SPECULAR, DIFFUSE, REFRACTION, DIFFRACTION, SENSING = 1, 2, 4, 8, 16
#: Name of the backscatter cross-polarisation matrix registered with Sionna.
BACKSCATTER_CPM = "raysim-backscatter"
#: Device axes (boresight x, y, polarisation z) expressed in frame A.
_DEVICE_IN_A = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]])
_TX_NAME, _RX_NAME = "raysim-radar-tx", "raysim-radar-rx"


@dataclass(frozen=True, eq=False)
class PathSet:
    """Frozen propagation paths of one monostatic trace (world frame W, SI units).

    Paths are sorted by ``length``, then by first and last vertex, so equal
    traces give equal arrays.

    Attributes
    ----------
    first_vertex : ndarray, shape ``[path, 3]``
        First interaction point (leaving the transmitter) in W [m].
    last_vertex : ndarray, shape ``[path, 3]``
        Last interaction point (towards the receiver) in W [m].
    length : ndarray, shape ``[path]``
        Total path length tx -> ... -> rx at trace time [m] (float64, from the vertices).
    amplitude : ndarray, shape ``[path]``, complex128
        IF amplitude [sqrt(W)] without the propagation phase ``exp(-j 2 pi f tau)``
        for isotropic (0 dBi) elements: ``|amplitude|^2`` is the received power
        before the two-way element gain, which re-projection applies.
    velocity : ndarray, shape ``[path, 3]``
        Velocity of the scattering point(s) in W [m/s] (zero for static geometry).
    doppler : ndarray, shape ``[path]``
        Doppler shift from moving objects at trace time [Hz], docs/conventions.md sign
        (``f_D = 2 v_r / lambda``, positive when the path lengthens).
    interactions : ndarray of uint32, shape ``[path, depth]``
        Interaction type of each bounce (1 specular, 2 diffuse, 16 target, 0 none).
    kind : ndarray of uint32, shape ``[path]``
        Bitwise OR of ``interactions`` over the bounces.
    polarimetric : ndarray, shape ``[path, 2, 2]``, complex128
        Sionna's ``[rx_pol, tx_pol]`` matrix (V, H) per path, same scaling as ``amplitude``.
    solver_delay : ndarray, shape ``[path]``
        Sionna's own two-way delay (float32 precision) [s], kept for validation.
    tx_position, rx_position : ndarray, shape ``[3]``
        Transmitter / receiver positions used by the trace, in W [m].
    trace_time : float
        Time of the pose the trace used [s].
    dropped : dict
        Paths removed by each cull: ``"invalid"``, ``"range"``, ``"pattern"``
        (two-way element gain below the floor), and ``"pattern_power_w"``: the
        power [W] the pattern-culled paths would have carried with their
        element gains at the trace pose, and ``"beam_power_w"`` the same for the
        kept paths (not a cull: the denominator of :func:`pattern_culled_share`).
    """

    first_vertex: np.ndarray
    last_vertex: np.ndarray
    length: np.ndarray
    amplitude: np.ndarray
    velocity: np.ndarray
    doppler: np.ndarray
    interactions: np.ndarray
    kind: np.ndarray
    polarimetric: np.ndarray
    solver_delay: np.ndarray
    tx_position: np.ndarray
    rx_position: np.ndarray
    trace_time: float = 0.0
    dropped: dict = field(default_factory=dict)

    @property
    def num_paths(self) -> int:
        """Number of paths."""
        return int(self.length.shape[0])

    @property
    def delay(self) -> np.ndarray:
        """Two-way delay at trace time ``length / c``, shape ``[path]`` [s]."""
        return self.length / SPEED_OF_LIGHT

    @property
    def depth(self) -> np.ndarray:
        """Number of interactions of each path, shape ``[path]``."""
        return np.count_nonzero(self.interactions, axis=1)

    def select(self, mask: np.ndarray) -> PathSet:
        """A PathSet with the paths where ``mask`` [path] is True."""
        mask = np.asarray(mask)
        if mask.shape != (self.num_paths,):
            raise ValueError(f"mask must have shape ({self.num_paths},), got {mask.shape}")
        fields = {n: getattr(self, n)[mask] for n in (
            "first_vertex", "last_vertex", "length", "amplitude", "velocity", "doppler",
            "interactions", "kind", "polarimetric", "solver_delay")}
        return PathSet(**fields, tx_position=self.tx_position, rx_position=self.rx_position,
                       trace_time=self.trace_time, dropped=dict(self.dropped))

    @classmethod
    def concatenate(cls, sets: list[PathSet]) -> PathSet:
        """Join path sets traced from the same pose (sorted again)."""
        if not sets:
            raise ValueError("sets is empty")
        ref = sets[0]
        for s in sets[1:]:
            if not (np.array_equal(s.tx_position, ref.tx_position)
                    and np.array_equal(s.rx_position, ref.rx_position)):
                raise ValueError("path sets were traced from different radar positions")
        depth = max(s.interactions.shape[1] for s in sets)
        inter = np.concatenate([
            np.pad(s.interactions, ((0, 0), (0, depth - s.interactions.shape[1]))) for s in sets])
        fields = {n: np.concatenate([getattr(s, n) for s in sets]) for n in (
            "first_vertex", "last_vertex", "length", "amplitude", "velocity", "doppler", "kind",
            "polarimetric", "solver_delay")}
        dropped: dict = {}
        for s in sets:
            for k, v in s.dropped.items():
                dropped[k] = dropped.get(k, 0) + v
        out = cls(**fields, interactions=inter, tx_position=ref.tx_position,
                  rx_position=ref.rx_position, trace_time=ref.trace_time, dropped=dropped)
        return out.select(np.ones(out.num_paths, bool))._sorted()

    def _sorted(self) -> PathSet:
        keys = (self.last_vertex[:, 2], self.last_vertex[:, 1], self.last_vertex[:, 0],
                self.first_vertex[:, 2], self.first_vertex[:, 1], self.first_vertex[:, 0],
                self.length)
        order = np.lexsort(keys) if self.num_paths else np.arange(0)
        fields = {n: getattr(self, n)[order] for n in (
            "first_vertex", "last_vertex", "length", "amplitude", "velocity", "doppler",
            "interactions", "kind", "polarimetric", "solver_delay")}
        return PathSet(**fields, tx_position=self.tx_position, rx_position=self.rx_position,
                       trace_time=self.trace_time, dropped=dict(self.dropped))


def _backscatter_cpm(k_i, k_s, seed=0):
    """CPM ``diag(1, -1)`` in Sionna's ``(theta, phi)`` basis: identity for the physical field."""
    import drjit as dr
    import mitsuba as mi

    zero = dr.zeros(mi.Float, dr.width(k_i))
    return (mi.Matrix2f(zero + 1.0, zero, zero, zero - 1.0),
            dr.zeros(mi.Matrix2f, dr.width(k_i)))


def _register_cpm() -> None:
    from sionna.rt.rcs import get_cpm, register_cpm

    try:
        get_cpm(BACKSCATTER_CPM)
    except ValueError:
        register_cpm(BACKSCATTER_CPM, _backscatter_cpm)


def _check_int(name: str, value, minimum: int) -> int:
    if int(value) != value or value < minimum:
        raise ValueError(f"{name} must be an integer >= {minimum}, got {value!r}")
    return int(value)


@dataclass
class MonostaticTracer:
    """Monostatic path tracer: configure once, call with a scene and a pose.

    Parameters
    ----------
    max_depth : int
        Bounces of scene-geometry paths (``PathSolver``), >= 1. The default 3
        costs about 2 % more paths than 1 on the bundled scenes at no
        measurable trace time (``raysim bench --chart``, depth panel) and keeps
        ground-structure double and triple bounces; ``for_scene`` picks the
        depth a scene needs.
    specular : bool
        Trace specular reflections.
    diffuse : bool
        Trace diffuse reflections (distributed clutter).
    samples_per_src : int
        Rays shot from the radar; sets the number of diffuse paths (about
        8 % of the samples give kept ground paths for a radar 15 m up).
    target_depth : int
        Interactions of target paths including the scattering event
        (``RCSSolver``); 1 = direct legs only, 2 adds one specular bounce per leg.
    targets : bool
        Trace the scene's discrete targets.
    pattern_floor_db : float
        Floor of the two-way element gain ``G_t(u_dep) G_r(u_arr) / G_peak^2``
        at the trace pose [dB] (default
        :data:`raysim.radar.pattern.PATTERN_FLOOR_DB`, -40 dB); paths below it
        are dropped and counted in ``PathSet.dropped``. ``-inf`` keeps all.
    min_range : float
        Smallest kept one-way equivalent range ``length / 2`` [m].
    max_range : float or None
        Largest kept ``length / 2`` [m]; ``None`` uses ``config.max_range``.
    seed : int
        Seed of Sionna's ray sampling and of the diffuse random phases.
    diffuse_phase : {"random", "none"}
        Phase given to diffuse paths (whose sign Sionna's model does not fix).
    link_budget : bool
        Scale amplitudes by ``sqrt(P_t)`` (config's transmit power) so that they
        are IF amplitudes [sqrt(W)] of isotropic elements; otherwise leave
        Sionna's isotropic-antenna transfer coefficients (unitless). Element
        gains are applied at re-projection.
    plan : raysim.echoes.rt.trace_plan.TracePlan or None
        When given, scene geometry is traced on the plan's pruned copy of the
        scene (triangles outside the range window / pattern cone removed, see
        :meth:`for_scene`); ``None`` traces the scene as loaded.
    rough_bounces : bool
        Multiply every path by the Ament factor ``exp(-2 (k s cos theta_i)^2)``
        of each of its specular bounces on a material with an rms height ``s``
        (the ground materials of
        :data:`raysim.echoes.ground.sigma0.CLUTTER_MATERIALS`), at that bounce's
        incidence angle (:mod:`raysim.echoes.rt.rough_bounces`); Sionna itself
        reflects such surfaces with the smooth Fresnel coefficient. ``False``
        keeps Sionna's amplitudes.
    fidelity : raysim.echoes.po.fidelity.FidelityLadder or None
        Echo model of each geometry target (:mod:`raysim.echoes.po.fidelity`);
        ``None`` keeps every target's mesh centres.
    """

    max_depth: int = 3
    specular: bool = True
    diffuse: bool = True
    samples_per_src: int = 100_000
    target_depth: int = 1
    targets: bool = True
    pattern_floor_db: float = PATTERN_FLOOR_DB
    min_range: float = 0.0
    max_range: float | None = None
    seed: int = 42
    diffuse_phase: str = "random"
    link_budget: bool = True
    plan: object = None
    rough_bounces: bool = True
    fidelity: object = None

    def __post_init__(self) -> None:
        from raysim.echoes.po.fidelity import FidelityLadder
        from raysim.echoes.rt.trace_plan import TracePlan

        if self.fidelity is not None and not isinstance(self.fidelity, FidelityLadder):
            raise ValueError(f"fidelity must be a FidelityLadder or None, "
                             f"got {type(self.fidelity)}")

        if self.plan is not None and not isinstance(self.plan, TracePlan):
            raise ValueError(f"plan must be a TracePlan from plan_trace() or None, "
                             f"got {type(self.plan)}")
        _check_int("max_depth", self.max_depth, 1)
        _check_int("target_depth", self.target_depth, 1)
        _check_int("samples_per_src", self.samples_per_src, 1)
        _check_int("seed", self.seed, 0)
        if not isinstance(self.pattern_floor_db, (int, float)) \
                or math.isnan(self.pattern_floor_db) or self.pattern_floor_db >= 0:
            raise ValueError(f"pattern_floor_db must be a level below the peak (< 0 dB, -inf "
                             f"keeps all paths), got {self.pattern_floor_db!r}")
        if self.min_range < 0 or (self.max_range is not None
                                  and not self.max_range > self.min_range):
            raise ValueError(f"range window must satisfy 0 <= min_range < max_range, got "
                             f"min_range={self.min_range!r}, max_range={self.max_range!r}")
        if self.diffuse_phase not in ("random", "none"):
            raise ValueError(f"diffuse_phase must be 'random' or 'none', "
                             f"got {self.diffuse_phase!r}")

    # ------------------------------------------------------------------ public
    @classmethod
    def for_scene(cls, scene, config: RadarConfig, array, *, radar_position_w=None,
                  rays_per_cell: float | None = None, margin: float = 0.5,
                  **overrides) -> MonostaticTracer:
        """A tracer sized for ``scene`` by :func:`raysim.echoes.rt.trace_plan.plan_trace`.

        The plan sets ``max_depth`` and ``samples_per_src`` and prunes the
        geometry outside the range window and the element-pattern cone (triangle
        by triangle; shapes with nothing left are removed). ``overrides`` are
        other tracer parameters and win over the plan; ``pattern_floor_db`` and
        ``max_range`` are also used by the plan (the pruning cone is where the
        one-way element gain falls below the floor). With ``max_depth > 2`` the
        cone pruning is switched off (see :mod:`raysim.echoes.rt.trace_plan`).

        Parameters
        ----------
        scene : str, path-like, SceneDescriptor or RadarScene
            Scene to plan for.
        config : RadarConfig
            Waveform (range resolution, wavelength, range window).
        array : VirtualArray
            Virtual array (angular resolution).
        radar_position_w : array_like, shape ``[3]``, optional
            Radar position of the plan in W [m] (default the hover point).
        rays_per_cell : float, optional
            Average rays per resolution cell (default
            :data:`raysim.echoes.rt.trace_plan.DEFAULT_RAYS_PER_CELL`).
        margin : float
            Pruning margin for platform motion [m].
        **overrides
            :class:`MonostaticTracer` parameters.

        Returns
        -------
        MonostaticTracer
            With ``plan`` set; ``tracer.plan.summary()`` says what was dropped.
        """
        from raysim.echoes.rt.trace_plan import DEFAULT_RAYS_PER_CELL, plan_trace

        floor = overrides.get("pattern_floor_db", cls.pattern_floor_db)
        depth = overrides.get("max_depth")
        plan = plan_trace(scene, config, array, radar_position_w=radar_position_w,
                          pattern_floor_db=floor, max_range=overrides.get("max_range"),
                          rays_per_cell=(DEFAULT_RAYS_PER_CELL if rays_per_cell is None
                                         else rays_per_cell),
                          margin=margin, prune_fov=depth is None or depth <= 2)
        options = plan.tracer_options()
        options.update(overrides)
        return cls(**options)

    def __call__(self, scene: RadarScene, config: RadarConfig,
                 trajectory: Trajectory | None = None, lever_arm=(0.0, 0.0, 0.0), *,
                 time: float = 0.0) -> PathSet:
        """Trace from the radar phase centre at the pose of ``time``.

        Parameters
        ----------
        scene : RadarScene
            From :func:`raysim.echoes.rt.scenes.load_scene`.
        config : RadarConfig
            Carrier, power, gains and range window.
        trajectory : Trajectory, optional
            Platform motion (stationary if omitted); only the pose at ``time`` is used.
        lever_arm : array_like, shape ``[3]``
            Radar phase centre in the body frame B [m].
        time : float
            Trace instant [s].

        Returns
        -------
        PathSet
        """
        if not isinstance(scene, RadarScene):
            raise ValueError(f"scene must be a RadarScene from load_scene(), got {type(scene)}")
        trajectory = stationary() if trajectory is None else trajectory
        lever = np.asarray(lever_arm, dtype=float)
        if lever.shape != (3,) or not np.all(np.isfinite(lever)):
            raise ValueError(f"lever_arm must be 3 finite numbers [m], got {lever_arm!r}")
        if not math.isfinite(time):
            raise ValueError(f"time must be finite [s], got {time!r}")
        radar_w = trajectory.point_world([time], lever)[0, 0]
        r_wb = trajectory.attitude([time]).as_matrix()[0]
        self._prepare(scene, config, radar_w, r_wb)

        sets = []
        if self.specular or self.diffuse:
            geometry = scene
            if self.plan is not None:
                geometry = self.plan.prune(scene)
                if geometry is not scene:
                    self._prepare(geometry, config, radar_w, r_wb)
            sets.append(self._solve_geometry(geometry, config, radar_w, r_wb, time))
        if self.targets and _points(scene):
            sets.append(self._solve_targets(scene, config, radar_w, r_wb, time))
        if self.targets and len(_points(scene)) < len(scene.targets):
            from raysim.echoes.po.paths import geometry_paths

            fields = geometry_paths(
                scene, [t for t in scene.targets if t.is_geometry], config, radar_w, r_wb, time,
                # the pattern's cull cone: beyond it the two-way gain is below the floor
                fov_half_angle=config.pattern.cull_angle(self.pattern_floor_db),
                min_range=self.min_range,
                max_range=self.max_range, link_budget=self.link_budget,
                fidelity=self.fidelity)
            self.geometry_stats = fields.pop("stats")       # PO + SBR tubes and time
            sets.append(PathSet(**fields))
        if not sets:
            return _empty(radar_w, time)
        return PathSet.concatenate(sets) if len(sets) > 1 else sets[0]._sorted()

    # ----------------------------------------------------------------- helpers
    def _prepare(self, scene: RadarScene, config: RadarConfig, radar_w, r_wb, *,
                 targets: bool = True) -> None:
        from raysim.echoes.rt.backend import sionna_rt

        rt = sionna_rt()
        import mitsuba as mi

        sc = scene.sionna_scene
        if abs(float(sc.frequency[0]) / config.carrier_frequency - 1.0) > 1e-6:
            if getattr(scene, "_targets_added", False):
                raise ValueError(
                    f"scene was loaded for {float(sc.frequency[0]):.6g} Hz but config.carrier_"
                    f"frequency is {config.carrier_frequency:.6g} Hz; load it again with "
                    "load_scene(..., frequency=config.carrier_frequency)")
            sc.frequency = float(config.carrier_frequency)
        sc.tx_array = rt.PlanarArray(num_rows=1, num_cols=1, pattern="iso", polarization="VH")
        sc.rx_array = sc.tx_array
        pos = scene.to_scene(radar_w)
        rot_s = ENU_FROM_NED @ r_wb @ _DEVICE_IN_A
        with warnings.catch_warnings():
            # looking straight down is a gimbal lock of Z-Y-X angles; the rotation stays exact
            warnings.simplefilter("ignore", UserWarning)
            ypr = Rotation.from_matrix(rot_s).as_euler("ZYX")
        orient = mi.Point3f(*(float(v) for v in ypr))
        point = mi.Point3f(*(float(v) for v in pos))
        for name, cls in ((_TX_NAME, rt.Transmitter), (_RX_NAME, rt.Receiver)):
            if name in sc.transmitters or name in sc.receivers:
                dev = sc.get(name)
                dev.position = point
                dev.orientation = orient
            else:
                sc.add(cls(name, position=point, orientation=orient))
        if (targets and self.targets and _points(scene)
                and not getattr(scene, "_targets_added", False)):
            _register_cpm()
            from sionna.rt.rcs import ConstantRCS, ScatteringModel, SensingTarget

            for t in _points(scene):
                model = ScatteringModel(mi.Point3f(0.0, 0.0, 0.0),
                                        rcs=ConstantRCS(10 ** (t.rcs_dbsm / 10)),
                                        cpm=BACKSCATTER_CPM)
                p = scene.to_scene(t.position)
                v = scene.vector_to_scene(t.velocity)
                sc.add(SensingTarget(t.name, scattering_model=model, length=t.size,
                                     width=t.size, height=t.size,
                                     position=mi.Point3f(*(float(x) for x in p)),
                                     velocity=mi.Vector3f(*(float(x) for x in v))))
            scene._targets_added = True

    def _solve_geometry(self, scene, config, radar_w, r_wb, time) -> PathSet:
        from raysim.echoes.rt.backend import sionna_rt

        rt = sionna_rt()
        paths = rt.PathSolver()(
            scene.sionna_scene, max_depth=self.max_depth,
            max_num_paths_per_src=self.samples_per_src, samples_per_src=self.samples_per_src,
            synthetic_array=True, los=False, specular_reflection=self.specular,
            diffuse_reflection=self.diffuse, refraction=False, seed=self.seed)
        return self._convert(paths, scene, config, radar_w, r_wb, time)

    def _solve_targets(self, scene, config, radar_w, r_wb, time) -> PathSet:
        from sionna.rt.rcs import RCSSolver

        n = 10_000
        paths = RCSSolver()(scene.sionna_scene, max_depth=self.target_depth,
                            buffer_size_per_sp=n, samples_per_sp=n, synthetic_array=True,
                            los=True, specular_reflection=self.target_depth > 1,
                            refraction=False, seed=self.seed)
        return self._convert(paths, scene, config, radar_w, r_wb, time)

    def _convert(self, paths, scene: RadarScene, config: RadarConfig, radar_w, r_wb,
                 time) -> PathSet:
        a = (np.asarray(paths.a[0], dtype=np.float64)
             + 1j * np.asarray(paths.a[1], dtype=np.float64))  # [rx, rx_pol, tx, tx_pol, path]
        if a.ndim != 5 or a.shape[1] != 2 or a.shape[3] != 2:
            raise RuntimeError(f"unexpected Sionna path amplitude shape {a.shape}")
        pol = np.moveaxis(a[0, :, 0, :, :], -1, 0)                 # [path, 2, 2]
        n_all = pol.shape[0]
        if n_all == 0:
            return _empty(radar_w, time)
        valid = np.asarray(paths.valid).reshape(-1).astype(bool)
        inter = np.asarray(paths.interactions).reshape(-1, n_all).T.astype(np.uint32)
        verts_s = np.asarray(paths.vertices, dtype=np.float64).reshape(-1, n_all, 3)
        doppler = -np.asarray(paths.doppler, dtype=np.float64).reshape(-1)
        tau = np.asarray(paths.tau, dtype=np.float64).reshape(-1)
        depth = np.count_nonzero(inter, axis=1)
        keep = valid & (depth > 0) & np.any(pol != 0, axis=(1, 2))
        dropped = {"invalid": int(n_all - keep.sum())}
        pol, inter, depth, doppler, tau = (pol[keep], inter[keep], depth[keep], doppler[keep],
                                           tau[keep])
        verts = scene.to_world(verts_s[:, keep, :])              # [depth, path, 3]
        if self.rough_bounces:
            # coherent loss of specular bounces on rough ground, before the amplitude is taken
            objects = np.asarray(paths.objects).reshape(-1, n_all).T[keep]
            pol = pol * rough_bounce_factor(
                inter, objects, verts, radar_w, object_materials(scene.sionna_scene),
                config.wavelength)[:, None, None]
        n = pol.shape[0]
        idx = np.arange(n)
        first = verts[0]
        last = verts[depth - 1, idx]
        seg = np.linalg.norm(np.diff(verts, axis=0), axis=-1)     # [depth-1, path]
        inner = np.sum(np.where(np.arange(1, verts.shape[0])[:, None] < depth[None, :], seg, 0.0),
                       axis=0)
        length = (np.linalg.norm(first - radar_w, axis=-1) + inner
                  + np.linalg.norm(last - radar_w, axis=-1))
        kind = np.bitwise_or.reduce(inter, axis=1)
        # polarisation: co-pol (V along X_A) except where a diffuse bounce mirrors it
        amp = pol[:, 0, 0].copy()
        is_diffuse = (kind & DIFFUSE) != 0
        amp[is_diffuse] = np.sqrt(0.5 * np.sum(np.abs(pol[is_diffuse]) ** 2, axis=(1, 2)))
        if self.diffuse_phase == "random" and np.any(is_diffuse):
            rng = np.random.default_rng([self.seed, 0x5EED])
            # one phase per distinct scattering point, independent of path order
            key = np.round(first[is_diffuse] * 1e4).astype(np.int64)
            h = (key[:, 0] * 73856093) ^ (key[:, 1] * 19349663) ^ (key[:, 2] * 83492791)
            table = rng.uniform(0, 2 * np.pi, 4096)
            amp[is_diffuse] *= np.exp(1j * table[np.abs(h) % table.size])
        scale = 1.0
        if self.link_budget:
            # isotropic elements: the element pattern is applied at re-projection
            scale = math.sqrt(10 ** (config.tx_power_dbm / 10) * 1e-3)
        velocity = np.zeros((n, 3))
        if np.any(kind & SENSING) and _points(scene):
            tpos = np.stack([t.position for t in _points(scene)])
            tvel = np.stack([t.velocity for t in _points(scene)])
            sens = np.nonzero(kind & SENSING)[0]
            # the scattering vertex is the one flagged SENSING
            j = np.argmax(inter[sens] == SENSING, axis=1)
            pts = verts[j, sens]
            nearest = np.argmin(np.linalg.norm(pts[:, None, :] - tpos[None], axis=-1), axis=1)
            velocity[sens] = tvel[nearest]
        # culls: range window and the two-way element gain at the trace pose
        r_max = config.max_range if self.max_range is None else self.max_range
        in_range = (0.5 * length >= self.min_range) & (0.5 * length < r_max)
        pattern = config.pattern
        g2 = two_way_gain(pattern, (first - radar_w) @ r_wb, (last - radar_w) @ r_wb)
        in_beam = g2 >= pattern.peak_gain ** 2 * 10 ** (self.pattern_floor_db / 10)
        culled = in_range & ~in_beam
        dropped["range"] = int(np.sum(~in_range))
        dropped["pattern"] = int(np.sum(culled))
        ok = in_range & in_beam
        power = np.abs(scale * amp) ** 2 * g2
        dropped["pattern_power_w"] = float(np.sum(power[culled]))
        dropped["beam_power_w"] = float(np.sum(power[ok]))
        return PathSet(first[ok], last[ok], length[ok], scale * amp[ok], velocity[ok],
                       doppler[ok], np.ascontiguousarray(inter[ok]), kind[ok], scale * pol[ok],
                       tau[ok], np.array(radar_w), np.array(radar_w), float(time), dropped)


def pattern_culled_share(paths: PathSet) -> float:
    """Estimated share of the traced power that the pattern floor culled.

    ``dropped["pattern_power_w"] / (dropped["pattern_power_w"] +
    dropped["beam_power_w"])``: culled and kept power of the trace, both with
    the two-way element gain at the trace pose; 0 when nothing was traced.
    """
    lost = float(paths.dropped.get("pattern_power_w", 0.0))
    total = lost + float(paths.dropped.get("beam_power_w", 0.0))
    return lost / total if total > 0 else 0.0


def _points(scene: RadarScene) -> list:
    """The scene's constant-RCS point targets (geometry targets are traced by PO + SBR)."""
    return [t for t in scene.targets if not t.is_geometry]


def _empty(radar_w, time) -> PathSet:
    z3 = np.zeros((0, 3))
    return PathSet(z3, z3.copy(), np.zeros(0), np.zeros(0, complex), z3.copy(), np.zeros(0),
                   np.zeros((0, 1), np.uint32), np.zeros(0, np.uint32),
                   np.zeros((0, 2, 2), complex), np.zeros(0), np.array(radar_w), np.array(radar_w),
                   float(time), {})


def trace(scene: RadarScene, config: RadarConfig, trajectory: Trajectory | None = None,
          lever_arm=(0.0, 0.0, 0.0), *, time: float = 0.0, **options) -> PathSet:
    """One-call form of :class:`MonostaticTracer` (``options`` are its parameters)."""
    return MonostaticTracer(**options)(scene, config, trajectory, lever_arm, time=time)
