"""End to end from files: a simulated flight, then ONE self-calibrating `raysim compensate`.

`raysim flight` writes a PX4 ULog (consumer MEMS IMU at 1 kHz, 3 ms late), a DCA1000
capture and its SDK .cfg of a point target seen from a drone in hover jitter with rotor
vibration (:func:`raysim.pipeline.flight.write_flight`). The compensate command gets only
what a user has: the IMU grade, the lever arm and the flight controller's attitude at the
first ramp; the initial velocity and the clock offset are estimated from the radar
(``--velocity radar --time-offset auto``). Every frame is measured from the store.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from raysim.cli import main
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import MEASURE_STEP_DEG, measure_store, write_flight

#: Must-show bounds, every frame: residual pseudo-velocity [bin], Doppler power outside
#: +-1 bin of the peak [dB], azimuth error [deg], clock-offset error [s].
PSEUDO_VELOCITY_BINS = 0.05
LEAKAGE_DB = -35.0
ANGLE_TOL_DEG = 0.2
OFFSET_TOL_S = 0.5e-3
#: Clock offset of the flight (IMU minus radar) [s] and its frames.
TIME_OFFSET = 0.003
FRAMES = 4


def _cells(flight):
    r, az, _ = flight.target
    return ("--range-m", f"{r - 0.5}:{r + 0.5}", "--az-deg",
            f"{az - 6}:{az + 6}:{MEASURE_STEP_DEG}", "--el-deg", "0:0:1", "--no-progress")


def test_flight_files_self_calibrated_in_one_command(tmp_path, capsys):
    flight = write_flight(tmp_path / "f", imu="consumer_mems", time_offset=TIME_OFFSET,
                          frames=FRAMES, seed=1)
    args = flight.calibrating_command(tmp_path / "c.zarr", *_cells(flight))
    # nothing of the truth but the attitude a flight controller logs
    assert "--initial-velocity" not in args
    assert args[args.index("--time-offset") + 1] == "auto"
    assert args[args.index("--velocity") + 1] == "radar"
    assert main(args) == 0
    assert "time offset" in capsys.readouterr().out
    ds = open_store(tmp_path / "c.zarr")
    assert list(ds["frame"].values) == list(range(FRAMES))
    assert abs(ds.attrs["time_offset_s"] - TIME_OFFSET) <= OFFSET_TOL_S
    cal = json.loads(ds.attrs["self_calibration"])
    assert cal["time_offset_s"] == ds.attrs["time_offset_s"]
    m = measure_store(tmp_path / "c.zarr", flight)              # [frame, 3]
    assert m.shape == (FRAMES, 3)
    assert np.all(m[:, 0] <= ANGLE_TOL_DEG)
    assert np.all(np.abs(m[:, 1]) <= PSEUDO_VELOCITY_BINS)
    assert np.all(m[:, 2] <= LEAKAGE_DB)


def test_same_files_uncalibrated_miss_the_bounds(tmp_path):
    """The same log with the hover velocity and no clock offset: the unknowns matter
    (so the calibrated run's bounds are not met by doing nothing)."""
    flight = write_flight(tmp_path / "f", imu="consumer_mems", time_offset=TIME_OFFSET,
                          frames=FRAMES, seed=1)
    args = flight.calibrating_command(tmp_path / "u.zarr", *_cells(flight))
    args[args.index("--time-offset") + 1] = "0"
    args[args.index("--velocity") + 1] = "hover"
    assert main(args) == 0
    m = measure_store(tmp_path / "u.zarr", flight)
    assert (np.abs(m[:, 1]).max() > PSEUDO_VELOCITY_BINS or m[:, 2].max() > LEAKAGE_DB
            or m[:, 0].max() > ANGLE_TOL_DEG)


def test_flight_prints_the_calibrating_command_first(tmp_path, capsys):
    """`raysim flight` prints the self-calibrating command (with the IMU grade) before the
    one with the simulated offset and velocity given; an unknown grade is refused."""
    import shlex

    assert main(["flight", str(tmp_path / "fl"), "--frames", "1", "--imu", "tactical"]) == 0
    lines = [ln.strip() for ln in capsys.readouterr().out.splitlines()
             if ln.strip().startswith("raysim compensate")]
    assert len(lines) == 2
    first = shlex.split(lines[0])
    assert first[first.index("--imu-grade") + 1] == "tactical"
    assert first[first.index("--time-offset") + 1] == "auto"
    assert "--initial-velocity" in shlex.split(lines[1])
    with pytest.raises(SystemExit) as exc:
        main(first[1:] + ["--imu-grade", "hobby"])
    assert exc.value.code == 2
    assert "--imu-grade" in capsys.readouterr().err
