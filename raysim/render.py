"""From a :class:`~raysim.scenario.Scenario` to frames, stores and metrics.

* :func:`frame_source` returns a callable ``f -> RadarFrame`` for frame ``f``
  (exact point-target oracle, or the Sionna RT renderer for bundled / mesh
  scenes, loaded once);
* :func:`render` writes every frame to a Zarr store with the truth pose and
  the IMU log, resuming after the last complete frame;
* :func:`analyse` measures the CONVENTIONS.md metrics of frames (range, angle,
  pseudo-velocity, Doppler width, entropies);
* :func:`evaluate` renders a scenario in memory and measures the uncompensated
  data and, with the ``compensation`` package, the paper and exact
  compensation chains (IMU log integrated by :func:`platform_motion`).
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .frame import RadarFrame
from .scenario import Scenario

__all__ = [
    "FeatureUnavailable", "Reference", "RenderSummary", "CHAINS", "LazyFrames", "frame_source",
    "reference_target", "imu_log", "render", "render_frames", "render_dataset", "analyse",
    "platform_motion", "evaluate", "gate_snapshots", "METRIC_UNITS", "IMU_MARGIN_S",
]

#: Names of the processing chains compared by :func:`evaluate` and the reports.
CHAINS = ("uncompensated", "paper", "exact")

#: Unit of every metric returned by :func:`analyse`.
METRIC_UNITS = {
    "range_m": "m", "az_deg": "deg", "el_deg": "deg", "angle_error_deg": "deg",
    "pseudo_velocity_mps": "m/s", "doppler_width_hz": "Hz", "doppler_width_bins": "bins",
    "entropy_ae_nats": "nats", "entropy_rd_nats": "nats", "peak_power_db": "dB(W)",
}

#: Half-width of the azimuth / elevation scan of :func:`analyse` [deg].
ANGLE_LIMIT_DEG = 60.0
#: Step of the azimuth / elevation scan of :func:`analyse` [deg].
ANGLE_STEP_DEG = 1.0
#: Most slow-time snapshots beamformed into the angle map (decimated beyond).
MAX_SNAPSHOTS = 256
#: Half-width of the range window searched around a known target range [m].
RANGE_SEARCH_M = 1.5


class FeatureUnavailable(RuntimeError):
    """A part of the simulator that this run needs is not installed or not working."""


@dataclass(frozen=True)
class Reference:
    """Truth direction and range of the reference target, from the nominal radar pose.

    Attributes
    ----------
    range_m : float
        Range [m].
    az_deg, el_deg : float
        Direction in frame A at the nominal attitude [deg].
    """

    range_m: float
    az_deg: float
    el_deg: float

    @property
    def direction(self) -> np.ndarray:
        """Unit vector in A, shape ``[3]``."""
        from .echo import direction

        return direction(math.radians(self.az_deg), math.radians(self.el_deg))


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
    """

    path: str
    frames_total: int
    frames_rendered: int
    frames_resumed: int
    notes: list[str] = field(default_factory=list)


# ------------------------------------------------------------------- sources
def _rt_scene(scenario: Scenario):
    try:
        from .rt.render import render_scene
        from .rt.scenes import load_scene
        from .rt.trace import MonostaticTracer
    except ImportError as exc:
        raise FeatureUnavailable(
            f"scene kind {scenario.scene.kind!r} needs the ray tracer (raysim.rt with Sionna "
            f"RT): {exc}") from None
    target = scenario.scene.name if scenario.scene.kind == "bundled" else scenario.scene.path
    if scenario.scene.kind == "mesh" and not str(target).endswith(".xml"):
        raise ValueError(f"scene.path: got {target!r}, expected a Mitsuba .xml scene file "
                         f"(convert other meshes with scenes/generate.py as a model)")
    cfg = scenario.radar_config()
    try:
        scene = load_scene(target, frequency=cfg.carrier_frequency)
    except ValueError:
        raise
    except Exception as exc:  # backend failures (no LLVM, no GPU) are not bad input
        raise FeatureUnavailable(f"cannot load scene {target!r} with Sionna RT: "
                                 f"{type(exc).__name__}: {exc}") from None
    tracer = MonostaticTracer(max_depth=max(1, scenario.scene.max_depth), seed=scenario.seed)
    return scene, tracer, render_scene


def frame_source(scenario: Scenario, trajectory=None) -> Callable[[int], RadarFrame]:
    """A callable that renders frame ``f`` of the scenario.

    Parameters
    ----------
    scenario : Scenario
    trajectory : Trajectory, optional
        Re-use an already built motion (default: ``scenario.trajectory()``).

    Returns
    -------
    callable
        ``source(f) -> RadarFrame`` with ``data`` ``[chirp, channel, sample]``;
        the callable carries ``source.reference`` (a :class:`Reference` or None).

    Raises
    ------
    FeatureUnavailable
        For a ray-traced scene when Sionna RT cannot be used here.
    """
    from .echo import simulate_point_targets

    cfg = scenario.radar_config()
    arr = scenario.virtual_array()
    traj = scenario.trajectory() if trajectory is None else trajectory
    lever = scenario.lever_arm
    if scenario.scene.kind == "points":
        targets = scenario.point_targets()

        def source(f: int) -> RadarFrame:
            return simulate_point_targets(cfg, arr, targets, traj, lever_arm=lever, frame=f,
                                          intra_chirp=scenario.intra_chirp,
                                          noise=scenario.noise, seed=scenario.seed + f)

        source.reference = reference_target(scenario)
        return source

    scene, tracer, render_scene = _rt_scene(scenario)

    def rt_source(f: int) -> RadarFrame:
        return render_scene(scene, cfg, arr, traj, lever, tracer=tracer, frame=f,
                            noise=scenario.noise, seed=scenario.seed + f)

    rt_source.reference = reference_target(scenario, scene)
    return rt_source


def reference_target(scenario: Scenario, rt_scene=None) -> Reference | None:
    """Range and direction of the first target seen from the nominal radar pose.

    Point scenes: the first ``[[scene.targets]]`` entry. Ray-traced scenes: the
    first discrete target of the loaded scene (None when it has none).
    """
    if scenario.scene.kind == "points":
        t = scenario.scene.targets[0]
        return Reference(t.range_m, t.az_deg, t.el_deg)
    targets = getattr(rt_scene, "targets", None) or []
    if not targets:
        return None
    from .echo import az_el

    d = np.asarray(targets[0].position, dtype=float) - scenario.lever_arm
    r = float(np.linalg.norm(d))
    az, el = az_el(d / r)
    return Reference(r, float(np.degrees(az)), float(np.degrees(el)))


def imu_log(scenario: Scenario, trajectory=None):
    """Simulate the scenario's IMU over all frames as an ``imu_time`` Dataset.

    Returns
    -------
    xarray.Dataset or None
        See :func:`raysim.storage.imu_dataset`; None when :mod:`raysim.imu`
        is not available.
    """
    try:
        from .imu import simulate_imu
    except ImportError:
        return None
    from .storage import imu_dataset

    traj = scenario.trajectory() if trajectory is None else trajectory
    start, end = scenario.time_span()
    rate = scenario.imu.rate_hz
    margin = max(IMU_MARGIN_S, 4.0 / rate)
    s = simulate_imu(traj, scenario.imu_spec(), rate=rate, start=start - margin, end=end + margin,
                     seed=scenario.imu_seed, time_offset=scenario.imu.time_offset_s,
                     clock_drift_ppm=scenario.imu.clock_drift_ppm)
    t, w, a = s.to_arrays()
    ds = imu_dataset(t, w, a, source=f"simulated, preset {scenario.imu.preset}")
    ds.attrs.update({"imu_rate_hz": float(rate), "imu_seed": int(scenario.imu_seed),
                     "imu_time_offset_s": float(scenario.imu.time_offset_s),
                     "imu_clock_drift_ppm": float(scenario.imu.clock_drift_ppm)})
    return ds


def _scenario_key(scenario: Scenario) -> str:
    d = scenario.to_dict()
    d.pop("output", None)
    return json.dumps(d, sort_keys=True, separators=(",", ":"))


def _store_attrs(scenario: Scenario, reference: Reference | None) -> dict:
    attrs = {"scenario_json": _scenario_key(scenario), "scenario_name": scenario.name,
             "frames_planned": int(scenario.frames), "motion_name": scenario.trajectory().name}
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
    from . import storage

    store = Path(store)
    traj = scenario.trajectory()
    done = 0
    if store.exists() and not overwrite:
        if not storage.store_exists(store):
            raise ValueError(f"{str(store)!r} exists and is not a Zarr store; choose another "
                             f"--out or pass --overwrite")
        import zarr

        attrs = dict(zarr.open_group(str(store), mode="r").attrs)
        if attrs.get("scenario_json") != _scenario_key(scenario):
            raise ValueError(f"store {str(store)!r} holds frames of a different scenario "
                             f"({attrs.get('scenario_name')!r}); pass --overwrite to replace "
                             f"it or choose another --out")
        done = storage.repair_store(store)
    elif store.exists() and overwrite:
        import shutil

        shutil.rmtree(store) if store.is_dir() else store.unlink()

    todo = list(range(done, scenario.frames))
    if max_frames is not None:
        todo = todo[: max(0, int(max_frames))]
    summary = RenderSummary(str(store), scenario.frames, 0, done)
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
                        summary.notes.append("raysim.imu is not available: no IMU log stored")
                    ds = storage.frames_to_dataset([fr], traj, imu=imu,
                                                   attrs=_store_attrs(scenario, source.reference))
                    storage.write_store(store, ds, overwrite=True)
                else:
                    storage.append_frames(store, storage.frames_to_dataset([fr], traj))
                summary.frames_rendered += 1
                if bar is not None:
                    bar.update(1)
        finally:
            if bar is not None:
                bar.close()
    if export_netcdf is not None and storage.frames_complete(store) == scenario.frames:
        storage.export_netcdf(storage.open_store(store), export_netcdf)
    return summary


class LazyFrames(Sequence):
    """The frames of a scenario, rendered when accessed (frame 0 is kept).

    Analyses of many large frames (the paper's yaw case: 20 frames of 490 MB)
    then hold about two frames in memory instead of all of them, at the price
    of rendering a frame again for every pass over the sequence.
    """

    def __init__(self, source: Callable[[int], RadarFrame], num_frames: int):
        self._source = source
        self._n = int(num_frames)
        self._first: RadarFrame | None = None
        self.reference = getattr(source, "reference", None)

    def __len__(self) -> int:
        return self._n

    def __getitem__(self, f):
        if isinstance(f, slice):
            return [self[i] for i in range(self._n)[f]]
        f = int(f) + (self._n if int(f) < 0 else 0)
        if not 0 <= f < self._n:
            raise IndexError(f"frame {f} out of range (0..{self._n - 1})")
        if f == 0:
            if self._first is None:
                self._first = self._source(0)
            return self._first
        return self._source(f)

    def chirp_times(self) -> np.ndarray:
        """Chirp start times of all frames, frame after frame, shape ``[frame * chirp]`` [s]."""
        cfg = self[0].config
        return np.concatenate([cfg.chirp_times(f) for f in range(self._n)])


def render_frames(scenario: Scenario, trajectory=None) -> list[RadarFrame]:
    """All frames of a scenario in memory (``[chirp, channel, sample]`` each)."""
    source = frame_source(scenario, trajectory)
    return [source(f) for f in range(scenario.frames)]


def render_dataset(scenario: Scenario) -> object:
    """All frames, truth pose and IMU log as one in-memory :class:`xarray.Dataset`."""
    from . import storage

    traj = scenario.trajectory()
    source = frame_source(scenario, traj)
    frames = [source(f) for f in range(scenario.frames)]
    return storage.frames_to_dataset(frames, traj, imu=imu_log(scenario, traj),
                                     attrs=_store_attrs(scenario, source.reference))


# ------------------------------------------------------------------ analysis
def gate_snapshots(data: np.ndarray, range_bin: float) -> np.ndarray:
    """Hann-windowed range DFT of IF data at one (fractional) range bin.

    Parameters
    ----------
    data : ndarray, shape ``[chirp, channel, sample]``
    range_bin : float
        Range-FFT bin (unpadded FFT of length ``sample``).

    Returns
    -------
    ndarray, shape ``[chirp, channel]``, complex64
        Equal to ``range_compress(data)[..., range_bin]`` for an integer bin.
    """
    from .processing import window

    k = data.shape[-1]
    w = window("hann", k)
    kern = (w / w.sum()) * np.exp(-2j * np.pi * range_bin * np.arange(k) / k)
    return (data @ kern.astype(np.complex64)).astype(np.complex64)


def _parabolic_peak(y: np.ndarray, i: int) -> float:
    from .metrics import parabolic_offset

    if 0 < i < y.size - 1:
        db = 10 * np.log10(np.maximum(y[i - 1: i + 2], 1e-300))
        return i + parabolic_offset(db[0], db[1], db[2])
    return float(i)


def _beamformer(chain: str, frame: RadarFrame, motion):
    """``bf(rc, chirps, ranges, az, el, direction) -> [chirp, range, azimuth, elevation]``.

    ``rc`` is ``[chirp, channel, range]`` (the chirps ``chirps`` of ``frame``),
    ``ranges`` the range of each of its bins [m], ``az``/``el`` grid axes
    [rad], ``direction`` the slow-time correction direction of the paper chain.
    """
    arr, cfg = frame.array, frame.config
    wl = cfg.center_wavelength
    if chain == "uncompensated":
        from .processing import az_el_grid

        def bf(rc, chirps, ranges, az, el, direction=None):
            a = arr.steering_vector(az_el_grid(az, el), wl).astype(np.complex64)
            y = np.swapaxes(rc, 1, 2) @ a.conj().T / arr.num_channels      # [chirp, range, dir]
            return y.reshape(y.shape[:2] + (len(az), len(el)))
        return bf
    try:
        from compensation import paper_chain, rigid_body_projection
    except ImportError as exc:
        raise FeatureUnavailable(f"the {chain} chain needs the compensation package: "
                                 f"{exc}") from None
    kw = dict(element_positions=arr.virtual_positions, wavelength=wl,
              grid_shape=arr.grid_shape)

    def bf(rc, chirps, ranges, az, el, direction=None):
        mot = motion.select(np.asarray(chirps))
        if chain == "exact":
            out = rigid_body_projection(rc, motion=mot, range_axis=ranges, azimuth=az,
                                        elevation=el, **kw)
        else:
            out = paper_chain(rc, motion=mot, direction=direction, range_axis=ranges,
                              azimuth=az, elevation=el, **kw)
        return out.data
    return bf


def analyse(frames: Sequence[RadarFrame], reference: Reference | None = None, *,
            chain: str = "uncompensated", motion=None,
            angle_limit_deg: float = ANGLE_LIMIT_DEG, angle_step_deg: float = ANGLE_STEP_DEG,
            return_maps: bool = False, range_angle_chirps: int = 16):
    """CONVENTIONS.md metrics of one or more frames, through one processing chain.

    Procedure: range profile of frame 0 (Hann, power summed over chirps and
    channels), peak within :data:`RANGE_SEARCH_M` of the reference range (or
    the global peak) refined by a parabola on dB; channel snapshots of every
    frame at that gate; azimuth-elevation map (grid ``+-angle_limit_deg`` in
    steps of ``angle_step_deg``, power summed over at most
    :data:`MAX_SNAPSHOTS` chirps) and its interpolated peak and entropy;
    slow-time signal of frame 0 at that gate in the beam towards the
    reference direction (or the measured one) for the pseudo-velocity and the
    Doppler width; range-Doppler map of the same beam and its entropy.

    The beams are a conventional beamformer for ``chain="uncompensated"``;
    ``"paper"`` and ``"exact"`` use :func:`compensation.paper_chain` (slow-time
    phase towards the chain's own angle estimate) and
    :func:`compensation.rigid_body_projection` with the platform ``motion``.

    Parameters
    ----------
    frames : sequence of RadarFrame
        ``data`` of shape ``[chirp, channel, sample]`` each.
    reference : Reference, optional
        Truth target (range window, Doppler beam, angle error).
    chain : {"uncompensated", "paper", "exact"}
    motion : compensation.PlatformMotion, optional
        Pose at every chirp of all frames, frame after frame (required for
        the compensated chains; see :func:`platform_motion`).
    return_maps : bool
        Also return the maps: ``range_profile`` (``range``), ``rd``
        (``range, doppler``), ``ae`` (``azimuth, elevation``), ``ra``
        (``range, azimuth``), ``re`` (``range, elevation``) as
        :class:`~raysim.processing.Map`, ``slow_time`` (``[chirp]``) and
        ``range_bin``.
    range_angle_chirps : int
        Chirps of frame 0 whose power is summed in the ``ra`` / ``re`` maps.

    Returns
    -------
    dict
        Metric name -> value, units in :data:`METRIC_UNITS`
        (``angle_error_deg`` is NaN without a reference). With
        ``return_maps``, a tuple ``(metrics, maps)``.
    """
    from .echo import direction
    from .metrics import angle_error_deg, doppler_mainlobe_width, pseudo_velocity
    from .processing import Map, doppler_fft, range_compress

    if not isinstance(frames, Sequence):
        frames = list(frames)
    if len(frames) == 0:
        raise ValueError("frames is empty: nothing to analyse")
    if chain not in CHAINS:
        raise ValueError(f"chain: got {chain!r}, expected one of {list(CHAINS)}")
    if chain != "uncompensated" and motion is None:
        raise ValueError(f"chain {chain!r} needs motion (the platform pose at every chirp)")
    if not (0 < angle_step_deg <= angle_limit_deg <= 90):
        raise ValueError(f"need 0 < angle_step_deg <= angle_limit_deg <= 90, got "
                         f"{angle_step_deg!r}, {angle_limit_deg!r}")
    cfg = frames[0].config
    n = frames[0].data.shape[0]
    if motion is not None and motion.num_chirps != n * len(frames):
        raise ValueError(f"motion has {motion.num_chirps} chirps, frames have "
                         f"{n * len(frames)}")
    bfs = [_beamformer(chain, frames[0], None if motion is None else
                       motion.select(slice(k * n, (k + 1) * n)))
           for k in range(len(frames))]
    wl = cfg.center_wavelength

    rc0 = range_compress(frames[0].data)                       # [chirp, channel, range]
    n_range = rc0.shape[-1]
    r_axis = cfg.range_axis(n_range)[:n_range]
    profile = np.sum(np.abs(rc0) ** 2, axis=(0, 1))[: r_axis.size]
    search = profile.copy()
    if reference is not None:
        outside = np.abs(r_axis - reference.range_m) > RANGE_SEARCH_M
        if not np.all(outside):
            search[outside] = 0.0
    i = int(np.argmax(search))
    range_m = float(np.interp(_parabolic_peak(profile, i), np.arange(r_axis.size), r_axis))
    gate_r = r_axis[[i]]

    grid = np.deg2rad(np.arange(-angle_limit_deg, angle_limit_deg + 1e-9, angle_step_deg))
    step = max(1, int(math.ceil(n * len(frames) / MAX_SNAPSHOTS)))
    pick = np.arange(0, n, step)
    power = 0.0
    snaps0 = None
    for k, bf in enumerate(bfs):
        snaps = gate_snapshots(frames[k].data, i)[:, :, None]   # [chirp, channel, 1]
        if k == 0:
            snaps0 = snaps
        beams = bf(snaps[pick], pick, gate_r, grid, grid, reference.direction
                   if reference is not None else None)
        power = power + np.sum(np.abs(beams[:, 0].astype(np.complex128)) ** 2, axis=0)
    ae = Map(power, ("azimuth", "elevation"), {"azimuth": grid, "elevation": grid})
    pk = ae.peak()
    u_hat = direction(pk["azimuth"], pk["elevation"])
    if reference is not None:
        look_az, look_el = math.radians(reference.az_deg), math.radians(reference.el_deg)
        err = angle_error_deg(pk["azimuth"], pk["elevation"], look_az, look_el)
    else:
        look_az, look_el, err = pk["azimuth"], pk["elevation"], math.nan
    all_chirps = np.arange(n)
    slow = bfs[0](snaps0, all_chirps, gate_r, [look_az], [look_el], u_hat)[:, 0, 0, 0]
    beam_rc = bfs[0](rc0, all_chirps, r_axis, [look_az], [look_el], u_hat)[:, :, 0, 0]
    spec = doppler_fft(beam_rc, axis=0)                          # [doppler, range]
    rd = Map(np.abs(spec.T) ** 2, ("range", "doppler"),
             {"range": r_axis, "doppler": cfg.velocity_axis(spec.shape[0])})
    width = doppler_mainlobe_width(slow, cfg.chirp_interval)
    metrics = {
        "range_m": range_m,
        "az_deg": math.degrees(pk["azimuth"]),
        "el_deg": math.degrees(pk["elevation"]),
        "angle_error_deg": float(err),
        "pseudo_velocity_mps": pseudo_velocity(slow, cfg.chirp_interval, wl),
        "doppler_width_hz": width,
        "doppler_width_bins": width / cfg.doppler_resolution,
        "entropy_ae_nats": ae.entropy(),
        "entropy_rd_nats": rd.entropy(),
        "peak_power_db": float(10 * np.log10(max(profile[i] / (n * snaps0.shape[1]),
                                                  1e-300))),
    }
    if not return_maps:
        return metrics
    ra_pick = np.unique(np.linspace(0, n - 1, min(n, range_angle_chirps)).astype(int))
    ra = bfs[0](rc0[ra_pick], ra_pick, r_axis, grid, [look_el], u_hat)[:, :, :, 0]
    re_ = bfs[0](rc0[ra_pick], ra_pick, r_axis, [look_az], grid, u_hat)[:, :, 0, :]
    maps = {
        "range_profile": Map(profile, ("range",), {"range": r_axis}), "rd": rd, "ae": ae,
        "ra": Map(np.sum(np.abs(ra) ** 2, axis=0), ("range", "azimuth"),
                  {"range": r_axis, "azimuth": grid}),
        "re": Map(np.sum(np.abs(re_) ** 2, axis=0), ("range", "elevation"),
                  {"range": r_axis, "elevation": grid}),
        "range_bin": i, "slow_time": slow,
    }
    return metrics, maps


# -------------------------------------------------------------- compensation
#: IMU record margin before the first and after the last chirp [s].
IMU_MARGIN_S = 0.02


def platform_motion(scenario: Scenario, imu, chirp_times: np.ndarray, trajectory=None):
    """Strapdown-integrate an IMU log to the platform pose at every chirp.

    Initial attitude, position and velocity at the first chirp are taken from
    the truth trajectory (the flight controller's state).

    Parameters
    ----------
    scenario : Scenario
        Lever arm and IMU clock offset.
    imu : xarray.Dataset
        ``imu_time`` [s, IMU clock], ``imu_gyro`` [rad/s], ``imu_accel`` [m/s^2].
    chirp_times : ndarray, shape ``[chirp]``
        Chirp start times of all frames, in order [s].

    Returns
    -------
    compensation.PlatformMotion

    Raises
    ------
    FeatureUnavailable
        Without the compensation package.
    """
    try:
        from compensation import integrate_imu
    except ImportError as exc:
        raise FeatureUnavailable(f"compensation needs the compensation package: {exc}") from None
    traj = scenario.trajectory() if trajectory is None else trajectory
    t = np.asarray(chirp_times, dtype=float).ravel()
    t_ref = float(t[0])
    return integrate_imu(np.asarray(imu["imu_time"].values), np.asarray(imu["imu_gyro"].values),
                         np.asarray(imu["imu_accel"].values), t, lever_arm=scenario.lever_arm,
                         time_offset=scenario.imu.time_offset_s, reference_time=t_ref,
                         initial_attitude=traj.attitude([t_ref]).as_matrix()[0],
                         initial_position=traj.position([t_ref])[0], velocity="given",
                         initial_velocity=traj.velocity([t_ref])[0])


def evaluate(scenario: Scenario, *, chains: Sequence[str] = CHAINS, frames=None, imu=None,
             reference: Reference | None = None, return_maps: bool = False) -> dict:
    """Render a scenario in memory (unless ``frames`` are given) and measure every chain.

    Parameters
    ----------
    scenario : Scenario
    chains : sequence of str
        Subset of :data:`CHAINS`.
    frames : sequence of RadarFrame, optional
        Frames already rendered (or read from a store); default a
        :class:`LazyFrames` of the scenario.
    imu : xarray.Dataset, optional
        IMU log; simulated from the scenario if omitted.
    reference : Reference, optional
        Truth target when ``frames`` are given (default: the scenario's first
        point target).
    return_maps : bool
        Also return the maps of every chain (see :func:`analyse`).

    Returns
    -------
    dict
        ``{"reference": Reference or None, "chains": {chain: metrics}, "notes": [str]}``
        (plus ``"maps": {chain: maps}`` with ``return_maps``); chains that
        cannot run here are skipped with a note.
    """
    bad = [c for c in chains if c not in CHAINS]
    if bad:
        raise ValueError(f"chains: got {bad}, expected names from {list(CHAINS)}")
    traj = scenario.trajectory()
    if frames is None:
        frames = LazyFrames(frame_source(scenario, traj), scenario.frames)
        reference = frames.reference
    elif reference is None and scenario.scene.kind == "points":
        reference = reference_target(scenario)
    out: dict = {"reference": reference, "chains": {}, "notes": []}
    if return_maps:
        out["maps"] = {}
    motion = None
    for chain in chains:
        try:
            if chain != "uncompensated" and motion is None:
                if imu is None:
                    imu = imu_log(scenario, traj)
                if imu is None:
                    raise FeatureUnavailable("raysim.imu is not available")
                times = (frames.chirp_times() if isinstance(frames, LazyFrames)
                         else np.concatenate([fr.chirp_times for fr in frames]))
                motion = platform_motion(scenario, imu, times, traj)
            res = analyse(frames, reference, chain=chain, motion=motion,
                          return_maps=return_maps)
        except FeatureUnavailable as exc:
            out["notes"].append(f"{chain}: {exc}")
            continue
        if return_maps:
            out["chains"][chain], out["maps"][chain] = res
        else:
            out["chains"][chain] = res
    return out
