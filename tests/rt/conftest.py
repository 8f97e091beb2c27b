"""Fixtures of the ray-tracing tests: warm kernels, small radar (backend: tests/conftest.py)."""

from __future__ import annotations

import pytest

from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig


@pytest.fixture(scope="module")
def warm_kernels(rt_backend):
    """Trace a tiny scene once so that the Dr.Jit kernels are compiled and cached.

    The first Sionna call of a process compiles its kernels (about 0.7 s with an
    empty cache, 0.04 s with a warm one); warming up front keeps per-test
    timings meaningful.
    """
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    cfg = RadarConfig(num_chirps=4)
    scene = load_scene("flat_reflectors", frequency=cfg.carrier_frequency)
    MonostaticTracer(samples_per_src=1000, max_depth=1)(scene, cfg)
    return rt_backend


@pytest.fixture(scope="session")
def rt_radar() -> RadarConfig:
    """Paper waveform with few chirps (tests that need no Doppler resolution)."""
    return RadarConfig(num_chirps=8)


@pytest.fixture(scope="session")
def upa4(rt_radar):
    """4 x 4 virtual UPA at half a wavelength."""
    return upa(4, 4, wavelength=rt_radar.wavelength)
