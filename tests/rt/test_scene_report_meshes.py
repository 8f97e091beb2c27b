"""Users' scenes through the main jobs: the scene report names, marks and summarises three
mesh formats; `render` + `report` work on them with the default chains."""

from __future__ import annotations

import json

import pytest

from raysim.measure.scene import CFAR_THRESHOLD_DB, MISS_REASONS

pytestmark = pytest.mark.sionna

#: A user's scenario: a PLY ground 15.1 m below the radar, an OBJ building and a GLB car
#: (glTF, +y up) on it, hovering.
THREE_MESHES = """
name = "my town"
seed = 3

[radar]
num_chirps = 16

[array]
nx = 4
ny = 4

[[scene.meshes]]
file = "ground.ply"
material = "dry-soil"
position_m = [0.0, 0.0, 15.1]

[[scene.meshes]]
file = "building.obj"
material = "concrete"
position_m = [9.0, -7.0, 11.1]
closed = true

[[scene.meshes]]
file = "car.glb"
material = "metal"
position_m = [3.0, 4.0, 14.4]
up = "y"
closed = true

[scene]
max_depth = 1

[motion.hover_jitter]
seed = 5
"""


def write_three_meshes(folder) -> None:
    """The meshes of :data:`THREE_MESHES` (small boxes) into ``folder``."""
    trimesh = pytest.importorskip("trimesh")
    trimesh.creation.box((40.0, 40.0, 0.2)).export(folder / "ground.ply")
    trimesh.creation.box((6.0, 5.0, 8.0)).export(folder / "building.obj")
    trimesh.creation.box((1.8, 1.4, 4.5)).export(folder / "car.glb")   # x left, y up, z fwd
    (folder / "s.toml").write_text(THREE_MESHES, encoding="utf-8")


def test_scene_report_names_and_marks_three_user_meshes(tmp_path, capsys, warm_kernels):
    """A PLY ground, an OBJ building and a GLB car: the report names each mesh, marks it on
    the maps, says what the radar saw of it, and draws the placement before tracing."""
    from raysim.cli import main

    write_three_meshes(tmp_path)
    out = tmp_path / "out"
    assert main(["scene-report", "--scenario", str(tmp_path / "s.toml"), "--quick",
                 "--chains", "none,exact", "--out", str(out), "--no-progress",
                 "--threads", "2"]) == 0
    data = json.loads((out / "my_town.json").read_text())
    names = ["ground.ply", "building.obj", "car.glb"]
    assert [m["name"] for m in data["meshes"]] == names
    marks = {t["name"]: t for t in data["targets"] if t.get("mesh")}
    assert list(marks) == names
    # azimuth towards north (x_A), elevation towards east here: the building is further
    # north and west of the car
    assert marks["building.obj"]["az_deg"] > marks["car.glb"]["az_deg"] > 0
    assert marks["building.obj"]["el_deg"] < 0 < marks["car.glb"]["el_deg"]
    # the ground under the radar: its top face (15.0 m down) straight below the phase centre
    assert marks["ground.ply"]["range_m"] == pytest.approx(15.0, abs=0.15)
    assert marks["ground.ply"]["az_deg"] == marks["ground.ply"]["el_deg"] == 0.0
    for m in data["meshes"]:
        assert set(m["detections"]) == {"stationary", "none", "exact"}
    for t in marks.values():                        # the CFAR's verdict on each mesh's cell
        assert set(t["cfar"]) == {"stationary", "none", "exact"}
        for v in t["cfar"].values():
            assert v["status"] in ("detected", *MISS_REASONS)
            assert v["threshold_db"] == CFAR_THRESHOLD_DB
    ground, building, _ = data["meshes"]       # the flat metal car top returns no path here
    assert ground["num_paths"] > 0 and ground["power_dbw"] is not None
    assert building["num_paths"] > 0                # its concrete roof scatters diffusely
    md = (out / "report.md").read_text()
    assert f"threshold {CFAR_THRESHOLD_DB:g} dB" in md and "SNR " in md
    for n in names:
        assert f"| my_town | {n} |" in md                # the per-mesh table
    assert "![placement](placement.png)" in md
    assert (out / "placement.png").read_bytes()[:4] == b"\x89PNG"
    assert "<img src=\"placement.png\"" in (out / "index.html").read_text()
    for m in ("ra", "ae"):
        assert (out / f"my_town_{m}.png").read_bytes()[:4] == b"\x89PNG"


def test_bundled_user_mesh_example_loads_its_package_meshes():
    """The bundled `[[scene.meshes]]` example: its mesh files ship beside it and load."""
    import raysim.data
    from raysim.scenario import load_scenario
    from raysim.studies.scene_report import QUICK
    from raysim.studies.scene_report.meshes import mesh_boxes

    path = raysim.data.example_path("scene_user_meshes.toml")
    s = load_scenario(path)
    assert s.scene.kind == "meshes"
    names = [b["name"] for b in mesh_boxes(QUICK.for_scenario(s).scenario)]
    assert names == ["ground.ply", "building.obj", "car.glb"]



def test_render_then_report_a_mesh_scene_with_the_default_chains(tmp_path, capsys,
                                                                   warm_kernels):
    """No reference target in the scene: the paper chain corrects towards the strongest
    return, the report says so, and every default chain is measured."""
    from raysim.cli import main
    from raysim.vocabulary import CHAINS

    write_three_meshes(tmp_path)
    scen = tmp_path / "s.toml"
    store = tmp_path / "town.zarr"
    assert main(["render", str(scen), "--out", str(store), "--no-progress"]) == 0
    capsys.readouterr()
    out = tmp_path / "town.html"
    assert main(["report", str(store), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "the scene has no reference target" in err and "strongest return" in err
    page = out.read_text()
    assert "strongest return" in page
    assert "needs direction" not in page
    for c in CHAINS:
        assert c in page


def test_a_mesh_off_the_maps_is_named(tmp_path, capsys, warm_kernels):
    """A range window that stops short of the meshes: the report says which are off the maps
    and why, and the detection table gives the reason."""
    from raysim.cli import main

    write_three_meshes(tmp_path)
    out = tmp_path / "out"
    assert main(["scene-report", "--scenario", str(tmp_path / "s.toml"), "--quick",
                 "--chains", "none", "--range-window", "5,12", "--out", str(out),
                 "--no-progress", "--threads", "2"]) == 0
    err = capsys.readouterr().err
    for n in ("ground.ply", "building.obj", "car.glb"):
        assert f"warning: my_town: mesh {n} (range" in err
    assert "is outside the range window (range window 5-12 m" in err
    assert "outside the range window" in (out / "report.md").read_text()
