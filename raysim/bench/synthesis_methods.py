"""pytest-benchmark micro-benchmarks of IF synthesis (not part of the test suite).

Run: ``pytest raysim/bench/synthesis_methods.py --benchmark-only`` (a few minutes).
The whole-frame figures with extrapolation and memory are ``raysim bench``.
"""

import numpy as np
import pytest

from raysim.bench.workloads import hover_paths, paper_setup, subset
from raysim.synthesis.select import synthesize

CFG, ARR, TRAJ, LEVER = paper_setup()


@pytest.fixture(scope="module", params=[10, 1_000, 10_000, 100_000])
def paths(request):
    return hover_paths(request.param, CFG, ARR, TRAJ, LEVER, seed=request.param)


def test_nufft_one_chirp(benchmark, paths):
    """One paper chirp (400 channels x 600 samples), eps 1e-5, one thread."""
    benchmark(synthesize, paths, None, CFG, method="nufft", eps=1e-5, chirps=range(1), threads=1)


def test_tones_one_chirp_subset(benchmark, paths):
    """Tone sum on 1 chirp x 400 channels for at most 1,000 paths (linear in paths)."""
    sub = subset(paths.select(np.arange(paths.num_paths) < 1_000), 1, ARR.num_channels)
    benchmark(synthesize, sub, None, CFG, method="tones", eps=1e-5)


def test_direct_one_chirp_subset(benchmark, paths):
    """Direct complex128 sum on 1 chirp x 400 channels for at most 100 paths."""
    sub = subset(paths.select(np.arange(paths.num_paths) < 100), 1, ARR.num_channels)
    benchmark.pedantic(synthesize, args=(sub, None, CFG), kwargs={"method": "direct"},
                       rounds=1, iterations=1)
