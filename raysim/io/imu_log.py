"""IMU logs as CSV: time stamps, angular rate and specific force with units in the header.

File format
-----------
Optional comment lines starting with ``#`` (free text, e.g. the source), then
one header row, then one row per sample. Column names carry their unit::

    # raysim IMU log: body frame FRD, accel = specific force
    time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2
    0.000,0.0012,-0.0003,0.0001,0.02,-0.01,-9.81
    ...

Recognised columns (order free, other columns ignored):

=================  ===========================================================
``time_<u>``       ``u`` in ``s``, ``ms``, ``us``, ``ns``
``gyro_<a>_<u>``   ``a`` in ``x, y, z``; ``u`` in ``rad_s``, ``deg_s``
``accel_<a>_<u>``  ``u`` in ``m_s2``, ``g``, ``mg`` (``g = 9.80665 m/s^2``)
=================  ===========================================================

A vector column without a unit (``gyro_x``, ``accel_x``; the layout
``raysim compensate`` documented before this format) is read in SI units,
rad/s and m/s^2.

Flight-log exports are read as they are (:data:`EXPORTS`): PX4's
``sensor_combined`` from pyulog's ``ulog2csv`` (``timestamp`` [us],
``gyro_rad[0..2]``, ``accelerometer_m_s2[0..2]``) and ArduPilot's ``IMU`` from
``mavlogdump.py --format csv`` or Mission Planner (``TimeUS``, ``GyrX..Z``,
``AccX..Z``; one instance ``I``), both FRD and SI.

Values are converted to SI on reading (s, rad/s, m/s^2). Time stamps must be
strictly increasing; every value must be a finite number. Errors name the row
(1-based data row and file line) and the column.
"""

from __future__ import annotations

import csv
import math
import os
import re
from pathlib import Path
from types import MappingProxyType

import numpy as np

from raysim.platform.imu import DEG, MILLI_G, STANDARD_GRAVITY, ImuSamples

__all__ = ["TIME_UNITS", "GYRO_UNITS", "ACCEL_UNITS", "read_imu_csv", "write_imu_csv"]

#: Time units accepted in the header and their value in seconds.
TIME_UNITS = MappingProxyType({"s": 1.0, "ms": 1e-3, "us": 1e-6, "ns": 1e-9})
#: Angular-rate units and their value in rad/s.
GYRO_UNITS = MappingProxyType({"rad_s": 1.0, "deg_s": DEG})
#: Specific-force units and their value in m/s^2.
ACCEL_UNITS = MappingProxyType({"m_s2": 1.0, "g": STANDARD_GRAVITY, "mg": MILLI_G})

_AXES = ("x", "y", "z")
_TIME_RE = re.compile(r"^time_(?P<unit>[a-z]+)$")
_VEC_RE = re.compile(r"^(?P<sensor>gyro|accel)_(?P<axis>[xyz])(?:_(?P<unit>[a-z0-9_]+))?$")
#: Unit of a vector column named without one (``gyro_x``): SI.
_SI_UNIT = {"gyro": "rad_s", "accel": "m_s2"}
#: CSV exports of flight logs read as they are: their columns -> this format's names. Both
#: log FRD body axes in SI units, time in microseconds since boot.
EXPORTS = MappingProxyType({
    "PX4 sensor_combined (pyulog ulog2csv)": MappingProxyType({
        "timestamp": "time_us",
        **{f"gyro_rad[{k}]": f"gyro_{a}_rad_s" for k, a in enumerate(_AXES)},
        **{f"accelerometer_m_s2[{k}]": f"accel_{a}_m_s2" for k, a in enumerate(_AXES)}}),
    **{f"ArduPilot IMU (mavlogdump --format csv, Mission Planner; {clock})": MappingProxyType({
        clock: f"time_{clock[4:].lower()}",
        **{f"Gyr{a.upper()}": f"gyro_{a}_rad_s" for a in _AXES},
        **{f"Acc{a.upper()}": f"accel_{a}_m_s2" for a in _AXES}})
       for clock in ("TimeUS", "TimeMS")},
})
#: The export whose rows are PX4 ``sensor_combined`` fields, read as the ULog reader does.
PX4_EXPORT = next(iter(EXPORTS))
#: Column of the IMU instance in an ArduPilot export (several IMUs interleave their rows).
INSTANCE_COLUMN = "I"


def _units_for(sensor: str) -> MappingProxyType:
    return GYRO_UNITS if sensor == "gyro" else ACCEL_UNITS


def _not_text(path, exc: UnicodeDecodeError) -> ValueError:
    return ValueError(f"{path}: not a text CSV (byte {exc.start} is not UTF-8): expected a "
                      f"CSV IMU log; a binary flight log keeps its own suffix (.ulg, .bin, "
                      f".bag, .mcap)")


def csv_header(path: str | os.PathLike) -> tuple[list[str], int]:
    """The header row of a CSV log (after ``#`` comment lines) and its 1-based line number."""
    try:
        with Path(path).open(newline="") as fh:
            for line_no, line in enumerate(fh, start=1):
                if line.strip() and not line.lstrip().startswith("#"):
                    return next(csv.reader([line])), line_no
    except UnicodeDecodeError as exc:
        raise _not_text(path, exc) from None
    raise ValueError(f"{path}: no header row found")


def export_layout(header: list[str]) -> str | None:
    """The flight-log export whose columns ``header`` holds (:data:`EXPORTS`), or None."""
    names = {h.strip() for h in header}
    return next((k for k, cols in EXPORTS.items() if set(cols) <= names), None)


def _parse_header(header: list[str], where: str) -> tuple[int, float, dict]:
    """Column index and SI factor of the time and of each (sensor, axis)."""
    time_col: tuple[int, float] | None = None
    vec: dict[tuple[str, str], tuple[int, float]] = {}
    alias = EXPORTS.get(export_layout(header), {})
    for i, raw in enumerate(header):
        name = alias.get(raw.strip(), raw.strip())
        m = _TIME_RE.match(name)
        if m:
            unit = m["unit"]
            if unit not in TIME_UNITS:
                raise ValueError(f"{where}column {name!r}: unknown time unit {unit!r}; "
                                 f"valid units are {list(TIME_UNITS)}")
            if time_col is not None:
                raise ValueError(f"{where}more than one time column ({header[time_col[0]]!r} "
                                 f"and {name!r})")
            time_col = (i, TIME_UNITS[unit])
            continue
        m = _VEC_RE.match(name)
        if m:
            sensor, axis = m["sensor"], m["axis"]
            unit = m["unit"] or _SI_UNIT[sensor]
            units = _units_for(sensor)
            if unit not in units:
                raise ValueError(f"{where}column {name!r}: unknown {sensor} unit {unit!r}; "
                                 f"valid units are {list(units)}")
            if (sensor, axis) in vec:
                raise ValueError(f"{where}more than one {sensor}_{axis} column "
                                 f"({header[vec[sensor, axis][0]]!r} and {name!r})")
            vec[sensor, axis] = (i, units[unit])
    missing = []
    if time_col is None:
        missing.append("time_<" + "|".join(TIME_UNITS) + ">")
    for sensor in ("gyro", "accel"):
        for axis in _AXES:
            if (sensor, axis) not in vec:
                missing.append(f"{sensor}_{axis}_<" + "|".join(_units_for(sensor)) + ">")
    if missing:
        raise ValueError(f"{where}missing column(s) {missing}; header is "
                         f"{[h.strip() for h in header]}")
    return time_col[0], time_col[1], vec


def read_imu_csv(path: str | os.PathLike) -> ImuSamples:
    """Read an IMU log CSV (module docstring) into SI units.

    Parameters
    ----------
    path : str or path-like
        CSV file.

    Returns
    -------
    ImuSamples
        ``time [sample]`` [s], ``gyro [sample, 3]`` [rad/s],
        ``accel [sample, 3]`` [m/s^2]; ``spec`` and ``truth`` are None.

    Raises
    ------
    ValueError
        Missing or duplicate columns, unknown units, short rows, values that
        are not finite numbers, time stamps that repeat or go backwards, or no
        data rows; the message names the row, file line and column.
    """
    path = Path(path)
    where = f"{path}: "
    try:
        with path.open(newline="") as fh:
            text_lines = fh.read().splitlines()
    except UnicodeDecodeError as exc:
        raise _not_text(path, exc) from None
    header = None
    rows: list[list[float]] = []
    lines_of_rows: list[int] = []
    instances: set[str] = set()
    inst_col = None
    for line_no, line in enumerate(text_lines, start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        fields = next(csv.reader([line]))
        if header is None:
            header = fields
            t_col, t_factor, vec = _parse_header(header, where)
            cols = [t_col] + [vec[s, a][0] for s in ("gyro", "accel") for a in _AXES]
            names = [header[c].strip() for c in cols]
            layout = export_layout(header)
            if layout == PX4_EXPORT:     # its samples are interval averages: the ULog's reader
                raise ValueError(f"{where}a PX4 sensor_combined export (pyulog ulog2csv): "
                                 f"read it with raysim.io.read_imu_log, which places each "
                                 f"sample at its averaging interval's middle as from the ULog")
            stripped = [h.strip() for h in header]
            if layout is not None and INSTANCE_COLUMN in stripped:
                inst_col = stripped.index(INSTANCE_COLUMN)
            continue
        row_no = len(rows) + 1
        if len(fields) != len(header):
            raise ValueError(f"{where}row {row_no} (line {line_no}) has {len(fields)} "
                             f"fields, the header has {len(header)}")
        values = []
        for c, name in zip(cols, names, strict=True):
            text = fields[c].strip()
            try:
                v = float(text)
            except ValueError:
                raise ValueError(f"{where}row {row_no} (line {line_no}), column {name!r}: "
                                 f"{text!r} is not a number") from None
            if not math.isfinite(v):
                raise ValueError(f"{where}row {row_no} (line {line_no}), column {name!r}: "
                                 f"value {text!r} is not finite")
            values.append(v)
        rows.append(values)
        lines_of_rows.append(line_no)
        if inst_col is not None:
            instances.add(fields[inst_col].strip())
    if header is None:
        raise ValueError(f"{where}no header row found")
    if not rows:
        raise ValueError(f"{where}no data rows after the header")
    if len(instances) > 1:
        raise ValueError(f"{where}rows of IMU instances {sorted(instances)} interleave "
                         f"(column {INSTANCE_COLUMN!r}); export one instance, e.g. "
                         f"mavlogdump.py --format csv --types IMU --condition 'IMU.I==0'")
    data = np.asarray(rows, dtype=float)
    time = data[:, 0] * t_factor
    factors = np.array([vec[s, a][1] for s in ("gyro", "accel") for a in _AXES])
    vals = data[:, 1:] * factors
    dt = np.diff(data[:, 0])
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        k = int(bad[0]) + 1  # 0-based index of the offending row
        what = "repeats" if dt[bad[0]] == 0 else "is earlier than"
        raise ValueError(f"{where}row {k + 1} (line {lines_of_rows[k]}), column {names[0]!r}: "
                         f"time stamp {float(data[k, 0])!r} {what} row {k} "
                         f"({float(data[k - 1, 0])!r}); time stamps must be strictly increasing")
    source = str(path) if layout is None else f"{path} ({layout}: FRD, SI, time since boot)"
    return ImuSamples(time, vals[:, :3], vals[:, 3:], spec=None, truth=None, source=source)


def write_imu_csv(path: str | os.PathLike, samples: ImuSamples, *, time_unit: str = "s",
                  gyro_unit: str = "rad_s", accel_unit: str = "m_s2",
                  comment: str | None = None) -> Path:
    """Write IMU samples as a CSV log (module docstring).

    Parameters
    ----------
    path : str or path-like
        Output file (replaced atomically: written to a temporary file in the
        same folder, then renamed, so an interrupted write leaves any previous
        file untouched and no partial file).
    samples : ImuSamples
        ``time [sample]`` [s], ``gyro [sample, 3]`` [rad/s], ``accel [sample, 3]`` [m/s^2].
    time_unit : {"s", "ms", "us", "ns"}
    gyro_unit : {"rad_s", "deg_s"}
    accel_unit : {"m_s2", "g", "mg"}
        Units written to the file (and named in the header).
    comment : str or None
        Text written as leading ``#`` lines; defaults to a note with the source.

    Returns
    -------
    pathlib.Path
        The written file. Values are written in their shortest round-trip
        decimal form, so a round trip in SI units is exact.
    """
    if not isinstance(samples, ImuSamples):
        raise ValueError(f"samples must be ImuSamples, got {type(samples).__name__}")
    for name, unit, table in (("time_unit", time_unit, TIME_UNITS),
                              ("gyro_unit", gyro_unit, GYRO_UNITS),
                              ("accel_unit", accel_unit, ACCEL_UNITS)):
        if unit not in table:
            raise ValueError(f"{name} must be one of {list(table)}, got {unit!r}")
    header = ([f"time_{time_unit}"] + [f"gyro_{a}_{gyro_unit}" for a in _AXES]
              + [f"accel_{a}_{accel_unit}" for a in _AXES])
    data = np.column_stack([samples.time / TIME_UNITS[time_unit],
                            samples.gyro / GYRO_UNITS[gyro_unit],
                            samples.accel / ACCEL_UNITS[accel_unit]])
    if comment is None:
        comment = (f"raysim IMU log; source: {samples.source or 'unknown'}; body frame FRD; "
                   f"accel is specific force")
    from raysim.io.files import atomic_write

    def write(tmp: Path) -> None:
        with tmp.open("w", newline="") as fh:
            for line in comment.splitlines():
                fh.write(f"# {line}\n")
            fh.write(",".join(header) + "\n")
            for row in data:
                fh.write(",".join(repr(float(v)) for v in row) + "\n")

    return atomic_write(path, write)
