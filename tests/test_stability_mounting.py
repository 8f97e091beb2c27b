"""Stability points of a mounted radar (``mounting_deg``): closed forms and the down radar.

Tiers: formula (a constant body rotation seen by any mounting: the angle of
Rodrigues' rotation of the target's body direction), cross-model (a forward
radar under a body rotation about one axis measures what the down radar
measures under the same rotation about the turned axis ``R_BA^T a``, the
whole motion turned by ``R_BA^T``), and the default mounting's gate and motion
(those of the body, untouched).
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from raysim.platform.motion import Ramp, Trajectory, sinusoid
from raysim.platform.mounting import mounting_matrix
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig
from raysim.studies.stability import StabilityPoint, evaluate, point_gate, point_motion
from raysim.studies.stability.metrics import MAP_CHAINS

#: Agreement of an interpolated beam-scan peak with a closed-form direction [deg]: a tenth
#: of the 0.1 deg fine-scan step of ``angle_error_worst_deg``.
PEAK_TOL_DEG = 0.01
#: Agreement of the metrics of two equivalent points: their gates are equal to rounding;
#: the navigation solutions differ by the strapdown's integration error (gravity lies
#: along other body axes) and the beams are complex64.
EQUIVALENT_RTOL, EQUIVALENT_ATOL = 1e-4, 1e-6
#: Residual of the exact chain under a constant attitude [deg] and [m/s] (float32 beams).
EXACT_ANGLE_TOL_DEG, EXACT_VELOCITY_TOL_MPS = 0.01, 1e-4

AXES = {"roll": 0, "pitch": 1, "yaw": 2}


def _radar(n: int = 8, num_chirps: int = 64) -> tuple[RadarConfig, object]:
    cfg = RadarConfig(num_chirps=num_chirps)
    return cfg, upa(n, n, wavelength=cfg.wavelength)


@pytest.mark.parametrize("mounting", ["down", "forward", "oblique", (30.0, 20.0, -10.0)])
@pytest.mark.parametrize("axis", ["roll", "pitch", "yaw"])
def test_constant_rotation_of_a_mounted_radar_matches_rodrigues(mounting, axis):
    """A constant body rotation ``psi`` about axis ``a`` (B) moves the target seen by the
    uncompensated radar by ``arccos(cos psi + (1 - cos psi) (a . v)^2)``, ``v = R_BA u``
    its nominal direction in B (Rodrigues); the exact chain removes it."""
    cfg, arr = _radar()
    psi, az, el = np.deg2rad(10.0), 30.0, 10.0
    point = StabilityPoint(cfg, arr, Trajectory((Ramp(axis, psi),)), 15.0, az, el,
                           lever_arm_m=(0.0, 0.0, 0.0), mounting_deg=mounting)
    res = evaluate(point, ("none", "exact"), coherent_map=False)
    v = mounting_matrix(mounting) @ point.direction
    a_dot_v = v[AXES[axis]]
    expected = np.rad2deg(np.arccos(np.cos(psi) + (1 - np.cos(psi)) * a_dot_v ** 2))
    assert res["none"]["angle_error_worst_deg"] == pytest.approx(expected, abs=PEAK_TOL_DEG)
    assert res["exact"]["angle_error_worst_deg"] < EXACT_ANGLE_TOL_DEG
    assert abs(res["exact"]["pseudo_velocity_mps"]) < EXACT_VELOCITY_TOL_MPS


def test_roll_about_a_forward_boresight_leaves_a_boresight_target_in_place():
    """The forward radar's boresight is the body's x axis: a roll turns the image about the
    target on boresight (no error), where the down radar sees the full roll."""
    cfg, arr = _radar()
    traj = Trajectory((Ramp("roll", np.deg2rad(10.0)),))
    res = {m: evaluate(StabilityPoint(cfg, arr, traj, 15.0, 0.0, 0.0, lever_arm_m=(0, 0, 0),
                                      mounting_deg=m), ("none",), coherent_map=False)["none"]
           for m in ("forward", "down")}
    assert res["forward"]["angle_error_worst_deg"] < PEAK_TOL_DEG
    assert res["down"]["angle_error_worst_deg"] == pytest.approx(10.0, abs=PEAK_TOL_DEG)


# forward mounting R_BA: x_A -> y_B, y_A -> z_B, z_A (boresight) -> x_B; a body rotation
# about axis a is the down radar's rotation about R_BA^T a
FORWARD_EQUIVALENT = [("pitch", "roll"), ("roll", "yaw"), ("yaw", "pitch")]


@pytest.mark.parametrize("body_axis, down_axis", FORWARD_EQUIVALENT,
                         ids=[f"{a}-{b}" for a, b in FORWARD_EQUIVALENT])
def test_forward_radar_measures_what_the_down_radar_measures_turned(body_axis, down_axis):
    """Forward radar, 10 deg at 20 Hz about one body axis, lever arm ``r``: every metric of
    every chain equals the down radar's under the same oscillation about ``R_BA^T a`` with
    lever arm ``R_BA^T r`` (the geometry turned by ``R_BA^T``: equal distances, equal
    directions in A)."""
    cfg, arr = _radar()
    m = mounting_matrix("forward")
    assert np.allclose(m.T @ np.eye(3)[AXES[body_axis]], np.eye(3)[AXES[down_axis]])
    lever = np.array([0.02, -0.01, 0.10])
    fwd = StabilityPoint(cfg, arr, sinusoid(body_axis, np.deg2rad(10.0), 20.0), 15.0, 20.0,
                         10.0, lever_arm_m=lever, mounting_deg="forward")
    down = StabilityPoint(cfg, arr, sinusoid(down_axis, np.deg2rad(10.0), 20.0), 15.0, 20.0,
                          10.0, lever_arm_m=m.T @ lever)
    a, b = evaluate(fwd, MAP_CHAINS), evaluate(down, MAP_CHAINS)
    assert a["none"]["angle_error_worst_deg"] > 1.0           # the motion matters here
    for chain in MAP_CHAINS:
        assert a[chain] == pytest.approx(b[chain], rel=EQUIVALENT_RTOL, abs=EQUIVALENT_ATOL), \
            chain
    gate_fwd, gate_down = point_gate(fwd)[0], point_gate(down)[0]
    assert np.max(np.abs(gate_fwd - gate_down)) < EQUIVALENT_RTOL * np.max(np.abs(gate_down))


def test_default_mounting_keeps_the_body_gate_and_motion():
    """``down`` (by name, by angles or left out) takes no turn: the gate of the body's own
    trajectory and lever arm, the navigation solution of the body, bit for bit."""
    from raysim.echoes.oracle import PointTarget
    from raysim.pipeline.estimate import estimate_motion
    from raysim.pipeline.sources import gated_source
    from raysim.studies.stability.motion import point_imu_record

    cfg, arr = _radar(n=4, num_chirps=16)
    traj = sinusoid("pitch", np.deg2rad(8.0), 20.0) + sinusoid("z", 0.02, 5.0)
    base = StabilityPoint(cfg, arr, traj, 15.0, 20.0, 5.0)
    gate = gated_source(cfg, arr, traj, [PointTarget.at(15.0, np.deg2rad(20.0),
                                                        np.deg2rad(5.0),
                                                        radar_origin=base.lever_arm_m)],
                        range_m=15.0, lever_arm=base.lever_arm_m)[0]
    t = base.chirp_times()
    motion = estimate_motion(*point_imu_record(base, t).to_arrays(), t,
                             lever_arm=base.lever_arm_m, trajectory=traj, time_offset=0.0,
                             velocity="given")
    for value in ("down", (0.0, 0.0, 0.0), "0,0,0"):
        p = base.with_(mounting_deg=value)
        assert p.mounting_deg == (0.0, 0.0, 0.0) and not p.mounted
        assert np.array_equal(point_gate(p)[0], gate)
        mine = point_motion(p, t)
        assert np.array_equal(mine.attitude, motion.attitude)
        assert np.array_equal(mine.position, motion.position)


def test_mounted_point_from_toml_scenario():
    """``[radar] mounting_deg`` of a scenario reaches the point: the same metrics as the
    direct build, the target along ``R_BA u(az, el)`` from the phase centre."""
    from raysim.platform.mounting import nominal_target_position
    from raysim.scenario import loads_scenario

    scn = loads_scenario("""
        lever_arm_m = [0.0, 0.0, 0.10]
        [radar]
        num_chirps = 64
        mounting_deg = "oblique"
        [array]
        nx = 8
        ny = 8
        [[scene.targets]]
        range_m = 15.0
        az_deg = 20.0
        el_deg = 5.0
        [[motion.sinusoids]]
        axis = "pitch"
        amplitude_deg = 10.0
        frequency_hz = 20.0
        [imu]
        preset = "ideal"
        rate_hz = 2000.0
    """)
    p = StabilityPoint.from_scenario(scn)
    cfg, arr = _radar()
    direct = StabilityPoint(cfg, arr, sinusoid("pitch", np.deg2rad(10.0), 20.0), 15.0, 20.0,
                            5.0, seed=scn.imu_seed, mounting_deg=(90.0, 0.0, 45.0))
    assert p.mounting_deg == (90.0, 0.0, 45.0) and p.mounted
    assert np.array_equal(p.target.position, nominal_target_position(
        15.0, np.deg2rad(20.0), np.deg2rad(5.0), (0.0, 0.0, 0.10), "oblique"))
    a = evaluate(p, ("none", "exact"), coherent_map=False)
    b = evaluate(direct, ("none", "exact"), coherent_map=False)
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
    assert a["exact"]["angle_error_worst_deg"] < EXACT_ANGLE_TOL_DEG


# --------------------------------------------------------------- the maps and the command
def _recording(seen: list):
    """Stand-in for ``stability.evaluate`` that records each point's mounting."""
    from raysim.studies.stability import STABILITY_METRICS

    def evaluate_stub(point, chains=MAP_CHAINS, **_):
        seen.append(point.mounting_deg)
        out = {c: {m: 0.0 for m in STABILITY_METRICS} for c in chains}
        out["warnings"], out["strapdown"] = [], "stub"
        return out

    return evaluate_stub


def test_maps_and_command_take_the_mounting(tmp_path, monkeypatch):
    """``--mounting-deg`` reaches every point of every map; a map or point record of one
    mounting is not reused for another."""
    from raysim.cli import main
    from raysim.studies.stability import read_netcdf
    from raysim.studies.stability import runner as stability_runner

    seen: list = []
    monkeypatch.setattr(stability_runner, "evaluate", _recording(seen))
    args = ["stability", "--out", str(tmp_path), "--quick", "--no-progress", "--executor",
            "serial", "--maps", "clock"]
    assert main(args + ["--mounting-deg", "forward"]) == 0
    n = len(seen)
    assert n > 0 and set(seen) == {(90.0, 0.0, 90.0)}
    assert json.loads((tmp_path / "summary.json").read_text())["clock"]["mounting_deg"] == \
        [90.0, 0.0, 90.0]
    assert json.loads(read_netcdf(tmp_path / "clock.nc").attrs["mounting_deg"]) == \
        [90.0, 0.0, 90.0]
    assert main(args + ["--mounting-deg", "90,0,90"]) == 0        # the same map: reused
    assert len(seen) == n
    assert main(args) == 0                                          # down: computed again
    assert len(seen) == 2 * n and set(seen[n:]) == {(0.0, 0.0, 0.0)}
    assert json.loads((tmp_path / "summary.json").read_text())["clock"]["mounting_deg"] == \
        [0.0, 0.0, 0.0]
