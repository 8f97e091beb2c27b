"""Rough-surface specular: the nadir mirror is Fresnel x Ament and ignores the triangulation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from clutter_grounds import grid_ground

from raysim.echoes.ground.field import radar_scale
from raysim.echoes.ground.sigma0 import CLUTTER_MATERIALS
from raysim.echoes.ground.specular import rough_specular_path
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.rt.reproject import synthesize_paths
from raysim.echoes.rt.trace import SPECULAR
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Rendered nadir power vs the closed form, and between triangulations [dB] (the brief's 1 dB).
NADIR_TOL_DB = 1.0
#: Radar height [m].
HEIGHT = 8.0
#: Range bins either side of the nadir peak summed (Parseval; > 98 % of a sinc^2).
PEAK_BINS = 8
MATERIAL = "asphalt-77ghz"


def _relief(x, y):
    """Metre-scale undulation with zero mean under the radar (the rms height is sub-mesh)."""
    return 0.15 * np.sin(2 * np.pi * x / 7.0) * np.sin(2 * np.pi * y / 9.0)


def _closed_form_w(config: RadarConfig) -> float:
    """``P_t G^2 lambda^2 |Gamma(0)|^2 chi^2 / ((4 pi)^2 (2h)^2)`` (Ament 1953; Beckmann 5.29)."""
    m = CLUTTER_MATERIALS[MATERIAL]
    root = np.sqrt(complex(m.permittivity))
    gamma2 = abs((1 - root) / (1 + root)) ** 2                       # Balanis eq. 5-24 at 0 deg
    k = 2 * math.pi / config.wavelength
    chi2 = math.exp(-4 * (k * m.rms_height) ** 2)
    g2 = config.pattern.peak_gain ** 2                               # nadir is boresight
    return radar_scale(config) * g2 * 4 * math.pi * gamma2 * chi2 / (2 * HEIGHT) ** 2


def _rendered_nadir_w(mesh, config, array) -> float:
    ground = GroundSurface.from_meshes([(mesh, MATERIAL)])
    paths = rough_specular_path(ground, config, np.zeros(3), np.eye(3))
    assert paths.num_paths == 1 and paths.kind[0] == SPECULAR
    cube, _ = synthesize_paths(paths, config, array)
    y = np.fft.fft(cube[0, 0], axis=-1)
    n = config.num_samples
    k = int(np.argmax(np.abs(y)))
    return float(np.sum(np.abs(y[k - PEAK_BINS: k + PEAK_BINS + 1]) ** 2) / n**2)


@pytest.mark.parametrize("relief", [None, _relief], ids=["flat", "undulating"])
def test_nadir_is_ament_fresnel_on_two_triangulations(relief):
    config = RadarConfig(num_chirps=1, sample_rate=2.5e6)
    array = upa(1, 1, wavelength=config.wavelength)
    ref = _closed_form_w(config)
    a = _rendered_nadir_w(grid_ground(30.0, 12, HEIGHT, height=relief), config, array)
    b = _rendered_nadir_w(grid_ground(30.0, 12, HEIGHT, height=relief, flip=True), config, array)
    c = _rendered_nadir_w(grid_ground(30.0, 5, HEIGHT, height=relief, centre=(0.4, -0.3)),
                          config, array)
    db = [10 * np.log10(p / ref) for p in (a, b, c)]
    print(f"nadir vs Ament-Fresnel closed form: {db[0]:+.3f}, {db[1]:+.3f}, {db[2]:+.3f} dB")
    assert all(abs(d) < NADIR_TOL_DB for d in db)
    assert abs(10 * np.log10(a / b)) < NADIR_TOL_DB
    assert abs(10 * np.log10(a / c)) < NADIR_TOL_DB
    # the roughness matters: a perfect mirror of the same material is > 20 dB stronger
    m = CLUTTER_MATERIALS[MATERIAL]
    assert 10 * np.log10(math.exp(4 * (2 * math.pi / config.wavelength * m.rms_height) ** 2)) > 20


def test_no_mirror_off_the_ground_or_outside_the_fov():
    config = RadarConfig(num_chirps=1)
    ground = GroundSurface.from_meshes([(grid_ground(10.0, 2, HEIGHT, centre=(30.0, 0.0)),
                                         MATERIAL)])
    assert rough_specular_path(ground, config, np.zeros(3), np.eye(3)).num_paths == 0
    ground = GroundSurface.from_meshes([(grid_ground(10.0, 2, HEIGHT), MATERIAL)])
    side = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])      # boresight east, horizontal
    assert rough_specular_path(ground, config, np.zeros(3), side).num_paths == 0
