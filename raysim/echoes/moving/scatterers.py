r"""Paths whose scattering points move during a frame: target-ground ghosts and moving objects.

A frozen :class:`raysim.echoes.rt.trace.PathSet` moves both end vertices of a
path with one velocity. Two cases need more and are handled here as *tracks*:
each path ends its transmit leg on a point ``P_t(t)`` and starts its receive
leg on a point ``P_r(t)``, and its length is

.. math::

    L(t) = |P_t(t) - x_t(t)| + |P_r(t) - x_r(t)|

for every chirp and channel (element positions ``x_t``, ``x_r`` as in
:mod:`raysim.echoes.rt.reproject`).

* **Ghosts** (image method, Balanis, *Advanced Engineering Electromagnetics*,
  sec. 7.4): with ``M`` the mirror across the mean ground plane under a point
  target ``p`` moving at ``v``, the ground-bounced legs are straight lines to
  the image ``M p``, which moves at ``M v`` (vertical component flipped). The
  bounce-on-receive path is ``(P_t, P_r) = (p, M p)``, bounce-on-transmit
  ``(M p, p)``, double bounce ``(M p, M p)``. This is exact for any target
  velocity; a frozen bounce point moved with the target velocity is not.
  Amplitudes follow the bistatic radar equation with the ground's Fresnel
  coefficient times the Ament factor at the bounce's incidence.
* **Moving objects**: scattering centres fixed on a rigid body that drives
  along a :class:`RigidTrajectory` (straight or turning at a constant yaw rate).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.echoes.ground.sigma0 import ament_factor, fresnel_coefficient
from raysim.echoes.ground.specular import FIT_RADIUS, mirror
from raysim.echoes.ground.surface import GroundSurface
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

__all__ = ["Tracks", "RigidTrajectory", "MovingObject", "ground_ghosts", "synthesize_tracks"]


@dataclass(frozen=True)
class RigidTrajectory:
    """Planar rigid-body motion in W: constant speed and yaw rate (a straight line or an arc).

    Attributes
    ----------
    start : ndarray, shape ``[3]``
        Body origin at ``t0`` in W [m].
    heading : float
        Heading at ``t0``, from north towards east [rad].
    speed : float
        Ground speed [m/s].
    yaw_rate : float
        Turn rate about ``+z_W`` (down) [rad/s]; 0 drives straight.
    t0 : float
        Reference time [s].
    """

    start: np.ndarray
    heading: float = 0.0
    speed: float = 10.0
    yaw_rate: float = 0.0
    t0: float = 0.0

    def __post_init__(self) -> None:
        s = np.asarray(self.start, dtype=float)
        if s.shape != (3,) or not np.all(np.isfinite(s)):
            raise ValueError(f"start must be 3 finite numbers [m], got {self.start!r}")
        object.__setattr__(self, "start", s)
        for name in ("heading", "speed", "yaw_rate", "t0"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")

    def pose(self, times) -> tuple[np.ndarray, np.ndarray]:
        """Body origin ``[..., 3]`` [m] and yaw ``[...]`` [rad] at ``times`` [s]."""
        t = np.asarray(times, dtype=float) - self.t0
        psi = self.heading + self.yaw_rate * t
        if self.yaw_rate == 0.0:
            dx = self.speed * t * math.cos(self.heading)
            dy = self.speed * t * math.sin(self.heading)
        else:
            k = self.speed / self.yaw_rate
            dx = k * (np.sin(psi) - math.sin(self.heading))
            dy = -k * (np.cos(psi) - math.cos(self.heading))
        c = self.start + np.stack([dx, dy, np.zeros_like(t)], axis=-1)
        return c, psi

    def to_world(self, body, times) -> np.ndarray:
        """Body-frame points in W at ``times`` [s], shape ``[point, ..., 3]`` [m].

        ``body`` [m] has shape ``[point, ..., 3]`` with ``...`` broadcastable to
        ``times``' shape; the body turns with the yaw about ``+z_W``.
        """
        c, psi = self.pose(times)
        cs, sn = np.cos(psi)[None], np.sin(psi)[None]
        b = np.asarray(body, dtype=float)
        x = cs * b[..., 0] - sn * b[..., 1]
        y = sn * b[..., 0] + cs * b[..., 1]
        return c[None] + np.stack([x, y, b[..., 2] + 0 * x], axis=-1)

    def velocity(self, times) -> np.ndarray:
        """Velocity of the body origin ``[..., 3]`` [m/s]."""
        _, psi = self.pose(times)
        return self.speed * np.stack([np.cos(psi), np.sin(psi), np.zeros_like(psi)], axis=-1)


class Tracks:
    """Moving-point paths: ``positions(times)`` and constant amplitudes over a frame.

    Parameters
    ----------
    p_tx, p_rx : callable
        ``f(times [...]) -> [path, ..., 3]`` end points of the transmit and receive legs [m].
    amplitude : ndarray, shape ``[path]``, complex
        IF amplitude [sqrt(W)].
    label : ndarray of str, shape ``[path]``
        What each path is (``"ghost-rx"``, ``"ghost-tx"``, ``"ghost-double"``, ``"mover"``...).
    """

    def __init__(self, p_tx, p_rx, amplitude, label):
        self.p_tx, self.p_rx = p_tx, p_rx
        self.amplitude = np.asarray(amplitude, dtype=complex)
        self.label = np.asarray(label)

    @property
    def num_paths(self) -> int:
        """Number of paths."""
        return int(self.amplitude.size)

    def lengths(self, times, x_tx, x_rx) -> np.ndarray:
        """Path lengths ``[path, chirp, channel]`` [m] at element positions ``[chirp, channel, 3]``.

        ``times`` ``[chirp, channel]`` are the transmit instants [s].
        """
        return (np.linalg.norm(self.p_tx(times) - x_tx[None], axis=-1)
                + np.linalg.norm(self.p_rx(times) - x_rx[None], axis=-1))


def _linear(p0: np.ndarray, v: np.ndarray, t_ref: float):
    def f(times):
        dt = np.asarray(times, dtype=float) - t_ref
        return p0.reshape(p0.shape[:1] + (1,) * dt.ndim + (3,)) + v.reshape(
            v.shape[:1] + (1,) * dt.ndim + (3,)) * dt[None, ..., None]
    return f


def ground_ghosts(targets, ground: GroundSurface, config: RadarConfig, radar_w, r_wb, *,
                  time: float = 0.0, polarisation: str = "VV",
                  fov_half_angle: float = math.radians(70.0), direct: bool = False) -> Tracks:
    """Target-ground-radar multipath of point targets by the image method.

    Parameters
    ----------
    targets : sequence of SceneTarget
        ``position`` [m] and ``velocity`` [m/s] in W, ``rcs_dbsm``.
    ground : GroundSurface
        The mean plane within :data:`raysim.echoes.ground.specular.FIT_RADIUS`
        under each target is its mirror.
    config : RadarConfig
    radar_w : array_like, shape ``[3]``
        Radar position of the frame [m] (sets the amplitudes and the checks).
    r_wb : array_like, shape ``[3, 3]``
        Attitude (boresight is the third column).
    time : float
        Instant at which the targets are at ``position`` [s].
    polarisation : {"VV", "HH"}
    fov_half_angle : float
        Paths with a leg outside this cone around boresight are left out [rad].
    direct : bool
        Also give the direct path (the ray tracer usually does).

    Returns
    -------
    Tracks
        Up to three ghosts per target (four with ``direct``); a ghost is left
        out when its bounce point is not on the ground.
    """
    from raysim.echoes.ground.field import radar_scale

    x0 = np.asarray(radar_w, dtype=float)
    bore = np.asarray(r_wb, dtype=float)[:, 2]
    cos_fov = math.cos(fov_half_angle)
    k0 = math.sqrt(radar_scale(config))
    rows = []                                            # (p_tx, v_tx, p_rx, v_rx, amp, label)

    def in_fov(p):
        u = p - x0
        return u @ bore >= cos_fov * np.linalg.norm(u)

    for t in targets:
        p, v = np.asarray(t.position, float), np.asarray(t.velocity, float)
        sq = math.sqrt(10 ** (t.rcs_dbsm / 10))
        r1 = float(np.linalg.norm(p - x0))
        if direct and in_fov(p):
            rows.append((p, v, p, v, k0 * sq / r1**2, "direct"))
        _, zg = ground.locate(p[None])
        if not np.isfinite(zg[0]):
            continue
        plane = ground.mean_plane(np.array([p[0], p[1], zg[0]]), FIT_RADIUS)
        if plane is None:
            continue
        o, n = plane
        if (p - o) @ n <= 0:
            continue
        pi, vi = mirror(p, o, n), v - 2 * (v @ n) * n
        # bounce point: where the line radar -> image crosses the plane
        s = x0 + ((o - x0) @ n) / ((pi - x0) @ n) * (pi - x0)
        facet, _ = ground.locate(s[None])
        if facet[0] < 0 or not (in_fov(p) and in_fov(s)):
            continue
        r2 = float(np.linalg.norm(pi - x0))
        cos_i = abs((x0 - s) @ n) / float(np.linalg.norm(x0 - s))
        mat = str(ground.material[facet[0]])
        theta = math.acos(min(1.0, cos_i))
        g = complex(fresnel_coefficient(mat, cos_i, polarisation)) * float(
            ament_factor(mat, theta, config.wavelength))
        single = k0 * sq / (r1 * r2) * g
        rows.append((p, v, pi, vi, single, "ghost-rx"))
        rows.append((pi, vi, p, v, single, "ghost-tx"))
        rows.append((pi, vi, pi, vi, k0 * sq / r2**2 * g * g, "ghost-double"))
    if not rows:
        z = np.zeros((0, 3))
        return Tracks(_linear(z, z, time), _linear(z, z, time), np.zeros(0), np.zeros(0, str))
    cols = list(zip(*rows, strict=True))
    pt, vt, pr, vr = (np.array(c, dtype=float) for c in cols[:4])
    return Tracks(_linear(pt, vt, time), _linear(pr, vr, time), np.array(cols[4]),
                  np.array(cols[5]))


@dataclass(frozen=True)
class MovingObject:
    """Scattering centres on a rigid body that drives along a :class:`RigidTrajectory`.

    Attributes
    ----------
    name : str
    points : ndarray, shape ``[point, 3]``
        Scattering centres in the body frame (x forward, y right, z down) [m].
    rcs_dbsm : ndarray, shape ``[point]``
        RCS of each centre [dBsm].
    trajectory : RigidTrajectory
    seed : int
        Seed of the centres' phases (used where ``phase`` is None).
    phase : ndarray, shape ``[point]``, optional
        Scattering phase of each centre [rad] (e.g. from PO); default uniform
        random phases drawn with ``seed``.
    """

    name: str
    points: np.ndarray
    rcs_dbsm: np.ndarray
    trajectory: RigidTrajectory
    seed: int = 0
    phase: np.ndarray | None = None

    def __post_init__(self) -> None:
        p = np.atleast_2d(np.asarray(self.points, dtype=float))
        r = np.broadcast_to(np.asarray(self.rcs_dbsm, dtype=float), (p.shape[0],)).copy()
        if p.ndim != 2 or p.shape[1] != 3 or not np.all(np.isfinite(p)):
            raise ValueError(f"points must be finite with shape [point, 3], got {p.shape}")
        if not np.all(np.isfinite(r)):
            raise ValueError("rcs_dbsm must be finite [dBsm]")
        if not isinstance(self.trajectory, RigidTrajectory):
            raise ValueError(f"trajectory must be a RigidTrajectory, got {type(self.trajectory)}")
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "rcs_dbsm", r)
        if self.phase is not None:
            ph = np.asarray(self.phase, dtype=float)
            if ph.shape != r.shape or not np.all(np.isfinite(ph)):
                raise ValueError(f"phase must be finite with shape {r.shape} [rad], "
                                 f"got shape {ph.shape}")
            object.__setattr__(self, "phase", ph)

    def positions(self, times) -> np.ndarray:
        """World positions of the centres ``[point, ..., 3]`` at ``times`` [s]."""
        b = self.points.reshape(self.points.shape[:1] + (1,) * np.ndim(times) + (3,))
        return self.trajectory.to_world(b, times)

    def tracks(self, config: RadarConfig, radar_w, *, time: float = 0.0, r_wb=None) -> Tracks:
        """Direct paths of the centres; amplitudes from the radar equation at ``time``.

        ``r_wb`` (radar attitude) is unused: the element gain is applied at synthesis.
        """
        from raysim.echoes.ground.field import radar_scale

        r = np.linalg.norm(self.positions(np.array(time)) - np.asarray(radar_w, float), axis=-1)
        if self.phase is None:
            rng = np.random.default_rng([self.seed, 0x4D0E])
            phase = np.exp(2j * np.pi * rng.random(r.size))
        else:
            phase = np.exp(1j * self.phase)
        amp = math.sqrt(radar_scale(config)) * np.sqrt(10 ** (self.rcs_dbsm / 10)) / r**2 * phase
        return Tracks(self.positions, self.positions, amp, np.full(r.size, "mover"))


def synthesize_tracks(tracks: list[Tracks], config: RadarConfig, array, trajectory=None,
                      lever_arm=(0.0, 0.0, 0.0), *, out: np.ndarray, chirps=None,
                      frame: int = 0, t0: float = 0.0, if_band: str = "cull",
                      synthesizer=None) -> int:
    """Add the IF signal of moving-point paths into ``out`` ``[chirp, channel, sample]``.

    Parameters
    ----------
    tracks : list of Tracks
    config, array, trajectory, lever_arm, chirps, frame, t0
        As for :func:`raysim.echoes.rt.reproject.reproject`.
    out : ndarray, complex64, shape ``[chirp, channel, sample]``
        Buffer added into.
    if_band : {"cull", "taper", "none"}
        Paths whose beat frequency leaves ``[0, f_s)``: dropped, weighted by
        :func:`raysim.echoes.rt.reproject.if_band_weight`, or kept.
    synthesizer : callable, optional
        ``f(tau, amplitude, config, out=cube)`` (default
        :func:`raysim.synthesis.select.synthesize`).

    Returns
    -------
    int
        Paths culled for leaving the sampled beat band.
    """
    from raysim.echoes.rt.reproject import IF_BAND_MODES, element_positions, if_band_weight
    from raysim.platform.motion import stationary
    from raysim.radar.pattern import path_gain
    from raysim.synthesis.select import synthesize

    if if_band not in IF_BAND_MODES:
        raise ValueError(f"if_band must be one of {IF_BAND_MODES}, got {if_band!r}")
    synth = synthesize if synthesizer is None else synthesizer
    trajectory = stationary() if trajectory is None else trajectory
    times, x_tx, x_rx = element_positions(config, array, trajectory,
                                          np.asarray(lever_arm, float), frame=frame, t0=t0,
                                          chirps=chirps)
    # the two-way element gain at each chirp's pose, as the re-projection gives frozen paths
    pose_t = times[:, 0]
    pos, rot = trajectory.pose(pose_t)
    mats = rot.as_matrix()                                            # [chirp, 3, 3] A -> W
    origin = pos + mats @ np.asarray(lever_arm, dtype=float)          # [chirp, 3]
    dropped = 0
    for tr in tracks:
        if tr.num_paths == 0:
            continue
        length = tr.lengths(times, x_tx, x_rx)
        gain = path_gain(config.pattern, mats, origin, tr.p_tx(pose_t), tr.p_rx(pose_t))
        amp = tr.amplitude[:, None, None] * gain[..., None]           # [path, chirp, 1]
        if if_band == "cull":
            ok = np.all((length >= 0) & (length < 2 * config.max_range), axis=(1, 2))
            dropped += int(np.sum(~ok))
            length, amp = length[ok], amp[ok]
        elif if_band == "taper":
            amp = amp * if_band_weight(0.5 * length, config)
        if length.shape[0]:
            synth(length / SPEED_OF_LIGHT, amp, config, out=out)
    return dropped
