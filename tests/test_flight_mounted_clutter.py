"""The flight's ground clutter for a mounted radar: drawn where the radar points.

The clutter field is built for the radar frame's own pose (attitude ``R_BA`` at the
hover point): an oblique radar's scatterers lie in its beam and range window, a
forward radar sees the ground ahead at low grazing, and ``raysim compensate`` with the
mounting restores the targets of a forward-mounted flight in that clutter.
"""

from __future__ import annotations

import numpy as np

from raysim.cli import main
from raysim.echoes.ground.field import FieldSettings
from raysim.pipeline.flight import FLIGHT_RADAR, measure_targets, write_flight
from raysim.pipeline.flight_clutter import RANGE_MARGIN_M, clutter_points
from raysim.platform.mounting import mounting_matrix
from raysim.radar.arrays import ti_3tx4rx
from raysim.radar.config import RadarConfig

#: Compensated with its mounting (consumer IMU, given velocity and clock offset): the
#: targets' beam angle error [deg] (measured 0.02 deg).
ANGLE_TOL_DEG = 0.2
#: The ground clutter raises the range cells of the ground (away from the targets) by at
#: least this much over the same flight without it [dB].
CLUTTER_GAIN_DB = 20.0
#: Share of an oblique radar's scatterers ahead of the drone, at least (measured 0.96).
AHEAD_SHARE = 0.9
#: A down-looking radar's scatterers lie ahead of it half the time, within this (about
#: 300 seeded scatterers: binomial standard deviation 0.03).
SYMMETRY_TOL = 0.1
LEVER = np.array([0.0, 0.0, 0.05])


def _directions(points, lever):
    d = np.array([p.position for p in points]) - lever
    r = np.linalg.norm(d, axis=1)
    return d / r[:, None], r


def test_oblique_clutter_lies_in_its_beam_and_range_window():
    cfg = RadarConfig(num_tx_slots=3, num_frames=1, **FLIGHT_RADAR)
    arr = ti_3tx4rx(cfg.wavelength)
    altitude = 8.0
    points, summary = clutter_points("flat_reflectors", cfg, arr, LEVER, altitude=altitude,
                                     max_scatterers=300, mounting_deg="oblique")
    assert "8 m" in summary and len(points) > 50
    u, r = _directions(points, LEVER)
    bore = mounting_matrix("oblique")[:, 2]                 # (1, 0, 1) / sqrt(2) in B = W
    cone = FieldSettings().fov(cfg)                          # the field's half-angle [rad]
    assert np.all(u @ bore >= np.cos(cone))
    assert np.all(r < cfg.max_range - RANGE_MARGIN_M) and np.all(r >= altitude - LEVER[2])
    # the ground under a 45 deg beam: ahead of the drone, along the boresight's slant range
    assert np.mean(u[:, 0] > 0) >= AHEAD_SHARE
    down, _ = clutter_points("flat_reflectors", cfg, arr, LEVER, altitude=altitude,
                             max_scatterers=300)
    assert abs(np.mean(_directions(down, LEVER)[0][:, 0] > 0) - 0.5) <= SYMMETRY_TOL


def test_forward_flight_in_clutter_restored_with_its_mounting(tmp_path):
    from raysim.io.mmwave_config import read_mmwave_config
    from raysim.io.ti_dca1000 import read_dca1000

    kw = dict(frames=1, targets=[(6.0, -15.0, 0.0), (9.0, 20.0, 0.0)], mounting_deg="forward")
    f = write_flight(tmp_path / "c", clutter_scene="flat_reflectors", clutter_altitude=3.0,
                     clutter_max_scatterers=300, **kw)
    n = write_flight(tmp_path / "n", **kw)

    def profile(flight):
        m = read_mmwave_config(flight.radar_config)
        x = read_dca1000(flight.capture, m.fmt).cube[0].astype(complex)
        spec = np.fft.fft(x * np.hanning(x.shape[-1]), axis=-1)
        power = 10 * np.log10((np.abs(spec) ** 2).sum(axis=(0, 1)) + 1e-30)
        return m.config.bin_ranges(x.shape[-1]), power - power.max()

    ranges, with_clutter = profile(f)
    _, without = profile(n)
    # the ground ahead, from 3 m down: its cells between and around the targets
    ground = (ranges > 3.5) & (ranges < 9.5) & (np.abs(ranges - 6.0) > 0.7) \
        & (np.abs(ranges - 9.0) > 0.7)
    assert np.median(with_clutter[ground] - without[ground]) >= CLUTTER_GAIN_DB
    out = tmp_path / "c.zarr"
    assert main(f.command(out, "--range-m", "5.5:9.5", "--az-deg", "-40:40:0.5",
                          "--el-deg", "0:0:1", "--no-progress")) == 0
    assert "--mounting-deg" in f.command(out)
    errors = measure_targets(out, f)[:, 0, 0]                # [target]: angle error [deg]
    assert np.all(errors <= ANGLE_TOL_DEG), errors
