"""The scene report's detection verdicts: SNR over the CFAR noise, threshold, reason of a miss."""

from __future__ import annotations

import numpy as np
import pytest

from raysim.measure.scene import (
    CFAR_RANK,
    CFAR_THRESHOLD_DB,
    CFAR_TRAIN,
    MISS_REASONS,
    SceneMeasurement,
    cfar_detect,
    explain_detection,
)
from raysim.processing.maps import Map

RANGE = 10.0 + 0.5 * np.arange(40)                     # gates of the window [m]
AZ = np.deg2rad(np.arange(-30.0, 31.0, 6.0))           # 11 cells
EL = AZ.copy()
#: The ordered statistic of a constant background over its mean in exponential
#: clutter (``sum_{i=n-k+1}^{n} 1/i``, n training cells, rank k): the CFAR's noise
#: estimate of a constant background of 1 is 1 over that sum [dB].
SCALE_DB = 10 * np.log10(np.sum(1.0 / np.arange(2 * CFAR_TRAIN - CFAR_RANK + 1,
                                                  2 * CFAR_TRAIN + 1)))


def _scene(cube: np.ndarray) -> SceneMeasurement:
    maps = {"ra": Map(cube.sum(axis=2), ("range", "azimuth"), {"range": RANGE, "azimuth": AZ}),
            "ae": Map(cube.sum(axis=0), ("azimuth", "elevation"),
                      {"azimuth": AZ, "elevation": EL})}
    return SceneMeasurement("none", maps, cube, {}, [], 0.0, 0.0)


@pytest.fixture()
def scene():
    cube = np.ones((RANGE.size, AZ.size, EL.size))
    cube[20, 5, 5] = 1000.0        # a strong point: 30 dB over the noise, at (20 m, 0, 0)
    cube[20, 6, 5] = 200.0         # its sidelobe towards a weaker neighbour
    cube[20, 7, 5] = 100.0         # a weaker point beside it (masked)
    cube[8, 2, 2] = 3.0            # a weak point: 4.8 dB (below threshold)
    return _scene(cube)


def test_every_verdict(scene):
    assert len(cfar_detect(scene.cube)) >= 1
    ok = explain_detection(scene, 20.0, 0.0, 0.0)
    assert ok["status"] == "detected" and ok["cell"] == [20, 5, 5]
    assert ok["snr_db"] == pytest.approx(30.0 + SCALE_DB, abs=0.5)
    assert ok["threshold_db"] == CFAR_THRESHOLD_DB
    weak = explain_detection(scene, 14.0, -18.0, -18.0)
    assert weak["status"] == "below threshold"
    assert weak["snr_db"] == pytest.approx(10 * np.log10(3.0) + SCALE_DB, abs=0.3)
    masked = explain_detection(scene, 20.0, 12.0, 0.0)
    assert masked["status"] == "masked by a stronger neighbour"
    assert masked["snr_db"] > CFAR_THRESHOLD_DB
    far = explain_detection(scene, 40.0, 0.0, 0.0)
    assert far == {"status": "outside the range window", "snr_db": None,
                   "threshold_db": CFAR_THRESHOLD_DB, "cell": None}
    wide = explain_detection(scene, 20.0, 50.0, 0.0)
    assert wide["status"] == "outside the grid" and wide["snr_db"] is None
    kept = explain_detection(scene, 20.0, 0.0, 0.0, max_detections=0)
    assert kept["status"] == "beyond the strongest detections kept"
    assert {weak["status"], masked["status"], far["status"], wide["status"],
            kept["status"]} == set(MISS_REASONS)


def test_bad_point_is_named(scene):
    with pytest.raises(ValueError, match="az_deg: got nan, expected a finite number"):
        explain_detection(scene, 20.0, float("nan"), 0.0)
