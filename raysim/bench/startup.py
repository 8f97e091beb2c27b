"""Start-up of the README job: its modules, the ray tracer's backend and Sionna RT.

    PYTHONPATH=$PWD python -m raysim.bench.startup [--runs 5]

Each run is a fresh child process that imports what ``raysim scene-report``
imports before it traces (the command line, the report's modules),
configures the CPU backend (``raysim.echoes.rt.backend.configure``, which
imports Sionna RT) and imports ``sionna.rt.rcs``. Two ways, interleaved run by
run: ``deferred`` (as the job starts: Sionna RT's Jupyter viewers are loaded on
first use, ``backend.DEFERRED_VIEWERS``) and the baseline ``eager`` (nothing
deferred, as before). Prints, per way, the median and range of the CPU seconds
of the child (``time.process_time``: all its threads) and of its wall seconds,
the modules loaded, the ratio of the medians and the load average before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

#: The two ways, the baseline last.
WAYS = ("deferred", "eager")

PROBE = """
import json, sys, time
c0, w0 = time.process_time(), time.perf_counter()
import raysim.cli, raysim.studies.scene_report, raysim.studies.scene_report.outputs
from raysim.echoes.rt import backend
if sys.argv[1] == "eager":
    backend.DEFERRED_VIEWERS = {}
backend.configure("cpu")
import sionna.rt.rcs
print(json.dumps({"cpu": time.process_time() - c0, "wall": time.perf_counter() - w0,
                  "modules": len(sys.modules)}))
"""


def measure(runs: int = 5) -> dict:
    """``runs`` child processes per way, interleaved.

    Returns
    -------
    dict
        Per way: ``cpu``, ``wall`` [s] and ``modules`` lists (one value per run);
        ``load``: the 1-minute load average before and after.
    """
    if int(runs) != runs or runs < 1:
        raise ValueError(f"runs must be a positive integer, got {runs!r}")
    root = Path(__file__).resolve().parents[2]
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(root), *filter(None, [os.environ.get("PYTHONPATH")])]))
    out: dict = {w: {"cpu": [], "wall": [], "modules": []} for w in WAYS}
    load0 = os.getloadavg()[0]
    for _ in range(int(runs)):
        for way in WAYS:
            run = subprocess.run([sys.executable, "-c", PROBE, way], capture_output=True,
                                 text=True, env=env, timeout=600, check=True)
            got = json.loads(run.stdout.strip().splitlines()[-1])
            for key in ("cpu", "wall", "modules"):
                out[way][key].append(got[key])
    out["load"] = (load0, os.getloadavg()[0])
    return out


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--runs", type=int, default=5)
    a = p.parse_args(argv)
    got = measure(a.runs)
    med = {w: statistics.median(got[w]["cpu"]) for w in WAYS}
    for w in WAYS:
        cpu, wall = got[w]["cpu"], got[w]["wall"]
        print(f"{w:9s} CPU {med[w]:.2f} s ({min(cpu):.2f}-{max(cpu):.2f}), wall "
              f"{statistics.median(wall):.2f} s ({min(wall):.2f}-{max(wall):.2f}), "
              f"{statistics.median(got[w]['modules']):.0f} modules")
    print(f"deferred / eager CPU: {med['deferred'] / med['eager']:.2f}; {a.runs} runs each, "
          f"interleaved; load {got['load'][0]:.1f} -> {got['load'][1]:.1f}")


if __name__ == "__main__":
    main()
