"""Stability maps: the range-gate shortcut, the chains, the failure boundaries, the command.

Tiers: formula (closed-form range gate vs the full IF synthesis and range FFT),
cross-model (the re-derived chains vs the ``compensation`` package on full
cubes), system (boundary points: a point inside the measured boundary passes
the criterion, a point outside fails it), and the one command that writes
every map.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from raysim.echoes.oracle import simulate_point_targets
from raysim.platform.motion import sinusoid, stationary
from raysim.processing.maps import range_compress
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig
from raysim.studies import stability
from raysim.studies.stability import (
    MAPS,
    Criteria,
    PoseEstimate,
    Scenario,
    chain_corrections,
    compensated_slow_time,
    criteria_for,
    evaluate,
    fails,
    gated_cube,
)

#: Relative agreement of the closed-form gate and the complex64 synthesis + FFT.
GATE_RTOL = 1e-5
#: Normalised correlation required between two implementations of one chain.
CHAIN_CORRELATION = 0.9999


def _small(num_chirps=64, n=8) -> tuple[RadarConfig, object]:
    cfg = RadarConfig(num_chirps=num_chirps)
    return cfg, upa(n, n, wavelength=cfg.wavelength)


def _truth_pose(scn: Scenario) -> PoseEstimate:
    t = scn.config.chirp_times(0, scn.t0)
    q, _, _ = scn.trajectory.states(t)
    att = Rotation.from_euler("ZYX", q[:, [5, 4, 3]]).as_matrix()
    return PoseEstimate(att, q[:, :3], scn.trajectory.angular_rate(t), "truth")


# ---------------------------------------------------------------- formula tier
def test_gate_equals_range_fft_of_synthesised_if():
    cfg, arr = _small(num_chirps=16, n=4)
    scn = Scenario(cfg, arr, sinusoid("pitch", np.deg2rad(10), 20.0), 15.3, 0.3, -0.2)
    gate, k = gated_cube(scn)
    frame = simulate_point_targets(cfg, arr, [scn.target], scn.trajectory,
                                   lever_arm=scn.lever_arm)
    ref = range_compress(frame.data)[:, :, k]
    assert k == int(np.argmin(np.abs(cfg.range_axis() - 15.3)))
    assert np.max(np.abs(gate - ref)) < GATE_RTOL * np.max(np.abs(ref))


def test_criteria_of_paper_radar():
    cfg = RadarConfig()
    crit = criteria_for(cfg, upa(20, 20, wavelength=cfg.wavelength))
    assert crit.velocity_bin == pytest.approx(cfg.center_wavelength / (2 * 256 * 60e-6))
    assert crit.doppler_bin_hz == pytest.approx(1 / (256 * 60e-6))
    # 0.886 lambda_c / (20 * lambda / 2) rad, halved
    half = 0.5 * np.rad2deg(0.886 * cfg.center_wavelength / (10 * cfg.wavelength))
    assert crit.half_beamwidth_deg == pytest.approx(half, rel=1e-9)
    c = Criteria(0.1, 60.0, 2.0)
    assert not fails({"pseudo_velocity": -0.09, "angle_error_deg": 1.9}, c)
    assert fails({"pseudo_velocity": -0.11, "angle_error_deg": 0.0}, c)
    assert fails({"pseudo_velocity": 0.0, "angle_error_deg": 2.1}, c)


def test_stationary_platform_restores_hann_width():
    cfg, arr = _small()
    res = evaluate(Scenario(cfg, arr, stationary(), 15.0, 0.3, 0.1), ("none", "exact"))
    for chain in ("none", "exact"):
        assert abs(res[chain]["pseudo_velocity"]) < 1e-6
        assert res[chain]["doppler_width_hz"] / cfg.doppler_resolution == pytest.approx(
            1.44, abs=0.01)
        assert res[chain]["angle_error_deg"] < 0.05


# ------------------------------------------------------------ cross-model tier
@pytest.mark.parametrize("chain, phase", [("paper", "published"),
                                          ("paper_integrated", "integrated")])
def test_paper_chains_match_compensation_package(chain, phase):
    comp = pytest.importorskip("compensation")
    cfg, arr = _small()
    r_gate = float(cfg.range_axis()[100])
    traj = sinusoid("pitch", np.deg2rad(8), 20.0) + sinusoid("yaw", np.deg2rad(5), 10.0) \
        + sinusoid("z", 0.03, 5.0)
    scn = Scenario(cfg, arr, traj, r_gate, np.deg2rad(20), np.deg2rad(10))
    pose = _truth_pose(scn)
    mine = compensated_slow_time(scn, chain, pose)
    motion = comp.PlatformMotion(scn.config.chirp_times(), pose.attitude, pose.position,
                                 np.zeros_like(pose.position), pose.omega, scn.lever_arm)
    rc = range_compress(simulate_point_targets(cfg, arr, [scn.target], traj,
                                               lever_arm=scn.lever_arm).data)
    beams = comp.paper_chain(rc, arr.virtual_positions, motion,
                             wavelength=cfg.center_wavelength, direction=scn.direction,
                             range_axis=cfg.range_axis(), azimuth=[scn.target_az],
                             elevation=[scn.target_el], range_gates=[100],
                             rotation_phase=phase)
    theirs = np.asarray(beams.data)[:, 0, 0, 0]
    corr = abs(np.vdot(mine, theirs)) / (np.linalg.norm(mine) * np.linalg.norm(theirs))
    assert corr > CHAIN_CORRELATION
    assert np.linalg.norm(theirs) == pytest.approx(np.linalg.norm(mine), rel=1e-3)


def test_exact_chain_matches_rigid_body_projection():
    comp = pytest.importorskip("compensation")
    cfg, arr = _small()
    r_gate = float(cfg.range_axis()[100])
    traj = sinusoid("pitch", np.deg2rad(15), 20.0) + sinusoid("roll", np.deg2rad(10), 7.0) \
        + sinusoid("y", 0.05, 5.0)
    scn = Scenario(cfg, arr, traj, r_gate, np.deg2rad(30), np.deg2rad(-20))
    pose = _truth_pose(scn)
    mine = compensated_slow_time(scn, "exact", pose)
    motion = comp.PlatformMotion(scn.config.chirp_times(), pose.attitude, pose.position,
                                 np.zeros_like(pose.position), pose.omega, scn.lever_arm)
    rc = range_compress(simulate_point_targets(cfg, arr, [scn.target], traj,
                                               lever_arm=scn.lever_arm).data)
    beams = comp.rigid_body_projection(rc, arr.virtual_positions, motion,
                                       wavelength=cfg.center_wavelength,
                                       range_axis=cfg.range_axis(), azimuth=[scn.target_az],
                                       elevation=[scn.target_el], range_gates=[100])
    theirs = np.asarray(beams.data)[:, 0, 0, 0]
    corr = abs(np.vdot(mine, theirs)) / (np.linalg.norm(mine) * np.linalg.norm(theirs))
    assert corr > CHAIN_CORRELATION
    # both restore a constant slow-time sequence (static target, exact chain)
    assert np.std(np.angle(mine * np.conj(mine[0]))) < 0.02


def test_reference_strapdown_agrees_with_compensation_strapdown():
    pytest.importorskip("compensation")
    cfg, arr = _small()
    scn = Scenario(cfg, arr, sinusoid("pitch", np.deg2rad(10), 20.0) + sinusoid("z", 0.05, 5.0),
                   15.0, np.deg2rad(20))
    t = cfg.chirp_times()
    a = stability.estimate_pose(scn, t, strapdown="compensation")
    b = stability.estimate_pose(scn, t, strapdown="reference")
    truth = _truth_pose(scn)
    lam = cfg.center_wavelength
    for est in (a, b):
        rot_err = Rotation.from_matrix(est.attitude) * Rotation.from_matrix(truth.attitude).inv()
        assert np.max(rot_err.magnitude()) < 1e-4                      # rad
        assert np.max(np.abs(est.position - truth.position)) < lam / 100  # phase < 0.13 rad


def test_paper_tilt_correction_matches_closed_form_bias():
    """The small-angle tilt leaves a bias dbeta (1 - cos az) / cos az in azimuth."""
    cfg, arr = _small(n=20)
    rot, az = np.deg2rad(2.0), np.deg2rad(45.0)
    # constant pitch: no Doppler, only the spatial bias
    from raysim.platform.motion import Ramp, Trajectory

    scn = Scenario(cfg, arr, Trajectory((Ramp("pitch", rot),)), 15.0, az)
    res = evaluate(scn, ("paper_integrated",))
    expected = np.rad2deg(rot * (1 - np.cos(az)) / np.cos(az))
    assert res["paper_integrated"]["angle_error_deg"] == pytest.approx(expected, rel=0.05)


# ------------------------------------------------------ boundary points (system)
def _point(map_name: str, chains, seed: int = 0, **kw) -> tuple[dict, Criteria]:
    scn = MAPS[map_name].build(seed=seed, **kw)
    res = evaluate(scn, (chains,) if isinstance(chains, str) else chains, coherent_map=False)
    return res, criteria_for(scn.config, scn.array)


# (map, chain, inside point, outside point): measured boundaries, docs/stability.md
BOUNDARY_POINTS = [
    ("rotation_azimuth", "paper_integrated", dict(rotation_deg=10, target_deg=20),
     dict(rotation_deg=10, target_deg=60)),
    ("rotation_elevation", "paper_integrated", dict(rotation_deg=5, target_deg=30),
     dict(rotation_deg=15, target_deg=40)),
    ("frequency_chirps", "paper", dict(frequency_hz=2, num_chirps=128),
     dict(frequency_hz=20, num_chirps=256)),
    ("clock", "paper_integrated", dict(time_offset_ms=0.1, clock_drift_ppm=0),
     dict(time_offset_ms=2.0, clock_drift_ppm=0)),
    ("lever_arm", "exact", dict(lever_error_cm=0.5, error_axis_index=0),
     dict(lever_error_cm=5, error_axis_index=0)),
    ("imu_rate", "paper_integrated", dict(imu_rate_hz=100, frequency_hz=20),
     dict(imu_rate_hz=50, frequency_hz=40)),
]


@pytest.mark.parametrize("map_name, chain, inside, outside", BOUNDARY_POINTS,
                         ids=[f"{b[0]}-{b[1]}" for b in BOUNDARY_POINTS])
def test_boundary_point_inside_passes_outside_fails(map_name, chain, inside, outside):
    res_in, crit_in = _point(map_name, chain, **inside)
    res_out, crit_out = _point(map_name, chain, **outside)
    assert not fails(res_in[chain], crit_in), res_in[chain]
    assert fails(res_out[chain], crit_out), res_out[chain]


def test_baseline_fails_where_the_paper_case_moves():
    res, crit = _point("rotation_azimuth", "none", rotation_deg=10, target_deg=20)
    assert fails(res["none"], crit)
    assert res["none"]["angle_error_deg"] > 3 * crit.half_beamwidth_deg


def test_lever_arm_error_makes_compensation_worse_than_none():
    res, _ = _point("lever_arm", ("none", "exact"), lever_error_cm=20, error_axis_index=0)
    assert abs(res["exact"]["pseudo_velocity"]) > abs(res["none"]["pseudo_velocity"])


def test_hover_assumption_fails_under_strong_jitter():
    res_truth, crit = _point("hover_jitter", "paper_integrated", seed=1, jitter_scale=4,
                             init_index=0)
    res_hover, _ = _point("hover_jitter", "paper_integrated", seed=1, jitter_scale=4,
                          init_index=1)
    assert not fails(res_truth["paper_integrated"], crit)
    assert fails(res_hover["paper_integrated"], crit)


# --------------------------------------------------------------- the command
def _cheap(scenario, chains=stability.CHAINS, **_):
    """Stand-in for ``stability.evaluate``: pseudo-velocity set by the clock offset."""
    pv = 0.5 * scenario.imu_time_offset * 1e3                       # fails above 0.25 ms
    rec = {"pseudo_velocity": pv, "doppler_width_hz": 94.0, "angle_error_deg": 0.1,
           "angle_error_mid_deg": 0.1, "focused_angle_error_deg": 0.1, "entropy": 3.5}
    out = {c: dict(rec) for c in chains}
    out["none"]["pseudo_velocity"] = 0.2
    out["warnings"], out["strapdown"] = [], "stub"
    return out


def test_one_command_writes_every_map(tmp_path, monkeypatch, capsys):
    from raysim.cli import main

    monkeypatch.setattr(stability, "evaluate", _cheap)
    assert main(["stability", "--out", str(tmp_path), "--quick", "--no-progress",
                 "--executor", "serial"]) == 0
    for name in MAPS:
        for ext in ("png", "nc", "json"):
            assert (tmp_path / f"{name}.{ext}").stat().st_size > 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert sorted(summary) == sorted(MAPS)
    clock = stability.read_netcdf(tmp_path / "clock.nc")
    fail = clock.fail.sel(chain="exact").isel(seed=0, clock_drift_ppm=0).values
    offsets = clock.time_offset_ms.values
    assert list(fail) == [o * 0.5 > clock.velocity_bin.values[0, 0] for o in offsets]
    assert not [p for p in tmp_path.rglob("*.part")]
    assert "wrote 8 maps" in capsys.readouterr().out


def test_run_map_resumes_from_point_records(tmp_path, monkeypatch):
    calls = []

    def counting(scenario, chains=stability.CHAINS, **kw):
        calls.append(1)
        return _cheap(scenario, chains)

    monkeypatch.setattr(stability, "evaluate", counting)
    a = stability.run_map("clock", quick=True, progress=False, points_dir=tmp_path,
                          executor="serial")
    n = len(calls)
    assert n == a.time_offset_ms.size * a.clock_drift_ppm.size
    b = stability.run_map("clock", quick=True, progress=False, points_dir=tmp_path,
                          executor="serial")
    assert len(calls) == n
    assert bool((a.pseudo_velocity == b.pseudo_velocity).all())


def test_chain_corrections_reject_unknown_chain():
    cfg, arr = _small()
    scn = Scenario(cfg, arr, stationary(), 15.0)
    with pytest.raises(ValueError, match="'kalman'"):
        chain_corrections("kalman", scn, None, cfg.chirp_times())
