"""Scene entropy report: ray-traced scenes seen from a hovering drone, compensated or not.

The report is a configuration of the one pipeline: a scenario
(:class:`raysim.scenario.Scenario`: radar, array, motion, IMU, scene) plus
the study's knobs (:class:`ReportSettings`: rays, grid, range window, jitter
axes, the report's car). For each bundled scene (:data:`raysim.echoes.rt.scenes.SCENES`,
:func:`report_scenario`) or scenario file, frame 0 is rendered by the
pipeline's stationary / hover twin (:func:`raysim.pipeline.sources.hover_twin`):
a traced scene is traced once from the nominal hover pose and the frozen paths
are re-projected (:mod:`raysim.echoes.rt.reproject`, exact image method for
the specular ground return) onto two platforms sharing the same scattering
points: the radar held at the nominal pose (the reference,
:data:`raysim.vocabulary.REFERENCE` ``"stationary"``), and the radar on the
scenario's motion moved to the nominal pose at the first chirp
(:func:`report_trajectory`; for the bundled scenes the seeded hover jitter
:func:`hover_trajectory`). Both are processed by every chain of
:data:`raysim.vocabulary.CHAINS` through :func:`raysim.pipeline.chains.project`:

``none``
    no compensation (a conventional beamformer, as if the radar did not move);
``paper``
    the published chain (tilt element phase, slow-time phase, yaw beam
    projection) with its slow-time translation/rotation phase re-pointed per
    beam towards the beam's own direction, i.e. the paper's per-target
    correction evaluated for every grid direction (:mod:`raysim.measure.scene`);
``exact``
    the exact rigid-body projection.

The pose comes from the scenario's simulated IMU
(:func:`raysim.pipeline.sensors.imu_record`, ``ideal`` by default) integrated by
:func:`raysim.pipeline.estimate.estimate_motion` with the true initial state
(pose and velocity from the flight controller).

The scene measurement (:func:`raysim.measure.scene.measure_scene`) forms the
maps ``rd`` ``[range, doppler]``, ``ra`` ``[range, azimuth]`` and ``ae``
``[azimuth, elevation]`` over the global grid and range window, their image
entropies (``scene_entropy_rd_nats``, ``scene_entropy_ra_nats``,
``scene_entropy_ae_nats``: not the point metrics ``entropy_rd_nats`` /
``entropy_ae_nats`` of one target), the RD power off the zero-Doppler ridge
(``ridge_leakage_db``, :mod:`raysim.measure.ridge`) and cell-averaging CFAR
detections compared with the scene's known reflectors. For a scenario's
reference target (:func:`raysim.pipeline.sources.reference_target`) the point
metrics of every chain are reported too (:func:`point_metrics`); for a point
scenario they are those of ``raysim simulate``.

Options: ``mover_speed`` drives a car mesh (PO + SBR,
:class:`raysim.echoes.moving.cars.CarMover`) through the scene in both frames;
it is looked for off the zero-Doppler ridge at its own range rate
(:func:`find_mover`). The scenario's ``[scene.clutter]`` selects the persistent
clutter field (:mod:`raysim.echoes.ground.field`, default, ``per_cell`` scatterers per
cell), Sionna's own diffuse paths and mirror (``"sionna"``) or neither (``"none"``).

Modules: :mod:`.settings` (scenario and knobs, limits), :mod:`.simulate` (trajectory,
IMU estimate, twin frames), :mod:`.process` (scene and point measurements),
:mod:`.evaluate` (one scene or scenario), :mod:`.outputs` (figures, tables, files),
:mod:`raysim.bench.reprojection` (re-projection speed).
"""

from __future__ import annotations

from .evaluate import (
                       MOVER_CENTRE_SPAN_DB,
                       SceneResult,
                       evaluate_scenario,
                       evaluate_scene,
                       find_mover,
                       mover_truth,
                       settings_dict,
)
from .outputs import (
                       POINT_TABLE_METRICS,
                       plot_scene,
                       report_html,
                       report_markdown,
                       result_label,
                       write_scene_report,
)
from .process import (
                       BORESIGHT,
                       ChainResult,
                       beam_blocks,
                       cfar_detect,
                       chain_result,
                       point_metrics,
                       report_cube,
)
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
                       SCENARIO_KEYS,
                       ReportSettings,
                       report_scenario,
)
from .simulate import (
                       hover_trajectory,
                       imu_samples,
                       path_kinds,
                       report_mover,
                       report_trajectory,
                       scene_motion,
                       simulate_scene,
)

__all__ = [
    "REPORT_MAPS", "ENTROPY_MARGIN_NATS", "RIDGE_HALF_WIDTH_BINS",
    "MOVER_START_NE", "MAX_MOVER_SPEED", "REPORT_CLUTTER",
    "CFAR_TRAIN", "CFAR_GUARD", "CFAR_THRESHOLD_DB", "RD_PLOT_HALF_WIDTH_BINS",
    "MAX_DETECTIONS", "SCENARIO_KEYS", "ReportSettings", "report_scenario", "FULL", "QUICK",
    "hover_trajectory", "report_trajectory", "imu_samples", "scene_motion", "simulate_scene",
    "path_kinds", "BORESIGHT", "ChainResult", "beam_blocks", "cfar_detect", "chain_result",
    "report_cube", "point_metrics",
    "SceneResult", "evaluate_scene", "evaluate_scenario", "settings_dict", "mover_truth",
    "find_mover", "MOVER_CENTRE_SPAN_DB", "report_mover",
    "POINT_TABLE_METRICS", "plot_scene", "report_markdown", "report_html",
    "write_scene_report", "result_label",
]
