"""Slow-time decimation on vibrating platforms, rotors, movers and TDM.

Every ``decimate="auto"`` cube is held to its tolerance against the exact sum, in
relative l2 and in its worst chirp row: against the undecimated render of the same
method and row tolerance (the interpolation alone, its share
``DECIMATION_EPS_SHARE * eps``) and against the complex128 direct sum (``eps``).
Where decimation cannot meet it, it must be refused (factor 1) with a reason.

The sideband bound is the spectrum of sinusoidal phase modulation,
``exp(j beta sin(2 pi f_m t)) = sum_n J_n(beta) exp(j 2 pi n f_m t)`` (Jacobi-Anger;
Carson's rule ``2 (beta + 1) f_m`` keeps about 98 % of the power), with the power
beyond ``N f_m`` ``sum_{|n| > N} J_n(beta)^2``.
"""

import numpy as np
import pytest

from raysim.bench.workloads import hover_paths
from raysim.platform.motion import hover_jitter, sinusoid
from raysim.radar.arrays import ti_3tx4rx, upa
from raysim.radar.config import PAPER_RADAR, RadarConfig
from raysim.synthesis import decimate as dm
from raysim.synthesis import kernel
from raysim.synthesis.nufft import PathDelays
from raysim.synthesis.select import DECIMATION_EPS_SHARE, synthesize

METHOD = "kernel" if kernel.available() else "nufft"
EPS = 1e-5
LEVER = (0.05, 0.0, 0.1)


def assert_within(pd, cfg, eps=EPS, chirps=None):
    """Decimated cube within its tolerance (or refused); returns the decimation report."""
    report = []
    got = synthesize(pd, None, cfg, method=METHOD, eps=eps, decimate="auto", chirps=chirps,
                     decimation_report=report)
    assert report, "no decimation report"
    for group in report:
        if group["factor"] == 1:
            assert group["reason"], group
    undecimated = synthesize(pd, None, cfg, method=METHOD, eps=(1 - DECIMATION_EPS_SHARE) * eps,
                             chirps=chirps)
    l2, row = dm.check_errors(got, undecimated)
    share = DECIMATION_EPS_SHARE * eps
    assert l2 <= share and row <= share, (l2, row, report)
    direct = synthesize(pd, None, cfg, method="direct", chirps=chirps)
    l2, row = dm.check_errors(got, direct)
    assert l2 <= eps and row <= eps, (l2, row, report)
    return report


def scene(trajectory, num_paths=40, num_chirps=128, nx=2, ny=1, seed=1, static=True):
    cfg = PAPER_RADAR.with_(num_chirps=num_chirps)
    arr = upa(nx, ny, wavelength=cfg.wavelength)
    pd = hover_paths(num_paths, cfg, arr, trajectory, LEVER, seed=seed)
    if static:
        pd = pd.select(~np.any(pd.velocity != 0, axis=1))
    return cfg, pd


# ---------------------------------------------------------------- closed form
@pytest.mark.parametrize("beta", [0.01, 0.3, 1.0, 3.2, 12.0])
def test_bessel_tail_matches_the_spectrum_of_phase_modulation(beta):
    """The power beyond N f_m of exp(j beta sin) read off an FFT equals the Bessel tail."""
    n_fft, k0 = 4096, 16                                          # f_m = 16 bins
    s = np.exp(1j * beta * np.sin(2 * np.pi * k0 * np.arange(n_fft) / n_fft))
    power = np.abs(np.fft.fft(s) / n_fft) ** 2
    f = np.fft.fftfreq(n_fft, 1.0 / n_fft)
    for order in (0, 1, 2, int(beta) + 1, int(beta) + 4):
        measured = power[np.abs(f) > order * k0].sum()
        assert dm.bessel_tail(beta, order) == pytest.approx(measured, rel=1e-6, abs=1e-28)
    assert dm.bessel_tail(beta, 0) == pytest.approx(1 - power[0], abs=1e-14)


def test_sideband_order_against_carson():
    for beta in (0.05, 0.5, 2.0, 8.0):
        n = dm.sideband_order(beta, 1e-7)
        assert dm.bessel_tail(beta, n) <= 1e-14 < dm.bessel_tail(beta, n - 1) if n else True
        assert n >= beta + 1                                     # wider than Carson at 1e-7
    # Carson's rule keeps about 98 % of the power
    for beta in (1.0, 3.0, 10.0):
        assert dm.bessel_tail(beta, int(beta + 1)) < 0.03
    assert dm.carson_bandwidth(3.0, 200.0) == 1600.0
    assert dm.sideband_order(1e-9, 1e-7) == 0
    with pytest.raises(ValueError, match="tol"):
        dm.sideband_order(1.0, 0.0)


def test_sideband_margin_of_a_vibration():
    """z vibration: the platform margin is the Bessel order at beta = 4 pi A / lambda
    (two-way) times the vibration frequency in cycles per chirp."""
    cfg, pd = scene(sinusoid("z", 1e-4, 200.0), num_chirps=256)
    lam = dm._top_wavelength(cfg)
    beta = 4 * np.pi * 1e-4 / lam
    f_m = 200.0 * cfg.chirp_interval
    margin = dm.platform_sidebands(pd, cfg, 1e-6)
    n = dm.sideband_order(beta, dm.SIDEBAND_SHARE * 1e-6)
    assert margin == pytest.approx(n * f_m, rel=0.05)
    # without the sidebands the bound was the instantaneous Doppler only
    assert dm.doppler_bound(pd, cfg, 1e-6) > dm.doppler_bound(pd, cfg) + 0.9 * n * f_m


# ---------------------------------------------------------------- platforms
@pytest.mark.parametrize("seed", [0, 3])
@pytest.mark.parametrize("static", [True, False])
def test_hover_jitter(seed, static):
    cfg, pd = scene(hover_jitter(seed), num_paths=60, num_chirps=256, static=static, seed=seed)
    report = assert_within(pd, cfg)
    assert max(g["factor"] for g in report) >= 2, report


AMPLITUDES = (5e-6, 5e-5, 2e-4, 1e-3)                  # [m]
FREQUENCIES = (20.0, 60.0, 120.0, 200.0)               # [Hz]


@pytest.mark.parametrize("amplitude", AMPLITUDES)
@pytest.mark.parametrize("frequency", FREQUENCIES)
def test_vibration_grid(amplitude, frequency):
    """5 um - 1 mm x 20 - 200 Hz vertical vibration (with the slow paper motion under it)."""
    from raysim.bench.workloads import paper_setup

    traj = paper_setup()[2] + sinusoid("z", amplitude, frequency)
    cfg, pd = scene(traj)
    assert_within(pd, cfg)


@pytest.mark.parametrize("axis, amplitude", [("pitch", np.deg2rad(0.05)),
                                             ("roll", np.deg2rad(0.2))])
def test_rotational_vibration(axis, amplitude):
    """Frame vibration in attitude: the lever arm turns it into element motion."""
    cfg, pd = scene(sinusoid(axis, amplitude, 150.0), nx=4, ny=2)
    report = assert_within(pd, cfg)
    assert max(g["factor"] for g in report) >= 2, report


def test_tdm_array_under_vibration():
    """TDM 3Tx x 4Rx (three slots per chirp interval), hover jitter plus 0.1 mm at 200 Hz,
    moving clutter; a chirp range."""
    cfg = RadarConfig(num_chirps=160, num_tx_slots=3)
    arr = ti_3tx4rx(cfg.wavelength)
    pd = hover_paths(50, cfg, arr, hover_jitter(1) + sinusoid("z", 1e-4, 200.0), LEVER,
                     seed=4)
    report = assert_within(pd, cfg, chirps=range(10, 150))
    assert sum(g["paths"] for g in report) == pd.num_paths


# ---------------------------------------------------------------- moving scatterers
def _per_chirp(points, cfg, arr, trajectory=None, amp_seed=0):
    """PathDelays of point scatterers with per-chirp positions ``[path, chirp, 3]``."""
    rng = np.random.default_rng(amp_seed)
    n = points.shape[0]
    amp = (rng.normal(size=n) + 1j * rng.normal(size=n)) * 1e-4
    return PathDelays.for_array(points, points, np.zeros(n), amp, cfg, arr, trajectory,
                                lever_arm=LEVER)


@pytest.mark.parametrize("rate", [0.5, 3.0, 50.0])
def test_rotors(rate):
    """A rotor's blade scatterers (per-chirp positions) 8 m below a hovering platform:
    slow fans decimate, a 50 rev/s rotor (micro-Doppler beyond the chirp rate) is
    refused, and every cube stays within its tolerance."""
    from raysim.echoes.moving.rotors import Rotor

    cfg = PAPER_RADAR.with_(num_chirps=128)
    arr = upa(2, 1, wavelength=cfg.wavelength)
    rotor = Rotor("fan", hub=np.array([1.0, 0.5, 8.0]), rate=rate, blades=2,
                  blade_length=0.12, scatterers_per_blade=6)
    pts = rotor.positions(cfg.chirp_times(), cfg.wavelength)            # [path, chirp, 3]
    pd = _per_chirp(pts, cfg, arr, sinusoid("z", 2e-5, 120.0))
    report = assert_within(pd, cfg)
    if rate >= 50:
        assert all(g["factor"] == 1 for g in report), report
    else:
        assert max(g["factor"] for g in report) >= 2, report


def test_walking_movers():
    """Walkers: a body at 1.4 m/s (velocity form) and limbs swinging +-0.3 m at 1 Hz
    (per-chirp positions), over static ground, under hover jitter."""
    cfg = PAPER_RADAR.with_(num_chirps=128)
    arr = upa(2, 1, wavelength=cfg.wavelength)
    t = cfg.chirp_times()[None, :, None]
    rng = np.random.default_rng(5)
    base = rng.uniform(-5, 5, (8, 1, 3)) + [0, 0, 15]
    heading = np.array([1.0, 0.3, 0.0]) / np.linalg.norm([1.0, 0.3, 0.0])
    limbs = base + 1.4 * heading * t + 0.3 * heading * np.sin(2 * np.pi * 1.0 * t
                                                              + rng.uniform(0, 6, (8, 1, 1)))
    pd = _per_chirp(limbs, cfg, arr, hover_jitter(2))
    assert_within(pd, cfg)
    ground = hover_paths(40, cfg, arr, hover_jitter(2), LEVER, seed=6)   # 5 % walk (velocity)
    assert_within(ground, cfg)


# ---------------------------------------------------------------- the check itself
def test_check_catches_an_optimistic_bound(monkeypatch):
    """With the Doppler-only bound of before (no sidebands), the a-posteriori check halves
    the factor until the cube fits, and says so."""
    cfg, pd = scene(sinusoid("z", 1e-4, 200.0), num_chirps=256)
    doppler_only = dm.path_doppler
    monkeypatch.setattr(dm, "path_doppler", lambda src, config, tol=None: doppler_only(src,
                                                                                      config))
    report = assert_within(pd, cfg)
    assert any("halved" in g["reason"] for g in report), report


def test_check_refuses_what_it_cannot_fit(monkeypatch):
    """A vibration near the chirp rate's Nyquist limit with a bound that misses it: no
    factor fits, decimation is refused by the check (factor 1, reason) and the cube is
    exact."""
    cfg, pd = scene(sinusoid("z", 2e-4, 0.45 / PAPER_RADAR.chirp_interval))
    monkeypatch.setattr(dm, "path_doppler",
                        lambda src, config, tol=None: np.full(src.num_paths, 1e-3))
    report = assert_within(pd, cfg)
    assert all(g["factor"] == 1 for g in report), report
    assert any("check failed" in g["reason"] for g in report), report


def test_check_channels_and_errors():
    cfg, pd = scene(hover_jitter(0), nx=20, ny=20, num_paths=10)
    chk = dm.check_channels(pd)
    assert chk.size == 4 and np.all(np.diff(chk) > 0) and {0, 399} <= set(chk.tolist())
    assert dm.check_channels(pd, 1).size == 1
    with pytest.raises(ValueError, match="count"):
        dm.check_channels(pd, 0)
    sub = dm.channel_subset(pd, chk)
    np.testing.assert_allclose(sub.delays(3), pd.delays(3)[chk])
    a = np.ones((4, 2, 3), np.complex64)
    b = a.copy()
    b[2, 0, 0] += 0.1
    l2, row = dm.check_errors(b, a)
    assert l2 == pytest.approx(0.1 / np.sqrt(24), rel=1e-6)
    assert row == pytest.approx(0.1 / np.sqrt(6), rel=1e-6)
