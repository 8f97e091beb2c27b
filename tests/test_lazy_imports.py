"""The command line starts without the heavy libraries: they load where a command uses them."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: Libraries that only the commands using them may import (plots, stores, ray tracing,
#: signal processing).
HEAVY = ("matplotlib", "sionna", "dask", "xarray", "mitsuba", "drjit", "zarr", "scipy.signal")

PROBE = f"""
import contextlib, io, json, sys
import raysim.cli
from raysim.cli import main
with contextlib.redirect_stdout(io.StringIO()):
    try:
        code = main(sys.argv[1:])
    except SystemExit as exc:
        code = exc.code
print(json.dumps({{"code": code, "modules": sorted(m for m in {HEAVY!r} if m in sys.modules)}}))
"""


@pytest.mark.parametrize("argv", [["--help"], ["scenes", "list"], ["bench", "--help"]])
def test_cli_start_does_not_import_heavy_libraries(argv):
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]))
    run = subprocess.run([sys.executable, "-c", PROBE, *argv], capture_output=True, text=True,
                         cwd=ROOT, env=env, timeout=120)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got["code"] in (0, None), got
    assert got["modules"] == [], f"raysim {' '.join(argv)} imported {got['modules']}"


def test_io_package_names_load_on_first_use():
    import raysim.io as io_pkg

    assert callable(io_pkg.read_dca1000) and callable(io_pkg.read_imu_log)
    assert set(io_pkg.__all__) <= set(dir(io_pkg))
    with pytest.raises(AttributeError, match="has no attribute 'no_such_reader'"):
        io_pkg.no_such_reader  # noqa: B018


def test_ray_tracer_defers_sionna_viewers_until_used():
    """``backend.configure`` imports Sionna RT (and its RCS module) without its Jupyter
    viewers (IPython, ipywidgets, pythreejs); the first use loads the real module."""
    pytest.importorskip("sionna.rt")
    probe = """
import json, sys
from raysim.echoes.rt import backend
backend.configure()
import sionna.rt, sionna.rt.rcs
before = sorted(m for m in ("IPython", "ipywidgets", "pythreejs") if m in sys.modules)
real = backend._real_viewer("sionna.rt.preview")
viewer = backend._real_viewer("sionna.rt.rcs.scattering_model_viewer")
st = sys.modules["sionna.rt.rcs.sensing_target"]
print(json.dumps({"before": before, "loaded": "IPython" in sys.modules,
                  "scene": sys.modules["sionna.rt.scene"].Previewer is real.Previewer,
                  "package": sionna.rt.Previewer is real.Previewer,
                  "rcs": sionna.rt.rcs.ScatteringModelViewer is viewer.ScatteringModelViewer
                         is st.ScatteringModelViewer}))
"""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]))
    run = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                         cwd=ROOT, env=env, timeout=300)
    assert run.returncode == 0, run.stderr
    got = json.loads(run.stdout.strip().splitlines()[-1])
    assert got == {"before": [], "loaded": True, "scene": True, "package": True, "rcs": True}


def test_startup_bench_loads_fewer_modules_deferred():
    """``raysim.bench.startup``: the job's start-up with Sionna RT's viewers deferred loads
    fewer modules than its eager baseline (none of IPython's stack)."""
    pytest.importorskip("sionna.rt")
    from raysim.bench.startup import WAYS, measure

    got = measure(1)
    assert set(WAYS) <= set(got)
    assert got["deferred"]["modules"][0] < got["eager"]["modules"][0]
    with pytest.raises(ValueError, match="runs"):
        measure(0)
