"""Fidelity ladder of geometry targets: point, reduced centres, mesh (raysim.echoes.po.fidelity).

Closed forms: a point moved by ``d`` along the line of sight, its amplitude
re-referred at the sweep's centre frequency, leaves the phase ramp
``phi(t) = 2 pi (2 mu d / c)(t - T / 2)`` over the sweep, whose relative l2 error
is ``sqrt(mean |exp(j phi) - 1|^2) = sqrt(mean 4 sin^2(phi / 2))``; a triangular
trihedral on its axis has ``sigma = 4 pi a^4 / (3 lambda^2)`` (Knott, Shaeffer &
Tuley, *Radar Cross Section*, 2nd ed., table 6.1).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.radar.arrays import upa
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig

pytestmark = pytest.mark.sionna

#: Tolerance of the ladder in these tests (its default).
TOLERANCE = 0.05
#: First-order prediction vs the closed-form error of a moved point, relative.
PREDICTION_TOL = 0.05
#: Direct-sum check vs the closed-form phase-ramp error, relative.
RAMP_TOL = 0.01
#: Point level of a trihedral vs Knott's closed form [dB] (as for its terms, 0.5 dB).
RCS_TOL_DB = 0.5


def _facing(mesh, distance: float):
    """``mesh`` (boresight +z) turned to face a radar at the origin from ``(0, 0, distance)``."""
    from raysim.echoes.po.mesh import TriangleMesh

    v = mesh.vertices * np.array([1.0, 1.0, -1.0]) + [0.0, 0.0, distance]
    return TriangleMesh(v, mesh.faces[:, ::-1])


def _mesh_centres(mesh, distance: float, config: RadarConfig):
    from raysim.echoes.po.paths import cluster_terms, scattering_terms

    ref = np.array([0.0, 0.0, distance])
    terms = scattering_terms(_facing(mesh, distance), "metal", np.zeros(3), ref,
                             frequency=config.carrier_frequency)
    centre, amp, _ = cluster_terms(terms, config.range_resolution)
    return centre, amp, terms


def test_point_moved_along_the_line_of_sight_matches_closed_form():
    """One centre re-referred to a point ``d`` farther: the check's error is the phase ramp's
    closed form, and the first-order prediction ``2 pi d / (dR sqrt 12)`` agrees."""
    from raysim.echoes.po.fidelity import check_echo, predicted_error

    config = RadarConfig()
    array = upa(4, 4, wavelength=config.wavelength)
    d_r = config.range_resolution
    radar = np.zeros(3)
    centre = np.array([[0.0, 0.0, 10.0]])
    moved = centre + [0.0, 0.0, 0.02 * d_r]
    amp = np.array([1.0 + 0.5j])
    # re-referred as the ladder merges: same echo at the centre frequency
    k = 2 * math.pi / config.center_wavelength
    a_moved = amp * np.exp(1j * k * 2 * (np.linalg.norm(centre) - np.linalg.norm(moved)))
    ref = check_echo(centre, amp, radar, np.eye(3), config, array)
    e = (np.linalg.norm(check_echo(moved, a_moved, radar, np.eye(3), config, array) - ref)
         / np.linalg.norm(ref))
    t = config.fast_time()
    tau_d = 2 * 0.02 * d_r / SPEED_OF_LIGHT
    phi = 2 * math.pi * config.chirp_rate * tau_d * (t - config.chirp_duration / 2)
    closed = math.sqrt(np.mean(4 * np.sin(phi / 2) ** 2))
    assert abs(e / closed - 1) < RAMP_TOL, (e, closed)
    pred = predicted_error(centre, amp, moved, np.array([0]), range_cell=d_r, cross_cell=1.0,
                           radar_w=radar)
    assert abs(pred / closed - 1) < PREDICTION_TOL, (pred, closed)


def test_far_point_like_object_gets_the_point_with_its_rcs(rt_backend):
    """A 0.1 m trihedral at 40 m (one cell) gets the point level, within the tolerance of its
    mesh, carrying Knott's closed-form RCS."""
    from raysim.echoes.po.fidelity import choose_level
    from raysim.echoes.po.targets import trihedral, trihedral_rcs

    config = RadarConfig()
    array = upa(8, 8, wavelength=config.wavelength)
    centre, amp, terms = _mesh_centres(trihedral(0.1), 40.0, config)
    point, a, choice = choose_level("tri", centre, amp, np.zeros(3), np.eye(3), config, array,
                                    tolerance=TOLERANCE, range_m=terms.range_m)
    assert choice.level == "point" and choice.predicted_level == "point"
    assert choice.measured_error["point"] <= TOLERANCE
    assert point.shape == (1, 3)
    rcs = 4 * math.pi * abs(a[0]) ** 2
    assert abs(10 * math.log10(rcs / trihedral_rcs(0.1, config.wavelength))) < RCS_TOL_DB


def test_near_extended_object_gets_the_mesh_and_every_choice_is_within_tolerance(rt_backend):
    """A 1 m plate at 5 m (many cross-range cells, coherent facets) keeps its mesh; on a small
    set of objects every chosen level's echo is within the tolerance of the mesh level, checked
    again on every channel of the array (the choice saw 16)."""
    from raysim.echoes.po.fidelity import check_echo, choose_level
    from raysim.echoes.po.targets import dihedral, square_plate, trihedral

    config = RadarConfig()
    array = upa(8, 8, wavelength=config.wavelength)
    every = np.arange(array.num_channels)
    objects = {"plate": (square_plate(1.0), 5.0), "dihedral": (dihedral(0.3, 0.2), 10.0),
               "trihedral": (trihedral(0.1), 40.0)}
    chosen = {}
    for name, (mesh, distance) in objects.items():
        centre, amp, terms = _mesh_centres(mesh, distance, config)
        point, a, choice = choose_level(name, centre, amp, np.zeros(3), np.eye(3), config,
                                        array, tolerance=TOLERANCE, range_m=terms.range_m)
        chosen[name] = choice.level
        ref = check_echo(centre, amp, np.zeros(3), np.eye(3), config, array, every)
        err = np.linalg.norm(check_echo(point, a, np.zeros(3), np.eye(3), config, array, every)
                             - ref) / np.linalg.norm(ref)
        assert err <= TOLERANCE, (name, choice.level, err)
        assert choice.measured_error[choice.level] <= TOLERANCE
    assert chosen["plate"] == "mesh"
    assert chosen["trihedral"] == "point"
    assert chosen["dihedral"] != "mesh"       # 0.3 m at 10 m: within one range cell


def test_forced_mesh_is_todays_render_and_auto_reuses_its_models(warm_kernels):
    """``fidelity="mesh"`` renders bit-identically to no setting; ``"auto"`` records one choice
    per geometry target, each within the tolerance, and a second frame from the same pose
    re-uses them (no PO trace) with an identical cube."""
    from raysim.echoes.po.fidelity import FidelityLadder
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    config = RadarConfig(num_chirps=4)
    array = upa(4, 4, wavelength=config.wavelength)
    scene = load_scene("flat_reflectors", frequency=config.carrier_frequency)
    tracer = MonostaticTracer(max_depth=1, samples_per_src=2000, diffuse=False)
    kw = {"tracer": tracer, "clutter": "none", "decimate": "off"}
    today = render_scene(scene, config, array, **kw)
    forced = render_scene(scene, config, array, fidelity="mesh", **kw)
    assert np.array_equal(today.data, forced.data)
    assert forced.truth["fidelity"] == []
    ladder = FidelityLadder(array, "auto", TOLERANCE)
    first = render_scene(scene, config, array, fidelity=ladder, **kw)
    names = {t.name for t in scene.targets if t.is_geometry}
    assert {c["name"] for c in first.truth["fidelity"]} == names
    assert all(c["measured_error"][c["level"]] <= TOLERANCE and not c["reused"]
               for c in first.truth["fidelity"])
    second = render_scene(scene, config, array, fidelity=ladder, **kw)
    reduced = {c["name"] for c in first.truth["fidelity"] if c["level"] != "mesh"}
    assert reduced, "no object was reduced"
    assert {c["name"] for c in second.truth["fidelity"] if c["reused"]} == reduced
    assert np.array_equal(first.data, second.data)


def test_bad_fidelity_settings_are_refused(rt_backend):
    from raysim.echoes.po.fidelity import FidelityLadder, resolve_fidelity

    array = upa(2, 2, wavelength=RadarConfig().wavelength)
    with pytest.raises(ValueError, match="fidelity must be one of"):
        FidelityLadder(array, "fine")
    with pytest.raises(ValueError, match="fidelity_tolerance"):
        FidelityLadder(array, "auto", -0.1)
    with pytest.raises(ValueError, match="reuse_distance"):
        FidelityLadder(array, "auto", 0.05, float("nan"))
    with pytest.raises(ValueError, match="fidelity must be one of"):
        resolve_fidelity("coarse", array)
    assert resolve_fidelity("mesh", array) is None


def test_scenario_key_takes_the_ladder_modes():
    """``[scene] fidelity`` accepts exactly the ladder's modes; a bad value names the key."""
    import typing

    from raysim.echoes.po.fidelity import DEFAULT_FIDELITY_TOLERANCE, FIDELITY_MODES
    from raysim.scenario.model import SceneSection

    field = SceneSection.model_fields["fidelity"]
    assert set(typing.get_args(field.annotation)) == set(FIDELITY_MODES)
    assert field.default == "mesh"
    assert SceneSection.model_fields["fidelity_tolerance"].default == DEFAULT_FIDELITY_TOLERANCE
    with pytest.raises(ValueError, match="fidelity"):
        SceneSection(name="parking_lot", fidelity="fine")


def test_scene_report_lists_the_choice_per_object(tmp_path, warm_kernels):
    """``fidelity = "auto"``: the report's JSON and report.md give each reflector's level,
    its predicted and measured errors (within the tolerance) and its times."""
    import json

    from raysim.studies import scene_report as sr

    tiny = sr.QUICK.with_values(num_chirps=16, array_size=4, samples_per_src=2000,
                                grid_step_deg=12.0, range_window=(14.0, 20.0),
                                fidelity="auto", fidelity_tolerance=TOLERANCE)
    sr.write_scene_report(tmp_path, scenes=["flat_reflectors"], settings=tiny, progress=False)
    data = json.loads((tmp_path / "summary.json").read_text())["flat_reflectors"]
    assert data["settings"]["fidelity"] == "auto"
    assert len(data["fidelity"]) == 4
    for c in data["fidelity"]:
        assert c["level"] in ("point", "centres", "mesh")
        assert c["measured_error"][c["level"]] <= TOLERANCE
        assert c["trace_seconds"] > 0 and c["choice_seconds"] > 0
    text = (tmp_path / "report.md").read_text()
    assert "Echo model per geometry target" in text
    assert all(c["name"] in text for c in data["fidelity"])


def test_speed_chart_panel_of_the_ladder(warm_kernels):
    """The chart's fidelity panel on a small frame of ``flat_reflectors``: four settings, the
    mesh the reference, no reduced setting with more paths, and "auto" within the
    tolerance on the whole targets' cube (each object's echo is, and the reflectors'
    echoes, apart in range and angle, are nearly orthogonal)."""
    from raysim.bench.fidelity_ladder import fidelity_ladder_points

    rows = fidelity_ladder_points(quick=True, scene="flat_reflectors", num_chirps=4,
                                  array_size=4, tolerance=TOLERANCE)
    by = {r["setting"]: r for r in rows}
    assert list(by) == ["point", "centres", "auto", "mesh"]
    assert by["mesh"]["reference"] and by["mesh"]["rel_error"] == 0.0
    assert by["auto"]["rel_error"] <= TOLERANCE
    assert by["point"]["paths"] <= by["centres"]["paths"] <= by["mesh"]["paths"]
    assert sum(by["auto"]["levels"].values()) == 4
    assert all(r["s_per_frame"] > 0 and r["first_s"] > 0 for r in rows)
