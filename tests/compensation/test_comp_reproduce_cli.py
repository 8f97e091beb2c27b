"""`raysim reproduce` on a reduced size: noisy IMU over 20 seeds, table files, figures."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from raysim.cli import main


def test_reproduce_consumer_mems_20_seeds(tmp_path, capsys):
    out = tmp_path / "rep"
    code = main(["reproduce", "--quick", "--cases", "rotation_y", "--imu", "consumer_mems",
                 "--seeds", "20", "--chains", "none,exact", "--no-figures",
                 "--out", str(out)])
    assert code == 0
    text = capsys.readouterr().out
    assert "rotation_y" in text and "+-" in text
    res = json.loads((out / "reproduction.json").read_text())
    rows = {r["chain"]: r for r in res["rows"]}
    assert rows["exact"]["seeds"] == 20 and rows["exact"]["imu"] == "consumer_mems"
    assert rows["exact"]["pseudo_velocity_bins_std"] > 0
    assert res["meta"]["units"]["entropy_ae_nats"] == "nats"
    for key in ("pseudo_velocity_mps", "doppler_width_hz", "angle_error_deg", "entropy_ae_nats"):
        assert np.isfinite(rows["exact"][key]) and np.isfinite(rows["exact"][key + "_std"])
    with open(out / "reproduction.csv", newline="") as fh:
        assert len(list(csv.DictReader(fh))) == 2
    assert not list(out.glob(".tmp_*"))


def test_reproduce_writes_figures(tmp_path):
    out = tmp_path / "fig"
    assert main(["reproduce", "--quick", "--cases", "stationary", "--out", str(out)]) == 0
    names = sorted(p.name for p in (out / "figures").glob("*.png"))
    assert names == ["stationary_ideal_ae.png", "stationary_ideal_ra.png",
                     "stationary_ideal_rd.png"]


def test_reproduce_rejects_bad_options(tmp_path, capsys):
    assert main(["reproduce", "--cases", "loop", "--out", str(tmp_path)]) == 2
    assert "unknown case 'loop'" in capsys.readouterr().err
    assert main(["reproduce", "--imu", "cheap", "--out", str(tmp_path)]) == 2
    assert main(["reproduce", "--seeds", "0", "--out", str(tmp_path)]) == 2
    assert main(["reproduce", "--chains", "uncompensated", "--out", str(tmp_path)]) == 2
    assert "--chains: got 'uncompensated'" in capsys.readouterr().err
    assert main(["reproduce", "--chains", "paper_vrt", "--out", str(tmp_path)]) == 2
    assert "paper:published" in capsys.readouterr().err


def test_reproduce_help_has_examples(capsys):
    with pytest.raises(SystemExit):
        main(["reproduce", "--help"])
    text = capsys.readouterr().out
    assert "examples:" in text and "raysim reproduce --out" in text and "paper:published" in text
