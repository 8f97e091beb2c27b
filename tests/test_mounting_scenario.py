"""A mounted radar in a scenario file: ``[radar] mounting_deg``, as ``--mounting-deg``.

The mounting ``R_BA`` turns the whole radar frame A (elements, element pattern,
targets given in the nominal radar frame N) about its phase centre; a radar at
rest then sees exactly what a down-looking radar sees of the same target in its
own frame (the delays are distances, unchanged by a rotation), while the target
lies where the mounting points: ahead of the drone for ``forward``.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from raysim.cli import main
from raysim.pipeline.run import evaluate
from raysim.pipeline.sources import frame_source, point_targets, radar_pose
from raysim.scenario import loads_scenario, scenario_from_case

#: Float round-off of a few 3x3 products on metre-size vectors [m].
EXACT_M = 1e-12
#: A rotated copy of the same geometry: delays equal to float64 round-off, the IF samples
#: then rounded to complex64 (relative to the frame's largest sample).
ROTATION_RTOL = 1e-5
#: The map peak's direction within this of the truth [deg]: peak interpolation on the map
#: grid of a 4 x 4 UPA (measured 0.003 deg at rest, 0.012-0.031 deg compensated).
MAP_ANGLE_TOL_DEG = 0.05
#: Pitching platform, chain ``exact`` with a tactical IMU, beams in N: the angle error the
#: compensation leaves [deg] (measured 6e-4 forward, 3e-4 oblique, 5e-4 down; 1.5 deg
#: when the motion is left in W).
EXACT_ANGLE_TOL_DEG = 0.01

SCENARIO = """
name = "mounted"
frames = 1
seed = 0
lever_arm_m = [0.1, -0.05, 0.05]

[radar]
num_chirps = 32
{mount}

[array]
kind = "upa"
nx = 4
ny = 4

[[scene.targets]]
range_m = 15.0
az_deg = 20.0
el_deg = -10.0
{motion}
[imu]
preset = "tactical"
rate_hz = 2000.0
"""
PITCH = '\n[motion]\ncase = "rotation_y"\n'


def _scenario(mount=None, motion=""):
    return loads_scenario(SCENARIO.format(
        mount="" if mount is None else f"mounting_deg = {json.dumps(mount)}", motion=motion))


def test_mounting_key_is_validated_and_named():
    assert _scenario("Forward").radar.mounting_deg == "forward"
    assert _scenario([90, 0, 45]).radar.mounting_deg == (90.0, 0.0, 45.0)
    assert _scenario("10,-5,3").radar.mounting_deg == (10.0, -5.0, 3.0)
    for bad in ("sideways", [1, 2], [1, 2, 3, 4], 7):
        with pytest.raises(ValueError, match=r"radar\.mounting_deg: got .*expected one of"):
            _scenario(bad)
    with pytest.raises(ValueError, match="did you mean 'forward'"):
        _scenario("froward")
    # a mounting is written back and read again the same
    s = _scenario("oblique")
    assert loads_scenario(s.to_toml()).radar.mounting_deg == "oblique"


def test_default_mounting_leaves_scenarios_as_they_were():
    """No key (every paper case), ``down`` and ``[0, 0, 0]``: the same radar pose objects,
    the same stored scenario key and bit-identical frames."""
    for name in ("rotation_y", "yaw"):
        case = scenario_from_case(name)
        assert case.radar.mounting_deg is None and "mounting_deg" not in case.to_json()
        traj = case.trajectory()
        t, lever = radar_pose(case, traj)
        assert t is traj and np.array_equal(lever, case.lever_arm)
    ref = frame_source(_scenario(motion=PITCH))(0)
    for mount in ("down", [0, 0, 0]):
        frame = frame_source(_scenario(mount, PITCH))(0)
        assert np.array_equal(frame.data, ref.data)
        assert np.array_equal(frame.lever_arm, ref.lever_arm)


def test_forward_radar_sees_the_target_ahead_at_its_range_and_angle():
    s = _scenario("forward")
    az, el, r = math.radians(20.0), math.radians(-10.0), 15.0
    # forward: boresight +x_B, azimuth towards +y_B (right), elevation towards +z_B (down)
    ahead = s.lever_arm + r * np.array([math.cos(el) * math.cos(az),
                                        math.cos(el) * math.sin(az), math.sin(el)])
    assert np.max(np.abs(point_targets(s)[0].position - ahead)) < EXACT_M
    # at rest it sees in its own frame what a down-looking radar sees of the same target
    fwd, down = frame_source(s)(0), frame_source(_scenario())(0)
    assert np.max(np.abs(fwd.data - down.data)) <= ROTATION_RTOL * np.abs(down.data).max()
    assert np.array_equal(fwd.lever_arm, s.lever_arm)          # the frame keeps r_IR in B
    m = evaluate(s, chains=["none"])["chains"]["none"]        # range within a tenth of a cell
    assert abs(m["range_m"] - r) <= 0.1 * s.radar_config().range_resolution
    assert m["map_angle_error_deg"] <= MAP_ANGLE_TOL_DEG


@pytest.mark.parametrize("mount", ["forward", "oblique"])
def test_mounted_radar_on_a_pitching_drone_is_compensated_in_its_frame(mount):
    """The rotation_y case turns a forward radar about its azimuth axis (not its
    elevation axis, as for the down-looking one): the motion estimate in N undoes it."""
    s = _scenario(mount, PITCH)
    res = evaluate(s, chains=["none", "exact"])["chains"]
    down = evaluate(_scenario(None, PITCH), chains=["none"])["chains"]["none"]
    assert res["none"]["map_angle_error_deg"] != down["map_angle_error_deg"]
    assert res["exact"]["angle_error_deg"] <= EXACT_ANGLE_TOL_DEG
    assert res["exact"]["map_angle_error_deg"] <= MAP_ANGLE_TOL_DEG


def test_scene_report_of_a_forward_scenario(tmp_path, capsys):
    """`scene-report --scenario` with a forward mounting runs and measures the point target
    as `raysim simulate` does."""
    path = tmp_path / "fwd.toml"
    path.write_text(SCENARIO.format(mount='mounting_deg = "forward"', motion=PITCH))
    out = tmp_path / "report"
    assert main(["scene-report", "--scenario", str(path), "--quick", "--chains", "none,exact",
                 "--out", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    assert main(["simulate", "--scenario", str(path), "--chains", "none,exact", "--json"]) == 0
    simulated = json.loads(capsys.readouterr().out)
    report = json.loads((out / "mounted.json").read_text())
    assert report["settings"]["scenario"]["radar"]["mounting_deg"] == "forward"
    points = report["point_metrics"]["metrics"]
    for chain in ("none", "exact"):
        assert points[chain]["angle_error_deg"] == pytest.approx(
            simulated["chains"][chain]["angle_error_deg"], abs=1e-12)
    assert points["exact"]["angle_error_deg"] <= EXACT_ANGLE_TOL_DEG


#: A compensated target's beam held still over slow time: ``|mean| / mean |.|`` of its
#: samples at least this (measured 0.999995); with the wrong mounting at most
#: :data:`SMEARED` (measured 0.002).
COHERENT = 0.9999
SMEARED = 0.5


def test_rendered_store_is_compensated_with_its_mounting(tmp_path, capsys):
    """`raysim render` records the scenario's mounting in the store; `raysim compensate`
    of the store takes it unless told otherwise."""
    import zarr

    path = tmp_path / "fwd.toml"
    path.write_text(SCENARIO.format(mount='mounting_deg = "forward"', motion=PITCH))
    store = tmp_path / "s.zarr"
    assert main(["render", str(path), "--out", str(store), "--no-progress"]) == 0
    assert zarr.open_group(str(store), mode="r").attrs["mounting_deg"] == [90.0, 0.0, 90.0]
    cells = ["--range-m", "14.6:15.4", "--az-deg", "20:20:1", "--el-deg", "-10:-10:1",
             "--velocity", "given", "--initial-velocity", "0,0,0"]
    stillness = {}
    for name, extra in (("store", []), ("down", ["--mounting-deg", "down"])):
        out = tmp_path / f"{name}.npz"
        assert main(["compensate", str(store), "--out", str(out), *cells, *extra]) == 0
        with np.load(out) as z:
            b = z["beams"]                                   # [chirp, range, az, el]
        slow = b[:, int(np.argmax(np.abs(b).sum(axis=(0, 2, 3)))), 0, 0]
        stillness[name] = np.abs(slow.mean()) / np.abs(slow).mean()
    capsys.readouterr()
    assert stillness["store"] >= COHERENT and stillness["down"] <= SMEARED


def test_coverage_spans_are_in_the_mounted_radar_frame():
    """The reflector under the radar: straight down is 45 deg elevation for ``oblique``."""
    from raysim.studies.scene_report.coverage import object_spans

    for mount, el in (("down", 0.0), ("oblique", 45.0)):
        s = loads_scenario(f'[radar]\nmounting_deg = "{mount}"\n'
                           f'[scene]\nname = "flat_reflectors"\n')
        nadir = next(o for o in object_spans(s) if o["name"] == "cr-nadir")
        assert np.allclose(nadir["el_deg"], el, atol=1e-9)
        assert np.allclose(nadir["az_deg"], 0.0, atol=1e-9)
