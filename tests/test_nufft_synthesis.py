"""NUFFT synthesis against the complex128 direct sum, and the automatic method choice.

References are re-derived here in plain NumPy (``ref_tone_sum``) or taken from
:func:`raysim.synthesis.tones.synthesize_if_direct`; tolerances are named constants.
"""

import numpy as np
import pytest
from path_sets import random_paths

from raysim.echoes.oracle import PointTarget, point_target_delays, simulate_point_targets
from raysim.platform.motion import sinusoid
from raysim.radar.arrays import ti_3tx4rx, upa
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.nufft import PathDelays, element_positions, synthesize_nufft
from raysim.synthesis.select import choose_method, estimate_seconds, synthesize, tones_error
from raysim.synthesis.tones import synthesize_if_direct

#: Tolerances the NUFFT must meet (relative l2 error over the cube).
EPS_VALUES = (1e-3, 1e-4, 1e-5, 1e-6)
#: PathDelays delays against an independent per-element norm [s].
DELAY_ATOL = 1e-19


def rel_err(x, ref):
    return float(np.linalg.norm(x - ref) / np.linalg.norm(ref))


def ref_tone_sum(tau, amp, cfg):
    """Plain NumPy tone sum over all axes at once (small inputs only)."""
    t = cfg.fast_time()
    ph = 2j * np.pi * (cfg.carrier_frequency * tau[..., None] + cfg.chirp_rate * tau[..., None] * t
                       - 0.5 * cfg.chirp_rate * tau[..., None] ** 2)
    return np.sum(amp[..., None] * np.exp(ph), axis=0)


@pytest.fixture(scope="module")
def short_radar():
    return RadarConfig(num_chirps=3)




def test_pathdelays_match_per_element_norm(short_radar, rng):
    arr = ti_3tx4rx(short_radar.wavelength)
    cfg = short_radar.with_(num_tx_slots=3)
    traj = sinusoid("roll", 0.02, 3.0) + sinusoid("z", 0.01, 4.0)
    pd = random_paths(cfg, arr, rng, 20, trajectory=traj)
    tau, _ = pd.dense()
    tx, rx = element_positions(cfg, arr, traj)
    assert rx is not None
    d_tx = np.linalg.norm(pd.first_vertex[:, :, None, :] - tx[None], axis=-1)
    d_rx = np.linalg.norm(pd.last_vertex[:, None, None, :] - rx[None], axis=-1)
    ref = (d_tx + pd.interior_length[:, None, None] + d_rx) / SPEED_OF_LIGHT
    np.testing.assert_allclose(tau, ref, rtol=0, atol=DELAY_ATOL)


@pytest.mark.parametrize("eps", EPS_VALUES)
def test_nufft_error_below_tolerance_random_geometry(short_radar, eps):
    rng = np.random.default_rng(int(-np.log10(eps)))
    arr = upa(6, 5, wavelength=short_radar.wavelength)
    traj = sinusoid("pitch", 0.03, 2.0) + sinusoid("y", 0.005, 7.0)
    pd = random_paths(short_radar, arr, rng, 400, trajectory=traj)
    tau, amp = pd.dense()
    ref = synthesize_if_direct(tau, amp, short_radar)
    got = synthesize_nufft(pd, None, short_radar, eps=eps, threads=2)
    assert got.dtype == np.complex64
    assert rel_err(got, ref) < eps
    got_dense = synthesize_nufft(tau, amp, short_radar, eps=eps, threads=1)
    assert rel_err(got_dense, ref) < eps


def test_nufft_error_per_channel_and_chirp(short_radar, rng):
    """Not only the total: every (chirp, channel) row meets the tolerance."""
    arr = upa(4, 4, wavelength=short_radar.wavelength)
    pd = random_paths(short_radar, arr, rng, 300, near=0.1)
    tau, amp = pd.dense()
    ref = synthesize_if_direct(tau, amp, short_radar)
    got = synthesize_nufft(pd, None, short_radar, eps=1e-5)
    row_err = np.linalg.norm(got - ref, axis=-1) / np.linalg.norm(ref, axis=-1)
    assert row_err.max() < 1e-5


def test_nufft_matches_plain_numpy_reference(rng):
    cfg = RadarConfig(num_chirps=2, chirp_duration=20e-6)      # 200 samples (odd shift path)
    tau = rng.uniform(1e-8, 0.9 * 2 * cfg.max_range / SPEED_OF_LIGHT, (50, 2, 3))
    amp = rng.normal(size=tau.shape) + 1j * rng.normal(size=tau.shape)
    ref = ref_tone_sum(tau, amp, cfg)
    assert rel_err(synthesize_nufft(tau, amp, cfg, eps=1e-6), ref) < 1e-6
    cfg_odd = RadarConfig(num_chirps=2, chirp_duration=20.1e-6)  # 201 samples
    assert cfg_odd.num_samples % 2 == 1
    ref = ref_tone_sum(tau, amp, cfg_odd)
    assert rel_err(synthesize_nufft(tau, amp, cfg_odd, eps=1e-6), ref) < 1e-6


def test_nufft_chirp_subset_and_out_accumulates(short_radar, rng):
    arr = upa(3, 3, wavelength=short_radar.wavelength)
    pd = random_paths(short_radar, arr, rng, 60)
    full = synthesize_nufft(pd, None, short_radar, eps=1e-6)
    part = np.ones((2, 9, short_radar.num_samples), dtype=np.complex64)
    synthesize_nufft(pd, None, short_radar, eps=1e-6, out=part, chirps=range(1, 3))
    np.testing.assert_allclose(part - 1, full[1:], atol=1e-6 * np.abs(full).max())


def test_point_targets_same_api_as_oracle(short_radar, small_upa):
    """Point targets through ``synthesize`` (every method) equal the oracle's frame."""
    targets = [PointTarget.at(12.0, 0.3, -0.2, velocity=(0.5, 0, 0)),
               PointTarget.at(30.0, -0.5, 0.1)]
    traj = sinusoid("x", 2e-3, 5.0)
    oracle = simulate_point_targets(short_radar, small_upa, targets, traj).data
    tau, amp = point_target_delays(short_radar, small_upa, traj, targets)
    for method in ("direct", "tones", "nufft", "auto"):
        eps = 1e-5 if method == "tones" else 1e-6
        got = synthesize(tau, amp, short_radar, method=method, eps=eps)
        assert rel_err(got, oracle) < 2e-6, method


def test_synthesize_methods_agree_on_pathdelays(short_radar, rng):
    arr = upa(3, 4, wavelength=short_radar.wavelength)
    pd = random_paths(short_radar, arr, rng, 40)
    ref = synthesize(pd, None, short_radar, method="direct")
    assert ref.dtype == np.complex128
    assert rel_err(synthesize(pd, None, short_radar, method="tones", eps=1e-5), ref) < 1e-6
    assert rel_err(synthesize(pd, None, short_radar, method="nufft", eps=1e-6), ref) < 1e-6
    sub = synthesize(pd, None, short_radar, method="direct", chirps=range(2, 3))
    np.testing.assert_allclose(sub, ref[2:3])


def test_auto_choice():
    from raysim.synthesis import kernel

    assert choose_method(1, 256, 400, 600, 1e-5) == "tones"
    # arrays of delays (no geometry): the fused kernel does not apply
    assert choose_method(100_000, 256, 400, 600, 1e-5, compact=False) == "nufft"
    # compact paths: the fused kernel where it is built, else FINUFFT
    assert choose_method(100_000, 256, 400, 600, 1e-5) == (
        "kernel" if kernel.available() else "nufft")
    assert choose_method(1000, 256, 400, 600, 1e-7) == "direct"
    # complex64 accumulation: many tones cannot reach 1e-6 whatever they cost
    assert tones_error(100_000) > 1e-6 > tones_error(10)
    assert choose_method(100_000, 1, 1, 600, 1e-6, compact=False) == "nufft"
    assert estimate_seconds("nufft", 1e5, 256, 400, 600, 1e-5) * 50 < estimate_seconds(
        "direct", 1e5, 256, 400, 600)


@pytest.mark.parametrize(("kwargs", "word"), [
    (dict(method="fft"), "method"),
    (dict(eps=0.0), "eps"),
    (dict(eps=2.0), "eps"),
    (dict(eps=1e-9, method="nufft"), "eps"),
    (dict(eps=1e-7, method="tones"), "eps"),
    (dict(chirps=range(0, 9)), "chirps"),
    (dict(chirps=range(0, 3, 2)), "chirps"),
])
def test_bad_arguments(short_radar, kwargs, word):
    tau = np.full((2, 3, 4), 1e-7)
    with pytest.raises(ValueError, match=word):
        synthesize(tau, 1.0, short_radar, **kwargs)


def test_bad_inputs(short_radar):
    with pytest.raises(ValueError, match="tau"):
        synthesize_nufft(np.zeros((2, 3)), 1.0, short_radar)
    with pytest.raises(ValueError, match="amplitude"):
        synthesize_nufft(np.zeros((2, 3, 4)), np.ones((5,)), short_radar)
    with pytest.raises(ValueError, match="amplitude"):
        synthesize(np.zeros((2, 3, 4)), None, short_radar)
    tx = np.zeros((3, 4, 3))
    with pytest.raises(ValueError, match="first_vertex"):
        PathDelays(np.zeros((2, 2)), np.zeros((2, 3)), np.zeros(2), np.ones(2), tx)
    with pytest.raises(ValueError, match="interior_length"):
        PathDelays(np.ones((2, 3)), np.ones((2, 3)), -np.ones(2), np.ones(2), tx)
    with pytest.raises(ValueError, match="amplitude"):
        PathDelays(np.ones((2, 3)), np.ones((2, 3)), np.zeros(2), np.ones(3), tx)
    pd = PathDelays(np.ones((2, 3)), np.ones((2, 3)), np.zeros(2), np.ones(2), tx)
    with pytest.raises(ValueError, match="amplitude must be None"):
        synthesize(pd, 1.0, short_radar)
    with pytest.raises(ValueError, match="threads"):
        synthesize_nufft(pd, None, short_radar, threads=0)


def test_moving_scatterers_tdm_exact(rng):
    """Velocity form: vertices move to each channel's own transmit instant (TDM slots)."""
    cfg = RadarConfig(num_chirps=3, num_tx_slots=3)
    arr = ti_3tx4rx(cfg.wavelength)
    n = 30
    first = rng.uniform(-10, 10, (n, 3)) + [0, 0, 25]
    last = first + rng.normal(0, 2, (n, 3)) * (rng.random((n, 1)) < 0.5)
    vel = rng.normal(0, 5, (n, 3))
    pd = PathDelays.for_array(first, last, np.zeros(n), np.ones(n), cfg, arr, velocity=vel,
                              reference_time=1e-4)
    tau, _ = pd.dense()
    tx, rx = element_positions(cfg, arr)
    times = cfg.chirp_times()[:, None] + arr.tx_slot[None, :] * cfg.slot_interval
    shift = vel[:, None, None, :] * (times[None, :, :, None] - 1e-4)
    ref = (np.linalg.norm(first[:, None, None] + shift - tx[None], axis=-1)
           + np.linalg.norm(last[:, None, None] + shift - rx[None], axis=-1)) / SPEED_OF_LIGHT
    np.testing.assert_allclose(tau, ref, rtol=0, atol=DELAY_ATOL)


def test_from_pathset_matches_reprojection(rng):
    trace = pytest.importorskip("raysim.echoes.rt.trace")
    reproject = pytest.importorskip("raysim.echoes.rt.reproject")
    cfg = RadarConfig(num_chirps=4, num_tx_slots=3)
    arr = ti_3tx4rx(cfg.wavelength)
    n = 40
    f = rng.uniform(-10, 10, (n, 3)) + [0, 0, 20]
    last = f + rng.normal(0, 1, (n, 3)) * (rng.random((n, 1)) < 0.5)
    length = (np.linalg.norm(f, axis=1) + np.linalg.norm(last, axis=1)
              + np.linalg.norm(f - last, axis=1))
    length[0] = 3 * cfg.max_range                                  # culled: outside the band
    vel = rng.normal(0, 2, (n, 3)) * (rng.random((n, 1)) < 0.3)
    origin = np.zeros(3)
    ps = trace.PathSet(f, last, length, rng.normal(size=n) + 0j, vel, np.zeros(n),
                       np.zeros((n, 2), np.uint32), np.zeros(n, np.uint32),
                       np.zeros((n, 2, 2), complex), length / SPEED_OF_LIGHT, origin, origin,
                       trace_time=2e-4)
    traj = sinusoid("roll", 0.01, 3.0)
    ref = reproject.reproject(ps, cfg, arr, traj)
    pd = PathDelays.from_pathset(ps, cfg, arr, traj)
    tau, amp = pd.dense()
    assert pd.num_paths == ref.tau.shape[0] == n - 1
    np.testing.assert_allclose(tau, ref.tau, rtol=0, atol=DELAY_ATOL)
    # one amplitude per path: reproject's element gain at the frame's middle chirp
    mid = cfg.num_chirps // 2
    np.testing.assert_allclose(amp, np.broadcast_to(ref.amplitude[:, mid:mid + 1], amp.shape),
                               rtol=1e-12)


# ---------------------------------------------------------------- speed-accuracy chart
def test_pareto_front_rules():
    from raysim.bench.speed_chart import pareto_front

    # (time, error): b is dominated by a (faster, as accurate); d is within the time
    # tolerance of a and more accurate (both stay); c is slowest but most accurate; e is
    # as fast as b and more accurate, but a still beats it
    front = pareto_front([1.0, 2.0, 5.0, 1.05, 2.0], [1e-3, 1e-3, 1e-9, 1e-4, 1e-3 * 0.5])
    assert front.tolist() == [True, False, True, True, False]
    with pytest.raises(ValueError, match="times"):
        pareto_front([1.0], [1.0, 2.0])


def test_chart_measures_every_knob(monkeypatch, tmp_path):
    """Every knob measured on a reduced frame, with one default and exact references.

    Whether the default is on the front is a timing, reported by the chart and the
    benchmark (docs/speed.md), not asserted here: a unit test's timings move with the
    machine's load."""
    from raysim.bench import speed_chart as sa
    from raysim.bench import workloads

    full = workloads.paper_setup

    def small_setup(num_chirps=16):
        cfg, _, traj, lever = full(16)
        return cfg, upa(4, 4, wavelength=cfg.wavelength), traj, lever

    # enough paths per (chirp, channel) row that per-path work, not call overhead, sets
    # the time (as on the paper frame)

    monkeypatch.setattr(workloads, "paper_setup", small_setup)
    monkeypatch.setattr(sa, "REPEAT", 3)
    monkeypatch.setattr(sa, "KNOB_PATHS", 3000)
    measured = sa.measure_knobs(quick=True, log=lambda m: None, rt=False)
    names = [k["knob"] for k in measured["knobs"]]
    from raysim.synthesis import kernel

    if kernel.available():
        assert names == ["nufft_eps", "kernel_eps", "decimation", "motion", "geometry",
                         "chirp_block"]
    else:
        assert names == ["nufft_eps", "motion", "geometry", "chirp_block"]
        assert "kernel not built" in measured["not_measured"]["kernel_eps_decimation"]
    assert "tube-density" in measured["not_measured"]["rt_samples_depth_retrace"]
    for k in measured["knobs"]:
        assert sum(s["default"] for s in k["settings"]) == 1, k["knob"]
        assert all(s["s_per_frame"] > 0 for s in k["settings"]), k["knob"]
        assert isinstance(k["default_on_front"], bool)
        ref = [s for s in k["settings"] if s.get("reference")]
        assert all(s["rel_error"] == 0.0 for s in ref)
    png = tmp_path / "chart.png"
    sa.draw_chart(measured, png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
