"""End to end from files like a real flight's, each compensated by ONE `raysim compensate`.

Every flight (:func:`raysim.pipeline.flight.write_flight`) has the five ``default5``
stationary targets (4.5-8.8 m, azimuth -25..30 deg, elevation -5/0/+5 deg) plus the
ground clutter of the bundled ``parking_lot`` scene (at most
:data:`CLUTTER_SCATTERERS` scatterers, so a flight is written in seconds), the
xWR18xx board (3 TX, TX1 raised lambda/2, x 4 RX), a consumer-MEMS IMU whose
realised accelerometer bias reaches :data:`MIN_ACCEL_BIAS_MG` (checked), logged at
1 kHz or as a flight controller's 250 Hz boxcar, with :data:`LOG_GAPS` logger gaps of
50-160 ms, with and without the flight controller's attitude (``vehicle_attitude``, the
truth turned by the controller's roll and pitch error,
:func:`raysim.pipeline.flight_log.controller_tilt_error`), the IMU clock
:data:`TIME_OFFSET_S` ahead with a :data:`DRIFT_PPM` drift, and :data:`FRAMES` frames.
The command gets only what a user has (the capture, its cfg, the ULog, the IMU grade
and the lever arm) and estimates the velocity and the clock
from the radar (``--velocity radar --time-offset auto``; the 250 Hz log adds
``--autofocus stationary``, and again ``--autofocus displacement``). Every target in
every frame is measured from the store (:func:`raysim.pipeline.flight.measure_targets`).

Where the bounds do not hold the case is marked ``xfail(strict=True)`` with the
measured figures, so the suite records the gap (and notices when it closes).
"""

from __future__ import annotations

import contextlib
import io
import json

import numpy as np
import pytest

from compensation.observability import HELD_WHEN_UNCONSTRAINED, UNCONSTRAINED_RATIO
from raysim.cli import main
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import DEFAULT5_TARGETS, measure_targets, write_flight

#: Bounds on every target and frame: residual pseudo-velocity [bin], Doppler power
#: outside +-1 bin of the peak [dB], angle error [deg]; and the clock-offset error [s].
PSEUDO_VELOCITY_BINS = 0.05
LEAKAGE_DB = -35.0
ANGLE_DEG = 0.2
OFFSET_TOL_S = 0.5e-3
#: The flights' clock, frames, logger gaps and seed (its realised accelerometer bias:
#: 3.7, -28.1, 13.5 mg).
TIME_OFFSET_S, DRIFT_PPM, FRAMES, LOG_GAPS, SEED = 6.5e-3, 30.0, 6, 2, 0
#: Largest realised accelerometer bias component the flights must have [mg].
MIN_ACCEL_BIAS_MG = 15.0
#: Clutter field bound (the full field of 3200 scatterers costs about 45 s a frame).
CLUTTER_SCATTERERS = 60
#: Frames of the degenerate-geometry flights (what they check needs no more).
FEW_FRAMES = 3
CELLS = ("--range-m", "4:9.3", "--az-deg", "-40:45:0.25", "--el-deg", "-5:5:5",
         "--no-progress")

CASES = {
    "1k_log_attitude": dict(imu_rate=1000.0, imu_boxcar=False, attitude=True),
    "1k_no_attitude": dict(imu_rate=1000.0, imu_boxcar=False, attitude=False),
    "250hz_boxcar_log_attitude": dict(imu_rate=250.0, imu_boxcar=True, attitude=True),
    "250hz_boxcar_no_attitude": dict(imu_rate=250.0, imu_boxcar=True, attitude=False),
}
_RUNS: dict = {}
_FLIGHTS: dict = {}


def _run(tmp, name: str, frames: int = FRAMES, targets="default5", autofocus="stationary",
         clutter: int = CLUTTER_SCATTERERS, **kw):
    """Write the flight once and compensate it with one command: (flight, store, stdout)."""
    key = name if autofocus == "stationary" else f"{name}-{autofocus}"
    if key in _RUNS:
        return _RUNS[key]
    if name in _FLIGHTS:
        flight = _FLIGHTS[name]
    else:
        flight = _FLIGHTS[name] = write_flight(
            tmp / name, targets=targets, frames=frames, seed=SEED, time_offset=TIME_OFFSET_S,
            clock_drift_ppm=DRIFT_PPM, log_gaps=LOG_GAPS, clutter_scene="parking_lot",
            clutter_max_scatterers=clutter, **kw)
    extra = ("--autofocus", autofocus) if kw.get("imu_boxcar") else ()
    args = flight.calibrating_command(tmp / f"{key}.zarr", *CELLS, *extra, attitude="log")
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(args) == 0
    _RUNS[key] = (flight, open_store(tmp / f"{key}.zarr"), out.getvalue())
    return _RUNS[key]


@pytest.fixture(scope="module")
def tmp(tmp_path_factory):
    return tmp_path_factory.mktemp("flights")


def _figures(flight, ds) -> str:
    m = measure_targets(ds, flight)                             # [target, frame, 3]
    return (f"angle {m[..., 0].max():.3f} deg, pseudo-velocity {np.abs(m[..., 1]).max():.3f} "
            f"bin, leakage {m[..., 2].max():.1f} dB, offset error "
            f"{(ds.attrs['time_offset_s'] - TIME_OFFSET_S) * 1e3:+.3f} ms")


def test_the_flights_have_a_consumer_accelerometer_bias():
    from raysim.pipeline.sensors import imu_record
    from raysim.platform.imu_spec import MILLI_G
    from raysim.platform.motion import hover_jitter

    s = imu_record(hover_jitter(SEED), "consumer_mems", rate=1000.0, times=[0.5, 1.0],
                   seed=SEED, start=0.0, time_offset=TIME_OFFSET_S, clock_drift_ppm=DRIFT_PPM)
    assert np.abs(s.truth.accel_bias.mean(axis=0)).max() >= MIN_ACCEL_BIAS_MG * MILLI_G


#: Stated spreads within which the clock offset must lie of the truth.
CLOCK_SIGMAS = 3.0


@pytest.mark.parametrize("case", list(CASES))
def test_clock_offset_and_scatterers_of_every_flight(tmp, case):
    """The offset within its bound and CLOCK_SIGMAS stated spreads on every log (the
    250 Hz averages read at their intervals' middles), the five targets found and no
    sidelobe taken for a sixth (the clutter lies beyond their cells), the flight as
    asked for."""
    flight, ds, out = _run(tmp, case, **CASES[case])
    print(case, _figures(flight, ds))          # the figures of GAPS (pytest -s)
    assert len(flight.targets) == len(DEFAULT5_TARGETS) and ds.sizes["frame"] == FRAMES
    assert len(flight.gaps) == LOG_GAPS
    assert abs(ds.attrs["time_offset_s"] - TIME_OFFSET_S) <= OFFSET_TOL_S
    sigma = json.loads(ds.attrs["self_calibration"])["time_offset_sigma_s"]
    assert abs(ds.attrs["time_offset_s"] - TIME_OFFSET_S) <= CLOCK_SIGMAS * sigma
    assert json.loads(ds.attrs["self_calibration"])["scatterers"] == len(DEFAULT5_TARGETS)
    # the IMU noise's velocity error the Doppler residuals show, removed and said
    ri = json.loads(ds.attrs["self_calibration"])["radar_inertial"]
    assert ri["noise_velocity_mps"] > 0
    assert "IMU noise's velocity error taken from the Doppler residuals" in out


#: Stated spreads within which the ground plane's roll and pitch must lie of the truth.
GROUND_SIGMAS = 3.0


@pytest.mark.parametrize("case", list(CASES))
def test_ground_plane_tilt_within_its_stated_spread(tmp, case):
    """The roll and pitch the ground clutter gives (compensation.ground_plane): the
    initial tilt where the log has no attitude, a check of the log's where it has; within
    GROUND_SIGMAS stated spreads of the truth at the first ramp, its assumption printed."""
    from scipy.spatial.transform import Rotation

    flight, ds, out = _run(tmp, case, **CASES[case])
    gp = json.loads(ds.attrs["self_calibration"])["ground_plane"]
    assert gp["used"] and gp["role"] == ("check of the given attitude" if CASES[case][
        "attitude"] else "initial roll and pitch")
    # the correction of the attitude the points were formed with: the log's (the flight
    # controller's, with its error) or level, heading 0
    given = (Rotation.from_euler("ZYX", flight.log_attitude_deg[0], degrees=True)
             if CASES[case]["attitude"] else Rotation.identity())
    truth = np.rad2deg((Rotation.from_euler("ZYX", flight.initial_attitude_deg[0],
                                            degrees=True) * given.inv()).as_rotvec()[:2])
    err = np.asarray(gp["tilt_deg"]) - truth
    print(case, "ground tilt error [deg]", np.round(err, 3), "sigma", np.round(
        gp["tilt_sigma_deg"], 3), f"{gp['inliers']} of {gp['points']} points")
    assert np.all(np.abs(err) <= GROUND_SIGMAS * np.asarray(gp["tilt_sigma_deg"])), err
    assert "ground plane tilt" in out and "assumes level flat ground" in out


#: Cases that miss the bounds, with the figures measured (worst target and frame).
GAPS = {
    "250hz_boxcar_log_attitude": "the 250 Hz boxcar folds the rotor band: leakage -28.2 dB "
                                 "(angle 0.084 deg, 0.017 bin, offset +0.087 ms within; "
                                 "--autofocus stationary)",
    "250hz_boxcar_no_attitude": "250 Hz boxcar, tilt from the ground plane: leakage -28.3 dB "
                                "(angle 0.110 deg, 0.013 bin, offset +0.085 ms within; "
                                "--autofocus stationary)",
}


@pytest.mark.parametrize("case", [
    pytest.param(c, marks=pytest.mark.xfail(strict=True, reason=GAPS[c])) if c in GAPS
    else c for c in CASES])
def test_every_target_and_frame_within_the_bounds(tmp, case):
    flight, ds, out = _run(tmp, case, **CASES[case])
    m = measure_targets(ds, flight)                             # [target, frame, 3]
    assert m.shape == (len(DEFAULT5_TARGETS), FRAMES, 3)
    assert np.all(m[..., 0] <= ANGLE_DEG), m[..., 0]
    assert np.all(np.abs(m[..., 1]) <= PSEUDO_VELOCITY_BINS), m[..., 1]
    assert np.all(m[..., 2] <= LEAKAGE_DB), m[..., 2]


@pytest.mark.parametrize("case", ["elevation0", "single"])
def test_degenerate_geometry_named_and_covered(tmp, case):
    """Targets all at elevation 0, or one target: what the Doppler cannot constrain is
    named in the command's output and kept at the prior, and the velocity's error is
    within 3 stated sigma."""
    targets = ([(r, az, 0.0) for r, az, _ in DEFAULT5_TARGETS] if case == "elevation0"
               else [DEFAULT5_TARGETS[2]])
    flight, ds, out = _run(tmp, case, frames=FEW_FRAMES, targets=targets,
                           imu_rate=1000.0, attitude=True)
    cal = json.loads(ds.attrs["self_calibration"])
    assert cal["scatterers"] == len(targets)
    v = np.asarray(cal["initial_velocity_mps"])
    sig = np.asarray(cal["initial_velocity_sigma_mps"])
    assert np.all(np.abs(v - flight.initial_velocity[0]) <= 3 * sig), (v, sig)
    named = [n for n in cal["unconstrained"] if n.startswith("velocity_")]
    # one line per prior kept (IMU grade, clock fit, gyro-bias fit)
    lines = " ".join(ln for ln in out.splitlines() if ln.strip().startswith("unconstrained"))
    assert all(n in lines for n in cal["unconstrained"])
    if case == "single":         # one direction: the two velocity components across it
        assert len(named) >= 2
    ri = cal["radar_inertial"]
    for n in cal["unconstrained"]:       # kept at the prior: its spread hardly reduced,
        i = ri["state_names"].index(n)   # the held ones not corrected at all
        assert ri["sigma"][i] >= UNCONSTRAINED_RATIO * ri["prior_sigma"][i], n
        if n in HELD_WHEN_UNCONSTRAINED:
            assert ri["state"][i] == 0.0, n


BOXCAR_CASES = [c for c in CASES if CASES[c]["imu_boxcar"]]


@pytest.mark.parametrize("case", BOXCAR_CASES)
def test_displacement_autofocus_doppler_within_the_bounds(tmp, case):
    """The 250 Hz log with ``--autofocus displacement``: pseudo-velocity and leakage of
    every target and frame within their bounds (the common-phase modes miss them)."""
    flight, ds, out = _run(tmp, case, autofocus="displacement", **CASES[case])
    m = measure_targets(ds, flight)                             # [target, frame, 3]
    print(case, "displacement:", _figures(flight, ds), "; worst angle per frame [deg]",
          np.round(m[..., 0].max(axis=0), 3), "least", np.round(m[..., 0].min(axis=0), 3))
    assert m.shape == (len(DEFAULT5_TARGETS), FRAMES, 3)
    assert np.all(np.abs(m[..., 1]) <= PSEUDO_VELOCITY_BINS), m[..., 1]
    assert np.all(m[..., 2] <= LEAKAGE_DB), m[..., 2]
    focus = json.loads(ds.attrs["autofocus"])
    assert all(f["mode"] == "displacement" and f["cells"] >= 4 for f in focus)
    assert "autofocus frame" in out


@pytest.mark.parametrize("case", BOXCAR_CASES)
def test_displacement_autofocus_angle_within_the_bound(tmp, case):
    """The 250 Hz log with ``--autofocus displacement``: the angle of every target and frame
    within its bound, the log's attitude a measurement at every frame (no drift through
    the boxcar-averaged gyro), or without it the ground plane's tilt."""
    flight, ds, out = _run(tmp, case, autofocus="displacement", **CASES[case])
    m = measure_targets(ds, flight)                             # [target, frame, 3]
    assert np.all(m[..., 0] <= ANGLE_DEG), m[..., 0]


#: A dense ground: the clutter field of DENSE_SCATTERERS (1.6 scatterers a range and
#: angle cell beyond the nadir, ten times the others' density; `raysim flight`'s
#: default is 10), where one snapshot's range cells give 12 points and the
#: range-Doppler cells the rest (compensation.ground_dbs).
DENSE_SCATTERERS = 200


@pytest.mark.slow
def test_dense_ground_no_attitude_within_the_bounds(tmp):
    """The 1 kHz flight without attitude over a dense ground: its roll and pitch from
    the range and range-Doppler cells' points within GROUND_SIGMAS stated spreads, and
    every target and frame within the bounds (measured: tilt error 0.25, 0.12 deg at
    0.50, 0.49 stated, 22 of 23 points; angle 0.137 deg, pseudo-velocity 0.005 bin,
    leakage -42.4 dB, offset error +0.017 ms, with the IMU noise's velocity error taken
    from the Doppler residuals; 18 s alone, 55 s on the loaded machine).
    Seeds 4 and 5 of the same field miss the angle's bound (0.57, 0.37 deg:
    docs/self_calibration.md)."""
    from scipy.spatial.transform import Rotation

    flight, ds, out = _run(tmp, "1k_no_attitude_dense", clutter=DENSE_SCATTERERS,
                           **CASES["1k_no_attitude"])
    gp = json.loads(ds.attrs["self_calibration"])["ground_plane"]
    assert gp["used"] and gp["point_cells"] == "range+doppler"
    truth = np.rad2deg(Rotation.from_euler("ZYX", flight.initial_attitude_deg[0],
                                           degrees=True).as_rotvec()[:2])
    err = np.asarray(gp["tilt_deg"]) - truth
    print("dense ground tilt error [deg]", np.round(err, 3), "sigma",
          np.round(gp["tilt_sigma_deg"], 3), f"{gp['inliers']} of {gp['points']} points; ",
          _figures(flight, ds))
    assert np.all(np.abs(err) <= GROUND_SIGMAS * np.asarray(gp["tilt_sigma_deg"])), err
    m = measure_targets(ds, flight)
    assert np.all(m[..., 0] <= ANGLE_DEG), m[..., 0]
    assert np.all(np.abs(m[..., 1]) <= PSEUDO_VELOCITY_BINS), m[..., 1]
    assert np.all(m[..., 2] <= LEAKAGE_DB), m[..., 2]
    assert abs(ds.attrs["time_offset_s"] - TIME_OFFSET_S) <= OFFSET_TOL_S
