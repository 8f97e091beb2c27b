"""Sizing of a ``raysim compensate`` job, before anything large is allocated.

A compensated output holds ``frames x chirps x cells x azimuths x
elevations`` complex64 beams; the user guide's one-frame example with the
default grid (121 x 121 beams) and every range cell of the paper case would
be 16.8 GiB. :func:`job_bytes` estimates the peak memory of the whole job
from its dimensions; :func:`choose_range_window` picks the range cells when
``--range-m`` is not given: the whole window when the job fits
:data:`AUTO_BUDGET_BYTES`, else the cells around the strongest return that
fit; :func:`check_job` refuses a job that does not fit the memory available
now (or the disk), naming the size and the settings to reduce, and announces
a large output. :func:`gated_range_compress` range-compresses a frame chirp
block by chirp block and keeps only the cells compensated, so the full
range-compressed frame is never held.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import numpy as np

from raysim.processing.maps import range_compress
from raysim.resources import (
    LARGE_OUTPUT_BYTES,
    available_memory,
    check_memory,
    format_bytes,
    free_disk,
)

__all__ = ["AUTO_BUDGET_BYTES", "BEAM_CELL_BYTES", "job_bytes", "output_bytes",
           "choose_range_window", "check_job", "gated_range_compress", "range_profile"]

#: Estimated peak of a job whose range window is chosen automatically [bytes]; with the
#: interpreter and its libraries the process stays within 2 GB of RAM.
AUTO_BUDGET_BYTES = 1200 << 20
#: Memory per beam cell (chirp, range, azimuth, elevation) of the frame being projected
#: and written, beyond its complex64 beams: the projection's and the Doppler FFT's
#: temporaries and the copies made when writing (measured: 20 bytes a cell in all for one
#: frame of the paper case) [bytes].
BEAM_CELL_BYTES = 12
#: Chirps range-compressed at once by :func:`gated_range_compress`.
CHIRP_BLOCK = 16
#: Half-width of the default window around the strongest return [m].
AUTO_HALF_WIDTH_M = 1.0
#: Returns nearer than this are not taken as the strongest (leakage, the drone itself) [m].
AUTO_MIN_RANGE_M = 1.0


def output_bytes(frames: int, chirps: int, cells: int, beams: int) -> int:
    """Bytes of the written output: complex64 beams and float32 Doppler power."""
    return int(frames) * int(chirps) * int(cells) * int(beams) * 12


def job_bytes(frames: int, chirps: int, channels: int, samples: int, cells: int, beams: int,
              *, calibrating: bool = False) -> int:
    """Estimated peak memory of a compensation [bytes].

    Parameters
    ----------
    frames, chirps, channels, samples : int
        Input record: frames of ``[chirp, channel, sample]`` complex64.
    cells : int
        Range cells compensated.
    beams : int
        Beam directions (azimuths x elevations).
    calibrating : bool
        The clock offset or the velocity is estimated from the radar: every
        frame's full range-compressed cube is kept.
    """
    frame_in = int(chirps) * int(channels) * int(samples) * 8
    per_beam_frame = int(chirps) * int(cells) * int(beams)
    kept = frames * frame_in if calibrating else 0
    # one input frame and its block temporaries; every frame's complex64 beams kept for
    # the output, the temporaries of the frame being projected, the output's copies
    return int(frame_in * 1.25 + kept + per_beam_frame * (8 * frames + BEAM_CELL_BYTES)
               + (frames - 1) * per_beam_frame * 12)


def range_profile(frame: np.ndarray, n_cells: int) -> np.ndarray:
    """Power of each range cell summed over chirps and channels, shape ``[cell]``.

    ``frame`` is ``[chirp, channel, sample]``; computed chirp block by block.
    """
    power = np.zeros(n_cells)
    for c0 in range(0, frame.shape[0], CHIRP_BLOCK):
        rc = range_compress(np.asarray(frame[c0: c0 + CHIRP_BLOCK]))[..., :n_cells]
        power += np.sum(np.abs(rc) ** 2, axis=(0, 1))
    return power


def gated_range_compress(frame: np.ndarray, lo: int, hi: int) -> np.ndarray:
    """Range cells ``lo:hi`` of a frame's range compression, shape ``[chirp, channel, hi-lo]``.

    Equal to ``range_compress(frame)[..., lo:hi]`` (complex64), computed chirp
    block by chirp block.
    """
    out = np.empty(frame.shape[:2] + (hi - lo,), dtype=np.complex64)
    for c0 in range(0, frame.shape[0], CHIRP_BLOCK):
        block = np.asarray(frame[c0: c0 + CHIRP_BLOCK])
        out[c0: c0 + CHIRP_BLOCK] = range_compress(block)[..., lo:hi]
    return out


def choose_range_window(r_axis: np.ndarray, frame0, *, size, budget: int | None = None
                        ) -> tuple[np.ndarray, str | None]:
    """Range cells compensated when ``--range-m`` is not given.

    Parameters
    ----------
    r_axis : ndarray, shape ``[cell]``
        Ranges of the cells [m].
    frame0 : callable
        Returns the first frame ``[chirp, channel, sample]`` (read only when the
        whole window does not fit).
    size : callable
        ``size(cells) -> bytes``, the job's peak for that many cells.
    budget : int, optional
        Largest estimated peak [bytes]; default :data:`AUTO_BUDGET_BYTES`;
        never over 80 % of the memory available.

    Returns
    -------
    gates : ndarray of int
        Cell indices.
    note : str or None
        What was chosen and why, when it is not the whole window.
    """
    n = r_axis.size
    budget = min(AUTO_BUDGET_BYTES if budget is None else int(budget),
                 int(0.8 * available_memory()))
    if size(n) <= budget:
        return np.arange(n), None
    power = range_profile(frame0(), n)
    power[r_axis < AUTO_MIN_RANGE_M] = 0.0
    peak = int(np.argmax(power))
    fits = 1
    while fits < n and size(fits + 1) <= budget:
        fits += 1
    step = float(r_axis[1] - r_axis[0]) if n > 1 else 1.0
    half = min(int(AUTO_HALF_WIDTH_M / step), (fits - 1) // 2)
    lo, hi = max(0, peak - half), min(n, peak + half + 1)
    gates = np.arange(lo, hi)
    note = (f"--range-m not given: all {n} range cells would need about "
            f"{format_bytes(size(n))}; compensating the {gates.size} cell(s) "
            f"{r_axis[lo]:.2f} .. {r_axis[hi - 1]:.2f} m around the strongest return "
            f"({r_axis[peak]:.2f} m). Give --range-m LO:HI to choose the cells")
    return gates, note


def check_job(peak: int, out: Path, disk: int, what: str) -> None:
    """Refuse a job that does not fit the memory or the disk; announce a large output.

    Parameters
    ----------
    peak : int
        Estimated peak memory [bytes].
    out : Path
        The output (its disk is checked).
    disk : int
        Estimated output size [bytes].
    what : str
        The job, e.g. ``"beams [1, 256, 600, 121, 121]"``.
    """
    hint = "--range-m, the --az-deg / --el-deg grid (fewer or coarser angles) or --frames"
    check_memory(peak, f"compensate {what}", hint)
    free = free_disk(Path(os.path.abspath(out)).parent)
    if disk > free:
        raise ValueError(f"--out {str(out)!r}: compensate {what} would write about "
                         f"{format_bytes(disk)}, {format_bytes(free)} are free on its disk; "
                         f"expected an output that fits: reduce {hint}")
    if disk > LARGE_OUTPUT_BYTES or peak > available_memory() // 2:
        print(f"compensate: {what}, about {format_bytes(disk)} in {str(out)!r} "
              f"(peak memory about {format_bytes(peak)})", file=sys.stderr, flush=True)
