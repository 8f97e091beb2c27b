"""Antenna arrays in the radar frame A: virtual UPAs and physical TDM-MIMO layouts.

Positions are in metres in frame A (array in the X-Y plane, boresight +Z_A).
The phase convention follows docs/conventions.md: a virtual channel with
``p_virt = p_tx + p_rx`` sees the one-way phase ``2 pi / lambda * u . p_virt``;
its monostatic-equivalent element sits at ``p_virt / 2``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, eq=False)
class VirtualArray:
    """Virtual MIMO channels with their physical transmit and receive positions.

    Attributes
    ----------
    tx_positions : ndarray, shape ``[channel, 3]``
        Transmit phase centre of each channel in frame A [m].
    rx_positions : ndarray, shape ``[channel, 3]``
        Receive phase centre of each channel in frame A [m].
    tx_slot : ndarray of int, shape ``[channel]``
        TDM slot of the channel's transmitter (0 for simultaneous/virtual arrays).
    grid_shape : tuple of int or None
        ``(nx, ny)`` when channels form a regular grid, x index major, y minor.
    name : str
        Human-readable description.
    """

    tx_positions: np.ndarray
    rx_positions: np.ndarray
    tx_slot: np.ndarray
    grid_shape: tuple[int, int] | None = None
    name: str = "array"

    def __post_init__(self) -> None:
        tx = np.asarray(self.tx_positions, dtype=float)
        rx = np.asarray(self.rx_positions, dtype=float)
        slot = np.asarray(self.tx_slot, dtype=int)
        if tx.ndim != 2 or tx.shape[1] != 3 or tx.shape[0] < 1:
            raise ValueError(f"tx_positions must have shape [channel, 3], got {tx.shape}")
        if rx.shape != tx.shape:
            raise ValueError(
                f"rx_positions shape {rx.shape} must equal tx_positions shape {tx.shape}"
            )
        if slot.shape != (tx.shape[0],) or slot.min() < 0:
            raise ValueError(
                f"tx_slot must be non-negative integers of shape ({tx.shape[0]},), got {slot}"
            )
        if not (np.all(np.isfinite(tx)) and np.all(np.isfinite(rx))):
            raise ValueError("array positions must be finite")
        if self.grid_shape is not None and int(np.prod(self.grid_shape)) != tx.shape[0]:
            raise ValueError(
                f"grid_shape {self.grid_shape} does not match {tx.shape[0]} channels"
            )
        object.__setattr__(self, "tx_positions", tx)
        object.__setattr__(self, "rx_positions", rx)
        object.__setattr__(self, "tx_slot", slot)

    @property
    def num_channels(self) -> int:
        """Number of virtual channels."""
        return self.tx_positions.shape[0]

    @property
    def num_slots(self) -> int:
        """Number of TDM transmit slots."""
        return int(self.tx_slot.max()) + 1

    @property
    def virtual_positions(self) -> np.ndarray:
        """``p_virt = p_tx + p_rx`` of each channel, shape ``[channel, 3]`` [m]."""
        return self.tx_positions + self.rx_positions

    @property
    def phase_centres(self) -> np.ndarray:
        """Monostatic-equivalent element positions ``p_virt / 2``, shape ``[channel, 3]`` [m]."""
        return 0.5 * self.virtual_positions

    def steering_vector(self, u: np.ndarray, wavelength: float) -> np.ndarray:
        """Plane-wave response ``exp(-j 2 pi / lambda u . p_virt)``.

        Parameters
        ----------
        u : ndarray, shape ``[..., 3]``
            Unit direction(s) in frame A.
        wavelength : float
            Carrier wavelength [m].

        Returns
        -------
        ndarray, shape ``[..., channel]``, complex128
        """
        phase = (2.0 * np.pi / wavelength) * (np.asarray(u) @ self.virtual_positions.T)
        return np.exp(-1j * phase)


def upa(nx: int = 20, ny: int = 20, spacing: float | None = None, wavelength: float = None,
        *, centred: bool = True) -> VirtualArray:
    """A virtual uniform planar array given directly (monostatic-equivalent).

    Parameters
    ----------
    nx, ny : int
        Virtual elements along X_A and Y_A.
    spacing : float, optional
        Virtual element spacing of ``p_virt`` [m]; defaults to half a wavelength.
    wavelength : float, optional
        Needed when ``spacing`` is omitted [m].
    centred : bool
        Put the array's centroid at the radar phase centre (origin of A).

    Returns
    -------
    VirtualArray
        Channel order x index major, y index minor; ``p_tx = p_rx = p_virt / 2``.
    """
    if int(nx) < 1 or int(ny) < 1:
        raise ValueError(f"nx and ny must be >= 1, got nx={nx}, ny={ny}")
    if spacing is None:
        if wavelength is None:
            raise ValueError("give spacing [m] or wavelength [m] for a half-wavelength UPA")
        spacing = wavelength / 2.0
    if not np.isfinite(spacing) or spacing <= 0:
        raise ValueError(f"spacing must be a positive length in metres, got {spacing!r}")
    ix, iy = np.meshgrid(np.arange(nx), np.arange(ny), indexing="ij")
    p = np.stack([ix.ravel() * spacing, iy.ravel() * spacing, np.zeros(nx * ny)], axis=1)
    if centred:
        p[:, :2] -= p[:, :2].mean(axis=0)
    half = 0.5 * p
    return VirtualArray(half, half.copy(), np.zeros(nx * ny, dtype=int), (int(nx), int(ny)),
                        name=f"virtual UPA {nx}x{ny}, spacing {spacing * 1e3:.3f} mm")


def tdm_mimo(tx_positions: np.ndarray, rx_positions: np.ndarray, *, name: str = "TDM MIMO",
             grid_shape: tuple[int, int] | None = None) -> VirtualArray:
    """Virtual channels of a physical TDM-MIMO layout.

    Parameters
    ----------
    tx_positions : ndarray, shape ``[tx, 3]``
        Physical transmit antennas in frame A [m]; fired one after another,
        tx 0 first.
    rx_positions : ndarray, shape ``[rx, 3]``
        Physical receive antennas in frame A [m].

    Returns
    -------
    VirtualArray
        ``tx * rx`` channels, tx major, rx minor; ``tx_slot`` = transmitter index.
    """
    tx = np.asarray(tx_positions, dtype=float)
    rx = np.asarray(rx_positions, dtype=float)
    if tx.ndim != 2 or tx.shape[1] != 3 or rx.ndim != 2 or rx.shape[1] != 3:
        raise ValueError(
            f"tx_positions and rx_positions must have shape [n, 3], got {tx.shape} and {rx.shape}"
        )
    n_tx, n_rx = tx.shape[0], rx.shape[0]
    return VirtualArray(
        np.repeat(tx, n_rx, axis=0), np.tile(rx, (n_tx, 1)), np.repeat(np.arange(n_tx), n_rx),
        grid_shape, name=name,
    )


def ti_3tx4rx(wavelength: float) -> VirtualArray:
    """TI AWR1843-style layout: 3 Tx, 4 Rx at lambda/2, the middle Tx raised by lambda/2.

    Gives an 8-element azimuth virtual row (Tx0, Tx2 slots) plus a 4-element row
    offset in elevation (Tx1). Channel order tx major, rx minor.
    """
    d = wavelength / 2.0
    rx = np.array([[i * d, 0.0, 0.0] for i in range(4)])
    tx = np.array([[0.0, 0.0, 0.0], [2 * d, d, 0.0], [4 * d, 0.0, 0.0]])
    return tdm_mimo(tx, rx, name="TI-style 3Tx x 4Rx TDM MIMO")
