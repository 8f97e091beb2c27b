"""The scene report's maps cover every object of a scenario: the default range window and
angle grid widen to hold each mesh and point target, a user's own are kept, and what lies
beyond the radar's reach stays named."""

from __future__ import annotations

import math

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from raysim.measure.scene import GRID_HALF_WIDTH_DEG, RANGE_WINDOW_M  # noqa: E402
from raysim.scenario import load_scenario  # noqa: E402
from raysim.studies.scene_report import QUICK  # noqa: E402
from raysim.studies.scene_report.coverage import (  # noqa: E402
    COVER_MARGIN_DEG,
    COVER_MARGIN_M,
    MAX_GRID_HALF_WIDTH_DEG,
    covering_extents,
    object_spans,
)
from raysim.studies.scene_report.meshes import mesh_boxes, mesh_targets  # noqa: E402

#: A ground 15 m below the radar and a 2 m metal block 48 m north, 15 m down: range
#: sqrt(47^2 + 14^2) ~ 49 m and azimuth atan(47 / 14) ~ 73 deg at its nearest face,
#: beyond the default window (12-45 m) and grid (+-60 deg).
FAR_BLOCK = """
name = "far block"
lever_arm_m = [0.0, 0.0, 0.1]

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
file = "block.obj"
material = "metal"
position_m = [{north}, 0.0, 14.0]
closed = true
"""


def _scenario(tmp_path, north=48.0):
    trimesh.creation.box((20.0, 20.0, 0.2)).export(tmp_path / "ground.ply")
    trimesh.creation.box((2.0, 2.0, 2.0)).export(tmp_path / "block.obj")
    (tmp_path / "s.toml").write_text(FAR_BLOCK.format(north=north), encoding="utf-8")
    return load_scenario(tmp_path / "s.toml")


def _on_maps(marker, st) -> bool:
    lo, hi = st.range_window
    w = st.grid_half_width_deg
    return lo <= marker["range_m"] <= hi and abs(marker["az_deg"]) <= w \
        and abs(marker["el_deg"]) <= w


def test_default_extents_widen_to_hold_a_far_mesh(tmp_path):
    s = _scenario(tmp_path)
    markers = {m["name"]: m for m in mesh_targets(mesh_boxes(s), s.lever_arm_m)}
    block = markers["block.obj"]
    # off the default maps: too far and too wide
    assert block["range_m"] > RANGE_WINDOW_M[1] and abs(block["az_deg"]) > GRID_HALF_WIDTH_DEG
    st = QUICK.for_scenario(s)
    assert all(_on_maps(m, st) for m in markers.values())
    # the whole placed box is on the maps, with the margin, in whole grid steps
    spans = {o["name"]: o for o in object_spans(s)}
    corners = np.array([[47.0, -1.0, 13.0], [49.0, 1.0, 15.0]]) - np.asarray(s.lever_arm_m)
    far = float(np.max(np.linalg.norm(np.array(
        [[x, y, z] for x in corners[:, 0] for y in corners[:, 1] for z in corners[:, 2]]),
        axis=1)))
    assert spans["block.obj"]["range_m"][1] == pytest.approx(far, rel=1e-9)
    assert st.range_window[1] == pytest.approx(far + COVER_MARGIN_M, rel=1e-9)
    widest = max(abs(v) for o in spans.values() for v in (*o["az_deg"], *o["el_deg"]))
    assert st.grid_half_width_deg >= widest + COVER_MARGIN_DEG
    assert st.grid_half_width_deg - QUICK.grid_step_deg < widest + COVER_MARGIN_DEG
    n = st.grid_half_width_deg / QUICK.grid_step_deg
    assert n == round(n)
    assert st.range_window[0] == RANGE_WINDOW_M[0]          # nothing nearer: kept


def test_azimuth_span_of_a_box_matches_its_closed_form(tmp_path):
    """The block's azimuth runs from atan((47 - 0) / (15 - 0.1)) at its bottom-near edge
    to atan(49 / (13 - 0.1)) at its top-far edge: az = atan2(north, down) from the
    phase centre 0.1 m below the hover point (u_z towards nadir)."""
    spans = {o["name"]: o for o in object_spans(_scenario(tmp_path))}
    lo, hi = spans["block.obj"]["az_deg"]
    assert lo == pytest.approx(math.degrees(math.atan2(47.0, 14.9)), abs=1e-9)
    assert hi == pytest.approx(math.degrees(math.atan2(49.0, 12.9)), abs=1e-9)


def test_user_window_and_grid_are_kept(tmp_path):
    s = _scenario(tmp_path)
    st = QUICK.with_values(range_window=(5.0, 30.0), grid_half_width_deg=42.0).for_scenario(s)
    assert st.range_window == (5.0, 30.0) and st.grid_half_width_deg == 42.0
    # only the default one of the two widens
    st = QUICK.with_values(range_window=(5.0, 30.0)).for_scenario(s)
    assert st.range_window == (5.0, 30.0) and st.grid_half_width_deg > GRID_HALF_WIDTH_DEG


def test_what_lies_beyond_the_radar_stays_named(tmp_path):
    s = _scenario(tmp_path, north=120.0)         # beyond the 90 m unambiguous range
    cfg = s.radar_config()
    top = cfg.max_range - 2 * cfg.range_resolution
    got = covering_extents(object_spans(s), RANGE_WINDOW_M, GRID_HALF_WIDTH_DEG,
                           QUICK.grid_step_deg, top)
    assert got["range_window"][1] == pytest.approx(top)
    assert got["grid_half_width_deg"] <= MAX_GRID_HALF_WIDTH_DEG
    assert "block.obj" in got["beyond"] and "ground.ply" not in got["beyond"]
    st = QUICK.for_scenario(s)
    assert st.range_window[1] == pytest.approx(top)
    block = {m["name"]: m for m in mesh_targets(mesh_boxes(s), s.lever_arm_m)}["block.obj"]
    assert not _on_maps(block, st)


def test_point_targets_widen_the_window(tmp_path):
    from raysim.scenario import scenario_from_case

    s = scenario_from_case("stationary").with_values(
        {"scene.targets": [{"range_m": 8.0, "az_deg": 70.0, "el_deg": -5.0},
                           {"range_m": 15.0, "az_deg": 20.0}]})
    st = QUICK.for_scenario(s)
    assert st.range_window[0] == pytest.approx(8.0 - COVER_MARGIN_M)
    assert st.grid_half_width_deg == 72.0                 # 70 + 2 deg in 6-degree steps
    assert st.range_window[1] == RANGE_WINDOW_M[1]


def test_maps_are_sized_on_the_widened_extents(tmp_path, monkeypatch):
    """Gates and beams of the widened maps (closed form: the window's range bins, a
    (2 n + 1)^2 grid of n = half-width / step), refused before any tracing when the
    memory they need is not there."""
    import raysim.resources
    from raysim.studies.scene_report import write_scene_report
    from raysim.studies.scene_report.coverage import maps_size

    s = _scenario(tmp_path)
    st = QUICK.for_scenario(s)
    size = maps_size(st)
    n = round(st.grid_half_width_deg / st.grid_step_deg)
    assert size["beams"] == (2 * n + 1) ** 2
    lo, hi = st.range_window
    res = st.radar().range_resolution
    assert abs(size["gates"] - (hi - lo) / res) <= 1
    assert size["peak_bytes"] > maps_size(QUICK.with_values(scenario=s))["peak_bytes"]
    monkeypatch.setattr(raysim.resources, "available_memory", lambda: 1 << 20)
    with pytest.raises(ValueError, match=rf"the maps of far_block \({size['gates']} range "
                                         rf"gates x {size['beams']} beams, 16 chirps\)"):
        write_scene_report(tmp_path / "out", settings=QUICK, scenarios=[s], progress=False)
    assert not (tmp_path / "out").exists()                   # refused before writing


@pytest.mark.sionna
def test_scene_report_maps_hold_a_far_mesh(tmp_path, capsys, rt_backend):
    """Through the command: the note gives the widened window and grid, the block's marker
    lies inside them and no mesh is named as off the maps."""
    import json

    from raysim.cli import main

    _scenario(tmp_path)
    out = tmp_path / "out"
    assert main(["scene-report", "--scenario", str(tmp_path / "s.toml"), "--quick",
                 "--chains", "none", "--out", str(out), "--no-progress",
                 "--threads", "2"]) == 0
    err = capsys.readouterr().err
    data = json.loads((out / "far_block.json").read_text())
    lo, hi = data["settings"]["range_window"]
    w = data["settings"]["grid_half_width_deg"]
    assert hi > RANGE_WINDOW_M[1] and w > GRID_HALF_WIDTH_DEG
    assert (f"note: far_block: maps widened to hold every mesh and point target: range "
            f"window {lo:.1f}-{hi:.1f} m, grid +-{w:g} deg (") in err
    block = {t["name"]: t for t in data["targets"] if t.get("mesh")}["block.obj"]
    assert lo <= block["range_m"] <= hi and abs(block["az_deg"]) <= w
    assert not block["cfar"]["stationary"]["status"].startswith("outside")
    assert "off the maps" not in err


def test_known_reflectors_of_bundled_and_xml_scenes_widen_the_grid():
    """The parking lot's facade corner, 29.8 m north and 15 m down (azimuth
    atan2(29.8, 15 - 0.1) = 63.4 deg from the phase centre 0.1 m below the hover point,
    beyond the +-60 deg grid), takes the grid to +-66 deg
    (63.4 + 2 in 6-degree steps), from the bundled name or from its XML file; the
    flat_reflectors' reflectors are all within the default maps."""
    from raysim.echoes.rt.scenes import SCENES

    st = QUICK.for_scene("parking_lot")
    corner = {o["name"]: o for o in object_spans(st.scenario)}["facade-corner"]
    assert corner["az_deg"][0] == pytest.approx(math.degrees(math.atan2(29.8, 15.0 - 0.1)),
                                                abs=1e-9)
    assert st.grid_half_width_deg == 66.0 and st.range_window == RANGE_WINDOW_M
    xml = QUICK.scenario.with_values({"scene.kind": "mesh",
                                      "scene.path": str(SCENES["parking_lot"].path)})
    assert QUICK.for_scenario(xml).grid_half_width_deg == 66.0
    flat = QUICK.for_scene("flat_reflectors")
    assert flat.grid_half_width_deg == GRID_HALF_WIDTH_DEG
    assert flat.range_window == RANGE_WINDOW_M
