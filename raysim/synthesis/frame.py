"""`RadarFrame`: one IF frame with the axes and truth needed to interpret it."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from raysim.radar.arrays import VirtualArray
from raysim.radar.config import RadarConfig


@dataclass(frozen=True, eq=False)
class RadarFrame:
    """An IF data cube and everything needed to process it.

    Attributes
    ----------
    data : ndarray, shape ``[chirp, channel, sample]``
        Dechirped IF samples [sqrt(W)]: complex64 for a complex (IQ) receiver,
        float32 (the in-phase channel, :func:`adc_samples`) for a real-sampled
        one (``config.complex_sampling`` False).
    config : RadarConfig
        Waveform that produced it.
    array : VirtualArray
        Channel layout (channel order as documented by the array).
    chirp_times : ndarray, shape ``[chirp]``
        Start time of each chirp (slot 0 of a TDM loop) [s].
    lever_arm : ndarray, shape ``[3]``
        Radar phase centre in the body frame B [m].
    frame_index : int
        Index of the frame within a render.
    truth : dict
        Free-form ground truth (targets, motion name, ...), for reports.
    """

    data: np.ndarray
    config: RadarConfig
    array: VirtualArray
    chirp_times: np.ndarray
    lever_arm: np.ndarray = field(default_factory=lambda: np.zeros(3))
    frame_index: int = 0
    truth: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        want = np.complex64 if self.config.complex_sampling else np.float32
        if self.data.dtype != want:
            raise ValueError(f"data must be {np.dtype(want).name} for complex_sampling="
                             f"{self.config.complex_sampling}, got {self.data.dtype}")
        expected = (self.config.num_chirps, self.array.num_channels, self.config.num_samples)
        if self.data.shape != expected:
            raise ValueError(
                f"data shape {self.data.shape} does not match [chirp, channel, sample] = {expected}"
            )
        if np.shape(self.chirp_times) != (self.config.num_chirps,):
            raise ValueError(
                f"chirp_times must have shape ({self.config.num_chirps},), "
                f"got {np.shape(self.chirp_times)}"
            )

    dims = ("chirp", "channel", "sample")

    def to_xarray(self):
        """The frame as a labelled :class:`xarray.DataArray` ``if_data``.

        Dimensions ``chirp, channel, sample`` (docs/conventions.md), as in a
        store's ``if_data`` without its ``frame`` axis. Coordinates:
        ``chirp_time`` ``[chirp]`` (chirp start, truth clock [s]), ``sample``
        (fast time within the chirp [s]), ``tx_slot`` ``[channel]`` (TDM
        transmit slot) and ``virtual_x``, ``virtual_y``, ``virtual_z``
        ``[channel]`` (virtual phase centres in frame A [m]); units in each
        coordinate's attrs. Attributes: ``frame_index``, ``lever_arm_m``,
        ``array_name``, ``carrier_frequency_hz``, ``wavelength_m``. The data is
        not copied.

        Returns
        -------
        xarray.DataArray
            Shape ``[chirp, channel, sample]``, complex64 (float32 for a
            real-sampled radar) [sqrt(W)].
        """
        import xarray as xr

        virt = np.asarray(self.array.virtual_positions, dtype=float)
        coords = {
            "chirp_time": ("chirp", np.asarray(self.chirp_times, dtype=float),
                           {"units": "s", "long_name": "chirp start time, truth clock"}),
            "sample": ("sample", self.fast_time,
                       {"units": "s", "long_name": "fast time: sample time within the chirp"}),
            "tx_slot": ("channel", np.asarray(self.array.tx_slot, dtype=np.int64),
                        {"units": "1", "long_name": "TDM transmit slot"}),
        }
        for i, axis in enumerate("xyz"):
            coords[f"virtual_{axis}"] = ("channel", virt[:, i], {
                "units": "m", "long_name": f"virtual phase centre {axis} in A"})
        return xr.DataArray(self.data, dims=self.dims, coords=coords, name="if_data", attrs={
            "units": "V", "long_name": "dechirped IF samples s_tx conj(s_rx)",
            "comment": "amplitude in sqrt(W): |if_data|^2 is the power in W",
            "frame_index": int(self.frame_index),
            "lever_arm_m": np.asarray(self.lever_arm, dtype=float).tolist(),
            "array_name": self.array.name,
            "carrier_frequency_hz": float(self.config.carrier_frequency),
            "wavelength_m": float(self.config.wavelength)})

    @property
    def fast_time(self) -> np.ndarray:
        """Sample times within a chirp, shape ``[sample]`` [s]."""
        return self.config.fast_time()

    @property
    def range_axis(self) -> np.ndarray:
        """Range of each unpadded range bin, shape ``[range]`` [m]."""
        return self.config.range_axis()

    @property
    def velocity_axis(self) -> np.ndarray:
        """Range rate of each fft-shifted Doppler bin, shape ``[doppler]`` [m/s]."""
        return self.config.velocity_axis()

    @property
    def doppler_axis(self) -> np.ndarray:
        """Doppler frequency of each fft-shifted bin, shape ``[doppler]`` [Hz]."""
        return self.config.doppler_axis()


def adc_samples(data: np.ndarray, config: RadarConfig) -> np.ndarray:
    """What the ADC delivers from a complex IF cube: itself (IQ) or its real part.

    A real-sampled receiver digitises the in-phase channel only,
    ``Re(s_if)``: a tone of complex amplitude ``a`` becomes
    ``|a| cos(...)``, half its power (its noise too: the SNR is 3 dB below
    the IQ receiver's, the negative-frequency noise folding in).

    Parameters
    ----------
    data : ndarray, shape ``[chirp, channel, sample]``, complex64
    config : RadarConfig

    Returns
    -------
    ndarray, shape ``[chirp, channel, sample]``
        complex64 (``complex_sampling``) or float32.
    """
    if config.complex_sampling:
        return data
    return np.ascontiguousarray(data.real, dtype=np.float32)
