"""`raysim scenes describe` gives positions in one frame: W (NED), that of [[scene.meshes]]."""

from __future__ import annotations

import json

import numpy as np
import pytest

from raysim.cli import main


def test_describe_prints_world_ned_positions_and_names_the_frame(capsys):
    scenes = pytest.importorskip("raysim.echoes.rt.scenes")
    assert main(["scenes", "describe", "flat_reflectors"]) == 0
    out = capsys.readouterr().out
    assert "positions: world frame W, NED" in out and "[[scene.meshes]]" in out
    assert "ENU" not in out
    # cr-east sits 8 m east and 2 m north of nadir on the ground, 15 m below the hover point
    assert "target cr-east: position (north, east, down) (2.00, 8.00, 15.00) m" in out
    assert main(["scenes", "describe", "flat_reflectors", "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["frame"].startswith("world frame W, NED")
    meta = scenes.get_scene("flat_reflectors").metadata()
    for t, raw in zip(info["targets"], meta["targets"], strict=True):
        e, n, u = raw["position"]
        np.testing.assert_allclose(t["position_m"], [n, e, meta["hover_altitude"] - u])
        assert "position" not in t
