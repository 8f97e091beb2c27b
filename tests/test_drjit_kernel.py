"""The Dr.Jit variant of the fused kernel against the complex128 direct sum.

Runs on Dr.Jit's LLVM backend here (the CUDA backend, used where a GPU is
present, is the same code and is not exercised by these tests). Skipped
without Dr.Jit or a usable backend.
"""

import numpy as np
import pytest
from path_sets import random_paths

from raysim.platform.motion import sinusoid
from raysim.radar.arrays import ti_3tx4rx, upa
from raysim.radar.config import RadarConfig
from raysim.synthesis import drjit_kernel
from raysim.synthesis.kernel import kernel_error
from raysim.synthesis.select import synthesize

pytestmark = pytest.mark.skipif(not drjit_kernel.available(), reason="Dr.Jit backend missing")

#: Tolerances the Dr.Jit kernel must meet (relative l2 error over the cube).
EPS_VALUES = (1e-3, 1e-5, 1e-6)


def rel_err(x, ref):
    return float(np.linalg.norm(x - ref) / np.linalg.norm(ref))


@pytest.mark.parametrize("eps", EPS_VALUES)
def test_drjit_error_below_tolerance_random_geometry(eps):
    """Near field, double bounces, per-chirp vertices, platform motion (LLVM backend)."""
    cfg = RadarConfig(num_chirps=3)
    rng = np.random.default_rng(11)
    traj = sinusoid("pitch", 0.05, 5.0) + sinusoid("x", 0.01, 3.0)
    for n in (1, 300):
        pd = random_paths(cfg, upa(4, 4, wavelength=cfg.wavelength), rng, n, trajectory=traj)
        ref = synthesize(pd, None, cfg, method="direct")
        got = drjit_kernel.synthesize_drjit(pd, cfg, eps=eps, use="llvm")
        assert got.dtype == np.complex64
        err = rel_err(got, ref)
        assert err < eps, (n, eps, err)
        assert err <= kernel_error(n, eps, cfg.num_samples, double_grid=True)[0]


def test_drjit_moving_scatterers_tdm_chirps_and_out():
    """Velocity form on TDM 3Tx x 4Rx, a sub-range of chirps added into ``out``, through
    ``synthesize(method="drjit")``."""
    cfg = RadarConfig(num_chirps=5, num_tx_slots=3)
    arr = ti_3tx4rx(cfg.wavelength)
    rng = np.random.default_rng(5)
    traj = sinusoid("roll", 0.03, 4.0) + sinusoid("z", 0.01, 2.0)
    pd = random_paths(cfg, arr, rng, 200, trajectory=traj, velocity=True)
    chirps = range(1, 4)
    ref = synthesize(pd, None, cfg, method="direct", chirps=chirps)
    out = np.full((3, arr.num_channels, cfg.num_samples), 1 + 1j, np.complex64)
    got = synthesize(pd, None, cfg, method="drjit", eps=1e-5, chirps=chirps, out=out)
    assert got is out
    assert rel_err(got - (1 + 1j), ref) < 1e-5


def test_drjit_bad_input():
    cfg = RadarConfig(num_chirps=2)
    tau = np.full((3, 2, 4), 2 * 10.0 / 299_792_458.0)
    with pytest.raises(ValueError, match="PathDelays"):
        synthesize(tau, 1.0, cfg, method="drjit", eps=1e-5)
    rng = np.random.default_rng(1)
    pd = random_paths(cfg, upa(2, 2, wavelength=cfg.wavelength), rng, 3)
    with pytest.raises(ValueError, match="use"):
        drjit_kernel.synthesize_drjit(pd, cfg, use="metal")
    with pytest.raises(ValueError, match="out"):
        drjit_kernel.synthesize_drjit(pd, cfg, out=np.zeros((1, 1, 1), np.complex64))


def test_auto_hands_many_compact_paths_to_drjit_only_on_cuda(monkeypatch):
    """``method="auto"``: the Dr.Jit kernel where a CUDA device is present, never on the CPU."""
    import raysim.synthesis.drjit_kernel as dk
    from raysim.synthesis.select import GPU_MIN_PATHS, choose_method

    shape = (GPU_MIN_PATHS, 256, 64, 256)
    monkeypatch.setattr(dk, "backend", lambda: "llvm")
    assert choose_method(*shape, 1e-5) != "drjit"
    monkeypatch.setattr(dk, "backend", lambda: "cuda")
    assert choose_method(*shape, 1e-5) == "drjit"
    assert choose_method(*shape, 1e-5, compact=False) != "drjit"     # dense delays: no geometry
    assert choose_method(GPU_MIN_PATHS - 1, *shape[1:], 1e-5) != "drjit"
