"""Six-degree-of-freedom platform motion with analytic derivatives.

A :class:`Trajectory` is a sum of per-axis components (sinusoids, ramps). Each
axis is one of ``x, y, z`` (body-origin position in the world NED frame W [m])
or ``roll, pitch, yaw`` (Euler Z-Y-X angles [rad]). Because every component
has closed-form first and second derivatives, body angular rate and
acceleration are exact (no finite differences), which the IMU simulation and
the tests rely on.

Attitude ``R_WB = Rz(yaw) Ry(pitch) Rx(roll)`` maps body (FRD) vectors to world
(NED), ``scipy.spatial.transform.Rotation.from_euler("ZYX", [yaw, pitch, roll])``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

#: Axis names in the order of the internal state vector.
AXES = ("x", "y", "z", "roll", "pitch", "yaw")
#: Axes whose values are angles [rad] (labelled in degrees).
ROTATION_AXES = ("roll", "pitch", "yaw")
_AXIS_INDEX = {name: i for i, name in enumerate(AXES)}


def _axis_index(axis: str) -> int:
    try:
        return _AXIS_INDEX[axis]
    except KeyError:
        raise ValueError(f"axis must be one of {AXES}, got {axis!r}") from None


@dataclass(frozen=True)
class Sinusoid:
    """``q(t) = amplitude * sin(2 pi frequency t + phase)`` on one axis.

    ``amplitude`` is in metres for x/y/z and radians for roll/pitch/yaw;
    ``frequency`` in Hz, ``phase`` in rad.
    """

    axis: str
    amplitude: float
    frequency: float
    phase: float = 0.0

    def __post_init__(self) -> None:
        _axis_index(self.axis)
        if not math.isfinite(self.amplitude):
            raise ValueError(f"amplitude must be finite, got {self.amplitude!r}")
        if not math.isfinite(self.frequency) or self.frequency < 0:
            raise ValueError(f"frequency must be >= 0 Hz, got {self.frequency!r}")

    @property
    def label(self) -> str:
        """``pitch 10 deg @ 20 Hz`` or ``z 0.05 m @ 5 Hz`` (see :func:`sinusoid_label`)."""
        return sinusoid_label(self.axis, self.amplitude, self.frequency)

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Value, first and second time derivative at times ``t`` [s]."""
        w = 2.0 * np.pi * self.frequency
        arg = w * t + self.phase
        s, c = np.sin(arg), np.cos(arg)
        a = self.amplitude
        return a * s, a * w * c, -a * w * w * s


@dataclass(frozen=True)
class Ramp:
    """``q(t) = offset + rate * t + 0.5 * accel * t**2`` on one axis."""

    axis: str
    offset: float = 0.0
    rate: float = 0.0
    accel: float = 0.0

    def __post_init__(self) -> None:
        _axis_index(self.axis)
        for name in ("offset", "rate", "accel"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")

    def evaluate(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Value, first and second time derivative at times ``t`` [s]."""
        return (self.offset + self.rate * t + 0.5 * self.accel * t * t,
                self.rate + self.accel * t, np.full_like(t, self.accel))


@dataclass(frozen=True)
class Trajectory:
    """Body pose over time as a sum of axis components.

    Parameters
    ----------
    components : tuple of Sinusoid or Ramp
        Contributions, summed per axis.
    name : str
        Label used in reports.
    """

    components: tuple = field(default_factory=tuple)
    name: str = "trajectory"

    def __post_init__(self) -> None:
        object.__setattr__(self, "components", tuple(self.components))
        for comp in self.components:
            if not hasattr(comp, "evaluate") or not hasattr(comp, "axis"):
                raise ValueError(f"trajectory component {comp!r} is not a Sinusoid or Ramp")

    def __add__(self, other: Trajectory) -> Trajectory:
        return Trajectory(self.components + other.components, f"{self.name} + {other.name}")

    def states(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Axis values and derivatives.

        Parameters
        ----------
        t : array_like, shape ``[time]``
            Times [s].

        Returns
        -------
        q, qd, qdd : ndarray, shape ``[time, 6]``
            Value, rate and second derivative of ``(x, y, z, roll, pitch, yaw)``
            in m, m/s, m/s^2 and rad, rad/s, rad/s^2.
        """
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if not np.all(np.isfinite(t)):
            raise ValueError("trajectory times must be finite")
        q = np.zeros(t.shape + (6,))
        qd = np.zeros_like(q)
        qdd = np.zeros_like(q)
        for comp in self.components:
            i = _AXIS_INDEX[comp.axis]
            v, d, dd = comp.evaluate(t)
            q[..., i] += v
            qd[..., i] += d
            qdd[..., i] += dd
        return q, qd, qdd

    # -------------------------------------------------------------- kinematics
    def position(self, t) -> np.ndarray:
        """Body-origin position in W, shape ``[time, 3]`` [m]."""
        return self.states(t)[0][..., :3]

    def velocity(self, t) -> np.ndarray:
        """Body-origin velocity in W, shape ``[time, 3]`` [m/s]."""
        return self.states(t)[1][..., :3]

    def acceleration(self, t) -> np.ndarray:
        """Body-origin acceleration in W, shape ``[time, 3]`` [m/s^2]."""
        return self.states(t)[2][..., :3]

    def euler(self, t) -> np.ndarray:
        """Euler angles ``(yaw, pitch, roll)`` (scipy ``"ZYX"``), shape ``[time, 3]`` [rad]."""
        q = self.states(t)[0]
        return q[..., [5, 4, 3]]

    def attitude(self, t) -> Rotation:
        """Attitude ``R_WB`` (body to world) at each time, a Rotation of length ``time``."""
        return Rotation.from_euler("ZYX", self.euler(t))

    def angular_rate(self, t) -> np.ndarray:
        """Body angular rate ``omega_B`` (what a gyroscope measures), shape ``[time, 3]`` [rad/s].

        From the Z-Y-X Euler rates:
        ``omega_B = [phid - psid s_th, thd c_ph + psid s_ph c_th, -thd s_ph + psid c_ph c_th]``.
        """
        q, qd, _ = self.states(t)
        phi, th = q[..., 3], q[..., 4]
        phid, thd, psid = qd[..., 3], qd[..., 4], qd[..., 5]
        sp, cp, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
        return np.stack([phid - psid * st, thd * cp + psid * sp * ct, -thd * sp + psid * cp * ct],
                        axis=-1)

    def pose(self, t) -> tuple[np.ndarray, Rotation]:
        """Position ``T`` [time, 3] (m, in W) and attitude ``R_WB`` at times ``t``."""
        q = self.states(t)[0]
        return q[..., :3], Rotation.from_euler("ZYX", q[..., [5, 4, 3]])

    def point_world(self, t, body_point: np.ndarray) -> np.ndarray:
        """World position of body-fixed points ``x = T + R b``.

        Parameters
        ----------
        t : array_like, shape ``[time]``
        body_point : ndarray, shape ``[point, 3]`` or ``[3]``
            Points in B [m].

        Returns
        -------
        ndarray, shape ``[time, point, 3]`` [m]
        """
        pos, rot = self.pose(t)
        b = np.atleast_2d(np.asarray(body_point, dtype=float))
        mats = rot.as_matrix()  # [time, 3, 3]
        return pos[:, None, :] + np.einsum("tij,pj->tpi", mats, b)


def stationary() -> Trajectory:
    """A platform at rest at the nominal hover point."""
    return Trajectory((), name="stationary")


def sinusoid_label(axis: str, amplitude: float, frequency: float) -> str:
    """The one label of a sinusoid in every command, store and report.

    Parameters
    ----------
    axis : str
        One of :data:`AXES`.
    amplitude : float
        Amplitude in SI units: rad for roll/pitch/yaw, m for x/y/z.
    frequency : float
        [Hz].

    Returns
    -------
    str
        ``"pitch 10 deg @ 20 Hz"`` (rotations, amplitude converted to degrees)
        or ``"z 0.05 m @ 5 Hz"`` (translations); numbers with 4 significant
        digits (``:.4g``).
    """
    _axis_index(axis)
    if axis in ROTATION_AXES:
        return f"{axis} {math.degrees(amplitude):.4g} deg @ {frequency:.4g} Hz"
    return f"{axis} {amplitude:.4g} m @ {frequency:.4g} Hz"


def sinusoid(axis: str, amplitude: float, frequency: float, phase: float = 0.0) -> Trajectory:
    """Single-axis sinusoidal motion (amplitude in m or rad), named by :func:`sinusoid_label`."""
    comp = Sinusoid(axis, amplitude, frequency, phase)
    return Trajectory((comp,), name=comp.label)


def constant_velocity(velocity: np.ndarray) -> Trajectory:
    """Translation at a constant world velocity [m/s] from the hover point."""
    v = np.asarray(velocity, dtype=float).reshape(3)
    return Trajectory(tuple(Ramp(a, 0.0, float(r)) for a, r in zip("xyz", v, strict=True)),
                      name=f"constant velocity {v.tolist()} m/s")


@dataclass(frozen=True)
class HoverJitterSpec:
    """Amplitudes and bands of stochastic hover jitter of a small multirotor.

    Defaults follow typical logs of 1-3 kg quadrotors holding position with GNSS
    in light wind: about 1 deg RMS roll/pitch and 0.5 deg yaw in the attitude
    loop band (0.5-8 Hz), about 3 cm RMS horizontal and 2 cm vertical position
    wander (0.05-2 Hz), plus frame vibration from the rotors (0.02 deg RMS at
    80-160 Hz).
    """

    attitude_rms: tuple[float, float, float] = (np.deg2rad(1.0), np.deg2rad(1.0),
                                                np.deg2rad(0.5))
    attitude_band: tuple[float, float] = (0.5, 8.0)
    position_rms: tuple[float, float, float] = (0.03, 0.03, 0.02)
    position_band: tuple[float, float] = (0.05, 2.0)
    vibration_rms: float = np.deg2rad(0.02)
    vibration_band: tuple[float, float] = (80.0, 160.0)
    tones_per_axis: int = 24


def hover_jitter(seed: int, spec: HoverJitterSpec | None = None) -> Trajectory:
    """Seeded stochastic hover jitter as a sum of random-phase tones.

    Each axis gets ``tones_per_axis`` sinusoids with log-uniform frequencies in
    its band, Rayleigh-distributed weights and uniform phases, scaled so the
    axis RMS equals the spec (a sum of tones of amplitude ``a_i`` has RMS
    ``sqrt(sum a_i^2 / 2)``). Derivatives stay analytic.
    """
    spec = HoverJitterSpec() if spec is None else spec
    if spec.tones_per_axis < 1:
        raise ValueError(f"tones_per_axis must be >= 1, got {spec.tones_per_axis}")
    rng = np.random.default_rng(seed)
    comps: list[Sinusoid] = []

    def add(axis: str, rms: float, band: tuple[float, float]) -> None:
        lo, hi = band
        if not (0 < lo < hi):
            raise ValueError(f"band for {axis} must satisfy 0 < low < high, got {band}")
        n = spec.tones_per_axis
        f = np.exp(rng.uniform(np.log(lo), np.log(hi), n))
        w = rng.rayleigh(1.0, n)
        a = w * rms * np.sqrt(2.0 / np.sum(w**2))
        ph = rng.uniform(0, 2 * np.pi, n)
        comps.extend(Sinusoid(axis, float(ai), float(fi), float(pi))
                     for ai, fi, pi in zip(a, f, ph, strict=True))

    for axis, rms in zip(("roll", "pitch", "yaw"), spec.attitude_rms, strict=True):
        add(axis, rms, spec.attitude_band)
        if spec.vibration_rms > 0:
            add(axis, spec.vibration_rms, spec.vibration_band)
    for axis, rms in zip("xyz", spec.position_rms, strict=True):
        add(axis, rms, spec.position_band)
    return Trajectory(tuple(comps), name=f"hover jitter (seed {seed})")
