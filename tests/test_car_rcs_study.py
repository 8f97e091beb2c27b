"""Aspect average and swing of the car RCS study (raysim.studies.car_rcs), in plain numpy."""

from __future__ import annotations

import numpy as np
import pytest


def test_aspect_average_reads_mirror_aspects_back():
    """+-2.5 deg on a 1 deg grid: five samples; beyond 0 and 180 deg the mirror images."""
    from raysim.studies.car_rcs import aspect_average

    az = np.arange(0.0, 181.0)
    rcs = np.zeros((len(az), 1))
    rcs[0, 0] = 5.0                       # a flash at the nose only
    rcs[180, 0] = 10.0                    # and at the tail
    avg = aspect_average(rcs, az)
    assert avg[0, 0] == pytest.approx(5.0 / 5)           # -2..2 deg: the nose once
    assert avg[2, 0] == pytest.approx(5.0 / 5)           # 0..4 deg
    assert avg[3, 0] == 0.0
    assert avg[180, 0] == pytest.approx(10.0 / 5)
    ref = np.random.default_rng(3).uniform(1.0, 2.0, (len(az), 2))
    out = aspect_average(ref, az)
    assert out[90] == pytest.approx(ref[88:93].mean(axis=0))
    assert out[1] == pytest.approx((ref[1] + ref[0] + ref[1] + ref[2] + ref[3]) / 5)


def test_swing_db():
    from raysim.studies.car_rcs import swing_db

    az = np.arange(0.0, 181.0, 2.0)
    rcs = np.ones((len(az), 1))
    rcs[10, 0] = 100.0                    # 20 dB above the rest
    assert swing_db(rcs, az)[0] == pytest.approx(20.0)
    assert swing_db(np.ones((len(az), 1)), az)[0] == 0.0


def test_unknown_model():
    from raysim.studies.car_rcs import car_model

    with pytest.raises(ValueError, match="car model"):
        car_model("truck")
    with pytest.raises(ValueError, match="facet"):
        car_model("simple", 0.1)


def test_cli_car_job_sized_and_checked(capsys):
    """``raysim rcs car:...``: unknown model, near range and a huge job refused (exit 2)."""
    from raysim.cli import main

    assert main(["rcs", "car:truck", "--az-deg", "0", "--el-deg", "0"]) == 2
    assert "car model" in capsys.readouterr().err
    assert main(["rcs", "car:sedan", "--az-deg", "0", "--el-deg", "0", "--range-m", "5"]) == 2
    assert "--range-m" in capsys.readouterr().err
    assert main(["rcs", "car:sedan", "--az-deg", "0:360:0.01", "--el-deg", "-90:90:0.01"]) == 2
    err = capsys.readouterr().err
    assert "directions" in err and "--az-deg / --el-deg" in err


def test_table_says_where_the_measured_ranges_come_from():
    """Every measured range in the table carries its provenance, and only at ground level
    (no measurement from 30-60 deg elevation is known)."""
    from raysim.studies.car_rcs import (
        MEASURED_DBSM,
        MEASURED_PROVENANCE,
        CarRcs,
        table_markdown,
    )

    assert set(MEASURED_PROVENANCE) == set(MEASURED_DBSM)
    assert set(MEASURED_PROVENANCE.values()) <= {"recalled", "read"}
    az = np.arange(0.0, 181.0, 2.0)
    el = np.array([0.0, 45.0])
    ones = np.ones((len(az), len(el)))
    rows = table_markdown({"m": CarRcs(az, el, ones, ones, 0.0)}).splitlines()[2:]
    assert len(rows) == len(MEASURED_DBSM) * len(el)
    for row in rows:
        cells = [c.strip() for c in row.strip("|").split("|")]
        aspect, elevation, measured = float(cells[1]), float(cells[2]), cells[5]
        if elevation == 0.0:
            low, high = MEASURED_DBSM[int(aspect)]
            assert measured == f"{low:g} to {high:g} ({MEASURED_PROVENANCE[int(aspect)]})"
        else:
            assert measured == "-"
