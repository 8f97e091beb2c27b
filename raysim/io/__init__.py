"""Recorded-data import and export.

* :mod:`raysim.io.ti_dca1000`: TI mmWave DCA1000 raw ADC captures
  (``read_dca1000``, ``write_dca1000``) as ``[frame, chirp, channel, sample]``
  cubes with ramp time stamps.
* :mod:`raysim.io.imu_log`: IMU logs as CSV with units in the header
  (``read_imu_csv``, ``write_imu_csv``).
* :mod:`raysim.io.flight_logs`: flight-controller IMU logs, one reader
  ``read_imu_log`` for CSV, PX4 ULog, ArduPilot DataFlash and ROS 2 bags.
"""

from raysim.io.flight_logs import read_imu_log
from raysim.io.imu_log import read_imu_csv, write_imu_csv
from raysim.io.ti_dca1000 import (
    Dca1000Capture,
    Dca1000Format,
    parse_dca1000,
    read_dca1000,
    write_dca1000,
)

__all__ = ["Dca1000Capture", "Dca1000Format", "parse_dca1000", "read_dca1000",
           "write_dca1000", "read_imu_csv", "read_imu_log", "write_imu_csv"]
