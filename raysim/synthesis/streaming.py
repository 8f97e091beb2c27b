"""Frame-by-frame, chirp-block-by-chirp-block rendering with bounded memory.

:func:`render_stream` asks a *source* for the paths of one frame, synthesises
``chirp_block`` chirps at a time with :func:`raysim.synthesis.select.synthesize`
and hands each block to a *writer* as soon as it is done. Nothing of size
``[frame, chirp, channel, sample]`` is ever held; with a compact
:class:`~raysim.synthesis.nufft.PathDelays` source the delays are never held at
``[path, chirp, channel]`` size either.

Peak memory (see :func:`peak_bytes`) is the paths of one frame, one chirp
block of output, the NUFFT accumulator ``[channel, sample]`` in complex128 and
:data:`raysim.synthesis.nufft.BLOCK_BYTES` of temporaries per thread, plus
what the writer keeps: nothing for :class:`NpyWriter` (a memory-mapped
``.npy`` file), one frame cube for :class:`FrameWriter`. For the paper frame
(256 x 400 x 600, 491 MB complex64) and 1e5 paths that is about 1.35 x one
cube including the writer's frame; ``raysim bench`` measures it.

Long renders show a progress bar on stderr (tqdm), one step per chirp block.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from raysim.radar.config import RadarConfig
from raysim.synthesis.nufft import BLOCK_BYTES, PathDelays, as_source, check_eps, default_threads
from raysim.synthesis.select import METHODS, choose_method, synthesize

#: ``writer(frame, first_chirp, block)`` with ``block`` of shape ``[chirp, channel, sample]``.
Writer = Callable[[int, int, np.ndarray], None]


@dataclass(frozen=True)
class StreamStats:
    """What :func:`render_stream` did.

    Attributes
    ----------
    frames : int
        Frames rendered.
    chirp_blocks : int
        Blocks handed to the writer.
    seconds : float
        Wall time of the whole render [s].
    synthesis_seconds : float
        Time spent in synthesis [s] (the rest is the source and the writer).
    method : str
        Synthesis method used for the first frame (``"auto"`` resolved).
    peak_bytes_estimate : int
        :func:`peak_bytes` for this render, writer excluded [bytes].
    """

    frames: int
    chirp_blocks: int
    seconds: float
    synthesis_seconds: float
    method: str
    peak_bytes_estimate: int


def peak_bytes(num_paths: int, num_channels: int, num_samples: int, *, chirp_block: int,
               threads: int = 1, path_bytes: int = 0) -> int:
    """Upper estimate of the renderer's working memory, writer excluded [bytes].

    ``path_bytes`` (the source's own arrays) + one complex64 chirp block + one
    complex128 ``[channel, sample]`` accumulator + ``min(BLOCK_BYTES,
    64 B * path * channel)`` per thread + the per-chirp vertex cache of a
    :class:`~raysim.synthesis.nufft.PathDelays` (at most 256 B per path).
    """
    block = chirp_block * num_channels * num_samples * 8
    acc = num_channels * num_samples * 16
    temps = threads * min(BLOCK_BYTES, 64 * num_paths * num_channels)
    return int(path_bytes + block + acc + temps + 256 * num_paths)


def render_stream(source: Callable[[int], object], config: RadarConfig, writer: Writer, *,
                  frames: int | Iterable[int] = 1, chirp_block: int = 16,
                  method: str = "auto", eps: float = 1e-6, threads: int | None = None,
                  progress: bool = True, desc: str = "render") -> StreamStats:
    """Render frames block by block, handing every chirp block to ``writer``.

    Parameters
    ----------
    source : callable
        ``source(frame)`` returns the paths of that frame: a
        :class:`~raysim.synthesis.nufft.PathDelays`, or a tuple
        ``(tau, amplitude)`` with ``tau`` of shape ``[path, chirp, channel]`` [s].
    config : RadarConfig
    writer : callable
        ``writer(frame, first_chirp, block)``; ``block`` has shape
        ``[chirp, channel, sample]`` and is reused after the call returns (copy
        it to keep it).
    frames : int or iterable of int
        Number of frames (``0 .. frames-1``) or the frame indices.
    chirp_block : int
        Chirps per block (>= 1).
    method : {"auto", "nufft", "tones", "direct"}
    eps : float
        Requested relative error (see :func:`raysim.synthesis.select.synthesize`).
    threads : int, optional
        NUFFT threads (default: usable CPUs).
    progress : bool
        Show a tqdm progress bar on stderr.
    desc : str
        Label of the progress bar.

    Returns
    -------
    StreamStats
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    check_eps(eps, floor=np.finfo(float).eps)
    if isinstance(chirp_block, bool) or not isinstance(chirp_block, (int, np.integer)) \
            or chirp_block < 1:
        raise ValueError(f"chirp_block must be a positive integer, got {chirp_block!r}")
    if isinstance(frames, (int, np.integer)):
        if frames < 1:
            raise ValueError(f"frames must be >= 1, got {frames!r}")
        frames = range(int(frames))
    frames = list(frames)
    if not frames:
        raise ValueError("frames is empty")
    if not callable(writer):
        raise ValueError(f"writer must be callable, got {writer!r}")
    n_chirp = config.num_chirps
    n_blocks = -(-n_chirp // chirp_block)
    threads = default_threads() if threads is None else int(threads)
    from tqdm.auto import tqdm

    bar = tqdm(total=len(frames) * n_blocks, unit="block", file=sys.stderr,
               disable=not progress, desc=desc, dynamic_ncols=True)
    t_start = time.perf_counter()
    t_synth = 0.0
    used_method = None
    peak = 0
    buf = None
    try:
        for f in frames:
            paths = source(f)
            if isinstance(paths, PathDelays):
                src, amp = paths, None
            else:
                try:
                    src, amp = paths
                except (TypeError, ValueError):
                    raise ValueError("source(frame) must return a PathDelays or a "
                                     f"(tau, amplitude) tuple, got {type(paths).__name__}"
                                     ) from None
            wrapped = as_source(src, amp)
            if wrapped.num_chirps != n_chirp:
                raise ValueError(f"source gave {wrapped.num_chirps} chirps for frame {f}, "
                                 f"config.num_chirps is {n_chirp}")
            m = method if method != "auto" else choose_method(
                wrapped.num_paths, n_chirp, wrapped.num_channels, config.num_samples, eps,
                compact=isinstance(wrapped, PathDelays))
            used_method = used_method or m
            dtype = np.complex128 if m == "direct" else np.complex64
            shape = (chirp_block, wrapped.num_channels, config.num_samples)
            if buf is None or buf.shape != shape or buf.dtype != dtype:
                buf = np.empty(shape, dtype=dtype)
            path_bytes = (paths.nbytes if isinstance(paths, PathDelays)
                          else int(wrapped.tau.nbytes + np.asarray(amp).nbytes))
            peak = max(peak, peak_bytes(wrapped.num_paths, wrapped.num_channels,
                                        config.num_samples, chirp_block=chirp_block,
                                        threads=threads, path_bytes=path_bytes))
            bar.set_postfix(frame=f, method=m, refresh=False)
            for n0 in range(0, n_chirp, chirp_block):
                chirps = range(n0, min(n0 + chirp_block, n_chirp))
                block = buf[: len(chirps)]
                block[...] = 0.0
                t0 = time.perf_counter()
                synthesize(src, amp, config, method=m, eps=eps, out=block, chirps=chirps,
                           threads=threads)
                t_synth += time.perf_counter() - t0
                writer(f, n0, block)
                bar.update(1)
    finally:
        bar.close()
    return StreamStats(len(frames), len(frames) * n_blocks, time.perf_counter() - t_start,
                       t_synth, used_method, peak)


class FrameWriter:
    """Writer that assembles whole frames and passes each to ``on_frame``.

    Holds one ``[chirp, channel, sample]`` cube, reused from frame to frame.

    Parameters
    ----------
    on_frame : callable
        ``on_frame(frame, cube)``, called when a frame's last chirp arrives;
        ``cube`` is reused afterwards (copy it to keep it).
    num_chirps : int
        Chirps per frame.
    """

    def __init__(self, on_frame: Callable[[int, np.ndarray], None], num_chirps: int) -> None:
        if not callable(on_frame):
            raise ValueError(f"on_frame must be callable, got {on_frame!r}")
        if int(num_chirps) < 1:
            raise ValueError(f"num_chirps must be >= 1, got {num_chirps!r}")
        self.on_frame = on_frame
        self.num_chirps = int(num_chirps)
        self.cube: np.ndarray | None = None

    def __call__(self, frame: int, first_chirp: int, block: np.ndarray) -> None:
        shape = (self.num_chirps,) + block.shape[1:]
        if self.cube is None or self.cube.shape != shape or self.cube.dtype != block.dtype:
            self.cube = np.empty(shape, dtype=block.dtype)
        n1 = first_chirp + block.shape[0]
        if n1 > self.num_chirps:
            raise ValueError(f"block ends at chirp {n1}, beyond num_chirps={self.num_chirps}")
        self.cube[first_chirp:n1] = block
        if n1 == self.num_chirps:
            self.on_frame(frame, self.cube)


def render_frames(source: Callable[[int], object], config: RadarConfig,
                  on_frame: Callable[[int, np.ndarray], None], **kwargs) -> StreamStats:
    """:func:`render_stream` with whole frames delivered to ``on_frame(frame, cube)``.

    ``cube`` has shape ``[chirp, channel, sample]``; memory is one cube more than
    :func:`render_stream`. Keyword arguments go to :func:`render_stream`.
    """
    return render_stream(source, config, FrameWriter(on_frame, config.num_chirps), **kwargs)


class NpyWriter:
    """Writer into a memory-mapped ``.npy`` file of shape ``[frame, chirp, channel, sample]``.

    Frame ``f`` of the render goes to index ``f - first_frame``. The file is
    flushed after every frame's last block, so an interrupted render keeps the
    finished frames.

    Parameters
    ----------
    path : str or Path
        Output ``.npy`` file (overwritten).
    num_frames, num_chirps, num_channels, num_samples : int
        Shape of the stored array.
    dtype : numpy dtype
        complex64 by default.
    first_frame : int
        Frame index stored at position 0.
    """

    def __init__(self, path, num_frames: int, num_chirps: int, num_channels: int,
                 num_samples: int, *, dtype=np.complex64, first_frame: int = 0) -> None:
        shape = (int(num_frames), int(num_chirps), int(num_channels), int(num_samples))
        if min(shape) < 1:
            raise ValueError(f"array shape must be positive, got {shape}")
        self.path = Path(path)
        self.first_frame = int(first_frame)
        self.array = np.lib.format.open_memmap(self.path, mode="w+", dtype=dtype, shape=shape)

    def __call__(self, frame: int, first_chirp: int, block: np.ndarray) -> None:
        i = frame - self.first_frame
        if not 0 <= i < self.array.shape[0]:
            raise ValueError(f"frame {frame} outside the stored frames "
                             f"[{self.first_frame}, {self.first_frame + self.array.shape[0]})")
        n1 = first_chirp + block.shape[0]
        self.array[i, first_chirp:n1] = block
        if n1 == self.array.shape[1]:
            self.array.flush()
