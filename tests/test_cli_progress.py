"""`raysim simulate` and `raysim rcs` show their progress on stderr; --no-progress silences it."""

from __future__ import annotations

import json

from raysim.cli import main

SMALL = ["--set", "radar.num_chirps=16", "--set", "array.nx=4", "--set", "array.ny=4",
         "--set", "radar.chirp_duration_s=12.8e-6", "--frames", "2"]


def test_simulate_shows_progress_unless_told_not_to(capsys):
    assert main(["simulate", "--case", "stationary", "--chains", "none,exact", "--json",
                 *SMALL]) == 0
    out = capsys.readouterr()
    assert "2/2" in out.err and "frame" in out.err             # one step per frame rendered
    assert "measuring chains none, exact" in out.err           # then the chains it measures
    first = json.loads(out.out)["chains"]
    assert main(["simulate", "--case", "stationary", "--chains", "none,exact", "--json",
                 *SMALL, "--no-progress"]) == 0
    out = capsys.readouterr()
    assert out.err == ""
    assert json.loads(out.out)["chains"] == first               # the bar changes nothing else


def test_rcs_shows_progress_unless_told_not_to(capsys):
    args = ["rcs", "plate:0.05", "--az-deg", "-2:2:2", "--el-deg", "-1,0", "--max-bounces",
            "1", "--json"]
    assert main(args) == 0
    out = capsys.readouterr()
    assert "6/6" in out.err and "direction" in out.err          # one step per direction
    first = json.loads(out.out)["rcs_dbsm"]
    assert main([*args, "--no-progress"]) == 0
    out = capsys.readouterr()
    assert out.err == ""
    assert json.loads(out.out)["rcs_dbsm"] == first
