"""Users' mesh files in the formats CAD and modelling tools export, in the unit they declare.

A 3MF file is in millimetres unless it says otherwise and a COLLADA file states
its unit in ``<asset><unit meter=...>``; read as metres, a 40 mm plate would be a
40 m one. The plate's normal-incidence RCS ``4 pi A^2 / lambda^2`` (Knott, Shaeffer
& Tuley, *Radar Cross Section*, 2nd ed., table 6.1) checks the unit end to end.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from raysim.echoes.po import targets as T
from raysim.echoes.rt.user_meshes import UserMesh, convert_meshes
from raysim.io.mesh_files import declared_scale, read_mesh_file

LAM = 299_792_458.0 / 77e9
#: PO of a flat plate at normal incidence against the closed form [dB] (as tests/test_po_rcs.py).
CLOSED_FORM_DB = 1.0
SIDE_M = 0.04


def _plate(unit_per_metre: float):
    import trimesh

    plate = T.square_plate(SIDE_M)
    return trimesh.Trimesh(plate.vertices * unit_per_metre, plate.faces, process=False)


def _write_3mf_mm(path):
    path.write_bytes(_plate(1000.0).export(file_type="3mf"))   # 3MF's unit: millimetre
    return path


def _write_dae_cm(path):
    text = _plate(100.0).export(file_type="dae").decode()
    assert "<unit" not in text and "<up_axis>" in text
    path.write_text(text.replace("<up_axis>", '<unit meter="0.01" name="centimeter"/>\n'
                                              "    <up_axis>", 1))
    return path


@pytest.mark.parametrize("writer", [_write_3mf_mm, _write_dae_cm], ids=["3mf-mm", "dae-cm"])
def test_rcs_of_a_plate_file_in_its_declared_unit(tmp_path, capsys, writer):
    from raysim.cli import main

    path = writer(tmp_path / ("plate.3mf" if writer is _write_3mf_mm else "plate.dae"))
    assert main(["rcs", str(path), "--az-deg", "0", "--el-deg", "0", "--json",
                 "--max-bounces", "1", "--no-progress"]) == 0
    captured = capsys.readouterr()
    got = json.loads(captured.out)["rcs_dbsm"][0][0]
    assert abs(got - 10 * math.log10(T.plate_rcs(SIDE_M, LAM))) < CLOSED_FORM_DB
    assert "declares its unit" in captured.err


def test_a_given_scale_overrides_the_declared_unit(tmp_path, capsys):
    from raysim.cli import main

    path = _write_3mf_mm(tmp_path / "plate.3mf")
    # the user says the numbers are tenths of a millimetre: a 4 mm plate, 40 dB less
    assert main(["rcs", str(path), "--az-deg", "0", "--el-deg", "0", "--json",
                 "--max-bounces", "1", "--no-progress", "--scale", "0.0001"]) == 0
    got = json.loads(capsys.readouterr().out)["rcs_dbsm"][0][0]
    assert abs(got - 10 * math.log10(T.plate_rcs(SIDE_M / 10, LAM))) < CLOSED_FORM_DB


def test_scene_mesh_in_millimetres_is_placed_in_metres(tmp_path):
    import trimesh

    path = _write_3mf_mm(tmp_path / "plate.3mf")
    out = convert_meshes([UserMesh(file=path, material="metal")], tmp_path / "scene")
    assert any("declares its unit" in n for n in out.notes)
    ply = next((tmp_path / "scene" / "meshes").glob("*.ply"))
    extents = trimesh.load(ply, process=False).extents
    np.testing.assert_allclose(sorted(extents)[1:], [SIDE_M, SIDE_M], rtol=1e-6)


def test_unreadable_files_name_the_file_and_what_was_expected(tmp_path, monkeypatch):
    import trimesh

    bad = tmp_path / "car.glb"
    bad.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(ValueError, match=r"car\.glb' is not a readable mesh"):
        read_mesh_file(bad)
    step = tmp_path / "car.step"
    step.write_text("ISO-10303-21;\n")
    with pytest.raises(ValueError, match=r"expected one of .*\.3mf, \.dae, got suffix '\.step'"):
        read_mesh_file(step)
    with pytest.raises(ValueError, match="does not exist"):
        read_mesh_file(tmp_path / "missing.ply")

    def needs_a_package(*args, **kwargs):
        raise ImportError("missing `pip install pycollada`")

    dae = _write_dae_cm(tmp_path / "plate.dae")
    monkeypatch.setattr(trimesh, "load", needs_a_package)
    with pytest.raises(ValueError, match=r"plate\.dae': its reader needs a package .*pycollada"):
        read_mesh_file(dae)


def test_declared_scale_refuses_a_unit_it_does_not_know(tmp_path):
    class Loaded:
        units = "cubits of the realm"

    with pytest.raises(ValueError, match="declares the unit 'cubits of the realm'"):
        declared_scale(Loaded(), tmp_path / "x.3mf")
    assert declared_scale(_plate(1.0), tmp_path / "x.stl") == (None, None)


def test_the_scene_report_places_a_millimetre_mesh_in_metres(tmp_path):
    """The scene report's placement and coverage boxes read the same unit the scene does."""
    from raysim.scenario import load_scenario
    from raysim.studies.scene_report.meshes import mesh_boxes

    _write_3mf_mm(tmp_path / "plate.3mf")
    (tmp_path / "s.toml").write_text(
        'name = "plate"\n[[scene.meshes]]\nfile = "plate.3mf"\nmaterial = "metal"\n'
        "position_m = [10.0, 0.0, 0.0]\n")
    (box,) = mesh_boxes(load_scenario(tmp_path / "s.toml"))
    size = np.asarray(box["upper_m"]) - np.asarray(box["lower_m"])
    np.testing.assert_allclose(sorted(size)[1:], [SIDE_M, SIDE_M], rtol=1e-6)
    np.testing.assert_allclose(box["centre_m"], [10.0, 0.0, 0.0], atol=SIDE_M)


def test_a_z_up_cad_mesh_faces_the_radar_where_its_nose_points(tmp_path, capsys):
    """A plate facing +x (the nose of a CAD frame, z up): at normal incidence from az 0
    with ``--up z``, from az 90 in the file's own (y-up) frame, where +x is left."""
    import trimesh

    from raysim.cli import main

    plate = T.square_plate(SIDE_M)            # in the xy plane, facing +z
    turned = plate.vertices @ np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]]).T
    path = tmp_path / "nose.stl"
    trimesh.Trimesh(turned, plate.faces, process=False).export(path)
    peak = 10 * math.log10(T.plate_rcs(SIDE_M, LAM))
    got = {}
    for up, az in (("z", "0"), ("y", "90")):
        assert main(["rcs", str(path), "--up", up, "--az-deg", az, "--el-deg", "0", "--json",
                     "--max-bounces", "1", "--no-progress"]) == 0
        got[up] = json.loads(capsys.readouterr().out)["rcs_dbsm"][0][0]
    assert abs(got["z"] - peak) < CLOSED_FORM_DB and abs(got["y"] - peak) < CLOSED_FORM_DB
    assert main(["rcs", "plate:0.1", "--up", "z", "--az-deg", "0", "--el-deg", "0"]) == 2
    assert "--up applies to a mesh file" in capsys.readouterr().err


def test_a_file_without_a_unit_is_said_to_be_read_as_metres_with_its_size(tmp_path):
    """STL, OBJ, PLY and OFF state no unit: the scene says it read metres and how large
    the mesh then is, so a 40 mm part read as 40 m shows at once."""
    path = tmp_path / "part.stl"
    path.write_bytes(_plate(1000.0).export(file_type="stl"))      # drawn in mm, 40 units
    out = convert_meshes([UserMesh(file=path, material="metal")], tmp_path / "scene")
    said = [n for n in out.notes if "declares no unit" in n]
    assert len(said) == 1 and "read as metres, 40 x 40 x 0 m across" in said[0], out.notes
    mm = convert_meshes([UserMesh(file=path, material="metal", scale=0.001)], tmp_path / "mm")
    assert not any("declares no unit" in n for n in mm.notes)


def test_a_missing_texture_is_not_logged_as_a_crash(tmp_path, caplog):
    """A radar uses no texture: trimesh's traceback for a missing image file is dropped
    while a file is read; its other log records still reach the user."""
    import logging

    from raysim.io.mesh_files import _appearance_logs_dropped

    text = _plate(1.0).export(file_type="ply", encoding="ascii").decode()
    head, body = text.split("end_header\n", 1)
    path = tmp_path / "textured.ply"
    path.write_text(head.replace("element vertex", "comment TextureFile missing.jpg\n"
                                 "element vertex", 1) + "end_header\n" + body)
    with caplog.at_level(logging.DEBUG):
        assert len(read_mesh_file(path).faces) == 2
        assert not [r for r in caplog.records if r.levelno >= logging.WARNING]
        with _appearance_logs_dropped():
            logging.getLogger("trimesh.util").warning("unable to load image!")
            logging.getLogger("trimesh.util").warning("face indices out of range")
    assert [r.getMessage() for r in caplog.records
            if r.levelno >= logging.WARNING] == ["face indices out of range"]
