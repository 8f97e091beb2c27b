"""The scenario model: one TOML file describes a whole simulation run.

A scenario fixes the radar waveform, the antenna array, the scene (point
targets, a bundled ray-tracing scene or a mesh file), the platform motion, the
radar lever arm, the IMU, the number of frames, the seeds and the outputs.
Files are parsed with :mod:`tomllib` and validated with pydantic models that
forbid unknown keys. Every validation problem is reported in one
:class:`ValueError` whose lines name the key path, the value and what was
expected, e.g. ``radar.sample_rate_hz: got -1, expected > 0``.

File units follow docs/conventions.md: SI with the unit in the key name
(``sample_rate_hz``, ``range_m``), angles in degrees (``az_deg``,
``amplitude_deg``). :meth:`Scenario.radar_config`, :meth:`Scenario.trajectory`
and friends convert to the SI / radian objects of the library. Files are read
by :mod:`raysim.scenario.reader`.

Example
-------
.. code-block:: toml

    name = "pitch wobble"
    frames = 1
    seed = 0

    [radar]
    num_chirps = 64

    [array]
    kind = "upa"
    nx = 8
    ny = 8

    [[scene.targets]]
    range_m = 15.0
    az_deg = 20.0
    el_deg = 0.0

    [[motion.sinusoids]]
    axis = "pitch"
    amplitude_deg = 10.0
    frequency_hz = 20.0
"""

from __future__ import annotations

import json
import math
from typing import Any, Literal

import numpy as np
from pydantic import (
    BaseModel,
    Field,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from raysim.radar.config import RCS_DBSM_RANGE
from raysim.scenario.keys import (
    ClutterSection,
    MoverSection,
    RotorSection,
    did_you_mean,
    dumps_toml,
    format_validation_error,
    set_key,
)
from raysim.scenario.meshes import MeshSpec
from raysim.scenario.paper_cases import PAPER_CASES, get_case
from raysim.scenario.radar import RadarSection, _in_range, _Section
from raysim.scenario.synthesis import SynthesisSection

__all__ = [
    "RadarSection", "ArraySection", "TargetSpec", "SceneSection", "SinusoidSpec",
    "HoverJitterSection", "MotionSection", "SensorErrorsSection", "ImuSection",
    "OutputSection", "SynthesisSection", "Scenario", "validate_scenario", "cross_problems",
    "ANGLE_AXES", "TRANSLATION_AXES",
]

#: Motion axes whose amplitudes are angles (given in degrees in files).
ANGLE_AXES = ("roll", "pitch", "yaw")
#: Motion axes whose amplitudes are lengths (given in metres in files).
TRANSLATION_AXES = ("x", "y", "z")

Vec3 = tuple[float, float, float]


# ----------------------------------------------------------------------- array
class ArraySection(_Section):
    """``[array]``: antenna layout in the radar frame A.

    ``kind = "upa"``: virtual ``nx x ny`` UPA (x major, y minor), spacing
    ``spacing_m`` (default half a carrier wavelength).
    ``kind = "ti_3tx4rx"``: TI-style 3 Tx x 4 Rx TDM MIMO (12 channels).
    ``kind = "custom"``: TDM MIMO from ``tx_positions_m`` and ``rx_positions_m``
    (lists of ``[x, y, z]`` in metres, frame A), fired tx 0 first.
    """

    kind: Literal["upa", "ti_3tx4rx", "custom"] = "upa"
    nx: int = Field(20, ge=1, le=256)
    ny: int = Field(20, ge=1, le=256)
    spacing_m: float | None = Field(None, gt=0)
    tx_positions_m: list[Vec3] | None = None
    rx_positions_m: list[Vec3] | None = None

    @model_validator(mode="after")
    def _custom_needs_positions(self) -> ArraySection:
        if self.kind == "custom":
            if not self.tx_positions_m or not self.rx_positions_m:
                raise ValueError("kind 'custom' needs tx_positions_m and rx_positions_m "
                                 "(lists of [x, y, z] in metres)")
        elif self.tx_positions_m is not None or self.rx_positions_m is not None:
            raise ValueError(f"tx_positions_m / rx_positions_m only apply to kind 'custom', "
                             f"not {self.kind!r}")
        return self


# ----------------------------------------------------------------------- scene
class TargetSpec(_Section):
    """One point target, placed from the nominal radar phase centre.

    ``range_m`` [m], direction ``az_deg`` / ``el_deg`` [deg] (docs/conventions.md),
    ``rcs_dbsm`` [dBsm] (range -250 to 100 dBsm), constant world (NED)
    velocity ``velocity_mps`` [m/s].
    """

    range_m: float = Field(gt=0)
    az_deg: float = Field(0.0, ge=-90, le=90)
    el_deg: float = Field(0.0, ge=-90, le=90)
    rcs_dbsm: float = 10.0

    _rcs = field_validator("rcs_dbsm")(
        lambda v: _in_range(v, RCS_DBSM_RANGE, "dBsm", "a radar cross-section"))
    velocity_mps: Vec3 = (0.0, 0.0, 0.0)


class SceneSection(_Section):
    """``[scene]``: what the radar sees.

    ``kind = "points"`` with ``[[scene.targets]]``; ``kind = "bundled"`` with
    ``name`` one of ``raysim.echoes.rt.scenes.SCENES``; ``kind = "mesh"`` with
    ``path`` to a Mitsuba XML scene or a mesh file (relative paths are taken
    from the scenario file's folder); ``kind = "meshes"`` with ``[[scene.meshes]]``
    (users' mesh files, :mod:`raysim.scenario.meshes`). ``kind`` may be omitted:
    it is inferred from which key is given. ``fidelity``: echo model of each
    geometry target (``"mesh"``, today's full PO + SBR centres; ``"point"``,
    ``"centres"``; ``"auto"``, the cheapest within ``fidelity_tolerance``, the
    relative l2 error of the object's echo against its mesh;
    :mod:`raysim.echoes.po.fidelity`). ``[[scene.movers]]``: cars driving
    through a ray-traced scene (:class:`raysim.scenario.keys.MoverSection`);
    ``[[scene.rotors]]``: rotating parts (:class:`raysim.scenario.keys.RotorSection`).
    """

    kind: Literal["points", "bundled", "mesh", "meshes"] | None = None
    targets: list[TargetSpec] = Field(default_factory=list)
    name: str | None = None
    path: str | None = None
    meshes: list[MeshSpec] = Field(default_factory=list)
    max_depth: int = Field(3, ge=0, le=10)
    fidelity: Literal["auto", "point", "centres", "mesh"] = "mesh"
    fidelity_tolerance: float = Field(0.05, gt=0, le=1)
    clutter: ClutterSection = Field(default_factory=ClutterSection)
    movers: list[MoverSection] = Field(default_factory=list)
    rotors: list[RotorSection] = Field(default_factory=list)

    @model_validator(mode="after")
    def _infer_kind(self) -> SceneSection:
        given = {"points": bool(self.targets), "bundled": self.name is not None,
                 "mesh": self.path is not None, "meshes": bool(self.meshes)}
        kind = self.kind
        if kind is None:
            chosen = [k for k, v in given.items() if v]
            if len(chosen) > 1:
                raise ValueError(f"give only one of targets / name / path / meshes, got {chosen}")
            kind = chosen[0] if chosen else "points"
            object.__setattr__(self, "kind", kind)
        problems = []               # every one, one line each
        if kind == "points" and not self.targets:
            problems.append("kind 'points' needs at least one [[scene.targets]] entry")
        if kind == "bundled" and not self.name:
            problems.append("kind 'bundled' needs name (see `raysim scenes list`)")
        if kind == "meshes" and not self.meshes:
            problems.append("kind 'meshes' needs at least one [[scene.meshes]] entry")
        if kind == "mesh" and not self.path:
            problems.append("kind 'mesh' needs path (a Mitsuba XML or mesh file)")
        for key, items in (("movers", self.movers), ("rotors", self.rotors)):
            if items and (kind == "points" or self.clutter.mode != "field"):
                problems.append(f"[[scene.{key}]] need a ray-traced scene with "
                                f"[scene.clutter] mode = 'field', got kind {kind!r}, "
                                f"mode {self.clutter.mode!r}")
        c = self.clutter
        if (c.wind_mps > 0 or c.vegetation is not None) and (kind == "points"
                                                              or c.mode != "field"):
            problems.append(f"[scene.clutter] wind_mps / vegetation need a ray-traced scene "
                            f"with mode = 'field', got kind {kind!r}, mode {c.mode!r}")
        if 0 < c.wind_mps < 0.224:
            problems.append(f"[scene.clutter] wind_mps: got {c.wind_mps:g} m/s, expected 0 "
                            f"(still) or at least 0.224 m/s (0.5 mph, the model's lightest air)")
        if problems:
            raise ValueError("\n".join(problems))
        return self


# ---------------------------------------------------------------------- motion
class SinusoidSpec(_Section):
    """One sinusoid ``A sin(2 pi f t + phase)`` on one motion axis.

    ``amplitude_m`` for ``x, y, z`` (NED body-origin position [m]),
    ``amplitude_deg`` for ``roll, pitch, yaw`` [deg]; ``frequency_hz`` [Hz];
    ``phase_deg`` [deg].
    """

    axis: Literal["x", "y", "z", "roll", "pitch", "yaw"]
    amplitude_m: float | None = None
    amplitude_deg: float | None = None
    frequency_hz: float = Field(ge=0)
    phase_deg: float = 0.0

    @model_validator(mode="after")
    def _amplitude_unit(self) -> SinusoidSpec:
        if self.axis in ANGLE_AXES:
            if self.amplitude_m is not None or self.amplitude_deg is None:
                raise ValueError(f"axis {self.axis!r} is an angle: give amplitude_deg "
                                 f"(not amplitude_m)")
        elif self.amplitude_deg is not None or self.amplitude_m is None:
            raise ValueError(f"axis {self.axis!r} is a translation: give amplitude_m "
                             f"(not amplitude_deg)")
        return self

    @property
    def amplitude_si(self) -> float:
        """Amplitude in SI: metres or radians."""
        if self.axis in ANGLE_AXES:
            return math.radians(self.amplitude_deg)
        return float(self.amplitude_m)


class HoverJitterSection(_Section):
    """``[motion.hover_jitter]``: seeded stochastic hover jitter.

    ``seed`` defaults to the scenario ``seed``; ``scale`` multiplies every
    amplitude of :class:`raysim.platform.motion.HoverJitterSpec` (1 = typical small
    multirotor, 0 = none).
    """

    seed: int | None = Field(None, ge=0)
    scale: float = Field(1.0, ge=0)


class MotionSection(_Section):
    """``[motion]``: platform motion, the sum of every part given.

    ``case``: the motion of a paper case (the ``motion`` keys of
    ``raysim.scenario.paper_cases.PAPER_CASES[case]["scenario"]``);
    ``[[motion.sinusoids]]``: extra sinusoids; ``velocity_mps``: constant world
    velocity [m/s]; ``[motion.hover_jitter]``: stochastic jitter. Nothing given
    means a stationary platform.
    """

    case: str | None = None
    sinusoids: list[SinusoidSpec] = Field(default_factory=list)
    velocity_mps: Vec3 | None = None
    hover_jitter: HoverJitterSection | None = None

    @field_validator("case")
    @classmethod
    def _known_case(cls, v: str | None) -> str | None:
        if v is not None:
            if v not in PAPER_CASES:
                raise ValueError(f"a paper case name, one of {sorted(PAPER_CASES)}"
                                 f"{did_you_mean(v, PAPER_CASES)}")
        return v


# ------------------------------------------------------------------------- imu
class SensorErrorsSection(_Section):
    """One sensor triad of a custom IMU, SI units (see :class:`raysim.platform.imu.SensorErrors`).

    Gyroscope values in rad/s based units, accelerometer values in m/s^2 based
    units; ``full_scale`` may be omitted for no saturation.
    """

    noise_density: float = Field(0.0, ge=0)
    bias_sigma: float = Field(0.0, ge=0)
    bias_instability: float = Field(0.0, ge=0)
    bias_correlation_time: float = Field(100.0, gt=0)
    bias_random_walk: float = Field(0.0, ge=0)
    scale_factor_sigma: float = Field(0.0, ge=0)
    misalignment_sigma: float = Field(0.0, ge=0)
    resolution: float = Field(0.0, ge=0)
    full_scale: float | None = Field(None, gt=0)


class ImuSection(_Section):
    """``[imu]``: strapdown IMU sampling the truth motion.

    ``preset`` one of ``ideal``, ``tactical``, ``consumer_mems``
    (:data:`raysim.platform.imu.PRESETS`), or ``preset = "custom"`` with ``[imu.gyro]``
    and ``[imu.accel]`` tables. ``rate_hz`` is the output rate, ``seed`` the
    error draw (default: scenario ``seed + 1``), ``time_offset_s`` and
    ``clock_drift_ppm`` the IMU clock errors.
    """

    preset: Literal["ideal", "tactical", "consumer_mems", "custom"] = "ideal"
    rate_hz: float = Field(1000.0, gt=0)
    seed: int | None = Field(None, ge=0)
    time_offset_s: float = 0.0
    clock_drift_ppm: float = Field(0.0, gt=-1e5, lt=1e5)
    gyro: SensorErrorsSection | None = None
    accel: SensorErrorsSection | None = None

    @model_validator(mode="after")
    def _custom_tables(self) -> ImuSection:
        if self.preset != "custom" and (self.gyro is not None or self.accel is not None):
            raise ValueError(f"[imu.gyro] / [imu.accel] only apply to preset 'custom', "
                             f"not {self.preset!r}")
        return self


# ---------------------------------------------------------------------- output
class OutputSection(_Section):
    """``[output]``: where ``raysim render`` writes (relative to the working folder).

    ``store``: Zarr store (directory); ``netcdf``: optional NetCDF export;
    ``report``: optional HTML report.
    """

    store: str | None = None
    netcdf: str | None = None
    report: str | None = None


# -------------------------------------------------------------------- scenario
class Scenario(_Section):
    """A complete, validated simulation run.

    Attributes
    ----------
    name, description : str
    frames : int
        Frames rendered back to back (frame ``f`` starts at
        ``f * frame_interval``).
    seed : int
        Master seed: thermal noise of frame ``f`` uses ``seed + f``; the hover
        jitter and the IMU default to seeds derived from it.
    noise : bool
        Add thermal receiver noise.
    intra_chirp : bool
        Evaluate the geometry at every sample instead of stop-and-hop.
    lever_arm_m : tuple of float
        Radar phase centre in the body frame B [m].
    time_epoch_utc : str, optional
        UTC instant (ISO 8601) of time 0 of the truth clock, so stored frames
        align with a flight log; default the Unix epoch.
    radar, array, scene, motion, imu, output, synthesis : sections
    """

    name: str = "scenario"
    description: str = ""
    frames: int = Field(1, ge=1, le=100_000)
    seed: int = Field(0, ge=0)
    noise: bool = False
    intra_chirp: bool = False
    lever_arm_m: Vec3 = (0.0, 0.0, 0.10)
    time_epoch_utc: str | None = None

    @field_validator("time_epoch_utc")
    @classmethod
    def _utc_instant(cls, v: str | None) -> str | None:
        if v is None:
            return v
        from datetime import datetime

        try:
            when = datetime.fromisoformat(v.strip().replace("Z", "+00:00"))
        except ValueError:
            raise ValueError(f"expected an ISO 8601 UTC instant such as "
                             f"'2026-05-01T12:00:00Z', got {v!r}") from None
        if when.utcoffset() is not None and when.utcoffset().total_seconds() != 0:
            raise ValueError(f"expected a UTC instant (suffix Z), got {v!r}")
        return v.strip()
    radar: RadarSection = Field(default_factory=RadarSection)
    array: ArraySection = Field(default_factory=ArraySection)
    scene: SceneSection
    motion: MotionSection = Field(default_factory=MotionSection)
    imu: ImuSection = Field(default_factory=ImuSection)
    output: OutputSection = Field(default_factory=OutputSection)
    synthesis: SynthesisSection = Field(default_factory=SynthesisSection)

    @model_validator(mode="after")
    def _cross_checks(self, info: ValidationInfo) -> Scenario:
        # checks across sections, every problem at once (one line each)
        if not (info.context or {}).get("skip_cross_checks"):
            problems = [line for _, line in cross_problems(self)]
            if problems:
                raise ValueError("\n".join(problems))
        return self

    def fastest_motion(self) -> tuple[float, str]:
        """Highest frequency of the platform motion [Hz] and what it belongs to.

        Sinusoids (the paper case's and ``[[motion.sinusoids]]``) at their
        frequency; the hover jitter at the top of its rotor-vibration band (or of
        its attitude / position bands when the vibration is zero); a constant
        velocity has none. ``(0.0, "")`` for a platform without oscillation.
        """
        from raysim.platform.motion import HoverJitterSpec

        m = self.motion
        sines = list(m.sinusoids)
        if m.case is not None:
            case = get_case(m.case)["scenario"].get("motion", {})
            sines += [SinusoidSpec.model_validate(s) for s in case.get("sinusoids", [])]
        best = (0.0, "")
        for s in sines:
            if s.frequency_hz > best[0]:
                best = (s.frequency_hz, f"the {s.axis} sinusoid")
        if m.hover_jitter is not None and m.hover_jitter.scale > 0:
            d = HoverJitterSpec()
            if d.vibration_rms > 0:
                band = (d.vibration_band[1], "the hover jitter's rotor vibration band "
                        f"({d.vibration_band[0]:g}-{d.vibration_band[1]:g} Hz)")
            else:
                band = (max(d.attitude_band[1], d.position_band[1]), "the hover jitter")
            best = max(best, band)
        return best

    # ---------------------------------------------------------- conversions
    def radar_config(self):
        """The :class:`~raysim.radar.config.RadarConfig` (SI), TDM slots from the array."""
        from raysim.radar.config import RadarConfig

        r = self.radar
        slots = {"upa": 1, "ti_3tx4rx": 3,
                 "custom": len(self.array.tx_positions_m or [0])}[self.array.kind]
        return RadarConfig(
            carrier_frequency=r.carrier_frequency_hz, bandwidth=r.bandwidth_hz,
            chirp_duration=r.chirp_duration_s, idle_time=r.idle_time_s,
            sample_rate=r.sample_rate_hz, num_chirps=r.num_chirps, num_frames=self.frames,
            complex_sampling=r.complex_sampling, tx_power_dbm=r.tx_power_dbm,
            antenna_gain_dbi=r.element_gain_dbi, noise_figure_db=r.noise_figure_db,
            frame_period=r.frame_period_s, num_tx_slots=slots,
            element_pattern=r.element_pattern)

    def virtual_array(self):
        """The :class:`~raysim.radar.arrays.VirtualArray` (positions in metres, frame A)."""
        from raysim.radar.arrays import tdm_mimo, ti_3tx4rx, upa

        a = self.array
        lam = self.radar_config().wavelength
        if a.kind == "upa":
            return upa(a.nx, a.ny, a.spacing_m, wavelength=lam)
        if a.kind == "ti_3tx4rx":
            return ti_3tx4rx(lam)
        return tdm_mimo(np.asarray(a.tx_positions_m), np.asarray(a.rx_positions_m),
                        name="custom TDM MIMO")

    @property
    def lever_arm(self) -> np.ndarray:
        """Radar phase centre in B, shape ``[3]`` [m]."""
        return np.asarray(self.lever_arm_m, dtype=float)

    def trajectory(self):
        """Platform motion as a :class:`~raysim.platform.motion.Trajectory` (SI, radians)."""
        from raysim.platform.motion import (
            HoverJitterSpec,
            Sinusoid,
            Trajectory,
            constant_velocity,
            hover_jitter,
            stationary,
        )

        def sines(specs: list[SinusoidSpec]) -> Trajectory:
            comps = tuple(Sinusoid(s.axis, s.amplitude_si, s.frequency_hz,
                                   math.radians(s.phase_deg)) for s in specs)
            return Trajectory(comps, name=", ".join(c.label for c in comps))

        m = self.motion
        parts: list[Trajectory] = []
        if m.case is not None:
            case = MotionSection.model_validate(get_case(m.case)["scenario"].get("motion", {}))
            parts.append(sines(case.sinusoids) if case.sinusoids
                         else stationary())
        if m.sinusoids:
            parts.append(sines(m.sinusoids))
        if m.velocity_mps is not None:
            parts.append(constant_velocity(np.asarray(m.velocity_mps)))
        if m.hover_jitter is not None and m.hover_jitter.scale > 0:
            k = m.hover_jitter.scale
            d = HoverJitterSpec()
            spec = HoverJitterSpec(
                attitude_rms=tuple(k * v for v in d.attitude_rms),
                position_rms=tuple(k * v for v in d.position_rms),
                vibration_rms=k * d.vibration_rms)
            seed = self.seed if m.hover_jitter.seed is None else m.hover_jitter.seed
            parts.append(hover_jitter(seed, spec))
        if not parts:
            return stationary()
        traj = parts[0]
        for p in parts[1:]:
            traj = traj + p
        return traj

    def imu_spec(self):
        """The :class:`raysim.platform.imu.ImuSpec` (requires :mod:`raysim.platform.imu`)."""
        from raysim.platform.imu import ImuSpec, SensorErrors, get_preset

        if self.imu.preset != "custom":
            return get_preset(self.imu.preset)

        def errors(s: SensorErrorsSection | None) -> SensorErrors:
            if s is None:
                return SensorErrors()
            d = s.model_dump()
            d["full_scale"] = math.inf if d["full_scale"] is None else d["full_scale"]
            return SensorErrors(**d)

        return ImuSpec("custom", errors(self.imu.gyro), errors(self.imu.accel),
                       source="scenario file")

    @property
    def imu_seed(self) -> int:
        """Seed of the IMU error draws (``imu.seed`` or ``seed + 1``)."""
        return self.seed + 1 if self.imu.seed is None else self.imu.seed

    def time_span(self) -> tuple[float, float]:
        """Truth-time interval ``[start, end]`` [s] covered by all frames' chirps."""
        cfg = self.radar_config()
        end = (self.frames - 1) * cfg.frame_interval + cfg.frame_duration
        return 0.0, float(end)

    # ------------------------------------------------------------- helpers
    def to_dict(self) -> dict:
        """Plain-data form (JSON / TOML safe; ``None`` values dropped)."""
        return _drop_none(self.model_dump(mode="json"))

    def to_json(self) -> str:
        """Canonical JSON (sorted keys), used to key stores and sweep points."""
        return json.dumps(self.to_dict(), sort_keys=True, separators=(",", ":"))

    def to_toml(self) -> str:
        """TOML text that :func:`~raysim.scenario.reader.loads_scenario` reads back equal."""
        return dumps_toml(self.to_dict())

    def with_values(self, changes: dict[str, Any]) -> Scenario:
        """Copy with key paths changed, validated again.

        Parameters
        ----------
        changes : dict
            Key path (``"radar.num_chirps"``, ``"scene.targets.0.range_m"``) -> value.
        """
        data = self.model_dump(mode="json")
        for path, value in changes.items():
            set_key(data, path, value)
        return validate_scenario(data)


def _drop_none(obj):
    if isinstance(obj, dict):
        return {k: _drop_none(v) for k, v in obj.items() if v is not None}
    if isinstance(obj, list):
        return [_drop_none(v) for v in obj]
    return obj


# ------------------------------------------------------------------ loading
def cross_problems(s: Scenario) -> list[tuple[frozenset[str], str]]:
    """Problems that involve several sections of a scenario, every one of them.

    Returns ``(sections, line)`` pairs: the top-level keys the check reads and
    one message line naming the key, the value and what was expected. Checked:
    the radar's own consistency (``[radar]``, ``[array]``, ``frames``: bandwidth
    below the carrier, at least 2 samples, ...), a clutter polarisation other
    than VV only with a clutter field (``[radar]``, ``[scene]``) and the IMU rate against the
    fastest motion (``[motion]``, ``[imu]``: at least twice its frequency).
    """
    out = []
    try:
        s.radar_config()
    except ValueError as exc:
        out.append((frozenset({"radar", "array", "frames"}),
                    f"radar: inconsistent waveform: {exc}"))
    if s.radar.polarisation != "VV" and (s.scene.kind == "points"
                                          or s.scene.clutter.mode != "field"):
        out.append((frozenset({"radar", "scene"}),
                    f"radar.polarisation: got {s.radar.polarisation!r}, which sets the ground "
                    f"clutter field's channel: expected 'VV' or a ray-traced scene with "
                    f"[scene.clutter] mode = 'field'"))
    freq, what = s.fastest_motion()
    if freq > 0 and s.imu.rate_hz < 2.0 * freq:
        out.append((frozenset({"motion", "imu"}),
                    f"imu.rate_hz: got {s.imu.rate_hz:g} Hz, below the Nyquist rate of the "
                    f"motion: {what} at {freq:g} Hz needs imu.rate_hz >= {2.0 * freq:g} Hz"))
    return out


#: A stand-in scene for checking the other sections of a scenario whose scene is invalid.
_STAND_IN_SCENE = {"kind": "points", "targets": [{"range_m": 1.0}]}


def _cross_problems_of_valid_sections(data: dict, exc: ValidationError) -> list[str]:
    """Cross-section problems among the sections that validated on their own.

    Pydantic skips a model's own checks once one of its fields failed, so a
    file with a bad value in ``[scene]`` and an IMU rate below the motion's
    Nyquist rate would report only the first. The sections with errors are
    replaced by their defaults, the rest validated again without the
    cross-section checks, and the checks run that read only valid sections.
    """
    bad = {str(e["loc"][0]) for e in exc.errors() if e.get("loc")}
    if not bad:                     # only cross-section problems: already listed
        return []
    repaired = {k: v for k, v in data.items() if k not in bad}
    if "scene" in bad or "scene" not in repaired:
        repaired["scene"] = _STAND_IN_SCENE
    try:
        partial = Scenario.model_validate(repaired, context={"skip_cross_checks": True})
    except (ValidationError, ValueError):
        return []
    return [line for keys, line in cross_problems(partial) if not keys & bad]


def validate_scenario(data: dict, source: str = "scenario") -> Scenario:
    """Validate plain data (as parsed from TOML) into a :class:`Scenario`.

    Raises
    ------
    ValueError
        Listing every problem at once, one line each: the key path, the value
        and what was expected (each section's values and checks, and the
        checks across sections that read only valid sections).
    """
    if not isinstance(data, dict):
        raise ValueError(f"{source}: expected a table of keys, got {type(data).__name__}")
    try:
        return Scenario.model_validate(data)
    except ValidationError as exc:
        raise format_validation_error(
            exc, source, known_keys=_known_keys,
            extra_lines=_cross_problems_of_valid_sections(data, exc)) from None


def _known_keys(loc: tuple) -> list[str]:
    """Keys of the scenario table at ``loc`` (for "did you mean" on unknown keys)."""
    model: Any = Scenario
    for part in loc:
        if isinstance(part, int) or model is None:
            continue
        field = model.model_fields.get(str(part))
        if field is None:
            return []
        model = None
        for typ in (field.annotation, *getattr(field.annotation, "__args__", ())):
            typ = (getattr(typ, "__args__", (None,)) or (None,))[0] \
                if getattr(typ, "__origin__", None) is list else typ
            if isinstance(typ, type) and issubclass(typ, BaseModel):
                model = typ
                break
    return list(model.model_fields) if model is not None else []
