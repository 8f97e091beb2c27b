"""One vocabulary: the names of chains, metrics and motions in every command's output.

``simulate --json``, ``report``, ``sweep`` and ``render`` run on the same small
scenario; every chain key and metric name they write must come from
:mod:`raysim.vocabulary`, and the same quantity must carry the same name (and,
where two commands compute it for the same scenario, the same value). The
studies too: ``reproduce`` rows and the stability metrics use the same names,
and ``simulate`` and ``reproduce`` give the same metric values on the
same paper case.
"""

from __future__ import annotations

import contextlib
import io
import json
import re

import pytest
import xarray as xr
import zarr
from scenario_texts import small_scenario

from raysim.cli import main
from raysim.measure.point import POINT_METRICS
from raysim.vocabulary import (
    CHAINS,
    MAP_TITLES,
    MAPS,
    METRICS,
    ROTATION_PHASES,
    ChainSpec,
    metric_unit,
    parse_chain,
    parse_chains,
)

#: Every chain key the commands accept, in the order asked for.
ALL_CHAINS = "none,paper,paper:published,exact"
#: The scenario every command runs: SMALL of tests/test_cli_simulate.py (32 chirps,
#: 4 x 4 UPA, 12.8 us chirps) with the rotation_y motion and target.
SCENARIO = small_scenario("vocabulary", frames=1, pitch_deg=10.0)
MOTION_LABEL = "pitch 10 deg @ 20 Hz"


def _valid_chain_key(key: str) -> bool:
    try:
        return parse_chain(key).key == key
    except ValueError:
        return False


# ------------------------------------------------------------ the module
def test_parse_chain_names_the_bad_value():
    for bad, needle in (("uncompensated", "'uncompensated'"), ("magic", "'magic'"),
                        ("exact:published", "'exact:published'"),
                        ("paper:sideways", "'sideways'")):
        with pytest.raises(ValueError, match=re.escape(needle)):
            parse_chain(bad)
    with pytest.raises(ValueError, match="42"):
        parse_chain(42)
    with pytest.raises(ValueError, match="at least one"):
        parse_chains("")
    with pytest.raises(ValueError, match="once"):
        parse_chains("paper,none,paper")


def test_paper_published_round_trips():
    spec = parse_chain("paper:published")
    assert spec == ChainSpec("paper", "published") and spec.compensated
    assert spec.key == str(spec) == "paper:published"
    assert parse_chain(spec.key) == spec
    # the default rotation phase is not written
    assert parse_chain("paper").key == "paper"
    assert parse_chain(f"paper:{ROTATION_PHASES[0]}").key == "paper"
    assert [s.key for s in parse_chains(ALL_CHAINS)] == ALL_CHAINS.split(",")
    assert [s.key for s in parse_chains(CHAINS)] == list(CHAINS)
    assert not parse_chain("none").compensated


def test_metric_unit_of_unknown_name_raises_naming_it():
    assert metric_unit("angle_error_deg") == "deg"
    assert metric_unit("pseudo_velocity_mps_std") == "m/s"
    with pytest.raises(ValueError, match="'angle_err'"):
        metric_unit("angle_err")
    assert set(POINT_METRICS) <= set(METRICS)
    assert set(MAP_TITLES) == set(MAPS)


# ------------------------------------------------------- the commands
@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """What simulate --json, report, sweep and render write for the same scenario."""
    pytest.importorskip("compensation")
    d = tmp_path_factory.mktemp("vocab")
    scen = d / "s.toml"
    scen.write_text(SCENARIO)
    out = {}
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf), contextlib.redirect_stderr(io.StringIO()):
        assert main(["simulate", "--scenario", str(scen), "--chains", ALL_CHAINS,
                     "--json"]) == 0
        out["simulate"] = json.loads(buf.getvalue())
        assert main(["report", "--scenario", str(scen), "--chains", ALL_CHAINS,
                     "--out", str(d / "r.html")]) == 0
        assert main(["sweep", str(scen), "--param", "scene.targets.0.range_m=15.0",
                     "--chains", ALL_CHAINS, "--no-progress", "--out", str(d / "sweep")]) == 0
        assert main(["render", str(scen), "--out", str(d / "s.zarr"), "--no-progress"]) == 0
    out["report"] = (d / "r.html").read_text()
    with xr.open_dataset(d / "sweep" / "sweep.nc") as ds:
        out["sweep"] = ds.load()
    out["points"] = [json.loads(p.read_text()) for p in (d / "sweep" / "points").glob("*.json")]
    out["store"] = dict(zarr.open_group(str(d / "s.zarr"), mode="r").attrs)
    return out


def _report_table(text: str) -> tuple[list[str], dict[str, str]]:
    table = re.search(r"<table class='metrics'>(.*?)</table>", text, re.S).group(1)
    header = re.findall(r"<th>([^<]*)</th>", table)
    assert header[:2] == ["metric", "unit"] and header[-1] == "definition"
    units = dict(re.findall(r"<tr><td>([^<]+)</td><td>([^<]*)</td>", table))
    return header[2:-1], units


def test_chain_keys_are_the_vocabulary_and_the_same_everywhere(outputs):
    want = ALL_CHAINS.split(",")
    sim = outputs["simulate"]
    assert list(sim["chains"]) == want and list(sim["warnings"]) == want
    report_chains, _ = _report_table(outputs["report"])
    sweep_chains = [str(c) for c in outputs["sweep"]["chain"].values]
    point_chains = [list(p["chains"]) for p in outputs["points"]]
    assert report_chains == want and sweep_chains == want and point_chains == [want]
    assert list(outputs["points"][0]["warnings"]) == want
    for key in want:
        assert _valid_chain_key(key), key


def test_metric_names_and_units_are_the_vocabulary_and_the_same_everywhere(outputs):
    sim = outputs["simulate"]
    names = set(POINT_METRICS)
    assert names <= set(METRICS)
    assert sim["units"] == {m: METRICS[m][0] for m in POINT_METRICS}
    for chain, metrics in sim["chains"].items():
        assert set(metrics) == names, chain
    _, report_units = _report_table(outputs["report"])
    assert report_units == sim["units"]
    ds = outputs["sweep"]
    sweep_metrics = set(ds.data_vars) - {"point_done", "warnings"}
    assert sweep_metrics == names
    assert {m: ds[m].attrs["units"] for m in sweep_metrics} == sim["units"]
    for p in outputs["points"]:
        for chain, metrics in p["chains"].items():
            assert set(metrics) == names, chain
    # the reference target in a store: the metric names of the truth, prefixed
    ref = {k.removeprefix("reference_"): v for k, v in outputs["store"].items()
           if k.startswith("reference_")}
    assert set(ref) == set(sim["reference"]) and set(ref) <= set(METRICS)
    assert ref == pytest.approx(sim["reference"])


def test_same_scenario_gives_the_same_numbers_in_simulate_and_sweep(outputs):
    ds = outputs["sweep"]
    for chain, metrics in outputs["simulate"]["chains"].items():
        for m, v in metrics.items():
            got = float(ds[m].sel(chain=chain).values.ravel()[0])
            if v is None:                                  # NaN in strict JSON
                assert got != got, (chain, m)
            else:
                assert got == pytest.approx(v, rel=1e-9, abs=1e-12), (chain, m)


def test_motion_label_is_the_same_everywhere(outputs):
    assert outputs["simulate"]["motion"] == MOTION_LABEL
    assert outputs["store"]["motion_name"] == MOTION_LABEL
    assert f"Motion: {MOTION_LABEL}" in outputs["report"]
    from raysim.scenario import scenario_from_case

    # a paper case's motion (built by raysim.platform.motion.sinusoid) reads the same
    assert scenario_from_case("rotation_y").trajectory().name == MOTION_LABEL
    assert scenario_from_case("translation_z").trajectory().name == "z 0.05 m @ 5 Hz"


def test_report_maps_are_titled_by_the_vocabulary(outputs):
    for name in MAPS:
        assert f"{MAP_TITLES[name]} maps" in outputs["report"]


# ------------------------------------------------- the studies speak it too
#: Columns of a reproduction row that describe the run rather than measure it.
REPRODUCE_DESCRIPTORS = {"case", "chain", "imu", "seeds", "num_chirps", "frames",
                         "velocity_bin_mps", "doppler_bin_hz", "warnings"}
#: Relative difference of one metric between ``simulate`` and ``reproduce`` on the same
#: case: both measure the same frames and IMU log with ``raysim.measure.point``.
SAME_METRIC_RTOL = 1e-9


def _metric_name(key: str) -> str:
    for prefix in ("stationary_", "paper_"):
        if key.startswith(prefix) and key[len(prefix):] in METRICS:
            return key[len(prefix):]
    return key[:-4] if key.endswith("_std") else key


@pytest.fixture(scope="module")
def reproduction(tmp_path_factory):
    out = tmp_path_factory.mktemp("repro")
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(["reproduce", "--quick", "--cases", "rotation_y", "--chains", ALL_CHAINS,
                     "--no-figures", "--out", str(out)]) == 0
    return json.loads((out / "reproduction.json").read_text())


def test_reproduce_rows_use_the_vocabulary(reproduction):
    rows = reproduction["rows"]
    assert [r["chain"] for r in rows] == ALL_CHAINS.split(",")
    for row in rows:
        for key in row:
            if key not in REPRODUCE_DESCRIPTORS:
                assert _metric_name(key) in METRICS, key


def test_simulate_and_reproduce_agree_on_the_same_case(reproduction, capsys):
    """The paper case rotation_y at the reproduction's quick size through ``simulate``."""
    code = main(["simulate", "--case", "rotation_y", "--json", "--chains", ALL_CHAINS,
                 "--set", "radar.sample_rate_hz=2.5e6"])
    assert code == 0
    sim = json.loads(capsys.readouterr().out)
    for row in reproduction["rows"]:
        got = sim["chains"][row["chain"]]
        for m in ("angle_error_deg", "az_deg", "el_deg", "entropy_ae_nats", "map_az_deg",
                  "map_el_deg", "pseudo_velocity_mps", "doppler_width_hz"):
            assert got[m] == pytest.approx(row[m], rel=SAME_METRIC_RTOL, abs=0.0), \
                (row["chain"], m)


def test_stability_names_are_the_vocabulary():
    from raysim.studies import stability

    assert set(stability.STABILITY_METRICS) <= set(METRICS)
    assert all(_valid_chain_key(c) for c in stability.MAP_CHAINS)


def test_chain_keys_are_the_one_vocabulary():
    """Every chain key (options included) parses to itself; the studies' chain lists are it."""
    from raysim.studies.reproduce import DEFAULT_CHAINS
    from raysim.studies.stability.metrics import MAP_CHAINS
    from raysim.vocabulary import CHAIN_KEYS, CHAIN_NAMES, CHAINS, parse_chains

    assert [s.key for s in parse_chains(CHAIN_KEYS)] == list(CHAIN_KEYS)
    assert set(CHAINS) <= set(CHAIN_KEYS)
    assert set(CHAINS) <= set(CHAIN_NAMES) and [s.name for s in parse_chains(CHAIN_NAMES)] == \
        list(CHAIN_NAMES)
    assert DEFAULT_CHAINS == MAP_CHAINS == CHAIN_KEYS
