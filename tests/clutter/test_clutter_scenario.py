"""Scenario keys of the clutter: ``[scene.clutter]`` reaches the frame source's SceneClutter."""

from __future__ import annotations

import pytest

from raysim.scenario import loads_scenario

SCENE = '[scene]\nname = "flat_reflectors"\n'


def test_clutter_section_defaults_and_values():
    from raysim.pipeline.sources import _clutter

    default = loads_scenario(SCENE)
    assert default.scene.clutter.mode == "field" and default.scene.clutter.ghosts
    sc = loads_scenario(SCENE + "[scene.clutter]\nper_cell = 4.0\nreuse_m = 1.5\nghosts = false\n")
    model = _clutter(sc)
    assert model.settings.scatterers_per_cell == 4.0
    assert model.settings.reuse_distance == 1.5
    assert model.settings.seed == sc.seed and not model.ghosts
    assert _clutter(loads_scenario(SCENE + '[scene.clutter]\nmode = "sionna"\n')) == "sionna"


@pytest.mark.parametrize("line, match", [('mode = "lambert"', "scene.clutter.mode"),
                                         ("per_cell = -1", "scene.clutter.per_cell"),
                                         ("reuse = 2", "reuse_m")])
def test_clutter_section_bad_values(line, match):
    with pytest.raises(ValueError, match=match):
        loads_scenario(SCENE + f"[scene.clutter]\n{line}\n")
