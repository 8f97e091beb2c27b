"""Geometry targets (PO + SBR meshes, absent from Sionna's scene) shadow the clutter field."""

from __future__ import annotations

import numpy as np
import pytest

pytestmark = pytest.mark.sionna

#: Radar height over the ground for the shadow checks [m] (the bundled scenes' hover is 15 m).
RADAR_HEIGHT_M = 10.0
#: Where the added car stands in the scene frame S (ENU) [m]: 6 m east, 1 m south of nadir.
CAR_AT_S = (6.0, -1.0, 0.0)


def _behind(ground, body_vertices: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Radar above the car's ground point, and the ray to the ground behind the car.

    The ray from the radar through the centre of the car's closed lower body (a
    point inside it) goes on to the ground behind the car: that ground point is
    in the car's shadow (similar triangles), whatever the car's shape.
    """
    centre = body_vertices.mean(axis=0)
    _, z = ground.locate(centre[None])
    radar = np.array([0.0, 0.0, z[0] - RADAR_HEIGHT_M])
    g = radar + (centre - radar) * (z[0] - radar[2]) / (centre[2] - radar[2])
    d = g - radar
    r = float(np.linalg.norm(d))
    return radar[None], (d / r)[None], r - 0.05           # stop 5 cm short of the ground


def test_ground_behind_a_car_is_shadowed(clutter_backend, tmp_path):
    """The parking lot's cars shadow the ground behind them, and so does a car added as a
    geometry target that the scene file does not hold (only its mesh can occlude)."""
    from raysim.echoes.ground.surface import GroundSurface, scene_meshes, target_meshes
    from raysim.echoes.po.car import car_parts
    from raysim.echoes.po.mesh import TriangleMesh
    from raysim.echoes.po.rays import RayScene
    from raysim.echoes.rt.scenes import SceneTarget, load_scene

    lot = load_scene("parking_lot")
    ground = GroundSurface.from_scene(lot)
    occ = RayScene(ground.occluders)
    cars = [t for t in lot.targets if t.is_geometry and t.name.startswith("car")]
    assert len(cars) == 6
    for t in cars:
        body = TriangleMesh.load(t.mesh[0])                   # part 0: the lower body
        o, u, r = _behind(ground, lot.to_world(body.vertices))
        assert not occ.unoccluded(o, u, r)[0], t.name

    parts = car_parts()
    files, materials = [], []
    for name, mesh, material in parts:
        import trimesh

        f = tmp_path / f"added-{name}.ply"
        trimesh.Trimesh(mesh.vertices + np.asarray(CAR_AT_S), mesh.faces,
                        process=False).export(f)
        files.append(str(f))
        materials.append(material)
    added = SceneTarget("added-car", lot.to_world(np.asarray(CAR_AT_S)[None])[0], mesh=tuple(files),
                        material=tuple(materials))
    flat = load_scene("flat_reflectors", extra_targets=[added])
    assert len(target_meshes(flat)) == len(parts)             # only the added car's parts
    with_car = GroundSurface.from_scene(flat)
    without = GroundSurface.from_meshes(scene_meshes(flat))
    body_w = flat.to_world(parts[0][1].vertices + np.asarray(CAR_AT_S))
    o, u, r = _behind(with_car, body_w)
    assert not RayScene(with_car.occluders).unoccluded(o, u, r)[0]
    assert RayScene(without.occluders).unoccluded(o, u, r)[0]  # nothing else is in the way
