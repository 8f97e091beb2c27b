"""Moving scattering points: image-method ghost Doppler and a driving car's Doppler and range walk.

Closed forms: a path of length ``L(t) = |P_t(t) - x| + |P_r(t) - x|`` has the
slow-time Doppler ``f_D = L'(t) / lambda_c`` (docs/conventions.md, positive when
the path lengthens; ``lambda_c`` the mid-chirp wavelength of range-compressed
data) and the beat frequency ``f_b = S L / c`` (S the chirp slope). For a ground
ghost of a target ``p`` moving at ``v`` the image method gives
``P = M p`` moving at ``M v`` (Balanis, *Advanced Engineering Electromagnetics*,
sec. 7.4).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from clutter_grounds import grid_ground, range_profile, tone_frequency

from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.moving.scatterers import (
    MovingObject,
    RigidTrajectory,
    ground_ghosts,
    synthesize_tracks,
)
from raysim.radar.arrays import upa
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

#: Measured vs closed-form Doppler and range walk [bins] (the brief's 0.1 bin).
BIN_TOL = 0.1
#: Radar height above the flat asphalt ground [m].
HEIGHT = 10.0


def _rate(f, t: float, dt: float = 1e-5) -> np.ndarray:
    """Central difference ``(f(t + dt) - f(t - dt)) / 2 dt`` of a path-length function."""
    return (f(t + dt) - f(t - dt)) / (2 * dt)


def _lengths(tracks, t: float) -> np.ndarray:
    tt = np.array(t)
    return (np.linalg.norm(tracks.p_tx(tt), axis=-1) + np.linalg.norm(tracks.p_rx(tt), axis=-1))


def test_rising_target_direct_and_ghost_doppler():
    """Target rising at 2 m/s, drifting north, over asphalt: each path's Doppler = image method."""
    config = RadarConfig(num_chirps=64)
    array = upa(1, 1, wavelength=config.wavelength)
    ground = GroundSurface.from_meshes([(grid_ground(60.0, 4, HEIGHT), "asphalt-77ghz")])
    target = SimpleNamespace(position=np.array([3.0, 2.0, HEIGHT - 3.0]),
                             velocity=np.array([0.5, 0.0, -2.0]), rcs_dbsm=10.0)
    tracks = ground_ghosts([target], ground, config, np.zeros(3), np.eye(3), direct=True)
    assert list(tracks.label) == ["direct", "ghost-rx", "ghost-tx", "ghost-double"]
    cube = np.zeros((config.num_chirps, 1, config.num_samples), np.complex64)
    synthesize_tracks([tracks], config, array, out=cube)
    y = range_profile(cube[:, 0])
    r_bins = config.bin_ranges(config.num_samples)
    t_mid = 0.5 * config.frame_duration
    rates = _rate(lambda t: _lengths(tracks, t), t_mid)
    bin_hz = config.doppler_resolution
    lam = config.center_wavelength
    for i, label in enumerate(tracks.label):               # ghost-rx and ghost-tx coincide
        k = int(np.argmin(np.abs(r_bins - 0.5 * _lengths(tracks, t_mid)[i])))
        f_meas = tone_frequency(y[:, k], config.chirp_interval)
        f_true = rates[i] / lam
        print(f"{label}: measured {f_meas / bin_hz:+.4f} bins, image method "
              f"{f_true / bin_hz:+.4f} bins")
        assert abs(f_meas - f_true) / bin_hz < BIN_TOL
    # a frozen bounce point moved with the target would be off by many bins
    p, v = target.position, target.velocity
    image = p * np.array([1, 1, -1]) + np.array([0, 0, 2 * HEIGHT])
    s = image * (HEIGHT / image[2])                            # bounce point on the ground
    frozen = (p / np.linalg.norm(p) + s / np.linalg.norm(s)) @ v
    assert abs(frozen - rates[1]) / lam / bin_hz > 10 * BIN_TOL


@pytest.mark.parametrize("yaw_rate", [0.0, 0.4], ids=["straight", "turning"])
def test_driving_car_doppler_and_range_walk(yaw_rate):
    """A car at 10 m/s: Doppler per frame and range walk over frames follow its trajectory."""
    config = RadarConfig(num_chirps=64, frame_period=0.05)
    array = upa(1, 1, wavelength=config.wavelength)
    traj = RigidTrajectory(start=np.array([12.0, 4.0, HEIGHT - 0.5]), heading=math.radians(30),
                           speed=10.0, yaw_rate=yaw_rate)
    car = MovingObject("car", points=[[1.5, 0.6, 0.0]], rcs_dbsm=[10.0], trajectory=traj)
    lam, n = config.center_wavelength, config.num_samples
    range_bin_hz = config.sample_rate / n
    beats, walk = [], []

    def length(t):
        # reference trajectory, written out: psi = psi0 + w t; straight line for w = 0
        psi = traj.heading + yaw_rate * t
        if yaw_rate == 0:
            c = traj.start + 10.0 * t * np.array([math.cos(traj.heading),
                                                  math.sin(traj.heading), 0.0])
        else:
            c = traj.start + 10.0 / yaw_rate * np.array([
                math.sin(psi) - math.sin(traj.heading), math.cos(traj.heading) - math.cos(psi),
                0.0])
        b = np.array([1.5 * math.cos(psi) - 0.6 * math.sin(psi),
                      1.5 * math.sin(psi) + 0.6 * math.cos(psi), 0.0])
        return 2 * np.linalg.norm(c + b)

    for frame in (0, 4):
        tracks = car.tracks(config, np.zeros(3), time=float(config.chirp_times(frame)[0]))
        cube = np.zeros((config.num_chirps, 1, n), np.complex64)
        synthesize_tracks([tracks], config, array, out=cube, frame=frame)
        t = config.chirp_times(frame)
        t_mid = 0.5 * (t[0] + t[-1])
        y = range_profile(cube[:, 0])
        k = int(np.argmax(np.sum(np.abs(y) ** 2, axis=0)))
        f_d = tone_frequency(y[:, k], config.chirp_interval)
        f_true = _rate(length, t_mid) / lam
        print(f"yaw rate {yaw_rate}: frame {frame} Doppler {f_d / config.doppler_resolution:+.4f}"
              f" bins vs trajectory {f_true / config.doppler_resolution:+.4f}")
        assert abs(f_d - f_true) / config.doppler_resolution < BIN_TOL
        beats.append(tone_frequency(cube[0, 0], 1.0 / config.sample_rate))
        walk.append(config.chirp_rate * length(t[0]) / SPEED_OF_LIGHT)
    measured = (beats[1] - beats[0]) / range_bin_hz
    expected = (walk[1] - walk[0]) / range_bin_hz
    print(f"range walk over 4 frames: {measured:+.4f} bins vs trajectory {expected:+.4f} bins")
    assert abs(expected) > 3                                   # the walk is many bins
    assert abs(measured - expected) < BIN_TOL


def test_rigid_trajectory_bad_input_and_closed_form():
    with pytest.raises(ValueError, match="start"):
        RigidTrajectory(start=[0.0, 1.0])
    with pytest.raises(ValueError, match="trajectory"):
        MovingObject("car", [[0, 0, 0]], [0.0], trajectory=None)
    # a turn of yaw rate w at speed v is a circle of radius v / w
    tr = RigidTrajectory(start=np.zeros(3), speed=10.0, yaw_rate=0.5)
    c, psi = tr.pose(np.linspace(0, 2 * math.pi / 0.5, 9))
    centre = np.array([0.0, 20.0, 0.0])
    assert np.allclose(np.linalg.norm(c - centre, axis=-1), 20.0)
    assert np.allclose(np.linalg.norm(tr.velocity(np.array([0.3, 1.7])), axis=-1), 10.0)
