"""The HTML API reference builds from the docstrings without a warning (scripts/api_docs.sh)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

pytest.importorskip("pdoc", reason="pdoc (the 'docs' and 'test' extras) builds the reference")

ROOT = Path(__file__).resolve().parents[1]
#: Longest build allowed [s] (about 30 s wall on a loaded 2-core machine).
BUILD_TIMEOUT_S = 300
#: Pages of the main public modules that the reference must have.
MAIN_PAGES = (
    "index.html", "raysim.html", "compensation.html",
    "raysim/scenario.html", "raysim/radar/config.html", "raysim/radar/arrays.html",
    "raysim/pipeline.html", "raysim/pipeline/run.html", "raysim/pipeline/sources.html",
    "raysim/pipeline/estimate.html", "raysim/synthesis/frame.html",
    "raysim/processing/maps.html", "raysim/processing/metrics.html",
    "raysim/echoes/oracle.html", "raysim/echoes/rt.html", "raysim/io/zarr_store.html",
    "raysim/studies/scene_report.html", "raysim/cli.html",
    "compensation/projection.html", "compensation/exact.html", "compensation/paper.html",
    "compensation/strapdown.html", "compensation/stream.html",
)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """The reference built once into a temporary folder: (folder, finished process)."""
    out = tmp_path_factory.mktemp("api")
    env = dict(os.environ, PYTHONWARNINGS="")
    run = subprocess.run(["bash", str(ROOT / "scripts" / "api_docs.sh"), str(out)],
                         capture_output=True, text=True, cwd=ROOT, env=env,
                         timeout=BUILD_TIMEOUT_S)
    return out, run


def test_reference_builds_without_warnings(built):
    _, run = built
    # the script exits 1 and lists them when pdoc (or an import) warned
    assert run.returncode == 0, run.stderr
    # and nothing else reached stderr but its closing line
    others = [line for line in run.stderr.splitlines()
              if line.strip() and not line.startswith("api_docs: ")]
    assert others == [], run.stderr
    assert "warning" not in run.stderr.lower(), run.stderr


def test_reference_has_the_main_modules(built):
    out, run = built
    assert run.returncode == 0, run.stderr
    missing = [page for page in MAIN_PAGES if not (out / page).is_file()]
    assert missing == [], f"pages missing from the reference: {missing}"
    # the entry points are documented on the package page, private modules are not
    top = (out / "raysim.html").read_text()
    for name in ("render", "evaluate", "RadarConfig", "load_scenario"):
        assert f'id="{name}"' in top, name
    assert not list(out.rglob("_*.html")), sorted(out.rglob("_*.html"))

