"""`raysim report` shows its progress on stderr (frames read, chains measured); --no-progress
silences it."""

from __future__ import annotations

from raysim.cli import main
from raysim.pipeline.run import render
from raysim.scenario import scenario_from_case

SMALL = {"radar.num_chirps": 16, "array.nx": 4, "array.ny": 4, "frames": 2,
         "radar.chirp_duration_s": 12.8e-6}


def test_report_shows_progress_unless_told_not_to(tmp_path, capsys):
    s = scenario_from_case("stationary").with_values(SMALL)
    render(s, tmp_path / "s.zarr")
    capsys.readouterr()
    assert main(["report", str(tmp_path / "s.zarr"), "--out", str(tmp_path / "a.html")]) == 0
    err = capsys.readouterr().err
    assert "2/2" in err and "frame" in err                    # one step per frame read
    assert "measuring chains none, paper, exact" in err    # then the chains it measures
    assert main(["report", str(tmp_path / "s.zarr"), "--out", str(tmp_path / "b.html"),
                 "--no-progress"]) == 0
    err = capsys.readouterr().err
    assert "2/2" not in err and "measuring" not in err
    assert main(["report", "--scenario", "examples/case_stationary.toml", "--set",
                 "radar.num_chirps=16", "--set", "array.nx=4", "--set", "array.ny=4",
                 "--out", str(tmp_path / "c.html")]) == 0
    err = capsys.readouterr().err
    assert "1/1" in err and "rendering" in err
