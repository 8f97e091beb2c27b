"""Every echo source follows the scenario's element pattern.

Closed form: the ``"patch"`` element of peak gain ``G_0 = 2 (q + 1)`` has
``G(theta) = 2 (q + 1) cos^q theta`` (Balanis, *Antenna Theory*, 4th ed., sec. 2.6),
and the received power of a point target is proportional to ``G_t G_r`` (radar
equation), so a target ``theta`` off boresight renders ``cos^{2q} theta`` times
weaker under ``patch`` than under ``"constant"`` (the same ``G_0`` everywhere):
-9.26 dB at 40 deg with the default ``q = 4``. The oracle's point target must get
that factor at each chirp's pose, and equal the same target traced as a path of a
scene (re-projected and synthesised, or traced by Sionna RT).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from raysim.pipeline.sources import frame_source, gated_source, point_targets
from raysim.processing.maps import range_compress
from raysim.scenario import validate_scenario

#: Patch vs constant power of the oracle against ``cos^{2q} theta`` per chirp [dB]
#: (the elements sit mm from the phase centre: their directions differ by ~1e-4 rad).
CLOSED_FORM_TOL_DB = 0.01
#: Point source against the same target rendered as a traced path: largest difference [dB].
TRACED_TOL_DB = 0.2
#: Target of the tests: range [m], azimuth [deg] (40 deg off boresight), RCS [dBsm].
RANGE_M, AZ_DEG, RCS_DBSM = 15.0, 40.0, 10.0
#: A pitch (about y_B, in the target's azimuth plane) that tilts the radar by about
#: 8 deg at the frame: the target's off-boresight angle is about 32 deg, not 40.
PITCH_DEG, PITCH_HZ, PITCH_PHASE_DEG = 8.0, 40.0, 90.0


def _scenario(pattern: str, *, pitch: bool = True):
    data = {"name": "pattern", "frames": 1, "lever_arm_m": [0.0, 0.0, 0.0],
            "radar": {"num_chirps": 16, "element_pattern": pattern},
            "array": {"kind": "upa", "nx": 4, "ny": 4},
            "scene": {"kind": "points",
                      "targets": [{"range_m": RANGE_M, "az_deg": AZ_DEG, "el_deg": 0.0,
                                   "rcs_dbsm": RCS_DBSM}]}}
    if pitch:
        data["motion"] = {"sinusoids": [{"axis": "pitch", "amplitude_deg": PITCH_DEG,
                                         "frequency_hz": PITCH_HZ,
                                         "phase_deg": PITCH_PHASE_DEG}]}
    return validate_scenario(data)


def _gate_power(data, config) -> np.ndarray:
    """Power of the range-compressed cube at the target's range bin, ``[chirp, channel]``."""
    k = int(np.argmin(np.abs(config.range_axis() - RANGE_M)))
    return np.abs(range_compress(data)[:, :, k]) ** 2


def _off_boresight(scenario) -> np.ndarray:
    """Angle [rad] between boresight ``+z_A`` and the target at each chirp (radar at rest in W)."""
    cfg = scenario.radar_config()
    t = cfg.chirp_times()
    p = point_targets(scenario)[0].position
    u_a = np.einsum("cji,j->ci", scenario.trajectory().attitude(t).as_matrix(), p)
    return np.arccos(u_a[:, 2] / np.linalg.norm(u_a, axis=1))


def test_point_source_applies_the_two_way_pattern_at_each_chirp():
    """Patch / constant power of a point target at 40 deg on a pitching radar is
    ``cos^{2q} theta_n`` at every chirp ``n`` (theta from that chirp's attitude)."""
    patch, const = _scenario("patch"), _scenario("constant")
    cfg = patch.radar_config()
    q = cfg.pattern.q
    p_patch = _gate_power(frame_source(patch)(0).data, cfg)
    p_const = _gate_power(frame_source(const)(0).data, const.radar_config())
    got_db = 10 * np.log10(p_patch / p_const)                     # [chirp, channel]
    theta = _off_boresight(patch)
    want_db = 10 * np.log10(np.cos(theta) ** (2 * q))[:, None]
    assert np.max(np.abs(got_db - want_db)) < CLOSED_FORM_TOL_DB
    # at rest: the 40 deg figure, -9.26 dB; the pitch moves the gain far more than the
    # tolerance away from it, so the pose of each chirp counts
    at_rest_db = 2 * q * 10 * math.log10(math.cos(math.radians(AZ_DEG)))
    assert np.min(np.abs(want_db - at_rest_db)) > 100 * CLOSED_FORM_TOL_DB
    still = [_gate_power(frame_source(_scenario(p, pitch=False))(0).data, cfg).mean()
             for p in ("patch", "constant")]
    assert 10 * math.log10(still[0] / still[1]) == pytest.approx(at_rest_db,
                                                                 abs=CLOSED_FORM_TOL_DB)


def test_constant_pattern_is_bit_identical_to_the_constant_gain():
    """``element_pattern = "constant"`` renders exactly what the oracle's default renders."""
    from raysim.echoes.oracle import simulate_point_targets

    s = _scenario("constant")
    cfg = s.radar_config()
    ref = simulate_point_targets(cfg, s.virtual_array(), point_targets(s), s.trajectory(),
                                 lever_arm=s.lever_arm)
    assert np.array_equal(frame_source(s)(0).data, ref.data)


def test_point_source_equals_the_traced_path_of_the_same_target():
    """The oracle's point target and the same target as a path of a traced scene
    (re-projected with the pattern at each chirp's pose and synthesised, as
    ``render_scene`` does) have the same power, and the gated source agrees."""
    from raysim.echoes.oracle import radar_equation_amplitude
    from raysim.echoes.rt.reproject import synthesize_paths
    from raysim.echoes.rt.trace import SENSING, PathSet
    from raysim.radar.config import SPEED_OF_LIGHT
    from raysim.synthesis.frame import adc_samples

    s = _scenario("patch")
    cfg, arr, traj = s.radar_config(), s.virtual_array(), s.trajectory()
    p = point_targets(s)[0].position[None]
    r = np.linalg.norm(p, axis=1)
    # a traced path's amplitude is that of 0 dBi elements (raysim.echoes.rt.trace.PathSet)
    iso = radar_equation_amplitude(cfg, r, r, RCS_DBSM) / 10 ** (cfg.antenna_gain_dbi / 10)
    paths = PathSet(p, p.copy(), 2 * r, iso.astype(complex), np.zeros((1, 3)), np.zeros(1),
                    np.full((1, 1), SENSING, np.uint32), np.full(1, SENSING, np.uint32),
                    np.zeros((1, 2, 2), complex), 2 * r / SPEED_OF_LIGHT, np.zeros(3),
                    np.zeros(3), 0.0, {})
    traced, _ = synthesize_paths(paths, cfg, arr, traj, s.lever_arm)
    p_traced = _gate_power(adc_samples(traced, cfg), cfg)
    p_point = _gate_power(frame_source(s)(0).data, cfg)
    err_db = 10 * np.log10(p_point / p_traced)
    assert np.max(np.abs(err_db)) < TRACED_TOL_DB
    gate, _, _ = gated_source(cfg, arr, traj, point_targets(s), range_m=RANGE_M,
                              lever_arm=s.lever_arm)
    gate_db = 10 * np.log10(np.abs(gate) ** 2 / p_point)
    assert np.max(np.abs(gate_db)) < TRACED_TOL_DB


def test_mounted_pattern_turns_with_the_radar():
    """A mounted radar's element gain towards a body direction is the pattern's towards
    the same direction in A (``u_A = R_BA^T u_B``), so the flight's targets keep their
    gain when the radar looks forward."""
    from raysim.platform.mounting import mount_pattern, mounting_matrix
    from raysim.radar.config import RadarConfig

    base = RadarConfig().pattern
    assert mount_pattern(base, "down") is base
    m = mounting_matrix("forward")
    u_a = np.array([[0.0, 0.0, 1.0], [math.sin(0.7), 0.0, math.cos(0.7)]])
    mounted = mount_pattern(base, "forward")
    np.testing.assert_allclose(mounted.gain_direction(u_a @ m.T), base.gain_direction(u_a),
                               rtol=1e-12)
    assert mounted.peak_gain == base.peak_gain


@pytest.mark.sionna
def test_point_source_equals_a_sionna_traced_scene_target(rt_backend):
    """The constant-RCS point target traced by Sionna RT in a scene, rendered by
    ``render_scene``, has the power of the scenario's point target (both ``patch``),
    within 0.2 dB, at every chirp of a pitching radar."""
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.scenes import SceneTarget, load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    s = _scenario("patch")
    cfg, arr, traj = s.radar_config(), s.virtual_array(), s.trajectory()
    tgt = SceneTarget("p40", point_targets(s)[0].position, RCS_DBSM)
    scene = load_scene("flat_reflectors", frequency=cfg.carrier_frequency, hover_altitude=20.0,
                       targets=[tgt])
    traced = render_scene(scene, cfg, arr, traj, s.lever_arm,
                          tracer=MonostaticTracer(specular=False, diffuse=False))
    err_db = 10 * np.log10(_gate_power(frame_source(s)(0).data, cfg)
                           / _gate_power(traced.data, cfg))
    print(f"point vs traced scene target: {np.max(np.abs(err_db)):.3f} dB")
    assert np.max(np.abs(err_db)) < TRACED_TOL_DB
