"""Frozen-path re-projection: formula, re-tracing agreement, IF band handling."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.platform.motion import Trajectory, constant_velocity, hover_jitter, sinusoid
from raysim.radar.arrays import upa
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis.tones import synthesize_if_direct

#: Re-projected vs re-traced IF cube, fixed scattering points, re-traced geometry [dB].
RETRACE_CUBE_TOL_DB = -50.0
#: The same against Sionna's own float32 delays (one float32 ulp of a 30 m delay is
#: 0.2 deg of carrier phase; measured -48.7 dB) [dB].
RETRACE_SOLVER_CUBE_TOL_DB = -45.0
#: Re-projected vs Sionna's re-traced delay, per path [deg] (measured 0.65 deg).
RETRACE_PHASE_TOL_DEG = 1.0


def _pathset(first, last, length, amplitude=None, velocity=None, radar=(0.0, 0.0, 0.0)):
    """A hand-made PathSet (no Sionna needed)."""
    from raysim.echoes.rt.trace import PathSet

    first = np.atleast_2d(np.asarray(first, float))
    n = first.shape[0]
    amp = np.ones(n, complex) if amplitude is None else np.asarray(amplitude, complex)
    vel = np.zeros((n, 3)) if velocity is None else np.atleast_2d(np.asarray(velocity, float))
    return PathSet(first, np.atleast_2d(np.asarray(last, float)), np.asarray(length, float),
                   amp, vel, np.zeros(n), np.full((n, 1), 16, np.uint32),
                   np.full(n, 16, np.uint32), np.zeros((n, 2, 2), complex),
                   np.asarray(length, float) / SPEED_OF_LIGHT,
                   np.asarray(radar, float), np.asarray(radar, float), 0.0, {})


def ref_point_lengths(points, times_xtx_xrx, velocity=None):
    """Exact bistatic lengths ``|P(t) - x_tx| + |P(t) - x_rx|`` of point scatterers."""
    times, x_tx, x_rx = times_xtx_xrx
    out = []
    for k, p in enumerate(points):
        v = np.zeros(3) if velocity is None else velocity[k]
        pt = p + times[..., None] * v
        out.append(np.linalg.norm(pt - x_tx, axis=-1) + np.linalg.norm(pt - x_rx, axis=-1))
    return np.stack(out)


def test_reprojection_is_exact_for_point_scatterers():
    """L' equals the exact geometry for frozen points, with motion, lever arm, TDM and velocity."""
    from raysim.echoes.rt.reproject import element_positions, path_lengths
    from raysim.radar.arrays import ti_3tx4rx

    config = RadarConfig(num_chirps=6, num_tx_slots=3)
    array = ti_3tx4rx(config.wavelength)
    motion = hover_jitter(5) + constant_velocity([0.3, -0.2, 0.1])
    lever = np.array([0.1, 0.0, 0.05])
    pts = np.array([[3.0, 1.0, 14.0], [-8.0, 5.0, 12.0]])
    vel = np.array([[0.0, 0.0, 0.0], [1.0, -0.5, 0.0]])
    paths = _pathset(pts, pts, 2 * np.linalg.norm(pts, axis=1), velocity=vel)
    geo = element_positions(config, array, motion, lever)
    got = path_lengths(paths, *geo)
    np.testing.assert_allclose(got, ref_point_lengths(pts, geo, vel), rtol=0, atol=1e-9)
    # at the trace position the formula gives back the traced length
    still = element_positions(config, array, Trajectory(), np.zeros(3))
    zero_arr = upa(1, 1, spacing=1e-3)
    still = element_positions(RadarConfig(num_chirps=2), zero_arr, Trajectory(), np.zeros(3))
    np.testing.assert_allclose(path_lengths(_pathset(pts, pts, paths.length), *still)[:, 0, 0],
                               paths.length, atol=1e-12)


def test_if_band_cull_and_taper():
    """Paths whose beat frequency leaves [0, f_s) are culled or tapered, never aliased."""
    from raysim.echoes.rt.reproject import if_band_weight, reproject

    # unit element gain (constant 0 dBi): the taper weight is the amplitude itself
    config = RadarConfig(num_chirps=16, element_pattern="constant", antenna_gain_dbi=0.0)
    array = upa(2, 2, wavelength=config.wavelength)
    r_max = config.max_range
    # one path well inside, one that crosses max_range during the frame (receding platform)
    pts = np.array([[0.0, 0.0, 20.0], [0.0, 0.0, r_max - 1e-3]])
    paths = _pathset(pts, pts, 2 * pts[:, 2])
    motion = constant_velocity([0.0, 0.0, -2.0])
    culled = reproject(paths, config, array, motion, if_band="cull")
    assert culled.dropped_if_band == 1
    assert list(culled.kept) == [0]
    assert np.all(culled.tau * SPEED_OF_LIGHT / 2 < r_max)
    tapered = reproject(paths, config, array, motion, if_band="taper")
    w = np.abs(np.broadcast_to(tapered.amplitude, tapered.tau.shape))
    assert np.all(w[0] == 1.0) and np.all(w[1] < 1e-3)
    r = np.array([-1.0, 0.0, 0.5 * r_max, 0.95 * r_max, r_max, 2 * r_max])
    np.testing.assert_allclose(if_band_weight(r, config, taper=0.1), [0, 1, 1, 0.5, 0, 0],
                               atol=1e-12)
    with pytest.raises(ValueError, match="if_band"):
        reproject(paths, config, array, if_band="wrap")


@pytest.mark.sionna
def test_reprojection_matches_retracing(warm_kernels):
    """Re-projection vs a fresh trace per chirp and channel, fixed scattering points.

    Targets are point scatterers, so re-tracing from every element position
    gives the exact lengths. Two references: the re-traced geometry (vertices
    and radio positions, float64; cube error < -50 dB) and Sionna's own delays
    (float32; phase error < 1 deg, cube error < -45 dB, both bounded by float32
    rounding inside Sionna).
    """
    from raysim.echoes.rt.reproject import element_positions, path_lengths
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    config = RadarConfig(num_chirps=4, chirp_duration=60e-6)
    array = upa(4, 4, wavelength=config.wavelength)
    # 2 deg roll at 0.3 Hz plus jitter: element displacements of a few cm
    motion = hover_jitter(9) + sinusoid("roll", np.deg2rad(2.0), 0.3, 0.4)
    lever = np.array([0.03, 0.0, 0.06])
    from raysim.echoes.rt.scenes import SceneTarget

    # Sionna's constant-RCS points at the reflectors' apexes (its own float32 delays)
    points = [SceneTarget(t.name, t.position, t.rcs_dbsm)
              for t in load_scene("flat_reflectors").targets]
    scene = load_scene("flat_reflectors", targets=points)
    tracer = MonostaticTracer(specular=False, diffuse=False)
    frozen = tracer(scene, config, motion, lever, time=0.0)
    times, x_tx, x_rx = element_positions(config, array, motion, lever)
    reproj = path_lengths(frozen, times, x_tx, x_rx)              # [path, chirp, channel]
    retraced = np.empty_like(reproj)
    retraced_geo = np.empty_like(reproj)
    for n in range(config.num_chirps):
        for m in range(array.num_channels):
            # the virtual UPA's tx and rx coincide: trace from the element itself
            p = tracer(scene, config, motion, lever + array.tx_positions[m], time=times[n, m])
            assert p.num_paths == frozen.num_paths
            order = [int(np.argmin(np.linalg.norm(p.first_vertex - v, axis=1)))
                     for v in frozen.first_vertex]
            # Sionna's own delay (float32), independent of the vertex-based lengths
            retraced[:, n, m] = p.solver_delay[order] * SPEED_OF_LIGHT
            retraced_geo[:, n, m] = p.length[order]
    phase_err_deg = np.rad2deg(2 * np.pi * np.abs(reproj - retraced) / config.wavelength)
    print(f"re-projection vs re-trace: max phase error {phase_err_deg.max():.3f} deg")
    assert phase_err_deg.max() < RETRACE_PHASE_TOL_DEG
    amp = frozen.amplitude[:, None, None]
    a = synthesize_if_direct(reproj / SPEED_OF_LIGHT, amp, config)
    b = synthesize_if_direct(retraced / SPEED_OF_LIGHT, amp, config)
    c = synthesize_if_direct(retraced_geo / SPEED_OF_LIGHT, amp, config)
    tiny = 1e-300
    rel_solver_db = 20 * np.log10(np.linalg.norm(a - b) / np.linalg.norm(b) + tiny)
    rel_geo_db = 20 * np.log10(np.linalg.norm(a - c) / np.linalg.norm(c) + tiny)
    print(f"re-projection vs re-trace: cube error {rel_geo_db:.1f} dB (geometry), "
          f"{rel_solver_db:.1f} dB (Sionna float32 delays)")
    assert rel_geo_db < RETRACE_CUBE_TOL_DB
    assert rel_solver_db < RETRACE_SOLVER_CUBE_TOL_DB


@pytest.mark.sionna
def test_render_retrace_every(warm_kernels):
    """``retrace_every=K`` traces ceil(N / K) times and keeps the frame shape."""
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.trace import MonostaticTracer

    config = RadarConfig(num_chirps=6)
    array = upa(2, 2, wavelength=config.wavelength)
    frame = render_scene("flat_reflectors", config, array, hover_jitter(1),
                         tracer=MonostaticTracer(samples_per_src=2000), retrace_every=4)
    assert frame.truth["num_traces"] == 2
    assert frame.data.shape == (6, 4, config.num_samples)
    assert frame.data.dtype == np.complex64
    assert np.all(np.isfinite(frame.data)) and np.abs(frame.data).max() > 0


#: Compact way vs dense re-projection, relative l2 of the IF cube: both synthesise at
#: eps = 1e-6 (complex64 accumulation), the geometry and gains are the same formulas.
COMPACT_CUBE_TOL = 1e-4


def test_compact_way_equals_dense_reprojection(monkeypatch):
    """synthesize_paths: the compact way gives the dense re-projection's cube and culls.

    Point scatterers, double bounces with an interior length, moving scatterers and a
    single-bounce specular path (image method, always dense) under hover jitter with a
    lever arm, TDM slots and the patch element; one path leaves the IF band.
    """
    from raysim.echoes.rt import reproject as rp
    from raysim.echoes.rt.trace import SPECULAR
    from raysim.radar.arrays import ti_3tx4rx

    config = RadarConfig(num_chirps=12, num_tx_slots=3)
    array = ti_3tx4rx(config.wavelength)
    rng = np.random.default_rng(3)
    n = 60
    first = rng.uniform([-15, -15, 5], [15, 15, 30], (n, 3))
    last = np.where((np.arange(n) % 3 == 0)[:, None], rng.uniform([-10, -10, 5], [10, 10, 25],
                                                                  (n, 3)), first)
    interior = np.linalg.norm(last - first, axis=1)
    length = np.linalg.norm(first, axis=1) + interior + np.linalg.norm(last, axis=1)
    first[-1] = last[-1] = [0.0, 0.0, config.max_range + 0.5]        # beyond the band
    length[-1] = 2 * (config.max_range + 0.5)
    vel = np.where((np.arange(n) % 4 == 1)[:, None], rng.normal(0, 3.0, (n, 3)), 0.0)
    amp = rng.normal(size=n) + 1j * rng.normal(size=n)
    paths = _pathset(first, last, length, amp, vel)
    kind = paths.kind.copy()
    inter = paths.interactions.copy()
    kind[0], inter[0, 0] = SPECULAR, SPECULAR                      # a ground mirror
    paths = rp.PathSet(**{**paths.__dict__, "kind": kind, "interactions": inter})
    motion = hover_jitter(5) + constant_velocity([0.4, -0.2, 0.1])
    lever = np.array([0.05, 0.0, 0.1])
    dense, cut_dense = rp.synthesize_paths(paths, config, array, motion, lever, compact=False)
    fast, cut_fast = rp.synthesize_paths(paths, config, array, motion, lever, compact=True)
    assert cut_dense == cut_fast == 1
    err = np.linalg.norm(fast - dense) / np.linalg.norm(dense)
    assert err < COMPACT_CUBE_TOL, err
    part, _ = rp.synthesize_paths(paths, config, array, motion, lever, compact=True,
                                  chirps=np.arange(4, 9))
    err = np.linalg.norm(part - dense[4:9]) / np.linalg.norm(dense[4:9])
    assert err < COMPACT_CUBE_TOL, err
    # "auto" takes the compact way from COMPACT_MIN_PATHS frozen-vertex paths on
    taken = []
    real = rp._synthesize_compact
    monkeypatch.setattr(rp, "_synthesize_compact",
                        lambda p, *a, **k: taken.append(p.num_paths) or real(p, *a, **k))
    monkeypatch.setattr(rp, "COMPACT_MIN_PATHS", n - 1)
    rp.synthesize_paths(paths, config, array, motion, lever)
    assert taken == [n - 1]                                        # all but the mirror
    monkeypatch.setattr(rp, "COMPACT_MIN_PATHS", n)
    rp.synthesize_paths(paths, config, array, motion, lever)
    assert taken == [n - 1]
    with pytest.raises(ValueError, match="if_band"):
        rp.synthesize_paths(paths, config, array, motion, lever, compact=True,
                            if_band="taper")
    with pytest.raises(ValueError, match="compact"):
        rp.synthesize_paths(paths, config, array, motion, lever, compact="yes")
