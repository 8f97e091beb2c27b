"""The scene CFAR: ordered statistic against cell averaging, its false-alarm rate, box matching.

Closed forms: Rohling (1983), "Radar CFAR thresholding in clutter and multiple
target situations", IEEE Trans. AES-19(4): in exponential clutter (Rayleigh
amplitude) the ordered statistic's false-alarm probability is
``prod_{i<k} (n - i) / (n - i + alpha)`` and the cell average's
``(1 + alpha/n)^-n`` (:func:`raysim.measure.scene.cfar_pfa`).
"""

from __future__ import annotations

import numpy as np
import pytest

from raysim.measure.scene import (
    CFAR_GUARD,
    CFAR_RANK,
    CFAR_THRESHOLD_DB,
    CFAR_TRAIN,
    cfar_detect,
    cfar_noise,
    cfar_pfa,
)
from raysim.studies.scene_report.evaluate import box_distance, object_box

#: Binomial bound of a Monte-Carlo count: expected +- this many standard deviations.
BINOMIAL_SIGMAS = 4.5
#: Independent trials of the false-alarm Monte Carlo.
TRIALS = 10_000
#: An extended target: contiguous range cells (a car of 3 m in 15 cm cells) and
#: each cell's power over the clutter mean [dB].
EXTENT_CELLS, TARGET_DB = 20, 20.0
#: The old detector: cell averaging over 12 training and 3 guard cells each side.
CA_TRAIN, CA_GUARD = 12, 3
#: Range cells of a profile and profiles of the extended-target trials.
PROFILE_CELLS, PROFILES = 400, 40


def _clutter(rng, shape):
    """Complex Gaussian clutter of unit mean power (exponential power, Rayleigh amplitude)."""
    return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) / np.sqrt(2)


def _extended_profile(rng, start):
    """Power ``[range, 1, 1]``: a line of equal scatterers over clutter (random phases)."""
    z = _clutter(rng, PROFILE_CELLS)
    amp = 10 ** (TARGET_DB / 20)
    z[start:start + EXTENT_CELLS] += amp * np.exp(2j * np.pi * rng.random(EXTENT_CELLS))
    return np.abs(z)[:, None, None] ** 2


def test_extended_target_found_by_the_ordered_statistic_not_the_cell_average():
    """A 20-cell line of scatterers 20 dB over clutter: the CA-CFAR's training cells lie on
    it (its noise estimate is about half the target's power, 17 dB over the clutter:
    3 dB of SNR at the edges, 0 dB inside, threshold 12 dB), the ordered statistic's
    (rank 72 of 96) do not while it fills fewer than 96 - 72 of them."""
    rng = np.random.default_rng(7)
    os_found = ca_found = 0
    for k in range(PROFILES):
        start = 150 + k
        p = _extended_profile(rng, start)
        on = slice(start, start + EXTENT_CELLS)
        os_hits = cfar_detect(p)
        ca_hits = cfar_detect(p, train=CA_TRAIN, guard=CA_GUARD, rank=None)
        os_found += np.any((os_hits[:, 0] >= on.start) & (os_hits[:, 0] < on.stop))
        ca_found += np.any((ca_hits[:, 0] >= on.start) & (ca_hits[:, 0] < on.stop))
        noise_on = cfar_noise(p)[on, 0, 0]
        assert np.all(noise_on < 10 ** (TARGET_DB / 10) / 10 ** (CFAR_THRESHOLD_DB / 10))
    assert os_found == PROFILES
    assert ca_found == 0


def _pfa_trials(threshold_db, train, guard, rank, seed):
    """Hits of the cell under test in ``TRIALS`` independent windows (no local-maximum test)."""
    rng = np.random.default_rng(seed)
    n = 2 * (train + guard) + 1
    p = rng.exponential(1.0, (n, TRIALS, 1))
    centre = train + guard
    noise = cfar_noise(p, train=train, guard=guard, rank=rank)[centre, :, 0]
    return int(np.sum(p[centre, :, 0] > noise * 10 ** (threshold_db / 10)))


@pytest.mark.parametrize("threshold_db, train, guard, rank", [
    (3.0, CFAR_TRAIN, CFAR_GUARD, CFAR_RANK),
    (6.0, CFAR_TRAIN, CFAR_GUARD, CFAR_RANK),
    (6.0, CA_TRAIN, CA_GUARD, None),
])
def test_false_alarm_rate_on_rayleigh_clutter(threshold_db, train, guard, rank):
    """Monte-Carlo false alarms of the cell under test within binomial bounds of the closed
    form (the design threshold's rate, 7e-7, is too small to count; the closed form
    checked here at lower thresholds is the one that gives it)."""
    pfa = cfar_pfa(threshold_db, train=train, rank=rank)
    hits = _pfa_trials(threshold_db, train, guard, rank, seed=11)
    mean, sd = TRIALS * pfa, np.sqrt(TRIALS * pfa * (1 - pfa))
    assert mean > 100                                  # a countable rate
    assert abs(hits - mean) <= BINOMIAL_SIGMAS * sd, (hits, mean, sd)


def test_design_false_alarm_rate():
    """The design threshold's rate: the ordered statistic's closed form, between the
    rate with the clutter mean known (``exp(-T)``, every estimate costs more) and the
    old 24-cell average's (5.2e-6)."""
    t = 10 ** (CFAR_THRESHOLD_DB / 10)
    pfa = cfar_pfa()
    assert np.exp(-t) < pfa < cfar_pfa(train=CA_TRAIN, rank=None)
    with pytest.raises(ValueError, match="rank"):
        cfar_pfa(rank=2 * CFAR_TRAIN + 1)


def test_object_box_and_distance():
    """A rotated 4.5 x 1.8 x 1.4 m box's corners give back its axes and half extents."""
    yaw = np.deg2rad(30.0)
    c, s = np.cos(yaw), np.sin(yaw)
    half = np.array([2.25, 0.9, 0.7])
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * half
    rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    centre = np.array([-9.0, 6.0, 14.3])
    box = object_box(corners @ rot.T + centre)
    assert sorted(box["half_m"]) == pytest.approx(sorted(half), abs=1e-9)
    assert box["centre_m"] == pytest.approx(centre, abs=1e-9)
    along = rot[:, 0]                                     # the long axis
    assert box_distance(box, centre + 2.0 * along)[0] == 0.0
    assert box_distance(box, centre + 3.25 * along)[0] == pytest.approx(1.0, abs=1e-9)
    up = centre + np.array([0, 0, -1.7])
    assert box_distance(box, up)[0] == pytest.approx(1.0, abs=1e-9)


def test_an_extended_object_matched_on_its_box_a_point_on_its_position():
    """A detection on a car's front face, 2.4 m from its reference point: outside a 1 m
    radius of the point, within it of the box; a point reflector keeps the point rule."""
    from types import SimpleNamespace

    from raysim.studies.scene_report.evaluate import _nearest

    half = np.array([2.25, 0.9, 0.7])
    corners = np.array([[i, j, k] for i in (-1, 1) for j in (-1, 1) for k in (-1, 1)]) * half
    centre = np.array([-9.0, -6.0, 14.3])
    face = centre + np.array([2.4, 0.0, 0.0])              # 0.15 m beyond the front face
    result = SimpleNamespace(detections=[{"position_m": face.tolist()}])
    car = {"position_m": centre.tolist(), "box": object_box(corners + centre)}
    point = {"position_m": centre.tolist()}
    got = _nearest(car, result, 1.0)
    assert got["detected"] and got["rule"] == "box"
    assert got["error_m"] == pytest.approx(0.15, abs=1e-9)
    missed = _nearest(point, result, 1.0)
    assert not missed["detected"] and missed["rule"] == "point"
    assert missed["error_m"] == pytest.approx(2.4, abs=1e-9)
