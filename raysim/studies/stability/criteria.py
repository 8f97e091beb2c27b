"""Failure criteria of the stability maps: one Doppler velocity bin, half a beamwidth."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig

__all__ = ["Criteria", "criteria_for", "fails"]


@dataclass(frozen=True)
class Criteria:
    """Failure thresholds of a configuration.

    Attributes
    ----------
    velocity_bin : float
        Doppler velocity bin ``lambda_c / (2 N T_rep)`` [m/s].
    doppler_bin_hz : float
        Doppler bin ``1 / (N T_rep)`` [Hz].
    half_beamwidth_deg : float
        Half of the 3 dB beamwidth at broadside [deg].
    """

    velocity_bin: float
    doppler_bin_hz: float
    half_beamwidth_deg: float


def criteria_for(config: RadarConfig, array: VirtualArray) -> Criteria:
    """Thresholds of :class:`Criteria` for a radar and a UPA.

    The 3 dB beamwidth of a uniform aperture of length ``L = n d`` is
    ``0.886 lambda / L`` rad at broadside; the smaller of the two UPA axes'
    beamwidths is used (largest aperture).
    """
    p = array.virtual_positions
    nx, ny = array.grid_shape
    lam = config.center_wavelength
    # p_virt spacing d_v corresponds to a one-way phase k u.p_virt: aperture n * d_v
    spans = []
    for axis, n in ((0, nx), (1, ny)):
        coords = np.unique(np.round(p[:, axis], 12))
        if n > 1:
            spans.append(n * float(np.min(np.diff(coords))))
    aperture = max(spans) if spans else lam / 2.0
    half_bw = 0.5 * np.rad2deg(0.886 * lam / aperture)
    return Criteria(config.velocity_resolution, config.doppler_resolution, float(half_bw))


def fails(metrics: dict, criteria: Criteria) -> bool:
    """True when a metrics record breaks a criterion of :class:`Criteria`.

    Parameters
    ----------
    metrics : dict
        Needs ``pseudo_velocity_mps`` [m/s] and ``angle_error_worst_deg`` [deg]
        (names of :data:`raysim.vocabulary.METRICS`).
    """
    for name in ("pseudo_velocity_mps", "angle_error_worst_deg"):
        if name not in metrics:
            raise ValueError(f"metrics: got keys {sorted(metrics)}, expected {name!r}")
    return bool(abs(metrics["pseudo_velocity_mps"]) > criteria.velocity_bin
                or metrics["angle_error_worst_deg"] > criteria.half_beamwidth_deg)
