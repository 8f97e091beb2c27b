"""One stability-map point: a scenario in the TOML model's names and units plus the study's knobs.

:class:`StabilityPoint` is a light dataclass (built thousands of times per
map) whose scalar fields carry the names and units of the TOML scenario model
(:class:`raysim.scenario.Scenario`), flattened: ``target_range_m`` is
``scene.targets[0].range_m``, ``imu_rate_hz`` is ``imu.rate_hz``, and so on.
Where the TOML model has a section it holds the library object that section
converts to (``config`` = ``Scenario.radar_config()``, ``array`` =
``Scenario.virtual_array()``, ``trajectory`` = ``Scenario.trajectory()``,
``imu_spec`` = ``Scenario.imu_spec()``). The study's own knobs, which no
scenario file has, are ``lever_arm_error_m`` (error of the lever arm the
chains believe), ``init`` (initial state of the strapdown) and ``t0_s``
(frame start). :meth:`StabilityPoint.from_scenario` builds a point from a
TOML scenario.

A mounted radar (``mounting_deg``, TOML ``radar.mounting_deg``;
:mod:`raysim.platform.mounting`) is placed as every echo source places it: the
gate sees the radar frame A's own trajectory (:meth:`StabilityPoint.radar_pose`),
the target sits at ``(az, el)`` of the nominal radar frame N, the IMU stays on
the body and the chains form their beams in N with the motion expressed there
(:func:`raysim.platform.mounting.mount_motion`). The default ``down`` mounting
takes none of these turns (results as without the field).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from raysim.echoes.oracle import PointTarget, direction
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig

__all__ = ["INITS", "StabilityPoint"]

#: Initial states of the strapdown: the truth (aligned) or the hover assumption.
INITS = ("truth", "hover")


@dataclass(frozen=True, eq=False)
class StabilityPoint:
    """One stability-map point: radar, motion, one static target, IMU and the chains' beliefs.

    Parameters
    ----------
    config : RadarConfig
        Waveform (TOML ``[radar]``); one frame starting at ``t0_s``.
    array : VirtualArray
        Virtual UPA (TOML ``[array]`` kind ``upa``; needs ``grid_shape``).
    trajectory : raysim.platform.motion.Trajectory
        Truth body motion (TOML ``[motion]``).
    target_range_m : float
        Target range from the nominal radar phase centre [m]
        (``scene.targets[0].range_m``).
    target_az_deg, target_el_deg : float
        Target direction at the nominal attitude [deg], in (-90, 90), in the
        nominal radar frame N (``scene.targets[0].az_deg`` / ``el_deg``).
    lever_arm_m : array_like, shape ``[3]``
        True radar phase centre in B [m] (``lever_arm_m``).
    lever_arm_error_m : array_like, shape ``[3]``
        Error of the lever arm the chains are given [m] (study knob).
    imu_spec : str or raysim.platform.imu.ImuSpec
        IMU error model: preset name (``imu.preset``) or spec.
    imu_rate_hz : float
        IMU output rate [Hz] (``imu.rate_hz``).
    imu_time_offset_s : float
        IMU clock reading at radar time 0 [s] (``imu.time_offset_s``); the
        chains assume 0.
    imu_clock_drift_ppm : float
        IMU clock rate error [ppm] (``imu.clock_drift_ppm``); the chains assume 0.
    init : {"truth", "hover"}
        Initial state of the strapdown at the frame start (study knob): the
        truth (an aligned navigation solution) or the hover assumption
        (nominal attitude and position, velocity averaging to zero over the
        IMU record).
    t0_s : float
        Radar time of the first chirp [s] (study knob).
    seed : int
        Seed of the IMU error draws (``imu.seed``; :meth:`from_scenario` takes
        ``Scenario.imu_seed``).
    companion_az_deg : float or None
        Study knob: a second static scatterer at the target's range and
        elevation, this many degrees off the target in azimuth (inside its
        beam), so the target's beam holds two scatterers whose relative phase a
        horizontal displacement changes (clutter inside a beam). None: one target.
    companion_db : float
        RCS of the companion relative to the target's [dB].
    mounting_deg : str or (float, float, float)
        Radar mounting ``R_BA`` (TOML ``radar.mounting_deg``): a name of
        :data:`raysim.platform.mounting.MOUNTING_PRESETS` or Z-Y-X Euler
        angles (yaw, pitch, roll) [deg]; stored as the three angles. Default
        ``down`` (A parallel to B).
    """

    config: RadarConfig
    array: VirtualArray
    trajectory: object
    target_range_m: float = 15.0
    target_az_deg: float = 0.0
    target_el_deg: float = 0.0
    lever_arm_m: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 0.10]))
    lever_arm_error_m: np.ndarray = field(default_factory=lambda: np.zeros(3))
    imu_spec: object = "ideal"
    imu_rate_hz: float = 2000.0
    imu_time_offset_s: float = 0.0
    imu_clock_drift_ppm: float = 0.0
    init: str = "truth"
    t0_s: float = 0.0
    seed: int = 0
    companion_az_deg: float | None = None
    companion_db: float = -6.0
    mounting_deg: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        from raysim.platform.mounting import mounting_deg

        object.__setattr__(self, "mounting_deg", mounting_deg(self.mounting_deg,
                                                              "mounting_deg"))
        if not isinstance(self.config, RadarConfig):
            raise ValueError(f"config must be a RadarConfig, got {type(self.config).__name__}")
        if not isinstance(self.array, VirtualArray) or self.array.grid_shape is None:
            raise ValueError(f"array must be a gridded VirtualArray (UPA), got {self.array!r}")
        for name in ("lever_arm_m", "lever_arm_error_m"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"{name} must be 3 finite numbers [m], got {v!r}")
            object.__setattr__(self, name, v)
        if not math.isfinite(self.target_range_m) or self.target_range_m <= 0:
            raise ValueError(f"target_range_m must be a positive distance [m], "
                             f"got {self.target_range_m!r}")
        self.config.check_range(self.target_range_m, "target_range_m")
        for name in ("target_az_deg", "target_el_deg"):
            v = getattr(self, name)
            if not math.isfinite(v) or abs(v) >= 90.0:
                raise ValueError(f"{name} must be a finite angle in (-90, 90) deg, got {v!r}")
        if not math.isfinite(self.imu_rate_hz) or self.imu_rate_hz <= 0:
            raise ValueError(f"imu_rate_hz must be a finite positive rate [Hz], "
                             f"got {self.imu_rate_hz!r}")
        for name in ("imu_time_offset_s", "imu_clock_drift_ppm", "t0_s"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")
        if self.init not in INITS:
            raise ValueError(f"init must be one of {INITS}, got {self.init!r}")
        if not isinstance(self.seed, (int, np.integer)) or self.seed < 0:
            raise ValueError(f"seed must be a non-negative integer, got {self.seed!r}")
        if self.companion_az_deg is not None:
            az = self.target_az_deg + self.companion_az_deg
            if not (math.isfinite(az) and abs(az) < 90.0 and math.isfinite(self.companion_db)):
                raise ValueError(f"companion_az_deg must put the companion at a finite "
                                 f"azimuth in (-90, 90) deg and companion_db be finite, got "
                                 f"companion_az_deg={self.companion_az_deg!r}, "
                                 f"companion_db={self.companion_db!r}")
        if isinstance(self.imu_spec, str):
            from raysim.platform.imu import get_preset

            get_preset(self.imu_spec)            # raises naming the unknown preset

    # ------------------------------------------------------------ derived
    @property
    def target_az(self) -> float:
        """Target azimuth [rad]."""
        return math.radians(self.target_az_deg)

    @property
    def target_el(self) -> float:
        """Target elevation [rad]."""
        return math.radians(self.target_el_deg)

    @property
    def mounted(self) -> bool:
        """Whether the radar is mounted other than ``down`` (A turned from B)."""
        from raysim.platform.mounting import is_default_mounting

        return not is_default_mounting(self.mounting_deg)

    def _static(self, az: float, rcs_dbsm: float = 10.0) -> PointTarget:
        """A static point at the target's range and elevation, azimuth ``az`` [rad] of N."""
        if not self.mounted:
            return PointTarget.at(self.target_range_m, az, self.target_el, rcs_dbsm=rcs_dbsm,
                                  radar_origin=self.lever_arm_m)
        from raysim.platform.mounting import nominal_target_position

        return PointTarget(nominal_target_position(self.target_range_m, az, self.target_el,
                                                   self.lever_arm_m, self.mounting_deg),
                           rcs_dbsm=rcs_dbsm)

    @property
    def target(self) -> PointTarget:
        """The static target, placed from the nominal radar phase centre along
        ``R_BA u(az, el)`` (W)."""
        return self._static(self.target_az)

    @property
    def targets(self) -> list[PointTarget]:
        """The target, then the companion (if any), both static, 10 dBsm and ``companion_db``."""
        out = [self.target]
        if self.companion_az_deg is not None:
            out.append(self._static(math.radians(self.target_az_deg + self.companion_az_deg),
                                    10.0 + self.companion_db))
        return out

    @property
    def direction(self) -> np.ndarray:
        """True target direction from the nominal radar phase centre in N, shape ``[3]``
        (the frame the chains' beams are formed in)."""
        return direction(self.target_az, self.target_el)

    def radar_pose(self) -> tuple:
        """Trajectory and lever arm [m] of the radar frame A, as every echo source takes them.

        :func:`raysim.platform.mounting.mount_trajectory` of ``trajectory`` and
        ``lever_arm_m``; the default mounting returns them themselves.
        """
        from raysim.platform.mounting import mount_trajectory

        return mount_trajectory(self.trajectory, self.lever_arm_m, self.mounting_deg)

    @property
    def believed_lever_arm_m(self) -> np.ndarray:
        """Lever arm the chains are given, ``lever_arm_m + lever_arm_error_m``, ``[3]`` [m]."""
        return self.lever_arm_m + self.lever_arm_error_m

    def chirp_times(self) -> np.ndarray:
        """Radar time of every chirp of the frame, shape ``[chirp]`` [s]."""
        return self.config.chirp_times(0, self.t0_s)

    def with_(self, **changes) -> StabilityPoint:
        """Copy with some fields changed (validated again)."""
        return replace(self, **changes)

    # ------------------------------------------------------------ TOML model
    @classmethod
    def from_scenario(cls, scenario, *, lever_arm_error_m=(0.0, 0.0, 0.0), init: str = "truth",
                      t0_s: float = 0.0) -> StabilityPoint:
        """The point of a TOML scenario with one point target, plus the study's knobs.

        Parameters
        ----------
        scenario : raysim.scenario.Scenario
            A ``points`` scene with exactly one static target and a ``upa`` array.
        lever_arm_error_m, init, t0_s
            The study's knobs (see the class).

        Returns
        -------
        StabilityPoint
            ``config`` = ``scenario.radar_config()``, ``array`` =
            ``scenario.virtual_array()``, ``trajectory`` =
            ``scenario.trajectory()``, the target, lever arm, mounting
            (``radar.mounting_deg``) and IMU fields of the file, ``seed`` =
            ``scenario.imu_seed``.
        """
        from raysim.scenario import Scenario

        if not isinstance(scenario, Scenario):
            raise ValueError(f"scenario must be a raysim.scenario.Scenario, got "
                             f"{type(scenario).__name__}")
        targets = scenario.scene.targets
        if scenario.scene.kind != "points" or len(targets) != 1:
            raise ValueError(f"scenario.scene: got kind {scenario.scene.kind!r} with "
                             f"{len(targets)} targets, expected kind 'points' with one target")
        tgt = targets[0]
        if any(v != 0.0 for v in tgt.velocity_mps):
            raise ValueError(f"scene.targets.0.velocity_mps: got {tgt.velocity_mps}, expected a "
                             f"static target (0, 0, 0)")
        imu = scenario.imu
        return cls(scenario.radar_config(), scenario.virtual_array(), scenario.trajectory(),
                   target_range_m=tgt.range_m, target_az_deg=tgt.az_deg,
                   target_el_deg=tgt.el_deg, lever_arm_m=scenario.lever_arm,
                   lever_arm_error_m=lever_arm_error_m,
                   imu_spec=imu.preset if imu.preset != "custom" else scenario.imu_spec(),
                   imu_rate_hz=imu.rate_hz, imu_time_offset_s=imu.time_offset_s,
                   imu_clock_drift_ppm=imu.clock_drift_ppm, init=init, t0_s=t0_s,
                   seed=scenario.imu_seed, mounting_deg=scenario.radar.mounting_deg)
