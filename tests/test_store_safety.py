"""Data safety of frame stores: foreign folders, concurrent readers, a second writer, debris."""

from __future__ import annotations

import hashlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr
import zarr

from raysim.cli import main as cli_main
from raysim.io import storage
from raysim.io.store_guard import lock_path, remove_debris, writer_lock
from raysim.pipeline.run import render
from raysim.scenario import scenario_from_case

ROOT = Path(__file__).resolve().parents[1]
SMALL = {"radar.num_chirps": 8, "array.nx": 2, "array.ny": 2,
         "radar.chirp_duration_s": 12.8e-6}


@pytest.fixture(scope="module")
def scenario():
    return scenario_from_case("stationary").with_values({**SMALL, "frames": 3})


def _snapshot(folder: Path) -> dict:
    """Every file below a folder with the hash of its bytes."""
    return {str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
            for p in sorted(folder.rglob("*")) if p.is_file()}


# ------------------------------------------------------------- foreign folders
def test_overwrite_refuses_a_folder_raysim_did_not_write(scenario, tmp_path):
    user = tmp_path / "thesis"
    user.mkdir()
    (user / "ch1.tex").write_text("\\chapter{One}")
    before = _snapshot(user)
    with pytest.raises(ValueError, match=r"thesis.*did not write.*refusing"):
        render(scenario, user, overwrite=True)
    with pytest.raises(ValueError, match="did not write"):
        render(scenario, user)
    assert _snapshot(user) == before


def test_cli_overwrite_of_the_working_folder_is_refused(tmp_path, monkeypatch, capsys):
    (tmp_path / "notes.txt").write_text("mine")
    scen = tmp_path / "s.toml"
    scen.write_text((ROOT / "examples" / "case_stationary.toml").read_text())
    monkeypatch.chdir(tmp_path)
    code = cli_main(["render", str(scen), "--out", ".", "--overwrite"])
    err = capsys.readouterr().err
    assert code == 2 and "did not write" in err
    assert (tmp_path / "notes.txt").read_text() == "mine"


def test_overwrite_replaces_a_raysim_store_and_a_file_is_refused(scenario, tmp_path):
    path = tmp_path / "s.zarr"
    render(scenario, path, max_frames=1)
    assert render(scenario.with_values({"seed": 3}), path, overwrite=True).frames_rendered == 3
    a_file = tmp_path / "data.bin"
    a_file.write_bytes(b"\x00" * 16)
    with pytest.raises(ValueError, match="is a file that raysim did not write"):
        render(scenario, a_file, overwrite=True)
    assert a_file.read_bytes() == b"\x00" * 16


def test_a_zarr_store_of_someone_else_is_not_replaced(scenario, tmp_path):
    import numpy as np

    other = tmp_path / "other.zarr"
    zarr.open_group(str(other), mode="w").create_array("x", data=np.arange(3))
    before = _snapshot(other)
    with pytest.raises(ValueError, match="raysim_format"):
        render(scenario, other, overwrite=True)
    assert _snapshot(other) == before


def test_a_raysim_store_holding_a_users_files_is_not_replaced(scenario, tmp_path):
    """Notes kept in a store, and the scenario a command reads from inside it, are not
    Zarr's: replacing the store would delete them with it."""
    from raysim.io.store_guard import foreign_files

    path = tmp_path / "s.zarr"
    render(scenario, path, max_frames=1)
    assert foreign_files(path) == []
    (path / "notes.txt").write_text("mine")
    scen = path / "scen.toml"
    scen.write_text((ROOT / "examples" / "case_stationary.toml").read_text())
    before = _snapshot(path)
    with pytest.raises(ValueError, match=r"also holds 'notes.txt' and 1 more.*did not\s+write"):
        render(scenario, path, overwrite=True)
    code = cli_main(["render", str(scen), "--out", str(path), "--overwrite", "--no-progress"])
    assert code == 2 and _snapshot(path) == before
    # a file among an array's chunks is not a chunk either
    arrays = [d for d in path.iterdir() if (d / "zarr.json").is_file() or (d / ".zarray").is_file()]
    (arrays[0] / "copy of chunk").write_text("x")
    assert path / arrays[0].name / "copy of chunk" in foreign_files(path)


# --------------------------------------------------------------- readers
def test_reader_of_a_store_being_appended_never_writes(scenario, tmp_path):
    """A half-appended frame (a writer between two variables) is left out, nothing written."""
    path = tmp_path / "r.zarr"
    render(scenario, path, max_frames=1)
    first = storage.open_store(path)
    fr = storage.frames_to_dataset(
        [__import__("raysim.pipeline.sources", fromlist=["x"]).render_frames(scenario)[1]])
    part = fr[["if_data"]].drop_vars([c for c in fr[["if_data"]].coords
                                      if "frame" not in fr[c].dims])
    part.attrs = dict(zarr.open_group(str(path), mode="r").attrs)
    part.to_zarr(str(path), append_dim="frame", consolidated=False, write_empty_chunks=True)
    before = _snapshot(path)
    ds = storage.open_store(path)
    assert ds.sizes["frame"] == 1 and ds["chirp_time"].shape[0] == 1
    xr.testing.assert_identical(ds, first)               # the complete frame, as before
    lazy = storage.open_store(path, load=False)
    assert lazy["if_data"].shape[0] == 1
    assert _snapshot(path) == before                      # the reader wrote nothing
    assert zarr.open_group(str(path))["if_data"].shape[0] == 2


def test_missing_integer_chunk_is_reported(scenario, tmp_path):
    path = tmp_path / "m.zarr"
    render(scenario, path, max_frames=1)
    chunk = next(p for p in (path / "tx_slot").rglob("*") if p.is_file()
                 and p.name != "zarr.json")
    chunk.unlink()
    with pytest.raises(ValueError, match=r"damaged.*'tx_slot'"):
        storage.open_store(path)


# ---------------------------------------------------------------- writers
_HOLDER = """
import sys, time
from raysim.io.store_guard import writer_lock
with writer_lock(sys.argv[1]):
    print("locked", flush=True)
    time.sleep(60)
"""


def test_second_writer_gets_a_clear_error(scenario, tmp_path):
    path = tmp_path / "w.zarr"
    render(scenario, path, max_frames=1)
    before = _snapshot(path)
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    holder = subprocess.Popen([sys.executable, "-c", _HOLDER, str(path)], env=env,
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "locked"
        with pytest.raises(ValueError, match=rf"w\.zarr.*another process \(pid {holder.pid}\)"):
            render(scenario, path)
        assert _snapshot(path) == before
    finally:
        holder.kill()
        holder.wait()
    assert render(scenario, path).frames_rendered == 2       # the lock died with its holder
    assert not lock_path(path).exists()


_KILLED_WRITER = """
import sys
from raysim.scenario import scenario_from_case
from raysim.pipeline.run import render
small = {"radar.num_chirps": 8, "array.nx": 2, "array.ny": 2, "radar.chirp_duration_s": 12.8e-6}
render(scenario_from_case("stationary").with_values({**small, "frames": 400}), sys.argv[1])
"""


def test_debris_of_a_killed_writer_is_removed_by_the_next_writer(tmp_path):
    path = tmp_path / "k.zarr"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    child = subprocess.Popen([sys.executable, "-c", _KILLED_WRITER, str(path)], env=env)
    deadline = time.monotonic() + 120
    while storage.frames_complete(path) < 2 and time.monotonic() < deadline:
        time.sleep(0.05)
    child.send_signal(signal.SIGKILL)
    child.wait()
    # what a writer killed inside write_store or a Zarr write leaves behind
    tmp = tmp_path / ".k.zarr.0123abcd.tmp"
    (tmp / "if_data").mkdir(parents=True)
    (tmp / "if_data" / "c").write_bytes(b"\x00" * 1024)
    partial = path / "if_data" / "leftover.partial"
    partial.write_bytes(b"\x00" * 64)
    mine = tmp_path / ".k.zarr.notes"                       # a user's file: not ours
    mine.write_text("keep")
    done = storage.frames_complete(path)
    scen = scenario_from_case("stationary").with_values({**SMALL, "frames": 400})
    summary = render(scen, path, max_frames=3)
    assert summary.frames_resumed == done and summary.frames_rendered == 3
    assert any("leftover" in n for n in summary.notes)
    assert not tmp.exists() and not partial.exists() and mine.read_text() == "keep"
    assert not lock_path(path).exists()
    assert storage.open_store(path).sizes["frame"] == done + 3


def test_remove_debris_touches_only_its_own_store(tmp_path):
    (tmp_path / ".a.zarr.11111111.tmp").mkdir()
    (tmp_path / ".b.zarr.22222222.tmp").mkdir()
    with writer_lock(tmp_path / "a.zarr"):
        removed = remove_debris(tmp_path / "a.zarr")
    assert [p.name for p in removed] == [".a.zarr.11111111.tmp"]
    assert (tmp_path / ".b.zarr.22222222.tmp").exists()


def test_report_of_a_store_with_a_corrupt_chunk_names_the_store(scenario, tmp_path, capsys):
    """The report reads frames lazily; a chunk that fails to decode is a clear error."""
    path = tmp_path / "c.zarr"
    render(scenario, path)
    chunk = next(p for p in sorted((path / "if_data").rglob("*"))
                 if p.is_file() and p.name != "zarr.json")
    chunk.write_bytes(chunk.read_bytes()[:7])
    assert cli_main(["report", str(path), "--out", str(tmp_path / "r.html")]) == 2
    err = capsys.readouterr().err
    assert "c.zarr" in err and "Traceback" not in err
    assert not (tmp_path / "r.html").exists()
