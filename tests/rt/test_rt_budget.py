"""Trace budget: pruning, ray count and depth from the scene geometry."""

from __future__ import annotations

import math
import shutil
import time

import numpy as np
import pytest

from raysim.echoes.rt.trace_plan import MAX_SAMPLES, MIN_SAMPLES, plan_trace
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

CFG = RadarConfig(num_chirps=8)
ARR = upa(4, 4, wavelength=CFG.wavelength)


def test_plans_of_bundled_scenes_are_deterministic_and_sensible():
    depths = {}
    for name in ("flat_reflectors", "parking_lot", "rough_terrain"):
        a, b = plan_trace(name, CFG, ARR), plan_trace(name, CFG, ARR)
        assert a.summary() == b.summary()
        assert a.samples_per_src == b.samples_per_src
        assert MIN_SAMPLES <= a.samples_per_src <= MAX_SAMPLES
        assert a.dropped_triangles < a.num_triangles
        # the pruning cone is where the default patch element's gain is 40 dB down
        assert a.fov_half_angle == CFG.pattern.cull_angle(a.pattern_floor_db)
        assert name in a.summary() and "max_depth" in a.summary()
        depths[name] = a.max_depth
    assert depths == {"flat_reflectors": 1, "parking_lot": 2, "rough_terrain": 1}


def _scene_with_extras(tmp_path):
    """flat_reflectors plus a box 150 m away and a sheet above the radar."""
    import trimesh

    from raysim.echoes.rt.scenes import FLAT_REFLECTORS

    src = FLAT_REFLECTORS.path.parent
    shutil.copytree(src / "meshes", tmp_path / "meshes")
    far = trimesh.creation.box((2.0, 2.0, 2.0))
    far.apply_translation((150.0, 0.0, 1.0))          # S: 150 m east, beyond 90 m
    far.export(tmp_path / "meshes" / "far.ply")
    above = trimesh.creation.box((4.0, 4.0, 0.2))
    above.apply_translation((0.0, 0.0, 25.0))        # S: 10 m above the radar (behind it)
    above.export(tmp_path / "meshes" / "above.ply")
    shutil.copy(FLAT_REFLECTORS.sidecar, tmp_path / "extras.json")   # marks geometry targets
    xml = FLAT_REFLECTORS.path.read_text()
    extra = "".join(
        f'    <shape type="ply" id="mesh-{n}">\n'
        f'        <string name="filename" value="meshes/{n}.ply"/>\n'
        f'        <boolean name="face_normals" value="true"/>\n'
        f'        <ref id="dry-soil" name="bsdf"/>\n    </shape>\n' for n in ("far", "above"))
    path = tmp_path / "extras.xml"
    path.write_text(xml.replace("</scene>", extra + "</scene>"))
    return path


def test_objects_beyond_range_or_behind_fov_are_dropped(tmp_path):
    plan = plan_trace(_scene_with_extras(tmp_path), CFG, ARR, hover_altitude=15.0)
    far, above, ground = plan.shape("far"), plan.shape("above"), plan.shape("ground")
    assert far.removed and far.range_triangles == far.num_triangles == 12
    assert above.removed and above.fov_triangles == above.num_triangles
    assert math.isclose(far.range_area, 24.0, rel_tol=1e-9)
    assert not ground.removed
    assert set(plan.removed_shapes) == {"far", "above"}
    text = plan.summary()
    assert "far: removed" in text and "beyond 89.9 m" in text
    assert "above: removed" in text and "outside the 84 deg cone" in text
    # past the range window the box (84 deg off nadir) still leaves a 70 deg cone ...
    wide = plan_trace(tmp_path / "extras.xml", CFG, ARR, hover_altitude=15.0, max_range=200.0,
                      fov_half_angle=math.radians(70.0))
    assert wide.shape("far").fov_triangles == 12 and wide.shape("far").range_triangles == 0
    # ... and a wider cone keeps it
    assert not plan_trace(tmp_path / "extras.xml", CFG, ARR, hover_altitude=15.0,
                          max_range=200.0, fov_half_angle=math.radians(89.0)).shape("far").removed


def test_sample_count_scales_with_illuminated_area():
    plans = [plan_trace("flat_reflectors", CFG, ARR, fov_half_angle=math.radians(a))
             for a in (20.0, 40.0, 60.0)]
    areas = [p.illuminated_area for p in plans]
    samples = [p.samples_uncapped for p in plans]
    assert areas[0] < areas[1] < areas[2]
    assert samples[0] < samples[1] < samples[2]
    double = plan_trace("flat_reflectors", CFG, ARR, rays_per_cell=8.0)
    single = plan_trace("flat_reflectors", CFG, ARR, rays_per_cell=4.0)
    assert abs(double.samples_uncapped / single.samples_uncapped - 2.0) < 1e-3
    finer = plan_trace("flat_reflectors", CFG, upa(8, 8, wavelength=CFG.wavelength))
    assert finer.samples_uncapped > single.samples_uncapped   # smaller cells, more rays


@pytest.mark.parametrize("kw, match", [
    ({"fov_half_angle": 0.0}, "fov_half_angle"),
    ({"rays_per_cell": -1.0}, "rays_per_cell"),
    ({"margin": -0.1}, "margin"),
    ({"radar_position_w": (0.0, 1.0)}, "radar_position_w"),
    ({"max_range": 0.0}, "max_range"),
    ({"boresight_w": (0.0, 0.0, 0.0)}, "boresight_w"),
])
def test_bad_input_is_named(kw, match):
    with pytest.raises(ValueError, match=match):
        plan_trace("flat_reflectors", CFG, ARR, **kw)


def _targets(ps):
    from raysim.echoes.po.paths import PO_CENTRE
    from raysim.echoes.rt.trace import SENSING

    m = (ps.kind & (SENSING | PO_CENTRE)) != 0
    return ps.length[m], np.abs(ps.amplitude[m])


@pytest.mark.sionna
def test_planned_trace_keeps_reflector_returns_with_fewer_rays(warm_kernels, tmp_path):
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    scene = load_scene("flat_reflectors", frequency=CFG.carrier_frequency)
    planned = MonostaticTracer.for_scene(scene, CFG, ARR)
    full = MonostaticTracer(max_depth=planned.max_depth)
    assert planned.max_depth == 1 and planned.samples_per_src < full.samples_per_src
    planned(scene, CFG), full(scene, CFG)                    # pruned copy loaded, warm
    t_full, t_plan = [], []
    for _ in range(3):
        t0 = time.perf_counter()
        ref = full(scene, CFG)
        t_full.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        got = planned(scene, CFG)
        t_plan.append(time.perf_counter() - t0)
    (l_ref, a_ref), (l_got, a_got) = _targets(ref), _targets(got)
    # the same centres in both: four trihedral apexes, weak rim centres of the two larger
    # ones and their ground-multipath centres (the count of the weak ones is the engine's)
    assert l_ref.size == l_got.size >= 4
    np.testing.assert_allclose(l_got, l_ref, atol=1e-6)
    assert np.max(np.abs(20 * np.log10(a_got / a_ref))) < 0.5
    # ground clutter is still sampled (fewer rays give proportionally fewer paths)
    assert np.count_nonzero(got.kind == 2) > 0.2 * np.count_nonzero(ref.kind == 2)
    print(f"rays {full.samples_per_src} -> {planned.samples_per_src}, "
          f"time {min(t_full) * 1e3:.1f} -> {min(t_plan) * 1e3:.1f} ms")


@pytest.mark.sionna
def test_pruned_scene_drops_far_shape(warm_kernels, tmp_path):
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    path = _scene_with_extras(tmp_path)
    scene = load_scene(path, frequency=CFG.carrier_frequency, hover_altitude=15.0,
                       targets=[])
    tracer = MonostaticTracer.for_scene(scene, CFG, ARR, samples_per_src=5000)
    pruned = tracer.plan.prune(scene)
    assert set(scene.sionna_scene.objects) == {"ground", "far", "above"}
    assert set(pruned.sionna_scene.objects) == {"ground"}
    assert tracer.plan.prune(scene) is pruned                 # cached
    ps = tracer(scene, CFG)
    assert ps.num_paths > 0 and tracer.samples_per_src == 5000
