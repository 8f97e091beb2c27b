"""What a flight controller logs of its IMU: boxcar-averaged low-rate output with logger gaps.

A flight controller samples its IMU fast (1-8 kHz) and logs much slower: PX4's
``sensor_combined`` and ArduPilot's ``IMU`` carry 200-400 Hz samples, each the
integral of the fast samples over its interval divided by the interval (a
boxcar average), and the logger drops whole blocks of messages when its
buffer overruns (gaps of 50-200 ms in real logs). A boxcar of length ``T``
passes a tone of frequency ``f`` with gain ``|sinc(f T)|`` and folds what lies
above ``1 / (2 T)`` into the logged band, so a 250 Hz log cannot show the
100-200 Hz rotor vibration that moves the radar: only the radar itself can
(docs/imu.md).

Stamp convention: output sample ``k`` is the integral over ``[t_k - 1/rate, t_k]``
of the fast samples joined by straight lines (the trapezoid rule, as PX4's
``Integrator::put`` integrates, ``(val + last_val) dt / 2``), divided by the
interval, and is stamped ``t_k``, the end of its interval (as PX4's integrators
stamp the last sample integrated); its effective time is the middle of the
interval, ``t_k - 1 / (2 rate)``, exactly: the weights ``1/2, 1, ..., 1, 1/2`` of
the ``m + 1`` fast samples are symmetric about it. (A plain mean of the ``m``
samples in ``(t_k - 1/rate, t_k]`` would sit half a fast period later, 0.25 ms
at 2 kHz: an offset the log cannot state.) Its gain at a tone ``f`` is the
discrete boxcar's ``|sin(m x) / (m sin x)|`` times ``cos x``, ``x = pi f / f_fast``
(the mean of the two rectangle rules half a fast period either side).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from raysim.platform.imu import ImuSamples

__all__ = ["boxcar_output", "drop_gaps", "boxcar_gain"]


def boxcar_gain(frequency, rate: float) -> np.ndarray:
    """Amplitude gain of a boxcar average of length ``1 / rate`` at ``frequency`` [1].

    ``|sin(pi f / rate) / (pi f / rate)|``; the phase is a delay of half the interval.

    Parameters
    ----------
    frequency : array_like
        Frequency [Hz].
    rate : float
        Output rate [Hz] (the boxcar is one output interval long).
    """
    return np.abs(np.sinc(np.asarray(frequency, dtype=float) / float(rate)))


def boxcar_output(samples: ImuSamples, rate: float) -> ImuSamples:
    """Average fast IMU samples into a flight controller's low-rate output.

    Parameters
    ----------
    samples : ImuSamples
        Fast samples on the IMU clock, ``time [sample]``, at a rate that is an
        integer multiple ``m >= 1`` of ``rate`` (within 1e-6).
    rate : float
        Output rate [Hz].

    Returns
    -------
    ImuSamples
        ``time [output]``: the end of each complete interval of ``m`` fast
        periods; ``gyro``/``accel [output, 3]``: their trapezoid means over the
        ``m + 1`` samples from its start to its end. ``truth`` keeps the
        matrices, the biases so averaged and the truth time of each stamp.
    """
    rate = float(rate)
    if not math.isfinite(rate) or rate <= 0.0:
        raise ValueError(f"rate must be a finite positive number of Hz, got {rate!r}")
    fast = samples.rate if samples.rate is not None else samples.mean_rate
    if not math.isfinite(fast) or fast <= 0.0:
        raise ValueError(f"samples need a known rate to be averaged, got {fast!r}")
    m = round(fast / rate)
    if m < 1 or abs(m * rate - fast) > 1e-6 * fast:
        raise ValueError(f"rate must divide the fast rate {fast:g} Hz by an integer, got "
                         f"{rate:g} Hz ({fast / rate:g} fast samples per output)")
    # Output intervals end on the output clock's ticks k / rate: the first complete one
    # starts at the first fast sample on a tick (its trapezoid needs that sample too).
    ticks = np.round(samples.time * fast).astype(np.int64)
    first = int(np.argmax(ticks % m == 0))
    if ticks[first] % m:
        first = samples.num_samples
    count = (samples.num_samples - 1 - first) // m
    if count < 1:
        raise ValueError(f"{samples.num_samples} fast samples hold no complete interval of "
                         f"{m} samples")
    # trapezoid weights of the m + 1 samples of each interval, both ends shared
    index = first + m * np.arange(count)[:, None] + np.arange(m + 1)       # [output, m + 1]
    weight = np.r_[0.5, np.ones(m - 1), 0.5] / m if m > 1 else np.array([0.5, 0.5])

    def mean(x: np.ndarray) -> np.ndarray:
        return np.einsum("j,kj...->k...", weight, x[index])

    time = samples.time[index[:, -1]]
    truth = samples.truth
    if truth is not None:
        truth = replace(truth, true_time=truth.true_time[index[:, -1]],
                        gyro_bias=mean(truth.gyro_bias), accel_bias=mean(truth.accel_bias))
    return ImuSamples(time, mean(samples.gyro), mean(samples.accel), spec=samples.spec,
                      truth=truth, source=f"{samples.source}, boxcar-averaged to {rate:g} Hz",
                      rate=rate)


def drop_gaps(samples: ImuSamples, gaps: Sequence[tuple[float, float]]) -> ImuSamples:
    """Remove the samples a logger lost: every sample stamped inside a gap.

    Parameters
    ----------
    samples : ImuSamples
    gaps : sequence of (start, length)
        Gaps on the IMU clock [s]; a sample at ``t`` is lost when
        ``start <= t < start + length``.

    Returns
    -------
    ImuSamples
        The samples kept (``rate`` unchanged: the nominal rate of what remains).
    """
    keep = np.ones(samples.num_samples, dtype=bool)
    for i, gap in enumerate(gaps):
        try:
            start, length = (float(v) for v in gap)
        except (TypeError, ValueError):
            raise ValueError(f"gaps[{i}] must be (start, length) in seconds, got {gap!r}") from None
        if not (math.isfinite(start) and math.isfinite(length) and length > 0.0):
            raise ValueError(f"gaps[{i}] must have a finite start and a positive length, "
                             f"got {gap!r}")
        keep &= ~((samples.time >= start) & (samples.time < start + length))
    if keep.sum() < 2:
        raise ValueError(f"the gaps {list(gaps)!r} leave fewer than 2 of "
                         f"{samples.num_samples} samples")
    truth = samples.truth
    if truth is not None:
        truth = replace(truth, true_time=truth.true_time[keep], gyro_bias=truth.gyro_bias[keep],
                        accel_bias=truth.accel_bias[keep])
    return ImuSamples(samples.time[keep], samples.gyro[keep], samples.accel[keep],
                      spec=samples.spec, truth=truth,
                      source=f"{samples.source}, {int((~keep).sum())} samples lost in gaps",
                      rate=samples.rate)
