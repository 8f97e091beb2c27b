"""Metrics of a compensated beam cube (raysim.measure.beams) against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.measure.beams import BEAM_METRICS, beam_metrics
from raysim.vocabulary import metric_unit

#: Slow-time tone frequency error of the zero-padded, parabola-refined peak [bins].
TONE_BINS_TOL = 0.01
#: Azimuth error of the parabola through a Gaussian (exact in dB) beam [deg].
PEAK_TOL_DEG = 1e-9
#: The target's peak beside a stronger scatterer 8 deg away, whose Gaussian beam's tail
#: (1e-6 of its peak there) bends the parabola [deg].
SEARCH_TOL_DEG = 1e-3
#: Two equal tones: leakage against -3.01 dB, allowing the Hann window's spill (< -40 dB).
HALF_POWER_TOL_DB = 0.02


def _cube(doppler_bins: float, az0_deg: float, *, n: int = 64):
    """One scatterer: a slow-time tone of ``doppler_bins`` in the beam of a Gaussian
    (a parabola in dB) azimuth response peaking at ``az0_deg``."""
    az = np.arange(-6.0, 6.01, 0.5)
    beam = np.exp(-((az - az0_deg) / 2.0) ** 2)                       # [azimuth]
    slow = np.exp(2j * np.pi * doppler_bins * np.arange(n) / n)       # [chirp]
    rng_prof = np.array([0.1, 1.0, 0.1])                              # [range]
    return slow[:, None, None] * rng_prof[None, :, None] * beam[None, None, :], az


def test_tone_and_peak_are_recovered():
    """A tone of k bins gives pseudo-velocity k bins; a Gaussian beam's peak is exact."""
    lam, t_rep, n = 3.9e-3, 1e-4, 64
    v_res = lam / (2 * n * t_rep)
    cube, az = _cube(1.3, 0.7, n=n)
    m = beam_metrics(cube, az, 0.7, chirp_interval=t_rep, wavelength=lam,
                     velocity_resolution=v_res)
    assert list(m) == list(BEAM_METRICS)
    assert all(metric_unit(k) for k in m)
    assert m["beam_pseudo_velocity_bins"] == pytest.approx(1.3, abs=TONE_BINS_TOL)
    assert m["beam_angle_error_deg"] < PEAK_TOL_DEG
    # two equal tones far apart: half the power lies outside the peak's +-1 bins,
    # 10 log10(1/2) = -3.01 dB, plus the (symmetric) Hann window's own spill
    one, _ = _cube(3.0, 0.7, n=n)
    other, _ = _cube(20.0, 0.7, n=n)
    own = beam_metrics(one, az, 0.7, chirp_interval=t_rep, wavelength=lam,
                       velocity_resolution=v_res)["doppler_leakage_db"]
    two = beam_metrics(one + 1.0001 * other, az, 0.7, chirp_interval=t_rep, wavelength=lam,
                       velocity_resolution=v_res)["doppler_leakage_db"]
    assert own < -40
    assert two == pytest.approx(10 * np.log10(0.5), abs=HALF_POWER_TOL_DB)


def test_edge_peak_and_bad_shape_are_refused():
    cube, az = _cube(0.0, 6.0)
    with pytest.raises(ValueError, match="edge of the azimuth grid"):
        beam_metrics(cube, az, 6.0, chirp_interval=1e-4, wavelength=3.9e-3,
                     velocity_resolution=0.3)
    with pytest.raises(ValueError, match=r"\[chirp, range, azimuth\]"):
        beam_metrics(cube[0], az, 0.0, chirp_interval=1e-4, wavelength=3.9e-3,
                     velocity_resolution=0.3)


def test_search_window_keeps_a_stronger_scatterer_elsewhere_out():
    """A target at +4 deg and a scatterer ten times stronger at -4 deg in the same cells
    (the ground under the radar): the whole grid takes the stronger one (8 deg off); a
    search within 3 deg of the truth finds the target, exactly (Gaussian beams); a window
    holding no beam is refused."""
    kw = dict(chirp_interval=1e-4, wavelength=3.9e-3, velocity_resolution=0.3)
    target, az = _cube(0.0, 4.0)
    ground, _ = _cube(0.0, -4.0)
    cube = target + 10.0 * ground
    assert beam_metrics(cube, az, 4.0, **kw)["beam_angle_error_deg"] > 7.0
    near = beam_metrics(cube, az, 4.0, search_deg=3.0, **kw)["beam_angle_error_deg"]
    assert near < SEARCH_TOL_DEG
    with pytest.raises(ValueError, match="no beam within"):
        beam_metrics(cube, az, 40.0, search_deg=1.0, **kw)
