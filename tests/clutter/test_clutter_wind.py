"""Wind-blown vegetation: Billingsley's exponential Doppler spectrum, in the process and in cubes.

Billingsley, *Low-Angle Radar Land Clutter* (2002), ch. 3: the spectrum over
radial velocity is ``r/(r+1) delta(v) + 1/(r+1) (beta/2) exp(-beta |v|)`` with
``1/beta = 0.1048 (log10 w + 0.4147)`` m/s and ``r = 489.8 w^-1.55 f0^-1.21``
(``w`` mph, ``f0`` GHz). Two winds: 1 m/s (2.2 mph, light air) and 4 m/s
(8.9 mph, breezy), at 77 GHz.

Estimators: ``beta`` is the slope of a straight-line fit of the log of the
Hann-windowed slow-time periodogram over ``|v|``, from beyond the DC line's
main lobe to :data:`FIT_DB` under the model's peak (``|v| < ln(10^3) / beta``). The DC line is a
constant in lag (the Fourier pair of a zero-Doppler line), so its power is the
plateau of the slow-time autocorrelation at lags far beyond the AC
correlation time (``1/(1 + (4 pi tau / (beta lambda))^2)`` < 3e-4 there).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from clutter_grounds import grid_ground

from raysim.echoes.ground.field import ClutterField, FieldSettings
from raysim.echoes.ground.icm import IcmProcess, ac_shape_factor, dc_ac_ratio, icm_spectrum
from raysim.echoes.ground.surface import GroundSurface
from raysim.echoes.rt.reproject import synthesize_paths
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Fitted DC/AC ratio of the process vs the model [dB] (1000 scatterers, 0.49 s record).
DC_AC_TOL_DB = 0.5
#: Fitted exponential shape factor vs the model (relative).
BETA_REL_TOL = 0.05
#: Mean power of the modulation vs 1 (sigma0 kept; 1000 scatterers of 16 random tones).
POWER_REL_TOL = 0.05
#: DC/AC ratio of one rendered patch vs the model [dB]. Its zero-Doppler line is
#: measured against the still render over ~45 range cells, and the AC continuum's
#: leakage into the zero-Doppler bin (about 1.4 % of the power at 2 Hz resolution)
#: projects onto those few cells: about 1 dB rms over seeds (0.2 to 1.9 dB seen over five).
PATCH_DC_AC_TOL_DB = 2.0
#: Depth of the fitted part of the exponential [dB] (sets the fit window in velocity).
FIT_DB = 30.0
#: The record at once vs frame by frame: 16 tones summed in complex64 (the cube's own
#: precision, 6e-8 each) on amplitudes up to about 5.
RECORD_ATOL = 1e-5
#: Winds [m/s] (light air, breezy).
WINDS = (1.0, 4.0)
CARRIER = 77e9
#: Chirp repetition interval [s] and chirps per frame of the records.
PRI = 240e-6
CHIRPS = 512


def _fit_beta(x: np.ndarray, interval: float, wavelength: float, v_end: float) -> float:
    """Exponential slope [s/m] of the Hann periodogram of ``x`` [time, ...] over ``|v| < v_end``.

    The window is set in velocity (not by the periodogram's own values, which
    would keep the tail bins that happen to be high and flatten the slope).
    """
    n = x.shape[0]
    w = np.hanning(n).reshape((n,) + (1,) * (x.ndim - 1))
    p = np.abs(np.fft.fft(x * w, axis=0)) ** 2
    p = p.reshape(n, -1).sum(axis=1)
    v = wavelength * np.fft.fftfreq(n, interval) / 2
    dv = abs(v[1])
    sel = (np.abs(v) > 3.5 * dv) & (np.abs(v) < v_end)     # no DC line (Hann main lobe)
    slope = np.polyfit(np.abs(v[sel]), np.log(p[sel]), 1)[0]
    return float(-slope)


def _v_end(wind: float) -> float:
    """End of the fit window [m/s]: the model's AC shape :data:`FIT_DB` under its peak."""
    return FIT_DB / 10 * math.log(10) / ac_shape_factor(wind)


def _plateau(x: np.ndarray, interval: float) -> tuple[float, float]:
    """Autocorrelation of ``x`` [time, cell] at lag 0 and its plateau (lags T/4 to T/2)."""
    n = x.shape[0]
    f = np.fft.fft(x, 2 * n, axis=0)
    r = np.fft.ifft(np.abs(f) ** 2, axis=0)[:n].real.sum(axis=1) / (n - np.arange(n))
    lag = np.arange(n) * interval
    return float(r[0]), float(r[(lag > n * interval / 4) & (lag < n * interval / 2)].mean())


def test_model_numbers():
    """Billingsley's formulas in their units (mph, GHz); unit areas; bad input refused."""
    mph10 = 10 * 0.44704                                               # 10 mph [m/s]
    assert ac_shape_factor(mph10) == pytest.approx(1 / (0.1048 * (1 + 0.4147)), rel=1e-12)
    assert dc_ac_ratio(mph10, 9.2e9) == pytest.approx(489.8 * 10**-1.55 * 9.2**-1.21,
                                                      rel=1e-12)
    ac, dc = icm_spectrum(np.linspace(-20, 20, 400001), 4.0, CARRIER)
    assert np.trapezoid(ac, dx=1e-4) + dc == pytest.approx(1.0, abs=1e-6)
    for bad in (0.0, -1.0, float("nan"), 0.1):
        with pytest.raises(ValueError, match="wind_mps"):
            ac_shape_factor(bad)
    for bad in (-1.0, float("nan"), 0.1):
        with pytest.raises(ValueError, match="wind_mps"):
            FieldSettings(wind_mps=bad)
    with pytest.raises(ValueError, match="vegetation"):
        FieldSettings(wind_mps=2.0, vegetation=("lawn",))
    with pytest.raises(ValueError, match="carrier_frequency"):
        dc_ac_ratio(2.0, 0.0)


@pytest.mark.parametrize("wind", WINDS)
def test_process_spectrum_matches_billingsley(wind):
    """1000 scatterers over 4 frames (0.49 s) rendered frame by frame: r, beta, power."""
    proc = IcmProcess.draw(1000, wind, CARRIER, seed=3)
    frames = [proc.modulation(f * CHIRPS * PRI + np.arange(CHIRPS) * PRI) for f in range(4)]
    m = np.concatenate(frames, axis=1).T                                   # [time, scatterer]
    # a function of time: the whole record at once is the frames joined
    whole = proc.modulation(np.arange(4 * CHIRPS) * PRI, rows=np.arange(0, 1000, 97)).T
    np.testing.assert_allclose(whole, m[:, ::97], rtol=0, atol=RECORD_ATOL)
    r0, dc = _plateau(m, PRI)
    assert r0 / m.shape[1] == pytest.approx(1.0, rel=POWER_REL_TOL)
    r = dc_ac_ratio(wind, CARRIER)
    assert 10 * math.log10(dc / (r0 - dc)) == pytest.approx(10 * math.log10(r),
                                                            abs=DC_AC_TOL_DB)
    beta = ac_shape_factor(wind)
    assert _fit_beta(m, PRI, 299792458.0 / CARRIER, _v_end(wind)) == pytest.approx(
        beta, rel=BETA_REL_TOL)


@pytest.fixture(scope="module")
def patch():
    """A 10 m grass patch 8 m below and 8 m beside a downward-looking radar, one channel."""
    config = RadarConfig(num_chirps=CHIRPS, sample_rate=2.5e6, idle_time=PRI - 60e-6)
    array = upa(1, 1, wavelength=config.wavelength)
    ground = GroundSurface.from_meshes([(grid_ground(10.0, 4, 8.0, centre=(8.0, 0.0)),
                                         "grass")])
    return config, array, ground


def _range_cells(cube: np.ndarray) -> np.ndarray:
    return np.fft.fft(cube * np.hanning(cube.shape[-1]), axis=-1).reshape(cube.shape[0], -1)


@pytest.mark.parametrize("wind", WINDS)
def test_rendered_patch_spectrum(patch, wind):
    """A windy patch rendered over 4 frames: Billingsley's beta and DC/AC in the cube's spectrum."""
    config, array, ground = patch
    field = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                               FieldSettings(wind_mps=wind, shadowing=False,
                                             scatterers_per_cell=40.0, seed=0))
    assert field.report["icm_scatterers"] == field.num_scatterers > 500
    paths = field.paths(config, np.zeros(3), np.eye(3))
    cubes = [synthesize_paths(paths, config, array, modulation=field.modulation, frame=k)[0]
             for k in range(4)]
    assert not np.allclose(cubes[0], cubes[1])
    x = _range_cells(np.concatenate(cubes))                               # [chirp, cell]
    still = _range_cells(synthesize_paths(paths, config, array, chirps=[0])[0])[0]
    # the zero-Doppler line is the still field scaled by sqrt(r / (r + 1))
    rho = np.vdot(still, x.mean(axis=0)) / np.vdot(still, still)
    r = dc_ac_ratio(wind, CARRIER)
    r_hat = abs(rho) ** 2 / (1 - abs(rho) ** 2)
    assert 10 * math.log10(r_hat) == pytest.approx(10 * math.log10(r), abs=PATCH_DC_AC_TOL_DB)
    assert _fit_beta(x, config.chirp_interval, config.wavelength, _v_end(wind)) == \
        pytest.approx(ac_shape_factor(wind), rel=BETA_REL_TOL)


def test_frames_are_one_record(patch, monkeypatch):
    """Frame 1 of a 512-chirp record is chirps 512-1023 of a 1024-chirp frame (no restart)."""
    config, array, ground = patch
    field = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                               FieldSettings(wind_mps=4.0, shadowing=False, seed=1))
    paths = field.paths(config, np.zeros(3), np.eye(3))
    one, _ = synthesize_paths(paths, config, array, modulation=field.modulation, frame=1)
    from dataclasses import replace

    long = replace(config, num_chirps=2 * CHIRPS)
    both, _ = synthesize_paths(paths, long, array, modulation=field.modulation,
                               chirps=np.arange(CHIRPS, 2 * CHIRPS))
    scale = np.max(np.abs(one))
    np.testing.assert_allclose(both, one, rtol=0, atol=1e-5 * scale)
    # the compact way (fused kernel) applies the same modulation, in blocks of paths too
    compact, _ = synthesize_paths(paths, config, array, modulation=field.modulation, frame=1,
                                  compact=True)
    np.testing.assert_allclose(compact, one, rtol=0, atol=1e-4 * scale)
    import raysim.echoes.rt.reproject as reproject

    monkeypatch.setattr(reproject, "MODULATION_CHUNK", 37)
    blocks, _ = synthesize_paths(paths, config, array, modulation=field.modulation, frame=1,
                                 compact=True)
    np.testing.assert_array_equal(blocks, compact)


def test_still_air_is_unchanged(patch):
    """wind_mps = 0 (default) and non-vegetation materials give the still field's cube."""
    config, array, ground = patch
    still = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                               FieldSettings(shadowing=False, seed=2))
    windy_soil = ClutterField.build(ground, config, array, np.zeros(3), np.eye(3),
                                    FieldSettings(shadowing=False, seed=2, wind_mps=4.0,
                                                  vegetation=("dry-soil",)))
    assert still.icm is None and windy_soil.report["icm_scatterers"] == 0
    np.testing.assert_array_equal(still.positions, windy_soil.positions)
    np.testing.assert_array_equal(still.z, windy_soil.z)
    paths = still.paths(config, np.zeros(3), np.eye(3))
    assert still.modulation(paths.first_vertex, [0.0]) is None
    assert windy_soil.modulation(paths.first_vertex, [0.0]) is None
    plain, _ = synthesize_paths(paths, config, array, chirps=np.arange(4))
    for compact in (False, True):
        hooked, _ = synthesize_paths(paths, config, array, chirps=np.arange(4), compact=compact,
                                     modulation=windy_soil.modulation)
        ref = plain if not compact else synthesize_paths(paths, config, array,
                                                         chirps=np.arange(4), compact=True)[0]
        np.testing.assert_array_equal(hooked, ref)


@pytest.mark.sionna
def test_render_scene_applies_the_wind(clutter_backend, tmp_path):
    """Two frames of a windy flat ground through render_scene are its paths synthesised with
    the field's modulation at those frames' chirps; in still air the frames repeat."""
    from clutter_grounds import write_flat_scene

    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.scenes import DRY_SOIL, load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.echoes.scene_clutter import SceneClutter

    scene = load_scene(write_flat_scene(tmp_path, DRY_SOIL), hover_altitude=10.0)
    config = RadarConfig(num_chirps=16, sample_rate=2.5e6)
    array = upa(2, 2, wavelength=config.wavelength)
    tracer = MonostaticTracer(samples_per_src=2_000, max_depth=1)
    windy = SceneClutter(FieldSettings(wind_mps=4.0, vegetation=("dry-soil",), seed=1))
    still = SceneClutter(FieldSettings(seed=1))
    out = {m: [render_scene(scene, config, array, tracer=tracer, frame=f, clutter=m)
               for f in range(2)] for m in (windy, still)}
    assert windy.summary()["icm_scatterers"] == windy.summary()["num_scatterers"] > 100
    assert windy.builds == still.builds == 1
    np.testing.assert_array_equal(out[still][0].data, out[still][1].data)
    for f, frame in enumerate(out[windy]):
        expect, _ = synthesize_paths(frame.truth["paths"], config, array, frame=f,
                                     modulation=windy.modulation)
        np.testing.assert_allclose(frame.data, expect, rtol=0,
                                   atol=1e-6 * np.abs(expect).max())
    assert not np.allclose(out[windy][0].data, out[windy][1].data)
