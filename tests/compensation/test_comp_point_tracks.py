"""A scatterer's track is one point's, or its cell holds two: the slow swing of its amplitude.

Closed form: two phasors ``1 + eps exp(j theta)``, ``theta`` turning once over the
frame, have ``|y| = 1 + eps cos theta + O(eps^2)``, an rms swing of ``eps / sqrt(2)``
over their mean; white noise alone has none beyond its spread.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from compensation.guards import CompensationWarning
from compensation.point_tracks import MIXED_CELL_SWING, amplitude_swing, clock_scatterers

#: Chirps per frame of the synthetic tracks.
CHIRPS = 64
#: Relative tolerance on ``eps / sqrt(2)``: the first-order expansion drops terms of
#: ``eps^2 / 4`` (1 % at eps 0.2) and the chirp-to-chirp term removes ``(2 pi / N)^2 / 4``
#: of the variance (0.2 % at 64 chirps).
SWING_RTOL = 0.02
#: Share of white-noise tracks allowed a swing (the threshold is three spreads of the
#: noise's estimate; measured about 1 % at 0-30 dB per chirp, 2000 draws each).
NOISE_FALSE_RATE = 0.03


def _beat(eps: float, cycles: float = 1.0, phase0: float = 0.0) -> np.ndarray:
    theta = phase0 + np.linspace(0.0, 2 * np.pi * cycles, CHIRPS, endpoint=False)
    return 1.0 + eps * np.exp(1j * theta)


@pytest.mark.parametrize("eps", [0.05, 0.1, 0.2])
def test_two_points_swing_by_eps_over_root_two(eps):
    swing = amplitude_swing(np.abs(_beat(eps)) ** 2)
    assert swing == pytest.approx(eps / np.sqrt(2), rel=SWING_RTOL)


@pytest.mark.parametrize("snr_db", [0.0, 10.0, 30.0])
def test_white_noise_alone_does_not_swing(snr_db):
    rng = np.random.default_rng(7)
    s = 10 ** (-snr_db / 20)
    swings = [amplitude_swing(np.abs(1 + s * (rng.normal(size=CHIRPS) + 1j * rng.normal(
        size=CHIRPS)) / np.sqrt(2)) ** 2) for _ in range(400)]
    assert np.mean(np.asarray(swings) > 0) <= NOISE_FALSE_RATE


def test_a_beat_is_found_under_noise():
    rng = np.random.default_rng(3)
    noise = 0.03 * (rng.normal(size=CHIRPS) + 1j * rng.normal(size=CHIRPS)) / np.sqrt(2)
    swing = amplitude_swing(np.abs(_beat(0.2) + noise) ** 2)
    assert swing == pytest.approx(0.2 / np.sqrt(2), rel=0.1)


def _tracks(per_scatterer, frames: int = 4, seed: int = 0):
    """Frame-major tracks of scatterers whose beam is ``per_scatterer[j](frame)``."""
    rng = np.random.default_rng(seed)
    t = np.arange(CHIRPS) * 2e-4
    out = []
    for k in range(frames):
        for make in per_scatterer:
            y = make(k) + 0.01 * (rng.normal(size=CHIRPS) + 1j * rng.normal(size=CHIRPS))
            out.append((t + 0.05 * k, np.unwrap(np.angle(y)), np.zeros(CHIRPS), np.abs(y) ** 2))
    return out


def _point(k):
    return np.ones(CHIRPS, dtype=complex)


def _mixed(k):
    return _beat(0.3, cycles=0.8, phase0=1.1 * k)


def test_mixed_cells_leave_the_clock_fit_and_are_named():
    names = ("a", "b", "c")
    with pytest.warns(CompensationWarning, match=r"clock: 1 of 3 scatterer\(s\) \(number 1\)"
                      r".*fitted on the other 2"):
        kept, spread = clock_scatterers(_tracks((_point, _mixed, _point)), names, 0.01)
    assert kept == ("a", "c") and spread == 0.0


def test_single_points_are_all_kept_without_a_word():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        kept, spread = clock_scatterers(_tracks((_point, _point)), ("a", "b"), 0.01)
    assert kept == ("a", "b") and spread == 0.0


def test_only_mixed_cells_state_the_search_width():
    with pytest.warns(CompensationWarning, match="not trusted: its spread states the search's "
                      "half-width 10 ms"):
        kept, spread = clock_scatterers(_tracks((_mixed,)), ("a",), 0.01)
    assert kept == ("a",) and spread == 0.01
    with pytest.warns(CompensationWarning, match="may lie beyond its spread"):
        assert clock_scatterers(_tracks((_mixed,)), ("a",), 0.0)[1] == 0.0


def test_the_median_over_frames_decides():
    # mixed in one frame of four (a passing reflection): still one point
    def once(k):
        return _mixed(k) if k == 2 else _point(k)
    assert amplitude_swing(np.abs(_mixed(2)) ** 2) > MIXED_CELL_SWING     # that frame alone
    assert clock_scatterers(_tracks((once, _point)), ("a", "b"), 0.01)[0] == ("a", "b")


def test_tracks_that_are_not_whole_frames_are_refused():
    with pytest.raises(ValueError, match="5 tracks for 2 scatterers"):
        clock_scatterers(_tracks((_point,), frames=5), ("a", "b"), 0.01)
