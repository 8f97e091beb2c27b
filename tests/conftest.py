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
