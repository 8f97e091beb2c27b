"""Persistent clutter: two frames of a hovering platform share their scatterers.

After exact rigid-body compensation with the pose of an ideal IMU, the
complex range-angle maps of consecutive frames 1 and 2 must correlate above
0.95; a field drawn afresh for each frame (what re-sampled diffuse rays gave)
must not. Frames are contiguous (1.9 ms): speckle of a persistent field still
decorrelates physically with translation, by the sub-cell phase
``2 k (u - u_G) . d`` that compensation to the cell centre ``u_G`` cannot remove
(about 9 rad at the cell edge for d = 23 mm, the hover drift over 0.1 s, with
an 8 x 8 array).
"""

from __future__ import annotations

import numpy as np
import pytest
from clutter_grounds import grid_ground

from raysim.echoes.ground.field import FieldSettings
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.rt.reproject import synthesize_paths
from raysim.echoes.scene_clutter import SceneClutter
from raysim.platform.motion import hover_jitter
from raysim.processing import maps as processing
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Correlation of the compensated range-angle maps of two frames (the brief's 0.95).
MAP_CORRELATION_MIN = 0.95
#: Largest correlation of two independent fields (re-drawn clutter; about 0.2 measured).
INDEPENDENT_CORRELATION_MAX = 0.4
HEIGHT = 8.0
LEVER = np.array([0.0, 0.0, 0.1])


@pytest.fixture(scope="module")
def hover():
    config = RadarConfig(num_chirps=8, sample_rate=2.5e6, idle_time=180e-6)  # 1.9 ms frames
    array = upa(8, 8, wavelength=config.wavelength)
    ground = GroundSurface.from_meshes([(grid_ground(36.0, 4, HEIGHT), "dry-soil")])
    return config, array, ground, hover_jitter(5)


def _frame(model, config, array, traj, frame):
    t = float(config.chirp_times(frame)[0])
    radar_w = traj.point_world([t], LEVER)[0, 0]
    r_wb = traj.attitude([t]).as_matrix()[0]
    field = model.field_for(config, array, radar_w, r_wb)
    paths = field.paths(config, radar_w, r_wb, time=t)
    cube, _ = synthesize_paths(paths, config, array, traj, LEVER, frame=frame, path_chunk=2048)
    return cube


def _compensated_map(cube, config, array, traj, frame):
    """Zero-Doppler range-angle map ``[gate * az * el]`` (complex), exactly compensated."""
    from compensation import integrate_imu, rigid_body_projection
    from raysim.platform.imu import simulate_imu

    t = config.chirp_times(frame)
    imu = simulate_imu(traj, "ideal", rate=4000.0, start=t[0] - 1e-3, end=t[-1] + 1e-3)
    pose = integrate_imu(*imu.to_arrays(), t, lever_arm=LEVER, reference_time=t[0],
                         initial_attitude=traj.attitude([t[0]]).as_matrix()[0],
                         initial_position=traj.position([t[0]])[0], velocity="given",
                         initial_velocity=traj.velocity([t[0]])[0])
    rc = processing.range_compress(cube)
    r_axis = config.range_axis()
    gates = np.nonzero((r_axis > 9.0) & (r_axis < 16.0))[0]
    grid = np.radians(np.linspace(-30.0, 30.0, 13))
    beams = rigid_body_projection(rc, array.virtual_positions, pose,
                                  wavelength=config.center_wavelength, range_axis=r_axis,
                                  azimuth=grid, elevation=grid, range_gates=gates,
                                  grid_shape=array.grid_shape)
    return beams.data.mean(axis=0).ravel()


def _coherence(a: np.ndarray, b: np.ndarray) -> float:
    """Complex correlation ``|sum a b*| / sqrt(sum |a|^2 sum |b|^2)`` of two maps, in [0, 1].

    Shared speckle gives ~1; independent clutter ~ 1 / sqrt(cells) whatever the
    mean power profile (which a correlation of magnitudes would count as shared).
    """
    return float(abs(np.vdot(b, a)) / np.sqrt(np.vdot(a, a).real * np.vdot(b, b).real))


def test_hovering_frames_share_clutter(hover):
    config, array, ground, traj = hover
    model = SceneClutter(FieldSettings(shadowing=False), ground=ground, specular=False,
                          ghosts=False)
    maps = [_compensated_map(_frame(model, config, array, traj, f), config, array, traj, f)
            for f in (1, 2)]
    moved = np.linalg.norm(traj.point_world([config.chirp_times(2)[0]], LEVER)[0, 0]
                           - traj.point_world([config.chirp_times(1)[0]], LEVER)[0, 0])
    rho = _coherence(maps[0], maps[1])
    print(f"frames 1-2: radar moved {moved * 1e3:.1f} mm, one field built "
          f"({model.builds}), compensated map correlation {rho:.4f}")
    assert model.builds == 1
    # the platform moved: the two-way carrier phase of every scatterer changed by > 0.5 rad
    assert 4 * np.pi * moved / config.wavelength > 0.5
    assert rho > MAP_CORRELATION_MIN
    # a fresh field for frame 2 (independent clutter) does not correlate
    fresh = SceneClutter(FieldSettings(shadowing=False, seed=1), ground=ground,
                          specular=False, ghosts=False)
    other = _compensated_map(_frame(fresh, config, array, traj, 2), config, array, traj, 2)
    rho_fresh = _coherence(maps[0], other)
    print(f"frame 1 vs a fresh field in frame 2: correlation {rho_fresh:.4f}")
    assert rho_fresh < INDEPENDENT_CORRELATION_MAX


def test_field_rebuilt_beyond_reuse_distance(hover):
    config, array, ground, _ = hover
    model = SceneClutter(FieldSettings(shadowing=False, reuse_distance=0.2), ground=ground)
    a = model.field_for(config, array, np.zeros(3), np.eye(3))
    assert model.field_for(config, array, np.array([0.1, 0.0, 0.0]), np.eye(3)) is a
    b = model.field_for(config, array, np.array([0.5, 0.0, 0.0]), np.eye(3))
    assert b is not a and model.builds == 2
    assert model.summary()["builds"] == 2 and model.summary()["num_scatterers"] > 0
