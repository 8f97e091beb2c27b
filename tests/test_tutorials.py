"""The tutorials of ``docs/tutorials/`` run as a newcomer runs them.

Each script runs in a fresh interpreter in its own temporary folder (they
write only there) and must finish with exit status 0 and print what its
docstring promises.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TUTORIALS = ROOT / "docs" / "tutorials"
SCRIPTS = sorted(TUTORIALS.glob("[0-9][0-9]_*.py"))


def run_tutorial(script: Path, folder: Path) -> str:
    """Run ``script`` in ``folder``; its stdout (the test fails on a non-zero exit)."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")]))
    res = subprocess.run([sys.executable, str(script)], cwd=folder, capture_output=True,
                         text=True, timeout=300, env=env)
    assert res.returncode == 0, f"{script.name} failed:\n{res.stderr[-3000:]}"
    return res.stdout


def test_tutorials_are_listed_and_linked():
    assert len(SCRIPTS) >= 2, SCRIPTS
    index = (TUTORIALS / "README.md").read_text(encoding="utf-8")
    for script in SCRIPTS:
        assert script.name in index, f"docs/tutorials/README.md does not list {script.name}"
    assert "docs/tutorials" in (ROOT / "README.md").read_text(encoding="utf-8")


def test_point_target_tutorial(tmp_path):
    out = run_tutorial(TUTORIALS / "01_point_target.py", tmp_path)
    assert "IF cube [chirp, channel, sample]: (64, 64, " in out
    rows = {m[0]: float(m[1]) for m in re.findall(r"^(none|paper|exact)\s+(\S+)", out, re.M)}
    assert set(rows) == {"none", "paper", "exact"}, out
    assert abs(rows["none"]) > 0.3 and abs(rows["exact"]) < 0.01, rows   # pseudo-velocity [m/s]
    assert list(tmp_path.iterdir()) == []                                 # writes nothing


def test_compensate_a_store_tutorial(tmp_path):
    out = run_tutorial(TUTORIALS / "02_compensate_a_store.py", tmp_path)
    coh = dict(re.findall(r"^(none|exact) .*coherence (\S+)$", out, re.M))
    assert float(coh["none"]) < 0.5 and float(coh["exact"]) > 0.99, out
    assert {"hover.zarr", "imu.csv", "beams_none.npz", "beams_exact.npz"} <= \
        {p.name for p in tmp_path.iterdir()}


@pytest.mark.parametrize("script", SCRIPTS, ids=[s.name for s in SCRIPTS])
def test_every_tutorial_has_a_test_and_a_docstring(script):
    text = script.read_text(encoding="utf-8")
    assert text.startswith('"""Tutorial '), script.name
    assert script.stem.split("_", 1)[1] in Path(__file__).read_text(encoding="utf-8")
