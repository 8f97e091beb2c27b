"""The fused exact kernel (compiled extension) against the complex128 direct sum.

Random path sets: near field (from 0.3 m), wide angles, double bounces with
interior length, per-chirp moving vertices, moving scatterers with TDM slots on
``ti_3tx4rx`` (bistatic element positions), platform motion. Skipped where the
extension is not built (``method="auto"`` then falls back to FINUFFT).
"""

import numpy as np
import pytest
from path_sets import random_paths

from raysim.platform.motion import sinusoid
from raysim.radar.arrays import ti_3tx4rx, upa
from raysim.radar.config import RadarConfig
from raysim.synthesis import kernel
from raysim.synthesis.nufft import PathDelays
from raysim.synthesis.select import choose_method, synthesize

pytestmark = pytest.mark.skipif(not kernel.available(), reason="kernel extension not built")

#: Tolerances the kernel must meet (relative l2 error over the cube).
EPS_VALUES = (1e-3, 1e-4, 1e-5, 1e-6)


def rel_err(x, ref):
    return float(np.linalg.norm(x - ref) / np.linalg.norm(ref))




@pytest.fixture(scope="module")
def short_radar():
    return RadarConfig(num_chirps=3)


@pytest.mark.parametrize("eps", EPS_VALUES)
def test_kernel_error_below_tolerance_random_geometry(short_radar, eps):
    rng = np.random.default_rng(11)
    traj = sinusoid("pitch", 0.05, 5.0) + sinusoid("x", 0.01, 3.0)
    for n in (1, 40, 400):
        pd = random_paths(short_radar, upa(4, 4, wavelength=short_radar.wavelength), rng, n,
                          trajectory=traj)
        ref = synthesize(pd, None, short_radar, method="direct")
        got = synthesize(pd, None, short_radar, method="kernel", eps=eps)
        assert got.dtype == np.complex64
        err = rel_err(got, ref)
        assert err < eps, (n, eps, err)
        assert err <= kernel.kernel_error(n, eps, short_radar.num_samples)[0]


@pytest.mark.parametrize("eps", (1e-4, 1e-6))
def test_kernel_moving_scatterers_tdm(eps):
    """Velocity form on the TDM 3Tx x 4Rx array (bistatic positions, per-slot instants)."""
    cfg = RadarConfig(num_chirps=4, num_tx_slots=3)
    arr = ti_3tx4rx(cfg.wavelength)
    rng = np.random.default_rng(5)
    traj = sinusoid("roll", 0.03, 4.0) + sinusoid("z", 0.01, 2.0)
    pd = random_paths(cfg, arr, rng, 300, trajectory=traj, velocity=True)
    assert pd.rx_positions is not None and pd.velocity is not None
    ref = synthesize(pd, None, cfg, method="direct")
    got = synthesize(pd, None, cfg, method="kernel", eps=eps)
    assert rel_err(got, ref) < eps
    # every single (chirp, channel) row, relative to its own norm
    row_err = np.linalg.norm(got - ref, axis=-1) / np.linalg.norm(ref, axis=-1)
    assert row_err.max() < 10 * eps


def test_kernel_many_paths_float32_grid():
    """2e4 paths at 1e-5: the float32 grid's accumulation stays inside the model."""
    cfg = RadarConfig(num_chirps=1)
    arr = upa(2, 2, wavelength=cfg.wavelength)
    pd = random_paths(cfg, arr, np.random.default_rng(9), 20_000, per_chirp=False)
    err_model, design = kernel.kernel_error(pd.num_paths, 1e-5, cfg.num_samples)
    assert not design.double_grid
    ref = synthesize(pd, None, cfg, method="direct")
    got = synthesize(pd, None, cfg, method="kernel", eps=1e-5)
    assert rel_err(got, ref) < min(1e-5, err_model)


def test_kernel_portable_matches_avx2(short_radar):
    pd = random_paths(short_radar, upa(3, 3, wavelength=short_radar.wavelength),
                      np.random.default_rng(2), 200)
    a = kernel.synthesize_kernel(pd, short_radar, eps=1e-6)
    b = kernel.synthesize_kernel(pd, short_radar, eps=1e-6, portable=True)
    assert rel_err(a, b) < 1e-6
    assert kernel.isa() in ("avx2", "portable")


def test_kernel_chirps_out_threads_and_amplitude_per_chirp(short_radar):
    rng = np.random.default_rng(3)
    pd = random_paths(short_radar, upa(3, 3, wavelength=short_radar.wavelength), rng, 50)
    amp = pd.amplitude[:, None] * np.exp(1j * rng.uniform(0, 6, (50, 3)))
    pd = PathDelays(pd.first_vertex, pd.last_vertex, pd.interior_length, amp, pd.tx_positions)
    ref = synthesize(pd, None, short_radar, method="direct")
    out = np.ones((2, 9, short_radar.num_samples), np.complex64)
    got = synthesize(pd, None, short_radar, method="kernel", eps=1e-5, chirps=range(1, 3),
                     out=out, threads=2)
    assert got is out
    assert rel_err(got - 1.0, ref[1:]) < 1e-5


def test_kernel_bad_input(short_radar):
    with pytest.raises(ValueError, match="PathDelays"):
        synthesize(np.zeros((2, 3, 4)), 1.0, short_radar, method="kernel")
    pd = random_paths(short_radar, upa(2, 2, wavelength=short_radar.wavelength),
                      np.random.default_rng(1), 3)
    with pytest.raises(ValueError, match="eps"):
        synthesize(pd, None, short_radar, method="kernel", eps=1e-9)
    with pytest.raises(ValueError, match="threads"):
        kernel.synthesize_kernel(pd, short_radar, threads=0)
    with pytest.raises(ValueError, match="out"):
        kernel.synthesize_kernel(pd, short_radar, out=np.zeros((1, 1, 1), np.complex64))


def test_auto_picks_kernel_for_compact_paths():
    assert choose_method(100_000, 256, 400, 600, 1e-5) == "kernel"
    assert choose_method(100_000, 256, 400, 600, 1e-5, compact=False) == "nufft"
