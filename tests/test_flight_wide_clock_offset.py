"""A clock offset past the +-10 ms the automatic search covers by default.

The coarse search of ``--time-offset auto`` tries offsets within +-10 ms of 0; a log
20 ms off settled at another minimum of the misfit inside that window (24 ms off,
0.36 deg, 0.06 bin, nothing about the search said). ``--time-offset-search`` widens it
(the misfit's lowest minimum over +-60 ms lies at the truth), the summary states the
window searched, and ``raysim flight`` prints it for an offset it was told of past the
default.
"""

from __future__ import annotations

import contextlib
import io
import json
import shlex

import pytest

from raysim.cli import main
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import write_flight
from raysim.pipeline.flight_truth import LIMITS

#: IMU clock minus radar clock [s]: twice the default search.
OFFSET_S = 0.02
CLOCK_SIGMAS = 3.0
GRID = ("--range-m", "4:9.3", "--az-deg", "-40:40:0.5", "--el-deg", "-5:5:5", "--no-progress")


def test_an_offset_past_the_default_search_is_found_with_a_wider_one(tmp_path, capsys):
    flight = write_flight(tmp_path / "f", frames=3, targets="default5", time_offset=OFFSET_S,
                          progress=False)
    args = flight.calibrating_command(tmp_path / "c.zarr", *GRID)
    assert args[args.index("--time-offset-search") + 1] == "0.03"
    out = io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(io.StringIO()):
        assert main(args) == 0
    ds = open_store(tmp_path / "c.zarr")
    cal = json.loads(ds.attrs["self_calibration"])
    err = ds.attrs["time_offset_s"] - OFFSET_S
    assert abs(err) * 1e3 <= LIMITS["offset_error_ms"] and abs(err) <= CLOCK_SIGMAS * cal[
        "time_offset_sigma_s"], err
    assert "(searched +-30 ms about 0" in out.getvalue()
    # the flight's command line prints it too
    assert main(["flight", str(tmp_path / "g"), "--frames", "1", "--imu", "ideal",
                 "--time-offset", "0.02", "--no-progress"]) == 0
    printed = [shlex.split(x.strip()) for x in capsys.readouterr().out.splitlines()
               if "--time-offset auto" in x]
    assert printed and printed[0][printed[0].index("--time-offset-search") + 1] == "0.03"


@pytest.mark.parametrize("extra, said", [
    (("--time-offset", "0.003", "--time-offset-search", "0.03"), "--time-offset is"),
    (("--time-offset", "auto", "--time-offset-search", "-0.01"), "positive half-width")])
def test_a_search_width_without_auto_or_not_positive_is_refused(tmp_path, capsys, extra, said):
    flight = write_flight(tmp_path / "f", frames=1, imu="ideal", progress=False)
    args = flight.command(tmp_path / "c.zarr", *GRID)
    i = args.index("--time-offset")
    args = args[:i] + args[i + 2:] + list(extra)
    assert main(args) == 2
    assert said in capsys.readouterr().err
    assert not (tmp_path / "c.zarr").exists()
