"""Ament factor on Sionna's specular bounces off rough ground (``MonostaticTracer.rough_bounces``).

Closed form: the coherent reflection of a Gaussian rough surface of rms height
``s`` is the smooth one times ``chi = exp(-2 (k s cos theta_i)^2)`` (Ament 1953;
Beckmann & Spizzichino 1963, eq. 5.29). The scene is built here: the radar
``H`` above a flat ground and a flat metal plate whose normal points at the
radar's image below the ground, so a ground -> plate -> ground path (normal
incidence on the plate) returns to the radar after two ground bounces at the
designed incidence ``THETA``; a second plate faces the radar (a smooth
single bounce); and the nadir mirror is a single ground bounce at 0 deg.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

#: Radar height above the ground [m].
H = 10.0
#: Incidence angle of the ground bounces of the ground-plate-ground path [rad].
THETA = math.radians(30.0)
#: Rays shot per trace (the 2 m plates are hit by tens of them).
SAMPLES = 30_000
#: On/off amplitude ratio vs the closed form [dB]: the same paths (same seed and
#: geometry) are compared, so only the factor differs; 0.05 dB covers the float32
#: vertices Sionna returns (incidence error < 1e-5 rad, < 1e-4 dB here).
RATIO_TOL_DB = 0.05
#: Largest change of a path with no rough bounce [dB] (float arithmetic only).
UNCHANGED_TOL_DB = 1e-6


def _plate(centre, normal, size=2.0):
    """Square of ``size`` [m] centred at ``centre`` (S) facing ``normal``, two triangles."""
    import trimesh

    n = np.asarray(normal, float) / np.linalg.norm(normal)
    u = np.cross(n, [0.0, 1.0, 0.0] if abs(n[1]) < 0.9 else [1.0, 0.0, 0.0])
    u /= np.linalg.norm(u)
    v = np.cross(n, u)
    h = size / 2
    corners = np.asarray(centre) + h * np.array([-u - v, u - v, u + v, -u + v])
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    if np.dot(np.cross(corners[1] - corners[0], corners[2] - corners[0]), n) < 0:
        faces = faces[:, ::-1]
    return trimesh.Trimesh(corners, faces, process=False)


def _write_scene(folder, ground_material):
    """Ground (``ground_material``) + two metal plates, frame S (ENU); returns the XML path."""
    from raysim.echoes.rt.scenes import MATERIALS, METAL

    folder.mkdir(parents=True, exist_ok=True)
    d = H * math.tan(THETA)
    up = np.array([math.sin(THETA), 0.0, math.cos(THETA)])   # leg after the ground bounce
    radar = np.array([0.0, 0.0, H])
    facing = np.array([-6.0, 4.0, 5.0])
    shapes = {"ground": (_plate([0.0, 0.0, 0.0], [0, 0, 1], 60.0), MATERIALS[ground_material]),
              "tilted": (_plate(np.array([d, 0.0, 0.0]) + 6.0 * up, -up), METAL),
              "facing": (_plate(facing, radar - facing), METAL)}
    xml = ['<scene version="2.1.0">\n']
    xml += [m.to_xml() for m in {m.name: m for _, m in shapes.values()}.values()]
    for name, (mesh, mat) in shapes.items():
        (folder / f"{name}.ply").write_bytes(mesh.export(file_type="ply", encoding="binary"))
        xml.append(f'    <shape type="ply" id="mesh-{name}">\n'
                   f'        <string name="filename" value="{name}.ply"/>\n'
                   f'        <boolean name="face_normals" value="true"/>\n'
                   f'        <ref id="{mat.name}" name="bsdf"/>\n    </shape>\n')
    path = folder / "scene.xml"
    path.write_text("".join(xml) + "</scene>\n")
    return path


def _chi(theta: float, rms_height: float, wavelength: float) -> float:
    """Ament amplitude factor, Beckmann & Spizzichino 1963 eq. 5.29 (written out here)."""
    k = 2 * math.pi / wavelength
    return math.exp(-2.0 * (k * rms_height * math.cos(theta)) ** 2)


def _trace(scene, config, rough):
    from raysim.echoes.rt.trace import MonostaticTracer

    return MonostaticTracer(samples_per_src=SAMPLES, max_depth=3, diffuse=False, targets=False,
                            pattern_floor_db=-math.inf, rough_bounces=rough)(scene, config)


def _by_kind(paths):
    """Index of the nadir mirror, the ground-plate-ground path and the facing plate's path."""
    length = {"nadir": 2 * H,
              "gpg": 2 * (H / math.cos(THETA) + 6.0),
              "facing": 2 * float(np.linalg.norm([-6.0, 4.0, 5.0 - H]))}
    out = {}
    for name, ell in length.items():
        i = np.flatnonzero(np.abs(paths.length - ell) < 1e-3)
        assert len(i) == 1, (name, ell, np.sort(paths.length))
        out[name] = int(i[0])
    assert paths.depth[out["gpg"]] == 3 and paths.depth[out["nadir"]] == 1
    return out


@pytest.fixture(scope="module")
def traced(warm_kernels, rt_radar, tmp_path_factory):
    """``{ground material: (paths with the factor, paths without)}``."""
    from raysim.echoes.rt.scenes import load_scene

    out = {}
    for material in ("asphalt-77ghz", "metal"):
        xml = _write_scene(tmp_path_factory.mktemp(material), material)
        scene = load_scene(xml, frequency=rt_radar.carrier_frequency, hover_altitude=H)
        out[material] = (_trace(scene, rt_radar, True), _trace(scene, rt_radar, False), scene)
    return out


def test_rough_ground_bounces_carry_the_ament_factor(traced, rt_radar):
    """Each asphalt bounce divides the path by chi(theta_i); the metal plate's path is unchanged."""
    from raysim.echoes.ground.sigma0 import CLUTTER_MATERIALS

    on, off, _ = traced["asphalt-77ghz"]
    s = CLUTTER_MATERIALS["asphalt-77ghz"].rms_height
    i_on, i_off = _by_kind(on), _by_kind(off)
    expected = {"nadir": _chi(0.0, s, rt_radar.wavelength),
                "gpg": _chi(THETA, s, rt_radar.wavelength) ** 2, "facing": 1.0}
    for name, chi in expected.items():
        ratio = on.amplitude[i_on[name]] / off.amplitude[i_off[name]]
        pol = on.polarimetric[i_on[name]] / np.where(off.polarimetric[i_off[name]] == 0, 1,
                                                     off.polarimetric[i_off[name]])
        err_db = 20 * np.log10(abs(ratio) / chi)
        print(f"{name}: on/off {20 * np.log10(abs(ratio)):+.3f} dB, closed form "
              f"{20 * np.log10(chi):+.3f} dB, error {err_db:+.1e} dB")
        tol = UNCHANGED_TOL_DB if chi == 1.0 else RATIO_TOL_DB
        assert abs(err_db) < tol, (name, err_db)
        assert abs(np.angle(ratio)) < 1e-9                 # a real, positive factor
        nz = off.polarimetric[i_off[name]] != 0
        np.testing.assert_allclose(pol[nz], ratio, rtol=1e-9)
    # the factor is not small by accident: two asphalt bounces at 30 deg lose > 20 dB
    assert 20 * np.log10(expected["gpg"]) < -20.0


def test_smooth_ground_is_untouched(traced):
    """A metal (smooth, no rms height) ground: every path is the same with and without."""
    on, off, _ = traced["metal"]
    i_on, i_off = _by_kind(on), _by_kind(off)
    for name in ("nadir", "gpg", "facing"):
        err_db = 20 * np.log10(abs(on.amplitude[i_on[name]] / off.amplitude[i_off[name]]))
        assert abs(err_db) < UNCHANGED_TOL_DB, (name, err_db)


def test_factor_is_one_for_zero_rms_height_and_checks_shapes():
    """s = 0 gives chi = 1 at any incidence; objects of s = 0 are not rough; bad shapes refused."""
    from raysim.echoes.ground.sigma0 import ClutterMaterial
    from raysim.echoes.rt.rough_bounces import rough_bounce_factor

    smooth = ClutterMaterial("smooth", gamma_db=-20.0, rms_height=0.0, rms_slope=0.1,
                             permittivity=3.0)
    rough = ClutterMaterial("rough", gamma_db=-20.0, rms_height=1e-3, rms_slope=0.1,
                            permittivity=3.0)
    # radar (0, 0, 4) -> ground (3, 0, 0) -> (6, 0, 4) -> radar: the ground bounce has
    # legs (3, 0, -4) / 5 and (3, 0, 4) / 5, so cos(theta_i) = 4 / 5
    verts = np.array([[[3.0, 0.0, 0.0]], [[6.0, 0.0, 4.0]]])
    inter, objects = np.array([[1, 1]]), np.array([[7, 9]])
    lam = 299792458.0 / 77e9
    assert rough_bounce_factor(inter, objects, verts, [0, 0, 4], {7: smooth}, lam)[0] == 1.0
    got = rough_bounce_factor(inter, objects, verts, [0, 0, 4], {7: rough}, lam)[0]
    assert got == pytest.approx(_chi(math.acos(0.8), 1e-3, lam), rel=1e-12)
    # a diffuse bounce on the same material is left to the diffuse model
    assert rough_bounce_factor(np.array([[2, 1]]), objects, verts, [0, 0, 4], {7: rough},
                               lam)[0] == 1.0
    with pytest.raises(ValueError, match="vertices"):
        rough_bounce_factor(inter, objects, verts[0], [0, 0, 4], {7: rough}, lam)


def test_field_mode_replaces_the_mirror_once_and_keeps_reduced_multibounce(traced, rt_radar):
    """SceneClutter drops the (already reduced) single-bounce mirror and adds Fresnel x Ament
    once; the ground-plate-ground path stays with its two Ament factors."""
    from raysim.echoes.ground.field import radar_scale
    from raysim.echoes.ground.sigma0 import ament_factor, fresnel_coefficient
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.echoes.scene_clutter import SceneClutter
    from raysim.platform.motion import stationary

    on, off, scene = traced["asphalt-77ghz"]
    model = SceneClutter(ghosts=False)
    # a tracer without diffuse paths asks the model for the mirror only (no field to build)
    model.tracer(MonostaticTracer(diffuse=False, targets=False))
    paths, _ = model.paths(scene, on, rt_radar, None, stationary(), np.zeros(3), time=0.0)
    nadir = np.flatnonzero(np.abs(paths.length - 2 * H) < 1e-3)
    assert len(nadir) == 1
    mat = "asphalt-77ghz"
    ref = (math.sqrt(radar_scale(rt_radar) * 4 * math.pi) / (2 * H)
           * abs(complex(fresnel_coefficient(mat, 1.0))) * float(ament_factor(mat, 0.0,
                                                                               rt_radar.wavelength)))
    assert abs(20 * np.log10(abs(paths.amplitude[nadir[0]]) / ref)) < RATIO_TOL_DB
    gpg = _by_kind(on)["gpg"]
    j = np.flatnonzero(np.abs(paths.length - on.length[gpg]) < 1e-6)
    assert len(j) == 1 and paths.amplitude[j[0]] == on.amplitude[gpg]
