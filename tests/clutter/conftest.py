"""Fixtures of the clutter tests: the Mitsuba backend for shadowing rays and scenes."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def clutter_backend(rt_backend):
    """The ray-tracing backend of the shared fixtures (Mitsuba shadowing rays and scenes)."""
    return rt_backend
