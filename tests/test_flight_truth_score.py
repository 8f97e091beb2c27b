"""A flight's truth beside its files, and ``raysim score`` of a compensated store against it."""

from __future__ import annotations

import contextlib
import io
import json
import shutil

import numpy as np
import pytest

from raysim.cli import main
from raysim.pipeline.flight import write_flight
from raysim.pipeline.flight_truth import LIMITS, TRUTH_FILE, read_truth, score_flight

#: One target off boresight, two frames (seconds to write and compensate).
TARGET = (6.0, 12.0, 0.0)
#: Azimuth the truth's target is moved by in the wrong-truth check [deg]; a score must
#: see it as an angle error within :data:`MOVED_TOL_DEG`.
MOVE_DEG = 1.0
MOVED_TOL_DEG = 0.1


@pytest.fixture(scope="module")
def scored(tmp_path_factory):
    """(flight folder, store) of a written flight compensated with its given command."""
    root = tmp_path_factory.mktemp("score")
    flight = write_flight(root / "f", target=TARGET, frames=2, seed=1)
    store = root / "f" / "compensated.zarr"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(flight.command(store, "--range-m", "5.5:6.5", "--az-deg", "6:18:0.25",
                                   "--el-deg", "0:0:1", "--no-progress")) == 0
    return flight, root / "f", store


def test_the_truth_file_gives_back_the_flight(scored):
    flight, folder, _ = scored
    back = read_truth(folder)
    for name in flight.__dataclass_fields__:
        a, b = getattr(flight, name), getattr(back, name)
        if isinstance(a, np.ndarray):
            np.testing.assert_array_equal(a, b)          # JSON keeps every float digit
        else:
            assert a == b, name


def test_a_moved_folder_keeps_its_truth(scored, tmp_path):
    _, folder, _ = scored
    moved = tmp_path / "moved"
    shutil.copytree(folder, moved, ignore=shutil.ignore_patterns("*.zarr"))
    back = read_truth(moved)
    assert back.capture == moved / "adc_data.bin" and back.capture.is_file()


def test_score_holds_on_the_compensated_flight(scored, capsys):
    _, folder, store = scored
    assert main(["score", str(folder), str(store), "--json"]) == 0
    s = json.loads(capsys.readouterr().out)
    assert s["passed"]["all"] and s["limits"] == LIMITS
    assert np.asarray(s["targets"]).shape == (1, 2, 3)
    assert s["worst"]["offset_error_ms"] == pytest.approx(0.0, abs=1e-9)   # given offset


def test_score_sees_a_wrong_truth(scored, tmp_path, capsys):
    """The same store scored against a truth whose target is moved in azimuth: the angle
    error is the move and the exit status 1 (a score that cannot fail would pass it)."""
    _, folder, store = scored
    wrong = tmp_path / "wrong"
    shutil.copytree(folder, wrong, ignore=shutil.ignore_patterns("*.zarr"))
    data = json.loads((wrong / TRUTH_FILE).read_text())
    for t in (data["targets"][0], data["target"]):
        t[1] += MOVE_DEG
    (wrong / TRUTH_FILE).write_text(json.dumps(data))
    s = score_flight(wrong, store)
    assert s["worst"]["beam_angle_error_deg"] == pytest.approx(MOVE_DEG, abs=MOVED_TOL_DEG)
    assert not s["passed"]["beam_angle_error_deg"] and not s["passed"]["all"]
    assert main(["score", str(wrong), str(store)]) == 1
    assert "beam_angle_error_deg" in capsys.readouterr().out


def test_score_refuses_a_folder_without_truth(scored, tmp_path, capsys):
    _, _, store = scored
    assert main(["score", str(tmp_path), str(store)]) == 2
    assert TRUTH_FILE in capsys.readouterr().err
    (tmp_path / TRUTH_FILE).write_text(json.dumps({"format": "something-else"}))
    assert main(["score", str(tmp_path), str(store)]) == 2
    assert "something-else" in capsys.readouterr().err


@pytest.mark.parametrize("edit, named", [
    (lambda d: {"format": d["format"]}, "missing field(s) ['capture'"),
    (lambda d: {**d, "time_offset": None}, "'time_offset' is None, expected a finite number"),
    (lambda d: {**d, "targets": "abc"}, "'targets' is 'abc', expected finite numbers of "
                                         "shape [Nx3]"),
    (lambda d: {**d, "lever_arm": [1]}, "'lever_arm' is [1], expected finite numbers of "
                                        "shape [3]"),
    (lambda d: {**d, "attitude": 1}, "'attitude' is 1, expected true or false"),
    (lambda d: {**d, "wind": 3}, "unknown field(s) ['wind']")])
def test_an_edited_truth_is_refused_naming_its_field(scored, tmp_path, capsys, edit, named):
    _, folder, store = scored
    data = json.loads((folder / TRUTH_FILE).read_text())
    (tmp_path / TRUTH_FILE).write_text(json.dumps(edit(data)))
    assert main(["score", str(tmp_path), str(store)]) == 2
    assert named in capsys.readouterr().err


def test_flight_keeps_a_truth_file_it_did_not_write(tmp_path, capsys):
    (tmp_path / "f").mkdir()
    mine = tmp_path / "f" / TRUTH_FILE
    mine.write_text("my notes\n")
    assert main(["flight", str(tmp_path / "f"), "--frames", "1", "--no-progress"]) == 2
    assert "truth.json" in capsys.readouterr().err
    assert mine.read_text() == "my notes\n"


def test_score_of_a_later_frame_takes_it_from_the_store(scored, tmp_path):
    """A store of frame 1 alone (``--frames 1:2``) is scored against frame 1's position:
    the store's frame coordinate says so; a frame the flight lacks is refused."""
    flight, folder, _ = scored
    store = tmp_path / "k1.zarr"
    with contextlib.redirect_stdout(io.StringIO()):
        assert main(flight.command(store, "--range-m", "5.5:6.5", "--az-deg", "6:18:0.25",
                                   "--el-deg", "0:0:1", "--no-progress", frame=1)) == 0
    auto = score_flight(folder, store)
    assert auto == score_flight(folder, store, first=1) and auto["passed"]["all"]
    with pytest.raises(ValueError, match="first frame 5"):
        score_flight(folder, store, first=5)


def test_targets_two_range_cells_apart_are_measured_each_in_its_own(tmp_path):
    """Two targets 0.35 m apart in range (2.3 cells of 15 cm) and 6 deg apart in azimuth,
    the nearer stronger: each is measured on its own cells (1.5 range resolutions each
    side), not on the other's peak (with a fixed 0.45 m window the farther one was
    scored 6 deg off, at the nearer one's direction)."""
    from raysim.pipeline.flight import measure_targets

    flight = write_flight(tmp_path / "f", frames=1, imu="ideal", targets=[
        (5.0, 0.0, 0.0), (5.35, 6.0, 0.0)], progress=False)
    out = tmp_path / "c.zarr"
    assert main(flight.command(out, "--range-m", "4.5:6", "--az-deg", "-15:20:0.25",
                               "--el-deg", "0:0:1", "--no-progress")) == 0
    m = measure_targets(out, flight)                              # [target, frame, 3]
    assert np.all(m[..., 0] <= LIMITS["beam_angle_error_deg"]), m[..., 0]


def test_a_store_of_another_flight_is_refused_a_copied_folder_passes(scored, tmp_path, capsys):
    """A store compensated from another capture scored against this flight's truth would
    measure the wrong targets; a copy of the flight's folder is the same flight."""
    _, folder, store = scored
    other = tmp_path / "other"
    shutil.copytree(folder, other, ignore=shutil.ignore_patterns("*.zarr"))
    assert main(["score", str(other), str(store)]) == 0             # same bytes: scored
    capture = other / "adc_data.bin"
    data = bytearray(capture.read_bytes())
    data[-1] ^= 1                                                # another capture
    capture.write_bytes(bytes(data))
    capsys.readouterr()
    assert main(["score", str(other), str(store)]) == 2
    assert "compensated from the capture" in capsys.readouterr().err
