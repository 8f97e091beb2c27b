"""Metrics of docs/conventions.md, shared by tests, reports and benchmarks.

* pseudo-velocity: range rate at the peak of the Doppler spectrum of a static
  target (Hann window over slow time, zero-padded 16x, peak refined by a
  parabola through the three highest dB samples);
* Doppler mainlobe width: -3 dB width [Hz] of that power spectrum, linear
  interpolation at both crossings (Hann, no motion: about 1.44 bins);
* angle error: great-circle distance [deg] between the interpolated map peak
  (:func:`raysim.processing.maps.map_peak`) and the true direction;
* image entropy: Shannon entropy [nats] of ``p = |I|^2 / sum |I|^2``.
"""

from __future__ import annotations

import numpy as np

from raysim.processing.windows import window

#: Slow-time zero-padding factor of the Doppler metrics.
DOPPLER_PAD = 16


def parabolic_offset(y_minus: float, y0: float, y_plus: float) -> float:
    """Vertex offset in [-0.5, 0.5] bins of a parabola through three samples."""
    den = y_minus - 2.0 * y0 + y_plus
    if den >= 0:  # not a strict maximum
        return 0.0
    return float(np.clip(0.5 * (y_minus - y_plus) / den, -0.5, 0.5))


def doppler_power_spectrum(slow_time: np.ndarray, chirp_interval: float, *,
                           pad: int = DOPPLER_PAD) -> tuple[np.ndarray, np.ndarray]:
    """Hann-windowed, zero-padded slow-time power spectrum.

    Parameters
    ----------
    slow_time : ndarray, shape ``[chirp]``
    chirp_interval : float
        Slow-time sampling period ``T_rep`` [s].

    Returns
    -------
    freq : ndarray, shape ``[doppler]`` [Hz], increasing
    power : ndarray, shape ``[doppler]``
    """
    x = np.asarray(slow_time)
    if x.ndim != 1 or x.size < 4:
        raise ValueError(f"slow_time must be 1-D with >= 4 chirps, got shape {x.shape}")
    if not chirp_interval > 0:
        raise ValueError(f"chirp_interval must be > 0 s, got {chirp_interval!r}")
    n = x.size
    spec = np.fft.fftshift(np.fft.fft(x * window("hann", n), n * pad))
    freq = np.fft.fftshift(np.fft.fftfreq(n * pad, d=chirp_interval))
    return freq, np.abs(spec) ** 2


def doppler_peak_frequency(slow_time: np.ndarray, chirp_interval: float) -> float:
    """Doppler frequency [Hz] at the interpolated spectral peak."""
    freq, p = doppler_power_spectrum(slow_time, chirp_interval)
    i = int(np.argmax(p))
    db = 10 * np.log10(np.maximum(p, 1e-300))
    frac = parabolic_offset(db[i - 1], db[i], db[(i + 1) % p.size]) if i > 0 else 0.0
    return float(freq[i] + frac * (freq[1] - freq[0]))


def pseudo_velocity(slow_time: np.ndarray, chirp_interval: float, wavelength: float) -> float:
    """Range rate [m/s] at the Doppler peak, ``v = f_D lambda / 2`` (positive receding)."""
    return doppler_peak_frequency(slow_time, chirp_interval) * wavelength / 2.0


def doppler_mainlobe_width(slow_time: np.ndarray, chirp_interval: float) -> float:
    """-3 dB width [Hz] of the Doppler mainlobe around the global peak.

    Walks out from the peak to the first samples below half power on both
    sides and interpolates the crossings linearly (in linear power).
    """
    freq, p = doppler_power_spectrum(slow_time, chirp_interval)
    i = int(np.argmax(p))
    half = 0.5 * p[i]
    n = p.size
    # circular walk: the spectrum wraps at +-PRF/2
    j = i
    while p[(j + 1) % n] >= half:
        j += 1
        if j - i >= n:
            return float(freq[-1] - freq[0] + (freq[1] - freq[0]))
    a, b = p[j % n], p[(j + 1) % n]
    right = j + (a - half) / (a - b)
    j = i
    while p[(j - 1) % n] >= half:
        j -= 1
    a, b = p[j % n], p[(j - 1) % n]
    left = j - (a - half) / (a - b)
    return float((right - left) * (freq[1] - freq[0]))


def angle_error_deg(az, el, az_true, el_true) -> float:
    """Great-circle angle [deg] between (az, el) and the true direction (all in rad)."""
    from compensation.geometry import direction

    u, v = direction(az, el), direction(az_true, el_true)
    return float(np.rad2deg(np.arccos(np.clip(np.dot(u, v), -1.0, 1.0))))


def image_entropy(intensity: np.ndarray) -> float:
    """Shannon entropy [nats] of a map: ``-sum p log p`` with ``p = I / sum I``.

    Parameters
    ----------
    intensity : ndarray
        Power values ``|I|^2`` (non-negative), any shape.
    """
    i = np.asarray(intensity, dtype=float).ravel()
    if np.any(i < 0) or not np.all(np.isfinite(i)):
        raise ValueError("intensity must be finite and non-negative (pass |I|^2)")
    total = i.sum()
    if total <= 0:
        raise ValueError("intensity is all zero: entropy undefined")
    p = i[i > 0] / total
    return float(-np.sum(p * np.log(p)))
