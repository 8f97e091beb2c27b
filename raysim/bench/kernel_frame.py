"""Wall time of one full 1e5-path paper frame (256 x 400 x 600) by the fused kernel.

    PYTHONPATH=$PWD python -m raysim.bench.kernel_frame [--threads N] [--decimate auto|1]

Renders the whole frame with ``synthesize(..., method="kernel", eps=1e-5,
decimate=...)`` on the usable CPUs (default) and prints wall and CPU seconds,
the thread count and the load average before and after.
"""

import argparse
import os
import time

from raysim.bench.workloads import hover_paths, paper_setup
from raysim.synthesis.nufft import default_threads
from raysim.synthesis.select import synthesize


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--threads", type=int, default=default_threads())
    p.add_argument("--decimate", default="auto")
    p.add_argument("--paths", type=int, default=100_000)
    a = p.parse_args()
    dec = a.decimate if a.decimate == "auto" else int(a.decimate)
    cfg, arr, traj, lever = paper_setup()
    pd = hover_paths(a.paths, cfg, arr, traj, lever, seed=1)
    load0 = os.getloadavg()
    w0, c0 = time.perf_counter(), time.process_time()
    cube = synthesize(pd, None, cfg, method="kernel", eps=1e-5, threads=a.threads, decimate=dec)
    wall, cpu = time.perf_counter() - w0, time.process_time() - c0
    print(f"{a.paths} paths, frame {cube.shape}, threads {a.threads}, decimate {a.decimate}: "
          f"wall {wall:.1f} s, cpu {cpu:.1f} s; load {load0[0]:.1f} -> {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
