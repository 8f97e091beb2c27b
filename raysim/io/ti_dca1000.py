"""TI mmWave DCA1000 raw ADC captures (``adc_data.bin``): reader and writer.

A DCA1000EVM capture, once mmWave Studio (or the DCA1000 CLI post-processing)
has stripped the UDP packet headers, is a flat little-endian ``int16`` stream
without a file header. Its layout depends on how many LVDS lanes the radar
device drives and on the ADC output format. Two layouts are supported:

``layout="2lane"`` (xWR16xx, xWR18xx, xWR68xx: two LVDS lanes)
    Chirps follow each other; inside a chirp the receivers follow each other
    (``rx0`` block, ``rx1`` block, ...), each block holding ``num_samples``
    samples.

    * complex: within a block, samples come in pairs written as two in-phase
      values followed by the two quadrature values::

          I0 I1 Q0 Q1 I2 I3 Q2 Q3 ...

      so ``num_samples`` must be even.
    * real: the block is ``x0 x1 x2 ...``.

``layout="4lane"`` (xWR12xx, xWR14xx: four LVDS lanes, one per receiver)
    Samples are interleaved across the four lanes; lane ``r`` carries
    receiver ``r`` and lanes of disabled receivers are zero-filled (the file
    always has four lanes, ``num_rx`` only selects how many are returned).

    * complex: for each sample the four in-phase values, then the four
      quadrature values::

          I(rx0,s0) I(rx1,s0) I(rx2,s0) I(rx3,s0) Q(rx0,s0) Q(rx1,s0) Q(rx2,s0) Q(rx3,s0)
          I(rx0,s1) ...

    * real: ``x(rx0,s0) x(rx1,s0) x(rx2,s0) x(rx3,s0) x(rx0,s1) ...``.

These are the layouts unpacked by TI's ``readDCA1000`` MATLAB scripts for
the two device families (mmWave Studio user guide; TI application note
SWRA581, "Mmwave Radar Device ADC Raw Data Capture"). What decides the layout
is the LVDS lane configuration of the capture, not the part number alone:
xWR18xx parts such as the AWR1843 are normally captured over two lanes and
then use ``"2lane"``. Files that still contain the raw UDP packet headers
(``adc_data_Raw_0.bin`` from a DCA1000 CLI capture before post-processing)
are not supported.

Chirp order (TDM MIMO): the file holds frames, each frame ``num_loops`` loops,
each loop one ramp per transmit slot in chirp-configuration order::

    frame 0: loop 0 (tx slot 0, 1, ..., num_tx-1), loop 1 (...), ...
    frame 1: ...

The reader returns a cube ``[frame, chirp, channel, sample]`` (``chirp`` = loop
index, ``channel = tx_slot * num_rx + rx``: tx major, rx minor, as in
docs/conventions.md) and the start time of every ramp,
``chirp_time[frame, chirp, tx_slot] = t0 + frame * frame_period
+ (chirp * num_tx + tx_slot) * slot_interval``.

The format need not be typed by hand: :func:`raysim.io.mmwave_config.read_mmwave_config`
builds it (with the waveform and the virtual array) from the radar's mmWave SDK
``.cfg`` or mmWave Studio JSON configuration.

ADC words narrower than 16 bit (``adc_bits`` 12 or 14) are sign-extended as
in TI's scripts: a value above ``2**(adc_bits-1) - 1`` becomes
``value - 2**adc_bits``.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Literal

import numpy as np

__all__ = ["Dca1000Format", "Dca1000Capture", "parse_dca1000", "read_dca1000",
           "write_dca1000", "check_capture_fits", "LAYOUTS"]

#: Supported LVDS layouts.
LAYOUTS = ("2lane", "4lane")
_INT16 = np.dtype("<i2")
_FOUR_LANES = 4


def _positive_int(name: str, value, lo: int = 1, hi: int | None = None) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise ValueError(f"{name} must be an integer, got {value!r}")
    if value < lo or (hi is not None and value > hi):
        rng = f"{lo}..{hi}" if hi is not None else f">= {lo}"
        raise ValueError(f"{name} must be in {rng}, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class Dca1000Format:
    """Binary layout and timing of a DCA1000 capture.

    Parameters
    ----------
    num_samples : int
        ADC samples per chirp (``numAdcSamples``).
    slot_interval : float
        Ramp repetition interval ``idle + ramp end time`` of one transmit slot
        [s] (the TI profile's ``idleTime + rampEndTime``).
    num_rx : int
        Enabled receivers, 1..4.
    num_tx : int
        TDM transmit slots per loop (chirps from ``chirpStartIdx`` to
        ``chirpEndIdx``), 1..4 (TI single-chip devices have three or four TX).
    num_loops : int
        Loops per frame (``numLoops``): the length of the cube ``chirp`` axis.
    layout : {"2lane", "4lane"}
        LVDS layout (module docstring).
    complex : bool
        Complex (I/Q) samples if True, real-only samples otherwise.
    frame_period : float or None
        Frame start-to-start interval [s]; None means frames are contiguous
        (``num_loops * num_tx * slot_interval``).
    t0 : float
        Start time of the first ramp of frame 0 [s].
    adc_bits : int
        ADC word width (12, 14 or 16); narrower words are sign-extended.
    """

    num_samples: int
    slot_interval: float
    num_rx: int = 4
    num_tx: int = 1
    num_loops: int = 1
    layout: Literal["2lane", "4lane"] = "2lane"
    complex: bool = True
    frame_period: float | None = None
    t0: float = 0.0
    adc_bits: int = 16

    def __post_init__(self) -> None:
        _positive_int("num_samples", self.num_samples)
        _positive_int("num_rx", self.num_rx, 1, 4)
        _positive_int("num_tx", self.num_tx, 1, 4)
        _positive_int("num_loops", self.num_loops)
        if self.layout not in LAYOUTS:
            raise ValueError(f"layout must be one of {LAYOUTS}, got {self.layout!r}")
        if not isinstance(self.complex, (bool, np.bool_)):
            raise ValueError(f"complex must be True or False, got {self.complex!r}")
        if self.adc_bits not in (12, 14, 16):
            raise ValueError(f"adc_bits must be 12, 14 or 16, got {self.adc_bits!r}")
        if self.layout == "2lane" and self.complex and self.num_samples % 2:
            raise ValueError(
                f"the 2-lane complex layout stores samples in I/Q pairs, so num_samples must "
                f"be even, got {self.num_samples}")
        si = float(self.slot_interval)
        if not math.isfinite(si) or si <= 0:
            raise ValueError(f"slot_interval must be a finite positive number of seconds, "
                             f"got {self.slot_interval!r}")
        object.__setattr__(self, "slot_interval", si)
        if not math.isfinite(float(self.t0)):
            raise ValueError(f"t0 must be finite, got {self.t0!r}")
        if self.frame_period is not None:
            fp = float(self.frame_period)
            if not math.isfinite(fp) or fp < self.frame_duration * (1 - 1e-12):
                raise ValueError(
                    f"frame_period {self.frame_period!r} s must be finite and at least one "
                    f"frame of chirps ({self.frame_duration!r} s = num_loops * num_tx * "
                    f"slot_interval)")
            object.__setattr__(self, "frame_period", fp)

    @classmethod
    def from_radar_config(cls, config, num_rx: int, *, layout: str = "2lane",
                          t0: float = 0.0, adc_bits: int = 16) -> Dca1000Format:
        """Format matching a :class:`raysim.radar.config.RadarConfig`.

        ``num_samples``, ``num_tx`` (``num_tx_slots``), ``num_loops``
        (``num_chirps``), ``slot_interval``, ``frame_period`` and ``complex``
        are taken from ``config``.
        """
        return cls(num_samples=config.num_samples, slot_interval=config.slot_interval,
                   num_rx=num_rx, num_tx=config.num_tx_slots, num_loops=config.num_chirps,
                   layout=layout, complex=bool(config.complex_sampling),
                   frame_period=config.frame_period, t0=t0, adc_bits=adc_bits)

    # ---------------------------------------------------------------- sizes
    @property
    def num_channels(self) -> int:
        """Virtual channels ``num_tx * num_rx``."""
        return self.num_tx * self.num_rx

    @property
    def num_lanes(self) -> int:
        """Receiver slots stored per chirp: ``num_rx`` (2-lane) or always 4 (4-lane)."""
        return self.num_rx if self.layout == "2lane" else _FOUR_LANES

    @property
    def words_per_chirp(self) -> int:
        """``int16`` words of one ramp (one tx slot)."""
        return self.num_lanes * self.num_samples * (2 if self.complex else 1)

    @property
    def words_per_frame(self) -> int:
        """``int16`` words of one frame."""
        return self.words_per_chirp * self.num_tx * self.num_loops

    @property
    def bytes_per_frame(self) -> int:
        """Bytes of one frame."""
        return 2 * self.words_per_frame

    @property
    def frame_duration(self) -> float:
        """Duration of the ramps of one frame ``num_loops num_tx slot_interval`` [s]."""
        return self.num_loops * self.num_tx * self.slot_interval

    @property
    def frame_interval(self) -> float:
        """Frame start-to-start interval [s]."""
        return self.frame_duration if self.frame_period is None else self.frame_period

    def describe_frame(self) -> str:
        """Human-readable breakdown of the frame size."""
        iq = "2 int16 (I, Q)" if self.complex else "1 int16"
        return (f"{self.num_loops} loops x {self.num_tx} tx x {self.num_lanes} lanes x "
                f"{self.num_samples} samples x {iq} x 2 bytes = {self.bytes_per_frame} bytes")

    def chirp_times(self, num_frames: int, first_frame: int = 0) -> np.ndarray:
        """Ramp start times of frames ``first_frame ...``, shape ``[frame, chirp, tx_slot]`` [s]."""
        f = (first_frame + np.arange(num_frames))[:, None, None] * self.frame_interval
        slot = (np.arange(self.num_loops)[None, :, None] * self.num_tx
                + np.arange(self.num_tx)[None, None, :])
        return float(self.t0) + f + slot * self.slot_interval


@dataclass(frozen=True, eq=False)
class Dca1000Capture:
    """A parsed DCA1000 capture.

    Attributes
    ----------
    cube : ndarray of complex64, shape ``[frame, chirp, channel, sample]``
        ADC samples in ADC counts; ``channel = tx_slot * num_rx + rx``. Real
        captures have a zero imaginary part.
    chirp_time : ndarray, shape ``[frame, chirp, tx_slot]``
        Start time of each ramp [s]; channel ``c`` of slow-time step ``n`` was
        sampled on the ramp starting at ``chirp_time[f, n, c // num_rx]``.
    fmt : Dca1000Format
        Layout and timing the capture was read with.
    path : str
        Source file ("" for in-memory data).
    """

    cube: np.ndarray
    chirp_time: np.ndarray
    fmt: Dca1000Format
    path: str = ""

    @property
    def num_frames(self) -> int:
        """Number of frames."""
        return int(self.cube.shape[0])

    @property
    def channel_tx(self) -> np.ndarray:
        """Transmit slot of each channel, shape ``[channel]``."""
        return np.repeat(np.arange(self.fmt.num_tx), self.fmt.num_rx)

    @property
    def channel_rx(self) -> np.ndarray:
        """Receiver of each channel, shape ``[channel]``."""
        return np.tile(np.arange(self.fmt.num_rx), self.fmt.num_tx)


def _check_format(fmt) -> Dca1000Format:
    if not isinstance(fmt, Dca1000Format):
        raise ValueError(f"fmt must be a Dca1000Format, got {type(fmt).__name__}")
    return fmt


def _count_frames(n_words: int, fmt: Dca1000Format, drop_incomplete: bool, where: str) -> int:
    n_frames, extra = divmod(n_words, fmt.words_per_frame)
    if extra and not drop_incomplete:
        raise ValueError(
            f"{where}capture holds {2 * n_words} bytes, which is not a whole number of "
            f"frames of {fmt.bytes_per_frame} bytes ({fmt.describe_frame()}): "
            f"{n_frames} complete frame(s) and {2 * extra} bytes left over. The capture is "
            f"truncated or the format does not match; pass drop_incomplete=True to keep the "
            f"complete frames")
    if n_frames == 0:
        raise ValueError(
            f"{where}capture holds {2 * n_words} bytes, less than one frame of "
            f"{fmt.bytes_per_frame} bytes ({fmt.describe_frame()})")
    return n_frames


def check_capture_fits(path: str | os.PathLike, fmt: Dca1000Format,
                       num_frames: int = 0, drop_incomplete: bool = False) -> int:
    """Refuse a capture whose size or content does not fit the lanes and format; its frames.

    Checks, each refusal naming the sizes:

    * the size is a whole number of frames of ``fmt`` (and, where the other
      layout fits instead, says so);
    * with ``num_frames`` > 0 (the configuration's ``numFrames``), a size that
      is exactly ``num_frames`` frames of the *other* layout and not of this
      one (a 2-lane capture of fewer than 4 receivers read as 4-lane, or the
      reverse);
    * 4-lane with fewer than 4 receivers: the lanes of the disabled receivers
      of the first frame must hold zeros (the DCA1000 zero-fills them).

    With 4 receivers the two layouts have the same size and no zero lanes:
    the lane count must then come from the board (:mod:`raysim.io.ti_boards`)
    or the Studio JSON's lane mask.

    Parameters
    ----------
    path : str or path-like
        The capture.
    fmt : Dca1000Format
    num_frames : int
        Frames the configuration asks for (0: until stopped, not checked).
    drop_incomplete : bool
        Accept a capture that ends inside a frame (stopped by hand) and count
        its whole frames; still refused where the other layout fits it whole.

    Returns
    -------
    int
        Whole frames in the capture.

    Raises
    ------
    ValueError
        The capture does not fit (message names file size, frame size and
        the layouts).
    """
    fmt = _check_format(fmt)
    path = Path(path)
    size = path.stat().st_size
    other = replace(fmt, layout="4lane" if fmt.layout == "2lane" else "2lane")
    total, extra = divmod(size, fmt.bytes_per_frame)
    o_total, o_extra = divmod(size, other.bytes_per_frame)
    hint = (f"; it is {o_total} whole frame(s) of the {other.layout} layout "
            f"({other.bytes_per_frame} bytes: {other.describe_frame()})"
            if o_total and not o_extra and other.bytes_per_frame != fmt.bytes_per_frame else "")
    if total == 0 or (extra and (hint or not drop_incomplete)):
        remedy = ("" if hint or total == 0 or drop_incomplete else
                  f"; a capture stopped inside a frame keeps its {total} whole frame(s) with "
                  f"--drop-incomplete")
        raise ValueError(f"{path}: the capture holds {size} bytes, not a whole number of "
                         f"frames of {fmt.bytes_per_frame} bytes ({fmt.layout}: "
                         f"{fmt.describe_frame()}){hint}{remedy}")
    if (num_frames > 0 and total != num_frames and o_total == num_frames and not o_extra
            and other.bytes_per_frame != fmt.bytes_per_frame):
        raise ValueError(f"{path}: the capture holds {size} bytes = {num_frames} frames of the "
                         f"{other.layout} layout ({other.bytes_per_frame} bytes), the "
                         f"configuration's numFrames, but {total} frames of the {fmt.layout} "
                         f"layout asked for ({fmt.bytes_per_frame} bytes); the capture is "
                         f"{other.layout}: give that layout (--layout {other.layout})")
    if fmt.layout == "4lane" and fmt.num_rx < _FOUR_LANES:
        words = np.fromfile(path, dtype=_INT16, count=fmt.words_per_frame)
        lanes = words.reshape(-1, _FOUR_LANES)[:, fmt.num_rx:]
        if np.any(lanes != 0):
            raise ValueError(f"{path}: read as 4-lane with {fmt.num_rx} receiver(s), the lanes "
                             f"of the disabled receivers ({_FOUR_LANES - fmt.num_rx} of 4) hold "
                             f"{int(np.count_nonzero(lanes))} non-zero words in frame 0 of "
                             f"{fmt.bytes_per_frame} bytes; a 4-lane capture zero-fills them: "
                             f"the capture is not 4-lane (try --layout 2lane)")
    return total


def parse_dca1000(words, fmt: Dca1000Format, *, drop_incomplete: bool = False,
                  path: str = "", first_frame: int = 0) -> Dca1000Capture:
    """Unpack a DCA1000 ``int16`` stream.

    Parameters
    ----------
    words : array_like of int16, shape ``[word]``
        The capture as read from the file.
    fmt : Dca1000Format
        Layout and timing.
    drop_incomplete : bool
        Drop a trailing partial frame instead of raising.
    path : str
        Source file, used in messages and stored in the result.
    first_frame : int
        Index of the first frame in ``words`` within the capture (sets the
        time stamps).

    Returns
    -------
    Dca1000Capture

    Raises
    ------
    ValueError
        If the stream is not a whole number of frames (truncated capture or
        wrong format) or holds no complete frame.
    """
    fmt = _check_format(fmt)
    first_frame = _positive_int("first_frame", first_frame, lo=0)
    words = np.asarray(words)
    if words.ndim != 1 or words.dtype.kind not in "iu":
        raise ValueError(f"words must be a 1-D integer array, got {words.dtype} {words.shape}")
    n_frames = _count_frames(words.size, fmt, drop_incomplete, f"{path}: " if path else "")
    w = words[: n_frames * fmt.words_per_frame].astype(np.int32)
    if fmt.adc_bits < 16:
        w = np.where(w > 2 ** (fmt.adc_bits - 1) - 1, w - 2 ** fmt.adc_bits, w)
    shape = (n_frames, fmt.num_loops, fmt.num_tx)
    k, r = fmt.num_samples, fmt.num_rx
    if fmt.layout == "2lane":
        if fmt.complex:
            q = w.reshape(shape + (r, k // 2, 2, 2))  # [..., rx, pair, I/Q, member]
            re = q[..., 0, :].reshape(shape + (r, k))
            im = q[..., 1, :].reshape(shape + (r, k))
        else:
            re = w.reshape(shape + (r, k))
            im = None
    else:
        if fmt.complex:
            q = w.reshape(shape + (k, 2, _FOUR_LANES))  # [..., sample, I/Q, lane]
            re = np.moveaxis(q[..., 0, :r], -1, -2)
            im = np.moveaxis(q[..., 1, :r], -1, -2)
        else:
            q = w.reshape(shape + (k, _FOUR_LANES))
            re = np.moveaxis(q[..., :r], -1, -2)
            im = None
    cube = np.empty(shape + (r, k), dtype=np.complex64)
    cube.real = re
    cube.imag = 0.0 if im is None else im
    cube = cube.reshape(n_frames, fmt.num_loops, fmt.num_channels, k)
    return Dca1000Capture(cube=cube, chirp_time=fmt.chirp_times(n_frames, first_frame), fmt=fmt,
                          path=path)


def read_dca1000(path: str | os.PathLike, fmt: Dca1000Format, *,
                 drop_incomplete: bool = False, frames: slice | None = None) -> Dca1000Capture:
    """Read a DCA1000 capture file.

    Parameters
    ----------
    path : str or path-like
        Headerless ``int16`` capture (``adc_data.bin``).
    fmt : Dca1000Format
        Layout and timing (module docstring).
    drop_incomplete : bool
        Drop a trailing partial frame instead of raising.
    frames : slice or None
        Frames to load (step 1), e.g. ``slice(10, 20)``; only those bytes are
        read (memory-mapped). None loads all frames.

    Returns
    -------
    Dca1000Capture
        ``cube [frame, chirp, channel, sample]`` complex64 and
        ``chirp_time [frame, chirp, tx_slot]`` [s].

    Raises
    ------
    ValueError
        If the file size is not a whole number of frames (message names the
        file size, the frame size and its breakdown) or is odd.

    Examples
    --------
    >>> fmt = Dca1000Format(num_samples=256, slot_interval=60e-6, num_rx=4, num_tx=3,
    ...                     num_loops=128)  # doctest: +SKIP
    >>> cap = read_dca1000("adc_data.bin", fmt)  # doctest: +SKIP
    >>> cap.cube.shape  # doctest: +SKIP
    (n_frames, 128, 12, 256)
    """
    fmt = _check_format(fmt)
    path = Path(path)
    size = path.stat().st_size
    if size % 2:
        raise ValueError(f"{path}: size {size} bytes is odd; a DCA1000 capture is a stream of "
                         f"2-byte int16 words (truncated capture?)")
    if frames is None:
        words = np.fromfile(path, dtype=_INT16)
        return parse_dca1000(words, fmt, drop_incomplete=drop_incomplete, path=str(path))
    if not isinstance(frames, slice) or frames.step not in (None, 1):
        raise ValueError(f"frames must be a slice with step 1 or None, got {frames!r}")
    total = _count_frames(size // 2, fmt, drop_incomplete, f"{path}: ")
    start, stop, _ = frames.indices(total)
    if stop <= start:
        raise ValueError(f"{path}: frames={frames!r} selects no frame of the {total} in the "
                         f"capture")
    words = np.memmap(path, dtype=_INT16, mode="r", offset=start * fmt.bytes_per_frame,
                      shape=((stop - start) * fmt.words_per_frame,))
    try:
        return parse_dca1000(np.array(words), fmt, path=str(path), first_frame=start)
    finally:
        del words


def write_dca1000(path: str | os.PathLike, cube, fmt: Dca1000Format) -> Path:
    """Write a cube as a DCA1000 capture in ``fmt``'s layout.

    Parameters
    ----------
    path : str or path-like
        Output file (replaced atomically: written to a temporary file in the
        same folder, then renamed, so an interrupted write leaves any previous
        file untouched and no partial file).
    cube : array_like, shape ``[frame, chirp, channel, sample]``
        Samples in ADC counts, channel order tx major, rx minor. Values are
        rounded to the nearest integer; a round trip is exact for integer-valued
        data inside the ADC range. Real layouts need a zero imaginary part.
    fmt : Dca1000Format
        Layout (``num_loops``, ``num_rx``, ``num_tx``, ``num_samples`` must
        match the cube).

    Returns
    -------
    pathlib.Path
        The written file.

    Raises
    ------
    ValueError
        On a shape mismatch, non-finite values, values outside the
        ``adc_bits`` range, or a non-zero imaginary part with a real layout.
    """
    fmt = _check_format(fmt)
    cube = np.asarray(cube)
    want = (fmt.num_loops, fmt.num_channels, fmt.num_samples)
    if cube.ndim != 4 or cube.shape[1:] != want or cube.shape[0] < 1:
        raise ValueError(f"cube must have shape [frame, chirp, channel, sample] = "
                         f"[frame >= 1, {want[0]}, {want[1]}, {want[2]}], got {cube.shape}")
    if not np.all(np.isfinite(cube)):
        raise ValueError("cube values must be finite")
    re = np.rint(cube.real)
    im = np.rint(cube.imag) if np.iscomplexobj(cube) else np.zeros_like(re)
    if not fmt.complex and np.any(im != 0):
        raise ValueError("a real-only layout cannot store a non-zero imaginary part")
    lo, hi = -(2 ** (fmt.adc_bits - 1)), 2 ** (fmt.adc_bits - 1) - 1
    for part in (re, im):
        if part.size and (part.min() < lo or part.max() > hi):
            raise ValueError(f"cube values must lie in the {fmt.adc_bits}-bit ADC range "
                             f"[{lo}, {hi}], got [{part.min()}, {part.max()}]")
    n = cube.shape[0]
    shape = (n, fmt.num_loops, fmt.num_tx, fmt.num_rx, fmt.num_samples)
    re = re.reshape(shape).astype(np.int32)
    im = im.reshape(shape).astype(np.int32)
    if fmt.adc_bits < 16:  # store as unsigned adc_bits words (inverse of sign extension)
        re = np.where(re < 0, re + 2 ** fmt.adc_bits, re)
        im = np.where(im < 0, im + 2 ** fmt.adc_bits, im)
    k, r = fmt.num_samples, fmt.num_rx
    if fmt.layout == "2lane":
        if fmt.complex:
            out = np.stack([re.reshape(shape[:-1] + (k // 2, 2)),
                            im.reshape(shape[:-1] + (k // 2, 2))], axis=-2)
        else:
            out = re
    else:
        lanes = np.zeros(shape[:3] + (k, 2 if fmt.complex else 1, _FOUR_LANES), np.int32)
        lanes[..., 0, :r] = np.moveaxis(re, -2, -1)
        if fmt.complex:
            lanes[..., 1, :r] = np.moveaxis(im, -2, -1)
        out = lanes
    from raysim.io.storage import atomic_write

    words = np.ascontiguousarray(out, dtype=np.int32).astype(_INT16)
    return atomic_write(path, lambda tmp: words.tofile(tmp))
