"""Measurements of the report: the scene maps of one chain, and the point metrics of a target.

The scene maps, their entropies, the ridge leakage and the CFAR detections are
:func:`raysim.measure.scene.measure_scene` (definitions and parameters there
and in docs/conventions.md) on the report's grid and range window
(:func:`chain_result`). The point metrics of a scenario's reference target are
the point measurement of ``raysim simulate`` (:func:`point_metrics`).
"""

from __future__ import annotations

import numpy as np

from raysim.measure.scene import (
    BORESIGHT,
    SceneMeasurement,
    beam_blocks,
    cfar_detect,
    measure_scene,
    range_compressed,
)
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig

from .settings import ReportSettings

__all__ = ["BORESIGHT", "ChainResult", "beam_blocks", "cfar_detect", "chain_result",
           "report_cube", "point_metrics"]

#: The result of one chain (or of the stationary reference): the scene measurement.
ChainResult = SceneMeasurement


def report_cube(data: np.ndarray, settings: ReportSettings) -> np.ndarray:
    """Range-compressed cube ``[chirp, channel, range]`` with the report's channel taper.

    ``data`` is an IF cube ``[chirp, channel, sample]`` [sqrt(W)]
    (:func:`raysim.measure.scene.range_compressed`).
    """
    return range_compressed(data, settings.channel_taper())


def chain_result(chain, rc: np.ndarray, motion, settings: ReportSettings,
                 config: RadarConfig, array: VirtualArray, *,
                 subaperture=None) -> SceneMeasurement:
    """Beams, maps, entropies and detections of one chain (or of the reference).

    :func:`raysim.measure.scene.measure_scene` on the report's grid, range
    window, lever arm and gate block.

    Parameters
    ----------
    chain : str or ChainSpec
        A chain (``none``, ``paper``, ``paper:published``, ``exact``, ``dpca``), or
        :data:`raysim.vocabulary.REFERENCE` for the stationary platform's frame
        (beamformed like ``none``).
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube (Hann), channel taper applied (:func:`report_cube`;
        ``dpca`` moves the taper onto its sub-aperture).
    motion : compensation.PlatformMotion or None
        Pose estimate at the chirps (needed by the compensated chains).
    settings, config, array
        Report settings, waveform and virtual array.
    subaperture : (int, int) or array_like of int, optional
        ``dpca``: elements per axis of its sub-aperture, or the lattice indices
        ``[sub, 2]`` of its elements (default the largest the motion leaves).

    Returns
    -------
    SceneMeasurement
    """
    az, el = settings.grid()
    return measure_scene(chain, rc, motion, config=config, array=array, azimuth=az,
                         elevation=el, range_window=settings.range_window,
                         lever_arm=settings.lever_arm, gate_block=settings.gate_block,
                         spatial_window=settings.spatial_window, subaperture=subaperture,
                         mounting_deg=settings.scenario.radar.mounting_deg)


def point_metrics(frames, reference, chain, motion) -> dict:
    """Point metrics of the reference target through one chain (those of ``raysim simulate``).

    Parameters
    ----------
    frames : sequence of RadarFrame
        ``data`` ``[chirp, channel, sample]`` each.
    reference : raysim.pipeline.sources.Reference
        The scenario's reference target.
    chain : str or ChainSpec
        ``none``, ``paper``, ``paper:published`` or ``exact``.
    motion : compensation.PlatformMotion or None
        Pose at every transmit slot of every chirp of all frames (None for ``none``).

    Returns
    -------
    dict
        Metric name -> value (:data:`raysim.vocabulary.METRICS`).
    """
    from raysim.measure.point import measure

    return measure(frames, reference, chain=chain, motion=motion)
