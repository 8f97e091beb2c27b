"""Settings and limits of the scene report (radar, motion, tracing, processing)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from raysim.platform.motion import AXES
from raysim.radar.arrays import VirtualArray, upa
from raysim.radar.config import RadarConfig

__all__ = ["REPORT_MAPS", "ENTROPY_MARGIN_NATS",
           "RIDGE_HALF_WIDTH_BINS", "CFAR_TRAIN", "CFAR_GUARD", "CFAR_THRESHOLD_DB",
           "RD_PLOT_HALF_WIDTH_BINS", "MAX_DETECTIONS",
           "MOVER_START_NE", "MAX_MOVER_SPEED", "REPORT_CLUTTER", "ReportSettings", "FULL", "QUICK"]

#: The maps of every chain and of the reference, names from
#: :data:`raysim.vocabulary.MAPS`: ``rd`` (range, doppler), ``ra`` (range,
#: azimuth), ``ae`` (azimuth, elevation).
REPORT_MAPS = ("rd", "ra", "ae")
#: Largest ``|H_exact - H_stationary|`` (exact chain against the stationary
#: reference, :data:`raysim.vocabulary.REFERENCE`) of every map of every bundled scene with
#: the ideal IMU [nats] (checked by ``tests/rt/test_scene_report.py``). Set by
#: the residual Doppler of scatterers off a beam's centre, which no beam-domain
#: compensation removes (about ``2 d delta / lambda`` for a displacement ``d``
#: and an offset ``delta`` within the beamwidth). The persistent clutter field fills
#: every cell near nadir, where the hover's horizontal displacement (2.5 mm) changes
#: the relative phase of scatterers within one beam by up to about 1 rad
#: (``4 pi d du / lambda`` across a 14-degree beam): their speckle changes over the
#: frame, which no beam-domain compensation undoes (the parking lot's RD map stays
#: 0.23 nats off, QUICK, although its off-ridge power falls from -13.5 to -24 dB; the
#: report flags it). The margin holds, and is tested, for the jitter without horizontal
#: displacement (``jitter_axes=("z", "roll", "pitch", "yaw")``). See docs/scenes.md.
ENTROPY_MARGIN_NATS = 0.15
#: Doppler bins either side of zero counted as the stationary clutter ridge
#: (the Hann mainlobe: bins -1, 0, +1).
RIDGE_HALF_WIDTH_BINS = 1
#: CFAR: training and guard cells along range, and threshold over the local mean [dB].
CFAR_TRAIN, CFAR_GUARD, CFAR_THRESHOLD_DB = 12, 3, 12.0
#: Half-width of the Doppler axis shown in the RD figures [Doppler bins].
RD_PLOT_HALF_WIDTH_BINS = 12
#: Detections kept per chain (strongest first).
MAX_DETECTIONS = 12
#: Start of the report's mover on the ground, north and east of the nadir point [m]: the
#: parking lot's lane between its two rows of cars (rows at 6 m south and 4 m north).
MOVER_START_NE = (-1.0, 6.0)
#: Largest mover speed of the report [m/s] (a car in a car park or a street).
MAX_MOVER_SPEED = 40.0
#: Ground clutter models of the report (values of ``render_scene(clutter=...)``).
REPORT_CLUTTER = ("field", "sionna")


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
    jitter_axes : tuple of str
        Axes of :data:`raysim.platform.motion.AXES` the hover jitter moves (default
        all six; e.g. ``("z", "roll", "pitch", "yaw")`` keeps the radar's
        horizontal position, to separate what compensation can undo).
    imu : str
        IMU preset (:data:`raysim.platform.imu.PRESETS`).
    imu_rate : float
        IMU output rate [Hz] (above 20x the 160 Hz vibration band).
    imu_seed : int
        Seed of the IMU error draws.
    trace_seed : int
        Seed of the ray sampling and diffuse phases.
    nufft_eps : float
        Relative error of the IF synthesis (NUFFT, or the fused kernel where the
        paths go the compact way).
    path_chunk : int
        Paths re-projected and synthesised at once.
    gate_block : int
        Range gates beamformed at once (bounds memory).
    clutter : {"field", "sionna"}
        Ground clutter and multipath: the persistent clutter field
        (:mod:`raysim.echoes.clutter`: seeded scatterers with calibrated sigma0,
        rough-surface specular, target-ground ghosts), or Sionna's own diffuse
        paths and mirror (the values of ``render_scene(clutter=...)``).
    clutter_per_cell : float
        Scatterers of the field per range x angle cell where the two-way
        element pattern is within ``FULL_DENSITY_DB`` of its peak (10 gives
        Rayleigh cells).
    mover_speed : float or None
        Ground speed [m/s] of a car (:class:`raysim.echoes.clutter.movers.CarMover`)
        driving east along :data:`MOVER_START_NE` through the scene in both
        frames, or None for no mover.
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
    jitter_axes: tuple[str, ...] = AXES
    imu: str = "ideal"
    imu_rate: float = 4000.0
    imu_seed: int = 1
    trace_seed: int = 42
    nufft_eps: float = 1e-5
    path_chunk: int = 1024
    gate_block: int = 16
    spatial_window: str | None = "taylor"
    clutter: str = "field"
    clutter_per_cell: float = 10.0
    mover_speed: float | None = None

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
        axes = self.jitter_axes
        if not (isinstance(axes, tuple) and axes and all(a in AXES for a in axes)
                and len(set(axes)) == len(axes)):
            raise ValueError(f"jitter_axes must be a tuple of distinct names from {AXES}, "
                             f"got {axes!r}")
        if self.clutter not in REPORT_CLUTTER:
            raise ValueError(f"clutter must be one of {REPORT_CLUTTER}, got {self.clutter!r}")
        if not (isinstance(self.clutter_per_cell, (int, float)) and not isinstance(
                self.clutter_per_cell, bool) and math.isfinite(self.clutter_per_cell)
                and 0 < self.clutter_per_cell <= 1000):
            raise ValueError(f"clutter_per_cell must be in (0, 1000] scatterers per cell, "
                             f"got {self.clutter_per_cell!r}")
        if self.mover_speed is not None and not (
                math.isfinite(self.mover_speed) and 0 < self.mover_speed <= MAX_MOVER_SPEED):
            raise ValueError(f"mover_speed must be None or in (0, {MAX_MOVER_SPEED}] m/s, "
                             f"got {self.mover_speed!r}")
        if not 1e-7 <= self.nufft_eps < 1:
            raise ValueError(f"nufft_eps must lie in [1e-7, 1), got {self.nufft_eps!r}")

    def radar(self) -> RadarConfig:
        """Paper waveform (77 GHz, 1 GHz, 60 us, 10 MHz, 600 samples) with these chirps.

        The radar's default element pattern (:mod:`raysim.radar.pattern`, the
        patch element) weights every path by its two-way gain.
        """
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
