"""Ray-traced returns against closed forms and the point-target oracle.

Expected values are re-derived here from textbook formulas (radar equation,
normal-incidence Fresnel coefficient, image theory), never from the code
under test.
"""

from __future__ import annotations

import numpy as np
import pytest

from raysim.echoes.oracle import PointTarget, simulate_point_targets
from raysim.platform.motion import Trajectory, hover_jitter, sinusoid
from raysim.processing import maps as processing
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

pytestmark = pytest.mark.sionna

#: Amplitude tolerance of every physics comparison [dB].
AMPLITUDE_TOL_DB = 0.5
#: Phase tolerance of the specular ground return [deg].
PHASE_TOL_DEG = 2.0
#: Cross-model tolerances against ``raysim.echoes.oracle`` (brief of the ray tracer).
RANGE_TOL_BINS = 0.1
ANGLE_TOL_DEG = 0.1
DOPPLER_TOL_BINS = 0.1
#: Relative error of the whole IF cube, ray tracer vs oracle [dB].
CUBE_TOL_DB = -40.0


def ref_radar_equation(config: RadarConfig, r: np.ndarray, rcs_dbsm) -> np.ndarray:
    """``sqrt(P_t G^2 lambda^2 sigma / ((4 pi)^3 R^4))`` [sqrt(W)] with isotropic elements.

    A traced ``PathSet`` carries 0 dBi elements (``G = 1``); the element
    pattern is applied at re-projection.
    """
    pt = 1e-3 * 10 ** (config.tx_power_dbm / 10)
    g = 1.0
    sigma = 10 ** (np.asarray(rcs_dbsm) / 10)
    return np.sqrt(pt * g**2 * config.wavelength**2 * sigma / ((4 * np.pi) ** 3 * r**4))


def ref_fresnel_nadir(eps: complex) -> complex:
    """Normal-incidence Fresnel coefficient of a half-space ``(1 - sqrt eps) / (1 + sqrt eps)``."""
    n = np.sqrt(eps)
    return complex((1 - n) / (1 + n))


def ref_ground_echo(config: RadarConfig, height: float, eps: complex,
                    scattering_coefficient: float) -> complex:
    """Monostatic specular ground echo at nadir by image theory [sqrt(W)].

    The image of the radar lies ``2 h`` away: free-space transfer
    ``lambda / (4 pi 2 h)`` times the Fresnel coefficient, times
    ``sqrt(P_t)`` with isotropic elements (``G = 1``; the pattern is applied at
    re-projection) (no ``exp(-j k 2h)``: the IF phase is added at synthesis).
    A rough surface that scatters a share ``S`` of the reflected amplitude
    diffusely keeps ``sqrt(1 - S^2)`` of it in the specular direction (energy
    split of Sionna's reflection model, Degli-Esposti et al. 2007).
    """
    pt = 1e-3 * 10 ** (config.tx_power_dbm / 10)
    g = 1.0
    return (np.sqrt(pt) * g * ref_fresnel_nadir(eps) * np.sqrt(1 - scattering_coefficient**2)
            * config.wavelength / (4 * np.pi * 2 * height))


def test_constant_rcs_target_follows_radar_equation(warm_kernels, rt_radar):
    """Constant-RCS points where ``flat_reflectors`` has its reflectors (0-25 m off nadir)
    within 0.5 dB, phase 0."""
    from raysim.echoes.rt.scenes import SceneTarget, load_scene
    from raysim.echoes.rt.trace import SENSING, MonostaticTracer

    # constant-RCS points at the apexes of the scene's reflectors (which are meshes)
    points = [SceneTarget(t.name, t.position, t.rcs_dbsm)
              for t in load_scene("flat_reflectors").targets]
    scene = load_scene("flat_reflectors", targets=points)
    # a tilted radar (roll 8 deg, yaw 30 deg) must not change the co-polarised amplitude
    tilt = Trajectory(sinusoid("roll", np.deg2rad(8.0), 0.0, np.pi / 2).components
                      + sinusoid("yaw", np.deg2rad(30.0), 0.0, np.pi / 2).components)
    for trajectory in (None, tilt):
        paths = MonostaticTracer(specular=False, diffuse=False)(scene, rt_radar, trajectory)
        assert paths.num_paths == len(scene.targets)
        assert np.all(paths.kind == SENSING)
        for tgt in scene.targets:
            i = int(np.argmin(np.linalg.norm(paths.first_vertex - tgt.position, axis=1)))
            r = np.linalg.norm(tgt.position - paths.tx_position)
            assert paths.length[i] == pytest.approx(2 * r, abs=1e-5)
            err_db = 20 * np.log10(abs(paths.amplitude[i]) / ref_radar_equation(
                rt_radar, r, tgt.rcs_dbsm))
            print(f"{tgt.name}: amplitude vs radar equation {err_db:+.2e} dB")
            assert abs(err_db) < AMPLITUDE_TOL_DB, (tgt.name, err_db)
            assert abs(np.angle(paths.amplitude[i], deg=True)) < PHASE_TOL_DEG


@pytest.mark.parametrize("height", [10.0, 20.0])
def test_flat_ground_nadir_matches_fresnel(warm_kernels, rt_radar, height):
    """Specular nadir return vs image theory with the half-space Fresnel coefficient."""
    from raysim.echoes.rt.scenes import DRY_SOIL, load_scene
    from raysim.echoes.rt.trace import SPECULAR, MonostaticTracer

    scene = load_scene("flat_reflectors", hover_altitude=height, include_targets=False)
    # Sionna's smooth-surface reflection (the Ament factor is tested in test_rt_rough_bounces)
    paths = MonostaticTracer(diffuse=False, targets=False, rough_bounces=False)(scene, rt_radar)
    assert paths.num_paths == 1
    assert paths.kind[0] == SPECULAR
    assert paths.length[0] == pytest.approx(2 * height, abs=1e-5)
    np.testing.assert_allclose(paths.first_vertex[0], [0.0, 0.0, height], atol=1e-5)
    ref = ref_ground_echo(rt_radar, height, DRY_SOIL.complex_permittivity(
        rt_radar.carrier_frequency), DRY_SOIL.scattering_coefficient)
    got = paths.amplitude[0]
    print(f"nadir ground at {height} m vs Fresnel: {20 * np.log10(abs(got) / abs(ref)):+.2e} dB, "
          f"{np.angle(got / ref, deg=True):+.2e} deg")
    assert abs(20 * np.log10(abs(got) / abs(ref))) < AMPLITUDE_TOL_DB
    assert abs(np.angle(got / ref, deg=True)) < PHASE_TOL_DEG


def _peak_metrics(frame, array, config):
    """Range [m], Doppler [m/s], (ux, uy) direction cosines and amplitude of the strongest cell."""
    rc = processing.range_compress(frame.data)
    rd = processing.range_doppler_map(rc, config)
    pk = rd.peak()
    ir = int(np.argmin(np.abs(rd.coords["range"] - pk["range"])))
    snap = rc[:, :, ir].mean(axis=0)
    power, ux, uy = processing.upa_angle_fft(snap, array, config.wavelength, n_fft=256)
    i, j = np.unravel_index(int(np.argmax(power)), power.shape)
    return pk["range"], pk["doppler"], (ux[i], uy[j]), np.sqrt(pk["value"])


def test_cross_model_target_vs_point_target_oracle(warm_kernels):
    """A ray-traced constant-RCS target reproduces ``raysim.echoes.oracle`` under hover jitter.

    One moving reflector, a 4 x 4 UPA, 32 chirps: the whole cube agrees to
    -40 dB, and the peaks to 0.1 range bin, 0.1 deg, 0.1 Doppler bin and 0.5 dB.
    """
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.scenes import SceneTarget, load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    config = RadarConfig(num_chirps=32)
    array = upa(4, 4, wavelength=config.wavelength)
    motion = hover_jitter(3)
    lever = np.array([0.05, -0.02, 0.08])
    tgt = SceneTarget("mover", position=np.array([6.0, -4.0, 14.0]), rcs_dbsm=5.0,
                     velocity=np.array([0.4, 0.3, 0.0]))
    scene = load_scene("flat_reflectors", targets=[tgt])
    rt_frame = render_scene(scene, config, array, motion, lever,
                            tracer=MonostaticTracer(specular=False, diffuse=False))
    oracle = simulate_point_targets(config, array, [PointTarget(tgt.position, tgt.velocity,
                                                                tgt.rcs_dbsm)], motion,
                                    lever_arm=lever, pattern=config.pattern)
    err = np.linalg.norm(rt_frame.data - oracle.data) / np.linalg.norm(oracle.data)
    assert 20 * np.log10(err) < CUBE_TOL_DB
    r1, v1, u1, a1 = _peak_metrics(rt_frame, array, config)
    r0, v0, u0, a0 = _peak_metrics(oracle, array, config)
    assert abs(r1 - r0) < RANGE_TOL_BINS * config.range_resolution
    assert abs(v1 - v0) < DOPPLER_TOL_BINS * config.velocity_resolution
    ang = np.rad2deg(np.arccos(np.clip(
        np.dot([*u1, np.sqrt(1 - u1[0] ** 2 - u1[1] ** 2)],
               [*u0, np.sqrt(1 - u0[0] ** 2 - u0[1] ** 2)]), -1, 1)))
    print(f"ray-traced vs oracle: cube {20 * np.log10(err):.1f} dB, range "
          f"{abs(r1 - r0) / config.range_resolution:.1e} bin, Doppler "
          f"{abs(v1 - v0) / config.velocity_resolution:.1e} bin, angle {ang:.1e} deg, "
          f"amplitude {20 * np.log10(a1 / a0):+.1e} dB")
    assert ang < ANGLE_TOL_DEG
    assert abs(20 * np.log10(a1 / a0)) < AMPLITUDE_TOL_DB
