"""Slow-time decimation: error against the complex128 direct sum, and refusals."""

import numpy as np
import pytest

from raysim.bench.workloads import hover_paths, paper_setup, subset
from raysim.radar.arrays import ti_3tx4rx
from raysim.radar.config import RadarConfig
from raysim.synthesis import kernel
from raysim.synthesis.decimate import (
    MIN_CHIRPS,
    doppler_bound,
    interpolation_error,
    plan_decimation,
)
from raysim.synthesis.nufft import PathDelays
from raysim.synthesis.select import synthesize


def rel_err(x, ref):
    return float(np.linalg.norm(x - ref) / np.linalg.norm(ref))


@pytest.fixture(scope="module")
def hover():
    """300 hover paths (5 % moving) on the paper radar, 256 chirps x 4 channels."""
    cfg, arr, traj, lever = paper_setup()
    pd = subset(hover_paths(300, cfg, arr, traj, lever, seed=7), 256, 4)
    return cfg, pd, synthesize(pd, None, cfg, method="direct")


@pytest.mark.parametrize("method", ["nufft", "kernel"])
@pytest.mark.parametrize("eps", (1e-4, 1e-5))
def test_decimation_error_below_tolerance(hover, method, eps):
    if method == "kernel" and not kernel.available():
        pytest.skip("kernel extension not built")
    cfg, pd, ref = hover
    plan = plan_decimation(pd, cfg, 256, 0.1 * eps)
    assert plan.factor >= 2, plan.reason
    assert plan.exact.size + plan.missing.size == 256
    got = synthesize(pd, None, cfg, method=method, eps=eps, decimate="auto")
    assert rel_err(got, ref) < eps
    # interpolated chirps alone, against their own norm
    miss = plan.missing
    assert rel_err(got[miss], ref[miss]) < eps


def test_decimation_tdm_moving_scatterers():
    """TDM 3Tx x 4Rx with moving scatterers (velocity form), chirps range and out."""
    cfg = RadarConfig(num_chirps=160, num_tx_slots=3)
    arr = ti_3tx4rx(cfg.wavelength)
    rng = np.random.default_rng(4)
    n = 60
    first = rng.uniform(-10, 10, (n, 3)) + [0, 0, 25]
    last = first + rng.normal(0, 2, (n, 3)) * (rng.random((n, 1)) < 0.5)
    vel = rng.normal(0, 0.3, (n, 3))                   # walking-speed clutter [m/s]
    amp = rng.normal(size=n) + 1j * rng.normal(size=n)
    pd = PathDelays.for_array(first, last, np.zeros(n), amp, cfg, arr, velocity=vel)
    chirps = range(10, 150)
    ref = synthesize(pd, None, cfg, method="direct", chirps=chirps)
    assert plan_decimation(pd, cfg, len(chirps), 1e-6).factor >= 2
    out = np.zeros((len(chirps), arr.num_channels, cfg.num_samples), np.complex64)
    method = "kernel" if kernel.available() else "nufft"
    got = synthesize(pd, None, cfg, method=method, eps=1e-5, decimate="auto", chirps=chirps,
                     out=out)
    assert got is out
    assert rel_err(got, ref) < 1e-5


def test_refusals(hover):
    cfg, pd, _ = hover
    # too few chirps
    assert plan_decimation(pd, cfg, MIN_CHIRPS - 1, 1e-6).factor == 1
    assert "few chirps" in plan_decimation(pd, cfg, MIN_CHIRPS - 1, 1e-6).reason
    # amplitudes given per chirp: constant ones plan as the per-path ones; amplitudes
    # that flip sign every chirp (0.5 cycles/chirp) are too wide for any factor
    amp = np.broadcast_to(pd.amplitude[:, None], (pd.num_paths, 256)).copy()
    varying = PathDelays(pd.first_vertex, pd.last_vertex, pd.interior_length, amp,
                         pd.tx_positions, pd.rx_positions, pd.velocity, pd.element_times)
    plan = plan_decimation(varying, cfg, 256, 1e-6)
    assert plan.factor == plan_decimation(pd, cfg, 256, 1e-6).factor > 1
    flip = PathDelays(pd.first_vertex, pd.last_vertex, pd.interior_length,
                      amp * (-1.0) ** np.arange(256), pd.tx_positions, pd.rx_positions,
                      pd.velocity, pd.element_times)
    plan = plan_decimation(flip, cfg, 256, 1e-6)
    assert plan.factor == 1 and "too wide" in plan.reason
    # Doppler band too wide: fast scatterers (40 m/s)
    fast = PathDelays(pd.first_vertex, pd.last_vertex, pd.interior_length, pd.amplitude,
                      pd.tx_positions, pd.rx_positions, np.full((pd.num_paths, 3), 25.0),
                      pd.element_times)
    assert doppler_bound(fast, cfg) > 0.25
    plan = plan_decimation(fast, cfg, 256, 1e-6)
    assert plan.factor == 1 and "too wide" in plan.reason
    # refused decimation renders every chirp exactly
    direct = synthesize(fast, None, cfg, method="direct", chirps=range(0, 2))
    sub = subset(fast, 2, 4)
    got = synthesize(sub, None, cfg, method="nufft", eps=1e-5, decimate="auto")
    assert rel_err(got, direct) < 1e-5
    # an explicit factor beyond the band is refused, not applied
    assert plan_decimation(pd, cfg, 256, 1e-6, 40).factor == 1
    assert plan_decimation(pd, cfg, 256, 1e-6, 1).reason == "decimate=1"


def test_error_model_and_bad_input(hover):
    cfg, pd, _ = hover
    assert interpolation_error(0.1, 2) < interpolation_error(0.1, 4) < 1e-3
    assert interpolation_error(0.3, 2) == np.inf
    for bad in (0, -1, 1.5, "x", True):
        with pytest.raises(ValueError, match="decimate"):
            plan_decimation(pd, cfg, 256, 1e-6, bad)
        with pytest.raises(ValueError, match="decimate"):
            synthesize(pd, None, cfg, method="nufft", decimate=bad)


def test_auto_picks_the_factor_with_fewest_exact_chirps(hover):
    """The edge margins grow with the factor: "auto" minimises the exact chirps."""
    cfg, pd, _ = hover
    plan = plan_decimation(pd, cfg, 256, 1e-6)
    assert plan.factor >= 2, plan.reason
    for d in range(2, 9):
        other = plan_decimation(pd, cfg, 256, 1e-6, d)
        if other.factor == d:
            assert plan.exact.size <= other.exact.size, (plan.factor, d)


def test_decimation_near_the_eps_floor_renders_every_chirp(hover):
    """At eps just above the floor the rows' share would fall below it: no decimation."""
    from raysim.synthesis.nufft import MIN_EPS

    cfg, pd, ref = hover
    sub = subset(pd, 256, 1)
    got = synthesize(sub, None, cfg, method="nufft", eps=1.05 * MIN_EPS, decimate="auto")
    assert rel_err(got, ref[:, :1]) < 1.05 * MIN_EPS


# tolerance of the slow-time interpolation used below (the share of eps=1e-5)
INTERP_TOL = 1e-6


@pytest.mark.parametrize("band, factor", [(0.14, 2), (0.06, 5), (0.008, 32)])
def test_weights_meet_their_error_on_pure_tones(band, factor):
    """A slow-time tone exp(j 2 pi f n), |f| <= band, is interpolated within each chirp's
    modelled error (the max of |E(f)|, module docstring); beyond the decimated Nyquist
    limit it is not (so the check can fail)."""
    from raysim.synthesis.decimate import _plan_band, scatter_add

    plan = _plan_band(256, band, INTERP_TOL, factor)
    assert plan.factor == factor, plan.reason
    assert plan.error <= INTERP_TOL
    n = np.arange(256)
    worst = 0.0
    for f in np.linspace(-band, band, 41):
        tone = np.exp(2j * np.pi * f * n).astype(np.complex64)[:, None]
        got = np.zeros_like(tone)
        scatter_add(got, np.ascontiguousarray(tone[plan.exact]), plan)
        np.testing.assert_array_equal(got[plan.exact], tone[plan.exact])
        worst = max(worst, float(np.abs(got - tone)[plan.missing].max()))
    # float32 arithmetic: rounding of the weights, of the complex64 samples and of the
    # sum, each 2^-24 relative, weighted by the l1 norm of a chirp's weights
    rounding = 3 * 2.0**-24 * float(np.abs(plan.weights).sum(axis=1).max()) + 2.0**-24
    assert worst <= plan.error + rounding
    alias = 0.5 / factor + 0.5 * (0.5 / factor - band)            # above decimated Nyquist
    tone = np.exp(2j * np.pi * alias * n).astype(np.complex64)[:, None]
    got = np.zeros_like(tone)
    scatter_add(got, np.ascontiguousarray(tone[plan.exact]), plan)
    assert float(np.abs(got - tone).max()) > 100 * INTERP_TOL


def test_groups_split_static_from_moving():
    """Static scatterers (platform motion only) get a larger factor than walking clutter
    once there are enough paths to pay for a group's own rows; every path is in exactly
    one group, and each group's plan covers its own bound."""
    from raysim.synthesis.decimate import path_doppler, plan_groups

    cfg, arr, traj, lever = paper_setup()
    pd = subset(hover_paths(3000, cfg, arr, traj, lever, seed=2), 256, 4)
    bound = path_doppler(pd, cfg)
    groups = plan_groups(pd, cfg, 256, INTERP_TOL)
    members = np.concatenate([g for g, _ in groups])
    np.testing.assert_array_equal(np.sort(members), np.arange(pd.num_paths))
    static = np.flatnonzero(~np.any(pd.velocity != 0, axis=1))
    factors = {}
    for g, plan in groups:
        assert bound[g].max() <= plan.doppler * (1 + 1e-12)
        for p in g:
            factors[int(p)] = plan.factor
    moving = np.setdiff1d(np.arange(pd.num_paths), static)
    assert min(factors[int(p)] for p in static) >= 8
    assert min(factors[int(p)] for p in static) > max(factors[int(p)] for p in moving)
    assert doppler_bound(pd, cfg) == pytest.approx(bound.max())


def test_scatter_add_checks_its_input(hover):
    from raysim.synthesis.decimate import scatter_add

    cfg, pd, _ = hover
    plan = plan_decimation(pd, cfg, 256, INTERP_TOL)
    out = np.zeros((256, 4), np.complex64)
    with pytest.raises(ValueError, match="exact_rows"):
        scatter_add(out, np.zeros((plan.exact.size + 1, 4), np.complex64), plan)
    with pytest.raises(ValueError, match="complex64"):
        scatter_add(out.astype(np.complex128), np.zeros((plan.exact.size, 4), np.complex64),
                    plan)


def test_still_platform_static_paths_apart():
    """A still platform: static paths have a zero band and get their own group (few
    exact chirps); the moving ones keep theirs. The render stays within eps."""
    from raysim.radar.arrays import upa
    from raysim.synthesis.decimate import plan_groups

    cfg = RadarConfig(num_chirps=128, chirp_duration=20e-6)
    arr = upa(1, 1, wavelength=cfg.wavelength)
    rng = np.random.default_rng(3)
    n = 400
    first = rng.uniform(-5, 5, (n, 3)) + [0, 0, 12]
    vel = rng.normal(0, 1.0, (n, 3)) * (rng.random((n, 1)) < 0.1)
    amp = rng.normal(size=n) + 1j * rng.normal(size=n)
    pd = PathDelays.for_array(first, first, np.zeros(n), amp, cfg, arr, velocity=vel)
    groups = plan_groups(pd, cfg, 128, 1e-6)
    assert len(groups) >= 2
    static = np.flatnonzero(~np.any(vel != 0, axis=1))
    still = [p for g, p in groups if np.isin(g, static).all()]
    assert still and still[0].exact.size < 16
    ref = synthesize(pd, None, cfg, method="direct")
    method = "kernel" if kernel.available() else "nufft"
    got = synthesize(pd, None, cfg, method=method, eps=1e-5, decimate="auto")
    assert rel_err(got, ref) < 1e-5
