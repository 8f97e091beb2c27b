"""Specular re-projection under platform motion: image method vs frozen reflection point.

A specular reflection point slides over its facet as the radar moves, so the
frozen-vertex re-projection carries a second-order error (about ``d^2 / h``).
The image method (``specular="image"``, the default) is exact: the re-projected
length of a single-bounce specular path off a plane equals the closed form
``|x_tx - M(x_rx)|`` (``2 (h - z)`` for co-located elements over flat ground).
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from raysim.platform.motion import Trajectory, constant_velocity, hover_jitter, sinusoid
from raysim.radar.arrays import upa
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

#: Image-method length vs closed form, hand-made traces [m] (float64 rounding of ~30 m).
IMAGE_LENGTH_TOL_M = 1e-12
#: Frozen-vertex error vs its closed form ``2 (sqrt(h^2 + d^2) - h)`` [m].
FROZEN_FORMULA_TOL_M = 1e-12
#: Image-method length vs closed form for a Sionna trace [m]: the traced reflection
#: point is float32 (one ulp of 15 m is 1 um) but it only enters through its
#: distance to the plane, which is exact for the flat ground at z = 0.
SIONNA_IMAGE_TOL_M = 1e-9
#: Ground height below the nominal hover point in the hand-made tests [m].
H = 15.0


def _specular_pathset(vertex, radar_tx, radar_rx=None):
    """A hand-made single-bounce specular PathSet traced from ``radar_tx``/``radar_rx``."""
    from raysim.echoes.rt.trace import SPECULAR, PathSet

    v = np.atleast_2d(np.asarray(vertex, float))
    tx = np.asarray(radar_tx, float)
    rx = tx if radar_rx is None else np.asarray(radar_rx, float)
    n = v.shape[0]
    length = np.linalg.norm(v - tx, axis=1) + np.linalg.norm(v - rx, axis=1)
    return PathSet(v, v.copy(), length, np.ones(n, complex), np.zeros((n, 3)), np.zeros(n),
                   np.full((n, 1), SPECULAR, np.uint32), np.full(n, SPECULAR, np.uint32),
                   np.zeros((n, 2, 2), complex), length / SPEED_OF_LIGHT, tx, rx, 0.0, {})


def ref_image_length(x_tx, x_rx, point, normal):
    """Closed form: ``|x_tx - M(x_rx)|``, ``M`` the mirror across the plane (point, normal)."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    d = np.sum((x_rx - point) * n, axis=-1, keepdims=True)
    return np.linalg.norm(x_tx - (x_rx - 2 * d * n), axis=-1)


def _geometry(motion, lever, config=None, array=None):
    from raysim.echoes.rt.reproject import element_positions

    config = RadarConfig(num_chirps=16) if config is None else config
    array = upa(4, 4, wavelength=config.wavelength) if array is None else array
    return element_positions(config, array, motion, lever)


def test_image_method_is_exact_over_flat_ground():
    """Translated and tilted platform: L' = 2 (h - z_m) for every chirp and channel."""
    from raysim.echoes.rt.reproject import path_lengths

    lever = np.array([0.05, -0.02, 0.10])
    # 10 cm/s drift plus 3 deg roll at 2 Hz plus hover jitter: cm-scale element motion
    motion = (constant_velocity([0.4, -0.3, 0.2]) + sinusoid("roll", np.deg2rad(3.0), 2.0)
              + sinusoid("pitch", np.deg2rad(-2.0), 1.5) + hover_jitter(4))
    traced_from = lever                              # nominal phase centre, nominal pose
    paths = _specular_pathset([traced_from[0], traced_from[1], H], traced_from)
    times, x_tx, x_rx = _geometry(motion, lever)
    got = path_lengths(paths, times, x_tx, x_rx)[0]
    exact = 2.0 * (H - x_tx[..., 2])
    err = np.abs(got - exact).max()
    disp = np.linalg.norm(x_tx - traced_from, axis=-1).max()
    print(f"image method over flat ground: max |L' - 2 (h - z)| = {err:.2e} m "
          f"(element displacement up to {disp * 100:.1f} cm)")
    assert disp > 0.01
    assert err < IMAGE_LENGTH_TOL_M
    # the delay form used by the synthesiser
    from raysim.echoes.rt.reproject import reproject

    r = reproject(paths, RadarConfig(num_chirps=16), upa(4, 4, wavelength=RadarConfig(
        num_chirps=16).wavelength), motion, lever)
    np.testing.assert_allclose(r.tau[0] * SPEED_OF_LIGHT, exact, rtol=0, atol=1e-12)


def test_image_method_is_exact_for_a_sloped_bistatic_facet():
    """Sloped facet, tx and rx apart (TDM MIMO), platform rotating: image-method closed form."""
    from raysim.echoes.rt.reproject import path_lengths, specular_normals
    from raysim.radar.arrays import ti_3tx4rx

    normal = np.array([0.3, -0.2, -1.0])             # facet faces up (towards -Z, the radar)
    normal /= np.linalg.norm(normal)
    p0 = np.array([1.0, 2.0, H])                     # a point of the facet plane
    tx0 = np.array([0.0, 0.0, 0.0])
    rx0 = np.array([0.02, 0.01, 0.0])
    # reflection point of the trace: where the segment tx0 -> mirror(rx0) crosses the plane
    rx_m = rx0 - 2 * np.dot(rx0 - p0, normal) * normal
    s = np.dot(p0 - tx0, normal) / np.dot(rx_m - tx0, normal)
    v = tx0 + s * (rx_m - tx0)
    paths = _specular_pathset(v, tx0, rx0)
    np.testing.assert_allclose(specular_normals(paths)[0], normal, atol=1e-12)
    config = RadarConfig(num_chirps=12, num_tx_slots=3)
    motion = sinusoid("yaw", np.deg2rad(10.0), 5.0) + constant_velocity([0.5, 0.2, -0.3])
    times, x_tx, x_rx = _geometry(motion, np.array([0.0, 0.0, 0.1]), config,
                                  ti_3tx4rx(config.wavelength))
    got = path_lengths(paths, times, x_tx, x_rx)[0]
    exact = ref_image_length(x_tx, x_rx, p0, normal)
    assert np.abs(got - exact).max() < IMAGE_LENGTH_TOL_M


def test_frozen_vertex_error_is_second_order():
    """Frozen reflection point: error 2 (sqrt(h'^2 + d^2) - h') ~ d^2 / h', quantified."""
    from raysim.echoes.rt.reproject import path_lengths

    paths = _specular_pathset([0.0, 0.0, H], [0.0, 0.0, 0.0])
    d = np.array([0.0, 0.01, 0.03, 0.05, 0.10])      # horizontal displacement [m]
    dz = 0.02                                        # and 2 cm climb
    x = np.stack([d, np.zeros_like(d), np.full_like(d, -dz)], axis=1)[None]   # [1, 5, 3]
    times = np.zeros((1, d.size))
    frozen = path_lengths(paths, times, x, x, specular="frozen")[0, 0]
    image = path_lengths(paths, times, x, x)[0, 0]
    h = H + dz
    np.testing.assert_allclose(image, 2 * h, rtol=0, atol=IMAGE_LENGTH_TOL_M)
    err = frozen - image
    np.testing.assert_allclose(err, 2 * (np.sqrt(h**2 + d**2) - h), rtol=0,
                               atol=FROZEN_FORMULA_TOL_M)
    np.testing.assert_allclose(err[1:], d[1:] ** 2 / h, rtol=1e-4)
    wavelength = RadarConfig().wavelength
    phase_deg = np.rad2deg(2 * np.pi * err / wavelength)
    print("frozen-vertex error over flat ground at 15 m: "
          + ", ".join(f"d={di * 100:.0f} cm: {e * 1e6:.1f} um ({p:.1f} deg)"
                      for di, e, p in zip(d, err, phase_deg, strict=True)))
    assert phase_deg[3] > 10.0                       # 5 cm: clearly not negligible
    # other interaction types keep the frozen-vertex formula
    from raysim.echoes.rt.trace import DIFFUSE

    diffuse = _specular_pathset([0.0, 0.0, H], [0.0, 0.0, 0.0])
    object.__setattr__(diffuse, "kind", np.array([DIFFUSE], np.uint32))
    object.__setattr__(diffuse, "interactions", np.array([[DIFFUSE]], np.uint32))
    np.testing.assert_array_equal(path_lengths(diffuse, times, x, x), frozen[None, None])
    with pytest.raises(ValueError, match="specular"):
        path_lengths(paths, times, x, x, specular="exact")


@pytest.mark.sionna
def test_sionna_ground_return_is_exact_under_motion(warm_kernels):
    """Traced flat-ground specular path, re-projected to a moving, tilted array."""
    from raysim.echoes.rt.reproject import path_lengths, single_bounce_specular
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    scene = load_scene("flat_reflectors", include_targets=False)
    lever = np.array([0.0, 0.0, 0.1])
    motion = hover_jitter(3) + sinusoid("pitch", np.deg2rad(4.0), 3.0) + constant_velocity(
        [0.3, 0.0, 0.0])
    config = RadarConfig(num_chirps=32, idle_time=440e-6)        # 16 ms frame
    paths = MonostaticTracer(diffuse=False, targets=False)(scene, config, Trajectory(), lever)
    spec = single_bounce_specular(paths)
    assert spec.sum() == 1
    times, x_tx, x_rx = _geometry(motion, lever, config)
    got = path_lengths(paths, times, x_tx, x_rx)[spec][0]
    frozen = path_lengths(paths, times, x_tx, x_rx, specular="frozen")[spec][0]
    exact = 2.0 * (scene.hover_altitude - x_tx[..., 2])
    err = np.abs(got - exact).max()
    ferr = np.abs(frozen - exact).max()
    print(f"Sionna ground return: image-method error {err:.2e} m, frozen-vertex error "
          f"{ferr * 1e6:.1f} um ({np.rad2deg(2 * np.pi * ferr / config.wavelength):.2f} deg)")
    assert err < SIONNA_IMAGE_TOL_M
    assert ferr > 1e3 * SIONNA_IMAGE_TOL_M


def test_rotation_only_moves_elements_not_the_image():
    """Pure rotation about the phase centre: the image distance follows each element's height."""
    from raysim.echoes.rt.reproject import path_lengths

    paths = _specular_pathset([0.0, 0.0, H], [0.0, 0.0, 0.0])
    rot = Rotation.from_euler("ZYX", [0.3, 0.05, -0.04]).as_matrix()
    p = np.array([[0.01, 0.0, 0.0], [0.0, 0.01, 0.0], [-0.01, -0.01, 0.0]])
    x = (p @ rot.T)[None]
    got = path_lengths(paths, np.zeros((1, 3)), x, x)[0, 0]
    np.testing.assert_allclose(got, 2 * (H - x[0, :, 2]), rtol=0, atol=IMAGE_LENGTH_TOL_M)
