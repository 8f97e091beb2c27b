"""Element power patterns: closed forms, Sionna's TR 38.901 element, path weighting, culling.

Closed forms: a ``cos^q`` power pattern on the front hemisphere has directivity
``D_0 = 2 (q + 1)`` (Balanis, *Antenna Theory*, 4th ed., sec. 2.6) and half-power
beamwidth ``2 arccos(2^{-1/q})`` (from ``cos^q theta = 1/2``). The TR 38.901
element is checked against Sionna RT's own ``v_tr38901_pattern`` and
``compute_gain``; path gains against the point-target oracle with ``pattern=``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from raysim.radar.config import RadarConfig
from raysim.radar.pattern import (
    CosinePattern,
    TabulatedPattern,
    Tr38901Pattern,
    direction_angles,
    element_pattern,
)

#: Sphere integral / 4 pi of an analytic pattern (adaptive quadrature).
EFFICIENCY_TOL = 1e-6
#: Half-power beamwidth against the closed form [rad].
BEAMWIDTH_TOL = 1e-6
#: Our TR 38.901 element vs Sionna's float32 evaluation [dB].
SIONNA_GAIN_TOL_DB = 1e-3
#: Our sphere integral of the TR 38.901 element vs Sionna's compute_gain (both quadratures).
SIONNA_EFFICIENCY_TOL = 5e-3
#: A 1 deg x 5 deg tabulated cos^4 against the closed form, main lobe (|theta| < 60 deg) [dB].
TABLE_GAIN_TOL_DB = 0.05
#: Re-projected path gain (one direction per chirp) vs the oracle's per-channel gain [dB].
PATH_GAIN_TOL_DB = 0.1


def _cos_table(path, q=4.0, d_theta=1.0, d_phi=5.0):
    theta = np.arange(0.0, 180.0 + d_theta / 2, d_theta)
    phi = np.arange(0.0, 360.0, d_phi)
    c = np.cos(np.radians(theta))
    g = np.where(c > 0, 2 * (q + 1) * np.clip(c, 1e-12, None) ** q, 1e-12)
    rows = ["theta_deg,phi_deg,gain_dbi"]
    rows += [f"{t:g},{p:g},{10 * np.log10(max(gi, 1e-6)):.6f}"
             for t, gi in zip(theta, g, strict=True) for p in phi]
    path.write_text("\n".join(rows) + "\n", encoding="utf-8")
    return path


@pytest.mark.parametrize("q", [0.0, 1.0, 4.0, 7.5])
def test_cos_q_is_energy_consistent_with_closed_form_beamwidth(q):
    p = CosinePattern("cos", q)
    integral, _ = quad(lambda t: float(p.gain(t, 0.0)) * math.sin(t), 0.0, math.pi,
                       points=[math.pi / 2], epsabs=1e-12)
    assert abs(2 * math.pi * integral / (4 * math.pi) - 1.0) < EFFICIENCY_TOL
    assert p.peak_gain == pytest.approx(2 * (q + 1), rel=1e-12)
    if q > 0:
        hpbw = 2 * math.acos(2 ** (-1 / q))
        assert abs(p.half_power_beamwidth() - hpbw) < BEAMWIDTH_TOL
        assert abs(p.half_power_beamwidth(math.pi / 2) - hpbw) < BEAMWIDTH_TOL
        # the budget cone: one-way gain 40 dB down at arccos(10^(-4/q)), within a grid row
        assert abs(p.cull_angle(-40.0) - math.acos(10 ** (-4 / q))) <= math.pi / 720


def test_default_patch_element_and_gain_relation():
    cfg = RadarConfig()
    assert cfg.element_pattern == "patch"
    assert cfg.pattern.peak_gain_dbi == pytest.approx(cfg.antenna_gain_dbi, abs=1e-12)
    assert math.degrees(cfg.pattern.half_power_beamwidth()) == pytest.approx(
        math.degrees(2 * math.acos(2 ** -0.25)), abs=1e-6)     # 65.5 deg
    # "patch" takes q from the stated gain: G0 = 2 (q + 1)
    assert RadarConfig(antenna_gain_dbi=13.0).pattern.q == \
        pytest.approx(10 ** 1.3 / 2 - 1, rel=1e-12)


@pytest.mark.parametrize("kwargs, words", [
    ({"element_pattern": "cos^6"}, ("antenna_gain_dbi", "11.46", "cos^6")),
    ({"element_pattern": "tr38901"}, ("antenna_gain_dbi", "8.00", "tr38901")),
    ({"element_pattern": "horn"}, ("element_pattern", "'horn'")),
    ({"element_pattern": "cos^-1", "antenna_gain_dbi": 3.0}, ("q", "-1")),
    ({"element_pattern": "missing.csv"}, ("missing.csv",)),
])
def test_inconsistent_or_bad_patterns_are_refused(kwargs, words):
    # refused when the configuration is made
    with pytest.raises(ValueError) as err:
        RadarConfig(**kwargs)
    for w in words:
        assert w in str(err.value)


def test_tr38901_matches_sionna(rt_backend):
    import mitsuba as mi
    from sionna.rt import PlanarArray
    from sionna.rt.antenna_pattern import v_tr38901_pattern

    rng = np.random.default_rng(3)
    u = rng.normal(size=(500, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    ours = Tr38901Pattern("tr38901").gain_direction(u)
    # Sionna's element looks along its x with zenith z: x_s = z_A, y_s = x_A, z_s = y_A
    zen = np.arccos(u[:, 1])
    azi = np.arctan2(u[:, 0], u[:, 2])
    c = v_tr38901_pattern(mi.Float(zen.astype(np.float32)), mi.Float(azi.astype(np.float32)))
    theirs = np.asarray(c.real, dtype=float) ** 2 + np.asarray(c.imag, dtype=float) ** 2
    assert np.max(np.abs(10 * np.log10(ours / theirs))) < SIONNA_GAIN_TOL_DB
    _, g, eta = PlanarArray(num_rows=1, num_cols=1, pattern="tr38901",
                            polarization="V").antenna_pattern.compute_gain(verbose=False)
    pat = element_pattern("tr38901")
    assert pat.peak_gain_dbi == pytest.approx(10 * np.log10(float(g[0])), abs=1e-3)
    assert abs(pat.efficiency - float(eta[0])) < SIONNA_EFFICIENCY_TOL
    # boresight +z_A; azimuth (x_A) and elevation (y_A) cuts: 12 (x / 65 deg)^2 = 10 log10 2
    hpbw = math.radians(65.0) * math.sqrt(10 * math.log10(2) / 3)
    assert abs(pat.half_power_beamwidth(0.0) - hpbw) < BEAMWIDTH_TOL
    assert abs(pat.half_power_beamwidth(math.pi / 2) - hpbw) < BEAMWIDTH_TOL


def test_tabulated_pattern_reads_interpolates_and_refuses(tmp_path):
    path = _cos_table(tmp_path / "cos4.csv")
    tab = TabulatedPattern.from_csv(path)
    ref = CosinePattern("cos4", 4.0)
    rng = np.random.default_rng(0)
    theta = rng.uniform(0, math.radians(60), 200)
    phi = rng.uniform(-math.pi, math.pi, 200)
    err_db = 10 * np.log10(tab.gain(theta, phi) / ref.gain(theta, phi))
    assert np.max(np.abs(err_db)) < TABLE_GAIN_TOL_DB
    assert abs(tab.efficiency - 1.0) < 0.01
    assert element_pattern(str(path)).peak_gain_dbi == pytest.approx(10.0, abs=0.01)
    # the same file with 3 dB too much gain radiates twice its input: refused
    hot = tmp_path / "hot.csv"
    lines = path.read_text().splitlines()
    hot.write_text("\n".join([lines[0]] + [
        ",".join(r.split(",")[:2] + [str(float(r.split(",")[2]) + 3.0)]) for r in lines[1:]]))
    with pytest.raises(ValueError, match="exceeds its directivity"):
        TabulatedPattern.from_csv(hot)
    bad = tmp_path / "bad.csv"
    bad.write_text("theta,phi,gain\n0,0,1\n")
    with pytest.raises(ValueError, match="header"):
        TabulatedPattern.from_csv(bad)
    bad.write_text("\n".join(lines[:-1]))          # one grid point missing
    with pytest.raises(ValueError, match="grid"):
        TabulatedPattern.from_csv(bad)


def test_angles_follow_conventions():
    """u(az, el) = (cos el sin az, sin el, cos el cos az): azimuth is the phi = 0 cut."""
    az, el = math.radians(25.0), math.radians(-10.0)
    u = np.array([math.cos(el) * math.sin(az), math.sin(el), math.cos(el) * math.cos(az)])
    theta, phi = direction_angles(u)
    assert math.cos(theta) == pytest.approx(math.cos(el) * math.cos(az), abs=1e-15)
    theta0, phi0 = direction_angles(np.array([math.sin(az), 0.0, math.cos(az)]))
    assert theta0 == pytest.approx(az, abs=1e-15) and phi0 == pytest.approx(0.0, abs=1e-15)


def test_reprojected_paths_carry_the_oracle_pattern_gain():
    """Point paths at 0-60 deg off boresight on a rolling platform: gain as the oracle's."""
    from raysim.echoes.oracle import PointTarget, point_target_delays, radar_equation_amplitude
    from raysim.echoes.rt.reproject import reproject
    from raysim.echoes.rt.trace import PathSet
    from raysim.platform.motion import Trajectory, sinusoid
    from raysim.radar.arrays import upa
    from raysim.radar.config import SPEED_OF_LIGHT

    cfg = RadarConfig(num_chirps=16)
    arr = upa(4, 4, wavelength=cfg.wavelength)
    motion = Trajectory(sinusoid("roll", math.radians(10.0), 50.0).components)
    pos = np.array([[0.0, 0.0, 15.0], [5.0, 0.0, 14.0], [-3.0, 9.0, 10.0], [12.0, -8.0, 9.0]])
    targets = [PointTarget(p, rcs_dbsm=0.0) for p in pos]
    _, amp_oracle = point_target_delays(cfg, arr, motion, targets, pattern=cfg.pattern)
    r = np.linalg.norm(pos, axis=1)
    iso = radar_equation_amplitude(cfg, r, r, 0.0) / 10 ** (cfg.antenna_gain_dbi / 10)
    n = len(pos)
    paths = PathSet(pos, pos.copy(), 2 * r, iso.astype(complex), np.zeros((n, 3)), np.zeros(n),
                    np.full((n, 1), 16, np.uint32), np.full(n, 16, np.uint32),
                    np.zeros((n, 2, 2), complex), 2 * r / SPEED_OF_LIGHT, np.zeros(3),
                    np.zeros(3), 0.0, {})
    got = np.abs(np.broadcast_to(reproject(paths, cfg, arr, motion).amplitude,
                                 amp_oracle.shape))
    err_db = 20 * np.log10(got / amp_oracle)
    assert np.max(np.abs(err_db)) < PATH_GAIN_TOL_DB
    # the roll modulates the off-boresight gains by far more than the tolerance
    assert np.ptp(20 * np.log10(got[3, :, 0])) > 10 * PATH_GAIN_TOL_DB
    # stationary: the closed form 2 (q + 1) cos^q theta per leg, squared -> amplitude G(theta)
    still = np.abs(reproject(paths, cfg, arr).amplitude[:, 0, 0]) / iso
    np.testing.assert_allclose(still, 10.0 * (pos[:, 2] / r) ** 4, rtol=1e-9)


@pytest.mark.sionna
def test_tracer_culls_below_the_pattern_floor(warm_kernels, rt_radar):
    """Targets whose two-way gain is below the floor are dropped and counted with their power."""
    from raysim.echoes.rt.scenes import SceneTarget, load_scene
    from raysim.echoes.rt.trace import MonostaticTracer, pattern_culled_share

    # constant-RCS points at the apexes of the scene's reflectors (which are meshes)
    points = [SceneTarget(t.name, t.position, t.rcs_dbsm)
              for t in load_scene("flat_reflectors").targets]
    scene = load_scene("flat_reflectors", targets=points)
    floor_db = -6.0
    pos = np.stack([t.position for t in scene.targets])
    r = np.linalg.norm(pos, axis=1)
    g2 = ((pos[:, 2] / r) ** 4) ** 2                      # two-way cos^4, relative to peak
    below = 10 * np.log10(g2) < floor_db
    assert 0 < below.sum() < len(pos)                      # the floor splits the targets
    full = MonostaticTracer(specular=False, diffuse=False,
                            pattern_floor_db=-math.inf)(scene, rt_radar)
    cut = MonostaticTracer(specular=False, diffuse=False,
                           pattern_floor_db=floor_db)(scene, rt_radar)
    assert full.num_paths == len(pos) and full.dropped["pattern"] == 0
    assert cut.num_paths == len(pos) - below.sum() and cut.dropped["pattern"] == below.sum()
    sigma = np.array([10 ** (t.rcs_dbsm / 10) for t in scene.targets])
    power = sigma * g2 / r ** 4                             # radar equation up to a constant
    assert pattern_culled_share(cut) == pytest.approx(power[below].sum() / power.sum(),
                                                      rel=1e-3)


_TARGET = "[[scene.targets]]\nrange_m = 10.0\naz_deg = 0.0\nel_deg = 0.0\n"


def test_scenario_element_pattern_key(tmp_path):
    from raysim.scenario import load_scenario, loads_scenario

    cfg = loads_scenario('[radar]\nelement_pattern = "tr38901"\n' + _TARGET).radar_config()
    assert cfg.element_pattern == "tr38901" and cfg.antenna_gain_dbi == pytest.approx(8.0)
    assert loads_scenario(_TARGET).radar_config().element_pattern == "patch"
    with pytest.raises(ValueError) as err:
        loads_scenario('[radar]\nelement_pattern = "tr38901"\nantenna_gain_dbi = 12.0\n'
                       + _TARGET)
    assert "radar" in str(err.value) and "12.0" in str(err.value) and "8.00" in str(err.value)
    with pytest.raises(ValueError, match="'horn'"):
        loads_scenario('[radar]\nelement_pattern = "horn"\n' + _TARGET)
    # a pattern file relative to the scenario file
    _cos_table(tmp_path / "elem.csv")
    (tmp_path / "s.toml").write_text('[radar]\nelement_pattern = "elem.csv"\n' + _TARGET)
    cfg = load_scenario(tmp_path / "s.toml").radar_config()
    assert cfg.element_pattern == str((tmp_path / "elem.csv").resolve())
    assert cfg.antenna_gain_dbi == pytest.approx(10.0, abs=0.05)


def test_stores_keep_the_element_pattern():
    from raysim.io.storage import config_from_attrs, radar_attrs

    cfg = RadarConfig(element_pattern="tr38901", antenna_gain_dbi=8.0)
    attrs = radar_attrs(cfg)
    assert config_from_attrs(attrs) == cfg
    del attrs["radar_element_pattern"]            # a store from before element patterns
    assert config_from_attrs(attrs).element_pattern == "constant"


@pytest.mark.parametrize("floor", [3.0, math.nan, "low"])
def test_bad_pattern_floor_is_refused(floor):
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.echoes.rt.trace_plan import plan_trace
    from raysim.radar.arrays import upa

    with pytest.raises(ValueError, match="pattern_floor_db"):
        MonostaticTracer(pattern_floor_db=floor)
    cfg = RadarConfig(num_chirps=8)
    with pytest.raises(ValueError, match="pattern_floor_db"):
        plan_trace("flat_reflectors", cfg, upa(2, 2, wavelength=cfg.wavelength),
                   pattern_floor_db=floor)


def test_low_gain_patch_is_refused_where_used_not_where_made():
    # a 0 dBi configuration stays valid for the isotropic oracle; a patch cannot have it
    cfg = RadarConfig(antenna_gain_dbi=0.0)
    with pytest.raises(ValueError) as err:
        _ = cfg.pattern
    for w in ("patch", "3.01", "constant"):
        assert w in str(err.value)
