"""System tier: every command that reports a point metric prints the same value for one case.

``simulate --json``, ``reproduce``, ``render`` + ``report``, ``sweep`` and
``scene-report --scenario`` run
one small paper case (two frames, a noisy IMU so that the IMU seeds must agree
too) and every metric two of them share must be equal per chain, not only
named alike: they all read the same frames and IMU log and measure through
:mod:`raysim.measure.point`.

A leg is a function ``(tmp_path) -> {chain: {metric: value}}`` in :data:`LEGS`.
The scene report's own maps (``scene_entropy_*_nats``, ``ridge_leakage_db``)
have names of their own and are not compared here.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from pathlib import Path

import pytest

from raysim.cli import main
from raysim.measure.point import POINT_METRICS
from raysim.scenario import scenario_from_case

#: Relative tolerance of the agreement (the commands compute the same floats).
AGREEMENT_RTOL = 1e-9
#: The case and the scenario keys that shrink it (runs in seconds).
CASE = "rotation_y"
OVERRIDES = {"radar.sample_rate_hz": 2.5e6, "radar.num_chirps": 64, "array.nx": 8,
             "array.ny": 8, "frames": 2}
#: IMU preset of every leg (noisy, so the legs must draw the same IMU errors).
IMU = "consumer_mems"
CHAINS = ("none", "paper", "exact")
#: Metrics every comparison must include.
REQUIRED = {"entropy_ae_nats", "pseudo_velocity_mps", "angle_error_deg"}


def _set_args() -> list[str]:
    args = []
    for key, value in {**OVERRIDES, "imu.preset": IMU}.items():
        args += ["--set", f"{key}={value}"]
    return args


def _scenario():
    return scenario_from_case(CASE).with_values({**OVERRIDES, "imu.preset": IMU})


def _finite(metrics: dict) -> dict:
    return {m: float(v) for m, v in metrics.items()
            if m in POINT_METRICS and v is not None and math.isfinite(float(v))}


def leg_simulate(tmp_path: Path, capsys) -> dict:
    """``raysim simulate --case CASE --json``."""
    capsys.readouterr()
    assert main(["simulate", "--case", CASE, *_set_args(), "--chains", ",".join(CHAINS),
                 "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    return {chain: _finite(m) for chain, m in out["chains"].items()}


def leg_reproduce(tmp_path: Path, capsys) -> dict:
    """``raysim reproduce --cases CASE`` (its function, with the scenario overrides)."""
    from raysim.studies.reproduce import ReproductionSettings, reproduce

    res = reproduce([CASE], imu=IMU, seeds=1, settings=ReproductionSettings(overrides=OVERRIDES),
                    out_dir=str(tmp_path / "reproduction"), figures=False, chains=CHAINS)
    return {row["chain"]: _finite(row) for row in res["rows"]}


def leg_report(tmp_path: Path, capsys) -> dict:
    """``raysim render`` to a store, then what ``raysim report STORE`` measures."""
    from raysim.io import storage
    from raysim.report.html import collect_from_dataset

    toml = tmp_path / "case.toml"
    toml.write_text(_scenario().to_toml())
    store = tmp_path / "case.zarr"
    assert main(["render", str(toml), "--out", str(store), "--no-progress"]) == 0
    data = collect_from_dataset(storage.open_store(store, load=False), chains=CHAINS,
                                source=str(store))
    return {chain: _finite(m) for chain, m in data.result["chains"].items()}


def leg_sweep(tmp_path: Path, capsys) -> dict:
    """``raysim sweep`` of the scenario (one value of one key, seed 0)."""
    import xarray as xr

    toml = tmp_path / "base.toml"
    toml.write_text(_scenario().to_toml())
    out = tmp_path / "sweep"
    assert main(["sweep", str(toml), "--param", f"frames={OVERRIDES['frames']}",
                 "--chains", ",".join(CHAINS), "--out", str(out), "--no-progress"]) == 0
    with xr.open_dataset(out / "sweep.nc") as ds:
        point = ds.isel(frames=0, seed=0).load()
    return {str(chain): _finite({m: point[m].sel(chain=chain).item() for m in POINT_METRICS
                                 if m in point})
            for chain in point.chain.values}


def leg_scene_report(tmp_path: Path, capsys) -> dict:
    """``raysim scene-report --scenario FILE``: the point metrics of its reference target."""
    toml = tmp_path / "case.toml"
    scenario = _scenario()
    toml.write_text(scenario.to_toml())
    out = tmp_path / "report"
    assert main(["scene-report", "--scenario", str(toml), "--quick", "--chains",
                 ",".join(CHAINS), "--out", str(out), "--no-progress"]) == 0
    written = sorted(out.glob("*.json"))
    reports = [json.loads(f.read_text()) for f in written]
    reports = [r for r in reports if "point_metrics" in r]
    assert len(reports) == 1, [f.name for f in written]
    return {chain: _finite(m) for chain, m in reports[0]["point_metrics"]["metrics"].items()
            if chain in CHAINS}


#: Command name -> leg.
LEGS: dict[str, Callable] = {"simulate": leg_simulate, "reproduce": leg_reproduce,
                             "report": leg_report, "sweep": leg_sweep,
                             "scene-report": leg_scene_report}


def test_every_shared_metric_agrees_per_chain(tmp_path, capsys):
    got = {}
    for name, leg in LEGS.items():
        (tmp_path / name).mkdir()
        got[name] = leg(tmp_path / name, capsys)
    compared: set[str] = set()
    names = list(got)
    for i, a in enumerate(names):
        for b in names[i + 1:]:
            chains = set(got[a]) & set(got[b])
            assert chains == set(CHAINS), (a, b, sorted(got[a]), sorted(got[b]))
            for chain in sorted(chains):
                shared = set(got[a][chain]) & set(got[b][chain])
                assert REQUIRED <= shared, (a, b, chain, sorted(shared))
                compared |= shared
                for m in sorted(shared):
                    assert got[a][chain][m] == pytest.approx(got[b][chain][m],
                                                             rel=AGREEMENT_RTOL, abs=0.0), \
                        f"{m} of chain {chain}: {a} {got[a][chain][m]!r}, {b} {got[b][chain][m]!r}"
    assert REQUIRED <= compared


#: Relative agreement of the accumulated AE map of ``none`` formed from the chirp mean
#: and from every chirp's beams (complex64 beams).
LINEAR_MAP_RTOL = 1e-5


def test_none_chain_map_of_the_chirp_mean_is_the_mean_of_its_beams():
    """``gate_metrics`` beamforms the chirp mean for ``none``; a NumPy reference sums beams."""
    import numpy as np

    from raysim.measure.point import PointGate, gate_metrics, map_grid
    from raysim.pipeline.sources import Reference

    s = _scenario().with_values({"frames": 1})
    cfg, arr = s.radar_config(), s.virtual_array()
    rng = np.random.default_rng(3)
    snaps = (rng.standard_normal((1, cfg.num_chirps, arr.num_channels))
             + 1j * rng.standard_normal((1, cfg.num_chirps, arr.num_channels)))
    maps: dict = {}
    gate_metrics(PointGate(snaps.astype(np.complex64), 15.0, cfg, arr),
                 Reference(15.0, 20.0, 0.0), maps=maps)
    g = map_grid()
    az, el = np.meshgrid(g, g, indexing="ij")
    u = np.stack([np.cos(el) * np.sin(az), np.sin(el), np.cos(el) * np.cos(az)], axis=-1)
    steer = arr.steering_vector(u.reshape(-1, 3), cfg.center_wavelength)   # [direction, channel]
    beams = snaps[0].astype(np.complex64) @ np.conj(steer).T / arr.num_channels
    ref = np.abs(beams.mean(axis=0)) ** 2
    got = maps["ae"].values.ravel()
    assert np.allclose(got / got.max(), ref / ref.max(), rtol=0, atol=LINEAR_MAP_RTOL)
