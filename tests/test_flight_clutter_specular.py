"""The flight clutter's coherent specular mirror against the image method's closed form.

A radar at the distance ``d`` above a rough plane receives the mirror's power
``P_t G^2 lambda^2 |Gamma(0) chi|^2 / ((4 pi)^2 (2d)^2)`` (Beckmann & Spizzichino
1963, eq. 5.29; Ulaby, Moore & Fung Vol. II, eq. 12.57), the radar equation's power
of a point of RCS ``pi d^2 |Gamma(0) chi|^2`` at the range ``d``, with
``Gamma(0) = (1 - sqrt(eps)) / (1 + sqrt(eps))`` (normal incidence) and the Ament
factor ``chi = exp(-2 (k s)^2)`` of the rms height ``s``.
"""

from __future__ import annotations

import math

import numpy as np

from raysim.echoes.ground.sigma0 import clutter_material
from raysim.pipeline.flight import FLIGHT_RADAR
from raysim.pipeline.flight_clutter import clutter_points
from raysim.radar.arrays import ti_3tx4rx
from raysim.radar.config import RadarConfig

#: The mirror's RCS against the closed form [dB] (both in double precision; the mean
#: plane of the flat ground is exact).
RCS_TOL_DB = 1e-6
#: The mirror's position against the foot of the perpendicular [m].
POSITION_TOL_M = 1e-9
LEVER = np.array([0.0, 0.0, 0.05])
ALTITUDE = 15.0


def _flight_clutter(specular: bool):
    cfg = RadarConfig(num_tx_slots=3, num_frames=1, **FLIGHT_RADAR)
    arr = ti_3tx4rx(cfg.wavelength)
    return cfg, clutter_points("parking_lot", cfg, arr, LEVER, altitude=ALTITUDE,
                               max_scatterers=100, specular=specular)


def test_specular_mirror_matches_the_image_method_closed_form():
    cfg, (points, summary) = _flight_clutter(True)
    _, (plain, _) = _flight_clutter(False)
    assert len(points) == len(plain) + 1 and "specular mirror" in summary
    mirror = points[-1]
    # the parking lot's ground at the scene's origin, straight below the radar
    foot = np.array([LEVER[0], LEVER[1], ALTITUDE])
    assert np.allclose(mirror.position, foot, rtol=0.0, atol=POSITION_TOL_M)
    assert np.allclose(mirror.velocity, 0.0)
    d = ALTITUDE - LEVER[2]
    m = clutter_material("asphalt-77ghz")
    root = np.sqrt(complex(m.permittivity))
    gamma = abs((1 - root) / (1 + root))
    chi = math.exp(-2.0 * (2 * math.pi / cfg.wavelength * m.rms_height) ** 2)
    expected_db = 10 * math.log10(math.pi * d**2 * (gamma * chi) ** 2)
    assert abs(mirror.rcs_dbsm - expected_db) <= RCS_TOL_DB
    # the other points are the same field with or without the mirror
    assert all(np.array_equal(a.position, b.position) and a.rcs_dbsm == b.rcs_dbsm
               for a, b in zip(points[:-1], plain, strict=True))


def test_clutter_specular_option_reaches_the_flight(tmp_path, capsys):
    """``raysim flight --clutter-specular`` adds the mirror (its summary line); without
    the option the clutter has none."""
    from raysim.cli import main

    base = ["--targets", "default5", "--frames", "1", "--seed", "0", "--clutter-scene",
            "parking_lot", "--clutter-max-scatterers", "60"]
    assert main(["flight", str(tmp_path / "plain"), *base]) == 0
    plain = capsys.readouterr()
    assert main(["flight", str(tmp_path / "mirror"), *base, "--clutter-specular"]) == 0
    mirror = capsys.readouterr()
    assert "ground clutter of parking_lot" in plain.err + plain.out
    assert "specular mirror" not in plain.err + plain.out
    assert "specular mirror" in mirror.err + mirror.out
