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


def test_wind_and_polarisation_keys_reach_the_field():
    """``[scene.clutter] wind_mps``, ``vegetation`` and ``[radar] polarisation`` set the field."""
    from raysim.pipeline.sources import _clutter

    default = _clutter(loads_scenario(SCENE))
    assert default.settings.wind_mps == 0.0 and default.settings.polarisation == "VV"
    sc = loads_scenario('[radar]\npolarisation = "HV"\n' + SCENE
                        + '[scene.clutter]\nwind_mps = 4.0\nvegetation = ["dry-soil"]\n')
    s = _clutter(sc).settings
    assert (s.wind_mps, s.vegetation, s.polarisation) == (4.0, ("dry-soil",), "HV")


@pytest.mark.parametrize("text, match", [
    (SCENE + "[scene.clutter]\nwind_mps = 0.1\n", "0.224 m/s"),
    (SCENE + "[scene.clutter]\nwind_mps = 40\n", "wind_mps"),
    (SCENE + '[scene.clutter]\nwind_mps = 3\nmode = "sionna"\n', "mode = 'field'"),
    ('[radar]\npolarisation = "VH"\n' + SCENE, "polarisation"),
    ('[radar]\npolarisation = "HH"\n[[scene.targets]]\nrange_m = 5.0\n', "polarisation")])
def test_wind_and_polarisation_bad_values(text, match):
    with pytest.raises(ValueError, match=match):
        loads_scenario(text)
