"""Scene entropy report: ray-traced scenes seen from a hovering drone, compensated or not.

For each bundled scene (:data:`raysim.echoes.rt.scenes.SCENES`) the scene is traced
once from the nominal hover pose; the frozen paths are re-projected
(:mod:`raysim.echoes.rt.reproject`, exact image method for the specular ground
return) onto two platforms sharing the same scattering points: the radar held
at the nominal hover pose (the reference, :data:`raysim.vocabulary.REFERENCE`
``"stationary"``), and the radar on a seeded stochastic hover
(:func:`hover_trajectory`), processed by every chain of
:data:`raysim.vocabulary.CHAINS` through :func:`raysim.pipeline.chains.project`:

``none``
    no compensation (a conventional beamformer, as if the radar did not move);
``paper``
    the published chain (tilt element phase, slow-time phase, yaw beam
    projection) with its slow-time translation/rotation phase re-pointed per
    beam towards the beam's own direction, i.e. the paper's per-target
    correction evaluated for every grid direction (:mod:`.process`);
``exact``
    the exact rigid-body projection.

The pose comes from a simulated IMU (:func:`raysim.platform.imu.simulate_imu`, preset
selectable, ``ideal`` by default) integrated by
:func:`raysim.pipeline.estimate.estimate_motion` with the true initial state
(pose and velocity from the flight controller).

Every chain yields a beam cube ``[chirp, range, azimuth, elevation]`` on one
fixed global grid and range window, from which three maps are formed
(names and dimensions from :data:`raysim.vocabulary.MAPS`):

* ``rd`` ``[range, doppler]``: Hann-windowed Doppler power summed over all
  beams (range rate axis, m/s);
* ``ra`` ``[range, azimuth]``: coherent (zero-Doppler, Hann-weighted) beam
  power summed over elevation;
* ``ae`` ``[azimuth, elevation]``: coherent beam power summed over the range
  window.

Each map's image entropy (``entropy_rd_nats``, ``entropy_ra_nats``,
``entropy_ae_nats``) and the RD power off the zero-Doppler ridge
(``ridge_leakage_db``) are reported; discrete scatterers are detected by a
cell-averaging CFAR on the coherent ``[range, azimuth, elevation]`` cube and
compared with the scene's known reflector positions.

Options (:class:`ReportSettings`): ``mover_speed`` drives a car mesh (PO + SBR,
:class:`raysim.echoes.clutter.movers.CarMover`) through the scene in both frames;
it is looked for off the zero-Doppler ridge at its own range rate
(:func:`find_mover`). ``clutter`` is the persistent clutter field
(:mod:`raysim.echoes.clutter`, default, ``clutter_per_cell`` scatterers per
cell) or Sionna's own diffuse paths and mirror (``"sionna"``).

Modules: :mod:`.settings` (settings, limits), :mod:`.simulate` (trajectory,
IMU estimate, traced frames), :mod:`.process` (chain beams, maps, CFAR),
:mod:`.evaluate` (one scene), :mod:`.outputs` (figures, tables, files),
:mod:`.bench` (re-projection speed).
"""

from __future__ import annotations

from .bench import bench_reprojection
from .evaluate import MOVER_CENTRE_SPAN_DB, SceneResult, evaluate_scene, find_mover, mover_truth
from .outputs import plot_scene, report_html, report_markdown, write_scene_report
from .process import BORESIGHT, ChainResult, beam_blocks, cfar_detect, chain_result
from .settings import (
                       CFAR_GUARD,
                       CFAR_THRESHOLD_DB,
                       CFAR_TRAIN,
                       ENTROPY_MARGIN_NATS,
                       FULL,
                       MAX_DETECTIONS,
                       MAX_MOVER_SPEED,
                       MOVER_START_NE,
                       QUICK,
                       RD_PLOT_HALF_WIDTH_BINS,
                       REPORT_CLUTTER,
                       REPORT_MAPS,
                       RIDGE_HALF_WIDTH_BINS,
                       ReportSettings,
)
from .simulate import (
                       hover_trajectory,
                       imu_samples,
                       path_kinds,
                       report_mover,
                       scene_motion,
                       simulate_scene,
)

__all__ = [
    "REPORT_MAPS", "ENTROPY_MARGIN_NATS", "RIDGE_HALF_WIDTH_BINS",
    "MOVER_START_NE", "MAX_MOVER_SPEED", "REPORT_CLUTTER",
    "CFAR_TRAIN", "CFAR_GUARD", "CFAR_THRESHOLD_DB", "RD_PLOT_HALF_WIDTH_BINS",
    "MAX_DETECTIONS", "ReportSettings", "FULL", "QUICK",
    "hover_trajectory", "imu_samples", "scene_motion", "simulate_scene", "path_kinds",
    "BORESIGHT", "ChainResult", "beam_blocks", "cfar_detect", "chain_result",
    "SceneResult", "evaluate_scene", "mover_truth", "find_mover", "MOVER_CENTRE_SPAN_DB",
    "report_mover",
    "plot_scene", "report_markdown", "report_html", "write_scene_report",
    "bench_reprojection",
]
