"""The run path end to end: a scenario -> a store of frames, or -> metrics of every chain.

:func:`render` writes every frame of a scenario to a Zarr store (resumable);
:func:`evaluate` composes the stages in memory: echo source
(:mod:`~raysim.pipeline.sources`) -> IF frames -> IMU log
(:mod:`~raysim.pipeline.sensors`) -> motion estimate
(:mod:`~raysim.pipeline.estimate`) -> chain (:mod:`~raysim.pipeline.chains`)
-> point metrics and maps (:mod:`raysim.measure.point`).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from raysim.measure.point import measure, point_cells
from raysim.pipeline.estimate import scenario_motion
from raysim.pipeline.sensors import imu_log
from raysim.pipeline.sources import (
    FeatureUnavailable,
    LazyFrames,
    Reference,
    frame_source,
    reference_target,
)
from raysim.scenario import Scenario
from raysim.vocabulary import CHAINS, parse_chains

__all__ = ["RenderSummary", "render", "render_dataset", "evaluate"]


@dataclass
class RenderSummary:
    """What :func:`render` did.

    Attributes
    ----------
    path : str
        Zarr store.
    frames_total : int
        Frames the scenario asks for.
    frames_rendered : int
        Frames computed by this call.
    frames_resumed : int
        Frames found complete in the store and skipped.
    notes : list of str
        What the user should know (debris removed, no IMU log).
    first_frame : int or None
        The first frame rendered by this call (None when none was).
    truth : dict
        Its :attr:`~raysim.synthesis.frame.RadarFrame.truth`: for a traced scene
        ``paths`` (the frozen :class:`~raysim.echoes.rt.trace.PathSet` of its
        first trace), ``num_paths``, ``clutter`` (:mod:`raysim.echoes.rt.render`).
    """

    path: str
    frames_total: int
    frames_rendered: int
    frames_resumed: int
    notes: list[str] = field(default_factory=list)
    first_frame: int | None = None
    truth: dict = field(default_factory=dict)



def _scenario_key(scenario: Scenario) -> str:
    d = scenario.to_dict()
    d.pop("output", None)
    return json.dumps(d, sort_keys=True, separators=(",", ":"))


def _store_attrs(scenario: Scenario, reference: Reference | None) -> dict:
    attrs = {"scenario_json": _scenario_key(scenario), "scenario_name": scenario.name,
             "frames_planned": int(scenario.frames), "motion_name": scenario.trajectory().name}
    if scenario.time_epoch_utc is not None:
        attrs["time_epoch_utc"] = scenario.time_epoch_utc
    from raysim.platform.mounting import is_default_mounting, mounting_deg

    if not is_default_mounting(scenario.radar.mounting_deg):    # compensate reads it back
        attrs["mounting_deg"] = list(mounting_deg(scenario.radar.mounting_deg))
    if reference is not None:
        attrs.update({"reference_range_m": reference.range_m,
                      "reference_az_deg": reference.az_deg,
                      "reference_el_deg": reference.el_deg})
    return attrs


def render(scenario: Scenario, store: str | Path, *, overwrite: bool = False,
           progress: bool = False, export_netcdf: str | Path | None = None,
           max_frames: int | None = None) -> RenderSummary:
    """Render every frame of a scenario into a Zarr store, resuming if interrupted.

    Frame ``f`` is appended only after frames ``0 .. f-1``; a store written by
    the same scenario (``output`` aside) is continued from its first missing
    frame. Each frame is marked complete only after its arrays are written.

    Parameters
    ----------
    scenario : Scenario
    store : path
        Zarr store (a folder).
    overwrite : bool
        Start again even if the store holds frames of this or another scenario.
    progress : bool
        Show a tqdm progress bar on stderr.
    export_netcdf : path, optional
        Also export the finished store to this NetCDF file.
    max_frames : int, optional
        Stop after rendering this many new frames (the store stays resumable).

    Returns
    -------
    RenderSummary

    Raises
    ------
    ValueError
        The store holds frames of a different scenario (and ``overwrite`` is False).
    """
    from raysim.io import storage
    from raysim.io.store_guard import check_replaceable, remove_debris, writer_lock

    store = Path(store)
    traj = scenario.trajectory()
    if store.exists():
        check_replaceable(store, "--out")      # never touch what raysim did not write
    kept = (storage.frames_complete(store)
            if store.exists() and not overwrite and storage.store_exists(store) else 0)
    announce_store_size(scenario, store, progress=progress, frames_done=kept)
    summary = RenderSummary(str(store), scenario.frames, 0, 0)
    with writer_lock(store):
        removed = remove_debris(store)
        if removed:
            summary.notes.append(f"removed {len(removed)} leftover file(s) of an interrupted "
                                 f"writer of {str(store)!r}")
        done = 0
        if store.exists() and not overwrite and storage.store_exists(store):
            import zarr

            attrs = dict(zarr.open_group(str(store), mode="r").attrs)
            if attrs.get("scenario_json") != _scenario_key(scenario):
                raise ValueError(f"store {str(store)!r} holds frames of a different scenario "
                                 f"({attrs.get('scenario_name')!r}); pass --overwrite to "
                                 f"replace it or choose another --out")
            done = storage.repair_store(store)
        elif store.exists() and overwrite:
            from raysim.io.store_guard import remove_store

            remove_store(store)
        summary.frames_resumed = done
        _render_frames(scenario, store, traj, done, max_frames, progress, summary)
    if export_netcdf is not None and storage.frames_complete(store) == scenario.frames:
        storage.export_netcdf(storage.open_store(store), export_netcdf)
    return summary


def announce_store_size(scenario: Scenario, store: Path, *, progress: bool = False,
                        frames_done: int = 0) -> int:
    """Estimate what a render adds to its store; refuse it if the disk lacks room, announce
    it if large.

    The size is the IF cubes (complex64) plus the per-chirp pose of the
    frames still missing (``scenario.frames - frames_done``: a resumed render,
    e.g. after a full disk, needs room only for those); compression does not
    shrink noisy IF data. Printed on stderr when ``progress`` is set or the
    size exceeds :data:`raysim.resources.LARGE_OUTPUT_BYTES`.

    Returns
    -------
    int
        Estimated bytes still to write.
    """
    import sys

    from raysim.resources import LARGE_OUTPUT_BYTES, cube_bytes, format_bytes, free_disk

    cfg = scenario.radar_config()
    shape = (cfg.num_chirps, scenario.virtual_array().num_channels, cfg.num_samples)
    per_frame = cube_bytes(*shape) + cfg.num_chirps * 7 * 8
    missing = max(0, scenario.frames - int(frames_done))
    total = per_frame * missing
    free = free_disk(store.resolve().parent)
    if total > free:
        raise ValueError(f"store {str(store)!r} would take about {format_bytes(total)} "
                         f"({missing} missing frame(s) of {list(shape)} complex64), "
                         f"{format_bytes(free)} are free on its disk; expected a render that "
                         f"fits: reduce frames, radar.num_chirps or the array")
    if progress or total > LARGE_OUTPUT_BYTES:
        print(f"render: {missing} frame(s) to write of {list(shape)} complex64, "
              f"{format_bytes(per_frame)} each, about {format_bytes(total)} in {str(store)!r}",
              file=sys.stderr, flush=True)
    return total


def _render_frames(scenario: Scenario, store: Path, traj, done: int, max_frames, progress: bool,
                   summary: RenderSummary) -> None:
    """Frames ``done ..`` of a scenario appended to a store (the caller holds its lock)."""
    from raysim.io import storage

    todo = list(range(done, scenario.frames))
    if max_frames is not None:
        todo = todo[: max(0, int(max_frames))]
    if todo:
        source = frame_source(scenario, traj)
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=scenario.frames, initial=done, unit="frame", desc="render")
        try:
            for f in todo:
                fr = source(f)
                if f == 0 or not storage.store_exists(store):
                    imu = imu_log(scenario, traj)
                    if imu is None:
                        summary.notes.append("raysim.platform.imu is not available: "
                                             "no IMU log stored")
                    ds = storage.frames_to_dataset([fr], traj, imu=imu,
                                                   attrs=_store_attrs(scenario, source.reference))
                    storage.write_store(store, ds, overwrite=True)
                else:
                    storage.append_frames(store, storage.frames_to_dataset([fr], traj))
                if summary.first_frame is None:
                    summary.first_frame, summary.truth = f, dict(fr.truth)
                summary.frames_rendered += 1
                if bar is not None:
                    bar.update(1)
        finally:
            if bar is not None:
                bar.close()


def render_dataset(scenario: Scenario) -> object:
    """All frames, truth pose and IMU log as one in-memory :class:`xarray.Dataset`."""
    from raysim.io import storage

    traj = scenario.trajectory()
    source = frame_source(scenario, traj)
    frames = [source(f) for f in range(scenario.frames)]
    return storage.frames_to_dataset(frames, traj, imu=imu_log(scenario, traj),
                                     attrs=_store_attrs(scenario, source.reference))



def motion_times(frame, chirp_times: np.ndarray) -> np.ndarray:
    """Times at which the motion is needed: every TDM slot of every chirp [s].

    Parameters
    ----------
    frame : RadarFrame
        A frame of the run (its array's slots and its config's slot interval).
    chirp_times : ndarray, shape ``[chirp]``
        Chirp-loop start times of all frames [s].

    Returns
    -------
    ndarray, shape ``[chirp * slot]``
        Chirp major, slot minor; equal to ``chirp_times`` for a single-slot array.
    """
    from raysim.platform.kinematics import slot_times

    return slot_times(chirp_times, frame.array.num_slots, frame.config.slot_interval).ravel()


def evaluate(scenario: Scenario, *, chains: Sequence[str] = CHAINS, frames=None, imu=None,
             reference: Reference | None = None, return_maps: bool = False,
             velocity: str = "given") -> dict:
    """Render a scenario in memory (unless ``frames`` are given) and measure every chain.

    Parameters
    ----------
    scenario : Scenario
    chains : sequence of str
        Chain names (:data:`raysim.vocabulary.CHAINS`, ``paper:published``).
    frames : sequence of RadarFrame, optional
        Frames already rendered (or read from a store); default a
        :class:`LazyFrames` of the scenario.
    imu : xarray.Dataset, optional
        IMU log; simulated from the scenario if omitted.
    reference : Reference, optional
        Truth target when ``frames`` are given (default: the scenario's first
        point target).
    return_maps : bool
        Also return the maps of every chain (see :func:`raysim.measure.point.measure`).
    velocity : {"given", "hover"}
        Initial velocity of the strapdown integration
        (:data:`raysim.pipeline.estimate.VELOCITY_MODES`).

    Returns
    -------
    dict
        ``{"reference": Reference or None, "chains": {chain: metrics},
        "warnings": {chain: [str]}, "notes": [str]}`` (plus ``"maps": {chain:
        maps}`` with ``return_maps``); chains that cannot run here are
        skipped with a note.
    """
    specs = parse_chains(chains)
    traj = scenario.trajectory()
    if frames is None:
        frames = LazyFrames(frame_source(scenario, traj), scenario.frames)
        reference = frames.reference
    elif reference is None and scenario.scene.kind == "points":
        reference = reference_target(scenario)
    out: dict = {"reference": reference, "chains": {}, "warnings": {}, "notes": []}
    if return_maps:
        out["maps"] = {}
    cells = point_cells(frames, reference)          # every frame read once for all chains
    motion = None
    for spec in specs:
        found: list[str] = []
        try:
            if spec.compensated and motion is None:
                if imu is None:
                    imu = imu_log(scenario, traj)
                if imu is None:
                    raise FeatureUnavailable("raysim.platform.imu is not available")
                times = (frames.chirp_times() if isinstance(frames, LazyFrames)
                         else np.concatenate([fr.chirp_times for fr in frames]))
                motion = scenario_motion(scenario, imu, motion_times(frames[0], times), traj,
                                         velocity=velocity)
                found.extend(motion.warnings)
            res = measure(cells, reference, chain=spec, motion=motion if spec.compensated
                          else None, return_maps=return_maps, warnings=found)
        except FeatureUnavailable as exc:
            out["notes"].append(f"{spec.key}: {exc}")
            continue
        out["warnings"][spec.key] = found
        if return_maps:
            out["chains"][spec.key], out["maps"][spec.key] = res
        else:
            out["chains"][spec.key] = res
    return out
