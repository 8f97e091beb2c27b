"""The stability maps: which point parameters each map sweeps and how a point is built.

Every point is one static target seen by the paper's radar (256 chirps unless
the map varies it, the paper's constant-gain elements as in its cases:
:data:`ELEMENT_PATTERN`) and 20 x 20 half-wavelength virtual UPA, lever arm
``(0, 0, 0.10)`` m, target at 15 m (:class:`StabilityPoint` defaults). The
``dpca_displacement`` map varies the array and adds a second scatterer inside
the target's beam (clutter in a beam), comparing ``dpca`` with ``exact``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from raysim.platform.motion import HoverJitterSpec, hover_jitter, sinusoid
from raysim.radar.arrays import VirtualArray, upa
from raysim.radar.config import RadarConfig
from raysim.studies.stability.point import INITS, StabilityPoint

__all__ = ["MapSpec", "MAPS", "IMU_TERMS", "INT_AXES", "DPCA_CHAINS", "tick_labels",
           "companion_offset_deg"]

#: Consumer-MEMS error terms of the ``imu_grade`` map (``term_index`` axis).
IMU_TERMS = ("noise", "bias", "bias_instability", "scale_factor", "misalignment")
#: Axes whose values are integers (passed to the builders as int).
INT_AXES = ("num_chirps", "term_index", "error_axis_index", "init_index", "array_size")
#: Element pattern of the maps' radar: the paper names none, and its cases
#: (``raysim/scenario/cases/_paper.toml``) take the same gain in every direction, so
#: a map point and the same paper case in ``raysim simulate`` measure alike.
ELEMENT_PATTERN = "constant"
#: Chains of the ``dpca_displacement`` map.
DPCA_CHAINS = ("none", "exact", "dpca")


@dataclass(frozen=True)
class MapSpec:
    """A stability map: point builder and the axes swept.

    Attributes
    ----------
    name : str
    title : str
    axes : tuple of (name, unit, values, quick_values)
        One or two swept parameters; values in the unit named (deg, Hz, ...).
    build : callable
        ``build(**{axis: value}, seed=int) -> StabilityPoint``.
    seeds : int
        Seeds per point (full run); ``quick_seeds`` in quick mode.
    log_axes : tuple of str
        Axes drawn on a log scale.
    note : str
    chains : tuple of str or None
        Chains of the map (None: :data:`~raysim.studies.stability.metrics.MAP_CHAINS`).
    """

    name: str
    title: str
    axes: tuple
    build: Callable
    seeds: int = 1
    quick_seeds: int = 1
    log_axes: tuple = ()
    note: str = ""
    chains: tuple | None = None


def tick_labels(axis: str, values) -> list[str]:
    """Tick labels of a map axis (names for the index axes, ``%g`` otherwise)."""
    names = {"init_index": INITS, "term_index": IMU_TERMS, "error_axis_index": ("X", "Y", "Z")}
    if axis in names:
        return [names[axis][int(v)] for v in values]
    return [f"{v:g}" for v in values]


def _radar(num_chirps: int = 256) -> RadarConfig:
    return RadarConfig(num_chirps=int(num_chirps), element_pattern=ELEMENT_PATTERN)


def _array(cfg: RadarConfig) -> VirtualArray:
    return upa(20, 20, wavelength=cfg.wavelength)


_R = _radar()
_A = _array(_R)


def _b_rotation_angle(*, rotation_deg, target_deg, seed, axis="pitch"):
    tgt = {"target_az_deg": float(target_deg)} if axis == "pitch" else \
        {"target_el_deg": float(target_deg)}
    return StabilityPoint(_R, _A, sinusoid(axis, np.deg2rad(rotation_deg), 20.0), 15.0,
                          seed=seed, **tgt)


def _b_freq_chirps(*, frequency_hz, num_chirps, seed):
    cfg = _radar(num_chirps)
    return StabilityPoint(cfg, _A, sinusoid("pitch", np.deg2rad(10.0), frequency_hz), 15.0, 20.0,
                          seed=seed)


def _rot_y_case(seed, **kw):
    return StabilityPoint(_R, _A, sinusoid("pitch", np.deg2rad(10.0), 20.0), 15.0, 20.0,
                          seed=seed, **kw)


def _imu_term(term: str, scale: float):
    """Consumer-MEMS IMU with only one error term, scaled by ``scale``."""
    from raysim.platform.imu import CONSUMER_MEMS, ImuSpec, SensorErrors

    def one(e):
        kw = {"bias_correlation_time": e.bias_correlation_time}
        if term == "noise":
            kw["noise_density"] = e.noise_density * scale
        elif term == "bias":
            kw["bias_sigma"] = e.bias_sigma * scale
        elif term == "bias_instability":
            kw["bias_instability"] = e.bias_instability * scale
        elif term == "scale_factor":
            kw["scale_factor_sigma"] = e.scale_factor_sigma * scale
        elif term == "misalignment":
            kw["misalignment_sigma"] = e.misalignment_sigma * scale
        else:
            raise ValueError(f"IMU error term: got {term!r}, expected one of {list(IMU_TERMS)}")
        return SensorErrors(**kw)

    return ImuSpec(f"consumer_mems {term} x{scale:g}", one(CONSUMER_MEMS.gyro),
                   one(CONSUMER_MEMS.accel))


def _b_imu_grade(*, term_index, scale, seed):
    # pitch 10 deg at 20 Hz and Z 5 cm at 5 Hz together: gyro and accelerometer both matter
    traj = sinusoid("pitch", np.deg2rad(10.0), 20.0) + sinusoid("z", 0.05, 5.0)
    return StabilityPoint(_R, _A, traj, 15.0, 20.0, 10.0,
                          imu_spec=_imu_term(IMU_TERMS[int(term_index)], scale), seed=seed)


def _b_imu_rate(*, imu_rate_hz, frequency_hz, seed):
    return StabilityPoint(_R, _A, sinusoid("pitch", np.deg2rad(10.0), frequency_hz), 15.0, 20.0,
                          imu_rate_hz=imu_rate_hz, seed=seed)


def _b_clock(*, time_offset_ms, clock_drift_ppm, seed):
    return _rot_y_case(seed, imu_time_offset_s=time_offset_ms * 1e-3,
                       imu_clock_drift_ppm=clock_drift_ppm, t0_s=0.5)


def _b_lever(*, lever_error_cm, error_axis_index, seed):
    err = np.zeros(3)
    err[int(error_axis_index)] = lever_error_cm * 1e-2
    return _rot_y_case(seed, lever_arm_error_m=err)


def _b_jitter(*, jitter_scale, init_index, seed):
    base = HoverJitterSpec()
    spec = replace(base, attitude_rms=tuple(a * jitter_scale for a in base.attitude_rms),
                   position_rms=tuple(p * jitter_scale for p in base.position_rms),
                   vibration_rms=base.vibration_rms * jitter_scale)
    return StabilityPoint(_R, _A, hover_jitter(seed, spec), 15.0, 20.0, 10.0,
                          init=INITS[int(init_index)], t0_s=1.0 + 0.37 * seed, seed=seed)


def companion_offset_deg(array_size: int) -> float:
    """Azimuth offset of the ``dpca_displacement`` map's second scatterer [deg].

    Half the boresight 3 dB beamwidth ``0.886 lambda / (n d)`` of an ``n``-element
    half-wavelength axis (``d = lambda / 2`` in the one-way virtual
    coordinates), i.e. ``0.886 / n`` rad: inside the target's beam for every array.
    """
    return float(np.rad2deg(0.886 / int(array_size)))


def _b_dpca(*, displacement_mm, array_size, seed):
    # horizontal (x) sinusoid at 20 Hz: over the 15 ms frame the radar moves by about
    # the amplitude; a -6 dB scatterer half a beamwidth off the target shares its beam
    arr = upa(int(array_size), int(array_size), wavelength=_R.wavelength)
    return StabilityPoint(_R, arr, sinusoid("x", displacement_mm * 1e-3, 20.0), 15.0, 20.0,
                          companion_az_deg=companion_offset_deg(array_size), seed=seed)


MAPS: dict[str, MapSpec] = {m.name: m for m in (
    MapSpec("rotation_azimuth", "pitch amplitude (20 Hz) x target azimuth",
            (("rotation_deg", "deg", (1, 2, 5, 10, 15, 20, 30), (2, 10, 30)),
             ("target_deg", "deg", (0, 10, 20, 30, 40, 50, 60), (0, 30, 60))),
            _b_rotation_angle,
            note="small-angle spatial correction vs target azimuth; lever arm 10 cm"),
    MapSpec("rotation_elevation", "roll amplitude (20 Hz) x target elevation",
            (("rotation_deg", "deg", (1, 2, 5, 10, 15, 20, 30), (2, 10, 30)),
             ("target_deg", "deg", (0, 10, 20, 30, 40, 50, 60), (0, 30, 60))),
            lambda **kw: _b_rotation_angle(axis="roll", **kw)),
    MapSpec("frequency_chirps", "pitch 10 deg: motion frequency x chirps per frame",
            (("frequency_hz", "Hz", (1, 2, 5, 10, 20, 40), (2, 20)),
             ("num_chirps", "", (64, 128, 256, 512, 1024), (128, 512))),
            _b_freq_chirps, log_axes=("frequency_hz", "num_chirps"),
            note="paper:published (v_r(nT) nT phase) vs paper (integrated phase)"),
    MapSpec("imu_grade", "consumer-MEMS error terms, one at a time, scaled",
            (("term_index", "", tuple(range(len(IMU_TERMS))), tuple(range(len(IMU_TERMS)))),
             ("scale", "x consumer", (1, 10, 100, 1000, 10000), (1, 100, 10000))),
            _b_imu_grade, seeds=3, quick_seeds=1, log_axes=("scale",),
            note="terms: " + ", ".join(f"{i}={t}" for i, t in enumerate(IMU_TERMS))),
    MapSpec("imu_rate", "IMU rate x motion frequency (pitch 10 deg)",
            (("imu_rate_hz", "Hz", (50, 100, 200, 400, 1000, 2000), (50, 400)),
             ("frequency_hz", "Hz", (2, 5, 10, 20, 40), (10, 40))),
            _b_imu_rate, log_axes=("imu_rate_hz", "frequency_hz")),
    MapSpec("clock", "IMU-radar time offset x clock drift (rotation_y case)",
            (("time_offset_ms", "ms", (0, 0.05, 0.1, 0.2, 0.5, 1, 2), (0, 0.2, 2)),
             ("clock_drift_ppm", "ppm", (0, 100, 1000, 10000), (0, 10000))),
            _b_clock, note="frame starts at t0 = 0.5 s, so drift acts as an extra offset"),
    MapSpec("lever_arm", "lever-arm error x error axis (rotation_y case)",
            (("lever_error_cm", "cm", (0, 0.5, 1, 2, 5, 10, 20), (0, 2, 20)),
             ("error_axis_index", "", (0, 1, 2), (0, 2))),
            _b_lever, note="axis 0=X (forward), 1=Y (right), 2=Z (down); true arm 10 cm on Z"),
    MapSpec("hover_jitter", "hover jitter level x initial state",
            (("jitter_scale", "x default", (0.5, 1, 2, 4, 8), (1, 4)),
             ("init_index", "", (0, 1), (0, 1))),
            _b_jitter, seeds=6, quick_seeds=2, log_axes=("jitter_scale",),
            note="init 0=truth (aligned), 1=hover (nominal attitude, zero-mean velocity); "
                 "default jitter: 1 deg RMS roll/pitch, 3 cm RMS horizontal"),
    MapSpec("dpca_displacement", "horizontal displacement (x, 20 Hz) x array size, two "
            "scatterers in one beam",
            (("displacement_mm", "mm", (0.25, 0.5, 1, 2, 4, 8), (0.5, 4)),
             ("array_size", "", (8, 12, 16, 20), (8, 16))),
            _b_dpca, log_axes=("displacement_mm",), chains=DPCA_CHAINS,
            note="target 15 m, az 20 deg plus a -6 dB scatterer half a beamwidth off in "
                 "azimuth; exact leaves the pair's relative phase (small pseudo-velocity, "
                 "Doppler width below the stationary 1.44 bins), dpca restores it; dpca "
                 "fails (NaN) where the displacement exceeds the spare aperture"),
)}
