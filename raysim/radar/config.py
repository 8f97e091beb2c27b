"""FMCW radar configuration and the axes it implies.

All quantities are SI. The default is the paper's Table 2: 77 GHz carrier, 1 GHz
bandwidth, 60 us chirps, 10 MHz complex sampling (600 samples per chirp), 256
chirps per frame.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

#: Speed of light in vacuum [m/s].
SPEED_OF_LIGHT = 299_792_458.0
#: Boltzmann constant [J/K].
BOLTZMANN = 1.380649e-23
#: Reference noise temperature [K].
T0_KELVIN = 290.0

#: Physical range of the transmit power per transmitter [dBm]: 0.1 fW to 1 kW (automotive
#: 77 GHz parts emit 10-13 dBm; 55 dBm EIRP is the regulatory limit).
TX_POWER_DBM_RANGE = (-100.0, 60.0)
#: Physical range of one element's antenna gain [dBi].
ANTENNA_GAIN_DBI_RANGE = (-30.0, 50.0)
#: Physical range of the receiver noise figure [dB] (0 dB: a noiseless receiver).
NOISE_FIGURE_DB_RANGE = (0.0, 50.0)
#: Range of a radar cross-section [dBsm]: up to beyond a ship (+60 dBsm), which keeps the
#: radar equation's power finite in float32; down to a vanishing echo (an insect is
#: -60 dBsm; -250 dBsm lies far below any noise floor, for noise-only frames).
RCS_DBSM_RANGE = (-250.0, 100.0)


def check_in_range(name: str, value, bounds: tuple[float, float], unit: str) -> float:
    """``value`` as a float within ``bounds`` (inclusive); else ValueError naming it, the
    range and ``unit``."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a number in [{bounds[0]:g}, {bounds[1]:g}] {unit}, "
                         f"got {value!r}") from None
    if not (math.isfinite(v) and bounds[0] <= v <= bounds[1]):
        raise ValueError(f"{name} must lie in the physical range [{bounds[0]:g}, "
                         f"{bounds[1]:g}] {unit}, got {value!r}")
    return v


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not math.isfinite(value) or value <= 0.0:
        raise ValueError(f"{name} must be a finite positive number, got {value!r}")
    return value


@dataclass(frozen=True)
class RadarConfig:
    """FMCW waveform and sampling parameters.

    Parameters
    ----------
    carrier_frequency : float
        Start (carrier) frequency ``f_c`` [Hz].
    bandwidth : float
        Swept bandwidth ``B`` [Hz] over the sampled chirp duration.
    chirp_duration : float
        Sampled ramp duration ``T_c`` [s].
    idle_time : float
        Idle time between chirps [s]; the chirp repetition interval is
        ``T_rep = T_c + idle_time``.
    sample_rate : float
        ADC sample rate ``f_s`` [Hz].
    num_chirps : int
        Chirps per frame ``N`` (slow-time length).
    num_frames : int
        Frames rendered back to back.
    complex_sampling : bool
        Complex (I/Q) baseband if True; real sampling halves the unambiguous
        beat band.
    tx_power_dbm : float
        Transmit power per active transmitter [dBm], within
        :data:`TX_POWER_DBM_RANGE` (-100 to 60 dBm).
    antenna_gain_dbi : float
        Peak gain of one transmit and one receive element [dBi] (same for both),
        within :data:`ANTENNA_GAIN_DBI_RANGE` (-30 to 50 dBi); must agree with the
        peak of ``element_pattern`` (:func:`raysim.radar.pattern.check_peak_gain`).
    noise_figure_db : float
        Receiver noise figure [dB], used when thermal noise is switched on,
        within :data:`NOISE_FIGURE_DB_RANGE` (0 to 50 dB).
    frame_period : float or None
        Frame start-to-start interval [s]; ``None`` means frames are
        contiguous (``num_chirps * T_rep``).
    num_tx_slots : int
        Transmitters fired one after another (TDM MIMO) within one slow-time
        step. One cube ``chirp`` is then a loop of ``num_tx_slots`` ramps and the
        slow-time period is ``num_tx_slots * (T_c + idle)``.
    element_pattern : str
        Power pattern of every transmit and receive element
        (:func:`raysim.radar.pattern.element_pattern`): ``"patch"`` (default,
        ``cos^q`` with ``q`` from ``antenna_gain_dbi``: ``cos^4`` at 10 dBi),
        ``"cos^<q>"``, ``"tr38901"``, ``"constant"`` or a CSV file path. The
        point-target oracle ignores it unless asked (its elements are isotropic).
    """

    carrier_frequency: float = 77e9
    bandwidth: float = 1e9
    chirp_duration: float = 60e-6
    idle_time: float = 0.0
    sample_rate: float = 10e6
    num_chirps: int = 256
    num_frames: int = 1
    complex_sampling: bool = True
    tx_power_dbm: float = 12.0
    antenna_gain_dbi: float = 10.0
    noise_figure_db: float = 12.0
    frame_period: float | None = None
    num_tx_slots: int = 1
    element_pattern: str = "patch"

    def __post_init__(self) -> None:
        _positive("carrier_frequency", self.carrier_frequency)
        _positive("bandwidth", self.bandwidth)
        _positive("chirp_duration", self.chirp_duration)
        _positive("sample_rate", self.sample_rate)
        check_in_range("tx_power_dbm", self.tx_power_dbm, TX_POWER_DBM_RANGE, "dBm")
        check_in_range("antenna_gain_dbi", self.antenna_gain_dbi, ANTENNA_GAIN_DBI_RANGE, "dBi")
        check_in_range("noise_figure_db", self.noise_figure_db, NOISE_FIGURE_DB_RANGE, "dB")
        if not math.isfinite(self.idle_time) or self.idle_time < 0:
            raise ValueError(f"idle_time must be >= 0 s, got {self.idle_time!r}")
        for name in ("num_chirps", "num_frames", "num_tx_slots"):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or value < 1:
                raise ValueError(f"{name} must be a positive integer, got {value!r}")
        if self.num_samples < 2:
            raise ValueError(
                f"chirp_duration * sample_rate must give at least 2 samples, got "
                f"{self.chirp_duration} s * {self.sample_rate} Hz = {self.num_samples}"
            )
        if self.bandwidth >= self.carrier_frequency:
            raise ValueError(
                f"bandwidth {self.bandwidth} Hz must be below carrier_frequency "
                f"{self.carrier_frequency} Hz"
            )
        if self.element_pattern != "patch":
            # "patch" follows the stated gain; its q >= 0 is checked where it is used
            # (a scene render), so a low-gain config stays valid for the oracle.
            from raysim.radar.pattern import check_peak_gain

            check_peak_gain(self.pattern, self.antenna_gain_dbi)
        if self.frame_period is not None and self.frame_period < self.frame_duration:
            raise ValueError(
                f"frame_period {self.frame_period} s is shorter than one frame "
                f"({self.frame_duration} s = num_chirps * chirp_interval)"
            )

    # ------------------------------------------------------------------ derived
    @property
    def pattern(self):
        """The element power pattern (:class:`raysim.radar.pattern.ElementPattern`)."""
        from raysim.radar.pattern import element_pattern

        return element_pattern(self.element_pattern, self.antenna_gain_dbi)

    @property
    def wavelength(self) -> float:
        """Carrier wavelength ``lambda = c / f_c`` [m]."""
        return SPEED_OF_LIGHT / self.carrier_frequency

    @property
    def center_frequency(self) -> float:
        """Mid-chirp frequency ``f_c + B / 2`` [Hz].

        After a range FFT with a window symmetric about mid-chirp, a delay
        ``tau`` appears with phase ``2 pi (f_c + B/2) tau``: angle and Doppler
        processing of range-compressed data must use this frequency, not the
        start frequency ``f_c`` (the difference is 0.65 % in sin(az) at
        77 GHz / 1 GHz, i.e. 0.14 deg at 20 deg azimuth).
        """
        return self.carrier_frequency + 0.5 * self.bandwidth

    @property
    def center_wavelength(self) -> float:
        """Mid-chirp wavelength ``c / (f_c + B / 2)`` [m] (see :attr:`center_frequency`)."""
        return SPEED_OF_LIGHT / self.center_frequency

    @property
    def chirp_rate(self) -> float:
        """Chirp slope ``mu = B / T_c`` [Hz/s]."""
        return self.bandwidth / self.chirp_duration

    @property
    def slot_interval(self) -> float:
        """Ramp repetition interval ``T_c + idle`` [s] (one transmitter slot)."""
        return self.chirp_duration + self.idle_time

    @property
    def chirp_interval(self) -> float:
        """Slow-time period ``T_rep = num_tx_slots (T_c + idle)`` [s]."""
        return self.num_tx_slots * self.slot_interval

    @property
    def frame_duration(self) -> float:
        """Duration of the chirps of one frame ``N * T_rep`` [s]."""
        return self.num_chirps * self.chirp_interval

    @property
    def frame_interval(self) -> float:
        """Frame start-to-start interval [s]."""
        return self.frame_duration if self.frame_period is None else self.frame_period

    @property
    def num_samples(self) -> int:
        """ADC samples per chirp ``K = round(T_c f_s)``."""
        return int(round(self.chirp_duration * self.sample_rate))

    @property
    def range_resolution(self) -> float:
        """Range bin of an unpadded range FFT ``c / (2 B)`` [m]."""
        return SPEED_OF_LIGHT * self.sample_rate / (2.0 * self.chirp_rate * self.num_samples)

    @property
    def max_beat_frequency(self) -> float:
        """Largest unambiguous beat frequency [Hz]: ``f_s`` (complex) or ``f_s / 2`` (real)."""
        return self.sample_rate if self.complex_sampling else self.sample_rate / 2.0

    @property
    def max_range(self) -> float:
        """Largest range whose beat frequency fits the sampled band [m]."""
        return SPEED_OF_LIGHT * self.max_beat_frequency / (2.0 * self.chirp_rate)

    @property
    def doppler_resolution(self) -> float:
        """Doppler bin ``1 / (N T_rep)`` [Hz]."""
        return 1.0 / (self.num_chirps * self.chirp_interval)

    @property
    def velocity_resolution(self) -> float:
        """Range-rate bin ``lambda_c / (2 N T_rep)`` [m/s] (mid-chirp wavelength)."""
        return self.center_wavelength * self.doppler_resolution / 2.0

    @property
    def max_velocity(self) -> float:
        """Unambiguous range rate ``lambda_c / (4 T_rep)`` [m/s] (spectrum spans +-)."""
        return self.center_wavelength / (4.0 * self.chirp_interval)

    # -------------------------------------------------------------------- axes
    def fast_time(self) -> np.ndarray:
        """Sample times within a chirp, shape ``[sample]`` [s]."""
        return np.arange(self.num_samples) / self.sample_rate

    def chirp_times(self, frame: int = 0, t0: float = 0.0) -> np.ndarray:
        """Start times of the chirps of ``frame``, shape ``[chirp]`` [s]."""
        return t0 + frame * self.frame_interval + np.arange(self.num_chirps) * self.chirp_interval

    def range_axis(self, n_fft: int | None = None) -> np.ndarray:
        """Range of each range-FFT bin, shape ``[range]`` [m].

        Complex sampling gives ``n_fft`` bins from 0 up to ``max_range``; real
        sampling keeps the first half.
        """
        n_fft = self.num_samples if n_fft is None else int(n_fft)
        beat = np.arange(n_fft) * self.sample_rate / n_fft
        if not self.complex_sampling:
            beat = beat[: n_fft // 2]
        return SPEED_OF_LIGHT * beat / (2.0 * self.chirp_rate)

    def bin_ranges(self, num_bins: int) -> np.ndarray:
        """Range of each bin of a range-compressed cube with ``num_bins`` bins [m].

        The FFT length is ``num_bins`` for complex samples and ``2 num_bins``
        for real ones (:func:`raysim.processing.maps.range_compress` keeps the
        positive half), zero padding included.
        """
        n = int(num_bins)
        return self.range_axis(n if self.complex_sampling else 2 * n)[:n]

    def doppler_axis(self, n_fft: int | None = None) -> np.ndarray:
        """Doppler frequency of each fft-shifted slow-time bin, shape ``[doppler]`` [Hz]."""
        n_fft = self.num_chirps if n_fft is None else int(n_fft)
        return np.fft.fftshift(np.fft.fftfreq(n_fft, d=self.chirp_interval))

    def velocity_axis(self, n_fft: int | None = None) -> np.ndarray:
        """Range rate of each fft-shifted Doppler bin, shape ``[doppler]`` [m/s].

        Positive is receding (range growing), following ``f_D = 2 v_r / lambda_c``
        with the mid-chirp wavelength of range-compressed data.
        """
        return self.doppler_axis(n_fft) * self.center_wavelength / 2.0

    def check_range(self, distance: float | np.ndarray, what: str = "target range") -> None:
        """Raise if a range lies outside the unambiguous beat band.

        Parameters
        ----------
        distance : float or array
            One-way range(s) [m].
        what : str
            Name of the quantity, used in the error message.
        """
        d = np.atleast_1d(np.asarray(distance, dtype=float))
        bad = d[(d >= self.max_range) | (d < 0)]
        if bad.size:
            raise ValueError(
                f"{what} {bad[0]:.3f} m is outside the unambiguous range window "
                f"[0, {self.max_range:.3f}) m set by sample_rate={self.sample_rate} Hz and "
                f"chirp_rate={self.chirp_rate:.4g} Hz/s"
            )

    def with_(self, **changes) -> RadarConfig:
        """Copy with some fields changed (validated again)."""
        return replace(self, **changes)


#: The paper's Table 2 radar (256 chirps).
PAPER_RADAR = RadarConfig()
