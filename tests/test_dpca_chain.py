"""The dpca chain wired into raysim: chains.project, the Beamformer, the scene measurement,
simulate, scene-report, compensate and the stability map.

The algorithm itself is tested against closed forms in tests/compensation/test_comp_dpca.py;
here: the pipeline hands dpca the same data and options as calling
:func:`compensation.dpca_projection` directly, and its price and warnings reach the user.
"""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest
from scenario_texts import small_scenario

from compensation import PlatformMotion, dpca_plan, dpca_projection
from raysim.cli import main
from raysim.pipeline.beams import PRICE_PREFIX, Beamformer
from raysim.pipeline.chains import project
from raysim.radar.arrays import upa
from raysim.vocabulary import CHAIN_NAMES, CHAINS, chain_label, parse_chain, parse_chains

LAM = 3.9e-3
T_CHIRP = 60e-6
#: complex64 round-off relative to the peak: the same computation, bit for bit up to
#: summation order.
SAME_TOL = 1e-6


def _motion(n_pose: int, amp: float = 1.5e-3) -> PlatformMotion:
    """Horizontal (x, y) displacement over the poses, level attitude [m]."""
    s = np.linspace(0.0, 1.0, n_pose)
    disp = np.stack([amp * s, 0.4 * amp * s ** 2, 1e-4 * s], axis=1)
    z = np.zeros((n_pose, 3))
    att = np.broadcast_to(np.eye(3), (n_pose, 3, 3)).copy()
    return PlatformMotion(np.arange(n_pose) * T_CHIRP, att, disp, z, z.copy(), np.zeros(3))


def _rc(n_chirp: int, n_chan: int, n_range: int = 3, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    shape = (n_chirp, n_chan, n_range)
    return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(np.complex64)


# ------------------------------------------------------------------ vocabulary
def test_dpca_is_a_chain_by_name_but_not_a_default():
    assert "dpca" in CHAIN_NAMES and "dpca" not in CHAINS
    spec = parse_chain("dpca")
    assert spec.key == "dpca" and spec.compensated
    assert [s.key for s in parse_chains("none,exact,dpca")] == ["none", "exact", "dpca"]
    assert "dpca" in chain_label("dpca")
    with pytest.raises(ValueError, match="'dpca:linear'"):
        parse_chain("dpca:linear")


# ------------------------------------------------------------ chains.project
def test_project_equals_dpca_projection_upa():
    arr = upa(8, 8, wavelength=LAM)
    rc, mot = _rc(24, 64), _motion(24)
    kw = dict(wavelength=LAM, range_axis=[14.9, 15.0, 15.1], azimuth=np.deg2rad([-10, 0, 12]),
              elevation=np.deg2rad([-5, 3]))
    taper = lambda i: np.hanning(i[:, 0].max() + 3)[i[:, 0] + 1] * (1 + 0.1 * i[:, 1])  # noqa: E731
    a = project("dpca", rc, arr.virtual_positions, motion=mot, grid_shape=arr.grid_shape,
                weights=taper, range_gates=[0, 2], **kw)
    b = dpca_projection(rc, arr.virtual_positions, mot, grid_shape=arr.grid_shape,
                        weights=taper, range_gates=[0, 2], **kw)
    assert a.plan.sub_shape == b.plan.sub_shape and a.plan.sub_shape[0] < 8
    np.testing.assert_allclose(a.data, b.data, rtol=0, atol=SAME_TOL * np.abs(b.data).max())
    assert a.warnings == b.warnings
    # options pass through: a fixed sub-aperture and the linear stencil
    c = project("dpca", rc, arr.virtual_positions, motion=mot, grid_shape=arr.grid_shape,
                subaperture=(3, 4), order=1, **kw)
    d = dpca_projection(rc, arr.virtual_positions, mot, grid_shape=arr.grid_shape,
                        subaperture=(3, 4), order=1, **kw)
    assert c.plan.sub_shape == (3, 4) and c.plan.order == 1
    np.testing.assert_allclose(c.data, d.data, rtol=0, atol=SAME_TOL * np.abs(d.data).max())


def test_project_equals_dpca_projection_tdm():
    """A TDM array: every slot's channels at the pose of its own ramp (chirp major)."""
    arr = upa(6, 6, wavelength=LAM)
    slot = (np.arange(36) // 6) % 2                    # two transmit slots, rows alternate
    rc, mot = _rc(12, 36, 2, seed=1), _motion(24, amp=1.0e-3)
    kw = dict(wavelength=LAM, range_axis=[15.0, 15.1], azimuth=np.deg2rad([0, 8]),
              elevation=np.deg2rad([0.0]))
    a = project("dpca", rc, arr.virtual_positions, motion=mot, channel_slot=slot, **kw)
    b = dpca_projection(rc, arr.virtual_positions, mot, channel_slot=slot, **kw)
    np.testing.assert_allclose(a.data, b.data, rtol=0, atol=SAME_TOL * np.abs(b.data).max())


def test_project_names_misplaced_dpca_options():
    arr = upa(4, 4, wavelength=LAM)
    kw = dict(wavelength=LAM, range_axis=[15.0], azimuth=[0.0], elevation=[0.0])
    with pytest.raises(ValueError, match="subaperture=.*options of the dpca chain.*'exact'"):
        project("exact", _rc(4, 16, 1), arr.virtual_positions, motion=_motion(4),
                subaperture=(2, 2), **kw)
    with pytest.raises(ValueError, match="'dpca' needs motion"):
        project("dpca", _rc(4, 16, 1), arr.virtual_positions, **kw)
    # a full-array taper is refused: dpca tapers its sub-aperture
    six = upa(6, 6, wavelength=LAM)
    with pytest.raises(ValueError, match="weights"):
        project("dpca", _rc(8, 36, 1), six.virtual_positions, motion=_motion(8),
                grid_shape=six.grid_shape, weights=np.ones(36), **kw)


# ---------------------------------------------------------------- Beamformer
def test_beamformer_plans_the_frame_once_and_states_the_price():
    arr = upa(8, 8, wavelength=LAM)
    mot, rc = _motion(32), _rc(32, 64, 1, seed=2)
    found: list[str] = []
    bf = Beamformer("dpca", arr, LAM, motion=mot, warnings=found)
    plan = dpca_plan(arr.virtual_positions, mot, wavelength=LAM, grid_shape=arr.grid_shape)
    assert bf.plan.sub_shape == plan.sub_shape
    assert found[0] == PRICE_PREFIX + plan.summary().removeprefix("dpca: ")
    # the whole frame through the Beamformer is dpca_projection of the frame
    ref = dpca_projection(rc, arr.virtual_positions, mot, wavelength=LAM,
                          range_axis=[15.0], azimuth=[0.5], elevation=[0.2],
                          grid_shape=arr.grid_shape)
    whole = bf(rc, np.arange(32), [15.0], [0.5], [0.2])
    assert whole.shape == (32, 1, 1, 1)
    np.testing.assert_allclose(whole, ref.data, rtol=0, atol=SAME_TOL * np.abs(ref.data).max())
    # the frame's reference sub-aperture in every call: a chirp's beam (off the
    # beam's own direction too) is the same alone, in a block and in the whole frame
    for pick in ([5], [0, 1, 2], [30, 31], [7, 19, 23]):
        part = bf(rc[pick], pick, [15.0], [0.5], [0.2])
        np.testing.assert_allclose(part, whole[pick], rtol=0,
                                   atol=SAME_TOL * np.abs(whole).max())
    assert all(not w.startswith("dpca ") or w in plan.warnings for w in found[1:])


# ------------------------------------------------------------ scene measurement
def test_measure_scene_moves_the_taper_onto_the_sub_aperture():
    from raysim.measure.scene import (
        channel_taper,
        measure_scene,
        range_compressed,
        sub_aperture_taper,
    )
    from raysim.radar.config import RadarConfig

    cfg = RadarConfig(num_chirps=16, sample_rate=2.5e6)
    arr = upa(8, 8, wavelength=cfg.wavelength)
    rng = np.random.default_rng(3)
    data = (rng.standard_normal((16, 64, cfg.num_samples))
            + 1j * rng.standard_normal((16, 64, cfg.num_samples))).astype(np.complex64)
    mot = _motion(16, amp=1.2e-3)
    az = el = np.deg2rad([-9.0, 0.0, 9.0])
    rc = range_compressed(data, channel_taper(arr))
    r_axis = cfg.bin_ranges(rc.shape[-1])
    res = measure_scene("dpca", rc, mot, config=cfg, array=arr, azimuth=az, elevation=el,
                        range_window=(10.0, 12.0), lever_arm=np.zeros(3),
                        spatial_window="taylor")
    gates = np.nonzero((r_axis >= 10.0) & (r_axis <= 12.0))[0]
    bare = range_compressed(data, np.ones(64))[:, :, gates]
    direct = dpca_projection(bare, arr.virtual_positions, mot, wavelength=cfg.center_wavelength,
                             range_axis=r_axis[gates], azimuth=az, elevation=el,
                             grid_shape=arr.grid_shape, weights=sub_aperture_taper("taylor"))
    want = direct.coherent_power(window="hann")
    np.testing.assert_allclose(res.cube, want, rtol=1e-4, atol=1e-6 * want.max())
    assert res.plan.sub_shape == direct.plan.sub_shape
    price = res.price()
    assert price["sub_shape"] == list(direct.plan.sub_shape)
    assert price["gain_loss_db"] == pytest.approx(direct.plan.gain_loss_db)
    assert measure_scene("exact", rc, mot, config=cfg, array=arr, azimuth=az, elevation=el,
                         range_window=(10.0, 12.0), lever_arm=np.zeros(3)).price() == {}
    w = sub_aperture_taper("taylor")(np.stack(np.divmod(np.arange(12), 4), axis=1))
    assert w.shape == (12,) and w.mean() == pytest.approx(1.0)
    assert sub_aperture_taper(None) is None


# ------------------------------------------------------------------ commands
def test_simulate_takes_dpca_and_its_warnings_reach_stderr_and_json(tmp_path):
    scen = tmp_path / "s.toml"
    scen.write_text(small_scenario("dpca", frames=1, pitch_deg=10.0))
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        assert main(["simulate", "--scenario", str(scen), "--chains", "none,exact,dpca",
                     "--json"]) == 0
    res = json.loads(out.getvalue())
    assert list(res["chains"]) == ["none", "exact", "dpca"]
    warned = res["warnings"]["dpca"]
    # 4 x 4 array, 10 deg pitch: band-limited interpolation keeps 3 x 4 (Lagrange 1 x 4)
    assert warned[0].startswith(PRICE_PREFIX + "sub-aperture 3 x 4 of 4 x 4 elements "
                                "(band-limited")
    for w in warned:
        assert f"warning: dpca: {w}" in err.getvalue()
    m = res["chains"]["dpca"]
    assert abs(m["pseudo_velocity_mps"]) < 0.05 and m["doppler_width_bins"] < 1.6


def test_scene_report_takes_dpca_with_its_price(tmp_path, capsys):
    from test_scene_report_scenario import ARRAYS, SMALL_POINT

    path = tmp_path / "small.toml"
    path.write_text(SMALL_POINT.format(frames=1, array=ARRAYS["upa"].replace("4", "8")))
    out = tmp_path / "report"
    assert main(["scene-report", "--scenario", str(path), "--quick", "--chains",
                 "none,exact,dpca", "--out", str(out), "--no-progress"]) == 0
    err = capsys.readouterr().err
    data = json.loads((out / "small_rotation_y.json").read_text())
    dpca = data["chains"]["dpca"]
    assert list(data["chains"]) == ["none", "exact", "dpca"]
    assert dpca["price"]["full_shape"] == [8, 8]
    assert 1 <= dpca["price"]["sub_shape"][0] <= 8 and dpca["price"]["gain_loss_db"] >= 0
    assert isinstance(dpca["within_margin"], bool)
    same = dpca["same_aperture_reference"]                # stationary, dpca's sub-aperture
    assert set(same["metrics"]) == set(dpca["metrics"])
    assert same["minus_same_aperture"]["scene_entropy_ae_nats"] == pytest.approx(
        dpca["metrics"]["scene_entropy_ae_nats"] - same["metrics"]["scene_entropy_ae_nats"])
    # the margin verdict is against that reference; the aperture's cost is stated apart
    assert dpca["margin_reference"] == "same_aperture"
    assert data["chains"]["exact"]["margin_reference"] == "stationary"
    cost = same["aperture_cost_nats"]["scene_entropy_ae_nats"]
    assert cost == pytest.approx(same["metrics"]["scene_entropy_ae_nats"]
                                 - data["reference"]["metrics"]["scene_entropy_ae_nats"])
    for w in dpca["warnings"]:
        assert f"warning: small_rotation_y: dpca: {w}" in err
    md = (out / "report.md").read_text()
    assert "Price of `dpca`" in md and "dpca - stationary" in md
    assert "through the same sub-aperture" in md and "aperture cost rd / ra / ae" in md
    assert "dpca" in data["point_metrics"]["metrics"]


def test_compensate_dpca_on_a_stored_cube(tmp_path, capsys):
    from raysim.echoes.oracle import PointTarget, simulate_point_targets
    from raysim.io import storage
    from raysim.platform.imu import simulate_imu
    from raysim.platform.motion import sinusoid
    from raysim.radar.config import RadarConfig

    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6)
    arr = upa(8, 8, wavelength=cfg.wavelength)
    lever = np.array([0.0, 0.0, 0.1])
    traj = sinusoid("x", 1.0e-3, 10.0, phase=np.pi / 2)      # at rest at chirp 0
    tgt = PointTarget.at(12.0, np.deg2rad(15), 0.0, radar_origin=lever)
    frame = simulate_point_targets(cfg, arr, [tgt], traj, lever_arm=lever)
    s = simulate_imu(traj, "ideal", rate=1000.0, start=-0.01, end=0.02)
    ds = storage.frames_to_dataset([frame], traj, imu=storage.imu_dataset(s.time, s.gyro,
                                                                          s.accel))
    storage.write_store(tmp_path / "s.zarr", ds)
    out = tmp_path / "beams.npz"
    assert main(["compensate", str(tmp_path / "s.zarr"), "--out", str(out), "--chain", "dpca",
                 "--range-m", "11.5:12.5", "--az-deg", "15:15:1", "--el-deg", "0:0:1",
                 "--velocity", "given", "--initial-velocity", "0,0,0"]) == 0
    cap = capsys.readouterr()
    assert "chain dpca" in cap.out
    assert f"warning: dpca: {PRICE_PREFIX}sub-aperture" in cap.err
    with np.load(out) as z:
        assert str(z["chain"]) == "dpca"
        price = str(z["warnings"][0])
        assert price.startswith(PRICE_PREFIX)
        # the whole array's channels estimated at the shifted positions: 8 x 8 kept
        assert price.startswith(PRICE_PREFIX + "sub-aperture 8 x 8 of 8 x 8 elements "
                                "(band-limited")
        gate = int(np.argmax(np.abs(z["beams"]).sum(axis=(0, 2, 3))))
        slow = z["beams"][:, gate, 0, 0]
        assert np.abs(slow.mean()) / np.abs(slow).mean() > 0.999   # a static target: one phase


# ------------------------------------------------------------------ stability
def test_stability_map_of_dpca_beside_exact(tmp_path):
    """The quick dpca_displacement map: dpca runs where the array has spare aperture and
    fails (NaN, fail) where the displacement exceeds it; exact runs everywhere."""
    from raysim.studies.stability import run_map

    ds = run_map("dpca_displacement", quick=True, progress=False, executor="serial",
                 points_dir=tmp_path)
    assert ds.chain.values.tolist() == ["none", "exact", "dpca"]
    d = ds.sel(chain="dpca").isel(seed=0)
    ok = np.isfinite(d.pseudo_velocity_mps.values)
    assert ok.any() and ok[0].all()                     # 0.5 mm: every array keeps one
    assert bool(d.fail.values[~ok].all())               # beyond the spare aperture: fails
    assert np.isfinite(ds.sel(chain="exact").pseudo_velocity_mps.values).all()
    assert np.nanmax(np.abs(d.pseudo_velocity_mps.values)) < float(ds.velocity_bin.max())
    assert "dpca price" in ds.attrs["warnings"]


def test_report_and_sweep_take_dpca(tmp_path):
    """The HTML report states dpca's price apart from the warnings; sweep keeps its key."""
    import xarray as xr

    scen = tmp_path / "s.toml"
    scen.write_text(small_scenario("dpca", frames=1, pitch_deg=10.0))
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["report", "--scenario", str(scen), "--chains", "exact,dpca",
                     "--out", str(tmp_path / "r.html")]) == 0
        assert main(["sweep", str(scen), "--param", "scene.targets.0.range_m=15.0",
                     "--chains", "exact,dpca", "--no-progress",
                     "--out", str(tmp_path / "sweep")]) == 0
    page = (tmp_path / "r.html").read_text()
    assert "Price of the chains" in page and "sub-aperture 3 x 4 of 4 x 4" in page
    warnings = page.split("<h2 id='warnings'>")[-1].split("</ul>")[0]
    assert PRICE_PREFIX not in warnings
    with xr.open_dataset(tmp_path / "sweep" / "sweep.nc") as ds:
        assert [str(c) for c in ds["chain"].values] == ["exact", "dpca"]


def test_compensate_dpca_on_a_tdm_capture(tmp_path, capsys):
    """A DCA1000 capture (TI 3 Tx x 4 Rx, TDM slots TX0, TX2, TX1) with its .cfg and ULog:
    dpca projects every slot's channels at the pose of its own ramp, its price is printed."""
    from raysim.io.zarr_store import open_store
    from raysim.pipeline.flight import measure_store, write_flight
    from raysim.platform.motion import sinusoid

    motion = sinusoid("x", 0.5e-3, 20.0, np.pi / 2) + sinusoid("pitch", np.deg2rad(2.0), 20.0)
    flight = write_flight(tmp_path / "tdm", trajectory=motion, imu="ideal", time_offset=0.0,
                          frames=1, target=(11.3, 28.0, 0.0), lever_arm=(0.0, 0.0, 0.0))
    out = tmp_path / "dpca.zarr"
    assert main(flight.command(out, "--range-m", "10.8:11.8", "--az-deg", "22:34:0.25",
                               "--el-deg", "0:0:1", "--chain", "dpca")) == 0
    err = capsys.readouterr().err
    assert f"warning: dpca: {PRICE_PREFIX}sub-aperture" in err
    ds = open_store(out)
    assert ds.attrs["chain"] == "dpca"
    (angle_err, pv_bins, _), = [tuple(r) for r in measure_store(ds, flight, 0)]
    assert angle_err < 0.1 and abs(pv_bins) < 0.01      # measured 0.019 deg, 9e-5 bin


def test_point_metrics_of_several_frames_use_one_subaperture():
    """Frames of one record are measured through one dpca sub-aperture (one price line)."""
    from raysim.pipeline.beams import PRICE_PREFIX
    from raysim.pipeline.run import evaluate
    from raysim.scenario import scenario_from_case

    s = scenario_from_case("rotation_y").with_values(
        {"radar.sample_rate_hz": 2.5e6, "radar.num_chirps": 32, "array.nx": 20, "array.ny": 20,
         "frames": 3})
    res = evaluate(s, chains=["dpca"])
    prices = [w for w in res["warnings"]["dpca"] if w.startswith(PRICE_PREFIX)]
    assert len(prices) == 1, prices
    assert res["chains"]["dpca"]["entropy_ae_nats"] > 0
