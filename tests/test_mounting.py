"""Radar mounting R_BA (raysim.platform.mounting): presets, parsing, and the frame algebra.

The mounted motion must place every element where the simulation places it, expressed
in the nominal radar frame N: ``M^T (T + R_WB (r_IR + M p))`` for ``M = R_BA``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.strapdown import PlatformMotion
from raysim.platform.mounting import (
    MOUNTING_PRESETS,
    mount_array,
    mount_motion,
    mount_trajectory,
    mounting_deg,
    mounting_matrix,
)
from raysim.radar.arrays import ti_3tx4rx

#: Float round-off of a few 3x3 products on metre-size vectors [m].
EXACT_M = 1e-12


def test_presets_point_the_boresight_where_named():
    z = np.array([0.0, 0.0, 1.0])
    assert np.allclose(mounting_matrix("down") @ z, [0, 0, 1], atol=EXACT_M)
    assert np.allclose(mounting_matrix("forward") @ z, [1, 0, 0], atol=EXACT_M)
    s = np.sqrt(0.5)
    assert np.allclose(mounting_matrix("oblique") @ z, [s, 0, s], atol=EXACT_M)
    # forward and oblique keep azimuth (+x_A) horizontal, to the right
    for name in ("forward", "oblique"):
        assert np.allclose(mounting_matrix(name) @ [1, 0, 0], [0, 1, 0], atol=EXACT_M)
    assert mounting_deg(None) == MOUNTING_PRESETS["down"]
    assert mounting_deg("10,-5,3") == (10.0, -5.0, 3.0)


@pytest.mark.parametrize("bad", ["sideways", "1,2", "1,2,nan", (1, 2, 3, 4), "a,b,c"])
def test_bad_mounting_is_named(bad):
    with pytest.raises(ValueError, match="--mounting-deg"):
        mounting_deg(bad)


def test_mounted_motion_places_the_elements_as_the_simulation_does():
    rng = np.random.default_rng(3)
    n = 5
    att = Rotation.from_euler("ZYX", rng.normal(0, 0.2, (n, 3))).as_matrix()
    motion = PlatformMotion(np.arange(n) * 1e-4, att, rng.normal(0, 0.1, (n, 3)),
                            rng.normal(0, 0.5, (n, 3)), rng.normal(0, 1.0, (n, 3)),
                            np.array([0.1, -0.02, 0.05]))
    mount = (30.0, -20.0, 70.0)
    m = mounting_matrix(mount)
    arr = ti_3tx4rx(3.9e-3)
    p = arr.virtual_positions / 2                             # [channel, 3] in A
    world = (motion.position[:, None] + np.einsum(
        "nij,cj->nci", motion.attitude, motion.lever_arm + p @ m.T))   # simulation
    mm = mount_motion(motion, mount)
    in_n = mm.position[:, None] + np.einsum("nij,cj->nci", mm.attitude, mm.lever_arm + p)
    assert np.max(np.abs(in_n - world @ m)) < EXACT_M          # M^T x_W
    assert np.allclose(mount_array(arr, mount).tx_positions, arr.tx_positions @ m.T)
    assert mount_motion(motion, "down") is motion and mount_array(arr, None) is arr


def test_radar_frame_trajectory_places_the_elements_as_the_mounted_array():
    """The radar frame's own pose (attitude ``R_WB R_BA``, lever arm ``R_BA^T r_IR``) puts
    every element where ``T + R_WB (r_IR + R_BA p)`` does, and turns the rates into A."""
    from raysim.platform.kinematics import element_world_positions
    from raysim.platform.motion import hover_jitter

    body, lever = hover_jitter(1), np.array([0.1, -0.02, 0.05])
    mount = (30.0, -20.0, 70.0)
    m = mounting_matrix(mount)
    arr = ti_3tx4rx(3.9e-3)
    radar, lever_a = mount_trajectory(body, lever, mount)
    t = np.linspace(0.0, 0.1, 7)[:, None] * np.ones((1, arr.num_channels))
    p = arr.virtual_positions / 2
    got = element_world_positions(radar, t, p, lever_a)
    want = element_world_positions(body, t, p @ m.T, lever)
    assert np.max(np.abs(got - want)) < EXACT_M
    tt = t[:, 0]
    assert np.allclose(radar.attitude(tt).as_matrix(), body.attitude(tt).as_matrix() @ m,
                       atol=EXACT_M)
    assert np.allclose(radar.angular_rate(tt), body.angular_rate(tt) @ m, atol=EXACT_M)
    assert np.array_equal(radar.position(tt), body.position(tt))      # the body origin's
    same, same_lever = mount_trajectory(body, lever, "down")
    assert same is body and same_lever is lever
