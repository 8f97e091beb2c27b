"""Atomic file output: complete files or none."""

import json

import pytest

from raysim.io.files import (
    MANIFEST,
    atomic_savefig,
    atomic_write,
    atomic_write_json,
    atomic_write_text,
    written_together,
)


def _names(folder):
    """Names in ``folder`` without raysim's manifest of its outputs."""
    return sorted(p.name for p in folder.iterdir() if p.name != MANIFEST)


def test_written_file_is_complete_and_no_temporary_is_left(tmp_path):
    path = atomic_write_json(tmp_path / "sub" / "a.json", {"x": 1})
    assert json.loads(path.read_text()) == {"x": 1}
    assert _names(path.parent) == ["a.json"]


def test_failure_midway_keeps_the_old_file(tmp_path):
    path = atomic_write_text(tmp_path / "a.txt", "old")

    def half(tmp):
        tmp.write_text("partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(path, half)
    assert path.read_text() == "old"
    assert _names(tmp_path) == ["a.txt"]


def test_figure_is_saved_in_the_suffix_format(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure()
    path = atomic_savefig(fig, tmp_path / "f.png", dpi=20)
    plt.close(fig)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_users_file_is_never_replaced(tmp_path):
    """A file raysim did not write (or one changed since) is refused by every writer."""
    mine = tmp_path / "notes.json"
    mine.write_text("mine")
    with pytest.raises(ValueError, match="raysim did not write") as info:
        atomic_write_json(mine, {"x": 1})
    assert str(mine) in str(info.value)
    assert mine.read_text() == "mine"
    ours = atomic_write_text(tmp_path / "ours.txt", "1")
    atomic_write_text(ours, "2")                               # raysim's own output: replaced
    assert ours.read_text() == "2"
    ours.write_text("edited by hand, longer")
    with pytest.raises(ValueError, match="raysim did not write"):
        atomic_write_text(ours, "3")
    assert ours.read_text() == "edited by hand, longer"


def test_output_that_is_an_input_is_refused(tmp_path):
    from raysim.io.files import check_output

    src = atomic_write_text(tmp_path / "run.nc", "x")          # even raysim's own file
    with pytest.raises(ValueError, match="one of the command's inputs") as info:
        check_output(src, "file", "--out", inputs=[("STORE", src)])
    assert "--out" in str(info.value) and str(src) in str(info.value)
    store = tmp_path / "s.zarr"
    store.mkdir()
    with pytest.raises(ValueError, match="inputs"):
        check_output(store / "r.html", "file", "--out", inputs=[store])


NAMES = ("capture.bin", "log.ulg", "truth.json")


def _write_set(folder, upto: int, stop: BaseException):
    with written_together(folder, NAMES):
        for name in NAMES[:upto]:
            atomic_write_text(folder / name, name)
        raise stop


@pytest.mark.parametrize("stop", [KeyboardInterrupt(), ValueError("disk full")])
def test_a_set_interrupted_midway_leaves_nothing_not_even_its_folder(tmp_path, stop):
    folder = tmp_path / "flight"
    with pytest.raises(type(stop)):
        _write_set(folder, 2, stop)
    assert not folder.exists()


def test_an_interrupted_rewrite_removes_the_stale_set_but_not_a_users_file(tmp_path):
    """A capture rewritten, then the job stopped: the old log and truth no longer match it,
    all of raysim's go; the user's notes stay. Stopped before writing, all stay."""
    folder = tmp_path / "flight"
    folder.mkdir()
    (folder / "notes.txt").write_text("mine")
    for name in NAMES:
        atomic_write_text(folder / name, "old " + name)
    with pytest.raises(KeyboardInterrupt):
        _write_set(folder, 0, KeyboardInterrupt())
    assert _names(folder) == sorted([*NAMES, "notes.txt"])
    with pytest.raises(KeyboardInterrupt):
        _write_set(folder, 1, KeyboardInterrupt())
    assert _names(folder) == ["notes.txt"]


def test_an_interrupted_command_says_one_line_and_the_dying_tasks_nothing(monkeypatch, capsys):
    """Ctrl-C in a command that runs Dask: the pending tasks' loggers and the threads that
    die with the process used to print a hundred lines after the one that says what
    happened."""
    import logging
    import sys
    import threading

    import raysim.cli.cmd_scenes as scenes

    monkeypatch.setattr(sys, "unraisablehook", sys.unraisablehook)
    monkeypatch.setattr(threading, "excepthook", threading.excepthook)

    def interrupted(args):
        raise KeyboardInterrupt

    monkeypatch.setattr(scenes, "run_list", interrupted)
    from raysim.cli import main

    try:
        assert main(["scenes", "list"]) == 130
        logging.getLogger("asyncio").error("Task was destroyed but it is pending!")
        threading.excepthook(None)
    finally:
        logging.disable(logging.NOTSET)
    err = capsys.readouterr().err
    assert err.strip() == "raysim scenes: interrupted; finished outputs were kept"
