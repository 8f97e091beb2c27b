"""The catalogue of bad inputs, part 1: the public API, the file readers and the stores.

Every case names one bad input, the exception type it must raise and the
fragments its message must contain (the offending parameter and/or value),
so a user reading the error knows what to fix. Guard rails (the compensation
flagging its own broken assumptions, damaged stores) are tested at the end.

Part 2, the command line and scenario files, is tests/test_bad_input_cli.py
(which also counts the whole catalogue); atomic writes and interrupted runs
are tests/test_bad_input_writes.py.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from bad_input_common import ARR, SMALL, Bad, validate
from bad_input_common import imu_samples as _imu_samples

from raysim.echoes.oracle import PointTarget, simulate_point_targets
from raysim.platform.kinematics import element_times
from raysim.platform.motion import HoverJitterSpec, Sinusoid, hover_jitter, sinusoid, stationary
from raysim.radar.arrays import VirtualArray, tdm_mimo, ti_3tx4rx, upa
from raysim.radar.config import RadarConfig

IMU_HEADER = ("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,"
              "accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n")


def _imu_csv(tmp: Path, body: str) -> Path:
    p = tmp / "imu.csv"
    p.write_text(IMU_HEADER + body)
    return p


def _read_imu(tmp: Path, body: str):
    from raysim.io.imu_log import read_imu_csv

    return read_imu_csv(_imu_csv(tmp, body))


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


def _analyse_bad(value: float):
    """``measure`` of a frame (``frame_index`` 2) with ``value`` at chirp 3, channel 1, sample 7."""
    from dataclasses import replace

    from raysim.measure.point import measure

    fr = simulate_point_targets(SMALL, ARR, [PointTarget.at(10.0, 0.1, 0.0)])
    data = fr.data.copy()
    data[3, 1, 7] = value
    return measure([replace(fr, data=data, frame_index=2)])


def _point_gate(snapshots, range_m: float = 10.0):
    from raysim.measure.point import PointGate

    return PointGate(snapshots, range_m, SMALL, ARR)


def _gate_ones():
    return _point_gate(np.ones((1, SMALL.num_chirps, ARR.num_channels), np.complex64))


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
    Bad("config-tx-power-overflow", lambda _: RadarConfig(tx_power_dbm=1e6), ValueError,
        ("tx_power_dbm", "1000000.0", "[-100, 60] dBm")),
    Bad("config-antenna-gain-nan", lambda _: RadarConfig(antenna_gain_dbi=math.nan), ValueError,
        ("antenna_gain_dbi", "nan", "dBi")),
    Bad("config-noise-figure-negative", lambda _: RadarConfig(noise_figure_db=-1.0), ValueError,
        ("noise_figure_db", "-1.0", "[0, 50] dB")),
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
    Bad("target-rcs-900", lambda _: PointTarget.at(10.0, 0.0, 0.0, rcs_dbsm=900.0), ValueError,
        ("rcs_dbsm", "900.0", "[-250, 100] dBsm")),
    Bad("target-rcs-text", lambda _: PointTarget(np.zeros(3), rcs_dbsm="big"), ValueError,
        ("rcs_dbsm", "'big'")),
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
    Bad("measure-nan-in-if", lambda _: _analyse_bad(math.nan), ValueError,
        ("frame 2", "chirp 3", "channel 1", "sample 7", "non-finite")),
    Bad("measure-inf-in-if", lambda _: _analyse_bad(math.inf), ValueError,
        ("frame 2", "chirp 3", "channel 1", "sample 7", "inf")),
    Bad("point-gate-missing-frame-axis",
        lambda _: _point_gate(np.ones((SMALL.num_chirps, ARR.num_channels))), ValueError,
        ("snapshots", "[frame, chirp, channel]")),
    Bad("point-gate-wrong-channels",
        lambda _: _point_gate(np.ones((1, SMALL.num_chirps, ARR.num_channels + 1))), ValueError,
        ("snapshots", f"{ARR.num_channels + 1} channels", f"{ARR.num_channels}")),
    Bad("point-gate-negative-range",
        lambda _: _point_gate(np.ones((1, SMALL.num_chirps, ARR.num_channels)), -1.0),
        ValueError, ("range_m", "-1.0")),
    Bad("gate-metrics-exact-without-motion",
        lambda _: __import__("raysim.measure.point", fromlist=["x"]).gate_metrics(
            _gate_ones(), chain="exact"), ValueError, ("'exact'", "motion")),
    Bad("gate-metrics-no-map-no-reference",
        lambda _: __import__("raysim.measure.point", fromlist=["x"]).gate_metrics(
            _gate_ones(), accumulate=False), ValueError, ("accumulate=False", "reference")),
    Bad("beamformer-paper-without-motion",
        lambda _: __import__("raysim.pipeline.beams", fromlist=["x"]).Beamformer(
            "paper", ARR, SMALL.center_wavelength), ValueError, ("'paper'", "motion")),
    Bad("reproduction-overrides-not-a-mapping",
        lambda _: __import__("raysim.studies.reproduce", fromlist=["x"]).ReproductionSettings(
            overrides=[("radar.num_chirps", 64)]), ValueError, ("overrides", "list")),
    Bad("reproduction-seeds-beyond-the-bound",
        lambda _: __import__("raysim.studies.reproduce", fromlist=["x"]).reproduce(
            ["rotation_y"], seeds=1_000_000_000), ValueError, ("1 to 1000", "1000000000")),
    Bad("unknown-paper-case",
        lambda _: __import__("raysim.scenario", fromlist=["x"]).get_case("roll_x"), ValueError,
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
    Bad("output-path-under-a-file",
        lambda t: (t / "f").write_text("x")
        and __import__("raysim.io.files", fromlist=["x"]).check_output(t / "f" / "o.nc"),
        ValueError, ("--out", "o.nc", "is a file, not a folder")),
    Bad("output-dir-is-a-file",
        lambda t: (t / "f").write_text("x")
        and __import__("raysim.io.files", fromlist=["x"]).check_output(t / "f", "dir",
                                                                       "output.store"),
        ValueError, ("output.store", "existing file", "expected a folder")),
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
        .from_scenario(validate(dict(scene={"kind": "bundled", "name": "parking_lot"}))),
        ValueError, ("scenario.scene", "'bundled'", "one target")),
    Bad("stability-unknown-mounting", lambda _: _stability_point(mounting_deg="sideways"),
        ValueError, ("mounting_deg", "'sideways'", "forward")),
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


# ------------------------------------------------------------ arrays without aperture
@pytest.mark.parametrize(("nx", "ny", "az_ok", "el_ok"),
                         [(1, 1, False, False), (4, 1, True, False), (1, 4, False, True),
                          (4, 4, True, True)])
def test_angle_metrics_need_aperture(nx, ny, az_ok, el_ok):
    """A single channel or a line array reports NaN (not the grid edge) on an axis it
    cannot resolve; the angle errors need both axes."""
    from raysim.measure.point import measure
    from raysim.pipeline.sources import Reference

    arr = upa(nx, ny, wavelength=SMALL.wavelength)
    fr = simulate_point_targets(SMALL, arr, [PointTarget.at(10.0, 0.1, 0.05)])
    ref = Reference(range_m=10.0, az_deg=math.degrees(0.1), el_deg=math.degrees(0.05))
    m = measure([fr], ref)
    for key in ("az_deg", "map_az_deg"):
        assert math.isfinite(m[key]) == az_ok, (key, m[key])
    for key in ("el_deg", "map_el_deg"):
        assert math.isfinite(m[key]) == el_ok, (key, m[key])
    for key in ("angle_error_deg", "map_angle_error_deg"):
        assert math.isfinite(m[key]) == (az_ok and el_ok), (key, m[key])
    if az_ok and el_ok:
        assert m["angle_error_deg"] < 1.0
    assert math.isfinite(m["range_m"]) and abs(m["range_m"] - 10.0) < 0.1
