"""The single catalogue of bad inputs across the public API, the CLI and the file readers.

Every case names one bad input, the exception type it must raise and the
fragments its message must contain (the offending parameter and/or value),
so a user reading the error knows what to fix. Guard rails (the compensation
flagging its own broken assumptions, damaged stores) are tested at the end.

Atomic writes and interrupted runs are tested at the bottom: nothing
half-written may stay on disk.
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest

from raysim.echoes.oracle import PointTarget, element_times, simulate_point_targets
from raysim.platform.motion import HoverJitterSpec, Sinusoid, hover_jitter, sinusoid, stationary
from raysim.radar.arrays import VirtualArray, tdm_mimo, ti_3tx4rx, upa
from raysim.radar.config import RadarConfig

SMALL = RadarConfig(num_chirps=8, sample_rate=2.5e6)        # 150 samples, max range 22.5 m
ARR = upa(2, 2, wavelength=SMALL.wavelength)
IMU_HEADER = ("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,"
              "accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n")


@dataclass(frozen=True)
class Bad:
    """One bad input: ``call(tmp_path)`` must raise ``exc`` with every ``needle`` in the message."""

    id: str
    call: Callable[[Path], object]
    exc: type | tuple
    needles: tuple[str, ...]


def _imu_csv(tmp: Path, body: str) -> Path:
    p = tmp / "imu.csv"
    p.write_text(IMU_HEADER + body)
    return p


def _read_imu(tmp: Path, body: str):
    from raysim.io.imu_log import read_imu_csv

    return read_imu_csv(_imu_csv(tmp, body))


def _imu_samples(t, gyro=None, accel=None):
    from raysim.platform.imu import ImuSamples

    t = np.asarray(t, dtype=float)
    g = np.zeros((t.size, 3)) if gyro is None else gyro
    a = np.tile([0.0, 0.0, -9.80665], (t.size, 1)) if accel is None else accel
    return ImuSamples(t, g, a)


def _dca_truncated(tmp: Path):
    from raysim.io.ti_dca1000 import Dca1000Format, read_dca1000, write_dca1000

    fmt = Dca1000Format(num_samples=16, slot_interval=60e-6, num_rx=4, num_tx=1, num_loops=4)
    cube = np.ones((2, 4, 4, 16), dtype=np.complex64)
    write_dca1000(tmp / "adc.bin", cube, fmt)
    data = (tmp / "adc.bin").read_bytes()
    (tmp / "cut.bin").write_bytes(data[:-6])                 # a capture cut mid-frame
    return read_dca1000(tmp / "cut.bin", fmt)


def _damaged_store(tmp: Path, damage: str):
    """A three-frame store whose ``if_data`` chunk of frame 1 is deleted or truncated."""
    from raysim.io import storage

    fr = simulate_point_targets(SMALL, ARR, [PointTarget.at(10.0, 0.1, 0.0)])
    frames = [__import__("dataclasses").replace(fr, frame_index=i) for i in range(3)]
    storage.write_store(tmp / "s.zarr", storage.frames_to_dataset(frames))
    chunk = tmp / "s.zarr" / "if_data" / "c" / "1" / "0" / "0" / "0"
    if damage == "delete":
        chunk.unlink()
    else:
        chunk.write_bytes(chunk.read_bytes()[:7])
    return storage.open_store(tmp / "s.zarr")


_PLY_HEAD = ("ply\nformat ascii 1.0\nelement vertex {nv}\nproperty float x\nproperty float y\n"
             "property float z\nelement face {nf}\nproperty list uchar int vertex_indices\n"
             "end_header\n")


def _load_mesh_scene(tmp: Path, name: str, vertices: str, faces: str, **kw):
    """Load a one-shape concrete scene whose mesh ``meshes/<name>`` has the given rows."""
    from raysim.echoes.rt.scenes import load_scene

    path = _scene_file(tmp, "concrete", name)
    nv, nf = len(vertices.splitlines()), len(faces.splitlines())
    (tmp / "meshes" / name).write_text(_PLY_HEAD.format(nv=nv, nf=nf) + vertices + faces)
    return load_scene(path, **kw)


_TRIANGLE = "0 0 0\n1 0 0\n0 1 0\n"


def _scenario_data(**radar):
    from raysim.io.scenario import scenario_from_case

    data = scenario_from_case("rotation_y").model_dump(mode="json", exclude_none=True)
    data["radar"].update(radar)
    return data


def _validate(data):
    from raysim.io.scenario import validate_scenario

    return validate_scenario(data)


class CliError(Exception):
    """A non-zero exit of the ``raysim`` command: ``"exit <code>: <stderr>"``."""


def _cli(argv):
    """Run the CLI in-process; a non-zero exit raises CliError carrying the code and stderr."""
    import contextlib
    import io

    from raysim.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:                       # argparse usage errors
            code = exc.code
    if code:
        raise CliError(f"exit {code}: {err.getvalue()}")
    return code


def _integrate(t, *, chirps=None, **kw):
    from compensation import integrate_imu

    t = np.asarray(t, dtype=float)
    gyro = kw.pop("gyro", np.zeros((t.size, 3)))
    accel = kw.pop("accel", np.tile([0.0, 0.0, -9.80665], (t.size, 1)))
    chirps = np.arange(8) * 60e-6 + 0.01 if chirps is None else chirps
    kw.setdefault("velocity", "given")
    if kw["velocity"] == "given":
        kw.setdefault("initial_velocity", np.zeros(3))
    return integrate_imu(t, gyro, accel, chirps, **kw)


def _stability_point(**kw):
    from raysim.studies.stability import StabilityPoint

    base = dict(config=SMALL, array=ARR, trajectory=stationary(), target_range_m=10.0)
    base.update(kw)
    return StabilityPoint(**base)


T_IMU = np.arange(0.0, 0.05, 1e-3)

CASES = [
    # ---------------------------------------------------------------- radar config
    Bad("config-zero-sample-rate", lambda _: RadarConfig(sample_rate=0.0), ValueError,
        ("sample_rate", "0.0")),
    Bad("config-negative-sample-rate", lambda _: RadarConfig(sample_rate=-1e6), ValueError,
        ("sample_rate", "-1000000.0")),
    Bad("config-nan-carrier", lambda _: RadarConfig(carrier_frequency=math.nan), ValueError,
        ("carrier_frequency", "nan")),
    Bad("config-zero-chirps", lambda _: RadarConfig(num_chirps=0), ValueError,
        ("num_chirps", "0")),
    Bad("config-float-chirps", lambda _: RadarConfig(num_chirps=256.5), ValueError,
        ("num_chirps", "256.5")),
    Bad("config-bandwidth-above-carrier", lambda _: RadarConfig(bandwidth=1e11), ValueError,
        ("bandwidth", "carrier_frequency")),
    Bad("config-negative-idle", lambda _: RadarConfig(idle_time=-1e-6), ValueError,
        ("idle_time", "-1e-06")),
    Bad("config-frame-period-too-short", lambda _: RadarConfig(frame_period=1e-3), ValueError,
        ("frame_period", "0.001")),
    Bad("config-fewer-than-two-samples",
        lambda _: RadarConfig(chirp_duration=1e-7, sample_rate=1e6), ValueError,
        ("at least 2 samples",)),
    # ------------------------------------------------------- aliasing geometry
    Bad("target-beyond-max-range",
        lambda _: simulate_point_targets(SMALL, ARR, [PointTarget.at(30.0, 0.0, 0.0)]),
        ValueError, ("30.0", "unambiguous range", "sample_rate")),
    Bad("negative-range-check", lambda _: SMALL.check_range(-1.0), ValueError,
        ("-1.000", "unambiguous range")),
    Bad("target-negative-range", lambda _: PointTarget.at(-5.0, 0.0, 0.0), ValueError,
        ("range_m", "-5.0")),
    Bad("target-position-shape", lambda _: PointTarget(np.zeros(2)), ValueError,
        ("position", "3 finite")),
    Bad("target-velocity-nan", lambda _: PointTarget(np.zeros(3), np.array([0, math.nan, 0])),
        ValueError, ("velocity", "nan")),
    # ------------------------------------------------------------------- arrays
    Bad("upa-zero-elements", lambda _: upa(0, 4, wavelength=3.9e-3), ValueError,
        ("nx", "0")),
    Bad("upa-negative-spacing", lambda _: upa(4, 4, spacing=-1e-3), ValueError,
        ("spacing", "-0.001")),
    Bad("upa-no-spacing-no-wavelength", lambda _: upa(4, 4), ValueError,
        ("spacing", "wavelength")),
    Bad("array-mismatched-shapes",
        lambda _: VirtualArray(np.zeros((4, 3)), np.zeros((5, 3)), np.zeros(4, int)),
        ValueError, ("rx_positions", "(5, 3)", "(4, 3)")),
    Bad("tdm-positions-not-3d", lambda _: tdm_mimo(np.zeros((3, 2)), np.zeros((4, 3))),
        ValueError, ("tx_positions", "(3, 2)")),
    Bad("tdm-slots-vs-config",
        lambda _: element_times(SMALL, ti_3tx4rx(SMALL.wavelength)), ValueError,
        ("num_tx_slots", "3 TDM slots")),
    # ------------------------------------------------------------------- motion
    Bad("motion-unknown-axis", lambda _: Sinusoid("w", 0.1, 1.0), ValueError,
        ("axis", "'w'")),
    Bad("motion-negative-frequency", lambda _: sinusoid("pitch", 0.1, -2.0), ValueError,
        ("frequency", "-2.0")),
    Bad("motion-nan-times", lambda _: sinusoid("x", 0.1, 1.0).states([0.0, math.nan]),
        ValueError, ("times", "finite")),
    Bad("jitter-inverted-band",
        lambda _: hover_jitter(0, HoverJitterSpec(attitude_band=(8.0, 0.5))), ValueError,
        ("band", "(8.0, 0.5)")),
    # ---------------------------------------------------- synthesis / processing
    Bad("synthesis-tau-shape",
        lambda _: __import__("raysim.synthesis.tones", fromlist=["x"]).synthesize_if(
            np.zeros((2, 3)), 1.0, SMALL), ValueError, ("tau", "(2, 3)")),
    Bad("synthesis-tau-nan",
        lambda _: __import__("raysim.synthesis.tones", fromlist=["x"]).synthesize_if(
            np.full((1, 8, 4), math.nan), 1.0, SMALL), ValueError, ("tau", "NaN")),
    Bad("processing-unknown-window",
        lambda _: __import__("raysim.processing.windows", fromlist=["x"]).window("hammock", 8),
        ValueError,
        ("window", "'hammock'")),
    Bad("metrics-short-slow-time",
        lambda _: __import__("raysim.processing.metrics", fromlist=["x"]).pseudo_velocity(
            np.ones(2), 60e-6, 3.9e-3), ValueError, ("slow_time", ">= 4", "(2,)")),
    Bad("metrics-zero-chirp-interval",
        lambda _: __import__("raysim.processing.metrics", fromlist=["x"]).pseudo_velocity(
            np.ones(16), 0.0, 3.9e-3), ValueError, ("chirp_interval", "0.0")),
    Bad("metrics-negative-intensity",
        lambda _: __import__("raysim.processing.metrics", fromlist=["x"]).image_entropy(
            np.array([1.0, -1.0])), ValueError, ("intensity", "non-negative")),
    Bad("unknown-paper-case",
        lambda _: __import__("raysim.studies.cases", fromlist=["x"]).get_case("roll_x"), ValueError,
        ("'roll_x'", "rotation_y")),
    # ---------------------------------------------------------------------- IMU
    Bad("imu-zero-rate",
        lambda _: __import__("raysim.platform.imu", fromlist=["x"]).simulate_imu(
            stationary(), "ideal", rate=0.0, start=0.0, end=0.1), ValueError, ("rate", "0.0")),
    Bad("imu-negative-rate",
        lambda _: __import__("raysim.platform.imu", fromlist=["x"]).simulate_imu(
            stationary(), "ideal", rate=-100.0, start=0.0, end=0.1), ValueError,
        ("rate", "-100.0")),
    Bad("imu-unknown-preset",
        lambda _: __import__("raysim.platform.imu", fromlist=["x"]).get_preset("navigation_grade"),
        ValueError, ("'navigation_grade'", "consumer_mems")),
    Bad("imu-negative-noise",
        lambda _: __import__("raysim.platform.imu",
                             fromlist=["x"]).SensorErrors(noise_density=-1.0),
        ValueError, ("noise_density", "-1.0")),
    Bad("imu-unsorted-samples", lambda _: _imu_samples([0.0, 0.002, 0.001]), ValueError,
        ("strictly increasing", "0.001")),
    Bad("imu-nan-gyro",
        lambda _: _imu_samples([0.0, 0.001], gyro=np.array([[0, 0, 0], [math.nan, 0, 0]])),
        ValueError, ("gyro", "finite")),
    Bad("imu-gyro-shape", lambda _: _imu_samples([0.0, 0.001], gyro=np.zeros((2, 2))),
        ValueError, ("gyro", "(2, 2)")),
    # -------------------------------------------------------------- file readers
    Bad("imu-csv-nan", lambda t: _read_imu(t, "0,0,0,0,0,0,-9.8\n0.001,nan,0,0,0,0,-9.8\n"),
        ValueError, ("gyro_x_rad_s", "row 2", "'nan'")),
    Bad("imu-csv-unsorted",
        lambda t: _read_imu(t, "0.002,0,0,0,0,0,-9.8\n0.001,0,0,0,0,0,-9.8\n"), ValueError,
        ("time_s", "row 2", "strictly increasing")),
    Bad("imu-csv-duplicate-time",
        lambda t: _read_imu(t, "0.001,0,0,0,0,0,-9.8\n0.001,0,0,0,0,0,-9.8\n"), ValueError,
        ("time_s", "row 2")),
    Bad("imu-csv-unknown-unit",
        lambda t: (t / "u.csv").write_text(IMU_HEADER.replace("gyro_x_rad_s", "gyro_x_rpm")
                                           + "0,0,0,0,0,0,-9.8\n")
        and __import__("raysim.io.imu_log", fromlist=["x"]).read_imu_csv(t / "u.csv"),
        ValueError, ("gyro_x_rpm", "'rpm'", "deg_s")),
    Bad("imu-csv-short-row", lambda t: _read_imu(t, "0,0,0,0,0,0\n"), ValueError,
        ("row 1", "6 fields")),
    Bad("imu-csv-empty",
        lambda t: (t / "e.csv").write_text("")
        or __import__("raysim.io.imu_log", fromlist=["x"]).read_imu_csv(t / "e.csv"),
        ValueError, ("e.csv", "header")),
    Bad("imu-csv-missing-file",
        lambda t: __import__("raysim.io.imu_log", fromlist=["x"]).read_imu_csv(t / "none.csv"),
        (ValueError, OSError), ("none.csv",)),
    Bad("dca1000-truncated-capture", _dca_truncated, ValueError,
        ("cut.bin", "2042 bytes", "not a whole number of frames", "truncated")),
    Bad("dca1000-too-many-rx",
        lambda _: __import__("raysim.io.ti_dca1000", fromlist=["x"]).Dca1000Format(
            num_samples=16, slot_interval=60e-6, num_rx=5), ValueError, ("num_rx", "5")),
    Bad("dca1000-negative-slot",
        lambda _: __import__("raysim.io.ti_dca1000", fromlist=["x"]).Dca1000Format(
            num_samples=16, slot_interval=-1.0), ValueError, ("slot_interval", "-1")),
    Bad("zarr-not-a-store",
        lambda t: __import__("raysim.io.storage", fromlist=["x"]).open_store(t / "none.zarr"),
        ValueError, ("none.zarr", "not a Zarr store")),
    Bad("zarr-missing-chunk", lambda t: _damaged_store(t, "delete"), ValueError,
        ("s.zarr", "'if_data'", "frame 1", "c/1/0/0/0")),
    Bad("zarr-truncated-chunk", lambda t: _damaged_store(t, "truncate"), ValueError,
        ("s.zarr", "'if_data'", "frame 1", "Zstd")),
    Bad("stability-netcdf-truncated",
        lambda t: (t / "m.nc").write_bytes(b"CDF\x01\x00\x00")
        and __import__("raysim.studies.stability", fromlist=["x"]).read_netcdf(t / "m.nc"),
        ValueError, ("m.nc", "truncated")),
    # ---------------------------------------------------------- scenario files
    Bad("scenario-negative-sample-rate", lambda _: _validate(_scenario_data(sample_rate_hz=-1)),
        ValueError, ("radar.sample_rate_hz", "-1")),
    Bad("scenario-unknown-key", lambda _: _validate(_scenario_data(samplerate=1)), ValueError,
        ("radar.samplerate", "unknown keys")),
    Bad("scenario-missing-file",
        lambda t: __import__("raysim.io.scenario", fromlist=["x"]).load_scenario(t / "no.toml"),
        ValueError, ("no.toml", "cannot read")),
    # -------------------------------------------------------------- ray tracing
    Bad("rt-unknown-scene",
        lambda _: __import__("raysim.echoes.rt.scenes", fromlist=["x"]).get_scene("moon_base"),
        ValueError, ("'moon_base'", "flat_reflectors")),
    Bad("rt-material-permittivity-below-one",
        lambda _: __import__("raysim.echoes.rt.scenes", fromlist=["x"]).MaterialSpec(
            "foam", relative_permittivity=0.5), ValueError, ("relative_permittivity", "0.5")),
    Bad("rt-material-negative-conductivity",
        lambda _: __import__("raysim.echoes.rt.scenes", fromlist=["x"]).MaterialSpec(
            "foam", conductivity=-1.0), ValueError, ("conductivity", "-1.0")),
    Bad("rt-mesh-nan-vertex",
        lambda t: _load_mesh_scene(t, "nan.ply", "0 0 0\n1 nan 0\n0 1 0\n", "3 0 1 2\n"),
        ValueError, ("nan.ply", "not finite", "vertex 1")),
    Bad("rt-mesh-non-manifold",
        lambda t: _load_mesh_scene(t, "fan.ply", _TRIANGLE + "0 -1 0\n0 0 1\n",
                                   "3 0 1 2\n3 0 1 3\n3 0 1 4\n"),
        ValueError, ("fan.ply", "non-manifold", "more than two faces")),
    Bad("rt-mesh-index-out-of-range",
        lambda t: _load_mesh_scene(t, "oor.ply", _TRIANGLE, "3 0 1 7\n"), ValueError,
        ("oor.ply", "[0, 7]", "[0, 2]")),
    Bad("rt-mesh-missing-file",
        lambda t: __import__("raysim.echoes.rt.scenes", fromlist=["x"]).load_scene(
            _scene_file(t, "concrete", "gone.ply")), ValueError, ("gone.ply", "does not exist")),
    Bad("rt-scene-negative-frequency",
        lambda t: _load_mesh_scene(t, "tri.ply", _TRIANGLE, "3 0 1 2\n", frequency=-77e9),
        ValueError, ("frequency", "-77000000000.0")),
    # --------------------------------------------------------------- compensation
    Bad("comp-imu-not-covering-frame", lambda _: _integrate(T_IMU, chirps=np.array([0.0, 0.08])),
        ValueError, ("chirp_times", "cover")),
    Bad("comp-imu-unsorted",
        lambda _: _integrate(np.array([0.0, 0.002, 0.001, 0.003, 0.004])), ValueError,
        ("imu_time",)),
    Bad("comp-imu-nan-accel",
        lambda _: _integrate(T_IMU, accel=np.full((T_IMU.size, 3), math.nan)), ValueError,
        ("accel",)),
    Bad("comp-gyro-shape-mismatch",
        lambda _: _integrate(T_IMU, gyro=np.zeros((T_IMU.size - 1, 3))), ValueError,
        ("gyro",)),
    Bad("comp-too-few-imu-samples", lambda _: _integrate(T_IMU[:3]), ValueError,
        ("imu_time", "4", "3")),
    Bad("comp-given-velocity-missing",
        lambda _: _integrate(T_IMU, velocity="given", initial_velocity=None), ValueError,
        ("initial_velocity", "hover")),
    Bad("comp-unknown-velocity-mode", lambda _: _integrate(T_IMU, velocity="gps"), ValueError,
        ("velocity", "'gps'")),
    Bad("comp-hover-window-outside",
        lambda _: _integrate(T_IMU, velocity="hover", hover_window=(-1.0, 0.02)), ValueError,
        ("hover_window",)),
    Bad("comp-unknown-paper-step",
        lambda _: __import__("compensation", fromlist=["x"]).paper_chain(
            np.ones((8, 4, 1), np.complex64), ARR.virtual_positions,
            __import__("compensation", fromlist=["x"]).static_motion(np.arange(8) * 60e-6),
            wavelength=3.9e-3, direction=[0.0, 0.0, 1.0], range_axis=[10.0], azimuth=[0.0],
            elevation=[0.0], steps=("tilt", "roll")), ValueError, ("steps", "'roll'")),
    Bad("comp-direction-not-unit",
        lambda _: __import__("compensation", fromlist=["x"]).range_change(
            __import__("compensation", fromlist=["x"]).static_motion(np.arange(8) * 60e-6),
            [0.0, 0.0, 2.0]), ValueError, ("direction", "unit")),
    # ---------------------------------------------------------------- stability
    Bad("stability-target-beyond-range", lambda _: _stability_point(target_range_m=40.0),
        ValueError, ("target_range_m", "40.000")),
    Bad("stability-zero-imu-rate", lambda _: _stability_point(imu_rate_hz=0.0), ValueError,
        ("imu_rate_hz", "0.0")),
    Bad("stability-unknown-init", lambda _: _stability_point(init="gnss"), ValueError,
        ("init", "'gnss'")),
    Bad("stability-unknown-imu-preset", lambda _: _stability_point(imu_spec="nav_grade"),
        ValueError, ("'nav_grade'", "tactical")),
    Bad("stability-negative-seed", lambda _: _stability_point(seed=-1), ValueError,
        ("seed", "-1")),
    Bad("stability-unknown-map",
        lambda _: __import__("raysim.studies.stability", fromlist=["x"]).run_map("wind"),
        ValueError,
        ("'wind'", "rotation_azimuth")),
    Bad("stability-angle-out-of-range",
        lambda _: _stability_point(target_az_deg=115.0), ValueError,
        ("target_az_deg", "115.0")),
    Bad("stability-unknown-chain",
        lambda _: __import__("raysim.studies.stability", fromlist=["x"]).run_map(
            "clock", chains=("none", "paper_integrated")), ValueError,
        ("'paper_integrated'", "paper:published")),
    Bad("stability-point-from-mesh-scenario",
        lambda _: __import__("raysim.studies.stability", fromlist=["x"]).StabilityPoint
        .from_scenario(_validate(dict(scene={"kind": "bundled", "name": "parking_lot"}))),
        ValueError, ("scenario.scene", "'bundled'", "one target")),
    # ---------------------------------------------------------------------- CLI
    Bad("cli-stability-unknown-map",
        lambda t: _cli(["stability", "--out", t / "o", "--maps", "wind"]), CliError,
        ("exit 2", "--maps", "'wind'")),
    Bad("cli-stability-missing-out", lambda _: _cli(["stability"]), CliError,
        ("exit 2", "--out")),
    Bad("cli-stability-bad-executor",
        lambda t: _cli(["stability", "--out", t / "o", "--executor", "mpi"]), CliError,
        ("exit 2", "'mpi'")),
    Bad("cli-unknown-subcommand", lambda _: _cli(["levitate"]), CliError,
        ("exit 2", "'levitate'")),
    Bad("cli-simulate-unknown-case", lambda _: _cli(["simulate", "--case", "roll_x"]), CliError,
        ("exit 2", "'roll_x'", "rotation_y")),
    Bad("cli-simulate-unknown-imu",
        lambda _: _cli(["simulate", "--case", "rotation_y", "--imu", "navigation_grade"]),
        CliError, ("exit 2", "navigation_grade", "consumer_mems")),
    Bad("cli-simulate-bad-motion",
        lambda _: _cli(["simulate", "--case", "rotation_y", "--motion", "pitch:abc:20"]),
        CliError, ("exit 2", "--motion", "pitch:abc:20")),
    Bad("cli-render-missing-scenario",
        lambda t: _cli(["render", t / "none.toml", "--out", t / "x.zarr"]), CliError,
        ("exit 2", "none.toml")),
    Bad("cli-compensate-missing-cube",
        lambda t: _cli(["compensate", t / "none.npz", t / "none.csv", "--out", t / "o.npz"]),
        CliError, ("exit 2", "none.npz", "does not exist")),
    Bad("cli-scenes-unknown-scene", lambda _: _cli(["scenes", "describe", "moon"]), CliError,
        ("exit 2", "'moon'", "flat_reflectors")),
]


@pytest.mark.parametrize("case", CASES, ids=[c.id for c in CASES])
def test_bad_input(case: Bad, tmp_path, capsys):
    """Each bad input raises the documented exception naming the offending value."""
    if case.id.startswith("comp-"):
        pytest.importorskip("compensation.strapdown")
    with pytest.raises(case.exc) as info:
        case.call(tmp_path)
    msg = str(info.value)
    for needle in case.needles:
        assert needle in msg, f"message {msg!r} does not name {needle!r}"


def test_catalogue_is_large_and_unique():
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids))
    assert len(ids) >= 30


def test_cli_errors_name_the_value(tmp_path, capsys):
    """The CLI turns ValueError into exit code 2 and prints the offending value on stderr."""
    from raysim.cli import main

    assert main(["stability", "--out", str(tmp_path / "o"), "--maps", "wind"]) == 2
    err = capsys.readouterr().err
    assert "'wind'" in err and "--maps" in err


# ------------------------------------------------------------ missing guard rails
def _warnings_of(result) -> list[str]:
    for name in ("warnings", "flags"):
        if hasattr(result, name):
            return list(getattr(result, name))
    return []


def _rot_motion(pitch_deg: float):
    comp = pytest.importorskip("compensation")
    n = 16
    t = np.arange(n) * 60e-6
    att = np.broadcast_to(
        __import__("scipy.spatial.transform", fromlist=["Rotation"]).Rotation.from_euler(
            "ZYX", [0.0, np.deg2rad(pitch_deg), 0.0]).as_matrix(), (n, 3, 3)).copy()
    z = np.zeros((n, 3))
    return comp.PlatformMotion(t, att, z, z.copy(), z.copy(), np.array([0.0, 0.0, 0.1]))


def test_guard_imu_gap_is_reported():
    t = np.concatenate([np.arange(0.0, 0.01, 1e-3), np.arange(0.03, 0.05, 1e-3)])
    try:
        m = _integrate(t, chirps=np.arange(8) * 60e-6 + 0.02)
    except ValueError as exc:
        assert "gap" in str(exc)
        return
    assert any("gap" in w for w in _warnings_of(m))


def test_guard_paper_chain_flags_large_rotation():
    comp = pytest.importorskip("compensation")
    motion = _rot_motion(25.0)
    arr = upa(4, 4, wavelength=3.9e-3)
    beams = comp.paper_chain(np.ones((16, 16, 1), np.complex64), arr.virtual_positions, motion,
                             wavelength=3.9e-3, direction=[0.0, 0.0, 1.0], range_axis=[10.0],
                             azimuth=[0.0], elevation=[0.0])
    assert any("small-angle" in w for w in _warnings_of(beams))


def test_guard_hover_window_too_short_is_reported():
    m = _integrate(T_IMU, velocity="hover")
    assert any("hover window" in w for w in _warnings_of(m))


def test_guard_zarr_missing_chunk(tmp_path):
    from raysim.io import storage

    fr = simulate_point_targets(SMALL, ARR, [PointTarget.at(10.0, 0.1, 0.0)])
    storage.write_store(tmp_path / "s.zarr", storage.frames_to_dataset([fr]))
    chunk = next(p for p in (tmp_path / "s.zarr" / "if_data").rglob("*")
                 if p.is_file() and p.name != "zarr.json")
    chunk.unlink()
    with pytest.raises(ValueError, match="if_data"):
        storage.open_store(tmp_path / "s.zarr")


def test_guard_zarr_truncated_chunk(tmp_path):
    from raysim.io import storage

    fr = simulate_point_targets(SMALL, ARR, [PointTarget.at(10.0, 0.1, 0.0)])
    storage.write_store(tmp_path / "s.zarr", storage.frames_to_dataset([fr]))
    chunk = next(p for p in (tmp_path / "s.zarr" / "if_data").rglob("*")
                 if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(chunk.read_bytes()[:7])
    with pytest.raises(ValueError, match="s.zarr"):
        storage.open_store(tmp_path / "s.zarr")


def test_zarr_all_zero_frame_is_not_a_missing_chunk(tmp_path):
    """A frame equal to the fill value is written out, so the chunk check does not flag it."""
    from raysim.io import storage

    fr = simulate_point_targets(SMALL, ARR, [PointTarget.at(10.0, 0.1, 0.0)])
    ds = storage.frames_to_dataset([fr])
    ds["if_data"][:] = 0
    storage.write_store(tmp_path / "z.zarr", ds)
    back = storage.open_store(tmp_path / "z.zarr")
    assert back["if_data"].values.tobytes() == ds["if_data"].values.tobytes()


# --------------------------------------------------------------- atomic writes
def test_atomic_write_interrupted_leaves_nothing(tmp_path):
    """A write interrupted half-way leaves neither the file nor a temporary behind."""
    from raysim.studies.stability import atomic_write

    target = tmp_path / "map.json"

    def half(p: Path) -> None:
        p.write_text('{"half": ')
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(target, half)
    assert list(tmp_path.iterdir()) == []


def test_atomic_write_interrupted_keeps_old_file(tmp_path):
    from raysim.studies.stability import atomic_write

    target = tmp_path / "map.json"
    target.write_text("old")

    def half(p: Path) -> None:
        p.write_text("new, but half")
        raise OSError("disk full")

    with pytest.raises(OSError):
        atomic_write(target, half)
    assert target.read_text() == "old"
    assert sorted(os.listdir(tmp_path)) == ["map.json"]


def test_interrupted_stability_run_keeps_finished_maps(tmp_path, monkeypatch):
    """An interrupted ``raysim stability`` keeps the maps it finished and resumes from them."""
    from raysim.studies import stability
    from raysim.studies.stability import runner

    calls = []
    real = runner.run_map

    def fake_run_map(name, **kw):
        calls.append(name)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(name, **kw)

    small = {k: stability.MAPS[k] for k in ("lever_arm", "clock")}
    monkeypatch.setattr(runner, "MAPS", small)
    monkeypatch.setattr(runner, "run_map", fake_run_map)
    monkeypatch.setattr(runner, "evaluate", _cheap_evaluate)
    with pytest.raises(KeyboardInterrupt):
        stability.write_stability(tmp_path, quick=True, progress=False, executor="serial")
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == ["lever_arm.json", "lever_arm.nc", "lever_arm.png", "points"]
    assert not [p for p in tmp_path.rglob("*") if p.name.startswith(".")]  # no partial files
    for rec in (tmp_path / "points").rglob("*.json"):
        json.loads(rec.read_text())                                        # complete records
    calls.clear()
    monkeypatch.setattr(runner, "run_map", real)
    stability.write_stability(tmp_path, quick=True, progress=False, executor="serial")
    assert (tmp_path / "clock.nc").exists() and (tmp_path / "summary.json").exists()


def _cheap_evaluate(point, chains=("none", "paper", "paper:published", "exact"), **_):
    """Stand-in for :func:`raysim.studies.stability.evaluate` (file handling only)."""
    rec = {"pseudo_velocity_mps": 0.01, "pseudo_velocity_bins": 0.08,
           "doppler_width_hz": 94.0, "angle_error_worst_deg": 0.1, "angle_error_deg": 0.1,
           "map_angle_error_deg": 0.1, "entropy_ae_nats": 3.5}
    out = {c: dict(rec) for c in chains}
    out["warnings"] = []
    out["strapdown"] = "stub"
    return out


# ------------------------------------------------------------- ray-tracing scenes
_ITU_XML = """<scene version="2.1.0">
    <bsdf type="itu-radio-material" id="soil">
        <string name="type" value="{itu}"/>
        <float name="thickness" value="1.0"/>
    </bsdf>
    <shape type="ply" id="mesh-ground">
        <string name="filename" value="meshes/{mesh}"/>
        <ref id="soil" name="bsdf"/>
    </shape>
</scene>
"""
_EMPTY_PLY = ("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
              "property float z\nelement face 0\nproperty list uchar int vertex_indices\n"
              "end_header\n")


def _scene_file(tmp: Path, itu: str, mesh: str) -> Path:
    import shutil

    from raysim.echoes.rt.scenes import SCENES

    (tmp / "meshes").mkdir(exist_ok=True)
    ground = SCENES["flat_reflectors"].path.parent / "meshes" / "ground.ply"
    shutil.copy(ground, tmp / "meshes" / "ground.ply")
    (tmp / "meshes" / "empty.ply").write_text(_EMPTY_PLY)
    path = tmp / f"{itu}_{mesh.split('.')[0]}.xml"
    path.write_text(_ITU_XML.format(itu=itu, mesh=mesh))
    return path


@pytest.fixture
def rt_cpu():
    """Sionna RT on the CPU variant; skip when it cannot run here."""
    from raysim.echoes.rt import backend

    try:
        return backend.configure("cpu", threads=2)
    except backend.BackendError as err:
        pytest.skip(f"Sionna RT LLVM backend unavailable: {err}")


@pytest.mark.sionna
def test_rt_material_undefined_at_carrier(tmp_path, rt_cpu):
    """ITU-R P.2040 ground types are defined up to 10 GHz only: loading at 77 GHz must fail."""
    from raysim.echoes.rt.scenes import load_scene

    with pytest.raises(ValueError, match="very_dry_ground"):
        load_scene(_scene_file(tmp_path, "very_dry_ground", "ground.ply"), frequency=77e9)


@pytest.mark.sionna
def test_rt_empty_mesh_is_named(tmp_path, rt_cpu):
    from raysim.echoes.rt.scenes import load_scene

    with pytest.raises(ValueError, match="empty.ply"):
        load_scene(_scene_file(tmp_path, "concrete", "empty.ply"), frequency=77e9)


# ----------------------------------------------- interrupted writes of other writers
def test_storage_atomic_write_interrupted_at_rename(tmp_path, monkeypatch):
    """raysim.io.storage writes aside and renames: an interruption leaves no file at all."""
    from raysim.io import storage

    def boom(*_a, **_k):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        storage.atomic_write_text(tmp_path / "points.json", '{"a": 1}')
    assert list(tmp_path.iterdir()) == []


def test_stability_netcdf_interrupted_at_rename(tmp_path, monkeypatch):
    import xarray as xr

    from raysim.studies.stability import write_netcdf

    ds = xr.Dataset({"fail": (("x",), np.array([True, False]))}, coords={"x": [0.0, 1.0]})

    def boom(*_a, **_k):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(KeyboardInterrupt):
        write_netcdf(ds, tmp_path / "map.nc")
    assert list(tmp_path.iterdir()) == []


def _interrupt_writers(monkeypatch, which: str) -> None:
    """Make ``which`` writer fail half-way through its file."""
    from raysim.io import imu_log, ti_dca1000

    if which == "imu":
        calls = []

        def interrupted_repr(v):
            calls.append(1)
            if len(calls) > 300:
                raise KeyboardInterrupt
            return repr(v)

        monkeypatch.setattr(imu_log, "repr", interrupted_repr, raising=False)
    else:
        class HalfWritten(np.ndarray):
            def tofile(self, fid, *a, **k):
                np.asarray(self).ravel()[: self.size // 2].tofile(fid)
                raise OSError("disk full")

        real = np.ascontiguousarray

        class NumpyProxy:
            def __getattr__(self, name):
                return getattr(np, name)

            @staticmethod
            def ascontiguousarray(a, dtype=None):
                return real(a, dtype=dtype).view(HalfWritten)

        monkeypatch.setattr(ti_dca1000, "np", NumpyProxy())


@pytest.mark.parametrize("which", ["imu", "dca1000"])
def test_interrupted_writer_leaves_no_partial_file(tmp_path, monkeypatch, which):
    from raysim.io import imu_log, ti_dca1000
    from raysim.io.ti_dca1000 import Dca1000Format

    _interrupt_writers(monkeypatch, which)
    with pytest.raises((KeyboardInterrupt, OSError)):
        if which == "imu":
            imu_log.write_imu_csv(tmp_path / "out", _imu_samples(np.arange(200) * 1e-3))
        else:
            fmt = Dca1000Format(num_samples=16, slot_interval=60e-6, num_rx=4, num_tx=1,
                                num_loops=4)
            ti_dca1000.write_dca1000(tmp_path / "out", np.ones((2, 4, 4, 16), np.complex64), fmt)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("which", ["imu", "dca1000"])
def test_interrupted_writer_keeps_existing_file(tmp_path, monkeypatch, which):
    """An interrupted IMU-log or capture write leaves the previous file byte for byte and no
    temporary file; the next complete write replaces it."""
    from raysim.io import imu_log, ti_dca1000
    from raysim.io.ti_dca1000 import Dca1000Format

    fmt = Dca1000Format(num_samples=16, slot_interval=60e-6, num_rx=4, num_tx=1, num_loops=4)
    if which == "imu":
        target = tmp_path / "imu.csv"

        def write(n):
            return imu_log.write_imu_csv(target, _imu_samples(np.arange(n) * 1e-3))
    else:
        target = tmp_path / "adc.bin"

        def write(n):
            return ti_dca1000.write_dca1000(target, np.full((n, 4, 4, 16), 3 + 1j, np.complex64),
                                            fmt)
    write(2)
    old = target.read_bytes()
    with monkeypatch.context() as mp:
        _interrupt_writers(mp, which)
        with pytest.raises((KeyboardInterrupt, OSError)):
            write(200)
    assert target.read_bytes() == old
    assert sorted(os.listdir(tmp_path)) == [target.name]
    write(3)
    assert len(target.read_bytes()) > len(old)
    assert sorted(os.listdir(tmp_path)) == [target.name]
