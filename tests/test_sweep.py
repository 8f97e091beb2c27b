"""Dask sweeps: values, gathering into xarray, resume after interruption and after failures."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scenario_texts import small_scenario

import raysim.pipeline.sweep as sweep_mod
from raysim.cli import main
from raysim.pipeline.sweep import SweepSpec, parse_values, run_sweep, sweep_points
from raysim.scenario import scenario_from_case

SMALL = {"radar.num_chirps": 32, "array.nx": 4, "array.ny": 4,
         "radar.chirp_duration_s": 12.8e-6}


@pytest.fixture(scope="module")
def spec():
    """3 azimuths x 2 seeds = 6 points on a small radar."""
    base = scenario_from_case("stationary").with_values({**SMALL, "noise": True})
    return SweepSpec(base, {"scene.targets.0.az_deg": [0.0, 10.0, 20.0]}, (0, 1),
                     ("none",))


@pytest.fixture(scope="module")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                       dashboard_address=":0")
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def test_parse_values():
    assert parse_values("1,2,4") == [1, 2, 4]
    assert parse_values("[0.5, 1.5]") == [0.5, 1.5]
    assert parse_values("range(0, 10, 5)") == [0, 5]
    assert parse_values("linspace(0, 1, 3)") == [0.0, 0.5, 1.0]
    assert parse_values("logspace(0, 2, 3)") == [1.0, 10.0, 100.0]
    assert parse_values("ideal,tactical") == ["ideal", "tactical"]
    for bad in ("range(a)", "linspace(0, 1)", ""):
        with pytest.raises(ValueError):
            parse_values(bad)


@pytest.mark.parametrize("text, named", [
    ("linspace(1, 2, 1000000000)", "1000000000 values"),
    ("range(1000000000)", "1000000000 values"),
    ("range(1, 5, 0)", "step must not be zero"),
    ("linspace(1, inf, 3)", "finite")])
def test_a_range_too_long_or_malformed_is_refused_before_it_is_expanded(text, named,
                                                                         monkeypatch):
    """A mistyped count is refused by its length, not by running out of memory."""
    monkeypatch.setattr(sweep_mod.np, "linspace", None)      # never reached
    with pytest.raises(ValueError, match=named):
        parse_values(text)


def test_a_sweep_of_more_points_than_its_bound_is_refused(capsys, tmp_path):
    code = main(["sweep", "--case", "rotation_y", "--param", "imu.rate_hz=range(1, 1000)",
                 "--seeds", "range(1000)", "--out", str(tmp_path / "sw")])
    assert code == 2 and "999000 points (999 values x 1000 seeds)" in capsys.readouterr().err
    assert not (tmp_path / "sw").exists()


def test_points_are_validated_and_keyed(spec):
    pts = sweep_points(spec)
    assert len(pts) == 6 and len({p.key for p in pts}) == 6
    with pytest.raises(ValueError, match=r"radar.num_chirps: got 1, expected >= 4"):
        sweep_points(SweepSpec(spec.base, {"radar.num_chirps": [32, 1]}))
    with pytest.raises(ValueError, match="--seeds"):
        SweepSpec(spec.base, {"seed": [1]})


def test_sweep_on_local_cluster_resumes_after_interruption(spec, client, tmp_path,
                                                           monkeypatch):
    calls = []
    real = sweep_mod._point_metrics

    def counting(scenario, chains):
        calls.append((scenario.scene.targets[0].az_deg, scenario.seed))
        if scenario.scene.targets[0].az_deg == 10.0 and scenario.seed == 1:
            raise RuntimeError("worker lost")          # an interruption inside one point
        return real(scenario, chains)

    monkeypatch.setattr(sweep_mod, "_point_metrics", counting)
    # first run: stopped after 3 points
    r1 = run_sweep(spec, tmp_path, client=client, limit=3)
    assert len(r1.computed) == 3 and not r1.failed
    assert int(r1.dataset["point_done"].sum()) == 3
    # second run: computes the rest; one point fails, the others are kept
    r2 = run_sweep(spec, tmp_path, client=client)
    assert sorted(r2.skipped) == sorted(r1.computed)
    assert len(r2.computed) == 2 and len(r2.failed) == 1
    assert "worker lost" in next(iter(r2.failed.values()))
    assert len(calls) == 6
    # third run with the point fixed: only the failed point is computed
    monkeypatch.setattr(sweep_mod, "_point_metrics", real)
    r3 = run_sweep(spec, tmp_path, client=client)
    assert r3.computed == list(r2.failed) and len(r3.skipped) == 5

    ds = r3.dataset
    assert ds["az_deg"].dims == ("scene_targets_0_az_deg", "seed", "chain")
    assert ds["scene_targets_0_az_deg"].attrs["key_path"] == "scene.targets.0.az_deg"
    assert bool(ds["point_done"].all())
    # the accumulated map (32 chirps) averages the noise that a single chirp sees
    np.testing.assert_allclose(ds["map_az_deg"].sel(chain="none").values,
                               np.repeat([[0.0], [10.0], [20.0]], 2, axis=1), atol=0.1)
    import xarray as xr

    on_disk = xr.open_dataset(r3.path)
    np.testing.assert_array_equal(on_disk["az_deg"].values, ds["az_deg"].values)
    on_disk.close()
    records = list((tmp_path / "points").glob("*.json"))
    assert len(records) == 6
    assert json.loads(records[0].read_text())["chains"]["none"]["range_m"] > 14


def test_sweep_cli_default_local_cluster(tmp_path, capsys):
    args = ["sweep", "--case", "stationary", "--chains", "none", "--no-progress",
            "--param", "scene.targets.0.range_m=10,12", "--out", str(tmp_path)]
    for k, v in SMALL.items():
        args += ["--set", f"{k}={v}"]
    assert main(args + ["--limit", "1"]) == 0
    assert "1/2 points done (1 computed now" in capsys.readouterr().out
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "2/2 points done (1 computed now, 1 from before, 0 failed)" in out
    assert main(["sweep", "--case", "stationary", "--param", "radar.nope=1",
                 "--out", str(tmp_path)]) == 2


TILTED = small_scenario("tilted", az_deg=50.0, pitch_deg=30.0, pitch_hz=5.0,
                        pitch_phase_deg=90.0)


def test_sweep_stores_and_summarises_guard_warnings(tmp_path, capsys):
    """Pitch 30 deg (at 5 Hz: within a gyro's full scale) with the target at azimuth 50 deg:
    the paper chain's small-angle
    warnings (compensation.guards) are kept in the point record and the dataset and
    summarised on stderr; the none chain has none."""
    pytest.importorskip("compensation")
    (tmp_path / "t.toml").write_text(TILTED)
    out = tmp_path / "sw"
    assert main(["sweep", str(tmp_path / "t.toml"), "--chains", "none,paper",
                 "--param", "scene.targets.0.az_deg=50", "--no-progress",
                 "--out", str(out)]) == 0
    err = capsys.readouterr().err
    (record,) = [json.loads(p.read_text()) for p in (out / "points").glob("*.json")]
    assert record["warnings"]["none"] == []
    paper = record["warnings"]["paper"]
    assert paper and all(w.startswith("small-angle: ") for w in paper)
    import xarray as xr

    with xr.open_dataset(out / "sweep.nc") as ds:
        assert ds["warnings"].dims == ("scene_targets_0_az_deg", "seed", "chain")
        assert str(ds["warnings"].sel(chain="paper").values.ravel()[0]).split("\n") == paper
        assert str(ds["warnings"].sel(chain="none").values.ravel()[0]) == ""
        assert sweep_mod.warning_summary(ds) == [
            f"paper: small-angle at 1/1 points (e.g. {paper[0]})"]
    assert f"warning: paper: small-angle at 1/1 points (e.g. {paper[0]})" in err


def test_dimension_names_are_identifiers():
    assert sweep_mod.dimension_name("imu.preset") == "imu_preset"
    assert sweep_mod.dimension_name("motion.sinusoids.0.amplitude_deg") == \
        "motion_sinusoids_0_amplitude_deg"
    assert sweep_mod.dimension_name("0.x") == "p_0_x"
    names = sweep_mod.dimension_names(["a.b", "a_b", "chain"])
    assert names == {"a.b": "a_b", "a_b": "a_b_2", "chain": "chain_2"}
    assert all(n.isidentifier() for n in names.values())


def test_sweep_dimensions_work_with_sel(tmp_path):
    """Nothing computed (limit 0): the gathered Dataset and sweep.nc are indexed by name."""
    import xarray as xr

    base = scenario_from_case("stationary").with_values(SMALL)
    spec = SweepSpec(base, {"imu.preset": ["ideal", "tactical"],
                            "radar.num_chirps": [32, 64]}, (0,), ("none",))
    res = run_sweep(spec, tmp_path, limit=0)
    ds = res.dataset
    assert set(ds.dims) == {"imu_preset", "radar_num_chirps", "seed", "chain"}
    sub = ds["az_deg"].sel(imu_preset="tactical", radar_num_chirps=64, chain="none")
    assert sub.dims == ("seed",) and bool(np.isnan(sub).all())        # not computed yet
    assert ds["imu_preset"].attrs["key_path"] == "imu.preset"
    assert json.loads(ds.attrs["dimensions"]) == {"imu.preset": "imu_preset",
                                                  "radar.num_chirps": "radar_num_chirps"}
    with xr.open_dataset(res.path) as on_disk:
        assert on_disk["point_done"].sel(imu_preset="ideal", radar_num_chirps=32).item() == 0
        assert on_disk["radar_num_chirps"].attrs["key_path"] == "radar.num_chirps"


def test_sweep_refuses_out_of_another_sweep(tmp_path):
    base = scenario_from_case("stationary").with_values(SMALL)
    spec = SweepSpec(base, {"radar.num_chirps": [32, 64]}, (0,), ("none",))
    run_sweep(spec, tmp_path, limit=0)
    run_sweep(spec, tmp_path, limit=0)                       # the same sweep resumes
    before = sorted(p.name for p in tmp_path.rglob("*"))
    others = {
        "parameters": SweepSpec(base, {"radar.num_chirps": [32, 128]}, (0,), ("none",)),
        "seeds": SweepSpec(base, {"radar.num_chirps": [32, 64]}, (0, 1), ("none",)),
        "chains": SweepSpec(base, {"radar.num_chirps": [32, 64]}, (0,), ("exact",)),
        "base.radar.chirp_duration_s": SweepSpec(
            base.with_values({"radar.chirp_duration_s": 25.6e-6}),
            {"radar.num_chirps": [32, 64]}, (0,), ("none",)),
    }
    for what, other in others.items():
        with pytest.raises(ValueError, match=rf"holds another sweep .*differs in {what}"):
            run_sweep(other, tmp_path, limit=0)
    assert sorted(p.name for p in tmp_path.rglob("*")) == before   # nothing written
    (tmp_path / "sweep.json").write_text("{not json")
    with pytest.raises(ValueError, match="sweep.json cannot be read"):
        run_sweep(spec, tmp_path, limit=0)
    (tmp_path / "file").write_text("x")
    for out in (tmp_path / "file", tmp_path / "file" / "sub"):
        with pytest.raises(ValueError, match=r"--out: cannot write .*file.*\(expected a folder\)"):
            run_sweep(spec, out, limit=0)


def test_sweep_cli_refuses_out_of_another_sweep(tmp_path, capsys):
    args = ["sweep", "--case", "stationary", "--no-progress", "--limit", "0",
            "--out", str(tmp_path)]
    assert main(args + ["--param", "radar.num_chirps=32"]) == 0
    capsys.readouterr()
    assert main(args + ["--param", "radar.num_chirps=64"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "holds another sweep" in err
    assert "parameters.radar.num_chirps" in err


def test_more_local_workers_than_the_machine_holds_are_refused(capsys, tmp_path):
    from raysim.cli.cmd_sweep import MAX_WORKERS_PER_CPU

    too_many = MAX_WORKERS_PER_CPU * (__import__("os").cpu_count() or 1) + 1
    code = main(["sweep", "--case", "rotation_y", "--param", "imu.rate_hz=1,2", "--workers",
                 str(too_many), "--out", str(tmp_path / "sw")])
    assert code == 2 and f"--workers: got {too_many}" in capsys.readouterr().err
    assert not (tmp_path / "sw").exists()
