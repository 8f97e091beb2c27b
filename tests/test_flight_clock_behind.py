"""A flight whose IMU clock runs behind the radar's (a negative ``time_offset``).

A flight controller's log counts from its own boot, so its stamps are never
negative; with the IMU clock behind, the simulated log starts where that clock
reads zero, and the self-calibration finds the negative offset as it finds a
positive one. Also: the compensate summary of a run without ground points says
so instead of printing a fit it did not make.
"""

from __future__ import annotations

import contextlib
import io
import json

from raysim.cli import main
from raysim.cli.cmd_compensate import _calibration_text
from raysim.io.flight_logs import read_imu_log
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import write_flight

#: IMU clock minus radar clock [s] and its rate error [ppm]: behind, and slowing.
OFFSET_S = -0.006
DRIFT_PPM = -30.0
#: The clock offset's bound (the flights' 0.5 ms) and the stated spreads it must lie in.
OFFSET_TOL_S = 0.5e-3
CLOCK_SIGMAS = 3.0


def test_a_clock_behind_the_radar_gives_a_log_from_boot_and_is_found(tmp_path):
    flight = write_flight(tmp_path / "f", targets="default5", time_offset=OFFSET_S,
                          clock_drift_ppm=DRIFT_PPM, frames=2)
    log = read_imu_log(flight.imu_log)
    assert log.time[0] >= 0.0                                   # stamps since boot
    assert log.time[0] <= flight.start + OFFSET_S               # and the capture covered
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(flight.calibrating_command(tmp_path / "c.zarr")) == 0
    ds = open_store(tmp_path / "c.zarr")
    cal = json.loads(ds.attrs["self_calibration"])
    err = ds.attrs["time_offset_s"] - OFFSET_S
    assert abs(err) <= OFFSET_TOL_S, err
    assert abs(err) <= CLOCK_SIGMAS * cal["time_offset_sigma_s"], (err, cal)


def test_the_summary_names_a_ground_plane_it_could_not_fit():
    report = {"scatterers": 1, "ground_plane": {
        "tilt_deg": [float("nan")] * 2, "tilt_sigma_deg": [float("nan")] * 2,
        "role": "check of the given attitude", "inliers": 0, "points": 0,
        "assumption": "level flat ground in view"}}
    text = _calibration_text(report)
    assert "ground plane tilt [deg] (N, E) not fitted" in text and "nan" not in text
