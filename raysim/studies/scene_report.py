"""Scene entropy report: ray-traced scenes seen from a hovering drone, compensated or not.

For each bundled scene (:data:`raysim.echoes.rt.scenes.SCENES`) the scene is traced
once from the nominal hover pose; the frozen paths are re-projected
(:mod:`raysim.echoes.rt.reproject`, exact image method for the specular ground
return) onto two platforms sharing the same scattering points:

``stationary``
    the radar held at the nominal hover pose;
``uncompensated``
    the radar on a seeded stochastic hover (:func:`raysim.platform.motion.hover_jitter`),
    processed as if it did not move;
``paper``
    the hovering radar, compensated with the published chain
    (:func:`compensation.paper_chain`: roll/pitch element phase and yaw beam
    projection), whose slow-time translation/rotation phase is applied per
    beam towards the beam's own direction (:func:`compensation.range_change`),
    i.e. the paper's per-target correction evaluated for every grid direction;
``exact``
    the hovering radar, compensated with the exact rigid-body projection
    (:func:`compensation.rigid_body_projection`).

The pose comes from a simulated IMU (:func:`raysim.platform.imu.simulate_imu`, preset
selectable, ``ideal`` by default) integrated by
:func:`compensation.integrate_imu` with the true initial state (pose and
velocity from the flight controller).

Every chain yields a beam cube ``[chirp, range, azimuth, elevation]`` on one
fixed global grid and range window, from which three maps are formed:

* **RD** ``[range, doppler]``: Hann-windowed Doppler power summed over all
  beams (range rate axis, m/s);
* **RA** ``[range, azimuth]``: coherent (zero-Doppler, Hann-weighted) beam
  power summed over elevation;
* **RE** ``[azimuth, elevation]``: coherent beam power summed over the range
  window.

Each map's image entropy (CONVENTIONS.md, nats) is reported; discrete
scatterers are detected by a cell-averaging CFAR on the coherent
``[range, azimuth, elevation]`` cube and compared with the scene's known
reflector positions.
"""

from __future__ import annotations

import functools
import html
import json
import math
import os
import sys
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, replace
from pathlib import Path

import numpy as np

from raysim.io.files import atomic_write
from raysim.processing.maps import Map, range_compress
from raysim.processing.metrics import image_entropy
from raysim.radar.arrays import VirtualArray, upa
from raysim.radar.config import RadarConfig

#: The chains compared in the report, in display order.
CHAINS = ("stationary", "uncompensated", "paper", "exact")
#: The maps of every chain.
MAPS = ("rd", "ra", "re")
#: Map axis names (CONVENTIONS.md).
MAP_DIMS = {"rd": ("range", "doppler"), "ra": ("range", "azimuth"),
            "re": ("azimuth", "elevation")}
#: Largest ``|H_exact - H_stationary|`` of every map of every bundled scene with
#: the ideal IMU [nats] (checked by ``tests/rt/test_scene_report.py``). Set by
#: the residual Doppler of scatterers off a beam's centre, which no beam-domain
#: compensation removes (about ``2 d delta / lambda`` for a displacement ``d``
#: and an offset ``delta`` within the beamwidth); the largest measured value is
#: the parking lot's RD map (0.13 nats, strong car roofs seen by neighbouring
#: beams). See docs/scenes.md.
ENTROPY_MARGIN_NATS = 0.15
#: Smallest RD-map entropy rise of the uncompensated hover over the stationary
#: platform that counts as a visible Doppler spread [nats].
MIN_HOVER_SPREAD_NATS = 0.05
#: Doppler bins either side of zero counted as the stationary clutter ridge
#: (the Hann mainlobe: bins -1, 0, +1).
RIDGE_HALF_WIDTH_BINS = 1
#: CFAR: training and guard cells along range, and threshold over the local mean [dB].
CFAR_TRAIN, CFAR_GUARD, CFAR_THRESHOLD_DB = 12, 3, 12.0
#: Half-width of the Doppler axis shown in the RD figures [Doppler bins].
RD_PLOT_HALF_WIDTH_BINS = 12
#: Detections kept per chain (strongest first).
MAX_DETECTIONS = 12


@dataclass(frozen=True)
class ReportSettings:
    """Radar, motion, tracing and processing settings of the scene report.

    Attributes
    ----------
    num_chirps : int
        Chirps per frame (slow-time length).
    idle_time : float
        Idle time between chirps [s]; the chirp interval is ``60 us + idle``.
        The defaults keep the frame duration of the paper's radar (256 x 60 us
        = 15.36 ms: 128 x 120 us, or 64 x 240 us with :data:`QUICK`), over
        which the hover jitter moves the radar by about 3 mm.
    array_size : int
        Virtual UPA of ``array_size x array_size`` half-wavelength elements.
    samples_per_src : int
        Rays shot by the tracer (about 8 % become ground paths).
    max_depth : int
        Bounces of scene-geometry paths.
    grid_half_width_deg, grid_step_deg : float
        Global azimuth/elevation grid ``-w..+w`` in steps of ``step`` [deg].
    range_window : (float, float)
        Processed range window [m] (all 600 samples are synthesised and range
        compressed; beams are formed on the gates inside the window only).
    lever_arm : tuple of float
        Radar phase centre in the body frame B [m].
    jitter_seed : int
        Seed of :func:`raysim.platform.motion.hover_jitter`.
    imu : str
        IMU preset (:data:`raysim.platform.imu.PRESETS`).
    imu_rate : float
        IMU output rate [Hz] (above 20x the 160 Hz vibration band).
    imu_seed : int
        Seed of the IMU error draws.
    trace_seed : int
        Seed of the ray sampling and diffuse phases.
    nufft_eps : float
        Relative error of the NUFFT IF synthesis.
    path_chunk : int
        Paths re-projected and synthesised at once.
    gate_block : int
        Range gates beamformed at once (bounds memory).
    spatial_window : str or None
        Amplitude taper over the virtual channels before beamforming, the same
        for every chain: ``"taylor"`` (30 dB, ``nbar = 4`` along x and y) or
        ``None`` (uniform, -13 dB sidelobes). Sidelobes see the platform
        motion from their own direction, which no beam-domain compensation
        removes, so low sidelobes matter for clutter.
    """

    num_chirps: int = 128
    idle_time: float = 60e-6
    array_size: int = 12
    samples_per_src: int = 100_000
    max_depth: int = 1
    grid_half_width_deg: float = 60.0
    grid_step_deg: float = 3.0
    range_window: tuple[float, float] = (12.0, 45.0)
    lever_arm: tuple[float, float, float] = (0.0, 0.0, 0.10)
    jitter_seed: int = 7
    imu: str = "ideal"
    imu_rate: float = 4000.0
    imu_seed: int = 1
    trace_seed: int = 42
    nufft_eps: float = 1e-5
    path_chunk: int = 1024
    gate_block: int = 16
    spatial_window: str | None = "taylor"

    def __post_init__(self) -> None:
        for name in ("num_chirps", "array_size", "samples_per_src", "max_depth", "path_chunk",
                     "gate_block"):
            v = getattr(self, name)
            if not isinstance(v, (int, np.integer)) or v < 1:
                raise ValueError(f"{name} must be a positive integer, got {v!r}")
        if self.num_chirps < 8:
            raise ValueError(f"num_chirps must be >= 8 for a Doppler map, got {self.num_chirps}")
        if not (math.isfinite(self.idle_time) and self.idle_time >= 0):
            raise ValueError(f"idle_time must be >= 0 s, got {self.idle_time!r}")
        if not 0 < self.grid_step_deg <= self.grid_half_width_deg <= 80:
            raise ValueError(f"need 0 < grid_step_deg <= grid_half_width_deg <= 80, got "
                             f"grid_step_deg={self.grid_step_deg!r}, "
                             f"grid_half_width_deg={self.grid_half_width_deg!r}")
        lo, hi = self.range_window
        if not 0 <= lo < hi:
            raise ValueError(f"range_window must satisfy 0 <= low < high [m], "
                             f"got {self.range_window!r}")
        if hi >= self.radar().max_range:
            raise ValueError(f"range_window upper edge {hi!r} m must be below the radar's "
                             f"max_range {self.radar().max_range:.1f} m")
        from raysim.platform.imu import get_preset

        get_preset(self.imu)
        if not self.imu_rate > 0:
            raise ValueError(f"imu_rate must be > 0 Hz, got {self.imu_rate!r}")
        if self.spatial_window not in ("taylor", None):
            raise ValueError(f"spatial_window must be 'taylor' or None, "
                             f"got {self.spatial_window!r}")
        if not 1e-7 <= self.nufft_eps < 1:
            raise ValueError(f"nufft_eps must lie in [1e-7, 1), got {self.nufft_eps!r}")

    def radar(self) -> RadarConfig:
        """Paper waveform (77 GHz, 1 GHz, 60 us, 10 MHz, 600 samples) with these chirps."""
        return RadarConfig(num_chirps=int(self.num_chirps), idle_time=float(self.idle_time))

    def array(self) -> VirtualArray:
        """Half-wavelength ``array_size x array_size`` virtual UPA (x major, y minor)."""
        return upa(self.array_size, self.array_size, wavelength=self.radar().wavelength)

    def channel_taper(self) -> np.ndarray:
        """Channel weights, shape ``[channel]`` (x index major, y minor), mean 1."""
        n = self.array_size
        if self.spatial_window is None:
            return np.ones(n * n)
        from scipy.signal.windows import taylor

        w = taylor(n, nbar=4, sll=30, norm=False)
        ww = np.outer(w, w).ravel()
        return ww / ww.mean()

    def grid(self) -> tuple[np.ndarray, np.ndarray]:
        """Azimuth and elevation axes of the global grid [rad]."""
        n = int(round(self.grid_half_width_deg / self.grid_step_deg))
        ax = np.deg2rad(np.arange(-n, n + 1) * self.grid_step_deg)
        return ax, ax.copy()


#: Settings of ``raysim scene-report`` (all scenes: 9.5 minutes on 2 busy cores, mostly
#: IF synthesis of 8,300 paths x 128 chirps x 144 channels x 600 samples).
FULL = ReportSettings()
#: Settings of ``raysim scene-report --quick`` and of the tests (15-30 s per scene).
QUICK = ReportSettings(num_chirps=64, idle_time=180e-6, array_size=8, samples_per_src=20_000,
                       grid_step_deg=6.0)


# ---------------------------------------------------------------------- results
@dataclass(frozen=True, eq=False)
class ChainResult:
    """Maps, entropies and detections of one chain.

    Attributes
    ----------
    chain : str
        One of :data:`CHAINS`.
    maps : dict
        ``"rd"`` (dims ``range, doppler``), ``"ra"`` (``range, azimuth``), ``"re"``
        (``azimuth, elevation``) -> :class:`raysim.processing.maps.Map` of beam power [W]
        (channel-averaged beams of IF amplitudes in sqrt(W)); axes in m, m/s, rad.
    cube : ndarray, shape ``[range, azimuth, elevation]``
        Coherent (zero-Doppler, Hann-weighted) beam power [W].
    entropy : dict
        Map name -> image entropy [nats].
    detections : list of dict
        CFAR detections, strongest first: ``range_m``, ``az_deg``, ``el_deg``,
        ``velocity_mps`` (range rate at the RD peak of the detection's gate),
        ``power_db`` (relative to the cube's maximum), ``position_m`` (in W).
    ridge_leakage_db : float
        RD power outside the zero-Doppler ridge relative to the total [dB].
    seconds : float
        Processing time of the chain [s].
    """

    chain: str
    maps: dict
    cube: np.ndarray
    entropy: dict
    detections: list
    ridge_leakage_db: float
    seconds: float


@dataclass(frozen=True, eq=False)
class SceneResult:
    """Everything the report shows for one scene.

    Attributes
    ----------
    scene : str
    settings : ReportSettings
    chains : dict
        Chain name -> :class:`ChainResult`.
    targets : list of dict
        Known reflectors: ``name``, ``position_m`` (W), ``range_m``, ``az_deg``,
        ``el_deg`` from the nominal radar phase centre, and per chain the
        nearest detection (``match``) with its position error.
    num_paths : int
        Traced paths (after culls).
    path_kinds : dict
        Path count per interaction kind (``specular``, ``diffuse``, ``target``).
    motion_rms : dict
        RMS of the radar phase-centre displacement [m] and attitude angles [deg]
        over the frame.
    seconds : dict
        Wall time of tracing, synthesis and each chain [s].
    """

    scene: str
    settings: ReportSettings
    chains: dict
    targets: list
    num_paths: int
    path_kinds: dict
    motion_rms: dict
    seconds: dict

    def entropy_table(self) -> dict:
        """``{chain: {map: entropy}}`` [nats]."""
        return {c: dict(r.entropy) for c, r in self.chains.items()}

    def to_dict(self) -> dict:
        """JSON-ready summary (no arrays)."""
        st = self.chains["stationary"].entropy
        return {
            "scene": self.scene,
            "settings": asdict(self.settings),
            "num_paths": self.num_paths,
            "path_kinds": self.path_kinds,
            "motion_rms": self.motion_rms,
            "entropy_nats": self.entropy_table(),
            "entropy_minus_stationary_nats": {
                c: {m: r.entropy[m] - st[m] for m in MAPS} for c, r in self.chains.items()},
            "entropy_margin_nats": ENTROPY_MARGIN_NATS,
            "exact_within_margin": bool(all(
                abs(self.chains["exact"].entropy[m] - st[m]) <= ENTROPY_MARGIN_NATS
                for m in MAPS)),
            "ridge_leakage_db": {c: r.ridge_leakage_db for c, r in self.chains.items()},
            "detections": {c: r.detections for c, r in self.chains.items()},
            "targets": self.targets,
            "seconds": self.seconds,
        }


# ------------------------------------------------------------------- simulation
def _path_kinds(paths) -> dict:
    from raysim.echoes.rt.trace import DIFFUSE, SENSING, SPECULAR

    k = paths.kind
    return {"specular": int(np.sum(k == SPECULAR)), "diffuse": int(np.sum((k & DIFFUSE) != 0)),
            "target": int(np.sum((k & SENSING) != 0)),
            "other_specular": int(np.sum(((k & SPECULAR) != 0) & (k != SPECULAR)
                                         & ((k & (DIFFUSE | SENSING)) == 0)))}


def hover_trajectory(seed: int, t0: float = 0.0):
    """Seeded hover jitter that starts at the nominal hover pose at ``t0``.

    :func:`raysim.platform.motion.hover_jitter` wanders centimetres and degrees away
    from the hover point; constant offsets (:class:`raysim.platform.motion.Ramp`)
    remove its pose at ``t0`` on all six axes, so the stationary and the
    hovering radar share the first chirp's pose and differ only by the motion
    within the frame (a static offset would shift the range profile by a
    fraction of a bin, which is no Doppler effect).

    Parameters
    ----------
    seed : int
        Seed of the jitter.
    t0 : float
        Time at which the pose is nominal [s].

    Returns
    -------
    raysim.platform.motion.Trajectory
    """
    from raysim.platform.motion import AXES, Ramp, Trajectory, hover_jitter

    jitter = hover_jitter(seed)
    q0 = jitter.states([t0])[0][0]
    return jitter + Trajectory(tuple(Ramp(a, offset=-float(v)) for a, v in zip(AXES, q0,
                                                                               strict=True)),
                               name="nominal pose at t0")


def platform_motion(trajectory, chirp_times: np.ndarray, settings: ReportSettings):
    """IMU samples along the trajectory, integrated to the pose at every chirp.

    Parameters
    ----------
    trajectory : raysim.platform.motion.Trajectory
    chirp_times : ndarray, shape ``[chirp]`` [s]
    settings : ReportSettings
        ``imu``, ``imu_rate``, ``imu_seed`` and ``lever_arm`` are used.

    Returns
    -------
    compensation.PlatformMotion
        Initial pose and velocity from the truth (flight controller), the rest
        integrated from the IMU.
    """
    from compensation import integrate_imu
    from raysim.platform.imu import simulate_imu

    t = np.asarray(chirp_times, dtype=float)
    margin = 4.0 / settings.imu_rate
    samples = simulate_imu(trajectory, settings.imu, rate=settings.imu_rate,
                           start=float(t[0]) - margin, end=float(t[-1]) + margin,
                           seed=settings.imu_seed)
    t0 = float(t[0])
    return integrate_imu(*samples.to_arrays(), t, lever_arm=np.asarray(settings.lever_arm),
                         reference_time=t0,
                         initial_attitude=trajectory.attitude([t0]).as_matrix()[0],
                         initial_position=trajectory.position([t0])[0], velocity="given",
                         initial_velocity=trajectory.velocity([t0])[0])


def simulate_scene(scene: str, settings: ReportSettings, trajectory, *, progress=None) -> dict:
    """Trace ``scene`` once at the nominal pose and synthesise both IF frames.

    Parameters
    ----------
    scene : str
        Registry name.
    settings : ReportSettings
    trajectory : raysim.platform.motion.Trajectory
        Hover motion of the moving platform.
    progress : callable, optional
        ``progress(message)`` after each step.

    Returns
    -------
    dict
        ``"stationary"``, ``"hover"``: IF cubes ``[chirp, channel, sample]``
        complex64 [sqrt(W)]; ``"paths"`` (:class:`raysim.echoes.rt.trace.PathSet`),
        ``"scene"`` (:class:`raysim.echoes.rt.scenes.RadarScene`), ``"seconds"``.
    """
    from raysim.echoes.rt.reproject import synthesize_paths
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.platform.motion import stationary
    from raysim.synthesis.nufft import synthesize_nufft

    config = settings.radar()
    array = settings.array()
    lever = np.asarray(settings.lever_arm, dtype=float)
    seconds = {}
    t = time.perf_counter()
    loaded = load_scene(scene, frequency=config.carrier_frequency)
    tracer = MonostaticTracer(max_depth=settings.max_depth,
                              samples_per_src=settings.samples_per_src, seed=settings.trace_seed)
    paths = tracer(loaded, config, stationary(), lever, time=float(config.chirp_times()[0]))
    seconds["trace"] = time.perf_counter() - t
    if progress:
        progress("traced")
    synth = functools.partial(synthesize_nufft, eps=settings.nufft_eps)
    out = {"paths": paths, "scene": loaded}
    for name, motion in (("stationary", stationary()), ("hover", trajectory)):
        t = time.perf_counter()
        out[name], _ = synthesize_paths(paths, config, array, motion, lever,
                                        path_chunk=settings.path_chunk, synthesizer=synth)
        seconds[f"synthesis_{name}"] = time.perf_counter() - t
        if progress:
            progress(f"synthesised {name}")
    out["seconds"] = seconds
    return out


# ------------------------------------------------------------------- processing
def _beam_blocks(chain: str, rc: np.ndarray, positions: np.ndarray, motion, config: RadarConfig,
                 range_axis: np.ndarray, gates: np.ndarray, az: np.ndarray, el: np.ndarray,
                 grid_shape, gate_block: int):
    """Yield ``(gate_indices, BeamCube)`` of one chain, block by block."""
    from compensation import beam_projection, paper_chain, range_change, rigid_body_projection
    from compensation.geometry import grid_directions

    lam = config.center_wavelength
    kw = dict(wavelength=lam, range_axis=range_axis, azimuth=az, elevation=el,
              grid_shape=grid_shape)
    corr = None
    if chain == "paper":
        u = np.asarray(grid_directions(az, el)).reshape(len(az), len(el), 3)
        dr = np.stack([np.stack([range_change(motion, u[i, j]) for j in range(len(el))], -1)
                       for i in range(len(az))], -2)                     # [chirp, az, el]
        corr = np.exp(-4j * np.pi * dr / lam).astype(np.complex64)[:, None]
    for g0 in range(0, gates.size, gate_block):
        sel = gates[g0:g0 + gate_block]
        if chain in ("stationary", "uncompensated"):
            bc = beam_projection(rc, positions, range_gates=sel, chirp_time=motion.time, **kw)
        elif chain == "exact":
            bc = rigid_body_projection(rc, positions, motion, range_gates=sel, **kw)
        else:
            bc = paper_chain(rc, positions, motion, steps=("tilt", "yaw"),
                             direction=(0.0, 0.0, 1.0), range_gates=sel, **kw)
            bc = replace(bc, data=bc.data * corr)
        yield sel, bc


def cfar_detect(cube: np.ndarray, *, train: int = CFAR_TRAIN, guard: int = CFAR_GUARD,
                threshold_db: float = CFAR_THRESHOLD_DB) -> np.ndarray:
    """Cell-averaging CFAR along range plus 3 x 3 x 3 local-maximum test.

    Parameters
    ----------
    cube : ndarray, shape ``[range, azimuth, elevation]``
        Non-negative power.
    train, guard : int
        Training and guard cells on each side along range.
    threshold_db : float
        Detection threshold over the mean of the training cells [dB].

    Returns
    -------
    ndarray of int, shape ``[detection, 3]``
        Indices ``(range, azimuth, elevation)``, strongest first.
    """
    from scipy.ndimage import maximum_filter, uniform_filter1d

    p = np.asarray(cube, dtype=float)
    if p.ndim != 3 or np.any(p < 0):
        raise ValueError(f"cube must be a non-negative [range, azimuth, elevation] array, got "
                         f"shape {p.shape}")
    if train < 1 or guard < 0:
        raise ValueError(f"need train >= 1 and guard >= 0, got train={train!r}, guard={guard!r}")
    big = uniform_filter1d(p, 2 * (train + guard) + 1, axis=0, mode="nearest") * (
        2 * (train + guard) + 1)
    small = uniform_filter1d(p, 2 * guard + 1, axis=0, mode="nearest") * (2 * guard + 1)
    noise = np.maximum((big - small) / (2 * train), np.finfo(float).tiny)
    hit = (p > noise * 10 ** (threshold_db / 10)) & (p == maximum_filter(p, size=3,
                                                                          mode="nearest"))
    idx = np.argwhere(hit)
    order = np.argsort(-p[hit])
    return idx[order]


def chain_result(chain: str, rc: np.ndarray, motion, settings: ReportSettings,
                 config: RadarConfig, array: VirtualArray) -> ChainResult:
    """Beams, maps, entropies and detections of one chain.

    Parameters
    ----------
    chain : str
        One of :data:`CHAINS`.
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube (Hann).
    motion : compensation.PlatformMotion
        Pose estimate at the chirps (a static one for ``"stationary"``).
    settings, config, array
        Report settings, waveform and virtual array.

    Returns
    -------
    ChainResult
    """
    if chain not in CHAINS:
        raise ValueError(f"chain must be one of {CHAINS}, got {chain!r}")
    t = time.perf_counter()
    n_range = rc.shape[-1]
    r_axis = config.range_axis(n_range)[:n_range]
    lo, hi = settings.range_window
    gates = np.nonzero((r_axis >= lo) & (r_axis <= hi))[0]
    az, el = settings.grid()
    positions = array.virtual_positions
    rd = np.zeros((gates.size, rc.shape[0]))
    cube = np.zeros((gates.size, az.size, el.size))
    rc_win = np.ascontiguousarray(rc[:, :, gates])               # the window only
    local = np.arange(gates.size)
    for k, bc in _beam_blocks(chain, rc_win, positions, motion, config, r_axis[gates], local,
                              az, el, array.grid_shape, settings.gate_block):
        spec = bc.doppler()                                  # [doppler, g, az, el]
        rd[k] = np.einsum("dgae->gd", np.abs(spec.astype(np.complex128)) ** 2)
        cube[k] = bc.coherent_power(window="hann")
    vel = config.velocity_axis(rc.shape[0])
    rng = r_axis[gates]
    maps = {
        "rd": Map(rd, MAP_DIMS["rd"], {"range": rng, "doppler": vel}),
        "ra": Map(cube.sum(axis=2), MAP_DIMS["ra"], {"range": rng, "azimuth": az}),
        "re": Map(cube.sum(axis=0), MAP_DIMS["re"], {"azimuth": az, "elevation": el}),
    }
    entropy = {m: image_entropy(maps[m].values) for m in MAPS}
    centre = rc.shape[0] // 2
    ridge = rd[:, centre - RIDGE_HALF_WIDTH_BINS: centre + RIDGE_HALF_WIDTH_BINS + 1].sum()
    leak = float(10 * np.log10(max(rd.sum() - ridge, 0.0) / rd.sum() + 1e-300))
    detections = []
    lever = np.asarray(settings.lever_arm, dtype=float)
    from raysim.echoes.oracle import direction

    for gi, ai, ei in cfar_detect(cube)[:MAX_DETECTIONS]:
        u = direction(az[ai], el[ei])
        d = int(np.argmax(rd[gi]))
        detections.append({
            "range_m": float(rng[gi]), "az_deg": float(np.rad2deg(az[ai])),
            "el_deg": float(np.rad2deg(el[ei])), "velocity_mps": float(vel[d]),
            "power_db": float(10 * np.log10(cube[gi, ai, ei] / cube.max())),
            "position_m": (lever + rng[gi] * u).tolist()})
    return ChainResult(chain, maps, cube, entropy, detections, leak, time.perf_counter() - t)


def _targets(scene, settings: ReportSettings) -> list:
    from raysim.echoes.oracle import az_el

    lever = np.asarray(settings.lever_arm, dtype=float)
    out = []
    for t in scene.targets:
        v = t.position - lever
        r = float(np.linalg.norm(v))
        a, e = az_el(v / r)
        out.append({"name": t.name, "position_m": t.position.tolist(), "range_m": r,
                    "az_deg": float(np.rad2deg(a)), "el_deg": float(np.rad2deg(e)),
                    "rcs_dbsm": float(t.rcs_dbsm)})
    return out


def _match(targets: list, chains: dict, settings: ReportSettings) -> None:
    """Attach the nearest detection of every chain to every known reflector."""
    beam = 2.0 / settings.array_size                  # ~ null-to-null half width [rad]
    for t in targets:
        t["match"] = {}
        p = np.asarray(t["position_m"])
        radius = max(1.0, t["range_m"] * beam / 2)
        for c, r in chains.items():
            if not r.detections:
                t["match"][c] = {"detected": False}
                continue
            d = [float(np.linalg.norm(np.asarray(x["position_m"]) - p)) for x in r.detections]
            i = int(np.argmin(d))
            t["match"][c] = {"detected": bool(d[i] <= radius), "error_m": d[i],
                             "radius_m": radius, "detection": i}


def evaluate_scene(scene: str, settings: ReportSettings = QUICK, *, progress: bool = True,
                   chains: Sequence[str] = CHAINS) -> SceneResult:
    """Simulate and process one scene for every chain.

    Parameters
    ----------
    scene : str
        Registry name (``flat_reflectors``, ``parking_lot``, ``rough_terrain``).
    settings : ReportSettings
    progress : bool
        Show a tqdm bar on stderr.
    chains : sequence of str
        Subset of :data:`CHAINS` (``"stationary"`` is always computed).

    Returns
    -------
    SceneResult
    """
    from compensation import static_motion
    from raysim.echoes.rt.scenes import SCENES

    if scene not in SCENES:
        raise ValueError(f"unknown scene {scene!r}; expected one of {sorted(SCENES)}")
    bad = [c for c in chains if c not in CHAINS]
    if bad:
        raise ValueError(f"unknown chain {bad[0]!r}; expected a subset of {CHAINS}")
    chains = ["stationary"] + [c for c in CHAINS if c in chains and c != "stationary"]
    from tqdm.auto import tqdm

    bar = tqdm(total=3 + len(chains), desc=scene, file=sys.stderr, disable=not progress,
               leave=False)
    trajectory = hover_trajectory(settings.jitter_seed, float(settings.radar().chirp_times()[0]))
    sim = simulate_scene(scene, settings, trajectory,
                         progress=lambda msg: (bar.set_postfix_str(msg), bar.update()))
    config, array = settings.radar(), settings.array()
    t_chirp = config.chirp_times()
    t = time.perf_counter()
    motion = platform_motion(trajectory, t_chirp, settings)
    seconds = dict(sim["seconds"], imu=time.perf_counter() - t)
    still = static_motion(t_chirp, lever_arm=settings.lever_arm)
    results = {}
    taper = settings.channel_taper().astype(np.float32)[None, :, None]
    rc = {k: range_compress(sim[k]) * taper for k in ("stationary", "hover")}
    for c in chains:
        bar.set_postfix_str(c)
        results[c] = chain_result(c, rc["stationary" if c == "stationary" else "hover"],
                                  still if c in ("stationary", "uncompensated") else motion,
                                  settings, config, array)
        seconds[c] = results[c].seconds
        bar.update()
    bar.close()
    targets = _targets(sim["scene"], settings)
    _match(targets, results, settings)
    lever = np.asarray(settings.lever_arm, dtype=float)
    truth_disp = trajectory.point_world(t_chirp, lever)[:, 0] - lever
    ypr = np.rad2deg(trajectory.euler(t_chirp))
    motion_rms = {"displacement_m": float(np.sqrt(np.mean(np.sum(truth_disp**2, axis=1)))),
                  "displacement_span_m": float(np.max(np.ptp(truth_disp, axis=0))),
                  "yaw_pitch_roll_deg": np.sqrt(np.mean(ypr**2, axis=0)).tolist(),
                  "velocity_mps": float(np.sqrt(np.mean(np.sum(
                      trajectory.velocity(t_chirp) ** 2, axis=1))))}
    return SceneResult(scene, settings, results, targets, sim["paths"].num_paths,
                       _path_kinds(sim["paths"]), motion_rms, seconds)


# --------------------------------------------------------------------- outputs
def _extent(m: Map):
    x = np.asarray(m.coords[m.dims[1]], dtype=float)
    y = np.asarray(m.coords[m.dims[0]], dtype=float)
    if m.dims[1] in ("azimuth", "elevation"):
        x = np.rad2deg(x)
    if m.dims[0] in ("azimuth", "elevation"):
        y = np.rad2deg(y)
    return [x[0], x[-1], y[0], y[-1]]


_LABELS = {"range": "range [m]", "doppler": "range rate [m/s]", "azimuth": "azimuth [deg]",
           "elevation": "elevation [deg]"}
_TITLES = {"rd": "range-Doppler", "ra": "range-azimuth", "re": "azimuth-elevation"}


def plot_scene(result: SceneResult, folder: str | os.PathLike, *,
               dynamic_range_db: float = 50.0) -> list[Path]:
    """One PNG per map type (``<scene>_{rd,ra,re}.png``), one panel per chain.

    Panels share the colour scale (dB relative to the stationary map's peak).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    for m in MAPS:
        ref = float(result.chains["stationary"].maps[m].values.max())
        fig, axes = plt.subplots(1, len(result.chains), figsize=(4.2 * len(result.chains), 4.0),
                                 constrained_layout=True)
        axes = np.atleast_1d(axes)
        im = None
        for ax, (c, r) in zip(axes, result.chains.items(), strict=True):
            mp = r.maps[m]
            db = 10 * np.log10(np.maximum(mp.values / ref, 1e-30))
            im = ax.imshow(db, origin="lower", aspect="auto", extent=_extent(mp),
                           vmin=-dynamic_range_db, vmax=0.0, cmap="viridis",
                           interpolation="nearest")
            ax.set_xlabel(_LABELS[mp.dims[1]])
            ax.set_ylabel(_LABELS[mp.dims[0]])
            ax.set_title(f"{c}\nH = {r.entropy[m]:.3f} nats", fontsize=10)
            if m == "rd":                                   # zoom on the clutter ridge
                dv = np.abs(np.diff(mp.coords["doppler"][:2]))[0]
                ax.set_xlim(-RD_PLOT_HALF_WIDTH_BINS * dv, RD_PLOT_HALF_WIDTH_BINS * dv)
            if m == "re":
                for t in result.targets:
                    ax.plot(t["el_deg"], t["az_deg"], "r+", ms=9)
            elif m == "ra":
                for t in result.targets:
                    ax.plot(t["az_deg"], t["range_m"], "r+", ms=9)
        fig.colorbar(im, ax=list(axes), label="power [dB re stationary peak]", shrink=0.9)
        fig.suptitle(f"{result.scene}: {_TITLES[m]} map")
        out = Path(folder) / f"{result.scene}_{m}.png"
        atomic_write(out, lambda p, fig=fig: fig.savefig(p, dpi=90, format="png"))
        plt.close(fig)
        paths.append(out)
    return paths


def _markdown(results: dict, settings: ReportSettings) -> str:
    lines = ["# Scene entropy report", "",
             f"Radar: {settings.num_chirps} chirps x "
             f"{settings.radar().chirp_interval * 1e6:.0f} us, "
             f"{settings.array_size}x{settings.array_size} UPA, 600 samples (range window "
             f"{settings.range_window[0]:g}-{settings.range_window[1]:g} m), grid "
             f"+-{settings.grid_half_width_deg:g} deg step {settings.grid_step_deg:g} deg, "
             f"hover jitter seed {settings.jitter_seed}, IMU `{settings.imu}`.", "",
             f"Entropy margin of the exact chain: {ENTROPY_MARGIN_NATS} nats.", "",
             "| scene | map | " + " | ".join(CHAINS) + " | exact - stationary |",
             "|---|---|" + "---|" * (len(CHAINS) + 1)]
    for s, r in results.items():
        e = r.entropy_table()
        for m in MAPS:
            cells = " | ".join(f"{e[c][m]:.4f}" if c in e else "-" for c in CHAINS)
            diff = e["exact"][m] - e["stationary"][m] if "exact" in e else float("nan")
            lines.append(f"| {s} | {m.upper()} | {cells} | {diff:+.4f} |")
    lines += ["", "Zero-Doppler ridge: RD power outside Doppler bins -1..+1 [dB]", "",
              "| scene | " + " | ".join(CHAINS) + " |", "|---|" + "---|" * len(CHAINS)]
    for s, r in results.items():
        lines.append(f"| {s} | " + " | ".join(
            f"{r.chains[c].ridge_leakage_db:.1f}" if c in r.chains else "-" for c in CHAINS)
            + " |")
    lines += ["", "Known reflectors: position error of the nearest detection [m] "
              "(* = outside the match radius)", "",
              "| scene | target | range [m] | az [deg] | el [deg] | "
              + " | ".join(CHAINS) + " |", "|---|---|---|---|---|" + "---|" * len(CHAINS)]
    for s, r in results.items():
        for t in r.targets:
            cells = []
            for c in CHAINS:
                mt = t.get("match", {}).get(c)
                if mt is None or "error_m" not in mt:
                    cells.append("-")
                else:
                    cells.append(f"{mt['error_m']:.2f}" + ("" if mt["detected"] else "*"))
            lines.append(f"| {s} | {t['name']} | {t['range_m']:.2f} | {t['az_deg']:.1f} | "
                         f"{t['el_deg']:.1f} | " + " | ".join(cells) + " |")
    lines.append("")
    for s in results:
        lines.append(f"## {s}")
        lines += [f"![{s} {m}]({s}_{m}.png)" for m in MAPS]
        lines.append("")
    return "\n".join(lines)


def _html(markdown: str) -> str:
    """A small self-contained HTML rendering of the report's markdown (tables, images)."""
    body = []
    rows: list[str] = []

    def flush():
        if rows:
            body.append("<table>" + "".join(rows) + "</table>")
            rows.clear()

    for line in markdown.splitlines():
        if line.startswith("|"):
            cells = [c.strip() for c in line.strip("|").split("|")]
            if all(set(c) <= {"-"} for c in cells):
                continue
            tag = "th" if not rows else "td"
            rows.append("<tr>" + "".join(f"<{tag}>{html.escape(c)}</{tag}>" for c in cells)
                        + "</tr>")
            continue
        flush()
        if line.startswith("# "):
            body.append(f"<h1>{html.escape(line[2:])}</h1>")
        elif line.startswith("## "):
            body.append(f"<h2>{html.escape(line[3:])}</h2>")
        elif line.startswith("!["):
            alt, src = line[2:].split("](")
            body.append(f'<img src="{html.escape(src[:-1])}" alt="{html.escape(alt)}" '
                        f'style="max-width:100%">')
        elif line:
            body.append(f"<p>{html.escape(line)}</p>")
    flush()
    return ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>Scene entropy report"
            "</title><style>body{font-family:sans-serif;margin:2em}table{border-collapse:"
            "collapse;margin:1em 0}td,th{border:1px solid #999;padding:2px 6px;text-align:"
            "right}</style></head><body>" + "\n".join(body) + "</body></html>\n")


def write_scene_report(out_dir: str | os.PathLike, *, scenes: Sequence[str] | None = None,
                       settings: ReportSettings = FULL, progress: bool = True) -> dict:
    """Evaluate scenes; write figures, JSON, ``report.md`` and ``index.html``.

    Every file is written atomically (temporary file, then ``os.replace``).

    Parameters
    ----------
    out_dir : path-like
        Output folder (created).
    scenes : sequence of str, optional
        Registry names; default all bundled scenes.
    settings : ReportSettings
        :data:`FULL` or :data:`QUICK` or custom.
    progress : bool
        tqdm progress on stderr.

    Returns
    -------
    dict
        ``{scene: SceneResult.to_dict()}``.
    """
    from raysim.echoes.rt.scenes import SCENES

    scenes = list(SCENES) if scenes is None else list(scenes)
    bad = [s for s in scenes if s not in SCENES]
    if bad:
        raise ValueError(f"unknown scene {bad[0]!r}; expected one of {sorted(SCENES)}")
    if not scenes:
        raise ValueError("scenes is empty")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    results, summary = {}, {}
    for s in scenes:
        r = evaluate_scene(s, settings, progress=progress)
        results[s] = r
        summary[s] = r.to_dict()
        plot_scene(r, out)
        atomic_write(out / f"{s}.json",
                     lambda p, d=summary[s]: p.write_text(json.dumps(d, indent=1)))
    atomic_write(out / "summary.json", lambda p: p.write_text(json.dumps(summary, indent=1)))
    md = _markdown(results, settings)
    atomic_write(out / "report.md", lambda p: p.write_text(md))
    atomic_write(out / "index.html", lambda p: p.write_text(_html(md)))
    return summary


# -------------------------------------------------------------------- benchmark
def bench_reprojection(scene: str = "rough_terrain", *, num_chirps: int = 16,
                       array_size: int = 8, samples_per_src: int = 100_000,
                       repeat: int = 3) -> dict:
    """Wall time of re-projection per chirp vs re-tracing per chirp (CPU).

    Both produce the delays of the scene's paths for one chirp of a hovering
    platform. Re-tracing runs :class:`raysim.echoes.rt.trace.MonostaticTracer` from
    the chirp's pose (only the phase centre; per-channel delays would need one
    trace per channel). Re-projection runs
    :func:`raysim.echoes.rt.reproject.path_lengths` for the same chirp, either for
    the phase centre only (same output as one trace) or for every channel.

    Parameters
    ----------
    scene : str
        Registry name.
    num_chirps : int
        Chirps timed (each traced once).
    array_size : int
        Virtual UPA size for the per-channel re-projection.
    samples_per_src : int
        Rays per trace.
    repeat : int
        Repetitions of the re-projection timing (best is kept).

    Returns
    -------
    dict
        ``trace_s_per_chirp``, ``reproject_s_per_chirp`` (phase centre),
        ``reproject_all_channels_s_per_chirp``, ``ratio`` (trace / re-projection,
        phase centre), ``ratio_all_channels`` (``channels`` traces / one
        per-channel re-projection), ``num_paths``, ``channels`` and the settings.
    """
    from raysim.echoes.rt.reproject import element_positions, path_lengths
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.platform.motion import hover_jitter

    for name, v in (("num_chirps", num_chirps), ("array_size", array_size),
                    ("samples_per_src", samples_per_src), ("repeat", repeat)):
        if not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name} must be a positive integer, got {v!r}")
    config = RadarConfig(num_chirps=num_chirps, idle_time=440e-6)
    lever = np.array([0.0, 0.0, 0.1])
    motion = hover_jitter(7)
    loaded = load_scene(scene, frequency=config.carrier_frequency)
    tracer = MonostaticTracer(samples_per_src=samples_per_src)
    paths = tracer(loaded, config, motion, lever, time=0.0)            # warm-up and frozen set
    times = config.chirp_times()
    t = time.perf_counter()
    for tn in times:
        tracer(loaded, config, motion, lever, time=float(tn))
    trace_s = (time.perf_counter() - t) / num_chirps
    centre = upa(1, 1, spacing=1e-3)
    full = upa(array_size, array_size, wavelength=config.wavelength)

    def per_chirp(array):
        geo = element_positions(config, array, motion, lever)
        best = math.inf
        for _ in range(repeat):
            t = time.perf_counter()
            for n in range(num_chirps):
                path_lengths(paths, geo[0][n:n + 1], geo[1][n:n + 1], geo[2][n:n + 1])
            best = min(best, (time.perf_counter() - t) / num_chirps)
        return best

    rep_c = per_chirp(centre)
    rep_a = per_chirp(full)
    m = full.num_channels
    return {"scene": scene, "num_paths": paths.num_paths, "num_chirps": num_chirps,
            "samples_per_src": samples_per_src, "channels": m,
            "trace_s_per_chirp": trace_s, "reproject_s_per_chirp": rep_c,
            "reproject_all_channels_s_per_chirp": rep_a,
            "ratio": trace_s / rep_c, "ratio_all_channels": m * trace_s / rep_a}


def _main_bench() -> None:  # pragma: no cover - used by ``python -m raysim.studies.scene_report``
    from raysim.echoes.rt import backend

    backend.configure("cpu", threads=int(os.environ.get("RAYSIM_RT_THREADS", "2")))
    print(json.dumps(bench_reprojection(), indent=1))


if __name__ == "__main__":  # pragma: no cover
    _main_bench()
