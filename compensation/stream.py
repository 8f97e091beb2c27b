"""Frames in, compensated beams out: the real-time chain as a radar runs it.

:class:`RealtimeStream` wraps one :class:`~compensation.realtime.RealtimeProjector`
(one geometry) and takes, frame after frame, the raw IF cube ``[chirp, channel,
sample]`` as the ADC delivers it and the platform's pose of every transmit slot
(a :class:`~compensation.strapdown.PlatformMotion`, or a callable returning one,
e.g. the strapdown of the frame's IMU samples). Per frame it

1. takes the range transform at the gated bins only
   (:meth:`RealtimeProjector.gated_range_transform`: a DFT of those bins,
   ``sample * gate`` complex products per chirp and channel instead of a whole
   FFT), into a buffer kept across frames; when ``motion`` is a callable (the
   strapdown of the frame's IMU samples), the compiled kernel runs this DFT on
   a thread of its own while the callable runs;
2. projects those bins onto the global grid
   (:meth:`RealtimeProjector.project` with ``gated=True``), into a beam buffer
   kept across frames.

The beams equal ``rigid_body_projection(range_compress(samples), ...,
method="direct")`` at the gates within float32 rounding (tested in
``tests/compensation/test_comp_stream.py``). No array the size of the frame is
allocated per frame.

:func:`replay` plays a capture at its frame rate (frame ``i`` arrives at
``start + i * frame_period``; a frame that arrives while the previous one is
still being processed waits) and yields each frame's latency from its arrival
to its beams, the figure a user of a live radar sees; :func:`latency_summary`
gives its percentiles.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass

import numpy as np

from .projection import BeamCube
from .realtime import RealtimeProjector
from .strapdown import PlatformMotion

#: Percentiles reported by :func:`latency_summary`.
PERCENTILES = (50, 95, 99)


class RealtimeStream:
    """Compensated beams of a stream of raw IF frames of one geometry.

    Parameters
    ----------
    projector : RealtimeProjector
        Geometry, grid and gated range bins (set up once).
    window : str or None
        Range window (``scipy.signal.get_window`` name, periodic), or None; as
        ``raysim.processing.maps.range_compress`` (Hann by default).
    chirp_weights : array_like, shape ``[chirp]``, optional
        Real slow-time factor of each chirp (e.g. the Doppler window), applied
        to the gated data (see :meth:`RealtimeProjector.project`).
    copy : bool
        Return beams in a new array each frame. Default False: every returned
        :class:`BeamCube` shares one buffer, overwritten by the next frame (use
        or copy it before asking for the next one).

    Examples
    --------
    >>> import numpy as np
    >>> from compensation.strapdown import static_motion
    >>> p = np.stack([np.arange(4) * 2e-3, np.zeros(4), np.zeros(4)], axis=1)
    >>> proj = RealtimeProjector(p, wavelength=3.9e-3, range_axis=np.arange(8) * 0.15,
    ...                          azimuth=[0.0], elevation=[0.0], range_gates=[2])
    >>> stream = RealtimeStream(proj, window=None)
    >>> tone = np.exp(2j * np.pi * 2 * np.arange(8) / 8)           # bin 2, all channels
    >>> frame = np.broadcast_to(tone, (16, 4, 8)).astype(np.complex64)
    >>> beams = stream.process(frame, static_motion(np.arange(16) * 6e-5))
    >>> beams.data.shape, round(abs(complex(beams.data[0, 0, 0, 0])), 5)
    ((16, 1, 1, 1), 1.0)
    """

    def __init__(self, projector: RealtimeProjector, *, window: str | None = "hann",
                 chirp_weights=None, copy: bool = False) -> None:
        if not isinstance(projector, RealtimeProjector):
            raise ValueError(f"projector must be a compensation.RealtimeProjector, got "
                             f"{type(projector)!r}")
        self.projector = projector
        self.window = window
        self.chirp_weights = None if chirp_weights is None else np.asarray(chirp_weights)
        self.copy = bool(copy)
        self._gated: np.ndarray | None = None     # [chirp, channel, gate] complex64
        self._beams: np.ndarray | None = None     # [chirp, gate, azimuth, elevation]
        #: Frames processed so far.
        self.frames = 0

    def _buffers(self, n_chirp: int) -> tuple[np.ndarray, np.ndarray]:
        p = self.projector
        if self._gated is None or self._gated.shape[0] != n_chirp:
            self._gated = np.empty((n_chirp, p.num_channels, p.gates.size), np.complex64)
            self._beams = np.empty((n_chirp, p.gates.size, p.azimuth.size, p.elevation.size),
                                   np.complex64)
        return self._gated, self._beams

    def process(self, samples, motion: PlatformMotion | Callable[[], PlatformMotion]
                ) -> BeamCube:
        """Beams of one frame.

        Parameters
        ----------
        samples : ndarray, shape ``[chirp, channel, sample]``, complex or real
            Raw IF samples of the frame.
        motion : PlatformMotion or callable
            Pose of every transmit slot (``chirp * slots`` poses, chirp major),
            or a callable with no argument returning it (called once, while the
            compiled kernel takes the range transform on a thread of its own).

        Returns
        -------
        BeamCube
            ``data [chirp, gate, azimuth, elevation]`` complex64 (the stream's
            buffer unless ``copy=True``).
        """
        x = np.asarray(samples)
        if x.ndim != 3:
            raise ValueError(f"samples must be an IF frame [chirp, channel, sample], got an "
                             f"array of shape {x.shape}")
        gated, beams = self._buffers(x.shape[0])
        if callable(motion) and not isinstance(motion, PlatformMotion):
            # the range transform on a thread of the kernel while Python integrates the poses
            job = self.projector._range_job(x, self.window, gated, start=True)
            try:
                motion = motion()
            finally:
                job()
        else:
            self.projector.gated_range_transform(x, window=self.window, out=gated)
        out = self.projector.project(gated, motion, gated=True,
                                     out=None if self.copy else beams,
                                     chirp_weights=self.chirp_weights)
        self.frames += 1
        return out

    def __call__(self, frames: Iterable) -> Iterator[BeamCube]:
        """Beams of each ``(samples, motion)`` pair of ``frames``, as :meth:`process`."""
        for item in frames:
            samples, motion = _pair(item)
            yield self.process(samples, motion)


def _pair(item) -> tuple:
    try:
        samples, motion = item
    except (TypeError, ValueError):
        raise ValueError("each frame must be a pair (samples [chirp, channel, sample], "
                         f"motion), got {type(item)!r}") from None
    return samples, motion


@dataclass(frozen=True)
class FrameTiming:
    """Timing of one replayed frame [s].

    ``latency`` runs from the frame's arrival (``start + index * period``) to
    its beams; ``service`` from the start of its processing (its arrival, or
    the end of the previous frame if that was later) to its beams (both wall
    clock, ``time.perf_counter``). ``cpu`` is the CPU time of the process, all
    threads (``time.process_time``), over the same span: the frame's cost to
    the cores, which other processes on them change far less than the wall
    times.
    """

    index: int
    latency: float
    service: float
    cpu: float


def replay(stream: RealtimeStream, frames: Iterable, *, frame_period: float,
           clock: Callable[[], float] = time.perf_counter,
           sleep: Callable[[float], None] = time.sleep,
           cpu_clock: Callable[[], float] = time.process_time
           ) -> Iterator[tuple[BeamCube, FrameTiming]]:
    """Play ``(samples, motion)`` frames at their frame rate through ``stream``.

    Frame ``i`` arrives at ``start + i * frame_period`` (``start`` = the first
    call of ``clock``); the loop waits for it, processes it, and yields its
    beams and :class:`FrameTiming`. A frame that arrives while an earlier one
    is still processed waits for it, so latency accumulates when processing is
    slower than the frame rate, as on a live radar with a frame queue.

    Parameters
    ----------
    stream : RealtimeStream
    frames : iterable of ``(samples, motion)``
        As :meth:`RealtimeStream.process` takes them.
    frame_period : float
        Time between frames [s] (> 0).
    clock, sleep, cpu_clock : callable
        Wall clock [s], sleep and CPU clock of the process [s] (replaceable in
        tests).
    """
    if not isinstance(stream, RealtimeStream):
        raise ValueError(f"stream must be a compensation.RealtimeStream, got {type(stream)!r}")
    period = float(frame_period)
    if not np.isfinite(period) or period <= 0:
        raise ValueError(f"frame_period must be a positive number of seconds, got "
                         f"{frame_period!r}")
    start = clock()
    for i, item in enumerate(frames):
        samples, motion = _pair(item)
        arrival = start + i * period
        now = clock()
        if now < arrival:
            sleep(arrival - now)
            now = clock()
        cpu0 = cpu_clock()
        beams = stream.process(samples, motion)
        done = clock()
        yield beams, FrameTiming(i, done - arrival, done - now, cpu_clock() - cpu0)


def latency_summary(seconds, *, budget: float | None = None) -> dict:
    """Percentiles of per-frame times [s]: ``p50_s``, ``p95_s``, ``p99_s``, ``max_s``, ``frames``.

    With ``budget`` [s] (the frame time) also ``over_budget`` (fraction of
    frames above it) and ``p95_within_budget``.
    """
    t = np.asarray(seconds, dtype=float).ravel()
    if t.size < 1 or not np.isfinite(t).all():
        raise ValueError(f"seconds must be finite per-frame times, got {t.size} values")
    out = {f"p{p}_s": float(np.percentile(t, p)) for p in PERCENTILES}
    out.update(max_s=float(t.max()), frames=int(t.size))
    if budget is not None:
        out.update(budget_s=float(budget), over_budget=float((t > budget).mean()),
                   p95_within_budget=bool(out["p95_s"] <= budget))
    return out
