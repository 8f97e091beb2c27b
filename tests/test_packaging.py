"""A plain install: the wheel ships the scenes (and their generator), the examples, the
conventions and the paper cases, and runs from a fresh virtual environment outside the
repository."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

import raysim.data
from raysim.echoes.rt import scenes
from raysim.scenario import paper_cases

ROOT = Path(__file__).resolve().parents[1]


def test_conventions_in_the_package_are_the_documentation_page():
    """docs/conventions.md links to the shipped raysim/data/conventions.md: one text."""
    page = ROOT / "docs" / "conventions.md"
    assert page.resolve() == (Path(raysim.data.__file__).parent / "conventions.md").resolve()
    assert raysim.data.conventions_text() == page.read_text(encoding="utf-8")
    assert "## Metrics" in raysim.data.conventions_text()


def test_package_data_is_found_from_the_package():
    assert scenes.SCENES_DIR.resolve() == (raysim.data.DATA_DIR / "scenes").resolve() or \
        "RAYSIM_SCENES_DIR" in os.environ
    for name in scenes.SCENES:
        assert scenes.get_scene(name).path.is_file(), name
    assert raysim.data.example_path("case_yaw.toml").is_file()
    assert (raysim.data.data_path("scenes") / "generate.py").is_file()
    with pytest.raises(ValueError, match="example 'nope.toml' does not exist; expected one of"):
        raysim.data.example_path("nope.toml")
    with pytest.raises(ValueError, match="package data 'nope' does not exist"):
        raysim.data.data_path("nope")
    # the repository's folders are the package's
    assert (ROOT / "scenes").resolve() == (raysim.data.DATA_DIR / "scenes").resolve()
    assert (ROOT / "examples").resolve() == (raysim.data.DATA_DIR / "examples").resolve()


def test_paper_cases_are_package_data():
    """Every paper case is a TOML file next to its loader, listed in ``_paper.toml``."""
    folder = paper_cases.CASES_DIR
    assert folder.resolve() == (Path(paper_cases.__file__).parent / "cases").resolve()
    files = sorted(p.stem for p in folder.glob("*.toml") if not p.stem.startswith("_"))
    assert files == sorted(paper_cases.PAPER_CASES)
    assert (folder / "_paper.toml").is_file()


def _expected_files() -> list[str]:
    data = raysim.data.DATA_DIR
    root = data.parent.parent
    shipped = [p for p in data.rglob("*") if p.is_file() and "__pycache__" not in p.parts]
    shipped += list(paper_cases.CASES_DIR.glob("*.toml"))
    return sorted(str(p.relative_to(root)) for p in shipped)


@pytest.mark.slow
def test_wheel_ships_the_data_and_runs_outside_the_repository(tmp_path):
    import importlib.util

    absent = [m for m in ("venv", "wheel", "pip") if importlib.util.find_spec(m) is None]
    if absent:
        pytest.skip(f"building and installing a wheel needs {absent} (not installed)")
    dist = tmp_path / "dist"
    build = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
         "-w", str(dist), str(ROOT)], capture_output=True, text=True, cwd=tmp_path)
    if build.returncode != 0 and "No module named pip" in build.stderr:
        pytest.skip("pip is not available to build the wheel")
    assert build.returncode == 0, build.stderr[-2000:]
    for leftover in ("build", "raysim.egg-info"):  # pip wheel builds in the tree
        if (ROOT / leftover).is_dir() and not _tracked(leftover):
            shutil.rmtree(ROOT / leftover, ignore_errors=True)
    (whl,) = dist.glob("raysim-*.whl")
    names = set(zipfile.ZipFile(whl).namelist())
    missing = [f for f in _expected_files() if f not in names]
    assert not missing, f"the wheel lacks {missing}"
    for must in ("raysim/data/conventions.md", "raysim/data/scenes/generate.py",
                 "raysim/data/examples/case_yaw.toml",
                 "raysim/data/scenes/flat_reflectors/flat_reflectors.xml",
                 "raysim/scenario/cases/_paper.toml", "raysim/scenario/cases/yaw.toml"):
        assert must in names

    env_dir = tmp_path / "venv"
    made = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages",
                           str(env_dir)], capture_output=True, text=True)
    if made.returncode != 0:
        pytest.skip(f"python -m venv is unavailable here: {made.stderr.strip()[-300:]}")
    py = env_dir / "bin" / "python"
    inst = subprocess.run([str(py), "-m", "pip", "install", "-q", "--no-deps", str(whl)],
                          capture_output=True, text=True)
    assert inst.returncode == 0, inst.stderr[-2000:]
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    # nothing of the repository on the path: only the installed wheel
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "RAYSIM_SCENES_DIR")}
    run = subprocess.run([str(env_dir / "bin" / "raysim"), "scenes", "list"],
                         capture_output=True, text=True, cwd=outside, timeout=300, env=env)
    assert run.returncode == 0, run.stderr[-2000:]
    for name in scenes.SCENES:
        assert name in run.stdout
    where = subprocess.run(
        [str(py), "-c", "import raysim, raysim.data as d; print(raysim.__file__); "
         "print(d.example_path('case_yaw.toml')); print(len(d.conventions_text())); "
         "from raysim.scenario import scenario_from_case, paper_cases as c; "
         "print(c.CASES_DIR); print(scenario_from_case('yaw').frames)"],
        capture_output=True, text=True, cwd=outside, env=env)
    assert where.returncode == 0, where.stderr
    module, example, size, cases, frames = where.stdout.split()
    assert str(env_dir) in module and str(env_dir) in example and int(size) > 1000
    assert str(env_dir) in cases and frames == "20"


def _tracked(path: str) -> bool:
    out = subprocess.run(["git", "ls-files", path], capture_output=True, text=True, cwd=ROOT)
    return bool(out.stdout.strip())
