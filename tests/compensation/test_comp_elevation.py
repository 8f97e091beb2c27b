"""Elevation by phase comparison across the raised TX's lambda/2 vertical baseline.

A TI xWR18xx-like array (3 TX, 4 RX, TX1 raised lambda/2: an 8-element azimuth row
and a 4-element row above it) resolves no elevation as a beam (its extent along y is
lambda/2), but the phase between the two rows gives it: the array's beam power at the
scatterer's azimuth is ``|A|^2 + |B|^2 + 2 |A B| cos(pi (sin el - sin el0))`` for a
lambda/2 baseline, whose one maximum over +-90 deg is the interferometric estimate
(Skolnik, Introduction to Radar Systems, 3rd ed., sec. 9.3, phase-comparison
monopulse). Oracle echoes of the five flight targets (elevation -5, 0, +5 deg) with
receiver noise, platform at rest.
"""

from __future__ import annotations

import numpy as np

from compensation import PlatformMotion
from compensation.calibration import UNRESOLVED_DIRECTION_SIGMA, _direction_cov, detect_scatterers
from raysim.echoes.oracle import PointTarget, simulate_point_targets
from raysim.pipeline.flight import DEFAULT5_TARGETS, FLIGHT_RADAR
from raysim.pipeline.self_calibration import _slot_times
from raysim.processing.maps import range_compress
from raysim.radar.arrays import ti_3tx4rx, upa
from raysim.radar.config import RadarConfig

#: Largest error of a detected elevation [deg] (measured: 0.05 deg; the stated spread
#: is at least 1 deg, so the error is also checked against 3 stated sigma).
ELEVATION_TOL_DEG = 0.2
#: Largest error of a detected azimuth [deg] (refined at the measured elevation).
AZIMUTH_TOL_DEG = 0.2
AXIS = np.deg2rad(np.arange(-60.0, 60.5, 2.0))


def _detect(array, cfg, noise_seed: int = 3):
    pts = [PointTarget.at(r, np.deg2rad(a), np.deg2rad(e)) for r, a, e in DEFAULT5_TARGETS]
    fr = simulate_point_targets(cfg, array, pts, noise=True, seed=noise_seed)
    t = _slot_times(fr)
    n = t.size
    z = np.zeros((n, 3))
    still = PlatformMotion(t, np.tile(np.eye(3), (n, 1, 1)), z, z.copy(), z.copy(), np.zeros(3))
    return detect_scatterers(range_compress(fr.data), array.virtual_positions, still,
                             wavelength=cfg.center_wavelength, range_axis=cfg.range_axis(),
                             azimuth=AXIS, elevation=AXIS, channel_slot=array.tx_slot)


def test_raised_tx_gives_each_target_its_elevation():
    cfg = RadarConfig(num_tx_slots=3, **FLIGHT_RADAR)
    array = ti_3tx4rx(cfg.wavelength)
    found = _detect(array, cfg)
    assert len(found) == len(DEFAULT5_TARGETS)
    ranges = cfg.range_axis()
    for s in found:
        r, az, el = min(DEFAULT5_TARGETS, key=lambda t: abs(t[0] - ranges[s.gate]))
        err = np.rad2deg(s.elevation) - el
        assert s.elevation_sigma is not None and s.elevation_sigma > 0
        assert abs(err) <= ELEVATION_TOL_DEG, (r, el, err)
        assert abs(err) <= 3 * np.rad2deg(s.elevation_sigma)
        assert abs(np.rad2deg(s.azimuth) - az) <= AZIMUTH_TOL_DEG
        # the radar-inertial estimate gets the measured spread, not the unresolved fan's
        cov = _direction_cov(s, array.virtual_positions, cfg.center_wavelength)
        up = np.array([-np.sin(s.elevation) * np.sin(s.azimuth), np.cos(s.elevation),
                       -np.sin(s.elevation) * np.cos(s.azimuth)])
        assert np.isclose(up @ cov @ up, s.elevation_sigma ** 2, rtol=1e-6)
        assert up @ cov @ up < UNRESOLVED_DIRECTION_SIGMA ** 2


def test_line_array_leaves_elevation_unmeasured():
    """No vertical baseline: elevation stays 0 and its spread unstated (the wide fan)."""
    cfg = RadarConfig(num_tx_slots=1, **FLIGHT_RADAR)
    array = upa(8, 1, wavelength=cfg.wavelength)
    for s in _detect(array, cfg):
        assert s.elevation == 0.0 and s.elevation_sigma is None
