"""Distributed ground clutter: a stationary platform gives a clean zero-Doppler ridge."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.platform.motion import hover_jitter, stationary
from raysim.processing import maps as processing
from raysim.processing import metrics
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

pytestmark = pytest.mark.sionna

#: Clutter power outside the Hann mainlobe (Doppler bins -1, 0, +1) of a stationary
#: platform, relative to the total [dB]. Frozen scattering points make every chirp
#: identical, so only float32 rounding remains.
STATIONARY_LEAKAGE_TOL_DB = -100.0
#: docs/conventions.md: -3 dB Doppler mainlobe of a static scene with a Hann window [bins].
HANN_WIDTH_BINS = 1.44
HANN_WIDTH_TOL = 0.02


def _leakage_db(data: np.ndarray) -> float:
    rc = processing.range_compress(data)
    spec = processing.doppler_fft(rc, axis=0)                     # [doppler, channel, range]
    power = np.sum(np.abs(spec) ** 2, axis=(1, 2))
    n = power.size
    centre = n // 2                                                # fft-shifted zero Doppler
    # summed outside the mainlobe (a difference of totals can round below zero)
    outside = power[: centre - 1].sum() + power[centre + 2:].sum()
    return float(10 * np.log10(outside / power.sum() + 1e-300))


@pytest.fixture(scope="module")
def clutter_scene(warm_kernels):
    from raysim.echoes.rt.scenes import load_scene

    return load_scene("rough_terrain")


def test_stationary_clutter_has_zero_doppler_ridge(clutter_scene):
    """Stationary radar over rough terrain: no Doppler spread; hovering: visible spread."""
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.trace import DIFFUSE, MonostaticTracer

    config = RadarConfig(num_chirps=32)
    array = upa(4, 4, wavelength=config.wavelength)
    tracer = MonostaticTracer(samples_per_src=20_000)
    still = render_scene(clutter_scene, config, array, stationary(), tracer=tracer)
    paths = still.truth["paths"]
    assert np.count_nonzero(paths.kind & DIFFUSE) > 500      # distributed clutter
    leak = _leakage_db(still.data)
    print(f"stationary clutter leakage outside the zero-Doppler mainlobe: {leak:.1f} dB")
    assert leak < STATIONARY_LEAKAGE_TOL_DB
    # mainlobe width of the strongest range gate (channel sum keeps it static)
    rc = processing.range_compress(still.data)
    gate = int(np.argmax(np.sum(np.abs(rc) ** 2, axis=(0, 1))))
    width = metrics.doppler_mainlobe_width(rc[:, 0, gate], config.chirp_interval)
    assert width / config.doppler_resolution == pytest.approx(HANN_WIDTH_BINS,
                                                              rel=HANN_WIDTH_TOL)
    # the same clutter seen while hovering spreads in Doppler (the metric is sensitive)
    moving = render_scene(clutter_scene, config, array, hover_jitter(2), tracer=tracer)
    leak_moving = _leakage_db(moving.data)
    print(f"hovering (jitter seed 2) leakage: {leak_moving:.1f} dB")
    assert leak_moving > leak + 60.0


def test_trace_is_deterministic_and_sorted(clutter_scene):
    """Equal traces give equal arrays; paths come sorted by length."""
    from raysim.echoes.rt.trace import MonostaticTracer

    config = RadarConfig(num_chirps=4)
    tracer = MonostaticTracer(samples_per_src=5_000)
    a = tracer(clutter_scene, config)
    b = tracer(clutter_scene, config)
    assert a.num_paths > 0
    for name in ("length", "amplitude", "first_vertex", "last_vertex", "kind"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert np.all(np.diff(a.length) >= 0)
    assert np.all(a.length / 2 < config.max_range)


#: Largest azimuth ripple of diffuse ground backscatter (45 deg vs 0 deg sectors) [dB].
DIFFUSE_AZIMUTH_RIPPLE_TOL_DB = 0.5


def test_diffuse_clutter_has_no_polarisation_azimuth_pattern(warm_kernels):
    """Flat ground: the used amplitude is azimuth-independent; raw co-pol is not.

    Sionna's diffuse model mirrors linear polarisation on backscatter, so the
    raw co-polarised entry falls off as ``cos(2 az)`` (a four-fold pattern,
    several dB down at 45 deg). The tracer's ``||H||_F / sqrt(2)`` must not.
    """
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import DIFFUSE, MonostaticTracer

    scene = load_scene("flat_reflectors", include_targets=False)
    p = MonostaticTracer(samples_per_src=20_000, specular=False, targets=False,
                         diffuse_phase="none")(scene, RadarConfig(num_chirps=4))
    d = (p.kind & DIFFUSE) != 0
    v = p.first_vertex[d]
    r = p.length[d] / 2
    az = np.mod(np.arctan2(v[:, 1], v[:, 0]), np.pi / 2)
    off_nadir = np.arccos(v[:, 2] / r)
    ring = (off_nadir > np.deg2rad(20)) & (off_nadir < np.deg2rad(50))
    near0 = ring & ((az < np.deg2rad(10)) | (az > np.deg2rad(80)))
    near45 = ring & (np.abs(az - np.pi / 4) < np.deg2rad(10))
    assert near0.sum() > 100 and near45.sum() > 100

    def ripple_db(a):
        x = np.abs(a) ** 2 * r**4
        return 10 * np.log10(x[near45].mean() / x[near0].mean())

    assert abs(ripple_db(p.amplitude[d])) < DIFFUSE_AZIMUTH_RIPPLE_TOL_DB
    assert ripple_db(p.polarimetric[d][:, 0, 0]) < -3.0      # the trap, documented
