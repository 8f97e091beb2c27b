"""RealtimeProjector: the same beams as the direct engine (float32 rounding), and its refusals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation import rigid_body_projection
from compensation.realtime import ENGINES, SMALL_PHASE, RealtimeProjector, compiled_isa
from compensation.strapdown import PlatformMotion

LAM = 3.8685e-3
#: Largest difference from the direct engine relative to the beams' peak: float32
#: rounding of phases up to ~200 rad and of complex64 products over 12-64 channels.
RT_TOL = 2e-6


def _ti_positions(lam=LAM):
    """TI-style 3 Tx x 4 Rx virtual layout (tx major, rx minor) and its TDM slots."""
    d = lam / 2
    rx = np.array([[i * d, 0.0, 0.0] for i in range(4)])
    tx = np.array([[0.0, 0.0, 0.0], [2 * d, d, 0.0], [4 * d, 0.0, 0.0]])
    return (tx[:, None] + rx[None]).reshape(-1, 3), np.repeat(np.arange(3), 4)


def _motion(rng, n, *, disp_m=0.03, angle_rad=0.15):
    t = np.arange(n) * 51.2e-6
    rot = Rotation.from_rotvec(rng.uniform(-angle_rad, angle_rad, (n, 3))).as_matrix()
    pos = rng.uniform(-disp_m, disp_m, (n, 3))
    z = np.zeros((n, 3))
    return PlatformMotion(t, rot, pos, z, z.copy(), np.array([0.1, 0.0, 0.02]),
                          warnings=("hover window",))


def _cube(rng, n, m, r):
    return (rng.standard_normal((n, m, r)) + 1j * rng.standard_normal((n, m, r))).astype(
        np.complex64)


#: The compiled kernel's copies where the extension is built (``"compiled"`` is the
#: AVX-512 copy on a CPU with AVX-512, ``"avx2"`` the copy without it); the NumPy engine
#: always.
BUILT = compiled_isa() != "missing"
ENGINE_CASES = ["numpy"] + [pytest.param(e, marks=pytest.mark.skipif(
    not BUILT, reason="extension compensation._native._ext not built")) for e in ("compiled",
                                                                               "avx2",
                                                                               "portable")]


def _expected_engine(engine: str) -> str:
    """The copy an engine runs here: the kernel's dispatch for its request."""
    from compensation.realtime import _ISA_REQUEST, _ext

    return engine if engine == "numpy" else _ext.isa(_ISA_REQUEST[engine])


def _compare(rc, p, motion, *, slot=None, weights=None, gate_block=8, threads=2,
             engine="auto", **kw):
    ref = rigid_body_projection(rc, p, motion, channel_slot=slot, method="direct",
                                weights=weights, gate_block=gate_block, **kw)
    proj = RealtimeProjector(p, channel_slot=slot, weights=weights, gate_block=gate_block,
                             chirp_block=5, threads=threads, engine=engine, **kw)
    assert proj.engine == _expected_engine(engine)
    out = proj.project(rc, motion)
    assert out.data.shape == ref.data.shape and out.data.dtype == np.complex64
    np.testing.assert_allclose(out.chirp_time, ref.chirp_time)
    np.testing.assert_allclose(out.range, ref.range)
    assert out.warnings == ref.warnings == ("hover window",)
    err = np.abs(out.data - ref.data).max() / np.abs(ref.data).max()
    assert err < RT_TOL, err
    return err


@pytest.mark.parametrize("engine", ENGINE_CASES)
@pytest.mark.parametrize("threads, gate_block", [(1, 3), (2, 3), (2, 5)])
def test_tdm_ti_layout_equals_direct_engine(threads, gate_block, engine):
    """3 slots on lines (Horner form), own pose per slot, two gate blocks, ranges 2-14 m.

    ``gate_block=5`` leaves the last gate alone in its block, at its focal range
    (no per-gate phase: the kernel's shorter path), next to a block of five.
    """
    rng = np.random.default_rng(4)
    p, slot = _ti_positions()
    n, r = 24, 90
    motion = _motion(rng, 3 * n)
    r_axis = np.linspace(1.0, 14.0, r)
    az = np.deg2rad(np.linspace(-40, 40, 9))
    el = np.deg2rad(np.linspace(-20, 25, 7))
    _compare(_cube(rng, n, 12, r), p, motion, slot=slot, wavelength=LAM, range_axis=r_axis,
             azimuth=az, elevation=el, range_gates=[8, 9, 10, 50, 51, 88],
             gate_block=gate_block, threads=threads, engine=engine)


@pytest.mark.parametrize("engine", ENGINE_CASES)
def test_grid_layout_with_taper_and_large_motion_equals_direct_engine(engine):
    """8 x 8 UPA in one slot (the kernel's lattice form, the NumPy engine's matrix product),
    taper, 10 cm displacements at 1-3 m (per-gate phases beyond the Taylor range, so the
    sin/cos path is used too)."""
    rng = np.random.default_rng(5)
    ix, iy = np.divmod(np.arange(64), 8)
    p = np.stack([ix * LAM / 2, iy * LAM / 2, np.zeros(64)], axis=1)
    taper = np.hanning(10)[1:9]
    n, r = 12, 40
    motion = _motion(rng, n, disp_m=0.1, angle_rad=0.3)
    r_axis = np.linspace(1.0, 3.0, r)
    d = motion.radar_displacement
    assert np.abs(d).max() > 0.05
    _compare(_cube(rng, n, 64, r), p, motion, weights=np.outer(taper, taper).ravel(),
             wavelength=LAM, range_axis=r_axis, azimuth=np.deg2rad([-30.0, 0.0, 12.0]),
             elevation=np.deg2rad([-10.0, 5.0]), range_gates=np.arange(0, 40, 5), gate_block=8,
             engine=engine)
    assert SMALL_PHASE < 2 * 2 * np.pi / LAM * 0.1 * 0.1 / 1.0


@pytest.mark.parametrize("engine", ENGINE_CASES)
def test_static_platform_unit_echo_gives_one(engine):
    p, slot = _ti_positions()
    t = np.arange(3 * 4) * 51.2e-6
    z = np.zeros((t.size, 3))
    motion = PlatformMotion(t, np.broadcast_to(np.eye(3), (t.size, 3, 3)).copy(), z, z.copy(),
                            z.copy(), np.zeros(3))
    proj = RealtimeProjector(p, channel_slot=slot, wavelength=LAM, range_axis=[10.0, 10.15],
                             azimuth=[0.0], elevation=[0.0], range_gates=[0, 1], engine=engine)
    out = proj.project(np.ones((4, 12, 2), np.complex64), motion)
    np.testing.assert_allclose(np.abs(out.data), 1.0, atol=1e-6)


@pytest.mark.parametrize("kwargs, match", [
    (dict(range_gates=[5]), "range_gates"),
    (dict(range_gates=[0.5]), "range_gates"),
    (dict(channel_slot=[0, 1]), "channel_slot"),
    (dict(wavelength=-1.0), "wavelength"),
    (dict(weights=np.zeros(12)), "weights"),
    (dict(azimuth=[]), "azimuth"),
    (dict(azimuth=np.arange(-30.0, 31.0, 1.0)), r"azimuth must be angles in radians.*degrees\?"),
    (dict(engine="gpu"), "engine must be one of"),
])
def test_bad_setup_is_refused(kwargs, match):
    p, slot = _ti_positions()
    kw = dict(channel_slot=slot, wavelength=LAM, range_axis=np.arange(5.0) + 5,
              azimuth=[0.0], elevation=[0.0], range_gates=[1])
    kw.update(kwargs)
    with pytest.raises(ValueError, match=match):
        RealtimeProjector(p, **kw)


def test_bad_frame_is_refused():
    rng = np.random.default_rng(6)
    p, slot = _ti_positions()
    proj = RealtimeProjector(p, channel_slot=slot, wavelength=LAM, range_axis=np.arange(5.0) + 5,
                             azimuth=[0.0], elevation=[0.0], range_gates=[1])
    rc = _cube(rng, 4, 12, 5)
    with pytest.raises(ValueError, match="chirp \\* slots"):
        proj.project(rc, _motion(rng, 4))
    with pytest.raises(ValueError, match="rc must be"):
        proj.project(rc[:, :8], _motion(rng, 12))
    with pytest.raises(ValueError, match="rc must be"):
        proj.project(rc.real, _motion(rng, 12))
    bad = rc.copy()
    bad[0, 0, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        proj.project(bad, _motion(rng, 12))
    with pytest.raises(ValueError, match="PlatformMotion"):
        proj.project(rc, "motion")


@pytest.mark.parametrize("engine", ENGINE_CASES)
@pytest.mark.parametrize("rows, cols, jitter", [(20, 20, 0.0), (5, 6, 0.0), (6, 6, 2e-4)])
def test_lattice_and_general_layouts_equal_direct_engine(rows, cols, jitter, engine):
    """A 20 x 20 lattice (the paper array: 19 + 19 Horner steps in float32) and a 5 x 6 one
    (rows of 6) take the kernel's lattice form; the same 6 x 6 layout with its positions
    moved by up to 0.2 mm is no lattice and takes the general form (one steering phase per
    channel). 8 cm displacements at 1-3 m, 8 gates in one block."""
    from compensation.realtime import _lattice

    rng = np.random.default_rng(11)
    m = rows * cols
    i2, i1 = np.divmod(np.arange(m), cols)
    p = np.stack([i2 * 0.6 * LAM, i1 * LAM / 2, np.zeros(m)], axis=1)
    p += rng.uniform(-jitter, jitter, p.shape)
    assert _lattice(p) == (0 if jitter else cols)
    n, r = 4, 24
    motion = _motion(rng, n, disp_m=0.08, angle_rad=0.2)
    rc = _cube(rng, n, m, r)
    kw = dict(wavelength=LAM, range_axis=np.linspace(1.0, 3.0, r),
              azimuth=np.deg2rad(np.linspace(-40, 40, 9)), elevation=np.deg2rad([-10.0, 5.0, 20.0]),
              range_gates=np.arange(8, 16), gate_block=8, engine=engine)
    _compare(rc, p, motion, **kw)
    # factorised=False: every channel with its own steering phase, the same beams
    general = RealtimeProjector(p, factorised=False, **kw)
    assert all(sl.line is None and sl.lattice == 0 for sl in general.slots)
    a = RealtimeProjector(p, **kw).project(rc, motion).data
    b = general.project(rc, motion).data
    assert np.abs(a - b).max() < RT_TOL * np.abs(b).max()


def test_lattice_detection():
    """Row-major lattices only: a line, a ragged count, a missing row, a shear are not."""
    from compensation.realtime import _lattice

    i2, i1 = np.divmod(np.arange(12), 4)
    grid = np.stack([i1 * 1e-3, i2 * 2e-3, np.zeros(12)], axis=1)
    assert _lattice(grid) == 4
    sheared = grid + np.stack([i2 * 0.5e-3, np.zeros(12), (i1 * i2) * 1e-4], axis=1)
    assert _lattice(sheared) == 0                          # not p0 + i1 a + i2 b
    assert _lattice(grid[:10]) == 0                        # 10 channels in rows of 4
    assert _lattice(grid[:4]) == 0                         # one row: a line, not a lattice
    assert _lattice(np.zeros((6, 3))) == 0                 # no step


@pytest.mark.parametrize("engine", ENGINE_CASES)
def test_grid_across_direction_chunks_equals_direct_engine(engine):
    """17 x 19 = 323 directions (more than the kernel's chunk of 256), TDM slots, 8 cm
    displacements at 1.2-2 m (per-gate phases beyond the Taylor range in part of the grid)."""
    rng = np.random.default_rng(7)
    p, slot = _ti_positions()
    n, r = 6, 30
    motion = _motion(rng, 3 * n, disp_m=0.08, angle_rad=0.2)
    _compare(_cube(rng, n, 12, r), p, motion, slot=slot, wavelength=LAM,
             range_axis=np.linspace(1.2, 2.0, r), azimuth=np.deg2rad(np.linspace(-60, 60, 17)),
             elevation=np.deg2rad(np.linspace(-45, 45, 19)), range_gates=[0, 3, 4, 5, 29],
             gate_block=4, engine=engine)


def test_without_extension_auto_is_the_numpy_engine(monkeypatch):
    """Fallback: no extension -> engine 'auto' runs NumPy; asking for the kernel is refused."""
    import compensation.realtime as rt

    p, slot = _ti_positions()
    kw = dict(channel_slot=slot, wavelength=LAM, range_axis=np.arange(5.0) + 5,
              azimuth=[0.0, 0.1], elevation=[0.0], range_gates=[1, 2])
    monkeypatch.setattr(rt, "_ext", None)
    assert rt.compiled_isa() == "missing"
    assert RealtimeProjector(p, **kw).engine == "numpy"
    for engine in ("compiled", "avx2", "portable"):
        with pytest.raises(ValueError, match=f"engine='{engine}' needs the compiled extension"):
            RealtimeProjector(p, engine=engine, **kw)
    assert set(ENGINES) == {"auto", "compiled", "avx2", "portable", "numpy"}


def test_bench_doppler_power_is_the_power_of_the_beams_doppler_spectrum():
    """The benchmark's lean Doppler step gives |BeamCube.doppler()|^2 (float32 rounding)."""
    from raysim.bench.realtime import doppler_power

    rng = np.random.default_rng(8)
    p, slot = _ti_positions()
    proj = RealtimeProjector(p, channel_slot=slot, wavelength=LAM, range_axis=np.arange(5.0) + 5,
                             azimuth=[0.0, 0.2, 0.4], elevation=[0.0, 0.1], range_gates=[1, 3])
    beams = proj.project(_cube(rng, 16, 12, 5), _motion(rng, 48))
    ref = np.abs(beams.doppler()) ** 2
    power = doppler_power(beams.data, threads=2)
    assert power.shape == ref.shape == (16, 2, 3, 2) and power.dtype == np.float32
    assert np.abs(power - ref).max() < RT_TOL * ref.max()
    assert np.argmax(power.sum(axis=(1, 2, 3))) == np.argmax(ref.sum(axis=(1, 2, 3)))


@pytest.mark.parametrize("engine", ENGINE_CASES)
def test_wide_gate_block_with_large_gate_phases_equals_direct_engine(engine):
    """One block spanning 0.3-14 m: per-gate phases of many rad take the float64 path.

    The near gates' phases are far beyond ``SMALL_PHASE`` (their Taylor values are
    huge), so an engine that adds a Taylor term and takes it out again loses the
    beam to float32 rounding (1e-4 of the peak), far outside ``RT_TOL``.
    """
    rng = np.random.default_rng(12)
    p, slot = _ti_positions()
    n = 12
    _compare(_cube(rng, n, 12, 90), p, _motion(rng, 3 * n), slot=slot, wavelength=LAM,
             range_axis=np.linspace(0.3, 14.0, 90), azimuth=np.deg2rad(np.linspace(-40, 40, 9)),
             elevation=np.deg2rad(np.linspace(-20, 25, 7)), range_gates=[0, 1, 60, 89],
             engine=engine)


#: Largest difference of the gated range transform from the range FFT relative to
#: the peak bin: float32 rounding of a 256-term sum.
RANGE_TOL = 1e-6


@pytest.mark.parametrize("engine", ENGINE_CASES)
@pytest.mark.parametrize("real", [False, True])
def test_gated_range_transform_is_the_range_fft_at_the_gates(engine, real):
    """DFT of the gated bins = range_compress(...)[..., gates] (Hann, /sum; real: doubled half)."""
    from raysim.processing.maps import range_compress

    rng = np.random.default_rng(9)
    p, slot = _ti_positions()
    k = 64
    n = np.arange(k)
    # two tones (bins 5 and 40.3) plus noise: the gated bins hold leakage and peaks
    tone = 3.0 * np.exp(2j * np.pi * 5 * n / k) + np.exp(2j * np.pi * 40.3 * n / k)
    x = tone[None, None] * np.exp(1j * rng.uniform(0, 6.3, (6, 12, 1))) + \
        0.1 * rng.standard_normal((6, 12, k))
    x = (x.real if real else x).astype(np.float32 if real else np.complex64)
    gates = [0, 5, 6, 31] if real else [0, 5, 6, 40, 63]
    proj = RealtimeProjector(p, channel_slot=slot, wavelength=LAM,
                             range_axis=2.0 + np.arange(k) * 0.1, azimuth=[0.0],
                             elevation=[0.0], range_gates=gates, engine=engine)
    ref = range_compress(x)[:, :, gates]
    got = proj.gated_range_transform(x)
    assert got.shape == ref.shape and got.dtype == np.complex64
    assert np.abs(got - ref).max() < RANGE_TOL * np.abs(ref).max()
    # same beams through the gated path as through the whole range-compressed cube
    motion = _motion(rng, 18)
    full = proj.project(range_compress(x), motion).data
    out = np.empty_like(full)
    beams = proj.project(got, motion, gated=True, out=out)
    assert beams.data is out
    assert np.abs(out - full).max() < RT_TOL * np.abs(full).max()
    with pytest.raises(ValueError, match="samples must be an IF cube"):
        proj.gated_range_transform(x[:, :5])
    with pytest.raises(ValueError, match="rc must be a complex cube"):
        proj.project(got[:, :, :2], motion, gated=True)
    with pytest.raises(ValueError, match="out must be a C-contiguous complex64"):
        proj.project(got, motion, gated=True, out=np.empty(full.shape, np.complex128))
    with pytest.raises(ValueError, match="not a scipy.signal window name"):
        proj.gated_range_transform(x, window="no-such-window")


@pytest.mark.skipif(not BUILT, reason="extension compensation._native._ext not built")
def test_kernel_beams_do_not_depend_on_the_thread_count():
    """Each (chirp, direction chunk) item is computed whole by one thread: 1, 2 and 5
    threads (more than the items of a chirp) give the same beams, bit for bit."""
    rng = np.random.default_rng(13)
    p, slot = _ti_positions()
    n, r = 5, 20
    motion = _motion(rng, 3 * n)
    rc = _cube(rng, n, 12, r)
    kw = dict(channel_slot=slot, wavelength=LAM, range_axis=np.linspace(2.0, 4.0, r),
              azimuth=np.deg2rad(np.linspace(-50, 50, 23)), elevation=np.deg2rad([0.0, 9.0]),
              range_gates=[3, 4, 5])
    beams = [RealtimeProjector(p, threads=t, **kw).project(rc, motion).data for t in (1, 2, 5)]
    np.testing.assert_array_equal(beams[0], beams[1])
    np.testing.assert_array_equal(beams[0], beams[2])


@pytest.mark.skipif(not BUILT, reason="extension compensation._native._ext not built")
def test_gated_range_transform_on_threads_equals_one_thread(monkeypatch):
    """Above DFT_THREADED_MACS the compiled DFT runs on the projector's threads: each row is
    the same sum, so the result is the one-thread result, bit for bit."""
    import compensation.realtime as rt

    rng = np.random.default_rng(12)
    p, slot = _ti_positions()
    x = _cube(rng, 9, 12, 96)
    proj = RealtimeProjector(p, channel_slot=slot, wavelength=LAM, range_axis=np.arange(96.0),
                             azimuth=[0.0], elevation=[0.0], range_gates=[3, 4, 50], threads=2)
    one = proj.gated_range_transform(x).copy()
    monkeypatch.setattr(rt, "DFT_THREADED_MACS", 0)
    np.testing.assert_array_equal(proj.gated_range_transform(x), one)


def test_bench_doppler_power_buffers_follow_each_frame():
    """DopplerPower reuses its buffers: each call gives that frame's power (even and odd N)."""
    from scipy.signal import get_window

    from raysim.bench.realtime import DopplerPower

    rng = np.random.default_rng(10)
    for n in (16, 15):
        dop = DopplerPower((n, 2, 3), threads=2)
        for _ in range(2):
            x = (rng.standard_normal((n, 2, 3)) + 1j * rng.standard_normal((n, 2, 3))).astype(
                np.complex64)
            w = get_window("hann", n, fftbins=True)
            ref = np.abs(np.fft.fftshift(np.fft.fft(x * (w / w.sum())[:, None, None], axis=0),
                                         axes=0)) ** 2
            got = dop(x)
            assert np.abs(got - ref).max() < RT_TOL * ref.max()
        with pytest.raises(ValueError, match="data must have shape"):
            dop(x[1:])


@pytest.mark.parametrize("engine", ENGINE_CASES)
def test_chirp_weights_carry_the_doppler_window(engine):
    """project(chirp_weights=w) = w[n] * beams; DopplerPower(weighted=True) then = its power."""
    from raysim.bench.realtime import DopplerPower

    rng = np.random.default_rng(13)
    p, slot = _ti_positions()
    proj = RealtimeProjector(p, channel_slot=slot, wavelength=LAM, range_axis=np.arange(5.0) + 5,
                             azimuth=[0.0, 0.2, 0.4], elevation=[0.0, 0.1], range_gates=[1, 3],
                             engine=engine)
    rc, motion = _cube(rng, 16, 12, 5), _motion(rng, 48)
    beams = proj.project(rc, motion).data
    dop = DopplerPower(beams.shape, threads=2)
    ref = dop(beams).copy()
    weighted = proj.project(rc, motion, chirp_weights=dop.chirp_weights).data
    wref = beams * dop.chirp_weights[:, None, None, None]
    assert np.abs(weighted - wref).max() < RT_TOL * np.abs(wref).max()
    assert np.abs(dop(weighted, weighted=True) - ref).max() < RT_TOL * ref.max()
    with pytest.raises(ValueError, match="chirp_weights must have shape"):
        proj.project(rc, motion, chirp_weights=np.ones(15))
    with pytest.raises(ValueError, match="weighted data must be C-contiguous complex64"):
        dop(beams.astype(np.complex128), weighted=True)
