"""IMU error specifications and datasheet presets (``ideal``, ``tactical``, ``consumer_mems``).

:class:`SensorErrors` describes one triad (gyro or accelerometer), :class:`ImuSpec`
a whole IMU; the presets carry their datasheet sources (docs/imu.md). Datasheet
figures are converted with the named constants (``DEG``, ``SQRT_HOUR``,
``MILLI_G`` ...), e.g. an angle random walk of ``0.125 deg/sqrt(h)`` is
``0.125 * DEG / SQRT_HOUR`` rad/sqrt(s).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

__all__ = [
    "STANDARD_GRAVITY", "GRAVITY_W", "DEG", "HOUR", "SQRT_HOUR", "MILLI_G", "MICRO_G", "PPM",
    "FOOT", "SensorErrors", "ImuSpec", "IDEAL", "TACTICAL", "CONSUMER_MEMS", "PRESETS",
    "get_preset",
]


# ------------------------------------------------------------------ constants
#: Standard gravity [m/s^2] (docs/conventions.md), also the unit ``g`` of datasheets.
STANDARD_GRAVITY = 9.80665
#: Gravity in the world NED frame ``g_W`` [m/s^2], shape ``[3]``.
GRAVITY_W = np.array([0.0, 0.0, STANDARD_GRAVITY])
GRAVITY_W.setflags(write=False)

#: One degree [rad].
DEG = math.pi / 180.0
#: One hour [s].
HOUR = 3600.0
#: ``sqrt(1 h)`` [sqrt(s)]; ``x deg/sqrt(h) = x * DEG / SQRT_HOUR rad/sqrt(s)``.
SQRT_HOUR = 60.0
#: One milli-g [m/s^2].
MILLI_G = 1e-3 * STANDARD_GRAVITY
#: One micro-g [m/s^2].
MICRO_G = 1e-6 * STANDARD_GRAVITY
#: One part per million [1].
PPM = 1e-6
#: One international foot [m].
FOOT = 0.3048

# Peak of the Allan deviation of a first-order Gauss-Markov process, in units of
# its stationary standard deviation (reached at tau = 1.89 T_c).
_GM_ADEV_PEAK = 0.6173642830545976


def _check_nonneg(owner: str, name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value < 0.0:
        raise ValueError(f"{owner}.{name} must be a finite number >= 0, got {value!r}")
    return value


# -------------------------------------------------------------- specification
@dataclass(frozen=True)
class SensorErrors:
    """Error specification of one sensor triad (three identical axes).

    Units are those of the measured quantity ``u``: rad/s for a gyroscope,
    m/s^2 for an accelerometer. All ``*_sigma`` values are one-sigma spreads of
    quantities drawn once per run; datasheet "typical" (+-) figures are used as
    one sigma.

    Parameters
    ----------
    noise_density : float
        White-noise density ``N`` [u/sqrt(Hz)], equal to the angle random walk
        [rad/sqrt(s)] or velocity random walk [m/s/sqrt(s)]. The Allan deviation
        of the white part is ``N / sqrt(tau)``.
    bias_sigma : float
        Turn-on (run-to-run) bias, one sigma [u].
    bias_instability : float
        Bias instability [u]: the floor of the Allan deviation curve as quoted
        on datasheets. Modelled as a first-order Gauss-Markov process with
        correlation time ``bias_correlation_time`` whose Allan deviation peaks
        at this value.
    bias_correlation_time : float
        Correlation time ``T_c`` of the Gauss-Markov bias [s]; the Allan
        deviation of that process peaks at ``tau = 1.89 T_c``.
    bias_random_walk : float
        Bias random walk ``K`` [u sqrt(Hz)] = [u/sqrt(s)] (rate random walk for
        a gyroscope); Allan deviation ``K sqrt(tau / 3)``.
    scale_factor_sigma : float
        Scale-factor error per axis, one sigma [1] (``150 ppm = 150 * PPM``).
    misalignment_sigma : float
        Each off-diagonal term of the axis misalignment / non-orthogonality
        matrix, one sigma [rad] (equivalently the cross-axis sensitivity [1]).
    resolution : float
        Output quantisation step (LSB) [u]; 0 disables quantisation.
    full_scale : float
        Saturation limit ``|y| <= full_scale`` [u]; ``inf`` disables clipping.
    """

    noise_density: float = 0.0
    bias_sigma: float = 0.0
    bias_instability: float = 0.0
    bias_correlation_time: float = 100.0
    bias_random_walk: float = 0.0
    scale_factor_sigma: float = 0.0
    misalignment_sigma: float = 0.0
    resolution: float = 0.0
    full_scale: float = math.inf

    def __post_init__(self) -> None:
        for name in ("noise_density", "bias_sigma", "bias_instability", "bias_random_walk",
                     "scale_factor_sigma", "misalignment_sigma", "resolution"):
            object.__setattr__(self, name, _check_nonneg("SensorErrors", name,
                                                         getattr(self, name)))
        tc = float(self.bias_correlation_time)
        if not math.isfinite(tc) or tc <= 0.0:
            raise ValueError(
                f"SensorErrors.bias_correlation_time must be a finite positive number of "
                f"seconds, got {self.bias_correlation_time!r}")
        object.__setattr__(self, "bias_correlation_time", tc)
        fs = float(self.full_scale)
        if math.isnan(fs) or fs <= 0.0:
            raise ValueError(f"SensorErrors.full_scale must be > 0 (inf for none), got {fs!r}")
        object.__setattr__(self, "full_scale", fs)

    @property
    def gauss_markov_sigma(self) -> float:
        """Stationary standard deviation of the Gauss-Markov bias [u].

        ``bias_instability / 0.6174``: a first-order Gauss-Markov process of
        standard deviation ``sigma`` has a peak Allan deviation ``0.6174 sigma``.
        """
        return self.bias_instability / _GM_ADEV_PEAK

    def allan_deviation(self, tau, rate: float) -> np.ndarray:
        """Model Allan deviation of a stationary record [u].

        Parameters
        ----------
        tau : array_like, shape ``[tau]``
            Cluster times [s].
        rate : float
            Sample rate [Hz]; sets the quantisation-noise term.

        Returns
        -------
        ndarray, shape ``[tau]``
            ``sqrt(N^2/tau + AVAR_GM(tau) + K^2 tau/3 + q^2/(12 rate tau))``.

        Notes
        -----
        Gauss-Markov Allan variance with ``x = tau / T_c``:
        ``AVAR_GM = 2 sigma^2 / x [1 - (3 - 4 e^-x + e^-2x) / (2x)]``.
        """
        tau = np.asarray(tau, dtype=float)
        x = tau / self.bias_correlation_time
        sig2 = self.gauss_markov_sigma ** 2
        gm = 2.0 * sig2 / x * (1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x))
        avar = (self.noise_density ** 2 / tau + gm + self.bias_random_walk ** 2 * tau / 3.0
                + self.resolution ** 2 / (12.0 * rate * tau))
        return np.sqrt(avar)

    @property
    def is_ideal(self) -> bool:
        """True when the triad has no error term at all."""
        return (self.noise_density == 0 and self.bias_sigma == 0 and self.bias_instability == 0
                and self.bias_random_walk == 0 and self.scale_factor_sigma == 0
                and self.misalignment_sigma == 0 and self.resolution == 0
                and math.isinf(self.full_scale))


@dataclass(frozen=True)
class ImuSpec:
    """Error specification of a six-axis IMU.

    Parameters
    ----------
    name : str
        Short identifier (the preset name).
    gyro : SensorErrors
        Gyroscope triad, units rad/s.
    accel : SensorErrors
        Accelerometer triad, units m/s^2.
    source : str
        Where the figures come from (part numbers, datasheet values, assumptions).
    """

    name: str
    gyro: SensorErrors = field(default_factory=SensorErrors)
    accel: SensorErrors = field(default_factory=SensorErrors)
    source: str = ""

    def __post_init__(self) -> None:
        for name in ("gyro", "accel"):
            if not isinstance(getattr(self, name), SensorErrors):
                raise ValueError(f"ImuSpec.{name} must be a SensorErrors, "
                                 f"got {type(getattr(self, name)).__name__}")


# --------------------------------------------------------------------- presets
#: Error-free IMU: samples equal the truth angular rate and specific force.
IDEAL = ImuSpec("ideal", SensorErrors(), SensorErrors(), source="no errors")

#: Tactical-grade IMU, Honeywell HG1700 class (ring-laser gyros, AG58 grade).
#:
#: From the Honeywell HG1700 brochure (N61-1619-000-001), one sigma:
#: gyro bias (in-run stability and turn-on) 1 deg/h, angle random walk
#: 0.125 deg/sqrt(h), gyro scale factor 150 ppm; accelerometer bias 1 mg,
#: velocity random walk 0.065 ft/s/sqrt(h), accelerometer scale factor 300 ppm.
#: Assumed (not on the brochure): Gauss-Markov correlation time 300 s,
#: accelerometer bias instability 0.05 mg, axis misalignment 0.5 mrad per term,
#: no quantisation (output LSB far below the noise), no saturation.
TACTICAL = ImuSpec(
    "tactical",
    gyro=SensorErrors(
        noise_density=0.125 * DEG / SQRT_HOUR,          # 0.125 deg/sqrt(h) -> rad/sqrt(s)
        bias_sigma=1.0 * DEG / HOUR,                    # 1 deg/h -> rad/s
        bias_instability=1.0 * DEG / HOUR,              # 1 deg/h -> rad/s
        bias_correlation_time=300.0,
        scale_factor_sigma=150.0 * PPM,
        misalignment_sigma=0.5e-3,
    ),
    accel=SensorErrors(
        noise_density=0.065 * FOOT / SQRT_HOUR,         # 0.065 ft/s/sqrt(h) -> m/s/sqrt(s)
        bias_sigma=1.0 * MILLI_G,                       # 1 mg -> m/s^2
        bias_instability=0.05 * MILLI_G,                # assumed
        bias_correlation_time=300.0,
        scale_factor_sigma=300.0 * PPM,
        misalignment_sigma=0.5e-3,
    ),
    source=("Honeywell HG1700 (AG58) brochure: gyro bias 1 deg/h, ARW 0.125 deg/sqrt(h), "
            "SF 150 ppm; accel bias 1 mg, VRW 0.065 ft/s/sqrt(h), SF 300 ppm. Assumed: "
            "T_c 300 s, accel bias instability 0.05 mg, misalignment 0.5 mrad."),
)

#: Consumer MEMS IMU as flown on small drones (Bosch BMI088 / InvenSense ICM-42688-P).
#:
#: Datasheet figures (typical values used as one sigma):
#: gyro rate noise density 0.014 deg/s/sqrt(Hz) and bias stability 2 deg/h
#: (Bosch BMI088, BST-BMI088-DS001); gyro zero-rate offset 0.5 deg/s
#: (ICM-42688-P); gyro full scale +-2000 deg/s on 16 bit, i.e. 2000/32767 deg/s
#: per LSB (BMI088); accelerometer noise density 160 ug/sqrt(Hz) (BMI088, upper
#: end of the 70-160 ug/sqrt(Hz) class range, ICM-42688-P being 70); accel
#: zero-g offset 20 mg (both parts); accel range +-6 g on 16 bit (BMI088 range
#: setting), i.e. 6 g / 32768 per LSB; sensitivity tolerance 1 % and cross-axis
#: sensitivity 1 % (order of both datasheets).
#: Assumed: accelerometer bias instability 0.05 mg (Allan floor typical of this
#: class, e.g. 0.03 mg on the Xsens MTi-1), Gauss-Markov correlation time 100 s.
CONSUMER_MEMS = ImuSpec(
    "consumer_mems",
    gyro=SensorErrors(
        noise_density=0.014 * DEG,                      # 0.014 deg/s/sqrt(Hz) -> rad/s/sqrt(Hz)
        bias_sigma=0.5 * DEG,                           # 0.5 deg/s -> rad/s
        bias_instability=2.0 * DEG / HOUR,              # 2 deg/h -> rad/s
        bias_correlation_time=100.0,
        scale_factor_sigma=0.01,                        # 1 %
        misalignment_sigma=0.01,                        # 1 % cross-axis sensitivity
        resolution=2000.0 / 32767.0 * DEG,              # 16 bit over +-2000 deg/s
        full_scale=2000.0 * DEG,
    ),
    accel=SensorErrors(
        noise_density=160.0 * MICRO_G,                  # 160 ug/sqrt(Hz) -> m/s^2/sqrt(Hz)
        bias_sigma=20.0 * MILLI_G,                      # 20 mg -> m/s^2
        bias_instability=0.05 * MILLI_G,                # assumed
        bias_correlation_time=100.0,
        scale_factor_sigma=0.01,
        misalignment_sigma=0.01,
        resolution=6.0 * STANDARD_GRAVITY / 32768.0,    # 16 bit over +-6 g
        full_scale=6.0 * STANDARD_GRAVITY,
    ),
    source=("Bosch BMI088: gyro 0.014 deg/s/sqrt(Hz), bias stability 2 deg/h, +-2000 deg/s "
            "16 bit; accel 160 ug/sqrt(Hz), offset 20 mg, +-6 g 16 bit. InvenSense "
            "ICM-42688-P: gyro offset 0.5 deg/s. Sensitivity and cross-axis 1 %. Assumed: "
            "accel bias instability 0.05 mg, T_c 100 s."),
)

#: Presets by name (read-only).
PRESETS = MappingProxyType({spec.name: spec for spec in (IDEAL, TACTICAL, CONSUMER_MEMS)})


def get_preset(name: str) -> ImuSpec:
    """Return the preset called ``name`` (one of ``PRESETS``).

    Raises
    ------
    ValueError
        If ``name`` is not a preset name.
    """
    try:
        return PRESETS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown IMU preset {name!r}; valid presets are {sorted(PRESETS)}") from None


def _resolve_spec(spec: ImuSpec | str) -> ImuSpec:
    if isinstance(spec, ImuSpec):
        return spec
    if isinstance(spec, str):
        return get_preset(spec)
    raise ValueError(f"spec must be an ImuSpec or a preset name in {sorted(PRESETS)}, "
                     f"got {spec!r}")


