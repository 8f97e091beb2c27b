"""The pseudo-velocity a beam grid leaves a scatterer between its beams while the radar moves
(raysim.pipeline.grid_miss): closed form, the step it names, and the end-to-end warning."""

from __future__ import annotations

import numpy as np

from compensation.geometry import direction, direction_tangents
from raysim.pipeline.grid_miss import GRID_MISS_BINS, grid_miss_warning

#: One Doppler bin of the stand-in radar [m/s].
BIN = 0.05
#: Central-difference step [rad] and the agreement it allows (its error is h^2 / 6).
H, DERIVATIVE_TOL = 1e-5, 1e-9


def test_direction_tangents_are_the_derivatives_of_the_direction():
    az, el = np.meshgrid(np.deg2rad(np.arange(-60.0, 61.0, 15.0)),
                         np.deg2rad(np.arange(-40.0, 41.0, 20.0)), indexing="ij")
    d_az, d_el = direction_tangents(az, el)
    np.testing.assert_allclose(d_az, (direction(az + H, el) - direction(az - H, el)) / (2 * H),
                               rtol=0, atol=DERIVATIVE_TOL)
    np.testing.assert_allclose(d_el, (direction(az, el + H) - direction(az, el - H)) / (2 * H),
                               rtol=0, atol=DERIVATIVE_TOL)


def test_half_a_step_times_the_velocity_across_the_axis():
    # v along x only: on the azimuth axis d u / d az = cos(el) cos(az) along x, largest at
    # the boresight beam; the elevation axis's d u / d el has no x part at az 0 but
    # -sin(el) sin(az) off it
    az, el = np.deg2rad(np.arange(-30.0, 31.0, 1.0)), np.array([0.0])
    v = np.array([[0.3, 0.0, 0.0]])
    said = grid_miss_warning(az, el, v, BIN)
    closed = 0.5 * np.deg2rad(1.0) * 0.3 / BIN                           # [bin]
    assert closed > GRID_MISS_BINS
    assert f"azimuth step 1 deg leaves up to {closed:.2f} bin" in said
    assert "elevation" not in said                        # one elevation: not gridded
    fine = float(said.split("a step of ")[1].split(" deg")[0])
    assert grid_miss_warning(np.deg2rad(np.arange(-30.0, 30.0 + fine / 2, fine)), el, v,
                             BIN) is None                # the step it names is enough


def test_a_still_radar_or_a_fine_grid_says_nothing():
    az = np.deg2rad(np.arange(-60.0, 61.0, 1.0))
    assert grid_miss_warning(az, az, np.zeros((3, 3)), BIN) is None
    # 0.3 m/s across a 0.25 deg grid: 0.026 bin
    fine = np.deg2rad(np.arange(-10.0, 10.01, 0.25))
    assert grid_miss_warning(fine, fine, [[0.3, 0.0, 0.0]], BIN) is None


def test_the_frame_that_moves_most_decides():
    az, el = np.deg2rad(np.arange(-5.0, 5.5, 1.0)), np.deg2rad(np.arange(-5.0, 5.5, 5.0))
    slow, fast = [0.0, 0.01, 0.0], [0.0, 0.3, 0.0]
    assert grid_miss_warning(az, el, [slow], BIN) is None
    said = grid_miss_warning(az, el, [slow, fast], BIN)
    assert said.startswith("grid: ") and "elevation step 5 deg" in said
