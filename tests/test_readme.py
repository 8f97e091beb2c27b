"""The README is documentation a newcomer runs: every Python block runs, every command line parses.

Python blocks of ``README.md`` and ``docs/user_guide.md`` run in a fresh
interpreter in a temporary folder (so they define every name they use and
write nothing into the checkout). The folder holds ``examples/`` and, for a
user-guide block that reads what an earlier step of the guide wrote (a
rendered store, a flight log), a small one of those files. Every
``raysim ...`` line of a ``bash`` block of ``README.md`` and of every
``docs/*.md`` (continuation lines joined, comments dropped) is parsed
by the command line's own parser without running the job, and each
subcommand used shows its ``--help``.
"""

from __future__ import annotations

import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from raysim.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def code_blocks(path: Path, language: str) -> list[str]:
    """The fenced code blocks of ``path`` in ``language``, in order."""
    return re.findall(rf"^```{language}\n(.*?)^```", path.read_text(encoding="utf-8"),
                      re.S | re.M)


def command_lines(path: Path) -> list[str]:
    """Every ``raysim`` command of the bash blocks of ``path``, continuations joined."""
    lines = []
    for block in code_blocks(path, "bash"):
        for line in block.replace("\\\n", " ").splitlines():
            line = line.strip()
            if line.startswith("raysim ") or line == "raysim":
                lines.append(line)
            elif "&& raysim " in line:
                lines.append("raysim " + line.split("&& raysim ", 1)[1])
    return lines


def _argv(line: str) -> list[str]:
    return shlex.split(line, comments=True)[1:]


README_PY = code_blocks(ROOT / "README.md", "python")
GUIDE_PY = code_blocks(ROOT / "docs" / "user_guide.md", "python")
LINES = [(p.name, line) for p in DOCS for line in command_lines(p)]


def test_the_docs_have_what_this_test_checks():
    assert README_PY, "README.md lost its Python block"
    assert len(GUIDE_PY) >= 4, "docs/user_guide.md lost Python blocks"
    assert len(LINES) >= 30, LINES


@pytest.mark.parametrize("block", README_PY, ids=[f"block{i}" for i in range(len(README_PY))])
def test_readme_python_block_runs(block, tmp_path):
    res = subprocess.run([sys.executable, "-c", block], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300, env=_env())
    assert res.returncode == 0, f"README block failed:\n{block}\n{res.stderr[-3000:]}"


def prepare(block: str, folder: Path) -> None:
    """Put into ``folder`` what ``block`` reads: ``examples/``, and small stores and logs."""
    (folder / "examples").symlink_to(ROOT / "examples", target_is_directory=True)
    if "rotation_y.zarr" in block or "rotation_y.nc" in block:
        from raysim.pipeline.run import render
        from raysim.scenario import scenario_from_case

        small = scenario_from_case("rotation_y").with_values(
            {"radar.num_chirps": 32, "array.nx": 4, "array.ny": 4})
        render(small, folder / "rotation_y.zarr", export_netcdf=folder / "rotation_y.nc")
    if "flight.ulg" in block or "rosbag2_" in block:
        from raysim.io.flight_logs.rosbag import write_ros2_imu
        from raysim.io.flight_logs.ulog import write_px4_ulog
        from raysim.pipeline.sensors import imu_record
        from raysim.scenario import scenario_from_case

        s = scenario_from_case("rotation_y")
        imu = imu_record(s.trajectory(), "ideal", rate=500.0, times=[0.5, 0.6], start=0.0)
        write_px4_ulog(folder / "flight.ulg", imu)
        bags = re.findall(r'read_imu_log\("(rosbag2_[^"]+)", topic="([^"]+)"', block)
        for bag, topic in bags:
            write_ros2_imu(folder / bag, imu, topic=topic)


@pytest.mark.parametrize("block", GUIDE_PY, ids=[f"block{i}" for i in range(len(GUIDE_PY))])
def test_user_guide_python_block_runs(block, tmp_path):
    prepare(block, tmp_path)
    res = subprocess.run([sys.executable, "-c", block], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300, env=_env())
    assert res.returncode == 0, f"user guide block failed:\n{block}\n{res.stderr[-3000:]}"


def _env() -> dict:
    import os

    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    return env


@pytest.mark.parametrize("doc, line", LINES, ids=[f"{d}:{i}" for i, (d, _) in enumerate(LINES)])
def test_doc_command_line_parses(doc, line, capsys):
    argv = _argv(line)
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:       # argparse: 2 on a bad line, 0 after --help / --version
        assert exc.code == 0, f"{doc}: `{line}` does not parse:\n{capsys.readouterr().err}"
        return
    assert getattr(args, "func", None) is not None, f"{doc}: `{line}` names no subcommand"


def test_every_subcommand_used_has_help(capsys):
    used = sorted({_argv(line)[0] for _, line in LINES
                   if _argv(line) and not _argv(line)[0].startswith("-")})
    parser = build_parser()
    for cmd in used:
        with pytest.raises(SystemExit) as exc:
            parser.parse_args([cmd, "--help"])
        out = capsys.readouterr().out
        assert exc.value.code == 0 and f"raysim {cmd}" in out, (cmd, out[:300])
