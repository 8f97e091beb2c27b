r"""Rotating parts (a fan, a rotor): blades of point scatterers that spin about a hub.

Each blade is a line of point scatterers that turns rigidly about the spin axis
``n`` through the hub ``h(t)`` (fixed in W or riding on a
:class:`raysim.echoes.moving.scatterers.RigidTrajectory`):

.. math::

    p_{b,k}(t) = h(t) + R\bigl(n, \Omega (t - t_0) + \varphi_0 + 2 \pi b / N_b\bigr)\, d_k e_1

with ``R(n, theta)`` the right-handed rotation about ``n``, ``e_1`` the reference
direction in the rotor plane and ``d_k`` the scatterers' distances from the hub,
evenly spaced out to the tip. A scatterer at distance ``r`` seen at the angle
``beta`` between the line of sight and the rotor plane has the sinusoidal
micro-Doppler ``f_D(t) = (2 Omega r cos(beta) / lambda) sin(Omega t + phi)``
(Chen, *The Micro-Doppler Effect in Radar*, 2nd ed., Artech House 2019, ch. 4,
rotor blades). The scatterers of a blade keep one scattering phase, so their
coherent sum flashes when the blade lies across the line of sight (Chen's
``sinc`` blade model): a blade is sampled at most ``lambda / 4`` apart by
default so that the discrete line has no grating flashes at other aspects.

Sampling, as the radar has it (both physical, nothing is warned):

* **Aliasing.** The micro-Doppler reaches ``2 Omega r_tip / lambda``
  (:meth:`Rotor.max_doppler`); the slow time is sampled every ``T_rep``
  (:attr:`raysim.radar.config.RadarConfig.chirp_interval`), so Doppler beyond
  ``+-1 / (2 T_rep)`` (range rate beyond ``+-lambda / (4 T_rep)``,
  :attr:`~raysim.radar.config.RadarConfig.max_velocity`) folds back into the
  spectrum, as it does in a real radar.
* **Within a chirp.** As for every moving object
  (:func:`raysim.echoes.moving.scatterers.synthesize_tracks`), the scatterers'
  positions are taken at each chirp's and channel's transmit instant and frozen
  during the chirp (stop-and-hop): the Doppler shift of the beat frequency is
  left out, an error of ``f_D T_c`` range bins (0.3 bin for 5 kHz and 60 us).

Amplitudes follow the monostatic radar equation at the trace instant, as for
:class:`raysim.echoes.moving.scatterers.MovingObject`; the two-way element gain is
applied at synthesis.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.echoes.moving.scatterers import RigidTrajectory, Tracks
from raysim.radar.config import RCS_DBSM_RANGE, RadarConfig

__all__ = ["Rotor", "RCS_PER", "SAMPLES_PER_WAVELENGTH"]

#: What ``Rotor.rcs_dbsm`` is the RCS of.
RCS_PER = ("blade", "scatterer")
#: Default scatterers per wavelength along a blade: spacing ``lambda / 4`` keeps the blade's
#: grating flashes out (they need a spacing of ``lambda / 2`` or more) with a margin.
SAMPLES_PER_WAVELENGTH = 4


def _unit(v, name: str) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)) or np.linalg.norm(a) == 0.0:
        raise ValueError(f"{name} must be 3 finite numbers, not all zero, got {v!r}")
    return a / np.linalg.norm(a)


@dataclass(frozen=True)
class Rotor:
    """A rotor or fan: ``blades`` lines of point scatterers spinning about a hub.

    Attributes
    ----------
    name : str
    hub : ndarray, shape ``[3]``, or RigidTrajectory
        Hub position in W [m], or the trajectory of a body that carries the
        rotor (the hub is the body origin).
    axis : ndarray, shape ``[3]``
        Spin axis, in W for a fixed hub, in the body frame (FRD, turning with
        the trajectory's yaw) on a trajectory; normalised. Positive ``rate``
        turns right-handed about it. Default ``-z`` (up).
    rate : float
        Spin rate [rev/s] (``omega = 2 pi rate`` [rad/s]); 0 holds the blades still.
    blades : int
        Number of blades, evenly spaced in angle.
    blade_length : float
        Hub to blade tip [m].
    root : float
        Distance from the hub where the scattering part of a blade begins [m].
    start_angle : float
        Angle of blade 0 at ``t0`` from the reference direction ``e_1`` [rad]:
        ``e_1`` is the part of the frame's x axis (north, or forward on a
        trajectory) in the rotor plane, or of y where the axis is along x.
    scatterers_per_blade : int, optional
        Scatterers on each blade, spaced ``(blade_length - root) / n`` from the
        root, the last at the tip; default the fewest that keep the spacing at
        most ``lambda / SAMPLES_PER_WAVELENGTH``.
    rcs_dbsm : float
        RCS [dBsm] of a blade at its flash (``rcs_per="blade"``: its ``n``
        in-phase scatterers have ``sigma / n**2`` each) or of each scatterer
        (``rcs_per="scatterer"``).
    rcs_per : {"blade", "scatterer"}
    t0 : float
        Reference time of ``start_angle`` [s].
    """

    name: str
    hub: np.ndarray | RigidTrajectory
    axis: np.ndarray = (0.0, 0.0, -1.0)
    rate: float = 50.0
    blades: int = 2
    blade_length: float = 0.12
    root: float = 0.0
    start_angle: float = 0.0
    scatterers_per_blade: int | None = None
    rcs_dbsm: float = -20.0
    rcs_per: str = "blade"
    t0: float = 0.0

    def __post_init__(self) -> None:
        if not isinstance(self.hub, RigidTrajectory):
            h = np.asarray(self.hub, dtype=float)
            if h.shape != (3,) or not np.all(np.isfinite(h)):
                raise ValueError(f"hub must be 3 finite numbers [m] or a RigidTrajectory, "
                                 f"got {self.hub!r}")
            object.__setattr__(self, "hub", h)
        object.__setattr__(self, "axis", _unit(self.axis, "axis"))
        for name in ("rate", "start_angle", "t0"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")
        if isinstance(self.blades, bool) or not isinstance(self.blades, (int, np.integer)) \
                or self.blades < 1:
            raise ValueError(f"blades must be an integer >= 1, got {self.blades!r}")
        if not (math.isfinite(self.blade_length) and self.blade_length > 0):
            raise ValueError(f"blade_length must be > 0 m, got {self.blade_length!r}")
        if not (math.isfinite(self.root) and 0 <= self.root < self.blade_length):
            raise ValueError(f"root must be in [0, blade_length = {self.blade_length}) m, "
                             f"got {self.root!r}")
        n = self.scatterers_per_blade
        if n is not None and (isinstance(n, bool) or not isinstance(n, (int, np.integer))
                              or n < 1):
            raise ValueError(f"scatterers_per_blade must be an integer >= 1 or None, got {n!r}")
        lo, hi = RCS_DBSM_RANGE
        if not (math.isfinite(self.rcs_dbsm) and lo <= self.rcs_dbsm <= hi):
            raise ValueError(f"rcs_dbsm must be in [{lo}, {hi}] dBsm, got {self.rcs_dbsm!r}")
        if self.rcs_per not in RCS_PER:
            raise ValueError(f"rcs_per must be one of {RCS_PER}, got {self.rcs_per!r}")

    @property
    def omega(self) -> float:
        """Spin rate ``2 pi rate`` [rad/s]."""
        return 2.0 * math.pi * self.rate

    def max_doppler(self, wavelength: float) -> float:
        """Largest micro-Doppler ``2 |omega| r_tip / lambda`` [Hz] (line of sight in the plane)."""
        return 2.0 * abs(self.omega) * self.blade_length / wavelength

    def radii(self, wavelength: float) -> np.ndarray:
        """Distances of a blade's scatterers from the hub ``[k]`` [m], the last at the tip."""
        span = self.blade_length - self.root
        n = self.scatterers_per_blade
        if n is None:
            n = max(1, math.ceil(span * SAMPLES_PER_WAVELENGTH / wavelength))
        return self.root + span * np.arange(1, n + 1) / n

    def _plane(self) -> tuple[np.ndarray, np.ndarray]:
        ref = np.eye(3)[0] if abs(self.axis[0]) < 0.9 else np.eye(3)[1]
        e1 = ref - (ref @ self.axis) * self.axis
        e1 /= np.linalg.norm(e1)
        return e1, np.cross(self.axis, e1)

    def positions(self, times, wavelength: float) -> np.ndarray:
        """World positions of the scatterers ``[blade * k, ..., 3]`` at ``times`` [s].

        Blade-major order: blade 0's scatterers root to tip, then blade 1's...
        """
        t = np.asarray(times, dtype=float)
        d = self.radii(wavelength)
        e1, e2 = self._plane()
        phi = (self.omega * (t - self.t0))[None] + (
            self.start_angle + 2 * math.pi * np.arange(self.blades) / self.blades).reshape(
                (-1,) + (1,) * t.ndim)                                    # [blade, ...]
        arm = np.cos(phi)[..., None] * e1 + np.sin(phi)[..., None] * e2   # [blade, ..., 3]
        body = d.reshape((1, -1) + (1,) * (t.ndim + 1)) * arm[:, None]    # [blade, k, ..., 3]
        body = body.reshape((-1,) + t.shape + (3,))
        if not isinstance(self.hub, RigidTrajectory):
            return self.hub + body
        return self.hub.to_world(body, t)

    def tracks(self, config: RadarConfig, radar_w, *, time: float = 0.0, r_wb=None) -> Tracks:
        """Direct paths of the scatterers; amplitudes from the radar equation at ``time``.

        Parameters
        ----------
        config : RadarConfig
            Wavelength (default scatterer spacing) and radar equation.
        radar_w : array_like, shape ``[3]``
            Radar phase centre in W [m].
        time : float
            Trace instant [s].
        r_wb : array_like, optional
            Unused: the element gain is applied at synthesis.

        Returns
        -------
        Tracks
            ``blades * k`` paths labelled ``"rotor"``.
        """
        from raysim.echoes.ground.field import radar_scale

        lam = config.wavelength
        n = self.radii(lam).size
        sigma = 10 ** (self.rcs_dbsm / 10) / (n**2 if self.rcs_per == "blade" else 1)
        r = np.linalg.norm(self.positions(np.array(time), lam) - np.asarray(radar_w, float),
                           axis=-1)
        amp = (math.sqrt(radar_scale(config) * sigma) / r**2).astype(complex)

        def where(times):
            return self.positions(times, lam)

        return Tracks(where, where, amp, np.full(r.size, "rotor"))
