"""Cars driving through a scene: ``[[scene.movers]]`` keys and PO + SBR centres on the body."""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.scenario import loads_scenario

SCENE = '[scene]\nname = "flat_reflectors"\n'
MOVER = '[[scene.movers]]\nstart_m = [-1.0, 6.0, 15.0]\nheading_deg = 90\nspeed_mps = 8.0\n'
#: Slack of the centres around the car's box [m]: PO centres are mean equivalent points of
#: facets and of double bounces, within a range cell (0.15 m) of the surface.
BOX_SLACK_M = 0.15


def test_movers_keys_reach_the_clutter_model():
    from raysim.echoes.moving.cars import CarMover
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
    from raysim.echoes.moving.cars import CarMover
    from raysim.echoes.moving.scatterers import RigidTrajectory
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


# --- car-ground multipath of a mover --------------------------------------------------------
# A metal trihedral (edge 0.1 m, apex 0.5 m above a flat ground, axis horizontal towards the
# radar, one mirror plane horizontal) drives at 5 m/s straight at a radar 1.5 m above the
# ground, 6 m away (W, NED: ground at z = 1.5, radar at the origin). The image method
# (Balanis, Advanced Engineering Electromagnetics, sec. 7.4) puts the ground-target-ground
# ghost at the apex's image p' (range R2 = |p'|), moving at M v = v (horizontal motion), with
# power |Gamma chi|^4 (R1 / R2)^4 sigma(x') / sigma(x) relative to the direct return at R1
# (x' the radar's image; Gamma the Fresnel coefficient, TE for the horizontal polarisation,
# chi the Ament factor), as in tests/rt/test_rt_ground_multipath.py.
EDGE, APEX_HEIGHT, RADAR_HEIGHT, DISTANCE, SPEED = 0.1, 0.5, 1.5, 6.0, 5.0
#: Centre range and range rate vs the image method [range / velocity bins]: the
#: retro-reflected length is exact for a trihedral, this bounds the clustering.
BIN_TOL = 0.1
#: Ghost-to-direct power vs the image-method closed form [dB]: the tube-sampling error of
#: the trihedral, up to 0.4 dB at the default density, on each of the two traces.
GHOST_TOL_DB = 1.0
#: Radar attitude (columns X_A, Y_A, Z_A in W): polarisation east (horizontal, TE at the
#: ground bounce), boresight north towards the mover.
R_WB = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])


def _flat_ground(z, material="asphalt-77ghz"):
    from raysim.echoes.ground.surface import GroundSurface
    from raysim.echoes.po.mesh import TriangleMesh

    mesh = TriangleMesh(np.array([[-50.0, -50.0, z], [50.0, -50.0, z], [50.0, 50.0, z],
                                  [-50.0, 50.0, z]]), np.array([[0, 1, 2], [0, 2, 3]]))
    return GroundSurface.from_meshes([(mesh, material)])


def _trihedral_mover():
    """The trihedral on a trajectory through its apex, driving south (towards the radar)."""
    from raysim.echoes.moving.cars import CarMover
    from raysim.echoes.moving.scatterers import RigidTrajectory
    from raysim.echoes.po.mesh import TriangleMesh
    from raysim.echoes.po.targets import trihedral

    # mesh frame x forward, y left, z up: the trihedral's axis (+z local) forward, its
    # local x (normal of a mirror plane) up
    rot = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0], [1.0, 0.0, 0.0]]).T
    m = trihedral(EDGE)
    apex = [DISTANCE, 0.0, RADAR_HEIGHT - APEX_HEIGHT]
    return CarMover("trihedral", RigidTrajectory(apex, heading=math.pi, speed=SPEED),
                    parts=((TriangleMesh(m.vertices @ rot.T, m.faces), "metal"),))


def _range_rates(tracks, dt=1e-3):
    """Range rates ``[path]`` [m/s] of the tracks seen from a radar at rest at the origin."""
    times = np.array([[0.0], [dt]])
    length = tracks.lengths(times, np.zeros((2, 1, 3)), np.zeros((2, 1, 3)))[:, :, 0]
    return (length[:, 1] - length[:, 0]) / (2 * dt)


@pytest.mark.sionna
@pytest.mark.parametrize("material", ["asphalt-77ghz", "concrete"])
def test_mover_ghosts_follow_the_image_method(clutter_backend, material):
    from raysim.echoes.ground.sigma0 import ament_factor, fresnel_coefficient
    from raysim.echoes.moving.cars import GHOST_LABEL
    from raysim.echoes.po.paths import scattering_terms
    from raysim.radar.config import RadarConfig

    config = RadarConfig()
    mover = _trihedral_mover()
    apex = mover.trajectory.start
    image_apex = apex + [0.0, 0.0, 2 * APEX_HEIGHT]            # NED: the image lies deeper
    radar, image_radar = np.zeros(3), np.array([0.0, 0.0, 2 * RADAR_HEIGHT])
    r1, r2 = float(np.linalg.norm(apex)), float(np.linalg.norm(image_apex))
    tracks = mover.tracks(config, radar, time=0.0, r_wb=R_WB,
                          ground=_flat_ground(RADAR_HEIGHT, material))
    ghost = tracks.label == GHOST_LABEL
    assert ghost.any() and (~ghost).any()
    d = int(np.argmax(np.where(ghost, 0.0, np.abs(tracks.amplitude))))
    g = int(np.argmax(np.where(ghost, np.abs(tracks.amplitude), 0.0)))
    ranges = np.linalg.norm(tracks.p_tx(np.array(0.0)), axis=-1)
    assert abs(ranges[d] - r1) < BIN_TOL * config.range_resolution
    assert abs(ranges[g] - r2) < BIN_TOL * config.range_resolution   # the apex's image

    # Doppler: the ghost rides on the body (M v = v over flat ground), at the range rate
    # of the image point, v . p' / |p'|
    v = mover.trajectory.velocity(np.array(0.0))
    dt = 0.01
    moved = tracks.p_tx(np.array(dt)) - tracks.p_tx(np.array(0.0))
    assert np.allclose(moved, v * dt, atol=1e-12)
    rate = _range_rates(tracks)
    assert abs(rate[d] - v @ apex / r1) < BIN_TOL * config.velocity_resolution
    assert abs(rate[g] - v @ image_apex / r2) < BIN_TOL * config.velocity_resolution

    # power: image method with the Fresnel and Ament factors at the bounce's incidence
    cos_i = (RADAR_HEIGHT + APEX_HEIGHT) / r2
    gamma = abs(complex(fresnel_coefficient(material, cos_i, "HH")))
    chi = float(ament_factor(material, math.acos(cos_i), config.wavelength))
    assert chi < 0.95                                               # the roughness is felt
    meshes, materials = mover.meshes_w(0.0)
    sigma = [scattering_terms(meshes, materials, x, apex, frequency=config.carrier_frequency,
                              polarisation_w=R_WB[:, 0]).rcs_m2 for x in (radar, image_radar)]
    closed_db = 10 * math.log10((gamma * chi) ** 4 * (r1 / r2) ** 4 * sigma[1] / sigma[0])
    ghost_db = 20 * math.log10(abs(tracks.amplitude[g] / tracks.amplitude[d]))
    print(f"{material}: ghost {ghost_db:.2f} dB, closed form {closed_db:.2f} dB; range rate "
          f"direct {rate[d]:.3f}, ghost {rate[g]:.3f} m/s")
    assert abs(ghost_db - closed_db) < GHOST_TOL_DB


@pytest.mark.sionna
def test_without_ground_the_mover_has_no_ghosts(clutter_backend):
    """The same trace with ``ground=None`` (and a SceneClutter's ground through ``paths``)."""
    import dataclasses

    from raysim.echoes.moving.cars import GHOST_LABEL
    from raysim.echoes.rt.trace import PathSet
    from raysim.echoes.scene_clutter import SceneClutter
    from raysim.platform.motion import stationary
    from raysim.radar.config import RadarConfig

    config = RadarConfig()
    mover = _trihedral_mover()
    r1 = float(np.linalg.norm(mover.trajectory.start))
    alone = mover.tracks(config, np.zeros(3), time=0.0, r_wb=R_WB)
    assert not np.any(alone.label == GHOST_LABEL)
    assert np.all(np.linalg.norm(alone.p_tx(np.array(0.0)), axis=-1) < r1 + EDGE)

    @dataclasses.dataclass(frozen=True)
    class Switches:                       # the tracer switches SceneClutter.tracer reads
        diffuse: bool = False
        specular: bool = False
        targets: bool = False
        target_depth: int = 1

    model = SceneClutter(specular=False, ghosts=False, movers=[mover],
                          ground=_flat_ground(RADAR_HEIGHT))
    model.tracer(Switches())
    z3, z0 = np.zeros((0, 3)), np.zeros(0)
    none = PathSet(z3, z3, z0, z0.astype(complex), z3, z0, np.zeros((0, 1), np.uint32),
                   np.zeros(0, np.uint32), np.zeros((0, 2, 2), complex), z0, np.zeros(3),
                   np.zeros(3), 0.0, {})
    _, (tracks,) = model.paths(None, none, config, None, stationary(), np.zeros(3), time=0.0)
    assert np.any(tracks.label == GHOST_LABEL)


@pytest.mark.sionna
def test_car_ghosts_lie_at_or_below_the_ground(clutter_backend):
    """A car 15 m below the radar over flat asphalt: its ground-bounced centres are labelled,
    fixed in the body at or below the ground contact (z >= 0, FRD), within a range cell."""
    from raysim.echoes.moving.cars import GHOST_LABEL, CarMover
    from raysim.echoes.moving.scatterers import RigidTrajectory
    from raysim.radar.config import RadarConfig

    config = RadarConfig()
    car = CarMover("car", RigidTrajectory([-1.0, 6.0, 15.0], heading=math.pi / 2, speed=8.0))
    tracks = car.tracks(config, np.zeros(3), time=0.0, ground=_flat_ground(15.0))
    ghost = tracks.label == GHOST_LABEL
    print(f"{ghost.sum()} of {ghost.size} centres return by the ground")
    assert ghost.any() and (~ghost).any()
    # body z = W z - 15 (level ground, yaw only)
    assert np.all(tracks.p_tx(np.array(0.0))[ghost, 2] - 15.0 >= -BOX_SLACK_M)


def test_mover_bad_ground_and_parts_are_named():
    from raysim.echoes.moving.cars import CarMover
    from raysim.echoes.moving.scatterers import RigidTrajectory
    from raysim.radar.config import RadarConfig

    traj = RigidTrajectory([6.0, 0.0, 1.0])
    with pytest.raises(ValueError, match="parts"):
        CarMover("x", traj, parts=(("mesh", "metal"),))
    with pytest.raises(ValueError, match="GroundSurface"):
        CarMover("car", traj).moving_object(RadarConfig(), np.zeros(3), ground="asphalt")
