"""`raysim compensate`: a stored cube plus an IMU log (CSV, PX4 ULog, ROS bags), exact chain."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.cli import main
from raysim.echoes.oracle import PointTarget, simulate_point_targets
from raysim.platform.imu import simulate_imu
from raysim.platform.motion import sinusoid
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

BOOT_S = 1.0   # flight-controller logs count from boot: the IMU clock reads 1 s at chirp 0


def _write_imu(fmt: str, tmp_path, s):
    """The IMU log in format ``fmt``; returns (CLI arguments, IMU clock minus radar clock)."""
    from dataclasses import replace

    from ros1_bags import write_ros1_imu

    from raysim.io import write_imu_csv
    from raysim.io.flight_logs.rosbag import write_ros2_imu
    from raysim.io.flight_logs.ulog import write_px4_ulog

    if fmt == "legacy-csv":   # the header `raysim compensate` documented before, positional
        np.savetxt(tmp_path / "imu.csv", np.column_stack([s.time, s.gyro, s.accel]),
                   delimiter=",", header="time_s,gyro_x,gyro_y,gyro_z,accel_x,accel_y,accel_z",
                   comments="", fmt="%.17g")
        return [str(tmp_path / "imu.csv")], 0.0
    if fmt == "write_imu_csv":
        path = write_imu_csv(tmp_path / "imu.csv", s, time_unit="ms", gyro_unit="deg_s")
        return ["--imu", str(path)], 0.0
    booted = replace(s, time=s.time + BOOT_S)
    if fmt == "ulog":
        return ["--imu", str(write_px4_ulog(tmp_path / "f.ulg", booted))], BOOT_S
    if fmt == "ros2-mcap":
        return ["--imu", str(write_ros2_imu(tmp_path / "bag", booted, storage="mcap"))], BOOT_S
    if fmt == "ros1-bag":
        return ["--imu", str(write_ros1_imu(tmp_path / "f.bag", booted))], BOOT_S
    raise AssertionError(fmt)


@pytest.mark.parametrize("fmt", ["legacy-csv", "write_imu_csv", "ulog", "ros2-mcap",
                                 "ros1-bag"])
def test_compensate_cube_and_imu_log(tmp_path, fmt):
    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6)
    arr = upa(6, 6, wavelength=cfg.wavelength)
    lever = np.array([0.0, 0.0, 0.1])
    traj = sinusoid("pitch", np.deg2rad(5), 10.0)
    tgt = PointTarget.at(12.0, np.deg2rad(15), 0.0, radar_origin=lever)
    frame = simulate_point_targets(cfg, arr, [tgt], traj, lever_arm=lever)
    np.savez(tmp_path / "cube.npz", data=frame.data, chirp_times=frame.chirp_times,
             element_positions=arr.virtual_positions, carrier_frequency=cfg.carrier_frequency,
             bandwidth=cfg.bandwidth, chirp_duration=cfg.chirp_duration,
             sample_rate=cfg.sample_rate, grid_shape=np.array(arr.grid_shape), lever_arm=lever)
    s = simulate_imu(traj, "ideal", rate=1000.0, start=-0.01, end=0.02)
    imu_args, offset = _write_imu(fmt, tmp_path, s)
    out = tmp_path / "beams.npz"
    code = main(["compensate", str(tmp_path / "cube.npz"), *imu_args,
                 "--out", str(out), "--range-m", "11.5:12.5", "--az-deg", "15:15:1",
                 "--el-deg", "0:0:1", "--velocity", "given", "--initial-velocity", "0,0,0",
                 "--time-offset", repr(offset)])
    assert code == 0
    with np.load(out) as z:
        beams, v = z["beams"], z["velocity_mps"]
        power = z["doppler_power"]
        gate = int(np.argmax(np.abs(beams).sum(axis=(0, 2, 3))))
        slow = beams[:, gate, 0, 0]
        # compensated: a constant slow-time sequence, Doppler peak at zero
        assert np.abs(slow.mean()) / np.abs(slow).mean() > 0.9999
        assert v[int(np.argmax(power[:, gate, 0, 0]))] == 0.0
    assert not list(tmp_path.glob(".tmp_*"))


def test_compensate_takes_the_imu_log_once(tmp_path, capsys):
    np.savez(tmp_path / "c.npz", data=np.zeros((2, 2, 2), complex), chirp_times=np.zeros(2),
             element_positions=np.zeros((2, 3)), carrier_frequency=77e9, bandwidth=1e9,
             chirp_duration=1e-5, sample_rate=1e6)
    (tmp_path / "imu.txt").write_text("0,1\n")
    cube, out = str(tmp_path / "c.npz"), ["--out", str(tmp_path / "o.npz")]
    assert main(["compensate", cube, "a.csv", "--imu", "b.csv", *out]) == 2
    assert "give the IMU log once" in capsys.readouterr().err
    assert main(["compensate", cube, "--imu", str(tmp_path / "imu.txt"), *out]) == 2
    assert "unknown suffix '.txt'" in capsys.readouterr().err


def test_compensate_names_the_ardupilot_extra(tmp_path, capsys, monkeypatch):
    import sys

    from raysim.io.flight_logs.dataflash import write_dataflash_imu

    np.savez(tmp_path / "c.npz", data=np.zeros((2, 2, 2), complex), chirp_times=np.zeros(2),
             element_positions=np.zeros((2, 3)), carrier_frequency=77e9, bandwidth=1e9,
             chirp_duration=1e-5, sample_rate=1e6)
    s = simulate_imu(sinusoid("pitch", 0.01, 10.0), "ideal", rate=1000.0, start=0.0, end=0.01)
    path = write_dataflash_imu(tmp_path / "f.bin", s)
    monkeypatch.setitem(sys.modules, "pymavlink", None)   # as if the extra is not installed
    assert main(["compensate", str(tmp_path / "c.npz"), "--imu", str(path), "--out",
                 str(tmp_path / "o.npz")]) == 2
    assert "pip install raysim[ardupilot]" in capsys.readouterr().err


def test_compensate_reports_bad_files(tmp_path, capsys):
    assert main(["compensate", str(tmp_path / "none.npz"), str(tmp_path / "imu.csv"),
                 "--out", str(tmp_path / "o.npz")]) == 2
    assert "does not exist" in capsys.readouterr().err
    np.savez(tmp_path / "c.npz", data=np.zeros((2, 2, 2), complex))
    (tmp_path / "imu.csv").write_text("t,a\n0,1\n")
    assert main(["compensate", str(tmp_path / "c.npz"), str(tmp_path / "imu.csv"),
                 "--out", str(tmp_path / "o.npz")]) == 2
    assert "lacks keys" in capsys.readouterr().err


def _store_frame(cfg, arr, traj, lever):
    from raysim.io import storage

    tgt = PointTarget.at(12.0, np.deg2rad(15), 0.0, radar_origin=lever)
    frame = simulate_point_targets(cfg, arr, [tgt], traj, lever_arm=lever)
    s = simulate_imu(traj, "ideal", rate=1000.0, start=-0.01, end=0.02)
    imu = storage.imu_dataset(s.time, s.gyro, s.accel)
    return storage.frames_to_dataset([frame], traj, imu=imu)


def _check_beams(out):
    with np.load(out) as z:
        beams, v, power = z["beams"], z["velocity_mps"], z["doppler_power"]
        gate = int(np.argmax(np.abs(beams).sum(axis=(0, 2, 3))))
        slow = beams[:, gate, 0, 0]
        assert np.abs(slow.mean()) / np.abs(slow).mean() > 0.9999
        assert v[int(np.argmax(power[:, gate, 0, 0]))] == 0.0
        return list(z["warnings"])


def test_compensate_zarr_store_with_its_imu_log(tmp_path, capsys):
    from raysim.io import storage

    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6)
    arr = upa(6, 6, wavelength=cfg.wavelength)
    lever = np.array([0.0, 0.0, 0.1])
    ds = _store_frame(cfg, arr, sinusoid("pitch", np.deg2rad(5), 10.0), lever)
    storage.write_store(tmp_path / "s.zarr", ds)
    common = ["--range-m", "11.5:12.5", "--az-deg", "15:15:1", "--el-deg", "0:0:1"]
    out = tmp_path / "beams.npz"
    assert main(["compensate", str(tmp_path / "s.zarr"), "--out", str(out), *common,
                 "--velocity", "given", "--initial-velocity", "0,0,0"]) == 0
    assert _check_beams(out) == []
    # hover assumption over the 30 ms IMU log: compensated, but the result says so
    assert main(["compensate", str(tmp_path / "s.zarr"), "--out", str(out), *common]) == 0
    captured = capsys.readouterr()
    assert "warning: exact: hover window:" in captured.err
    assert [w.split(":")[0] for w in np.load(out)["warnings"]] == ["hover window"]
    assert main(["compensate", str(tmp_path / "s.zarr"), "--out", str(out), "--frame", "3",
                 *common]) == 2
    assert "--frame 3" in capsys.readouterr().err


def test_compensate_keeps_an_imu_log_kept_inside_its_output_store(tmp_path, capsys):
    """The IMU log moved into the compensated store of an earlier run, then given with
    --imu: replacing that store would delete the command's own input."""
    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6)
    arr = upa(6, 6, wavelength=cfg.wavelength)
    traj = sinusoid("pitch", np.deg2rad(5), 10.0)
    frame = simulate_point_targets(cfg, arr, [PointTarget.at(12.0, np.deg2rad(15), 0.0)],
                                   traj)
    np.savez(tmp_path / "cube.npz", data=frame.data, chirp_times=frame.chirp_times,
             element_positions=arr.virtual_positions, carrier_frequency=cfg.carrier_frequency,
             bandwidth=cfg.bandwidth, chirp_duration=cfg.chirp_duration,
             sample_rate=cfg.sample_rate, grid_shape=np.array(arr.grid_shape))
    s = simulate_imu(traj, "ideal", rate=1000.0, start=-0.01, end=0.02)
    out = tmp_path / "beams.zarr"
    args = ["--out", str(out), "--range-m", "11.5:12.5", "--az-deg", "15:15:1", "--el-deg",
            "0:0:1", "--velocity", "given", "--initial-velocity", "0,0,0", "--no-progress"]
    imu, _ = _write_imu("write_imu_csv", tmp_path, s)
    assert main(["compensate", str(tmp_path / "cube.npz"), *imu, *args]) == 0
    from raysim.resources import format_bytes, tree_bytes

    assert f"wrote {out} ({format_bytes(tree_bytes(out))}): beams" in capsys.readouterr().out
    kept = out / "imu.csv"
    (tmp_path / "imu.csv").rename(kept)
    capsys.readouterr()
    assert main(["compensate", str(tmp_path / "cube.npz"), "--imu", str(kept), *args]) == 2
    assert "which raysim did not write" in capsys.readouterr().err and kept.is_file()


def test_compensate_netcdf_store(tmp_path):
    from raysim.io import storage

    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6)
    arr = upa(6, 6, wavelength=cfg.wavelength)
    lever = np.array([0.0, 0.0, 0.1])
    ds = _store_frame(cfg, arr, sinusoid("pitch", np.deg2rad(5), 10.0), lever)
    try:
        storage.export_netcdf(ds, tmp_path / "s.nc")
    except (ImportError, storage.FeatureUnavailableError) as exc:  # no NetCDF engine
        import pytest

        pytest.skip(f"NetCDF engine unavailable: {exc}")
    out = tmp_path / "beams.npz"
    assert main(["compensate", str(tmp_path / "s.nc"), "--out", str(out), "--range-m",
                 "11.5:12.5", "--az-deg", "15:15:1", "--el-deg", "0:0:1", "--velocity",
                 "given", "--initial-velocity", "0,0,0"]) == 0
    assert _check_beams(out) == []


def test_compensate_chains_by_their_vocabulary_names(tmp_path, capsys):
    """--chain takes the names of raysim.vocabulary: none (no IMU needed), paper,
    paper:published, exact; the output records the chain key."""
    from raysim.io import storage

    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6)
    arr = upa(6, 6, wavelength=cfg.wavelength)
    lever = np.array([0.0, 0.0, 0.1])
    ds = _store_frame(cfg, arr, sinusoid("pitch", np.deg2rad(5), 10.0), lever)
    storage.write_store(tmp_path / "s.zarr", ds)
    common = ["--range-m", "11.5:12.5", "--az-deg", "15:15:1", "--el-deg", "0:0:1",
              "--velocity", "given", "--initial-velocity", "0,0,0"]
    out = tmp_path / "beams.npz"
    for chain in ("paper", "paper:published"):
        assert main(["compensate", str(tmp_path / "s.zarr"), "--out", str(out), "--chain",
                     chain, "--direction-deg", "15,0", *common]) == 0
        assert f"chain {chain}" in capsys.readouterr().out
        assert str(np.load(out)["chain"]) == chain
        _check_beams(out)
    # none: the conventional beamformer keeps the pitch's Doppler, on the real chirp times
    assert main(["compensate", str(tmp_path / "s.zarr"), "--out", str(out), "--chain", "none",
                 *common]) == 0
    with np.load(out) as z:
        assert str(z["chain"]) == "none"
        np.testing.assert_allclose(z["chirp_times"], ds["chirp_time"].values.ravel())
        gate = int(np.argmax(np.abs(z["beams"]).sum(axis=(0, 2, 3))))
        slow = z["beams"][:, gate, 0, 0]
        assert np.abs(slow.mean()) / np.abs(slow).mean() < 0.9999
    capsys.readouterr()
    assert main(["compensate", str(tmp_path / "s.zarr"), "--out", str(out), "--chain",
                 "uncompensated", *common]) == 2
    err = capsys.readouterr().err
    assert "--chain: got 'uncompensated'" in err and "'none'" in err
    assert main(["compensate", str(tmp_path / "s.zarr"), "--out", str(out), "--chain",
                 "paper", *common]) == 2
    assert "--chain paper needs --direction-deg" in capsys.readouterr().err


def test_compensate_help_has_examples(capsys):
    import pytest

    with pytest.raises(SystemExit) as ex:
        main(["compensate", "--help"])
    assert ex.value.code == 0
    text = capsys.readouterr().out
    assert "examples:" in text and "exit status" in text
    for line in ("raysim compensate rotation_y.zarr --out beams.npz",
                 "--chain paper:published --direction-deg 20,0",
                 "--chain none --out none.npz"):
        assert line in text, line


def test_a_real_sampled_cube_is_compensated_as_its_complex_twin(tmp_path, capsys):
    """A real-only ADC (TI ``adcCfg 2 0``): the range spectrum's positive half, the same
    target, the same compensated slow time as the complex cube of the same motion."""
    from raysim.io import write_imu_csv

    lever = np.array([0.0, 0.0, 0.1])
    traj = sinusoid("pitch", np.deg2rad(5), 10.0)
    tgt = PointTarget.at(5.0, np.deg2rad(15), 0.0, radar_origin=lever)
    imu = write_imu_csv(tmp_path / "imu.csv", simulate_imu(traj, "ideal", rate=1000.0,
                                                           start=-0.01, end=0.02))
    peaks = {}
    for real in (False, True):
        cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6, complex_sampling=not real)
        arr = upa(6, 6, wavelength=cfg.wavelength)
        frame = simulate_point_targets(cfg, arr, [tgt], traj, lever_arm=lever)
        assert np.iscomplexobj(frame.data) is not real
        cube = tmp_path / f"cube{real:d}.npz"
        np.savez(cube, data=frame.data, chirp_times=frame.chirp_times,
                 element_positions=arr.virtual_positions,
                 carrier_frequency=cfg.carrier_frequency, bandwidth=cfg.bandwidth,
                 chirp_duration=cfg.chirp_duration, sample_rate=cfg.sample_rate,
                 grid_shape=np.array(arr.grid_shape), lever_arm=lever)
        out = tmp_path / f"beams{real:d}.npz"
        assert main(["compensate", str(cube), "--imu", str(imu), "--out", str(out),
                     "--range-m", "4:6", "--az-deg", "0:30:1", "--el-deg", "0:0:1",
                     "--velocity", "given", "--initial-velocity", "0,0,0"]) == 0, \
            capsys.readouterr().err
        with np.load(out) as z:
            power = np.abs(z["beams"]).sum(axis=0)[..., 0]          # [range, azimuth]
            g, a = np.unravel_index(int(np.argmax(power)), power.shape)
            slow = z["beams"][:, g, a, 0]
            peaks[real] = (float(z["range_m"][g]), float(z["azimuth_deg"][a]))
            assert np.abs(slow.mean()) / np.abs(slow).mean() > 0.9999
    assert peaks[True] == peaks[False] and peaks[False][1] == pytest.approx(15.0), peaks


def test_a_cube_whose_chirp_times_do_not_fit_is_named(tmp_path, capsys):
    np.savez(tmp_path / "c.npz", data=np.zeros((4, 2, 2), complex), chirp_times=np.zeros(3),
             element_positions=np.zeros((2, 3)), carrier_frequency=77e9, bandwidth=1e9,
             chirp_duration=1e-5, sample_rate=1e6)
    assert main(["compensate", str(tmp_path / "c.npz"), "--chain", "none",
                 "--out", str(tmp_path / "o.npz")]) == 2
    assert "chirp_times has shape (3,), expected one time per chirp of 'data' (4,)" in \
        capsys.readouterr().err


def test_a_matlab_cube_reads_as_its_npz_twin(tmp_path, capsys):
    """The same keys saved by MATLAB (``save -v7``; here scipy's writer of that format,
    which stores vectors as 1 x n and scalars as 1 x 1) give the same beams."""
    from scipy.io import savemat

    cfg = RadarConfig(num_chirps=16, sample_rate=2.5e6)
    arr = upa(4, 2, wavelength=cfg.wavelength)
    frame = simulate_point_targets(cfg, arr, [PointTarget.at(5.0, np.deg2rad(-10), 0.0)],
                                   sinusoid("roll", np.deg2rad(2), 8.0))
    keys = dict(data=frame.data, chirp_times=frame.chirp_times,
                element_positions=arr.virtual_positions, carrier_frequency=cfg.carrier_frequency,
                bandwidth=cfg.bandwidth, chirp_duration=cfg.chirp_duration,
                sample_rate=cfg.sample_rate, grid_shape=np.array(arr.grid_shape))
    np.savez(tmp_path / "c.npz", **keys)
    savemat(tmp_path / "c.mat", keys)
    beams = []
    for name in ("c.npz", "c.mat"):
        out = tmp_path / f"{name}.beams.npz"
        assert main(["compensate", str(tmp_path / name), "--chain", "none", "--out", str(out),
                     "--range-m", "4:6", "--az-deg", "-20:0:2", "--el-deg", "0:0:1"]) == 0
        with np.load(out) as z:
            beams.append(z["beams"])
    np.testing.assert_array_equal(beams[0], beams[1])
    v73 = tmp_path / "v73.mat"        # a v7.3 file: MATLAB's text header, version 0x0200, HDF5
    v73.write_bytes(b"MATLAB 7.3 MAT-file".ljust(124) + b"\x00\x02IM" + bytes(384))
    capsys.readouterr()
    assert main(["compensate", str(v73), "--chain", "none", "--out",
                 str(tmp_path / "o.npz")]) == 2
    assert "MATLAB v7.3 (HDF5) file; save it with save(..., '-v7')" in capsys.readouterr().err


@pytest.mark.parametrize("suffix", [".npz", ".mat"])
def test_a_cube_larger_than_memory_is_refused_before_it_is_read(tmp_path, capsys, monkeypatch,
                                                                 suffix):
    from scipy.io import savemat

    import raysim.resources

    keys = dict(data=np.zeros((64, 8, 256), complex), chirp_times=np.arange(64) * 1e-4,
                element_positions=np.zeros((8, 3)), carrier_frequency=77e9, bandwidth=1e9,
                chirp_duration=5e-5, sample_rate=5e6)
    path = tmp_path / f"c{suffix}"
    (np.savez if suffix == ".npz" else savemat)(path, keys)
    # 2 MiB of samples (complex128): refused where 3 MiB are free
    monkeypatch.setattr(raysim.resources, "available_memory", lambda: 3 * 2**20)
    assert main(["compensate", str(path), "--chain", "none", "--out",
                 str(tmp_path / "o.npz")]) == 2
    err = capsys.readouterr().err
    assert f"cube file '{path}'" in err and "of memory" in err and "--frames" in err
