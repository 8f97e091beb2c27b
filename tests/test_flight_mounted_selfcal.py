"""Self-calibration of a mounted radar: a forward and an oblique flight in ground clutter,
each compensated by one ``raysim compensate --velocity radar --time-offset auto
--mounting-deg ...``.

The scatterers are found and their beams formed in the radar's nominal frame N, their
directions turned into W by ``R_BA`` for the Doppler model, whose radar velocity and lever
arm are the body's (:mod:`compensation.mounting`); the ground plane is fitted in W.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from compensation import PlatformMotion
from compensation.mounting import mounting_rotation, radar_frame_motion, world_directions
from raysim.cli import main
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import measure_targets, write_flight
from raysim.platform.mounting import mount_motion, mounting_matrix

#: Clock offset of the flights (IMU minus radar) [s], and the bound on its estimate [s].
TIME_OFFSET = 0.003
OFFSET_TOL_S = 0.5e-3
#: The estimated initial velocity lies within this many of its stated sigmas of the truth.
VELOCITY_SIGMAS = 3.0
#: Every target in every frame: beam angle error [deg] and residual pseudo-velocity
#: [Doppler bins] (measured: oblique 0.02 deg, 0.035 bin).
ANGLE_TOL_DEG = 0.2
PSEUDO_VELOCITY_BINS = 0.05
#: The ground plane's tilt correction of the given (true) attitude lies within this many
#: of its stated sigmas of zero.
TILT_SIGMAS = 3.0
#: Mountings whose beams miss the bounds, with the figures measured (worst target and
#: frame; seed 1 here, seeds 2-4 by hand): the forward radar 3 m over the ground. Not its
#: mounting nor its IMU attitude (tests/test_flight_mounted_chain.py), but two limits of
#: the scene. The ground lies in the first target's range cell 36 deg below it, which the
#: array hardly separates in elevation: with the true motion that target misses by
#: 0.25 deg (seed 1). The three targets lie in a narrow cone ahead, so the self-calibrated
#: velocity across it stays uncertain and its error moves their azimuth while the drone
#: drifts across the beams (:mod:`compensation.azimuth_shift`): seeds 3 and 4 miss by
#: 0.71 and 0.57 deg, which the stage warns of (0.73 and 0.65 deg).
ANGLE_GAPS = {"forward": "forward radar 3 m up: ground clutter in a target's range cell "
                         "(0.25 deg with the true motion) and the velocity across its narrow "
                         "cone of targets (warned): 0.30 deg seed 1 (0.10, 0.71, 0.57 deg "
                         "seeds 2-4)"}
#: Stationary targets (range [m], azimuth [deg], elevation [deg] in N), spread in both.
TARGETS = [(6.0, -20.0, -6.0), (7.5, 18.0, 6.0), (9.0, 2.0, -12.0)]
#: Rounding of a rotation of a motion [m, m/s, 1].
EXACT = 1e-12


def test_radar_frame_motion_is_the_mounting_of_raysim():
    """The transform to N (raysim's ``mount_motion`` is it) puts every element
    ``T + R_WB (r_IR + R_BA p)`` at ``R_BA^T`` times its world position; directions of N
    turn back into W by ``R_BA``; a matrix that is no rotation is refused, named."""
    rng = np.random.default_rng(3)
    from scipy.spatial.transform import Rotation

    n = 5
    m = PlatformMotion(np.arange(n) * 1e-3, Rotation.random(n, random_state=4).as_matrix(),
                       rng.normal(size=(n, 3)), rng.normal(size=(n, 3)),
                       rng.normal(size=(n, 3)), np.array([0.03, -0.02, 0.1]))
    for mount in ("forward", "oblique", (10.0, -5.0, 30.0)):
        r = mounting_matrix(mount)
        a = radar_frame_motion(m, r)
        assert mount_motion(m, mount).attitude is not m.attitude
        assert np.allclose(mount_motion(m, mount).attitude, a.attitude, atol=EXACT)
        p = rng.normal(size=3) * 0.01                      # an element in A [m]
        world = m.position + np.einsum("nij,j->ni", m.attitude, m.lever_arm + r @ p)
        in_n = a.position + np.einsum("nij,j->ni", a.attitude, a.lever_arm + p)
        assert np.allclose(in_n, world @ r, atol=EXACT)    # R_BA^T x, rows
        # the radar's velocity along a direction is the same in N and in W
        u_n = rng.normal(size=(n, 3))
        u_w = world_directions(u_n, r)
        assert np.allclose(np.einsum("ij,ij->i", a.radar_velocity, u_n),
                           np.einsum("ij,ij->i", m.radar_velocity, u_w), atol=EXACT)
    assert radar_frame_motion(m, None) is m and mounting_rotation(np.eye(3)) is None
    with pytest.raises(ValueError, match="mounting"):
        mounting_rotation(np.diag([1.0, 1.0, -1.0]))


@pytest.mark.parametrize("mount, altitude", [("forward", 3.0), ("oblique", 10.0)])
def test_mounted_flight_self_calibrated_in_one_command(tmp_path, capsys, mount, altitude):
    """Consumer MEMS IMU 3 ms late, unknown velocity, the flight controller's attitude:
    the offset, the velocity and every target's beam as for a down-looking radar. The
    oblique radar at 10 m sees the ground beyond the targets' cells: its plane, fitted in
    W, agrees with the given attitude."""
    flight = write_flight(tmp_path / "f", frames=2, targets=TARGETS, mounting_deg=mount,
                          time_offset=TIME_OFFSET, seed=1, clutter_scene="flat_reflectors",
                          clutter_altitude=altitude, clutter_max_scatterers=300)
    out = tmp_path / "c.zarr"
    args = flight.calibrating_command(out, "--range-m", "5.5:9.5", "--az-deg", "-30:30:0.5",
                                      "--el-deg", "-12:6:6", "--no-progress")
    assert "--mounting-deg" in args and "--initial-velocity" not in args
    assert args[args.index("--time-offset") + 1] == "auto"
    assert main(args) == 0
    assert "time offset" in capsys.readouterr().out
    ds = open_store(out)
    assert abs(ds.attrs["time_offset_s"] - TIME_OFFSET) <= OFFSET_TOL_S
    cal = json.loads(ds.attrs["self_calibration"])
    assert cal["scatterers"] >= len(TARGETS)
    v = np.array(cal["initial_velocity_mps"])
    sigma = np.array(cal["initial_velocity_sigma_mps"])
    assert not {"velocity_n", "velocity_e", "velocity_d"} & set(cal["unconstrained"])
    assert np.all(np.abs(v - flight.initial_velocity[0]) <= VELOCITY_SIGMAS * sigma), (
        v, flight.initial_velocity[0], sigma)
    m = measure_targets(out, flight)                          # [target, frame, metric]
    assert m.shape[:2] == (len(TARGETS), 2)
    if mount == "oblique":
        g = cal["ground_plane"]
        assert g["used"] and g["role"] == "check of the given attitude"
        assert np.all(np.abs(g["tilt_deg"]) <= TILT_SIGMAS * np.array(g["tilt_sigma_deg"]))
    within = (np.all(m[..., 0] <= ANGLE_TOL_DEG)
              and np.all(np.abs(m[..., 1]) <= PSEUDO_VELOCITY_BINS))
    if mount in ANGLE_GAPS:                  # recorded, and noticed when it closes
        assert not within, f"{mount} now within the bounds: drop it from ANGLE_GAPS"
        pytest.xfail(ANGLE_GAPS[mount])
    assert np.all(m[..., 0] <= ANGLE_TOL_DEG), m[..., 0]
    assert np.all(np.abs(m[..., 1]) <= PSEUDO_VELOCITY_BINS), m[..., 1]
