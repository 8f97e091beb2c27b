"""The clutter field: calibrated sigma0 in rendered cubes, Rayleigh cells, density and cost.

Rendered here means the project's render path without the ray tracer: the
field's PathSet goes through ``reproject.synthesize_paths`` (re-projection and
IF synthesis) into an IF cube, which is range-compressed like any frame.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from clutter_grounds import grid_ground
from scipy import stats
from scipy.signal.windows import blackmanharris

from raysim.echoes.ground.field import ClutterField, FieldCapped, FieldSettings, radar_scale
from raysim.echoes.ground.sigma0 import CLUTTER_MATERIALS, ament_factor, sigma0
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.rt.reproject import synthesize_paths
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Mean sigma0 measured from rendered cubes vs the model [dB] (the brief's 1 dB).
SIGMA0_TOL_DB = 1.0
#: Kolmogorov-Smirnov significance of the Rayleigh test.
KS_ALPHA = 0.05
#: Radar height above the flat ground [m].
HEIGHT = 8.0
#: Incidence angles of the sigma0 check [deg] and the half-width of each band [deg].
ANGLES_DEG = (25.0, 45.0, 62.0)
BAND_DEG = 3.0
#: Independent field realisations averaged (seeds) for sigma0, and for the KS test.
NUM_SEEDS = 16
SEEDS_KS = 12


@pytest.fixture(scope="module")
def setup():
    config = RadarConfig(num_chirps=1, sample_rate=2.5e6)        # 22.5 m window, 0.15 m bins
    array = upa(4, 4, wavelength=config.wavelength)
    ground = GroundSurface.from_meshes([(grid_ground(36.0, 4, HEIGHT), "dry-soil")])
    return config, array, ground


def _cube(field, config, array):
    paths = field.paths(config, np.zeros(3), np.eye(3))
    cube, _ = synthesize_paths(paths, config, array, path_chunk=4096)
    return cube[0]                                                 # [channel, sample]


def test_sigma0_model_closed_forms():
    """Constant gamma far from nadir, no Brewster dip, Ament factor, bad input refused."""
    lam = 299792458.0 / 77e9
    for name, m in CLUTTER_MATERIALS.items():
        theta = np.radians(np.arange(0.0, 89.0, 0.5))
        s = sigma0(theta, name, wavelength=lam)
        # far from nadir the quasi-specular lobe is gone: gamma cos(theta) (Nathanson 7.2)
        far = np.radians(80.0)
        assert 10 * np.log10(sigma0(far, name, wavelength=lam)) == pytest.approx(
            m.gamma_db + 10 * np.log10(math.cos(far)), abs=0.05), name
        # no Brewster collapse: monotonic decrease, never a dip of more than 0 dB
        assert np.all(np.diff(s) <= 0), name
    k = 2 * math.pi / lam
    s_rms = CLUTTER_MATERIALS["asphalt-77ghz"].rms_height
    assert ament_factor("asphalt-77ghz", 0.0, lam) == pytest.approx(
        math.exp(-2 * (k * s_rms) ** 2), rel=1e-12)
    for bad in (dict(incidence=math.pi / 2), dict(incidence=-0.1),
                dict(material="lava"), dict(polarisation="RL")):
        kw = dict(incidence=0.3, material="dry-soil") | bad
        with pytest.raises(ValueError):
            sigma0(**kw)


def test_rendered_mean_sigma0_matches_model(setup):
    """Mean sigma0 from rendered cubes at three incidence angles = model within 1 dB.

    Flat ground, single chirp, Blackman-Harris range window ``w``: Parseval gives
    ``E|Y_k|^2 = N sum(w^2) sum_{ring k} E|a_i|^2`` and the ring of bin ``k`` has the
    ground area ``2 pi R dR`` on flat ground (``rho drho = R dR``), so
    ``sigma0_hat = <|Y_k|^2> R^4 / (N^2 P_t G(theta)^2 lambda^2 / (4 pi)^3 2 pi R dR)``
    (Skolnik, *Radar Handbook*, eq. 7.1 with ``sigma = sigma0 dA``).
    """
    config, array, ground = setup
    n = config.num_samples
    r = config.bin_ranges(n)
    power = np.zeros(n)
    # a low-sidelobe window: the element pattern makes near-nadir bins tens of dB brighter
    # than those at 60 deg, and a rectangular window's sidelobes would fill the far bins;
    # for a uniform spread of beat frequencies E|Y_k|^2 = N sum(w^2) x power per bin
    w = blackmanharris(n)
    for seed in range(NUM_SEEDS):
        field = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                                   FieldSettings(shadowing=False, seed=seed))
        y = np.fft.fft(_cube(field, config, array) * w, axis=-1)
        power += np.mean(np.abs(y) ** 2, axis=0) / (n * np.sum(w**2)) / NUM_SEEDS
    ok = r > HEIGHT
    theta = np.arccos(HEIGHT / np.where(ok, r, HEIGHT))
    # boresight is nadir here, so the two-way element gain is G(theta)^2 at incidence theta
    g2 = config.pattern.gain(theta, 0.0) ** 2
    est = power * r**3 / (radar_scale(config) * g2 * 2 * math.pi * config.range_resolution
                          + 1e-300)
    for deg in ANGLES_DEG:
        sel = ok & (np.abs(np.degrees(theta) - deg) < BAND_DEG)
        model = np.mean(sigma0(theta[sel], "dry-soil", wavelength=config.wavelength))
        err = 10 * np.log10(np.mean(est[sel]) / model)
        print(f"{deg:.0f} deg: measured {10 * np.log10(np.mean(est[sel])):.2f} dB, "
              f"model {10 * np.log10(model):.2f} dB, {sel.sum()} bins, error {err:+.2f} dB")
        assert abs(err) < SIGMA0_TOL_DB


def _cell_powers(setup, per_cell: float, seeds: int) -> np.ndarray:
    """Range-angle cell powers over seeds normalised by each cell's mean, ``[seed * cell]``."""
    config, array, ground = setup
    cells = []
    for seed in range(seeds):
        field = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                                   FieldSettings(shadowing=False, seed=100 + seed,
                                                 scatterers_per_cell=per_cell))
        y = np.fft.fft(_cube(field, config, array), axis=-1).reshape(4, 4, -1)
        ra = np.fft.fft2(y, axes=(0, 1))                           # [u, v, range]
        cells.append(np.abs(ra[:, :, 70:120]) ** 2)                 # 10.5 - 18 m
    p = np.stack(cells)
    return (p / p.mean(axis=0, keepdims=True)).ravel()


def test_cell_amplitudes_are_rayleigh(setup):
    """Range-angle cell amplitudes pass a KS Rayleigh test at 5 %; too sparse a field fails it.

    The power of a complex Gaussian cell (Rayleigh amplitude, Skolnik, *Radar
    Handbook*, sec. 7.5) is exponential; divided by its mean over ``n``
    independent realisations it is distributed as ``n Beta(1, n - 1)``.
    """
    null = stats.beta(1, SEEDS_KS - 1, scale=SEEDS_KS).cdf
    p = _cell_powers(setup, 10.0, SEEDS_KS)
    sample = np.random.default_rng(0).choice(p, 400, replace=False)  # weakly dependent cells
    res = stats.kstest(sample, null)
    print(f"field (10 per cell): KS p = {res.pvalue:.3f}")
    assert res.pvalue > KS_ALPHA
    sparse = _cell_powers(setup, 0.05, SEEDS_KS)
    res_sparse = stats.kstest(np.random.default_rng(0).choice(sparse, 400, replace=False), null)
    print(f"field (0.05 per cell): KS p = {res_sparse.pvalue:.2e}")
    assert res_sparse.pvalue < KS_ALPHA


def test_density_count_and_cost_bound(setup):
    """At least the asked scatterers per resolution cell; the cap bounds the count."""
    config, array, ground = setup
    field = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                               FieldSettings(shadowing=False))
    rep = field.report
    # Poisson count: within 5 sigma of its expectation
    assert abs(rep["num_scatterers"] - rep["expected"]) < 5 * math.sqrt(rep["expected"])
    # the nadir angular cell (h^2 du dv) holds >= 10 scatterers on average
    du, dv = rep["resolution"][1:]
    half = 0.5 * HEIGHT * math.sqrt(du * dv)
    near = np.all(np.abs(field.positions[:, :2]) < half, axis=1)
    assert rep["cell_area_nadir"] == pytest.approx(HEIGHT**2 * du * dv)
    assert near.sum() >= 10 * 0.5            # Poisson spread of ~10 counts (>5 sigma margin)
    assert np.sum(field.area[near]) == pytest.approx(4 * half**2, rel=0.5)
    with pytest.warns(FieldCapped, match="max_scatterers = 500"):
        capped = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                                    FieldSettings(shadowing=False, max_scatterers=500))
    assert capped.report["density_scale"] < 1
    assert capped.num_scatterers < 500 + 5 * math.sqrt(500)
    with pytest.raises(ValueError, match="scatterers_per_cell"):
        FieldSettings(scatterers_per_cell=0)
    with pytest.raises(ValueError, match="reuse_distance"):
        field.paths(config, np.array([0.0, 0.0, -1.0]), np.eye(3))
