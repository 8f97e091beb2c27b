"""`raysim compensate` on a DCA1000 capture with its SDK .cfg and a PX4 ULog.

The files are written by :func:`raysim.pipeline.flight.write_flight` (the exact
oracle rendering a point target from a moving platform, TI 3 Tx x 4 Rx TDM in
the slot order TX0, TX2, TX1); the result is read back from the labelled store.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.cli import main
from raysim.io.mmwave_config import read_mmwave_config
from raysim.io.zarr_store import open_store
from raysim.pipeline.flight import write_flight
from raysim.platform.motion import sinusoid
from raysim.processing.metrics import parabolic_offset

#: Largest exact-chain azimuth error [deg] of the TDM case with per-slot poses.
TDM_ANGLE_TOL_DEG = 0.1
#: Must-show bounds for the flight from files (consumer MEMS IMU, 3 ms clock offset,
#: hover jitter with rotor vibration; offset, initial velocity and attitude given):
#: residual pseudo-velocity [bin], Doppler power outside +-1 bin [dB], azimuth error [deg].
FLIGHT_PSEUDO_VELOCITY_BINS = 0.05
FLIGHT_LEAKAGE_DB = -35.0
FLIGHT_ANGLE_TOL_DEG = 0.2
#: Angle grid step [deg] of the measurements (peaks interpolated by a parabola on dB).
GRID_STEP_DEG = 0.25


def _run(flight, out, chain="exact", *extra, frame=None, half_width_deg=6.0):
    az = flight.target[1]
    args = flight.command(out, "--range-m", "10.8:11.8",
                          "--az-deg", f"{az - half_width_deg}:{az + half_width_deg}:"
                          f"{GRID_STEP_DEG}", "--el-deg", "0:0:1", "--chain", chain, *extra,
                          frame=frame)
    assert main(args) == 0
    return open_store(out)


def _measure(ds, flight, first=0):
    """Per frame: azimuth error [deg] of the zero-Doppler beam peak, pseudo-velocity [bin]
    and Doppler power outside +-1 bin of the peak [dB] in the beam at the peak
    (:func:`raysim.pipeline.flight.measure_store`).

    Azimuth only: the 3 Tx x 4 Rx array has one lambda/2 step of elevation aperture (TX1
    raised), a beam some 100 deg wide in elevation, so the targets sit at elevation 0 and
    the beams are formed in that cut.
    """
    from raysim.pipeline.flight import measure_store

    return [tuple(row) for row in measure_store(ds, flight, first)]


def _tdm_flight(tmp_path):
    motion = sinusoid("pitch", np.deg2rad(8.0), 20.0, np.pi / 2) + sinusoid("z", 0.05, 5.0)
    return write_flight(tmp_path / "tdm", trajectory=motion, imu="ideal", time_offset=0.0,
                        frames=1, target=(11.3, 28.0, 0.0), lever_arm=(0.0, 0.0, 0.0))


def test_tdm_capture_is_compensated_per_slot(tmp_path):
    """TI 3 Tx x 4 Rx, target 11.3 m at 28 deg, pitch 8 deg + z 5 cm, ideal IMU, from the files."""
    flight = _tdm_flight(tmp_path)
    ds = _run(flight, tmp_path / "exact.zarr")
    (err, pv, _), = _measure(ds, flight)
    assert err <= TDM_ANGLE_TOL_DEG
    # there was motion to correct (uncompensated, the peak lies about 12 deg off: a wider grid)
    (err_none, _, _), = _measure(_run(flight, tmp_path / "none.zarr", "none",
                                      half_width_deg=14.0), flight)
    print(f"TDM capture: azimuth error {err:.3f} deg exact, {err_none:.2f} deg none")
    assert err_none > 1.0
    # the store carries its axes, units and the time of every slot's ramp
    cfg = read_mmwave_config(flight.radar_config).config
    assert ds["beams"].dims == ("frame", "chirp", "range", "azimuth", "elevation")
    assert ds["doppler_power"].dims == ("frame", "doppler", "range", "azimuth", "elevation")
    assert ds["range"].attrs["units"] == "m" and ds["azimuth"].attrs["units"] == "deg"
    assert ds["doppler"].attrs["units"] == "m/s" and ds.attrs["chain"] == "exact"
    t = ds["slot_time"].values[0]                                    # [chirp, slot]
    assert np.allclose(t - t[:1, :1], (np.arange(64)[:, None] * 3 + np.arange(3)) *
                       cfg.slot_interval, rtol=0, atol=1e-12)
    assert math.isclose(t[0, 0], flight.start + 0.0, abs_tol=1e-12)
    assert np.array_equal(ds["chirp_time"].values[0], t[:, 0])


def test_tdm_capture_paper_chain(tmp_path):
    """The paper chain with per-slot poses leaves only its small-angle tilt bias,
    ``asin(sin(az - theta) + theta) - az`` (compensation.paper.tilt_correction, Notes)."""
    flight = _tdm_flight(tmp_path)
    az, th = np.deg2rad(28.0), np.deg2rad(8.0)
    bound = abs(np.rad2deg(np.arcsin(np.sin(az - th) + th) - az)) + TDM_ANGLE_TOL_DEG
    ds = _run(flight, tmp_path / "paper.zarr", "paper", "--direction-deg", "28,0")
    (err, _, _), = _measure(ds, flight)
    assert err <= bound


def test_flight_from_files_one_command(tmp_path, capsys):
    """Consumer MEMS IMU, 3 ms clock offset, hover jitter with rotor vibration, 2 frames 50 ms
    apart: ULog + DCA1000 capture + SDK .cfg, one `raysim compensate` (with progress), against
    the same flight with an ideal IMU. The velocity given at the first ramp holds for frame 0;
    frame 1 is compensated again with the velocity at its own first ramp (``--frames 1:2``),
    as a per-frame velocity estimate would do (the consumer accelerometer bias integrated over
    the 50 ms between them is not observable from the IMU alone)."""
    flight = write_flight(tmp_path / "f", imu="consumer_mems", time_offset=0.003, frames=2,
                          seed=1)
    ideal = write_flight(tmp_path / "i", imu="ideal", time_offset=0.003, frames=2, seed=1)
    ds = _run(flight, tmp_path / "c.zarr")
    assert "compensate" in capsys.readouterr().err          # the progress bar
    assert list(ds["frame"].values) == [0, 1]
    runs = [(_measure(ds, flight)[0], _measure(_run(ideal, tmp_path / "i.zarr"), ideal)[0])]
    one = _run(flight, tmp_path / "one.zarr", frame=1)
    assert list(one["frame"].values) == [1]
    one_ideal = _run(ideal, tmp_path / "one_i.zarr", frame=1)
    runs.append((_measure(one, flight, 1)[0], _measure(one_ideal, ideal, 1)[0]))
    for (err, pv, leak), (err_i, pv_i, _) in runs:
        assert err_i <= TDM_ANGLE_TOL_DEG and abs(pv_i) <= FLIGHT_PSEUDO_VELOCITY_BINS
        assert err <= FLIGHT_ANGLE_TOL_DEG
        assert abs(pv) <= FLIGHT_PSEUDO_VELOCITY_BINS
        assert leak <= FLIGHT_LEAKAGE_DB


def test_capture_needs_its_configuration(tmp_path, capsys):
    flight = _tdm_flight(tmp_path)
    out = ["--out", str(tmp_path / "o.zarr")]
    assert main(["compensate", str(flight.capture), "--chain", "none", *out]) == 2
    assert "--radar-config" in capsys.readouterr().err
    bad = tmp_path / "bad.cfg"
    text = flight.radar_config.read_text()
    assert " 150 2500.0 " in text                      # numAdcSamples, digOutSampleRate
    bad.write_text(text.replace(" 150 2500.0 ", " 148 2500.0 "))
    assert main(["compensate", str(flight.capture), "--radar-config", str(bad), "--chain",
                 "none", *out]) == 2
    assert "not a whole number of frames" in capsys.readouterr().err
    assert main(["compensate", str(flight.capture), "--radar-config",
                 str(flight.radar_config), "--chain", "none", "--frames", "0:5", *out]) == 2
    assert "--frames: got '0:5'" in capsys.readouterr().err
    assert main(["compensate", str(flight.capture), "--radar-config",
                 str(flight.radar_config), "--chain", "none", "--range-m", "10:12",
                 "--az-deg", "20:30:1", "--el-deg", "0:0:1", "--out",
                 str(tmp_path / "x.npz")]) == 0
    with np.load(tmp_path / "x.npz") as z:              # one frame: the .npz layout
        assert z["beams"].shape[0] == 64 and z["azimuth_deg"].size == 11


@pytest.mark.parametrize("text", ["2:1", "a:b"])
def test_frame_selection_is_checked(text):
    from raysim.io.compensate_io import frame_selection

    with pytest.raises(ValueError, match="--frames"):
        frame_selection(text, 4)
    assert frame_selection(":2", 4) == [0, 1] and frame_selection("3", 4) == [3]


TDM_SCENARIO = """\
name = "tdm"
lever_arm_m = [0.0, 0.0, 0.0]
[radar]
num_chirps = 64
[array]
kind = "ti_3tx4rx"
[[scene.targets]]
range_m = 11.3
az_deg = 28.0
[[motion.sinusoids]]
axis = "pitch"
amplitude_deg = 8.0
frequency_hz = 20.0
phase_deg = 90.0
[[motion.sinusoids]]
axis = "z"
amplitude_m = 0.05
frequency_hz = 5.0
[imu]
preset = "ideal"
rate_hz = 2000.0
"""


def test_rendered_tdm_store_is_compensated_per_slot(tmp_path):
    """`raysim render` of the TDM case, then `raysim compensate` of the store (its IMU log,
    the true initial velocity and attitude): azimuth error within the TDM tolerance."""
    from raysim.scenario import loads_scenario

    (tmp_path / "tdm.toml").write_text(TDM_SCENARIO)
    store = tmp_path / "tdm.zarr"
    assert main(["render", str(tmp_path / "tdm.toml"), "--out", str(store),
                 "--no-progress"]) == 0
    traj = loads_scenario(TDM_SCENARIO).trajectory()
    v0 = traj.velocity([0.0])[0]
    ypr = np.rad2deg(traj.euler([0.0])[0])
    out = tmp_path / "c.zarr"
    assert main(["compensate", str(store), "--velocity", "given", "--initial-velocity",
                 ",".join(map(repr, map(float, v0))), "--initial-attitude-deg",
                 ",".join(map(repr, map(float, ypr))), "--range-m", "10.8:11.8",
                 "--az-deg", f"22:34:{GRID_STEP_DEG}", "--el-deg", "0:0:1",
                 "--out", str(out)]) == 0
    ds = open_store(out)
    zero = np.abs(ds["beams"].values[0, ..., 0].astype(np.complex128).sum(axis=0)) ** 2
    g, a = np.unravel_index(np.argmax(zero), zero.shape)
    db = 10 * np.log10(zero[g])
    az = ds.azimuth.values[a] + GRID_STEP_DEG * parabolic_offset(*db[a - 1:a + 2])
    assert abs(az - 28.0) <= TDM_ANGLE_TOL_DEG
    assert ds["slot_time"].shape == (1, 64, 3)
    # the frame store is never replaced by an output; an earlier compensated store is
    assert main(["compensate", str(store), "--chain", "none", "--range-m", "10.8:11.8",
                 "--az-deg", "0:0:1", "--el-deg", "0:0:1", "--out", str(store)]) == 2
    assert main(["compensate", str(store), "--chain", "none", "--range-m", "10.8:11.8",
                 "--az-deg", "0:0:1", "--el-deg", "0:0:1", "--out", str(out)]) == 0
    assert open_store(out).attrs["chain"] == "none" and open_store(store).sizes["frame"] == 1


def test_flight_command_prints_a_working_compensate(tmp_path, capsys):
    import shlex

    assert main(["flight", str(tmp_path / "fl"), "--frames", "1", "--imu", "ideal"]) == 0
    line = capsys.readouterr().out.strip().splitlines()[-1].split()
    assert line[0] == "raysim" and line[1] == "compensate"
    args = shlex.split(" ".join(line[1:]))
    assert main(args + ["--az-deg", "15:25:1", "--no-progress"]) == 0
    assert open_store(tmp_path / "fl" / "compensated.zarr")["beams"].shape[:2] == (1, 64)
    assert main(["flight", str(tmp_path / "fl2"), "--target", "11,20"]) == 2
    assert "--target" in capsys.readouterr().err


def test_flight_prints_a_beam_grid_through_every_target(tmp_path, capsys):
    """Targets at -10, 0, 5 and 10 deg elevation: the printed beam grid holds each of
    them where the first frame sees them, the platform off the hover point, within half
    its step (a fixed -5:5:5 measured the one at 10 deg 5 deg off its beam, 0.8 deg off
    in azimuth at 50 deg; a grid of the nominal elevations missed a drifting platform's
    targets by up to 2.6 deg, 0.094 bin of the drift's Doppler)."""
    import shlex

    from raysim.cli.cmd_flight import elevation_grid
    from raysim.cli.options import span_grid
    from raysim.pipeline.flight_truth import read_truth

    els = [10.0, -10.0, 5.0, 0.0]
    assert main(["flight", str(tmp_path / "fl"), "--frames", "1", "--imu", "ideal",
                 *(a for e in els for a in ("--target", f"8,{4 * e},{e}")),
                 "--no-progress"]) == 0
    seen = [read_truth(tmp_path / "fl").apparent_direction(0, j)[1] for j in range(4)]
    assert max(abs(a - e) for a, e in zip(seen, els, strict=True)) > 0.05   # moved
    for line in capsys.readouterr().out.splitlines():
        if line.strip().startswith("raysim compensate"):
            c = shlex.split(line.strip())
            grid = span_grid(c[c.index("--el-deg") + 1], "--el-deg")
            half = 0.5 * np.max(np.diff(grid))
            assert all(np.min(np.abs(grid - e)) <= half + 1e-9 for e in seen), (grid, seen)
    for els, worst in (([3.7, -2.0], 0.0), ([0.0], 0.0), ([-30.0, 30.0, 0.3], 0.75)):
        grid = span_grid(elevation_grid(els), "--el-deg")
        assert grid.size <= 41                        # a beam grid a flight can afford
        assert max(np.min(np.abs(grid - e)) for e in els) <= worst + 1e-9, (els, grid)
    # a target past compensate's default -60:60 azimuth grid: the printed grid reaches it
    assert main(["flight", str(tmp_path / "wide"), "--frames", "1", "--imu", "ideal",
                 "--target", "7,70,0", "--target", "6,-20,0", "--no-progress"]) == 0
    for line in capsys.readouterr().out.splitlines():
        if line.strip().startswith("raysim compensate"):
            c = shlex.split(line.strip())
            assert span_grid(c[c.index("--az-deg") + 1], "--az-deg").max() >= 70.0 + 5.0
    # a board that resolves elevation: half-degree steps a degree and a half beyond (the
    # displaced platform sees its targets off their nominal elevations)
    grid = span_grid(elevation_grid([-5.0, 0.0, 5.0], resolves=True), "--el-deg")
    assert grid.min() <= -6.5 and grid.max() >= 6.5 and np.allclose(np.diff(grid), 0.5)


def test_flight_with_a_low_rate_log_prints_the_autofocus(tmp_path, capsys):
    """A 250 Hz boxcar log does not resolve the rotor lines: the printed commands carry the
    radar autofocus, and compensate with the autofocus off says what would estimate that
    vibration."""
    import shlex

    assert main(["flight", str(tmp_path / "fl"), "--frames", "1", "--imu", "ideal",
                 "--imu-rate", "250", "--imu-boxcar", "--no-progress"]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    commands = [shlex.split(x.strip()) for x in lines if x.strip().startswith("raysim compensate")]
    assert len(commands) == 2
    for c in commands:
        assert c[c.index("--autofocus") + 1] == "displacement"
    given = commands[-1][1:]
    i = given.index("--autofocus")
    assert main(given[:i] + given[i + 2:] + ["--az-deg", "15:25:1", "--no-progress",
                                             "--autofocus", "off"]) == 0
    err = capsys.readouterr().err
    assert "imu rate:" in err and "note: --autofocus displacement" in err


def test_flight_of_a_mounted_radar_prints_the_self_calibrating_command(tmp_path, capsys):
    """An oblique radar's flight prints the command that estimates velocity and clock from
    the radar, with its mounting (tests/test_flight_mounted_selfcal.py runs it)."""
    import shlex

    assert main(["flight", str(tmp_path / "fl"), "--frames", "1", "--imu", "ideal",
                 "--mounting-deg", "oblique", "--target", "7,10,0", "--no-progress"]) == 0
    lines = [shlex.split(x.strip()) for x in capsys.readouterr().out.splitlines()
             if x.strip().startswith("raysim compensate")]
    calibrating = [c for c in lines if "--time-offset" in c
                   and c[c.index("--time-offset") + 1] == "auto"]
    assert len(lines) == 2 and len(calibrating) == 1
    assert "--mounting-deg" in calibrating[0] and "radar" in calibrating[0]


#: Span of a flight's frame: 64 loops of 3 slots of 70 us [s].
FRAME_SPAN_S = 64 * 3 * 70e-6


def test_frames_in_a_filled_logger_gap_are_named(tmp_path, capsys):
    """A logger gap inside the capture, filled with --max-gap: the frames it spans are
    named in the warnings (their motion is interpolated), the others are not."""
    import shlex

    from raysim.pipeline.flight_truth import read_truth

    assert main(["flight", str(tmp_path / "fl"), "--frames", "4", "--imu", "ideal",
                 "--target", "6,10,0", "--log-gaps", "1", "--gaps-in-capture",
                 "--no-progress"]) == 0
    lines = capsys.readouterr().out.splitlines()
    given = shlex.split([x for x in lines if x.strip().startswith("raysim compensate")][-1])
    assert main(given[1:] + ["--az-deg", "4:16:1", "--no-progress"]) == 0
    flight = read_truth(tmp_path / "fl")
    (start, length), = flight.gaps                           # [s, IMU clock]
    t0 = flight.frame_starts + flight.time_offset            # frames on the IMU clock
    inside = [k for k, t in enumerate(t0) if t < start + length and t + FRAME_SPAN_S > start]
    named = [ln for ln in capsys.readouterr().err.splitlines() if "imu gaps: frame(s)" in ln]
    assert inside and len(named) == 1
    listed = named[0].split("frame(s) ")[1].split(" lie")[0].split(", ")
    assert [int(k) for k in listed] == inside


def test_the_autofocus_runs_by_default_where_the_chain_says_it_leaves_motion(tmp_path, capsys):
    """A 250 Hz log of instantaneous samples does not resolve the rotor band (the chain's
    ``imu rate:`` warning): ``raysim compensate`` removes what it leaves by the radar's
    displacement autofocus, says so, and ``--autofocus off`` keeps the chain alone."""
    import json

    flight = write_flight(tmp_path / "f", frames=1, imu_rate=250.0)
    args = flight.command(tmp_path / "auto.zarr", "--range-m", "10.8:11.8", "--az-deg",
                          "14:26:0.5", "--el-deg", "0:0:1", "--no-progress")
    assert "--autofocus" not in args
    capsys.readouterr()
    assert main(args) == 0
    err = capsys.readouterr().err
    assert "note: autofocus: displacement applied (the log does not resolve" in err
    assert "warning: exact: imu rate:" in err
    focus = json.loads(open_store(tmp_path / "auto.zarr").attrs["autofocus"])
    assert [f["mode"] for f in focus] == ["displacement"]
    off = [*args[:args.index("--out") + 1], str(tmp_path / "off.zarr"),
           *args[args.index("--out") + 2:], "--autofocus", "off"]
    assert main(off) == 0
    err = capsys.readouterr().err
    assert "applied" not in err and "note: --autofocus displacement estimates" in err
    assert "autofocus" not in open_store(tmp_path / "off.zarr").attrs


def test_flight_prints_the_elevations_a_drifting_platform_sees(tmp_path, capsys, monkeypatch):
    """A platform drifting 0.3 m/s east (across the array's elevation axis) is 15 cm off
    the hover point when the capture starts: the default5 targets are seen up to 2.6 deg
    off their nominal -5/0/+5 deg. The printed grid holds where they are seen, within
    half its step; the nominal grid missed them (0.094 bin of the drift's Doppler and
    0.34 deg on such a flight; 0.010 bin, 0.073 deg on the grid of the seen ones)."""
    import shlex

    import raysim.platform.motion as motion
    from raysim.cli.options import span_grid
    from raysim.pipeline.flight_truth import read_truth

    jitter = motion.hover_jitter
    monkeypatch.setattr(motion, "hover_jitter", lambda seed, spec=None: jitter(
        seed, spec) + motion.constant_velocity([0.0, 0.3, 0.0]))
    assert main(["flight", str(tmp_path / "fl"), "--frames", "1", "--imu", "ideal",
                 "--targets", "default5", "--no-progress"]) == 0
    flight = read_truth(tmp_path / "fl")
    seen = np.array([flight.apparent_direction(0, j)[1] for j in range(5)])
    nominal = np.array([t[2] for t in flight.targets])
    assert np.abs(seen - nominal).max() > 1.0                      # the drift moved them
    printed = [shlex.split(ln.strip()) for ln in capsys.readouterr().out.splitlines()
               if ln.strip().startswith("raysim compensate")]
    assert printed
    for c in printed:
        grid = span_grid(c[c.index("--el-deg") + 1], "--el-deg")
        miss = np.abs(grid[None, :] - seen[:, None]).min(axis=1)
        assert miss.max() <= 0.5 * np.max(np.diff(grid)) + 1e-9 and miss.max() <= 0.3, (
            grid, seen)
