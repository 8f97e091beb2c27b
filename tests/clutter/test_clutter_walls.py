"""Diffuse clutter from walls: vertical faces of clutter materials scatter in the default mode.

A concrete wall seen obliquely from above (incidence 37-60 deg from its
normal, where the constant-gamma term of ``sigma0`` is all that is left) is the
only surface inside the range window. Its scatterers' powers sum to the radar
equation integrated over the wall (Skolnik, *Radar Handbook*, 3rd ed., eq. 7.1
with ``sigma = sigma0 dA``): ``sum_i E|a_i|^2 = P_t lambda^2 / (4 pi)^3
int sigma0(theta) / R^4 dA``, and a rendered cube carries that power times the
two-way element gain of each scatterer.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from clutter_grounds import grid_ground

from raysim.echoes.ground.field import ClutterField, FieldSettings, radar_scale
from raysim.echoes.ground.sigma0 import sigma0
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.po.mesh import TriangleMesh
from raysim.echoes.rt.reproject import synthesize_paths
from raysim.echoes.rt.scenes import SCENES, RadarScene
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Wall power summed over its scatterers (mean of SEEDS fields) vs the radar-equation
#: integral [dB]: Poisson positions and Exp(1) |z|^2 over SEEDS x ~250 scatterers (2-3 %).
WALL_POWER_TOL_DB = 0.5
#: Rendered cube power vs the paths' sum of |a|^2 G^2, both averaged over SEEDS fields [dB]:
#: scatterers of one resolution cell interfere (Rayleigh cells), and the nearest cells
#: dominate (R^-4), so one field's cube is within about +-1.5 dB of it.
RENDER_TOL_DB = 1.0
SEEDS = 16
#: The wall: the plane x_W = WALL_X (north of the radar), y_W in +-WALL_HALF_WIDTH,
#: z_W (down) from WALL_TOP to WALL_BOTTOM [m]; the radar at the origin looks down.
WALL_X, WALL_HALF_WIDTH, WALL_TOP, WALL_BOTTOM = 6.0, 3.0, 6.0, 10.0


def _wall_scene() -> GroundSurface:
    """A concrete wall (an open sheet) and a ground beyond the range window."""
    y, z = WALL_HALF_WIDTH, (WALL_TOP, WALL_BOTTOM)
    v = np.array([[WALL_X, -y, z[0]], [WALL_X, y, z[0]], [WALL_X, y, z[1]], [WALL_X, -y, z[1]]])
    wall = TriangleMesh(v, np.array([[0, 1, 2], [0, 2, 3]]))
    far = grid_ground(10.0, 1, 60.0)                    # 60 m down: outside the 22.5 m window
    return GroundSurface.from_meshes([(wall, "concrete"), (far, "dry-soil")])


def _wall_integral(config: RadarConfig, n: int = 400) -> float:
    """``P_t lambda^2 / (4 pi)^3 int sigma0 / R^4 dA`` over the wall, midpoint rule [W]."""
    y = np.linspace(-WALL_HALF_WIDTH, WALL_HALF_WIDTH, n + 1)
    z = np.linspace(WALL_TOP, WALL_BOTTOM, n + 1)
    yc, zc = np.meshgrid(0.5 * (y[1:] + y[:-1]), 0.5 * (z[1:] + z[:-1]), indexing="ij")
    r = np.sqrt(WALL_X**2 + yc**2 + zc**2)
    theta = np.arccos(WALL_X / r)                      # from the wall normal (-1, 0, 0)
    s0 = sigma0(theta, "concrete", wavelength=config.wavelength)
    da = (y[1] - y[0]) * (z[1] - z[0])
    return float(radar_scale(config) * np.sum(s0 / r**4) * da)


def test_wall_scatterers_carry_sigma0_times_area_and_reach_the_cube():
    config = RadarConfig(num_chirps=1, sample_rate=2.5e6)          # 22.5 m window
    array = upa(4, 4, wavelength=config.wavelength)
    ground = _wall_scene()
    assert len(ground.wall_triangles) == 4                         # 2 facets, both faces
    assert FieldSettings().walls                                   # the default mode
    expected = _wall_integral(config)
    sums, fields = [], []
    for seed in range(SEEDS):
        field = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                                   FieldSettings(shadowing=False, seed=seed))
        paths = field.paths(config, np.zeros(3), np.eye(3))
        assert field.report["wall_scatterers"] == field.num_scatterers == paths.num_paths
        assert np.allclose(paths.first_vertex[:, 0], WALL_X)
        sums.append(np.sum(np.abs(paths.amplitude) ** 2))
        fields.append((field, paths))
    err = 10 * np.log10(np.mean(sums) / expected)
    print(f"wall: {fields[0][0].num_scatterers} scatterers, sum |a|^2 {np.mean(sums):.4e} W "
          f"vs radar-equation integral {expected:.4e} W: {err:+.3f} dB")
    assert abs(err) < WALL_POWER_TOL_DB

    rendered, want = 0.0, 0.0
    for _, paths in fields:
        cube, _ = synthesize_paths(paths, config, array, path_chunk=4096)
        rendered += float(np.mean(np.abs(cube[0]) ** 2)) / SEEDS
        u = paths.first_vertex / np.linalg.norm(paths.first_vertex, axis=1, keepdims=True)
        g2 = config.pattern.gain_direction(u) ** 2                  # two-way element gain
        want += float(np.sum(np.abs(paths.amplitude) ** 2 * g2)) / SEEDS
    err_r = 10 * np.log10(rendered / want)
    print(f"rendered wall power {rendered:.4e} vs paths {want:.4e}: {err_r:+.3f} dB")
    assert abs(err_r) < RENDER_TOL_DB

    bare = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                              FieldSettings(shadowing=False, walls=False))
    assert bare.num_scatterers == 0                                # the ground is out of range


def test_parking_lot_facade_scatters_by_default():
    """The parking lot's concrete facade (a closed box 30 m north) returns diffuse clutter
    from its outward faces that the radar sees, and only from them."""
    d = SCENES["parking_lot"]
    ground = GroundSurface.from_scene(RadarScene(d, None, d.metadata()["hover_altitude"], []))
    config = RadarConfig()
    array = upa(8, 8, wavelength=config.wavelength)
    field = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                               FieldSettings(shadowing=False, seed=1))
    on_wall = np.abs(field.normals[:, 2]) < math.cos(math.radians(60.0))
    assert field.report["wall_scatterers"] == int(on_wall.sum()) > 500
    # the facade's south face (x_W = 29.8 m, normal towards the radar) and its ends
    front = on_wall & (np.abs(field.positions[:, 0] - 29.8) < 1e-6)
    assert front.sum() > 0.8 * on_wall.sum()
    assert np.allclose(field.normals[front], [-1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="go together"):
        GroundSurface(ground.triangles, ground.normals, ground.material,
                      wall_triangles=ground.wall_triangles)


def test_scenario_key_walls_reaches_the_field():
    """``[scene.clutter] walls`` turns the field's walls off; left out, walls stay on and
    the scenario's canonical JSON (its store key) does not name it."""
    from raysim.data import example_path
    from raysim.pipeline.sources import _clutter
    from raysim.scenario.reader import load_scenario

    s = load_scenario(example_path("scene_parking_lot.toml"))
    assert "walls" not in s.to_json()
    assert _clutter(s).settings.walls is True
    off = s.with_values({"scene.clutter.walls": False})
    assert _clutter(off).settings.walls is False
