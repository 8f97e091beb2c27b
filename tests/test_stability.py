"""Stability maps: the range-gate shortcut, the chains, the failure boundaries, the command.

Tiers: formula (closed-form range gate vs the full IF synthesis and range FFT),
cross-model (the chains on the gated cube via ``raysim.pipeline.chains.project``
vs the ``compensation`` package on full cubes; the pipeline's strapdown vs a
second-order reference strapdown written here), system (boundary points: a
point inside the measured boundary passes the criterion, a point outside fails
it), and the one command that writes every map.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from raysim.echoes.gated import gated_cube
from raysim.echoes.oracle import simulate_point_targets
from raysim.measure.point import angle_chirp
from raysim.platform.motion import sinusoid, stationary
from raysim.processing.maps import range_compress
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig
from raysim.studies import stability
from raysim.studies.stability import (
    MAPS,
    Criteria,
    StabilityPoint,
    compensated_slow_time,
    criteria_for,
    evaluate,
    fails,
    point_gate,
)
from raysim.studies.stability import runner as stability_runner

#: Relative agreement of the closed-form gate and the complex64 synthesis + FFT.
GATE_RTOL = 1e-5
#: Normalised correlation required between two implementations of one chain.
CHAIN_CORRELATION = 0.9999


def _small(num_chirps=64, n=8) -> tuple[RadarConfig, object]:
    cfg = RadarConfig(num_chirps=num_chirps)
    return cfg, upa(n, n, wavelength=cfg.wavelength)


def _truth_pose(scn: StabilityPoint):
    """The true pose at every chirp as a ``compensation.PlatformMotion``."""
    from compensation import PlatformMotion

    t = scn.chirp_times()
    q, qd, _ = scn.trajectory.states(t)
    att = Rotation.from_euler("ZYX", q[:, [5, 4, 3]]).as_matrix()
    return PlatformMotion(t, att, q[:, :3], qd[:, :3], scn.trajectory.angular_rate(t),
                          scn.lever_arm_m)


def _reference_strapdown(scn: StabilityPoint, t_chirp: np.ndarray):
    """Second-order strapdown from the truth at the last IMU sample before the first chirp.

    Integrates the gyro with the rotation vector of the trapezoidal rate and
    the specific force ``a = R f + g`` with the trapezoidal rule, then
    interpolates (slerp for the attitude, linear otherwise) to the chirp times.
    Returns ``(attitude [chirp, 3, 3], position [chirp, 3])``.
    """
    from raysim.studies.stability.motion import point_imu_record

    t, gyro, accel = point_imu_record(scn, t_chirp).to_arrays()
    k0 = max(int(np.searchsorted(t, t_chirp[0], side="right")) - 1, 0)
    t, gyro, accel = t[k0:], gyro[k0:], accel[k0:]
    q, qd, _ = scn.trajectory.states(t[:1])
    rots = [Rotation.from_euler("ZYX", q[0, [5, 4, 3]])]
    for i in range(t.size - 1):
        rots.append(rots[-1] * Rotation.from_rotvec(0.5 * (gyro[i] + gyro[i + 1])
                                                    * (t[i + 1] - t[i])))
    rot = Rotation.concatenate(rots)
    acc_w = rot.apply(accel) + np.array([0.0, 0.0, 9.80665])
    h = np.diff(t)[:, None]
    vel = np.vstack([qd[0, :3], qd[0, :3] + np.cumsum(0.5 * (acc_w[1:] + acc_w[:-1]) * h,
                                                      axis=0)])
    pos = np.vstack([q[0, :3], q[0, :3] + np.cumsum(0.5 * (vel[1:] + vel[:-1]) * h, axis=0)])
    tc = np.clip(t_chirp, t[0], t[-1])
    attitude = Slerp(t, rot)(tc).as_matrix()
    return attitude, np.stack([np.interp(tc, t, pos[:, j]) for j in range(3)], axis=-1)


# ---------------------------------------------------------------- formula tier
def test_gate_equals_range_fft_of_synthesised_if():
    cfg, arr = _small(num_chirps=16, n=4)
    scn = StabilityPoint(cfg, arr, sinusoid("pitch", np.deg2rad(10), 20.0), 15.3,
                         np.rad2deg(0.3), np.rad2deg(-0.2))
    gate, k, r_k = point_gate(scn)
    frame = simulate_point_targets(cfg, arr, [scn.target], scn.trajectory,
                                   lever_arm=scn.lever_arm_m, pattern=cfg.pattern)
    ref = range_compress(frame.data)[:, :, k]
    assert k == int(np.argmin(np.abs(cfg.range_axis() - 15.3)))
    assert r_k == cfg.range_axis()[k]
    assert np.max(np.abs(gate - ref)) < GATE_RTOL * np.max(np.abs(ref))
    direct = gated_cube(cfg, arr, scn.trajectory, [scn.target], range_bin=k,
                        lever_arm=scn.lever_arm_m, pattern=cfg.pattern)
    assert np.array_equal(direct, gate)
    with pytest.raises(ValueError, match="range_bin"):
        gated_cube(cfg, arr, scn.trajectory, [scn.target], range_bin=cfg.num_samples)


def test_criteria_of_paper_radar():
    cfg = RadarConfig()
    crit = criteria_for(cfg, upa(20, 20, wavelength=cfg.wavelength))
    assert crit.velocity_bin == pytest.approx(cfg.center_wavelength / (2 * 256 * 60e-6))
    assert crit.doppler_bin_hz == pytest.approx(1 / (256 * 60e-6))
    # 0.886 lambda_c / (20 * lambda / 2) rad, halved
    half = 0.5 * np.rad2deg(0.886 * cfg.center_wavelength / (10 * cfg.wavelength))
    assert crit.half_beamwidth_deg == pytest.approx(half, rel=1e-9)
    c = Criteria(0.1, 60.0, 2.0)
    assert not fails({"pseudo_velocity_mps": -0.09, "angle_error_worst_deg": 1.9}, c)
    assert fails({"pseudo_velocity_mps": -0.11, "angle_error_worst_deg": 0.0}, c)
    assert fails({"pseudo_velocity_mps": 0.0, "angle_error_worst_deg": 2.1}, c)
    with pytest.raises(ValueError, match="angle_error_worst_deg"):
        fails({"pseudo_velocity_mps": 0.0, "angle_error_deg": 2.1}, c)


def test_stationary_platform_restores_hann_width():
    cfg, arr = _small()
    res = evaluate(StabilityPoint(cfg, arr, stationary(), 15.0, np.rad2deg(0.3),
                                  np.rad2deg(0.1)), ("none", "exact"))
    for chain in ("none", "exact"):
        assert abs(res[chain]["pseudo_velocity_mps"]) < 1e-6
        assert res[chain]["pseudo_velocity_bins"] == pytest.approx(
            res[chain]["pseudo_velocity_mps"] / cfg.velocity_resolution)
        assert res[chain]["doppler_width_hz"] / cfg.doppler_resolution == pytest.approx(
            1.44, abs=0.01)
        assert res[chain]["angle_error_worst_deg"] < 0.05
        assert res[chain]["angle_error_deg"] <= res[chain]["angle_error_worst_deg"] + 0.05


# ------------------------------------------------------------ cross-model tier
@pytest.mark.parametrize("chain, phase", [("paper:published", "published"),
                                          ("paper", "integrated")])
def test_paper_chains_match_compensation_package(chain, phase):
    comp = pytest.importorskip("compensation")
    cfg, arr = _small()
    r_gate = float(cfg.range_axis()[100])
    traj = sinusoid("pitch", np.deg2rad(8), 20.0) + sinusoid("yaw", np.deg2rad(5), 10.0) \
        + sinusoid("z", 0.03, 5.0)
    scn = StabilityPoint(cfg, arr, traj, r_gate, 20.0, 10.0)
    motion = _truth_pose(scn)
    mine = compensated_slow_time(scn, chain, motion)
    rc = range_compress(simulate_point_targets(cfg, arr, [scn.target], traj,
                                               lever_arm=scn.lever_arm_m,
                                               pattern=cfg.pattern).data)
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
    scn = StabilityPoint(cfg, arr, traj, r_gate, 30.0, -20.0)
    motion = _truth_pose(scn)
    mine = compensated_slow_time(scn, "exact", motion)
    rc = range_compress(simulate_point_targets(cfg, arr, [scn.target], traj,
                                               lever_arm=scn.lever_arm_m,
                                               pattern=cfg.pattern).data)
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
    scn = StabilityPoint(cfg, arr,
                         sinusoid("pitch", np.deg2rad(10), 20.0) + sinusoid("z", 0.05, 5.0),
                         15.0, 20.0)
    t = cfg.chirp_times()
    a = stability.point_motion(scn, t)                      # raysim.pipeline.estimate
    b_att, b_pos = _reference_strapdown(scn, t)
    truth = _truth_pose(scn)
    lam = cfg.center_wavelength
    for att, pos in ((a.attitude, a.position), (b_att, b_pos)):
        rot_err = Rotation.from_matrix(att) * Rotation.from_matrix(truth.attitude).inv()
        assert np.max(rot_err.magnitude()) < 1e-4                      # rad
        assert np.max(np.abs(pos - truth.position)) < lam / 100  # phase < 0.13 rad


def test_paper_tilt_correction_matches_closed_form_bias():
    """The small-angle tilt leaves a bias dbeta (1 - cos az) / cos az in azimuth."""
    cfg, arr = _small(n=20)
    rot, az = np.deg2rad(2.0), np.deg2rad(45.0)
    # constant pitch: no Doppler, only the spatial bias
    from raysim.platform.motion import Ramp, Trajectory

    scn = StabilityPoint(cfg, arr, Trajectory((Ramp("pitch", rot),)), 15.0, 45.0)
    res = evaluate(scn, ("paper",))
    expected = np.rad2deg(rot * (1 - np.cos(az)) / np.cos(az))
    assert res["paper"]["angle_error_worst_deg"] == pytest.approx(expected, rel=0.05)
    # constant attitude: the single chirp N/2 - 1 sees the same bias
    assert res["paper"]["angle_error_deg"] == pytest.approx(expected, rel=0.05)


# ------------------------------------------------------ boundary points (system)
def _point(map_name: str, chains, seed: int = 0, **kw) -> tuple[dict, Criteria]:
    scn = MAPS[map_name].build(seed=seed, **kw)
    res = evaluate(scn, (chains,) if isinstance(chains, str) else chains, coherent_map=False)
    return res, criteria_for(scn.config, scn.array)


# (map, chain, inside point, outside point): measured boundaries, docs/stability.md
BOUNDARY_POINTS = [
    ("rotation_azimuth", "paper", dict(rotation_deg=10, target_deg=20),
     dict(rotation_deg=10, target_deg=60)),
    ("rotation_elevation", "paper", dict(rotation_deg=5, target_deg=30),
     dict(rotation_deg=15, target_deg=40)),
    ("frequency_chirps", "paper:published", dict(frequency_hz=2, num_chirps=128),
     dict(frequency_hz=20, num_chirps=256)),
    ("clock", "paper", dict(time_offset_ms=0.1, clock_drift_ppm=0),
     dict(time_offset_ms=2.0, clock_drift_ppm=0)),
    ("lever_arm", "exact", dict(lever_error_cm=0.5, error_axis_index=0),
     dict(lever_error_cm=5, error_axis_index=0)),
    ("imu_rate", "paper", dict(imu_rate_hz=100, frequency_hz=20),
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
    assert res["none"]["angle_error_worst_deg"] > 3 * crit.half_beamwidth_deg


def test_lever_arm_error_makes_compensation_worse_than_none():
    res, _ = _point("lever_arm", ("none", "exact"), lever_error_cm=20, error_axis_index=0)
    assert abs(res["exact"]["pseudo_velocity_mps"]) > abs(res["none"]["pseudo_velocity_mps"])


def test_hover_assumption_fails_under_strong_jitter():
    res_truth, crit = _point("hover_jitter", "paper", seed=1, jitter_scale=4, init_index=0)
    res_hover, _ = _point("hover_jitter", "paper", seed=1, jitter_scale=4, init_index=1)
    assert not fails(res_truth["paper"], crit)
    assert fails(res_hover["paper"], crit)


# --------------------------------------------------------------- the command
def _cheap(point, chains=stability.MAP_CHAINS, **_):
    """Stand-in for ``stability.evaluate``: pseudo-velocity set by the clock offset."""
    pv = 0.5 * point.imu_time_offset_s * 1e3                        # fails above 0.25 ms
    rec = {"pseudo_velocity_mps": pv, "pseudo_velocity_bins": pv / 0.126,
           "doppler_width_hz": 94.0, "angle_error_worst_deg": 0.1, "angle_error_deg": 0.1,
           "map_angle_error_deg": 0.1, "entropy_ae_nats": 3.5}
    out = {c: dict(rec) for c in chains}
    out["none"]["pseudo_velocity_mps"] = 0.2
    out["warnings"], out["strapdown"] = [], "stub"
    return out


def test_one_command_writes_every_map(tmp_path, monkeypatch, capsys):
    from raysim.cli import main

    monkeypatch.setattr(stability_runner, "evaluate", _cheap)
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
    assert set(clock.chain.values.tolist()) == {"none", "paper", "paper:published", "exact"}
    for name in stability.STABILITY_METRICS:
        assert name in clock.data_vars and clock[name].attrs["units"]
    assert summary["clock"]["units"]["pseudo_velocity_mps"] == "m/s"
    assert not [p for p in tmp_path.rglob("*.part")]
    out = capsys.readouterr().out
    assert f"wrote {len(MAPS)} maps" in out
    # a table, one row per map and chain, not a raw dict
    assert "{" not in out
    header = out.splitlines()[0].split()
    assert header[:3] == ["map", "chain", "fail"]
    assert sum(line.startswith("clock ") for line in out.splitlines()) == 4


def test_run_map_resumes_from_point_records(tmp_path, monkeypatch):
    calls = []

    def counting(point, chains=stability.MAP_CHAINS, **kw):
        calls.append(1)
        return _cheap(point, chains)

    monkeypatch.setattr(stability_runner, "evaluate", counting)
    a = stability.run_map("clock", quick=True, progress=False, points_dir=tmp_path,
                          executor="serial")
    n = len(calls)
    assert n == a.time_offset_ms.size * a.clock_drift_ppm.size
    b = stability.run_map("clock", quick=True, progress=False, points_dir=tmp_path,
                          executor="serial")
    assert len(calls) == n
    assert bool((a.pseudo_velocity_mps == b.pseudo_velocity_mps).all())


def test_chains_reject_unknown_chain():
    cfg, arr = _small()
    scn = StabilityPoint(cfg, arr, stationary(), 15.0)
    with pytest.raises(ValueError, match="'kalman'"):
        compensated_slow_time(scn, "kalman")
    with pytest.raises(ValueError, match="'kalman'"):
        evaluate(scn, ("none", "kalman"))
    with pytest.raises(ValueError, match="'paper_integrated'"):
        stability.run_map("clock", quick=True, chains=("paper_integrated",), progress=False,
                          executor="serial")


def test_single_chirp_angle_error_is_chirp_n_over_2_minus_1():
    """``angle_error_deg`` is the error of chirp ``angle_chirp(N)``; the worst covers its set."""
    cfg, arr = _small()
    scn = StabilityPoint(cfg, arr, sinusoid("pitch", np.deg2rad(10), 20.0), 15.0, 20.0)
    res = evaluate(scn, ("none",), coherent_map=False)["none"]
    # uncompensated, the single-chirp error is the true tilt of that chirp
    t = scn.chirp_times()
    tilt = np.rad2deg(abs(scn.trajectory.states(t)[0][angle_chirp(t.size), 4]))
    assert res["angle_error_deg"] == pytest.approx(tilt, abs=0.3)
    assert res["angle_error_worst_deg"] >= res["angle_error_deg"] - 0.3
    assert np.isnan(res["map_angle_error_deg"]) and np.isnan(res["entropy_ae_nats"])


def test_point_from_toml_scenario():
    """A TOML scenario (one static target, UPA) gives the same point as the direct build."""
    from raysim.scenario import loads_scenario

    scn = loads_scenario("""
        seed = 4
        lever_arm_m = [0.0, 0.0, 0.10]
        [radar]
        num_chirps = 64
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
        preset = "consumer_mems"
        rate_hz = 2000.0
        time_offset_s = 0.0002
    """)
    p = StabilityPoint.from_scenario(scn, lever_arm_error_m=(0.01, 0.0, 0.0), t0_s=0.5)
    cfg, arr = _small()
    direct = StabilityPoint(cfg, arr, sinusoid("pitch", np.deg2rad(10.0), 20.0), 15.0, 20.0,
                            5.0, imu_spec="consumer_mems", imu_time_offset_s=2e-4,
                            lever_arm_error_m=(0.01, 0.0, 0.0), t0_s=0.5, seed=scn.imu_seed)
    assert p.seed == 5 and p.imu_rate_hz == 2000.0 and p.imu_spec == "consumer_mems"
    assert np.array_equal(p.believed_lever_arm_m, [0.01, 0.0, 0.10])
    assert np.array_equal(p.array.virtual_positions, arr.virtual_positions)
    assert p.config.num_chirps == 64 and p.config.center_wavelength == cfg.center_wavelength
    a = evaluate(p, ("paper", "exact"), coherent_map=False)
    b = evaluate(direct, ("paper", "exact"), coherent_map=False)
    assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True)
    with pytest.raises(ValueError, match="one target"):
        StabilityPoint.from_scenario(scn.with_values({"scene.targets": [
            {"range_m": 10.0}, {"range_m": 12.0}]}))
