"""Random multipath path sets shared by the synthesis tests."""

from __future__ import annotations

import numpy as np

from raysim.echoes.oracle import direction
from raysim.synthesis.paths import PathDelays


def random_paths(cfg, array, rng, n, *, trajectory=None, near=0.3, per_chirp=True,
                 velocity=False) -> PathDelays:
    """Random multipath geometry as a :class:`PathDelays`.

    Near field (from ``near`` m) to 0.45 of the maximum range, wide angles, half of
    the paths double bounces with an interior length; a quarter move at about 2 m/s:
    as per-chirp vertices (``per_chirp``), as scatterer velocities (``velocity``) or
    not at all (neither).
    """
    rmax = 0.45 * cfg.max_range
    r = np.exp(rng.uniform(np.log(near), np.log(rmax), n))
    first = r[:, None] * direction(rng.uniform(-1.45, 1.45, n), rng.uniform(-1.45, 1.45, n))
    bounce = rng.random(n) < 0.5
    last = np.where(bounce[:, None], rng.uniform(0.2, 1.0, n)[:, None]
                    * direction(rng.uniform(-1.4, 1.4, n), rng.uniform(-1.4, 1.4, n)) * r[:, None],
                    first)
    length = np.where(bounce, rng.uniform(0.0, 0.3, n) * rmax, 0.0)
    moving = rng.random(n) < 0.25
    v = rng.normal(0, 2.0, (n, 3)) * moving[:, None]
    amp = (rng.normal(size=n) + 1j * rng.normal(size=n)) * np.exp(rng.uniform(-2, 2, n))
    if velocity:
        return PathDelays.for_array(first, last, length, amp, cfg, array, trajectory,
                                    velocity=v, reference_time=2e-5)
    if per_chirp:
        first = first[:, None, :] + v[:, None, :] * cfg.chirp_times()[None, :, None]
    return PathDelays.for_array(first, last, length, amp, cfg, array, trajectory)
