"""Benchmark workloads shared by the benchmarks and the speed-versus-accuracy chart.

The paper radar with a hover-jitter trajectory (:func:`paper_setup`) and
synthetic ray paths of a drone hovering over flat ground (:func:`hover_paths`).
"""

from __future__ import annotations

import numpy as np

from raysim.radar.arrays import upa
from raysim.radar.config import PAPER_RADAR, RadarConfig
from raysim.synthesis.nufft import PathDelays

__all__ = ["HOVER_ALTITUDE", "paper_setup", "hover_paths", "subset"]

#: Hover altitude of the synthetic multipath scene [m].
HOVER_ALTITUDE = 20.0


def paper_setup(num_chirps: int = 256):
    """Paper radar (Table 2), 20 x 20 virtual UPA, hover-jitter trajectory, lever arm."""
    from raysim.platform.motion import sinusoid
    from raysim.scenario.paper_cases import DEFAULT_LEVER_ARM

    cfg = PAPER_RADAR.with_(num_chirps=int(num_chirps))
    arr = upa(20, 20, wavelength=cfg.wavelength)
    traj = (sinusoid("pitch", np.deg2rad(2.0), 7.0) + sinusoid("x", 0.005, 3.0)
            + sinusoid("yaw", np.deg2rad(1.0), 2.0))
    return cfg, arr, traj, DEFAULT_LEVER_ARM


def hover_paths(num_paths: int, config: RadarConfig, array, trajectory, lever_arm, *,
                seed: int = 0, frame: int = 0) -> PathDelays:
    """Synthetic ray paths of a drone hovering over flat ground, as a PathDelays.

    Scattering points lie on the ground ``HOVER_ALTITUDE`` m below (NED +z),
    up to 70 deg off nadir and inside the unambiguous range; a third of the
    paths are double bounces (a second point and the leg between them); 5 %
    move (walking-speed clutter). Amplitudes fall as ``1 / range^2`` with
    random phases.
    """
    rng = np.random.default_rng(seed)
    n = int(num_paths)
    rmax = 0.95 * config.max_range
    off = np.deg2rad(rng.uniform(0.0, 70.0, n))
    azi = rng.uniform(-np.pi, np.pi, n)
    ground = HOVER_ALTITUDE * np.tan(off)
    first = np.stack([ground * np.cos(azi), ground * np.sin(azi),
                      np.full(n, HOVER_ALTITUDE)], axis=1)
    double = rng.random(n) < 1 / 3
    hop = rng.normal(0.0, 5.0, (n, 3)) * [1, 1, 0]
    last = np.where(double[:, None], first + hop, first)
    interior = np.where(double, np.linalg.norm(hop, axis=1), 0.0)
    total = np.linalg.norm(first, axis=1) + interior + np.linalg.norm(last, axis=1)
    shrink = np.minimum(1.0, 2 * rmax / total)[:, None]         # keep inside the IF band
    first, last, interior = first * shrink, last * shrink, interior * shrink[:, 0]
    moving = rng.random(n) < 0.05
    vel = rng.normal(0.0, 1.0, (n, 3)) * moving[:, None]
    r = 0.5 * np.linalg.norm(first, axis=1) + 0.5 * np.linalg.norm(last, axis=1)
    amp = 1e-3 / r**2 * np.exp(2j * np.pi * rng.random(n))
    return PathDelays.for_array(first, last, interior, amp, config, array, trajectory,
                                lever_arm=lever_arm, frame=frame, velocity=vel)


def subset(paths: PathDelays, num_chirps: int, num_channels: int) -> PathDelays:
    """The first ``num_chirps`` chirps and ``num_channels`` channels of a PathDelays."""
    def cut(v):
        return v if v.ndim < 3 else v[:, :num_chirps]

    length = paths.interior_length if paths.interior_length.ndim == 1 \
        else paths.interior_length[:, :num_chirps]
    amp = paths.amplitude if paths.amplitude.ndim == 1 else paths.amplitude[:, :num_chirps]
    rx = None if paths.rx_positions is None else paths.rx_positions[:num_chirps, :num_channels]
    times = None if paths.element_times is None \
        else paths.element_times[:num_chirps, :num_channels]
    return PathDelays(cut(paths.first_vertex), cut(paths.last_vertex), length, amp,
                      paths.tx_positions[:num_chirps, :num_channels], rx, paths.velocity,
                      times, paths.reference_time)


