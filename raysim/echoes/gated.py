"""Range-gated echo source: the oracle's range-compressed samples at one range gate, in closed form.

The slow-time and angle physics of a point target need only its range gate.
:func:`gated_cube` evaluates the Hann-windowed range FFT of the exact
stop-and-hop IF tones of :func:`raysim.echoes.oracle.point_target_delays` at
one range bin in closed form (a sum of three Dirichlet kernels), so a frame
costs ``[chirp, channel]`` work instead of ``[chirp, channel, sample]``. It
equals ``range_compress(simulate_point_targets(...).data)[:, :, bin]`` to the
float32 rounding of the synthesis (tests/test_stability.py).
"""

from __future__ import annotations

import numpy as np

from raysim.echoes.oracle import point_target_delays
from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig

__all__ = ["gated_cube", "nearest_range_bin"]


def _dirichlet(nu: np.ndarray, k: int) -> np.ndarray:
    """``sum_{k'<k} exp(j 2 pi nu k')`` in closed form (``k`` at ``nu`` integer)."""
    nu = nu - np.round(nu)                       # the sum has period 1 in nu
    s = np.sin(np.pi * nu)
    small = np.abs(s) < 1e-12
    ratio = np.where(small, float(k), np.sin(np.pi * nu * k) / np.where(small, 1.0, s))
    return np.exp(1j * np.pi * nu * (k - 1)) * ratio


def nearest_range_bin(config: RadarConfig, range_m: float) -> int:
    """Index of the unpadded range-FFT bin nearest ``range_m`` [m]."""
    return int(np.argmin(np.abs(config.range_axis(config.num_samples) - range_m)))


def gated_cube(config: RadarConfig, array: VirtualArray, trajectory, targets, *, range_bin: int,
               lever_arm=(0.0, 0.0, 0.0), t0: float = 0.0,
               window_name: str = "hann", pattern=None) -> np.ndarray:
    """Range-compressed samples of one range gate of static or moving point targets.

    Parameters
    ----------
    config : RadarConfig
        Waveform (``complex_sampling`` must be True); one frame starting at ``t0``.
    array : VirtualArray
    trajectory : raysim.platform.motion.Trajectory
        Truth body motion.
    targets : sequence of raysim.echoes.oracle.PointTarget
    range_bin : int
        Bin of the unpadded range FFT (``0 <= range_bin < num_samples``).
    lever_arm : array_like, shape ``[3]``
        Radar phase centre in B [m].
    t0 : float
        Radar time of the first chirp [s].
    window_name : {"hann"}
        Fast-time window of the range FFT, normalised by its sum as in
        :func:`raysim.processing.maps.range_compress`.
    pattern : raysim.radar.pattern.ElementPattern, optional
        Element pattern (e.g. ``config.pattern``), applied at each chirp's pose
        as in :func:`raysim.echoes.oracle.point_target_delays`; default the
        constant gain ``config.antenna_gain_dbi``.

    Returns
    -------
    ndarray, shape ``[chirp, channel]``, complex128
        ``range_compress(IF)[:, :, range_bin]`` [sqrt(W)], summed over the targets.

    Notes
    -----
    A stop-and-hop tone ``a exp(j (phi0 + 2 pi f_b k / f_s))`` windowed by the
    periodic Hann window ``w_k = 1/2 - 1/4 (e^{j2pi k/K} + e^{-j2pi k/K})`` has
    at FFT bin ``m``, with ``nu = f_b / f_s - m / K`` and the Dirichlet sum
    ``D(nu) = sum_k e^{j 2 pi nu k}``::

        X_m = a e^{j phi0} [D(nu)/2 - D(nu + 1/K)/4 - D(nu - 1/K)/4] / (K/2)
    """
    if window_name != "hann":
        raise ValueError(f"window_name must be 'hann', got {window_name!r}")
    if not config.complex_sampling:
        raise ValueError("gated_cube needs complex_sampling=True, got a real-sampled config")
    k = config.num_samples
    if not isinstance(range_bin, (int, np.integer)) or not 0 <= range_bin < k:
        raise ValueError(f"range_bin: got {range_bin!r}, expected an integer in [0, {k})")
    tau, amp = point_target_delays(config, array, trajectory, targets, lever_arm=lever_arm, t0=t0,
                                   pattern=pattern)
    fb = config.chirp_rate * tau                                  # [target, chirp, channel]
    phi0 = 2 * np.pi * (config.carrier_frequency * tau - 0.5 * config.chirp_rate * tau * tau)
    nu = fb / config.sample_rate - range_bin / k
    g = (0.5 * _dirichlet(nu, k) - 0.25 * _dirichlet(nu + 1.0 / k, k)
         - 0.25 * _dirichlet(nu - 1.0 / k, k)) / (k / 2.0)
    return np.sum(amp * np.exp(1j * phi0) * g, axis=0)
