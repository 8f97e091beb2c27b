"""Shared pieces of the bad-input catalogue (tests/test_bad_input*.py).

:class:`Bad` is one catalogue entry; :func:`cli` runs the ``raysim`` command
in-process and turns a non-zero exit into :class:`CliError` carrying the exit
code and stderr; the rest are small builders used by several catalogue files.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

SMALL = RadarConfig(num_chirps=8, sample_rate=2.5e6)        # 150 samples, max range 22.5 m
ARR = upa(2, 2, wavelength=SMALL.wavelength)

@dataclass(frozen=True)
class Bad:
    """One bad input: ``call(tmp_path)`` must raise ``exc`` with every ``needle`` in the message."""

    id: str
    call: Callable[[Path], object]
    exc: type | tuple
    needles: tuple[str, ...]



def imu_samples(t, gyro=None, accel=None):
    from raysim.platform.imu import ImuSamples

    t = np.asarray(t, dtype=float)
    g = np.zeros((t.size, 3)) if gyro is None else gyro
    a = np.tile([0.0, 0.0, -9.80665], (t.size, 1)) if accel is None else accel
    return ImuSamples(t, g, a)


def scenario_data(**radar):
    from raysim.scenario import scenario_from_case

    data = scenario_from_case("rotation_y").model_dump(mode="json", exclude_none=True)
    data["radar"].update(radar)
    return data


def validate(data):
    from raysim.scenario import validate_scenario

    return validate_scenario(data)


class CliError(Exception):
    """A non-zero exit of the ``raysim`` command: ``"exit <code>: <stderr>"``."""


def cli(argv):
    """Run the CLI in-process; a non-zero exit raises CliError carrying the code and stderr."""
    import contextlib
    import io

    from raysim.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in argv])
        except SystemExit as exc:                       # argparse usage errors
            code = exc.code
    if code:
        raise CliError(f"exit {code}: {err.getvalue()}")
    return code
