"""Fixtures of the clutter tests: the Mitsuba backend for shadowing rays and scenes."""

from __future__ import annotations

import pytest

#: Dr.Jit threads used by the tests (the CI machine has 2 cores).
CLUTTER_TEST_THREADS = 2


@pytest.fixture(scope="session")
def clutter_backend():
    """Configure the ray-tracing backend on the CPU; skip when it cannot run here."""
    from raysim.echoes.rt import backend

    try:
        return backend.configure("cpu", threads=CLUTTER_TEST_THREADS)
    except backend.BackendError as err:
        pytest.skip(f"Sionna RT / Mitsuba LLVM backend unavailable: {err}")
