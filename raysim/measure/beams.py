"""Metrics of a compensated beam cube (what the compensate stage writes), each defined once.

The cube of one frame is ``[chirp, range, azimuth]`` at one elevation (the
beams of :func:`raysim.pipeline.compensate.compensate`). At the peak of its
zero-Doppler map (the beams summed coherently over the chirps):

``beam_angle_error_deg``
    ``|az - az_true|``: azimuth of that peak (parabola on dB over the
    azimuth grid) against the true direction [deg];
``beam_pseudo_velocity_bins``
    pseudo-velocity (:func:`raysim.processing.metrics.pseudo_velocity`) of the
    slow-time signal of the peak cell, in Doppler velocity bins;
``doppler_leakage_db``
    power of that signal's Hann-windowed Doppler spectrum (no zero padding)
    outside the peak bin and its two neighbours, over the total [dB].
"""

from __future__ import annotations

import numpy as np

from raysim.processing.metrics import parabolic_offset, pseudo_velocity

__all__ = ["BEAM_METRICS", "beam_metrics", "zero_doppler_peak"]

#: Metrics of :func:`beam_metrics`, in order (names of :data:`raysim.vocabulary.METRICS`).
BEAM_METRICS = ("beam_angle_error_deg", "beam_pseudo_velocity_bins", "doppler_leakage_db")


def beam_metrics(beams: np.ndarray, azimuth_deg: np.ndarray, true_azimuth_deg: float, *,
                 chirp_interval: float, wavelength: float,
                 velocity_resolution: float,
                 search_deg: float | None = None) -> dict[str, float]:
    """The metrics of :data:`BEAM_METRICS` of one frame's beams.

    Parameters
    ----------
    beams : ndarray, shape ``[chirp, range, azimuth]``
        Compensated beams of one frame at one elevation.
    azimuth_deg : ndarray, shape ``[azimuth]``
        Uniform azimuth grid of the beams [deg].
    true_azimuth_deg : float
        The target's true azimuth [deg].
    chirp_interval : float
        Slow-time sampling period [s].
    wavelength : float
        Carrier wavelength [m].
    velocity_resolution : float
        Doppler velocity bin [m/s].
    search_deg : float, optional
        Look for the peak only within this many degrees of ``true_azimuth_deg`` (a
        stronger scatterer elsewhere in the cells, e.g. the ground under the radar, is
        then not taken for the target); None: the whole grid.

    Raises
    ------
    ValueError
        The zero-Doppler peak lies on the edge of the azimuth grid (no
        interpolation possible), or the cube is not 3-D.
    """
    b = np.asarray(beams)
    g, a, az = zero_doppler_peak(b, azimuth_deg, true_azimuth_deg, search_deg)
    slow = b[:, g, a]
    pv = pseudo_velocity(slow, chirp_interval, wavelength)
    spec = np.abs(np.fft.fft(slow * np.hanning(slow.size))) ** 2
    k = int(np.argmax(spec))
    near = spec[[(k - 1) % spec.size, k, (k + 1) % spec.size]].sum()
    leak = 10 * np.log10(max(spec.sum() - near, 1e-30 * spec.sum()) / spec.sum())
    return {"beam_angle_error_deg": float(abs(az - true_azimuth_deg)),
            "beam_pseudo_velocity_bins": float(pv / velocity_resolution),
            "doppler_leakage_db": float(leak)}


def zero_doppler_peak(beams: np.ndarray, azimuth_deg: np.ndarray, true_azimuth_deg: float,
                      search_deg: float | None = None) -> tuple[int, int, float]:
    """Range cell, azimuth index and interpolated azimuth [deg] of the zero-Doppler peak.

    ``beams [chirp, range, azimuth]`` summed over chirps; the strongest cell within
    ``search_deg`` of ``true_azimuth_deg`` (None: anywhere), its azimuth refined by a
    parabola through the dB powers of its neighbours. Raises as :func:`beam_metrics`.
    """
    b = np.asarray(beams)
    if b.ndim != 3:
        raise ValueError(f"beams must be [chirp, range, azimuth], got shape {b.shape}")
    az_axis = np.asarray(azimuth_deg, dtype=float)
    zero = np.abs(b.astype(np.complex128).sum(axis=0)) ** 2     # [range, azimuth]
    near = (np.ones(az_axis.size, bool) if search_deg is None
            else np.abs(az_axis - true_azimuth_deg) <= search_deg)
    if not near.any():
        raise ValueError(f"no beam within {search_deg} deg of the true azimuth "
                         f"{true_azimuth_deg:.2f} deg; expected the grid to cover it")
    g, a = np.unravel_index(np.argmax(np.where(near, zero, -np.inf)), zero.shape)
    if not 0 < a < zero.shape[1] - 1:
        raise ValueError(f"the beam peak lies on the edge of the azimuth grid "
                         f"({az_axis[a]:.2f} deg); expected it inside")
    step = float(az_axis[1] - az_axis[0])
    db = 10 * np.log10(zero[g])
    return int(g), int(a), float(az_axis[a] + step * parabolic_offset(*db[a - 1:a + 2]))
