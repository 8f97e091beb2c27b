"""`raysim scene-report --scenario`: a point-target scenario measured as `raysim simulate` does."""

from __future__ import annotations

import json
import math

import pytest

from raysim.cli import main

#: Largest difference between the point metrics of ``scene-report --scenario`` and those of
#: ``raysim simulate --scenario`` for the same scenario (same frames, same IMU record, same
#: motion estimate, same measurement: equal to the last bit; the bound only absorbs JSON
#: round-tripping) [in each metric's unit].
SAME_VALUE_TOL = 1e-12
#: Chains compared (all of them, the paper chain with both rotation phases).
CHAINS = "none,paper,paper:published,exact"
#: A small paper-case scenario: pitch 10 deg at 20 Hz, target at 15 m, azimuth 20 deg.
SMALL_POINT = """
name = "small rotation_y"
frames = {frames}
seed = 0
lever_arm_m = [0.0, 0.0, 0.1]

[radar]
num_chirps = 32

[array]
{array}

[[scene.targets]]
range_m = 15.0
az_deg = 20.0
el_deg = 0.0

[motion]
case = "rotation_y"

[imu]
preset = "tactical"
rate_hz = 2000.0
"""
ARRAYS = {"upa": 'kind = "upa"\nnx = 4\nny = 4', "ti_3tx4rx": 'kind = "ti_3tx4rx"'}


def _same(a, b) -> bool:
    if a is None or b is None or (isinstance(a, float) and math.isnan(a)):
        return (a is None or math.isnan(a)) and (b is None or math.isnan(b))
    return abs(a - b) <= SAME_VALUE_TOL


@pytest.mark.parametrize(("array", "frames"), [("upa", 1), ("ti_3tx4rx", 2)])
def test_point_metrics_equal_simulate(tmp_path, capsys, array, frames):
    """Every metric the two commands share has the same value, per chain (UPA, one frame;
    TDM MIMO, two frames: every slot at its own pose)."""
    path = tmp_path / "small.toml"
    path.write_text(SMALL_POINT.format(frames=frames, array=ARRAYS[array]))
    out = tmp_path / "report"
    assert main(["scene-report", "--scenario", str(path), "--quick", "--chains", CHAINS,
                 "--out", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    assert main(["simulate", "--scenario", str(path), "--chains", CHAINS, "--json"]) == 0
    simulated = json.loads(capsys.readouterr().out)
    report = json.loads((out / "small_rotation_y.json").read_text())
    assert report["point_metrics"]["reference"] == simulated["reference"]
    points = report["point_metrics"]["metrics"]
    assert set(simulated["chains"]) == set(CHAINS.split(",")) <= set(points)
    for chain, metrics in simulated["chains"].items():
        shared = set(metrics) & set(points[chain])
        assert shared == set(metrics), chain                 # every point metric is reported
        diff = {m: (metrics[m], points[chain][m]) for m in shared
                if not _same(metrics[m], points[chain][m])}
        assert diff == {}, chain
    # the scene maps are named apart from the point metrics of the same map
    assert {"scene_entropy_rd_nats", "scene_entropy_ae_nats"} <= set(
        report["reference"]["metrics"])
    assert "point metrics" in (out / "report.md").read_text().lower()


def test_scenario_errors_are_named(tmp_path, capsys):
    """A missing scenario file, a car, a jitter seed or jitter axes on point targets without
    hover jitter, and a bad range window exit 2 naming the setting."""
    assert main(["scene-report", "--scenario", str(tmp_path / "nope.toml"),
                 "--out", str(tmp_path / "o")]) == 2
    assert "nope.toml" in capsys.readouterr().err
    path = tmp_path / "small.toml"
    path.write_text(SMALL_POINT.format(frames=1, array=ARRAYS["upa"]))
    assert main(["scene-report", "--scenario", str(path), "--mover-speed", "6",
                 "--out", str(tmp_path / "o")]) == 2
    assert "mover_speed" in capsys.readouterr().err
    assert main(["scene-report", "--scenario", str(path), "--range-window", "20,10",
                 "--out", str(tmp_path / "o")]) == 2
    assert "--range-window" in capsys.readouterr().err
    assert main(["scene-report", "--scenario", str(path), "--jitter-seed", "3",
                 "--out", str(tmp_path / "o")]) == 2
    assert "hover_jitter" in capsys.readouterr().err
    assert main(["scene-report", "--scenario", str(path), "--jitter-axes", "z",
                 "--out", str(tmp_path / "o")]) == 2
    assert "jitter_axes" in capsys.readouterr().err


def test_default_range_window_fits_a_short_range_radar():
    """The default window is cut to a scenario radar's unambiguous range; a set one is kept."""
    from raysim.scenario import scenario_from_case
    from raysim.studies.scene_report import QUICK

    sc = scenario_from_case("rotation_y").with_values({"radar.sample_rate_hz": 2.5e6})
    cfg = sc.radar_config()
    lo, hi = QUICK.for_scenario(sc).range_window
    assert hi == pytest.approx(cfg.max_range - 2 * cfg.range_resolution)
    assert 0 <= lo < hi
    with pytest.raises(ValueError, match="max_range"):
        QUICK.with_values(range_window=(5.0, 40.0)).for_scenario(sc)
    assert QUICK.with_values(range_window=(5.0, 20.0)).for_scenario(sc).range_window == (5.0,
                                                                                         20.0)


def test_scene_report_traces_on_the_variant_the_environment_names(tmp_path, monkeypatch):
    """`raysim scene-report` leaves the Mitsuba variant to RAYSIM_RT_VARIANT (the README's
    switch to the GPU), the CPU where it is unset; the report itself is stubbed."""
    import raysim.studies.scene_report as sr
    from raysim.echoes.rt import backend

    asked = []
    monkeypatch.setattr(backend, "configure",
                        lambda variant=None, **kw: asked.append(backend.resolve_variant(variant)))
    monkeypatch.setattr(sr, "write_scene_report", lambda *a, **kw: {})
    for env, expected in ((None, backend.CPU_VARIANT), ("gpu", backend.GPU_VARIANT)):
        if env is None:
            monkeypatch.delenv("RAYSIM_RT_VARIANT", raising=False)
        else:
            monkeypatch.setenv("RAYSIM_RT_VARIANT", env)
        assert main(["scene-report", "--scenes", "flat_reflectors", "--quick", "--out",
                     str(tmp_path / str(env)), "--no-progress"]) == 0
        assert asked[-1] == expected
