"""Shared fixtures: small radars that keep the suite fast, and backend fixtures."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig


@pytest.fixture(scope="session")
def paper_radar() -> RadarConfig:
    """The paper's Table 2 radar (256 chirps, 600 samples)."""
    return RadarConfig()


@pytest.fixture(scope="session")
def paper_upa(paper_radar):
    """20 x 20 virtual UPA at half a wavelength."""
    return upa(20, 20, wavelength=paper_radar.wavelength)


@pytest.fixture(scope="session")
def small_upa(paper_radar):
    """8 x 8 virtual UPA at half a wavelength (Doppler tests that need no fine angle)."""
    return upa(8, 8, wavelength=paper_radar.wavelength)


@pytest.fixture
def rng():
    """Seeded generator for Monte-Carlo tests."""
    return np.random.default_rng(20261121)


#: Dr.Jit threads used by the tests (the CI machine has 2 cores).
RT_TEST_THREADS = 2


@pytest.fixture(scope="session")
def rt_backend():
    """Configure Sionna RT on the CPU (LLVM) variant; skip when it cannot run here."""
    from raysim.echoes.rt import backend

    try:
        return backend.configure("cpu", threads=RT_TEST_THREADS)
    except backend.BackendError as err:
        pytest.skip(f"Sionna RT LLVM backend unavailable: {err}")
