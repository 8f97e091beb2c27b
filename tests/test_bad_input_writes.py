"""Atomic writes and interrupted runs: nothing half-written may stay on disk.

Part of the bad-input catalogue (tests/test_bad_input*.py): every writer of
raysim either leaves the complete new file or the previous one, never a
partial file or a temporary behind.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest
from bad_input_common import Bad, CliError
from bad_input_common import imu_samples as _imu_samples

from raysim.io.files import MANIFEST


def _listing(folder: Path) -> list[str]:
    """Names in ``folder`` without raysim's manifest of its outputs."""
    return sorted(n for n in os.listdir(folder) if n != MANIFEST)


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
    from raysim.io.files import atomic_write_text
    from raysim.studies.stability import atomic_write

    target = tmp_path / "map.json"
    atomic_write_text(target, "old")

    def half(p: Path) -> None:
        p.write_text("new, but half")
        raise OSError("disk full")

    with pytest.raises(OSError):
        atomic_write(target, half)
    assert target.read_text() == "old"
    assert _listing(tmp_path) == ["map.json"]


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
    assert _listing(tmp_path) == ["lever_arm.json", "lever_arm.nc", "lever_arm.png", "points"]
    assert not [p for p in tmp_path.rglob("*")                             # no partial files
                if p.name.startswith(".") and p.name != MANIFEST]
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
    assert _listing(tmp_path) == [target.name]
    write(3)
    assert len(target.read_bytes()) > len(old)
    assert _listing(tmp_path) == [target.name]


# ------------------------------------------- the user's own files: never overwritten
ROOT = Path(__file__).resolve().parents[1]
CASE_TOML = ROOT / "examples" / "case_rotation_y.toml"
#: A small scenario for renders in these tests (8 chirps, 2 x 2 array).
TINY = ("--set", "radar.num_chirps=8", "--set", "array.nx=2", "--set", "array.ny=2",
        "--set", "radar.chirp_duration_s=12.8e-6")


def _kept(tmp: Path, files: dict, argv) -> None:
    """Create the user's ``files`` (name -> bytes) in ``tmp``, run ``raysim argv``, and check
    (whatever the outcome) that every file is still byte for byte the user's."""
    from bad_input_common import cli

    for name, data in files.items():
        (tmp / name).parent.mkdir(parents=True, exist_ok=True)
        (tmp / name).write_bytes(data)
    try:
        cli([a if not isinstance(a, str) or not a.startswith("@") else tmp / a[1:]
             for a in argv])
    finally:
        for name, data in files.items():
            assert (tmp / name).read_bytes() == data, f"{name} was changed"


SCENARIO_BYTES = CASE_TOML.read_bytes()
GUARD_CASES = [
    Bad("guard-report-out-is-its-input",
        lambda t: _kept(t, {"run.nc": b"CDF\x01 the user's export"},
                        ["report", "@run.nc", "--out", "@run.nc"]),
        CliError, ("exit 2", "--out", "run.nc", "one of the command's inputs")),
    Bad("guard-render-netcdf-is-the-scenario",
        lambda t: _kept(t, {"s.toml": SCENARIO_BYTES},
                        ["render", "@s.toml", "--out", "@s.zarr", "--netcdf", "@s.toml"]),
        CliError, ("exit 2", "--netcdf", "s.toml", "one of the command's inputs")),
    Bad("guard-rcs-plot-is-the-mesh",
        lambda t: _kept(t, {"car.obj": b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"},
                        ["rcs", "@car.obj", "--az-deg", "0", "--el-deg", "0",
                         "--plot", "@car.obj"]),
        CliError, ("exit 2", "--plot", "car.obj", "one of the command's inputs")),
    Bad("guard-flight-users-capture",
        lambda t: _kept(t, {"d/adc_data.bin": b"\x01\x02 a real capture",
                            "d/radar.cfg": b"sensorStop\n"}, ["flight", "@d"]),
        CliError, ("exit 2", "adc_data.bin", "raysim did not write", "choose another output")),
    Bad("guard-scene-report-users-index",
        lambda t: _kept(t, {"site/index.html": b"<html>my site</html>",
                            "site/report.md": b"# my notes\n"},
                        ["scene-report", "--quick", "--out", "@site"]),
        CliError, ("exit 2", "--out", "index.html", "raysim did not write")),
    Bad("guard-sweep-users-sweep-nc",
        lambda t: _kept(t, {"sw/sweep.nc": b"CDF\x01 someone else's sweep"},
                        ["sweep", "--case", "rotation_y", "--param", "radar.num_chirps=64",
                         "--out", "@sw"]),
        CliError, ("exit 2", "--out", "sweep.nc", "raysim did not write")),
    Bad("guard-compensate-out-is-the-cube",
        lambda t: _kept(t, {"c.npz": b"PK\x03\x04 the user's cube"},
                        ["compensate", "@c.npz", "--chain", "none", "--out", "@c.npz"]),
        CliError, ("exit 2", "--out", "c.npz", "one of the command's inputs")),
    Bad("guard-compensate-users-npz",
        lambda t: _kept(t, {"b.npz": b"PK\x03\x04 the user's beams"},
                        ["compensate", "@none.npz", "--chain", "none", "--out", "@b.npz"]),
        CliError, ("exit 2", "--out", "b.npz", "raysim did not write")),
    Bad("guard-bench-users-json",
        lambda t: _kept(t, {"bench.json": b'{"mine": 1}\n'},
                        ["bench", "--quick", "--out", "@bench.json"]),
        CliError, ("exit 2", "--out", "bench.json", "raysim did not write")),
    Bad("guard-stability-users-summary",
        lambda t: _kept(t, {"st/summary.json": b'{"mine": 1}\n'},
                        ["stability", "--quick", "--maps", "clock", "--out", "@st"]),
        CliError, ("exit 2", "--out", "summary.json", "raysim did not write")),
    Bad("guard-reproduce-users-csv",
        lambda t: _kept(t, {"r/reproduction.csv": b"a,b\n1,2\n"},
                        ["reproduce", "--quick", "--out", "@r"]),
        CliError, ("exit 2", "--out", "reproduction.csv", "raysim did not write")),
    Bad("guard-report-users-html",
        lambda t: _kept(t, {"r.html": b"<html>mine</html>"},
                        ["report", "--case", "rotation_y", "--out", "@r.html"]),
        CliError, ("exit 2", "--out", "r.html", "raysim did not write")),
    Bad("guard-render-users-netcdf",
        lambda t: _kept(t, {"x.nc": b"CDF\x01 mine"},
                        ["render", CASE_TOML, "--out", "@s.zarr", "--netcdf", "@x.nc"]),
        CliError, ("exit 2", "--netcdf", "x.nc", "raysim did not write")),
    Bad("guard-rcs-users-png",
        lambda t: _kept(t, {"p.png": b"\x89PNG mine"},
                        ["rcs", "plate:0.1", "--az-deg", "0", "--el-deg", "0",
                         "--plot", "@p.png"]),
        CliError, ("exit 2", "--plot", "p.png", "raysim did not write")),
    Bad("guard-report-into-its-store",
        lambda t: _kept(t, {"s.zarr/zarr.json": b'{"zarr_format": 3, "node_type": "group"}'},
                        ["report", "@s.zarr", "--out", "@s.zarr/r.html"]),
        CliError, ("exit 2", "--out", "s.zarr", "one of the command's inputs")),
    Bad("guard-writer-symlink",
        lambda t: (t.joinpath("real.txt").write_text("mine"),
                   t.joinpath("link.json").symlink_to(t / "real.txt"),
                   __import__("raysim.io.files", fromlist=["x"]).atomic_write_json(
                       t / "link.json", {})),
        ValueError, ("link.json", "symbolic link")),
    Bad("guard-writer-edited-output",
        lambda t: (__import__("raysim.io.files", fromlist=["x"]).atomic_write_text(
                   t / "o.txt", "raysim's"), t.joinpath("o.txt").write_text("edited by hand"),
                   __import__("raysim.io.files", fromlist=["x"]).atomic_write_text(
                   t / "o.txt", "again")),
        ValueError, ("o.txt", "raysim did not write", "or that changed since")),
]


@pytest.mark.parametrize("case", GUARD_CASES, ids=[c.id for c in GUARD_CASES])
def test_users_files_are_never_overwritten(case: Bad, tmp_path, capsys):
    """Each data-loss path: exit 2 with a message naming the file, the file byte-identical
    (checked by :func:`_kept`), nothing computed or shown on stdout."""
    with pytest.raises(case.exc) as info:
        case.call(tmp_path)
    msg = str(info.value)
    for needle in case.needles:
        assert needle in msg, f"message {msg!r} does not name {needle!r}"
    assert "Traceback" not in msg
    assert capsys.readouterr().out == ""


def test_overwrite_replaces_only_raysims_own_outputs(tmp_path, capsys):
    """A second ``render --netcdf`` replaces raysim's own export; a user's file stays."""
    from bad_input_common import CliError, cli

    args = ["render", CASE_TOML, *TINY, "--out", tmp_path / "s.zarr", "--no-progress"]
    cli(args + ["--netcdf", tmp_path / "run.nc"])
    first = (tmp_path / "run.nc").stat().st_ino
    cli(args + ["--overwrite", "--netcdf", tmp_path / "run.nc"])     # raysim's: replaced
    assert (tmp_path / "run.nc").stat().st_ino != first
    (tmp_path / "mine.nc").write_bytes(b"mine")
    with pytest.raises(CliError, match="mine.nc"):
        cli(args + ["--overwrite", "--netcdf", tmp_path / "mine.nc"])
    assert (tmp_path / "mine.nc").read_bytes() == b"mine"
    # report of raysim's own export, written beside it, then refused over it
    cli(["report", tmp_path / "run.nc", "--chains", "none", "--out", tmp_path / "r.html"])
    with pytest.raises(CliError, match="one of the command's inputs"):
        cli(["report", tmp_path / "run.nc", "--out", tmp_path / "run.nc"])
    capsys.readouterr()


# -------------------------------------- compensate and sweep: writers like render
def _tiny_cube(path: Path) -> Path:
    from bad_input_common import ARR, SMALL

    from raysim.echoes.oracle import PointTarget, simulate_point_targets

    fr = simulate_point_targets(SMALL, ARR, [PointTarget.at(10.0, -0.2, -0.1)])
    np.savez(path, data=fr.data, chirp_times=fr.chirp_times,
             element_positions=ARR.virtual_positions, carrier_frequency=SMALL.carrier_frequency,
             bandwidth=SMALL.bandwidth, chirp_duration=SMALL.chirp_duration,
             sample_rate=SMALL.sample_rate)
    return path


#: Runs ``raysim`` and stops it inside the store writer (temporary folder written) until
#: killed; writes ``argv[1]`` once it got there.
_STALLED_WRITER = """
import sys, time
import raysim.io.zarr_store as zs
real = zs.consolidate
def stalled(path):
    real(path)
    open(sys.argv[1], "w").write("in the writer")
    time.sleep(300)
zs.consolidate = stalled
from raysim.cli import main
sys.exit(main(sys.argv[2:]))
"""


def _stalled_compensate(tmp_path: Path):
    import subprocess
    import sys
    import time

    cube = _tiny_cube(tmp_path / "c.npz")
    ready = tmp_path / "ready"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    proc = subprocess.Popen([sys.executable, "-c", _STALLED_WRITER, str(ready), "compensate",
                             str(cube), "--chain", "none", "--range-m", "5:15", "--az-deg",
                             "-10:10:5", "--el-deg", "0:0:1", "--out",
                             str(tmp_path / "o.zarr")], env=env, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 240
    while not ready.exists():
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            raise AssertionError(f"compensate did not reach its writer: "
                                 f"{proc.stderr.read().decode()}")
        time.sleep(0.1)
    return proc


def _debris(tmp_path: Path) -> list[str]:
    return sorted(p.name for p in tmp_path.glob(".o.zarr.*.tmp"))


def test_killed_compensate_leftovers_are_removed_by_the_next_run(tmp_path, capsys):
    """SIGKILL mid-write leaves the hidden temporary store; the next run removes it."""
    import signal

    proc = _stalled_compensate(tmp_path)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=60)
    proc.stderr.close()
    assert _debris(tmp_path), "the killed writer left no temporary store to clean"
    assert not (tmp_path / "o.zarr").exists()
    from raysim.cli import main

    assert main(["compensate", str(tmp_path / "c.npz"), "--chain", "none", "--range-m", "5:15",
                 "--az-deg", "-10:10:5", "--el-deg", "0:0:1", "--out",
                 str(tmp_path / "o.zarr")]) == 0
    assert _debris(tmp_path) == []
    assert (tmp_path / "o.zarr" / "zarr.json").is_file()
    assert not (tmp_path / ".o.zarr.lock").exists()
    assert "removed 1 leftover" in capsys.readouterr().err


def test_sigterm_is_handled_like_ctrl_c(tmp_path):
    """SIGTERM mid-write: exit 130, the temporary store removed, no output, no lock file."""
    import signal

    proc = _stalled_compensate(tmp_path)
    proc.send_signal(signal.SIGTERM)
    assert proc.wait(timeout=60) == 130
    err = proc.stderr.read().decode()
    proc.stderr.close()
    assert "interrupted" in err
    assert _debris(tmp_path) == [] and not (tmp_path / "o.zarr").exists()
    assert not (tmp_path / ".o.zarr.lock").exists()


@pytest.mark.parametrize("which", ["compensate", "sweep"])
def test_one_writer_per_output(tmp_path, which):
    """A second writer of the same compensate or sweep output is refused, naming it."""
    from raysim.io.store_guard import writer_lock

    out = tmp_path / ("o.zarr" if which == "compensate" else "sw")
    with writer_lock(out), pytest.raises(ValueError, match="being written by another"):
        if which == "compensate":
            from raysim.pipeline.compensate import compensate

            compensate(_tiny_cube(tmp_path / "c.npz"), chain="none", out=out,
                       range_m=(5, 15), azimuth_deg=[0.0], elevation_deg=[0.0])
        else:
            from raysim.pipeline.sweep import SweepSpec, run_sweep
            from raysim.scenario import scenario_from_case

            spec = SweepSpec(scenario_from_case("stationary"), {"radar.num_chirps": [32]},
                             (0,), ("none",))
            run_sweep(spec, out, limit=0)


def test_sweep_removes_a_killed_writers_temporaries(tmp_path):
    from raysim.pipeline.sweep import SweepSpec, run_sweep
    from raysim.scenario import scenario_from_case

    spec = SweepSpec(scenario_from_case("stationary"), {"radar.num_chirps": [32]}, (0,),
                     ("none",))
    run_sweep(spec, tmp_path / "sw", limit=0)
    left = [tmp_path / "sw" / ".sweep.nc.k3j2h1g0.tmp",
            tmp_path / "sw" / "points" / ".0123abcd.json.zz9y8x7w.tmp"]
    for p in left:
        p.write_text("half")
    res = run_sweep(spec, tmp_path / "sw", limit=0)
    assert sorted(res.removed) == sorted(str(p) for p in left)
    assert not any(p.exists() for p in left)


def test_resume_after_a_full_disk_sizes_only_the_missing_frames(tmp_path, monkeypatch):
    """A render stopped by a full disk resumes when the disk holds the frames still missing."""
    import shutil

    from raysim.pipeline.run import render
    from raysim.resources import cube_bytes
    from raysim.scenario import scenario_from_case

    s = scenario_from_case("rotation_y").with_values(
        {"radar.num_chirps": 8, "array.nx": 2, "array.ny": 2, "radar.chirp_duration_s": 12.8e-6,
         "frames": 3})
    store = tmp_path / "s.zarr"
    render(s, store, max_frames=2)
    cfg = s.radar_config()
    frame = cube_bytes(cfg.num_chirps, s.virtual_array().num_channels, cfg.num_samples)
    real = shutil.disk_usage
    monkeypatch.setattr(shutil, "disk_usage",
                        lambda p: real(p)._replace(free=int(1.5 * frame)))
    with pytest.raises(ValueError, match="3 missing frame"):
        render(s, tmp_path / "new.zarr")                 # a new store needs all three
    assert render(s, store).frames_rendered == 1          # the resumed one only the last


def test_flight_rerun_replaces_its_own_files(tmp_path, capsys):
    """``raysim flight DIR`` twice: the second run replaces what the first wrote."""
    from raysim.cli import main

    assert main(["flight", str(tmp_path / "d"), "--frames", "1"]) == 0
    first = {n: (tmp_path / "d" / n).stat().st_ino for n in ("adc_data.bin", "radar.cfg")}
    assert main(["flight", str(tmp_path / "d"), "--frames", "1", "--seed", "1"]) == 0
    assert all((tmp_path / "d" / n).stat().st_ino != i for n, i in first.items())
    capsys.readouterr()


def test_compensate_npz_leftover_is_removed(tmp_path, capsys):
    """The hidden temporary of a killed ``.npz`` write is removed by the next writer."""
    from raysim.cli import main

    left = tmp_path / ".b.npz.ab12cd34.tmp"
    left.write_bytes(b"half an npz")
    other = tmp_path / ".other.npz.ab12cd34.tmp"          # another output's: kept
    other.write_bytes(b"x")
    assert main(["compensate", str(_tiny_cube(tmp_path / "c.npz")), "--chain", "none",
                 "--az-deg", "0:0:1", "--el-deg", "0:0:1", "--out",
                 str(tmp_path / "b.npz")]) == 0
    assert not left.exists() and other.exists()
    assert "removed 1 leftover" in capsys.readouterr().err
