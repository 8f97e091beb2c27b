"""`raysim render` says on stderr what it traced (per source kind, per mesh), the frames it
wrote and the store's size."""

from __future__ import annotations

import re

import pytest

from raysim.cli import main
from raysim.resources import format_bytes, tree_bytes

SMALL = ["--set", "radar.num_chirps=16", "--set", "array.nx=4", "--set", "array.ny=4",
         "--no-progress"]


def test_point_scene_summary_and_resume(tmp_path, capsys):
    store = tmp_path / "p.zarr"
    assert main(["render", "examples/case_stationary.toml", "--out", str(store), *SMALL]) == 0
    err = capsys.readouterr().err
    assert "traced (frame 0): 1 point target(s)" in err
    assert (f"wrote: 1 frame(s) rendered now, 0 kept, 1/1 in the store; "
            f"{format_bytes(tree_bytes(store))} in {store}") in err
    assert tree_bytes(store) > 0
    # resumed: nothing traced now, the frame kept is counted
    assert main(["render", "examples/case_stationary.toml", "--out", str(store), *SMALL]) == 0
    err = capsys.readouterr().err
    assert "traced" not in err and "wrote: 0 frame(s) rendered now, 1 kept, 1/1" in err


MESHES = """
frames = 1
[radar]
num_chirps = 8
[array]
nx = 2
ny = 2
[[scene.meshes]]
file = "ground.stl"
material = "dry-soil"
position_m = [0.0, 0.0, 10.0]
[[scene.meshes]]
file = "cube.stl"
material = "metal"
position_m = [6.0, 3.0, 8.0]
closed = true
"""


@pytest.mark.sionna
def test_mesh_scene_summary_counts_paths_per_kind_and_mesh(tmp_path, capsys, rt_backend):
    """A 20 m flat dry-soil slab 10 m below the radar and a metal cube: the clutter
    field's scatterers, one specular mirror point (a plane has one point whose normal
    points at the radar) and every path owned by the mesh it starts on."""
    trimesh = pytest.importorskip("trimesh")
    trimesh.creation.box((20.0, 20.0, 0.2)).export(tmp_path / "ground.stl")
    trimesh.creation.box((1.0, 1.0, 1.0)).export(tmp_path / "cube.stl")
    (tmp_path / "s.toml").write_text(MESHES, encoding="utf-8")
    store = tmp_path / "s.zarr"
    assert main(["render", str(tmp_path / "s.toml"), "--out", str(store),
                 "--no-progress"]) == 0
    err = capsys.readouterr().err
    head = re.search(r"traced \(frame 0\): (\d+) paths of its first trace \((.*)\)", err)
    assert head, err
    total = int(head.group(1))
    kinds = {k: int(n) for k, n in (part.rsplit(" ", 1) for part in head.group(2).split(", "))}
    assert kinds["specular ground"] == 1
    assert sum(kinds.values()) == total
    field = int(re.search(r"clutter field: (\d+) scatterers", err).group(1))
    assert 0 < kinds["diffuse"] <= field
    meshes = re.search(r"meshes: ground\.stl (\d+) paths, cube\.stl (\d+) paths", err)
    assert meshes, err
    ground, cube = int(meshes.group(1)), int(meshes.group(2))
    # the mirror point and the field's scatterers lie on the ground; every path starts on
    # one of the two meshes (the scene has nothing else)
    assert ground >= kinds["specular ground"] + kinds["diffuse"]
    assert ground + cube == total
    assert "wrote: 1 frame(s) rendered now, 0 kept, 1/1 in the store" in err
