"""Recorded-data import and export.

* :mod:`raysim.io.ti_dca1000`: TI mmWave DCA1000 raw ADC captures
  (``read_dca1000``, ``write_dca1000``) as ``[frame, chirp, channel, sample]``
  cubes with ramp time stamps.
* :mod:`raysim.io.imu_log`: IMU logs as CSV with units in the header
  (``read_imu_csv``, ``write_imu_csv``).
* :mod:`raysim.io.flight_logs`: flight-controller IMU logs, one reader
  ``read_imu_log`` for CSV, PX4 ULog, ArduPilot DataFlash and ROS 2 bags.
"""

from __future__ import annotations

import importlib

#: Public name -> submodule defining it; imported on first use (PEP 562), so that
#: ``import raysim.io.files`` (the command line's output checks) does not load the
#: readers and their SciPy dependencies.
_LAZY = {
    "read_imu_log": "flight_logs",
    "read_imu_csv": "imu_log", "write_imu_csv": "imu_log",
    "Dca1000Capture": "ti_dca1000", "Dca1000Format": "ti_dca1000",
    "parse_dca1000": "ti_dca1000", "read_dca1000": "ti_dca1000",
    "write_dca1000": "ti_dca1000",
}

__all__ = ["Dca1000Capture", "Dca1000Format", "parse_dca1000", "read_dca1000",
           "write_dca1000", "read_imu_csv", "read_imu_log", "write_imu_csv"]


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
