"""The compensate stage (`raysim.pipeline.compensate.compensate`) called from Python.

`raysim compensate` parses its options and calls the stage; the flight study calls the
stage, never the command.
"""

from __future__ import annotations

import numpy as np
import pytest

from raysim.cli import main
from raysim.io.zarr_store import open_store
from raysim.pipeline.compensate import compensate
from raysim.pipeline.flight import MEASURE_STEP_DEG, write_flight


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    return write_flight(tmp_path_factory.mktemp("flight"), imu="consumer_mems",
                        time_offset=0.003, frames=2, seed=1)


def _cells(flight):
    r, az, _ = flight.target
    return r, az


def test_stage_is_the_command(flight, tmp_path):
    """The self-calibrating stage and `raysim compensate` with the same options write the
    same beams; the result carries the calibration, the offset applied and the frames."""
    r, az = _cells(flight)
    res = compensate(**flight.calibrating_options(), out=tmp_path / "s.zarr",
                     range_m=(r - 0.5, r + 0.5),
                     azimuth_deg=az - 6 + MEASURE_STEP_DEG * np.arange(49),
                     elevation_deg=[0.0])
    assert res.frames == [0, 1] and res.chain == "exact"
    assert res.shape == (2, 64, 6, 49, 1)
    assert res.time_offset == res.calibration["time_offset_s"]
    assert abs(res.time_offset - flight.time_offset) < 0.5e-3
    assert main(flight.calibrating_command(
        tmp_path / "c.zarr", "--range-m", f"{r - 0.5}:{r + 0.5}", "--az-deg",
        f"{az - 6}:{az + 6}:{MEASURE_STEP_DEG}", "--el-deg", "0:0:1", "--no-progress")) == 0
    a, b = open_store(tmp_path / "s.zarr"), open_store(tmp_path / "c.zarr")
    assert np.array_equal(a["beams"].values, b["beams"].values)
    assert a.attrs["time_offset_s"] == b.attrs["time_offset_s"]
    # frames as a pair of numbers; the chain none needs no IMU log and applies no offset
    one = compensate(flight.capture, radar_config=flight.radar_config, frames=(1, 2),
                     chain="none", out=tmp_path / "n.npz", range_m=(r - 0.5, r + 0.5),
                     azimuth_deg=[az], elevation_deg=[0.0])
    assert one.frames == [1] and one.time_offset is None and one.calibration is None
    with pytest.raises(ValueError, match=r"--frames: got \(1, 2, 3\)"):
        compensate(flight.capture, radar_config=flight.radar_config, frames=(1, 2, 3),
                   chain="none", out=tmp_path / "m.npz")


def test_flight_table_runs_the_stage_not_the_cli(tmp_path, monkeypatch):
    import raysim.cli
    from raysim.pipeline.flight import calibrated_flight_table

    def refuse(*_a, **_k):
        raise AssertionError("the study called the command line")

    monkeypatch.setattr(raysim.cli, "main", refuse)
    rows = calibrated_flight_table(tmp_path, seeds=[1], frames=2)
    assert len(rows) == 1 and abs(rows[0]["offset_error_ms"]) < 0.5
    assert (tmp_path / "seed1" / "compensated.zarr").is_dir()


def test_stage_warnings_and_imu_table(tmp_path):
    """An IMU table instead of a file; the hover assumption over a short record is a
    warning of the result and of the output."""
    from raysim.echoes.oracle import PointTarget, simulate_point_targets
    from raysim.platform.imu import simulate_imu
    from raysim.platform.motion import sinusoid
    from raysim.radar.arrays import upa
    from raysim.radar.config import RadarConfig

    cfg = RadarConfig(num_chirps=32, sample_rate=2.5e6)
    arr = upa(4, 4, wavelength=cfg.wavelength)
    traj = sinusoid("pitch", np.deg2rad(3), 10.0)
    fr = simulate_point_targets(cfg, arr, [PointTarget.at(12.0, 0.2, 0.0)], traj)
    np.savez(tmp_path / "c.npz", data=fr.data, chirp_times=fr.chirp_times,
             element_positions=arr.virtual_positions, carrier_frequency=cfg.carrier_frequency,
             bandwidth=cfg.bandwidth, chirp_duration=cfg.chirp_duration,
             sample_rate=cfg.sample_rate, grid_shape=np.array(arr.grid_shape))
    s = simulate_imu(traj, "ideal", rate=1000.0, start=-0.01, end=0.02)
    table = np.column_stack([s.time, s.gyro, s.accel])
    res = compensate(tmp_path / "c.npz", table, out=tmp_path / "b.npz", range_m=(11, 13),
                     azimuth_deg=[11.0], elevation_deg=[0.0])
    assert [w.split(":")[0] for w in res.warnings] == ["hover window"]
    assert list(np.load(tmp_path / "b.npz")["warnings"]) == list(res.warnings)
    with pytest.raises(ValueError, match=r"imu: got an array of shape \(5, 3\)"):
        compensate(tmp_path / "c.npz", np.zeros((5, 3)), out=tmp_path / "x.npz")
    with pytest.raises(ValueError, match="--velocity: got 'guess'"):
        compensate(tmp_path / "c.npz", table, out=tmp_path / "x.npz", velocity="guess")
    with pytest.raises(ValueError, match="--time-offset: got 'later'"):
        compensate(tmp_path / "c.npz", table, out=tmp_path / "x.npz", time_offset="later")
    with pytest.raises(ValueError, match="--az-deg: got"):
        compensate(tmp_path / "c.npz", table, out=tmp_path / "x.npz", azimuth_deg=[])
    assert not (tmp_path / "x.npz").exists()
