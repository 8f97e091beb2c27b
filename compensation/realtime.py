"""Real-time exact rigid-body projection: the same beams as the direct engine, faster.

:class:`RealtimeProjector` computes what
:func:`compensation.exact.rigid_body_projection` computes with
``method="direct"`` (near focus, per-slot poses for TDM MIMO, channel taper),
equal within float32 rounding (tested against the direct engine,
``tests/compensation/test_comp_realtime.py``), but organised for a stream of
frames with the same geometry:

* set-up once per geometry (the "tables"): the grid directions ``u [D, 3]``,
  the TDM slots with their channels and weights, each slot's element line
  (``p0 + i a``) when its channels are equally spaced on a line, the gate
  blocks and their focal ranges;
* per chirp, slot and direction (float64, ``[chirp, direction]`` arrays, a few
  matrix products with three columns): ``q = u . d_n``, the focal distance
  ``L = |r u - d_n|``, the steering phases ``k (r u . R_n p - d_n . R_n p) / L``
  (the engine's ``v_n . p``) and the range phase ``2 k rho`` at the block's focal
  range, reduced modulo ``2 pi`` before the float32 ``cos``/``sin``;
* per gate only the small phase ``-2 k (rho_g - rho_mid)`` (float32, from the
  cancellation-free form ``rho = -q + e / (L + R - q)``, ``e = |d|^2 - q^2``)
  and the channel sum, by Horner's rule in ``z = exp(j k v . a)`` for a slot on
  a line (one ``cos``/``sin`` pair per chirp, slot and direction instead of one
  per channel), in the compiled kernel by Horner's rule along and across the
  rows of a slot on a lattice (``p0 + i1 a + i2 b``, row-major: three pairs per
  chirp and direction, e.g. the 20 x 20 paper array), or by a float32 matrix
  product for any other layout (``factorised=False``: for every slot);
* chirp blocks run on ``threads`` worker threads (NumPy releases the GIL in
  its array loops).

Two engines compute this: the compiled kernel ``compensation._native._ext``
(``engine="compiled"``, the default where it is built: one fused pass per
chirp, slot and direction chunk, ``threads`` threads started per call taking
those items in turn, ``exp(j .)`` by a
float32 polynomial after reduction to a quarter turn in float64, AVX-512 or
AVX2+FMA copy chosen at run time, ``engine="avx2"`` for the latter) and the
NumPy engine (``engine="numpy"``, the fallback where the extension is not
built, e.g. ``RAYSIM_NO_KERNEL=1``). Both follow the steps above and give the
same beams within float32 rounding.

Cost per frame: ``chirp * slot * direction * (2 sincos + ~40 flops) + chirp *
slot * gate * direction * (2 sincos + ~20 flops)``; a gate block whose gates
all lie at its focal range (a block of one gate) has no per-gate phase. A
slot of ``m`` channels off a line adds ``m`` sincos per chirp and direction
(3 on a lattice in the compiled kernel) and ``m`` complex products per gate.

For a stream of frames: :meth:`RealtimeProjector.gated_range_transform` gives
the range transform of the IF samples at the gated bins only (a DFT of those
bins, ``[chirp * channel, sample] x [sample, gate]``), which
:meth:`RealtimeProjector.project` takes with ``gated=True``; ``out=`` reuses
one beam buffer frame after frame.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ._checks import angle_axis, channel_slots, finite_array, positive
from .geometry import grid_directions
from .projection import BeamCube
from .strapdown import PlatformMotion

try:   # optional compiled kernel (setup.py); without it the NumPy engine runs
    from ._native import _ext
except ImportError:  # pragma: no cover - depends on the build
    _ext = None

#: Largest deviation of a slot's elements from an equally spaced line for the
#: Horner form [m]; beyond it the channel sum is a matrix product.
LINE_TOL = 1e-9
_TWO_PI = 2.0 * np.pi
#: Engines of :class:`RealtimeProjector`: ``"auto"`` (compiled where built, else
#: NumPy), ``"compiled"`` (best instruction set: AVX-512, else AVX2+FMA, else
#: x86-64-v2), ``"avx2"`` (compiled, at most AVX2+FMA: the copy without AVX-512,
#: the benchmark's baseline), ``"portable"`` (compiled, x86-64-v2 copy), ``"numpy"``.
ENGINES = ("auto", "compiled", "avx2", "portable", "numpy")
#: Complex products of a gated range transform (rows * samples * gates) above which
#: the compiled DFT runs on the projector's threads (the TI frame at 8 gates: 3.1 million,
#: one thread).
DFT_THREADED_MACS = 8_000_000
#: Request of each compiled engine to the kernel's dispatch (0 best, 1 portable, 2 <= AVX2).
_ISA_REQUEST = {"compiled": 0, "portable": 1, "avx2": 2}


def compiled_isa() -> str:
    """Instruction set of the compiled kernel here.

    ``"avx512"``, ``"avx2"``, ``"portable"`` (x86-64-v2), or ``"missing"`` where
    the extension is not built.
    """
    return "missing" if _ext is None else _ext.isa()


def _line(p: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """``(p0, a)`` with ``p[i] = p0 + i a`` for positions ``[m, 3]`` [m], else None."""
    if p.shape[0] < 2:
        return p[0], np.zeros(3)
    a = p[1] - p[0]
    model = p[0] + np.arange(p.shape[0])[:, None] * a
    return (p[0], a) if np.abs(model - p).max() <= LINE_TOL else None


def _lattice(p: np.ndarray) -> int:
    """Row length ``n1 >= 2`` when ``p[i1 + n1 i2] = p0 + i1 a + i2 b`` (positions ``[m, 3]``
    [m], rows of ``n1`` channels, at least two rows), else 0."""
    m = p.shape[0]
    if m < 4:
        return 0
    a = p[1] - p[0]
    if not np.any(np.abs(a) > LINE_TOL):
        return 0
    # the row length: the first channel off the line p0 + i a
    steps = np.arange(m)[:, None] * a
    off = np.flatnonzero(np.abs(p - p[0] - steps).max(axis=1) > LINE_TOL)
    n1 = int(off[0]) if off.size else 0
    if n1 < 2 or m % n1:
        return 0
    b = p[n1] - p[0]
    i = np.arange(m)
    model = p[0] + (i % n1)[:, None] * a + (i // n1)[:, None] * b
    return n1 if np.abs(model - p).max() <= LINE_TOL else 0


@dataclass(frozen=True)
class _Slot:
    index: int                  # TDM slot number
    channels: np.ndarray        # [m] channel indices into rc
    positions: np.ndarray       # [m, 3] virtual positions [m]
    weight: np.ndarray          # [m] w_m / sum(w) (float32)
    line: tuple | None          # (p0, a) or None
    lattice: int = 0            # row length n1 of a lattice p0 + i1 a + i2 b (kernel), else 0


def _default_threads() -> int:
    return max(1, min(len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity")
                      else (os.cpu_count() or 1), 8))


class RealtimeProjector:
    """Exact motion-compensated beams of one radar geometry, frame after frame.

    Parameters
    ----------
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions ``p_tx + p_rx`` in the radar frame A [m].
    wavelength : float
        Mid-chirp wavelength of the range-compressed data [m].
    range_axis : array_like, shape ``[range]``
        Range of each bin from the nominal radar phase centre [m].
    azimuth, elevation : array_like, shapes ``[azimuth]``, ``[elevation]``
        Global grid [rad].
    range_gates : array_like of int, shape ``[gate]``
        Range bins to project (the gated cells).
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM transmit slot of each channel; each slot uses the pose of its own
        transmit instant (``motion`` then holds ``chirp * slots`` poses, chirp
        major). Default: one slot.
    weights : array_like, shape ``[channel]``, optional
        Real channel taper; the output is divided by its sum. Default uniform.
    gate_block : int
        Gates sharing one steering direction (at their mean range), as in
        :func:`compensation.projection.beam_projection` (same default, 8).
    chirp_block : int
        Chirps per work item of the NumPy engine (bounds the temporaries: about
        ``chirp_block * direction * 60`` bytes per thread); the compiled kernel
        takes one chirp and 256 directions per item.
    threads : int, optional
        Worker threads (default: the CPUs this process may use, at most 8).
    engine : str
        One of :data:`ENGINES`; ``"compiled"``, ``"avx2"`` and ``"portable"``
        need the extension ``compensation._native._ext``.
    factorised : bool
        Sum the channels of a slot on a line (both engines) or on a lattice
        (rows of equally spaced channels, ``p0 + i1 a + i2 b`` in row-major
        order; compiled kernel) by Horner's rule in the steering of the steps,
        with 2 or 3 steering phases per chirp and direction. False: one
        steering phase per channel for every slot (the general form; slower,
        the same beams within float32 rounding), e.g. as a baseline.

    Examples
    --------
    >>> import numpy as np
    >>> from compensation.strapdown import static_motion
    >>> p = np.stack([np.arange(4) * 2e-3, np.zeros(4), np.zeros(4)], axis=1)
    >>> proj = RealtimeProjector(p, wavelength=3.9e-3, range_axis=[10.0, 10.15],
    ...                          azimuth=[0.0], elevation=[0.0], range_gates=[0, 1])
    >>> beams = proj.project(np.ones((8, 4, 2), np.complex64), static_motion(np.arange(8) * 6e-5))
    >>> beams.data.shape, round(abs(complex(beams.data[0, 0, 0, 0])), 5)
    ((8, 2, 1, 1), 1.0)
    """

    def __init__(self, element_positions, *, wavelength: float, range_axis, azimuth, elevation,
                 range_gates, channel_slot=None, weights=None, gate_block: int = 8,
                 chirp_block: int = 8, threads: int | None = None,
                 engine: str = "auto", factorised: bool = True) -> None:
        p = finite_array("element_positions", element_positions, ndim=2)
        if p.shape[1] != 3 or p.shape[0] < 1:
            raise ValueError(f"element_positions must have shape [channel, 3], got {p.shape}")
        n_chan = p.shape[0]
        self.wavelength = positive("wavelength", wavelength)
        self.k = _TWO_PI / self.wavelength
        r_axis = finite_array("range_axis", range_axis, ndim=1)
        self.azimuth = angle_axis("azimuth", azimuth)
        self.elevation = angle_axis("elevation", elevation)
        if self.azimuth.size < 1 or self.elevation.size < 1:
            raise ValueError("azimuth and elevation must each hold at least one angle")
        gates = np.atleast_1d(np.asarray(range_gates))
        if gates.ndim != 1 or gates.size < 1 or not np.issubdtype(gates.dtype, np.integer) or \
                gates.min() < 0 or gates.max() >= r_axis.size:
            raise ValueError(f"range_gates must be integer bin indices in [0, {r_axis.size}), "
                             f"got {range_gates!r}")
        self.gates = gates.astype(np.intp)
        self.range = r_axis[self.gates].copy()
        if weights is None:
            w = np.ones(n_chan)
        else:
            w = finite_array("weights", weights, shape=(n_chan,), what="(one per channel)")
        if w.sum() <= 0:
            raise ValueError(f"weights must have a positive sum, got {w.sum()!r}")
        if channel_slot is None:
            slot = np.zeros(n_chan, dtype=np.intp)
        else:
            slot = channel_slots(channel_slot, n_chan)
        self.num_slots = int(slot.max()) + 1
        self.num_channels = n_chan
        self.slots = []
        for s in range(self.num_slots):
            sel = np.flatnonzero(slot == s)
            if sel.size:
                line = _line(p[sel]) if factorised else None
                lattice = _lattice(p[sel]) if factorised and line is None else 0
                self.slots.append(_Slot(s, sel, p[sel], (w[sel] / w.sum()).astype(np.float32),
                                        line, lattice))
        self.u = grid_directions(self.azimuth, self.elevation).reshape(-1, 3)   # [D, 3]
        gb = max(1, int(gate_block))
        self.gate_blocks = [np.arange(i, min(i + gb, gates.size))
                            for i in range(0, gates.size, gb)]
        self.chirp_block = max(1, int(chirp_block))
        self.threads = _default_threads() if threads is None else max(1, int(threads))
        if engine not in ENGINES:
            raise ValueError(f"engine must be one of {ENGINES}, got {engine!r}")
        if engine in _ISA_REQUEST and _ext is None:
            raise ValueError(f"engine={engine!r} needs the compiled extension "
                             "compensation._native._ext, which is not built here (run `python "
                             "setup.py build_ext --inplace`), or use engine='numpy'")
        if engine == "auto":
            engine = "numpy" if _ext is None else "compiled"
        self._engine = engine
        self._dft_key, self._dft = None, None
        if engine != "numpy":
            self._tables = self._compiled_tables(p, w)

    @property
    def engine(self) -> str:
        """Engine in use: ``"avx512"``, ``"avx2"`` or ``"portable"`` (the compiled
        kernel's copy that runs on this CPU), or ``"numpy"``."""
        if self._engine == "numpy":
            return "numpy"
        return _ext.isa(_ISA_REQUEST[self._engine])

    def _compiled_tables(self, p: np.ndarray, w: np.ndarray) -> dict:
        """Geometry of the compiled kernel: channels ordered slot after slot (see rt_params.h)."""
        order = np.concatenate([sl.channels for sl in self.slots])
        sizes = [sl.channels.size for sl in self.slots]
        blocks = [int(gb[0]) for gb in self.gate_blocks] + [int(self.gates.size)]
        return {
            "order": order,
            "weight": np.concatenate([sl.weight for sl in self.slots]),   # float32
            "ints": np.array([len(self.slots), self.num_slots, self.num_directions,
                              self.gates.size, len(self.gate_blocks), order.size, max(sizes)],
                             dtype=np.int64),
            "slot_index": np.array([sl.index for sl in self.slots], dtype=np.int64),
            "slot_off": np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64),
            # 1: line (Horner), n1 >= 2: lattice with rows of n1 (two-step Horner), 0: general
            "slot_line": np.array([1 if sl.line is not None else sl.lattice
                                   for sl in self.slots], dtype=np.int64),
            "block_start": np.array(blocks, dtype=np.int64),
            "pos": np.ascontiguousarray(p[order], dtype=np.float64),
            "u": [np.ascontiguousarray(self.u[:, i]) for i in range(3)],
            "rg": np.ascontiguousarray(self.range, dtype=np.float64),
            "block_r": np.array([float(self.range[gb].mean()) for gb in self.gate_blocks]),
            "dbls": np.array([self.k, SMALL_PHASE], dtype=np.float64),
        }

    @property
    def num_directions(self) -> int:
        """Directions of the grid ``azimuth * elevation``."""
        return int(self.u.shape[0])

    def gated_range_transform(self, samples, *, window: str | None = "hann",
                              out: np.ndarray | None = None) -> np.ndarray:
        """Range transform of the IF samples at the gated bins only.

        The bins ``range_gates`` of the windowed range FFT (window divided by its
        sum; for real samples the positive-frequency bins doubled), i.e. of
        ``raysim.processing.maps.range_compress`` without zero padding, as one
        complex64 matrix product ``[chirp * channel, sample] x [sample, gate]``
        (a DFT of the gated bins: ``sample * gate`` complex products per channel
        instead of a whole FFT). The matrix is built once per sample count.

        Parameters
        ----------
        samples : ndarray, shape ``[chirp, channel, sample]``, complex or real
            IF samples.
        window : str or None
            ``scipy.signal.get_window`` name (periodic), or None for none.
        out : ndarray, shape ``[chirp, channel, gate]``, complex64, optional
            C-contiguous buffer for the result (reused frame after frame).

        Returns
        -------
        ndarray, shape ``[chirp, channel, gate]``, complex64
            Input of :meth:`project` with ``gated=True`` (``out`` if given).
        """
        return self._range_job(samples, window, out, start=False)()

    def _range_job(self, samples, window, out, *, start: bool):
        """:meth:`gated_range_transform` as a job: a callable with no argument returning
        its result. With ``start`` and the compiled kernel on complex samples the DFT
        runs on a thread of its own meanwhile (the callable waits for it); else it is
        done before the return."""
        x = np.asarray(samples)
        real = not np.iscomplexobj(x)
        bins = x.shape[-1] // 2 if real and x.ndim == 3 else (x.shape[-1] if x.ndim == 3 else 0)
        if x.ndim != 3 or x.shape[1] != self.num_channels or bins <= self.gates.max():
            raise ValueError(f"samples must be an IF cube [chirp, {self.num_channels}, sample] "
                             f"with more than {self.gates.max()} range bins, got {x.dtype} "
                             f"array of shape {x.shape}")
        key = (x.shape[-1], window, real)
        if self._dft_key != key:
            self._dft = _gated_dft(x.shape[-1], self.gates, window, real)
            self._dft_planar = (np.ascontiguousarray(self._dft.real.T),
                                np.ascontiguousarray(self._dft.imag.T))   # [G, K] float32
            self._dft_key = key
        n_gate = self.gates.size
        shape = (*x.shape[:2], n_gate)
        if out is None:
            out = np.empty(shape, dtype=np.complex64)
        elif not isinstance(out, np.ndarray) or out.shape != shape or \
                out.dtype != np.complex64 or not out.flags.c_contiguous:
            raise ValueError(f"out must be a C-contiguous complex64 array of shape {shape}, got "
                             f"{getattr(out, 'dtype', type(out))} {getattr(out, 'shape', '')}")
        if real or self._engine == "numpy":
            x = x.astype(np.float32 if real else np.complex64, copy=False)
            np.matmul(x.reshape(-1, x.shape[-1]), self._dft, out=out.reshape(-1, n_gate))
            return lambda: out
        # compiled, no BLAS call; one thread below DFT_THREADED_MACS (a thread barrier
        # busy-waits, which costs several times a small product's CPU time on a loaded
        # machine), the projector's threads above (the paper frame: 61 million)
        x = np.ascontiguousarray(x, dtype=np.complex64)
        wr, wi = self._dft_planar
        rows = x.shape[0] * x.shape[1]
        threads = self.threads if rows * x.shape[2] * n_gate > DFT_THREADED_MACS else 1
        args = (x.ctypes.data, wr.ctypes.data, wi.ctypes.data, out.ctypes.data, rows,
                x.shape[2], n_gate, threads, _ISA_REQUEST[self._engine])
        if not start:
            _ext.gated_dft(*args)
            return lambda: out
        job = _ext.gated_dft_start(*args)

        def result(arrays=(x, wr, wi, out)):   # the arrays stay alive until the join
            _ext.join(job)
            return arrays[-1]
        return result

    def project(self, rc, motion: PlatformMotion, *, gated: bool = False,
                out: np.ndarray | None = None, chirp_weights=None) -> BeamCube:
        """Beams of one frame.

        Parameters
        ----------
        rc : ndarray, shape ``[chirp, channel, range]``, complex
            Range-compressed cube; with ``gated=True`` only the gated bins,
            ``[chirp, channel, gate]`` (as :meth:`gated_range_transform` gives them).
        motion : PlatformMotion
            Pose per chirp (``chirp * slots`` poses, chirp major, with TDM slots).
        gated : bool
            ``rc`` holds the gated bins only.
        out : ndarray, shape ``[chirp, gate, azimuth, elevation]``, complex64, optional
            C-contiguous buffer for the beams (reused frame after frame, it saves
            the allocation and the first-touch page faults of a new one); the
            returned cube's ``data`` is then ``out``.
        chirp_weights : array_like, shape ``[chirp]``, optional
            Real factor of each chirp's beams (e.g. a slow-time window for the
            Doppler FFT), applied to the gated data at no extra pass; the beams
            are then the weighted beams.

        Returns
        -------
        BeamCube
            ``data [chirp, gate, azimuth, elevation]`` complex64, ``warnings`` of
            ``motion``.
        """
        x = np.asarray(rc)
        need = self.gates.size if gated else self.gates.max() + 1
        if x.ndim != 3 or not np.iscomplexobj(x) or x.shape[1] != self.num_channels or \
                x.shape[2] < need or (gated and x.shape[2] != need):
            what = f"{need}" if gated else f"> {self.gates.max()}"
            raise ValueError(f"rc must be a complex cube [chirp, {self.num_channels}, range "
                             f"{what}], got {x.dtype} array of shape {x.shape}")
        if not isinstance(motion, PlatformMotion):
            raise ValueError(f"motion must be a compensation.PlatformMotion, got {type(motion)!r}")
        n_chirp = x.shape[0]
        if motion.num_chirps != n_chirp * self.num_slots:
            raise ValueError(f"motion must hold chirp * slots = {n_chirp} * {self.num_slots} "
                             f"poses (chirp major), got {motion.num_chirps}")
        xg = np.ascontiguousarray(x if gated else x[:, :, self.gates],
                                  dtype=np.complex64)                        # [N, M, G]
        if not np.isfinite(xg.view(np.float32)).all():
            raise ValueError("rc holds NaN or infinite values in the gated cells")
        if chirp_weights is not None:
            cw = finite_array("chirp_weights", chirp_weights, shape=(n_chirp,),
                              what="(one real factor per chirp)")
            xg = xg * cw.astype(np.float32)[:, None, None]
        rot = motion.attitude.reshape(n_chirp, self.num_slots, 3, 3)
        disp = motion.radar_displacement.reshape(n_chirp, self.num_slots, 3)
        shape = (n_chirp, self.gates.size, self.azimuth.size, self.elevation.size)
        if out is None:
            out = np.empty(shape, dtype=np.complex64)
        elif not isinstance(out, np.ndarray) or out.shape != shape or \
                out.dtype != np.complex64 or not out.flags.c_contiguous:
            raise ValueError(f"out must be a C-contiguous complex64 array of shape {shape}, got "
                             f"{getattr(out, 'dtype', type(out))} {getattr(out, 'shape', '')}")
        beams = out
        out = out.reshape(n_chirp, self.gates.size, self.num_directions)
        (self._numpy if self._engine == "numpy" else self._compiled)(xg, rot, disp, out)
        return BeamCube(beams, motion.time[::self.num_slots],
                        self.range, self.azimuth, self.elevation, self.wavelength,
                        motion.warnings)

    def _compiled(self, xg: np.ndarray, rot: np.ndarray, disp: np.ndarray,
                  out: np.ndarray) -> None:
        """Fill ``out [N, G, D]`` by the kernel (``xg [N, M, G]``, poses ``[N, S, ...]``)."""
        tb = self._tables
        # weighted data, channels slot after slot, as the NumPy engine weights them (complex64)
        xw = np.ascontiguousarray(xg[:, tb["order"]] * tb["weight"][None, :, None],
                                  dtype=np.complex64)
        rot = np.ascontiguousarray(rot, dtype=np.float64)
        disp = np.ascontiguousarray(disp, dtype=np.float64)
        ints = np.array([xg.shape[0], *tb["ints"], self.threads], dtype=np.int64)
        arrays = (tb["slot_index"], tb["slot_off"], tb["slot_line"], tb["block_start"],
                  tb["pos"], rot, disp, *tb["u"], tb["rg"], tb["block_r"], xw, out)
        ptrs = np.array([a.ctypes.data for a in arrays], dtype=np.uint64)
        # the arrays above stay referenced until the call returns
        _ext.project(ints.ctypes.data, ptrs.ctypes.data, tb["dbls"].ctypes.data,
                     _ISA_REQUEST[self._engine])

    def _numpy(self, xg: np.ndarray, rot: np.ndarray, disp: np.ndarray,
               out: np.ndarray) -> None:
        """Fill ``out [N, G, D]`` by the NumPy engine, chirp blocks on worker threads."""
        n_chirp = xg.shape[0]
        blocks = [(n0, min(n0 + self.chirp_block, n_chirp))
                  for n0 in range(0, n_chirp, self.chirp_block)]

        def work(b):
            n0, n1 = b
            out[n0:n1] = self._block(xg[n0:n1], rot[n0:n1], disp[n0:n1])

        if self.threads == 1 or len(blocks) == 1:
            for b in blocks:
                work(b)
        else:
            with ThreadPoolExecutor(self.threads) as pool:
                list(pool.map(work, blocks))

    def _block(self, xg: np.ndarray, rot: np.ndarray, disp: np.ndarray) -> np.ndarray:
        """Beams ``[c, G, D]`` of one chirp block (``xg [c, M, G]``, poses ``[c, S, ...]``)."""
        c = xg.shape[0]
        k, u = self.k, self.u
        y = np.zeros((c, self.gates.size, u.shape[0]), dtype=np.complex64)
        for sl in self.slots:
            R, d = rot[:, sl.index], disp[:, sl.index]                 # [c, 3, 3], [c, 3]
            q = d @ u.T                                                # [c, D] u . d
            dd = np.einsum("ci,ci->c", d, d)[:, None]                  # [c, 1]
            e = dd - q * q                                             # |d x u|^2 >= 0
            np.maximum(e, 0.0, out=e)
            q32, e32 = q.astype(np.float32), e.astype(np.float32)
            xw = xg[:, sl.channels] * sl.weight[None, :, None]         # [c, m, G]
            for gb in self.gate_blocks:
                r = float(self.range[gb].mean())
                t = r - q
                L = np.sqrt(t * t + e)                                 # |r u - d|
                h_mid = e / (L + t)                                    # rho = -q + h
                inv_l = k / L
                # steering: k v . p = k (r u . R p - d . R p) / L ; range phase -2 k rho
                if sl.line is not None:
                    p0, a = sl.line
                    rp0, ra = R @ p0, R @ a                            # [c, 3]
                    phi0 = (r * (rp0 @ u.T) - np.einsum("ci,ci->c", d, rp0)[:, None]) * inv_l
                    alpha = (r * (ra @ u.T) - np.einsum("ci,ci->c", d, ra)[:, None]) * inv_l
                    base = _expj(phi0 + 2.0 * k * (q - h_mid))         # [c, D]
                    z = _expj(alpha)
                    steer = None
                else:
                    rp = R @ sl.positions.T                            # [c, 3, m]
                    ph = (r * np.einsum("di,cim->cdm", u, rp)
                          - np.einsum("ci,cim->cm", d, rp)[:, None, :]) * inv_l[..., None]
                    ph += (2.0 * k * (q - h_mid))[..., None]
                    steer = _expj(ph)                                  # [c, D, m]
                    sums = np.matmul(steer, xw)                        # [c, D, G]
                # rho_g - rho_mid = e (r - R_g) (1 + (t + t_g) / (L + L_g)) / ((L + t)(L_g + t_g))
                # with t = r - q, t_g = R_g - q: no cancellation, float32 keeps its precision
                # (float64 where the phase is not small: its float32 error grows with it)
                a64 = e * (-2.0 * k) / (L + t)
                t32, l32, a32 = (v.astype(np.float32) for v in (t, L, a64))
                for gi in gb:
                    small = _gate_phase(self.range[gi], r, q32, e32, t32, l32, a32)
                    if np.abs(small).max() <= SMALL_PHASE:
                        corr = _expj_small(small)
                    else:   # float64: the float32 error of a large phase grows with it
                        corr = _expj(_gate_phase(self.range[gi], r, q, e, t, L, a64))
                    if steer is None:
                        xs = xw[:, :, gi]                              # [c, m]
                        acc = z * xs[:, -1:]
                        if xs.shape[1] > 1:
                            acc += xs[:, -2:-1]
                        for i in range(xs.shape[1] - 3, -1, -1):
                            acc *= z
                            acc += xs[:, i:i + 1]
                        acc *= base
                    else:
                        acc = sums[:, :, gi]
                    acc *= corr
                    y[:, gi] += acc
        return y


def _gated_dft(n: int, gates: np.ndarray, window: str | None, real: bool) -> np.ndarray:
    """``[sample, gate]`` complex64 matrix: window / sum times ``exp(-2 pi j k g / n)``.

    Doubled for real samples (the positive-frequency half, as for a real tone).
    """
    if window is None:
        w = np.ones(n)
    else:
        from scipy.signal import get_window

        try:
            w = get_window(window, n, fftbins=True)
        except ValueError as exc:
            raise ValueError(f"window {window!r} is not a scipy.signal window name: "
                             f"{exc}") from None
    w = w / w.sum() * (2.0 if real else 1.0)
    # exact integer product k g modulo n keeps the phase of large bins exact
    kg = np.outer(np.arange(n), gates) % n
    return (w[:, None] * np.exp(-2j * np.pi * kg / n)).astype(np.complex64)


def _gate_phase(r_g: float, r: float, q, e, t, L, a) -> np.ndarray:
    """``-2 k (rho_g - rho_mid)`` [rad], shape ``[c, D]``, in the dtype of ``q``."""
    one = q.dtype.type
    tg = one(r_g) - q
    lg = np.sqrt(tg * tg + e)
    ph = (t + tg) / (L + lg)
    ph += one(1.0)
    ph *= a
    ph /= lg + tg
    ph *= one(r - r_g)
    return ph


#: Largest phase [rad] for which :func:`_expj_small` uses its Taylor series
#: (truncation ``x^6 / 720 < 4e-11`` there, below float32 rounding).
SMALL_PHASE = 0.05


def _expj_small(phase: np.ndarray) -> np.ndarray:
    """``exp(j phase)`` (complex64) of a float32 phase within ``SMALL_PHASE``, by Taylor series."""
    x2 = phase * phase
    out = np.empty(phase.shape, dtype=np.complex64)
    v = out.view(np.float32).reshape(phase.shape + (2,))
    re = x2 * np.float32(1.0 / 24.0)
    re -= np.float32(0.5)
    re *= x2
    re += np.float32(1.0)
    v[..., 0] = re
    im = x2 * np.float32(1.0 / 120.0)
    im -= np.float32(1.0 / 6.0)
    im *= x2
    im += np.float32(1.0)
    im *= phase
    v[..., 1] = im
    return out


def _expj(phase: np.ndarray) -> np.ndarray:
    """``exp(j phase)`` as complex64: float64 phases reduced modulo ``2 pi`` first."""
    if phase.dtype == np.float64:
        phase = phase - _TWO_PI * np.rint(phase / _TWO_PI)
        phase = phase.astype(np.float32)
    out = np.empty(phase.shape, dtype=np.complex64)
    v = out.view(np.float32).reshape(phase.shape + (2,))
    np.cos(phase, out=v[..., 0])
    np.sin(phase, out=v[..., 1])
    return out
