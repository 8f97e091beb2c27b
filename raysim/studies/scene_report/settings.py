"""Settings and limits of the scene report (radar, motion, tracing, processing)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from raysim.measure.ridge import RIDGE_HALF_WIDTH_BINS
from raysim.measure.scene import (
    CFAR_GUARD,
    CFAR_THRESHOLD_DB,
    CFAR_TRAIN,
    GRID_HALF_WIDTH_DEG,
    GRID_STEP_DEG,
    MAX_DETECTIONS,
    RANGE_WINDOW_M,
    SCENE_MAPS,
    SPATIAL_WINDOWS,
    angle_grid,
    channel_taper,
)
from raysim.platform.motion import AXES
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig
from raysim.scenario import Scenario

__all__ = ["REPORT_MAPS", "ENTROPY_MARGIN_NATS",
           "RIDGE_HALF_WIDTH_BINS", "CFAR_TRAIN", "CFAR_GUARD", "CFAR_THRESHOLD_DB",
           "RD_PLOT_HALF_WIDTH_BINS", "MAX_DETECTIONS",
           "MOVER_START_NE", "MAX_MOVER_SPEED", "REPORT_CLUTTER", "SCENARIO_KEYS",
           "report_scenario", "ReportSettings", "FULL", "QUICK"]

#: The maps of every chain and of the reference, names from
#: :data:`raysim.vocabulary.MAPS`: ``rd`` (range, doppler), ``ra`` (range,
#: azimuth), ``ae`` (azimuth, elevation).
REPORT_MAPS = SCENE_MAPS
#: Largest ``|H_exact - H_stationary|`` (exact chain against the stationary
#: reference, :data:`raysim.vocabulary.REFERENCE`) of every map of every bundled scene with
#: the ideal IMU [nats] (checked by ``tests/rt/test_scene_report.py``). Set by
#: the residual Doppler of scatterers off a beam's centre, which no beam-domain
#: compensation removes (about ``2 d delta / lambda`` for a displacement ``d``
#: and an offset ``delta`` within the beamwidth). The persistent clutter field fills
#: every cell near nadir, where the hover's horizontal displacement (2.5 mm) changes
#: the relative phase of scatterers within one beam by up to about 1 rad
#: (``4 pi d du / lambda`` across a 14-degree beam): their speckle changes over the
#: frame, which no beam-domain compensation undoes (the parking lot's RD map stays
#: 0.23 nats off, QUICK, although its off-ridge power falls from -13.5 to -24 dB; the
#: report flags it). The margin holds, and is tested, for the jitter without horizontal
#: displacement (``jitter_axes=("z", "roll", "pitch", "yaw")``). See docs/scenes.md.
ENTROPY_MARGIN_NATS = 0.15
#: Half-width of the Doppler axis shown in the RD figures [Doppler bins].
RD_PLOT_HALF_WIDTH_BINS = 12
#: Start of the report's mover on the ground, north and east of the nadir point [m]: the
#: parking lot's lane between its two rows of cars (rows at 6 m south and 4 m north).
MOVER_START_NE = (-1.0, 6.0)
#: Largest mover speed of the report [m/s] (a car in a car park or a street).
MAX_MOVER_SPEED = 40.0
#: Ground clutter models of the report (values of ``render_scene(clutter=...)``).
REPORT_CLUTTER = ("field", "sionna")


#: Keyword -> scenario key paths of :meth:`ReportSettings.with_values` (the report's
#: radar, array, motion, IMU and scene settings live in its scenario).
SCENARIO_KEYS = {
    "num_chirps": ("radar.num_chirps",), "idle_time": ("radar.idle_time_s",),
    "array_size": ("array.nx", "array.ny"), "lever_arm": ("lever_arm_m",),
    "jitter_seed": ("motion.hover_jitter.seed",), "imu": ("imu.preset",),
    "imu_rate": ("imu.rate_hz",), "imu_seed": ("imu.seed",), "trace_seed": ("seed",),
    "max_depth": ("scene.max_depth",), "clutter": ("scene.clutter.mode",),
    "clutter_per_cell": ("scene.clutter.per_cell",), "decimate": ("synthesis.decimate",),
    "decimate_tolerance": ("synthesis.decimate_tolerance",),
    "fidelity": ("scene.fidelity",), "fidelity_tolerance": ("scene.fidelity_tolerance",),
}


def report_scenario(scene: str = "flat_reflectors", *, num_chirps: int = 128,
                    idle_time: float = 60e-6, array_size: int = 12) -> Scenario:
    """The report's scenario of a bundled scene.

    The paper's waveform (77 GHz, 1 GHz, 60 us, 10 MHz, 600 samples, the patch
    element pattern) with ``num_chirps`` chirps every ``60 us + idle_time``;
    a half-wavelength ``array_size x array_size`` virtual UPA (x major, y
    minor); the radar phase centre 0.10 m below the body origin; the hover
    jitter of a small multirotor (:func:`raysim.platform.motion.hover_jitter`,
    seed 7); the ideal IMU at 4 kHz (seed 1, above 20x the 160 Hz vibration
    band); single-bounce tracing (``max_depth`` 1) with the persistent clutter
    field of 10 scatterers per cell; seed 42 for the rays, diffuse phases and
    the field; one frame, no receiver noise.

    Parameters
    ----------
    scene : str
        Bundled scene name (:data:`raysim.echoes.rt.scenes.SCENES`).
    num_chirps : int
        Chirps per frame.
    idle_time : float
        Idle time between chirps [s].
    array_size : int
        UPA side [elements].
    """
    from raysim.scenario import validate_scenario

    return validate_scenario({
        "name": scene, "frames": 1, "seed": 42, "noise": False,
        "lever_arm_m": [0.0, 0.0, 0.10],
        "radar": {"num_chirps": num_chirps, "idle_time_s": idle_time},
        "array": {"kind": "upa", "nx": array_size, "ny": array_size},
        "scene": {"kind": "bundled", "name": scene, "max_depth": 1,
                  "clutter": {"mode": "field", "per_cell": 10.0}},
        "motion": {"hover_jitter": {"seed": 7, "scale": 1.0}},
        "imu": {"preset": "ideal", "rate_hz": 4000.0, "seed": 1},
    }, source="scene report scenario")


@dataclass(frozen=True)
class ReportSettings:
    """The report's scenario plus the knobs of the study.

    The radar, array, lever arm, platform motion (hover jitter and its seed),
    IMU and scene (tracing depth, clutter mode and density, seeds) are the
    :class:`raysim.scenario.Scenario`'s; the attributes below are what the
    report adds. Read-only shortcuts (``num_chirps``, ``array_size``,
    ``lever_arm``, ``jitter_seed``, ``imu``, ``imu_rate``, ``imu_seed``,
    ``trace_seed``, ``max_depth``, ``clutter``, ``clutter_per_cell``, ``fidelity``,
    ``fidelity_tolerance``) read the
    scenario; :meth:`with_values` changes either.

    Attributes
    ----------
    scenario : raysim.scenario.Scenario
        Radar, array, motion, IMU and scene (:func:`report_scenario` for a
        bundled scene). The bundled scenes of ``--scenes`` replace its scene name.
    samples_per_src : int
        Rays shot by the tracer (about 8 % become ground paths).
    grid_half_width_deg, grid_step_deg : float
        Global azimuth/elevation grid ``-w..+w`` in steps of ``step`` [deg].
    range_window : (float, float)
        Processed range window [m] (all samples are synthesised and range
        compressed; beams are formed on the gates inside the window only).
    jitter_axes : tuple of str
        Axes of :data:`raysim.platform.motion.AXES` the scenario's motion moves
        (default all six; e.g. ``("z", "roll", "pitch", "yaw")`` keeps the
        radar's horizontal position, to separate what compensation can undo).
        Traced scenes only (a point scenario runs its own motion, as ``raysim
        simulate`` does).
    nufft_eps : float
        Relative error of the IF synthesis (NUFFT, or the fused kernel where the
        paths go the compact way).
    path_chunk : int
        Paths re-projected and synthesised at once.
    gate_block : int
        Range gates beamformed at once (bounds memory).
    spatial_window : str or None
        Amplitude taper over the virtual channels before beamforming, the same
        for every chain: ``"taylor"`` (30 dB, ``nbar = 4`` along x and y) or
        ``None`` (uniform, -13 dB sidelobes). Sidelobes see the platform
        motion from their own direction, which no beam-domain compensation
        removes, so low sidelobes matter for clutter.
    mover_speed : float or None
        Ground speed [m/s] of a car (:class:`raysim.echoes.moving.cars.CarMover`)
        driving east along :data:`MOVER_START_NE` through the scene in both
        frames, or None for no mover.
    """

    scenario: Scenario = field(default_factory=report_scenario)
    samples_per_src: int = 100_000
    grid_half_width_deg: float = GRID_HALF_WIDTH_DEG
    grid_step_deg: float = GRID_STEP_DEG
    range_window: tuple[float, float] = RANGE_WINDOW_M
    jitter_axes: tuple[str, ...] = AXES
    nufft_eps: float = 1e-5
    path_chunk: int = 1024
    gate_block: int = 16
    spatial_window: str | None = "taylor"
    mover_speed: float | None = None

    def __post_init__(self) -> None:
        from raysim.scenario import Scenario

        if not isinstance(self.scenario, Scenario):
            raise ValueError(f"scenario must be a raysim.scenario.Scenario, "
                             f"got {type(self.scenario).__name__}")
        for name in ("samples_per_src", "path_chunk", "gate_block"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or isinstance(v, bool) or v < 1:
                raise ValueError(f"{name} must be a positive integer, got {v!r}")
        if self.num_chirps < 8:
            raise ValueError(f"num_chirps (radar.num_chirps) must be >= 8 for a Doppler map, "
                             f"got {self.num_chirps}")
        angle_grid(self.grid_half_width_deg, self.grid_step_deg)      # checks the grid
        lo, hi = self.range_window
        if not 0 <= lo < hi:
            raise ValueError(f"range_window must satisfy 0 <= low < high [m], "
                             f"got {self.range_window!r}")
        if hi >= self.radar().max_range:
            raise ValueError(f"range_window upper edge {hi!r} m must be below the radar's "
                             f"max_range {self.radar().max_range:.1f} m")
        if self.spatial_window not in SPATIAL_WINDOWS:
            raise ValueError(f"spatial_window must be 'taylor' or None, "
                             f"got {self.spatial_window!r}")
        axes = self.jitter_axes
        if not (isinstance(axes, tuple) and axes and all(a in AXES for a in axes)
                and len(set(axes)) == len(axes)):
            raise ValueError(f"jitter_axes must be a tuple of distinct names from {AXES}, "
                             f"got {axes!r}")
        if self.mover_speed is not None and not (
                math.isfinite(self.mover_speed) and 0 < self.mover_speed <= MAX_MOVER_SPEED):
            raise ValueError(f"mover_speed must be None or in (0, {MAX_MOVER_SPEED}] m/s, "
                             f"got {self.mover_speed!r}")
        if self.jitter_axes != AXES and self.scenario.scene.kind == "points":
            raise ValueError(f"jitter_axes selects the moving axes of a traced scene's twin; "
                             f"scenario {self.scenario.name!r} has point targets, which run "
                             f"the scenario's own motion, got {self.jitter_axes!r}")
        if self.mover_speed is not None and self.scenario.scene.kind == "points":
            raise ValueError(f"mover_speed drives a car through a ray-traced scene; scenario "
                             f"{self.scenario.name!r} has point targets (scene.kind 'points')")
        if not 1e-7 <= self.nufft_eps < 1:
            raise ValueError(f"nufft_eps must lie in [1e-7, 1), got {self.nufft_eps!r}")

    # ---------------------------------------------------- scenario shortcuts
    @property
    def num_chirps(self) -> int:
        """Chirps per frame (``radar.num_chirps``)."""
        return int(self.scenario.radar.num_chirps)

    @property
    def idle_time(self) -> float:
        """Idle time between chirps [s] (``radar.idle_time_s``)."""
        return float(self.scenario.radar.idle_time_s)

    @property
    def array_size(self) -> int:
        """Side of a square UPA, else the smaller grid side (at least 1) [elements]."""
        g = self.array().grid_shape
        return int(min(g)) if g is not None else 1

    @property
    def lever_arm(self) -> tuple[float, float, float]:
        """Radar phase centre in B [m] (``lever_arm_m``)."""
        return tuple(float(v) for v in self.scenario.lever_arm_m)

    @property
    def jitter_seed(self) -> int | None:
        """Seed of the hover jitter (``motion.hover_jitter.seed``, else ``seed``), or None."""
        hj = self.scenario.motion.hover_jitter
        if hj is None:
            return None
        return self.scenario.seed if hj.seed is None else int(hj.seed)

    @property
    def imu(self) -> str:
        """IMU preset (``imu.preset``)."""
        return self.scenario.imu.preset

    @property
    def imu_rate(self) -> float:
        """IMU output rate [Hz] (``imu.rate_hz``)."""
        return float(self.scenario.imu.rate_hz)

    @property
    def imu_seed(self) -> int:
        """Seed of the IMU error draws (``imu.seed``, else ``seed + 1``)."""
        return int(self.scenario.imu_seed)

    @property
    def trace_seed(self) -> int:
        """Seed of the rays, diffuse phases and clutter field (``seed``)."""
        return int(self.scenario.seed)

    @property
    def max_depth(self) -> int:
        """Bounces of scene-geometry paths (``scene.max_depth``, at least 1)."""
        return max(1, int(self.scenario.scene.max_depth))

    @property
    def clutter(self) -> str:
        """Ground clutter mode (``scene.clutter.mode``: ``field``, ``sionna``, ``none``)."""
        return self.scenario.scene.clutter.mode

    @property
    def clutter_per_cell(self) -> float:
        """Clutter-field scatterers per range x angle cell (``scene.clutter.per_cell``)."""
        return float(self.scenario.scene.clutter.per_cell)

    @property
    def decimate(self) -> str:
        """Slow-time decimation of the synthesis (``synthesis.decimate``: ``auto``, ``off``)."""
        return self.scenario.synthesis.decimate

    @property
    def decimate_tolerance(self) -> float | None:
        """Relative error allowed to that interpolation (``synthesis.decimate_tolerance``;
        None: 0.1 x ``nufft_eps``)."""
        return self.scenario.synthesis.decimate_tolerance

    @property
    def fidelity(self) -> str:
        """Echo model of the geometry targets (``scene.fidelity``: ``mesh``, ``auto``, ...)."""
        return self.scenario.scene.fidelity

    @property
    def fidelity_tolerance(self) -> float:
        """Error allowed to each object's echo under ``auto`` (``scene.fidelity_tolerance``)."""
        return float(self.scenario.scene.fidelity_tolerance)

    def with_values(self, **changes) -> ReportSettings:
        """Copy with knobs and scenario values changed, validated again.

        Keywords are knob names (the attributes) or the shortcuts of
        :data:`SCENARIO_KEYS` (``num_chirps=64``, ``array_size=8``,
        ``imu="tactical"``, ``clutter="sionna"`` ...); errors name the keyword,
        its scenario key, the value and what was expected.
        """
        knobs = {k: v for k, v in changes.items() if k not in SCENARIO_KEYS}
        unknown = sorted(set(knobs) - {f.name for f in fields(self)})
        if unknown:
            raise ValueError(f"unknown report setting(s) {unknown}; expected knobs "
                             f"{sorted(f.name for f in fields(self))} or scenario shortcuts "
                             f"{sorted(SCENARIO_KEYS)}")
        scenario = knobs.pop("scenario", self.scenario)
        for name, value in changes.items():
            if name not in SCENARIO_KEYS:
                continue
            if name == "clutter" and value not in REPORT_CLUTTER + ("none",):
                raise ValueError(f"clutter must be one of {REPORT_CLUTTER + ('none',)}, "
                                 f"got {value!r}")
            if name == "jitter_seed" and scenario.motion.hover_jitter is None:
                raise ValueError(f"jitter_seed: scenario {scenario.name!r} has no "
                                 f"[motion.hover_jitter] to seed, got {value!r}")
            value = list(value) if isinstance(value, tuple) else value
            try:
                scenario = scenario.with_values({k: value for k in SCENARIO_KEYS[name]})
            except ValueError as exc:
                raise ValueError(f"{name} ({', '.join(SCENARIO_KEYS[name])}): got {value!r}: "
                                 f"{exc}") from None
        return replace(self, scenario=scenario, **knobs)

    def for_scenario(self, scenario: Scenario) -> ReportSettings:
        """These settings on a scenario file's scenario.

        The default range window (:data:`RANGE_WINDOW_M`) is cut to the
        scenario's radar where that radar sees less far: upper edge its
        unambiguous range less two range bins [m], lower edge at most half of
        that. The default window and the default grid half-width
        (:data:`GRID_HALF_WIDTH_DEG`) then widen so that every mesh and point
        target of the scenario is on the maps (:meth:`covering`). A window or
        grid the caller set is kept and checked as given.
        """
        window = tuple(self.range_window)
        default = window == tuple(RANGE_WINDOW_M)
        if default:
            cfg = scenario.radar_config()
            top = cfg.max_range - 2 * cfg.range_resolution
            if window[1] > top:
                window = (min(window[0], top / 2), top)
        return self.with_values(scenario=scenario, range_window=window).covering(
            window=default, grid=self.grid_half_width_deg == GRID_HALF_WIDTH_DEG)

    def covering(self, *, window: bool = True, grid: bool = True) -> ReportSettings:
        """These settings with the range window and the angle grid widened to hold every
        object of the scenario (:func:`raysim.studies.scene_report.coverage.covering_extents`
        over :func:`~raysim.studies.scene_report.coverage.object_spans`), within the
        radar's unambiguous range less two range bins.

        ``window``, ``grid``: which of the two may widen (False keeps a user's own).
        """
        from .coverage import covering_extents, object_spans

        if not (window or grid):
            return self
        cfg = self.radar()
        got = covering_extents(object_spans(self.scenario), self.range_window,
                               self.grid_half_width_deg, self.grid_step_deg,
                               cfg.max_range - 2 * cfg.range_resolution,
                               widen_window=window, widen_grid=grid)
        return self.with_values(range_window=got["range_window"],
                                grid_half_width_deg=got["grid_half_width_deg"])

    def for_scene(self, scene: str) -> ReportSettings:
        """These settings with the scenario's scene the bundled ``scene`` (and its name)."""
        from raysim.echoes.rt.scenes import SCENES

        if scene not in SCENES:
            raise ValueError(f"unknown scene {scene!r}; expected one of {sorted(SCENES)}")
        if self.scenario.scene.kind != "bundled":
            raise ValueError(f"for_scene needs a bundled-scene scenario, got scene.kind "
                             f"{self.scenario.scene.kind!r}")
        out = replace(self, scenario=self.scenario.with_values(
            {"scene.name": scene, "name": scene}))
        return out.covering(window=tuple(self.range_window) == tuple(RANGE_WINDOW_M),
                            grid=self.grid_half_width_deg == GRID_HALF_WIDTH_DEG)

    # ------------------------------------------------------------ derived
    def radar(self) -> RadarConfig:
        """The scenario's waveform (:meth:`raysim.scenario.Scenario.radar_config`).

        The radar's element pattern (:mod:`raysim.radar.pattern`, the patch
        element by default) weights every path by its two-way gain.
        """
        return self.scenario.radar_config()

    def array(self) -> VirtualArray:
        """The scenario's virtual array (:meth:`raysim.scenario.Scenario.virtual_array`)."""
        return self.scenario.virtual_array()

    def channel_taper(self) -> np.ndarray:
        """Channel weights, shape ``[channel]`` (x index major, y minor), mean 1."""
        return channel_taper(self.array(), self.spatial_window)

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Azimuth and elevation axes of the global grid [rad]."""
        return angle_grid(self.grid_half_width_deg, self.grid_step_deg)


#: Settings of ``raysim scene-report`` (all scenes: 9.5 minutes on 2 busy cores, mostly
#: IF synthesis of 8,300 paths x 128 chirps x 144 channels x 600 samples).
FULL = ReportSettings()
#: Settings of ``raysim scene-report --quick`` and of the tests (15-30 s per scene): 64
#: chirps every 240 us (the frame of the paper's radar, 15.36 ms), an 8 x 8 UPA, 20k rays,
#: a 6-degree grid.
QUICK = ReportSettings(report_scenario(num_chirps=64, idle_time=180e-6, array_size=8),
                       samples_per_src=20_000, grid_step_deg=6.0)
