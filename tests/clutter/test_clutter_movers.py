"""Cars driving through a scene: ``[[scene.movers]]`` keys and PO + SBR centres on the body."""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.io.scenario import loads_scenario

SCENE = '[scene]\nname = "flat_reflectors"\n'
MOVER = '[[scene.movers]]\nstart_m = [-1.0, 6.0, 15.0]\nheading_deg = 90\nspeed_mps = 8.0\n'
#: Slack of the centres around the car's box [m]: PO centres are mean equivalent points of
#: facets and of double bounces, within a range cell (0.15 m) of the surface.
BOX_SLACK_M = 0.15


def test_movers_keys_reach_the_clutter_model():
    from raysim.echoes.clutter.movers import CarMover
    from raysim.pipeline.sources import _clutter

    sc = loads_scenario(SCENE + MOVER)
    (car,) = _clutter(sc).movers
    assert isinstance(car, CarMover)
    assert car.trajectory.speed == 8.0
    assert math.isclose(car.trajectory.heading, math.pi / 2)
    assert np.array_equal(car.trajectory.start, [-1.0, 6.0, 15.0])


@pytest.mark.parametrize("text, match", [
    (SCENE + MOVER.replace("8.0", "0.0"), "speed_mps"),
    (SCENE + MOVER + "length_m = 9\n", "length_m"),
    (SCENE + '[scene.clutter]\nmode = "sionna"\n' + MOVER, "mode = 'field'"),
])
def test_movers_bad_values_are_named(text, match):
    with pytest.raises(ValueError, match=match):
        loads_scenario(text)


@pytest.mark.sionna
def test_car_centres_ride_on_the_body(clutter_backend):
    """PO + SBR centres of a car seen from 15 m up lie on the car, fixed in its body frame
    (x forward, y right, z down from the ground contact), and move with its trajectory."""
    from raysim.echoes.clutter.movers import CarMover
    from raysim.echoes.clutter.tracks import RigidTrajectory
    from raysim.radar.config import RadarConfig

    config = RadarConfig()
    car = CarMover("car", RigidTrajectory([-1.0, 6.0, 15.0], heading=math.pi / 2, speed=8.0))
    obj = car.moving_object(config, np.zeros(3), time=0.0)
    p = obj.points
    print(f"{len(p)} centres, total {10 * np.log10(np.sum(10 ** (obj.rcs_dbsm / 10))):.1f} dBsm")
    assert len(p) > 1
    assert np.all(np.abs(p[:, 0]) <= car.length / 2 + BOX_SLACK_M)
    assert np.all(np.abs(p[:, 1]) <= car.width / 2 + BOX_SLACK_M)
    assert np.all((p[:, 2] <= BOX_SLACK_M) & (p[:, 2] >= -car.height - BOX_SLACK_M))
    # seen from above, the strongest centres are on top of the car (z up to -height)
    assert p[np.argmax(obj.rcs_dbsm), 2] < -car.height / 2
    # 0.5 s later the centres have moved 4 m east with the car
    d = obj.positions(np.array(0.5)) - obj.positions(np.array(0.0))
    assert np.allclose(d, [0.0, 4.0, 0.0], atol=1e-9)
