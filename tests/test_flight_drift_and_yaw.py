"""A capture like an independent one: the platform drifts and turns while it shakes.

Five stationary targets (default5), the platform drifting 0.3 m/s east (across the
array's elevation axis) and turning 5.7 deg/s, its hover sway and rotor vibration at
118-173 Hz, a 5 cm lever arm, a consumer-MEMS IMU at 1 kHz, the IMU clock 4.7 ms ahead
with 30 ppm drift, two logger gaps, ground clutter, six frames, the true attitude at the
first ramp given as numbers; one ``raysim compensate --velocity radar --time-offset
auto``. By the capture's start the drift has carried the platform 15 cm: the targets
are seen up to 2.6 deg off their nominal elevations. On a beam grid through where they
are seen every bound holds; on the nominal -5:5:5 grid a target between the beams keeps
the drift's Doppler across it (0.094 bin, -32.7 dB, 0.34 deg), and the command says so.
"""

from __future__ import annotations

import contextlib
import io
from dataclasses import replace

import numpy as np
import pytest

from raysim.cli import main
from raysim.cli.cmd_flight import elevation_grid
from raysim.pipeline.flight import write_flight
from raysim.pipeline.flight_truth import LIMITS, score_flight
from raysim.platform.motion import (
    HoverJitterSpec,
    Ramp,
    Trajectory,
    constant_velocity,
    hover_jitter,
)

#: Seed, drift [m/s, east], yaw rate [rad/s] and rotor band [Hz] of the flight.
SEED, DRIFT_MPS, YAW_RATE, ROTOR_BAND_HZ = 2, 0.3, -np.deg2rad(5.7), (118.0, 173.0)
#: IMU clock ahead of the radar's [s] and its drift [ppm].
TIME_OFFSET_S, DRIFT_PPM = 0.0047, 30.0


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    traj = (hover_jitter(SEED, replace(HoverJitterSpec(), vibration_band=ROTOR_BAND_HZ))
            + constant_velocity([0.0, DRIFT_MPS, 0.0])
            + Trajectory((Ramp("yaw", 0.0, float(YAW_RATE)),)))
    return write_flight(tmp_path_factory.mktemp("drift") / "f", trajectory=traj,
                        targets="default5", seed=SEED, frames=6, time_offset=TIME_OFFSET_S,
                        clock_drift_ppm=DRIFT_PPM, attitude=False,
                        clutter_scene="parking_lot", clutter_max_scatterers=60, log_gaps=2)


def _compensate(flight, out, el_deg: str) -> str:
    given = ",".join(repr(float(v)) for v in flight.initial_attitude_deg[0])
    err = io.StringIO()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
        assert main(flight.calibrating_command(out, "--range-m", "4.0:9.3", "--el-deg", el_deg,
                                               "--initial-attitude-deg", given,
                                               "--no-progress", attitude="log")) == 0
    return err.getvalue()


def test_every_bound_holds_on_a_grid_through_the_targets_as_seen(flight, tmp_path):
    seen = [flight.apparent_direction(0, j)[1] for j in range(len(flight.targets))]
    assert max(abs(s - t[2]) for s, t in zip(seen, flight.targets, strict=True)) > 2.0
    out = tmp_path / "c.zarr"
    said = _compensate(flight, out, elevation_grid(seen))
    assert "grid:" not in said
    score = score_flight(flight.capture.parent, out)
    assert score["passed"]["all"], score["worst"]


def test_the_nominal_grid_is_named_too_coarse_for_the_drift(flight, tmp_path):
    out = tmp_path / "c.zarr"
    said = _compensate(flight, out, "-5:5:5")
    assert "grid: the radar moves across the beams" in said and "elevation step 5 deg" in said
    worst = score_flight(flight.capture.parent, out)["worst"]
    # what the warning is about: the drift's Doppler kept by targets between the beams
    assert worst["beam_pseudo_velocity_bins"] > LIMITS["beam_pseudo_velocity_bins"]
