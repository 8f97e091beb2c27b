"""Users' own meshes: every format, placement, materials per part, checks and refusals."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from raysim.echoes.rt.scenes import ENU_FROM_NED, check_mesh  # noqa: E402
from raysim.echoes.rt.user_meshes import UserMesh, cache_folder, convert_meshes  # noqa: E402

#: Vertex placement error after the PLY round trip [m] (PLY stores float32).
PLACEMENT_TOL_M = 1e-5


def _write(mesh_or_scene, path):
    mesh_or_scene.export(path)
    return path


@pytest.mark.parametrize("suffix", [".obj", ".stl", ".ply", ".glb", ".gltf"])
def test_each_format_is_converted_and_placed(tmp_path, suffix):
    box = trimesh.creation.box((2.0, 1.0, 0.5))
    src = _write(box, tmp_path / f"box{suffix}")
    before = src.read_bytes()
    yaw, pitch = math.radians(30.0), math.radians(10.0)
    spec = UserMesh(src, "metal", position_w=(3.0, -2.0, 14.0), yaw=yaw, pitch=pitch,
                    up="y" if suffix in (".glb", ".gltf") else "z")
    out = convert_meshes([spec], tmp_path / "out", hover_altitude=15.0)
    assert src.read_bytes() == before                   # the user's file is only read
    root = ET.parse(out.xml_path).getroot()
    plys = [s.find("string").get("value") for s in root.iter("shape")]
    assert len(plys) == 1 and out.num_triangles == 12
    assert check_mesh(out.xml_path.parent / plys[0]) == 12
    got = trimesh.load(out.xml_path.parent / plys[0], process=False)
    # expected: p_S = ENU_FROM_NED (T + R_zyx M_up p) + (0, 0, h)
    up = (np.diag([1.0, -1.0, -1.0]) if spec.up == "z"
          else np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]]))
    cy, sy, cp, sp = math.cos(yaw), math.sin(yaw), math.cos(pitch), math.sin(pitch)
    r_zyx = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]]) @ np.array(
        [[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    ref = (np.asarray(box.vertices) @ (r_zyx @ up).T + [3.0, -2.0, 14.0]) @ ENU_FROM_NED.T
    ref = ref + [0.0, 0.0, 15.0]
    d = np.linalg.norm(np.asarray(got.vertices)[:, None, :] - ref[None], axis=-1)
    assert np.max(d.min(axis=1)) < PLACEMENT_TOL_M and np.max(d.min(axis=0)) < PLACEMENT_TOL_M
    # outward normals survive the placement (volume positive)
    assert got.volume > 0


def test_materials_per_named_part_and_unknown_parts(tmp_path):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.box((4.0, 2.0, 1.2)), node_name="body",
                       geom_name="body")
    scene.add_geometry(trimesh.creation.cylinder(0.3, 0.2, sections=64), node_name="wheel",
                       geom_name="wheel")
    src = _write(scene, tmp_path / "car.glb")
    out = convert_meshes([UserMesh(src, materials={"body": "metal", "wheel": "concrete"},
                                   up="y")], tmp_path / "out")
    refs = {s.get("id"): s.find("ref").get("id") for s in ET.parse(out.xml_path).iter("shape")}
    assert refs == {"mesh-0-body": "metal", "mesh-0-wheel": "concrete"}
    with pytest.raises(ValueError, match="'door'"):
        convert_meshes([UserMesh(src, "metal", materials={"door": "glass"})], tmp_path / "o2")


def test_winding_is_fixed_and_reported(tmp_path):
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    faces = np.asarray(box.faces).copy()
    faces[:3] = faces[:3, ::-1]
    src = _write(trimesh.Trimesh(box.vertices, faces, process=False), tmp_path / "bad.obj")
    out = convert_meshes([UserMesh(src, "glass", closed=True)], tmp_path / "out")
    assert any("winding of 3 of 12 faces" in n for n in out.notes)
    got = trimesh.load(out.xml_path.parent / "meshes" / "0-bad.ply", process=False)
    assert got.is_winding_consistent and got.volume > 0


def test_units_watertightness_and_facet_checks(tmp_path):
    mm = _write(trimesh.creation.icosphere(subdivisions=2, radius=400.0), tmp_path / "mm.stl")
    with pytest.raises(ValueError, match="millimetres"):
        convert_meshes([UserMesh(mm, "metal")], tmp_path / "o1")
    ok = convert_meshes([UserMesh(mm, "metal", scale=1e-3)], tmp_path / "o2", range_m=15.0)
    assert ok.num_triangles == 320
    # an icosphere of 0.4 m: facets about 0.12 m wide against a 0.17 m Fresnel zone at
    # 15 m (no warning) and a 0.05 m zone at 1.5 m (warning)
    assert not any("Fresnel" in n for n in ok.notes)
    near = convert_meshes([UserMesh(mm, "metal", scale=1e-3)], tmp_path / "o3", range_m=1.5)
    assert any("Fresnel zone radius" in n for n in near.notes)
    # a box with one triangle missing: the hole is filled (and said); a tube without its
    # end caps (two 16-gon openings) cannot be closed: refused as a closed object
    box = trimesh.creation.box((1.0, 1.0, 1.0))
    holed = _write(trimesh.Trimesh(box.vertices, box.faces[:-1], process=False),
                   tmp_path / "holed.ply")
    fixed = convert_meshes([UserMesh(holed, "metal", closed=True)], tmp_path / "o4")
    assert any("filled holes" in n for n in fixed.notes) and fixed.num_triangles == 12
    tube = trimesh.creation.cylinder(0.5, 1.0, sections=16)
    side = np.abs(tube.face_normals[:, 2]) < 0.5
    tube_file = _write(trimesh.Trimesh(tube.vertices, tube.faces[side], process=False),
                       tmp_path / "tube.ply")
    with pytest.raises(ValueError, match="not watertight"):
        convert_meshes([UserMesh(tube_file, "metal", closed=True)], tmp_path / "o5")
    # an open surface is fine when it is not a closed object
    assert convert_meshes([UserMesh(tube_file, "metal")], tmp_path / "o6").num_triangles == 32


@pytest.mark.parametrize("kwargs, words", [
    ({"file": "x.fbx", "material": "metal"}, ("x.fbx", ".obj")),
    ({"material": "wood"}, ("'wood'", "metal")),
    ({"material": None}, ("material",)),
    ({"material": "metal", "scale": -1.0}, ("scale", "-1.0")),
    ({"material": "metal", "up": "x"}, ("up", "'x'")),
    ({"material": "metal", "position_w": (0.0, math.nan, 0.0)}, ("position",)),
])
def test_bad_mesh_specs_are_refused(tmp_path, kwargs, words):
    src = _write(trimesh.creation.box((1.0, 1.0, 1.0)), tmp_path / "b.stl")
    kwargs = {"file": src, **kwargs}
    if kwargs["file"] == "x.fbx":
        kwargs["file"] = tmp_path / "x.fbx"
    with pytest.raises(ValueError) as err:
        UserMesh(**kwargs)
    for w in words:
        assert w in str(err.value)


def test_cache_folder_follows_content(tmp_path):
    src = _write(trimesh.creation.box((1.0, 1.0, 1.0)), tmp_path / "b.stl")
    a = cache_folder([UserMesh(src, "metal")], tmp_path)
    assert a == cache_folder([UserMesh(src, "metal")], tmp_path)
    assert a != cache_folder([UserMesh(src, "metal", yaw=0.1)], tmp_path)
    _write(trimesh.creation.box((1.0, 2.0, 1.0)), src)
    assert a != cache_folder([UserMesh(src, "metal")], tmp_path)


def _scenario_text(extra=""):
    return ("[radar]\nnum_chirps = 8\n[array]\nnx = 2\nny = 2\n"
            "[[scene.meshes]]\nfile = \"plate.stl\"\nmaterial = \"metal\"\n"
            "position_m = [0.0, 0.0, 10.0]\n" + extra)


def test_scenario_meshes_key(tmp_path):
    from raysim.scenario import load_scenario

    plate = trimesh.creation.box((2.0, 2.0, 0.02))
    _write(plate, tmp_path / "plate.stl")
    (tmp_path / "s.toml").write_text(_scenario_text(), encoding="utf-8")
    sc = load_scenario(tmp_path / "s.toml")
    assert sc.scene.kind == "meshes"
    assert sc.scene.meshes[0].file == str((tmp_path / "plate.stl").resolve())
    (tmp_path / "bad.toml").write_text(_scenario_text().replace("metal", "wood"))
    with pytest.raises(ValueError, match="wood|radio material"):
        load_scenario(tmp_path / "bad.toml")
    (tmp_path / "bad2.toml").write_text(_scenario_text('up = "x"\n'))
    with pytest.raises(ValueError, match="up"):
        load_scenario(tmp_path / "bad2.toml")


@pytest.mark.sionna
def test_converted_scene_traces_the_plate_below(tmp_path):
    """A metal plate 10 m below the radar: one specular path of length 2 x 10 m."""
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import SPECULAR, MonostaticTracer
    from raysim.echoes.rt.user_meshes import convert_user_meshes
    from raysim.radar.config import RadarConfig
    from raysim.scenario import load_scenario

    _write(trimesh.creation.box((2.0, 2.0, 0.02)), tmp_path / "plate.stl")
    (tmp_path / "s.toml").write_text(_scenario_text(), encoding="utf-8")
    sc = load_scenario(tmp_path / "s.toml")
    out = convert_user_meshes([m.placement() for m in sc.scene.meshes],
                              root=tmp_path / "cache")
    cfg = RadarConfig(num_chirps=8)
    paths = MonostaticTracer(diffuse=False, targets=False, max_depth=1,
                             samples_per_src=2_000)(load_scene(out.xml_path), cfg)
    spec = paths.kind == SPECULAR
    assert spec.sum() == 1
    # the plate's top face is 1 cm above its centre at 10 m
    assert paths.length[spec][0] == pytest.approx(2 * (10.0 - 0.01), abs=1e-4)
