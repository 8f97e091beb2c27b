"""Real-time compensation benchmark: a TI-size TDM frame compensated and processed.

:func:`bench_realtime` (key ``realtime_compensation`` of ``raysim bench`` and
``realtime`` of ``raysim/bench/compensation_speed.py``) times, in wall-clock
seconds (``time.perf_counter``) with the CPU seconds of the process
(``time.process_time``, all threads) next to them, the chain a radar would run
on every frame:

1. Hann range transform of the IF cube ``[128 chirps, 12 channels, 256
   samples]`` (complex64, as a 16-bit ADC delivers it; TI-style 3 Tx x 4 Rx
   TDM, 51.2 us ramps, frame 19.66 ms) at the gated bins only
   (:meth:`~compensation.realtime.RealtimeProjector.gated_range_transform`, a
   DFT of those bins as one matrix product; the whole-cube FFT is timed apart
   as ``full_range_fft``);
2. strapdown integration of a 1 kHz IMU record to the pose of every transmit
   slot (``128 x 3`` poses, lever arm 10 cm);
3. exact rigid-body projection of the gated range cells onto a 61 x 61
   azimuth x elevation grid (30 deg half width), each slot with its own pose
   (:class:`compensation.realtime.RealtimeProjector`, compiled engine where
   built; its set-up, once per geometry, is timed apart);
4. Hann Doppler FFT of the beams and their power (:class:`DopplerPower`, the
   values of ``abs(BeamCube.doppler()) ** 2`` in fewer passes, buffers kept
   across frames, as the projector's beam buffer).

:func:`bench_stream` (key ``realtime`` of ``raysim bench``, and ``raysim bench
--realtime-only``) runs the same chain as a user would: 200 consecutive raw IF
frames replayed at the frame rate through :class:`compensation.RealtimeStream`,
with p50/p95/p99 of each frame's latency and service time.

:func:`bench_realtime` reports frames per second against the radar's frame rate for 1, 3 and 8
gated cells, the threads and engine used, the per-stage split (wall and CPU),
the projection with the NumPy engine and with the direct engine
(:func:`compensation.rigid_body_projection`, ``method="direct"``), and the
largest difference of the beams from the direct engine relative to their peak.
"""

from __future__ import annotations

import os
import time

import numpy as np

from raysim.radar.config import RadarConfig

#: TI-size frame: 128 chirps x 3 TDM slots of 51.2 us, 256 samples at 5 MHz.
TI_FRAME = dict(num_chirps=128, chirp_duration=51.2e-6, sample_rate=5e6, num_tx_slots=3)
#: Lever arm of the radar phase centre in the body frame [m].
LEVER = np.array([0.1, 0.0, 0.0])
#: Gated cells timed by default.
GATE_COUNTS = (1, 3, 8)


#: Highest motion frequency of the benchmark's platform [Hz] (pitch 20 Hz, heave 5 Hz),
#: stated to the strapdown for its IMU-rate check.
MOTION_BAND_HZ = 20.0


def ti_setup(*, grid: int = 61, half_width_deg: float = 30.0, target_range: float = 12.0):
    """Frame, IMU record and grid of the benchmark (pitch 10 deg at 20 Hz + heave 2 cm at 5 Hz).

    Returns
    -------
    dict
        ``config``, ``array``, ``cube [chirp, channel, sample]``, ``slot_times
        [chirp * 3]`` [s], ``imu`` (time, gyro, accel), ``initial_velocity``,
        ``azimuth``, ``elevation`` [rad], ``target_gate``.
    """
    from raysim.echoes.oracle import PointTarget, simulate_point_targets
    from raysim.platform.imu import simulate_imu
    from raysim.platform.kinematics import element_times
    from raysim.platform.motion import sinusoid
    from raysim.radar.arrays import ti_3tx4rx

    cfg = RadarConfig(**TI_FRAME)
    arr = ti_3tx4rx(cfg.wavelength)
    traj = sinusoid("pitch", np.deg2rad(10.0), 20.0) + sinusoid("z", 0.02, 5.0)
    tgt = PointTarget.at(target_range, np.deg2rad(20.0), 0.0, radar_origin=LEVER)
    cube = simulate_point_targets(cfg, arr, [tgt], traj, lever_arm=LEVER).data
    slot_times = np.unique(element_times(cfg, arr))
    imu = simulate_imu(traj, "ideal", rate=1000.0, start=-0.01, end=slot_times[-1] + 0.01)
    off = np.deg2rad(np.linspace(-half_width_deg, half_width_deg, grid))
    return {"config": cfg, "array": arr, "cube": cube, "slot_times": slot_times,
            "imu": (imu.time, imu.gyro, imu.accel),
            "initial_velocity": traj.velocity([0.0])[0], "azimuth": off, "elevation": off.copy(),
            "target_gate": int(np.argmin(np.abs(cfg.range_axis() - target_range)))}


def best_clocks(fn, repeat: int) -> tuple[float, float, object]:
    """Best wall and CPU seconds of ``repeat`` calls, and the last result."""
    wall = cpu = np.inf
    out = None
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        wall = min(wall, time.perf_counter() - w0)
        cpu = min(cpu, time.process_time() - c0)
    return float(wall), float(cpu), out


class DopplerPower:
    """Power of the Hann Doppler spectrum of beams, as ``abs(BeamCube.doppler()) ** 2``.

    Frame after frame with the same beam shape: the window (divided by its sum)
    times ``(-1)^n`` (for an even chirp count this puts the zero Doppler bin in
    the middle, the fft-shift, without a copy), the FFT in place in a buffer
    kept across frames (complex64, ``scipy.fft``), the power written into a
    float32 buffer also kept across frames.

    Parameters
    ----------
    shape : tuple of int
        Beam shape ``[chirp, ...]``.
    threads : int
        FFT workers.
    """

    def __init__(self, shape, *, threads: int = 1) -> None:
        from scipy.signal import get_window

        self.shape = tuple(int(v) for v in np.atleast_1d(shape))
        if len(self.shape) < 1 or min(self.shape) < 1:
            raise ValueError(f"shape must be [chirp, ...] with no empty axis, got {shape!r}")
        n = self.shape[0]
        w = get_window("hann", n, fftbins=True)
        w = w / w.sum()
        if n % 2 == 0:   # X[k - n/2] = sum x[m] (-1)^m exp(-2 pi j k m / n)
            w = w * (-1.0) ** np.arange(n)
        self._shifted = n % 2 == 0
        #: Slow-time factor of each chirp ``[chirp]`` (float32): window / sum, times
        #: ``(-1)^n`` for an even count; pass it to ``RealtimeProjector.project(...,
        #: chirp_weights=)`` and call with ``weighted=True`` to skip the window pass.
        self.chirp_weights = w.astype(np.float32)
        self._w = self.chirp_weights.reshape((n,) + (1,) * (len(self.shape) - 1))
        self._work = np.empty(self.shape, dtype=np.complex64)
        self._power = np.empty(self.shape, dtype=np.float32)
        self.threads = max(1, int(threads))

    def __call__(self, data: np.ndarray, *, weighted: bool = False) -> np.ndarray:
        """Power ``[doppler, ...]`` (float32, fft-shifted) of beams ``data [chirp, ...]``.

        With ``weighted=True`` the beams already carry :attr:`chirp_weights`
        (complex64, C-contiguous); their FFT is then taken in place, so ``data``
        is overwritten. The returned array is the object's buffer, overwritten by
        the next call.
        """
        import scipy.fft

        if data.shape != self.shape:
            raise ValueError(f"data must have shape {self.shape}, got {data.shape}")
        if weighted:
            if data.dtype != np.complex64 or not data.flags.c_contiguous:
                raise ValueError(f"weighted data must be C-contiguous complex64, got "
                                 f"{data.dtype} (contiguous: {data.flags.c_contiguous})")
            work = data
        else:
            work = np.multiply(data, self._w, out=self._work)
        spec = scipy.fft.fft(work, axis=0, workers=self.threads, overwrite_x=True)
        v = spec.view(np.float32)
        np.square(v, out=v)
        np.add(v[..., 0::2], v[..., 1::2], out=self._power)
        if not self._shifted:
            return np.fft.fftshift(self._power, axes=0)
        return self._power


def doppler_power(data: np.ndarray, *, threads: int = 1) -> np.ndarray:
    """Power of the Hann Doppler spectrum of beams, as ``abs(BeamCube.doppler()) ** 2``.

    Parameters
    ----------
    data : ndarray, shape ``[chirp, ...]``, complex64
        Beams (``BeamCube.data``).
    threads : int
        FFT workers.

    Returns
    -------
    ndarray, shape ``[doppler, ...]``, float32
        fft-shifted along the first axis, window normalised to unit sum (a new
        array; :class:`DopplerPower` reuses its buffers frame after frame).
    """
    return DopplerPower(data.shape, threads=threads)(data).copy()


def _stage(fn, rep: int) -> dict:
    """Best wall and CPU seconds of ``repeat`` calls as a dict."""
    wall, cpu, _ = best_clocks(fn, rep)
    return {"wall_s": wall, "cpu_s": cpu}


def bench_realtime(*, quick: bool = True, gate_counts=GATE_COUNTS, threads: int | None = None,
                   repeat: int | None = None) -> dict:
    """Frames per second of the compensated TI-size chain against its frame rate.

    Parameters
    ----------
    quick : bool
        Fewer repeats (5 instead of 15).
    gate_counts : sequence of int
        Numbers of gated range cells (consecutive, centred on the target).
    threads : int, optional
        Worker threads of the projector and the Doppler FFT (default: the CPUs
        of this process, at most 8).
    repeat : int, optional
        Timed repeats (best kept); default from ``quick``.

    Returns
    -------
    dict
        JSON-ready; ``cases`` has one entry per gate count with ``wall_s``,
        ``cpu_s``, ``fps``, ``frame_rate_hz``, ``realtime_factor`` (frame
        duration / wall time, > 1 is faster than real time), the per-stage
        split (wall and CPU) and the agreement with the direct engine.
    """
    import compensation
    from compensation.realtime import RealtimeProjector, compiled_isa
    from raysim.processing.maps import range_compress

    rep = (5 if quick else 15) if repeat is None else max(1, int(repeat))
    s = ti_setup()
    cfg, arr = s["config"], s["array"]
    cube = s["cube"].astype(np.complex64)
    lam, r_axis = cfg.center_wavelength, cfg.range_axis()

    def strapdown():
        # a stream states its platform's vibration band once (MOTION_BAND_HZ) rather
        # than estimating a spectrum from each frame's 40 IMU samples
        return compensation.integrate_imu(*s["imu"], s["slot_times"], lever_arm=LEVER,
                                          velocity="given",
                                          initial_velocity=s["initial_velocity"],
                                          vibration_hz=MOTION_BAND_HZ)

    rc = range_compress(cube)
    motion = strapdown()
    load_before = list(os.getloadavg())
    t_full_range = _stage(lambda: range_compress(cube), rep)
    t_strap = _stage(strapdown, rep)
    out = {
        "frame_shape": list(cube.shape), "tdm_slots": cfg.num_tx_slots,
        "frame_duration_s": cfg.frame_duration, "frame_rate_hz": 1.0 / cfg.frame_duration,
        "grid": [int(s["azimuth"].size), int(s["elevation"].size)],
        "clock": "wall (time.perf_counter), best of repeats; cpu_s = time.process_time "
                 "(all threads of the process)",
        "repeat": rep, "cpu_count": os.cpu_count(), "compiled_kernel": compiled_isa(),
        "included": ["Hann range transform of the complex64 cube at the gated bins "
                     "(RealtimeProjector.gated_range_transform, one matrix product)",
                     "strapdown of the IMU to 384 slot poses (vibration band stated)",
                     "exact projection of the gated cells (per-slot poses, near focus) into a "
                     "beam buffer kept across frames",
                     "Hann Doppler FFT of the beams and |.|^2 (DopplerPower, buffers kept "
                     "across frames; its window applied to the gated data by the projector's "
                     "chirp_weights, the FFT in place in the beam buffer)"],
        "excluded": ["projector and Doppler set-up (once per geometry, setup_s)",
                     "IF synthesis and IMU simulation (inputs)", "detection and tracking"],
        "full_range_fft": t_full_range, "strapdown": t_strap, "cases": [],
    }
    for n_gate in gate_counts:
        g0 = s["target_gate"] - n_gate // 2
        gates = np.arange(g0, g0 + n_gate)
        kw = dict(wavelength=lam, range_axis=r_axis, range_gates=gates,
                  azimuth=s["azimuth"], elevation=s["elevation"])
        w0 = time.perf_counter()
        proj = RealtimeProjector(arr.virtual_positions, channel_slot=arr.tx_slot,
                                 threads=threads, **kw)
        shape = (cube.shape[0], n_gate, *out["grid"])
        buf = np.empty(shape, dtype=np.complex64)
        dop = DopplerPower(shape, threads=proj.threads)
        setup_s = time.perf_counter() - w0
        numpy_proj = RealtimeProjector(arr.virtual_positions, channel_slot=arr.tx_slot,
                                       threads=proj.threads, engine="numpy", **kw)

        def chain(proj=proj, buf=buf, dop=dop):
            # the slow-time window rides on the gated data: no window pass over the beams
            beams = proj.project(proj.gated_range_transform(cube), strapdown(), gated=True,
                                 out=buf, chirp_weights=dop.chirp_weights)
            return dop(beams.data, weighted=True)

        chain()                                                      # warm-up
        wall, cpu, _ = best_clocks(chain, rep)
        t_range = _stage(lambda p=proj: p.gated_range_transform(cube), rep)
        range_err = float(np.abs(proj.gated_range_transform(cube) - rc[:, :, gates]).max()
                          / np.abs(rc[:, :, gates]).max())
        t_proj = _stage(lambda p=proj, b=buf: p.project(rc, motion, out=b), rep)
        beams = proj.project(rc, motion)
        # the stage with its window pass (the chain has none: an upper bound); the weighted
        # form overwrites its input, so repeats would need a copy of the beams each
        t_dopp = _stage(lambda b=beams, d=dop: d(b.data), rep)
        wb = proj.project(rc, motion, chirp_weights=dop.chirp_weights).data
        t_numpy = _stage(lambda p=numpy_proj: p.project(rc, motion), max(1, rep // 3))
        ref_power = np.abs(beams.doppler()) ** 2
        power_err = float(np.abs(dop(wb, weighted=True) - ref_power).max() / ref_power.max())

        def direct(kw=kw):
            return compensation.rigid_body_projection(
                rc, arr.virtual_positions, motion, channel_slot=arr.tx_slot, method="direct",
                **kw)

        t_direct, cpu_direct, ref = best_clocks(direct, 1)
        err = float(np.abs(beams.data - ref.data).max() / np.abs(ref.data).max())
        out["cases"].append({
            "gates": int(n_gate), "threads": proj.threads, "engine": proj.engine,
            "setup_s": setup_s, "wall_s": wall, "cpu_s": cpu, "fps": 1.0 / wall,
            "realtime_factor": cfg.frame_duration / wall,
            "cpu_realtime_factor": cfg.frame_duration / cpu,
            "split": {"gated_range_transform": t_range, "strapdown": t_strap,
                      "projection": t_proj, "doppler_and_power": t_dopp},
            "numpy_engine_projection": t_numpy,
            "projection_speedup_vs_numpy_engine": t_numpy["cpu_s"] / t_proj["cpu_s"],
            "direct_projection_wall_s": t_direct, "direct_projection_cpu_s": cpu_direct,
            "projection_speedup_vs_direct": t_direct / t_proj["wall_s"],
            "max_error_vs_direct": err, "doppler_power_max_diff": power_err,
            "gated_range_max_diff": range_err,
        })
    out["load_average"] = {"before": load_before, "after": list(os.getloadavg())}
    return out


#: Consecutive frames replayed per gate count by :func:`bench_stream`.
STREAM_FRAMES = 200
#: Frames of one stream replayed before the other (engine and baseline alternate) by
#: :func:`bench_stream`.
STREAM_BLOCK = 25
#: Engine of :func:`bench_stream`'s baseline stream: the compiled kernel without its
#: AVX-512 copy (the best copy before it).
BASELINE_ENGINE = "avx2"
#: Chirps of the paper frame projected by :func:`bench_stream` (its cost per chirp is
#: constant, so the whole 256-chirp frame is this times 256 / PAPER_CHIRPS; enough that
#: the gated range transform runs on the projector's threads, as for the whole frame:
#: 40 * 400 rows * 600 samples > ``compensation.realtime.DFT_THREADED_MACS``).
PAPER_CHIRPS = 40


def _percentiles(seconds, budget: float) -> dict:
    from compensation.stream import latency_summary

    return latency_summary(seconds, budget=budget)


def _cpu(seconds) -> dict:
    """Percentiles of per-frame CPU seconds (process, all threads), as :func:`_percentiles`."""
    from compensation.stream import latency_summary

    return latency_summary(seconds)


def bench_stream(*, frames: int = STREAM_FRAMES, gate_counts=GATE_COUNTS,
                 threads: int | None = None, paper: bool = True,
                 baseline: str | None = BASELINE_ENGINE) -> dict:
    """Per-frame latency of the TI-size stream replayed at its frame rate.

    A capture of ``frames`` consecutive raw IF frames ``[128 chirps, 12
    channels, 256 samples]`` (complex64, the frame of :func:`ti_setup` replayed;
    its content does not change the work) is played through
    :class:`compensation.RealtimeStream` at the radar's frame rate
    (:func:`compensation.stream.replay`, frame ``i`` arriving at ``i * 19.66
    ms``). Each frame's work: the Hann range transform of the gated bins (a DFT
    of those bins), the strapdown of the frame's IMU samples to its 384 slot
    poses, and the exact projection onto the 61 x 61 grid into the stream's
    beam buffer. Wall clock (``time.perf_counter``).

    With a ``baseline`` engine the same frames also go through a second stream
    on that engine; the two streams alternate in blocks of
    :data:`STREAM_BLOCK` frames (each block replayed at the frame rate), so
    that both see the same load, and each case gives the ratio of their p50
    and p95 service times.

    Parameters
    ----------
    frames : int
        Frames replayed per gate count and stream (>= 1; the bench uses 200).
    gate_counts : sequence of int
        Gated range cells (consecutive, centred on the target).
    threads : int, optional
        Projector threads (default: the CPUs of this process, at most 8).
    paper : bool
        Also project :data:`PAPER_CHIRPS` chirps of the paper frame (256 x 400
        x 600, one slot, 20 x 20 array, one gate, same grid) and scale to its
        256 chirps: what the paper frame needs against its 15.36 ms.
    baseline : str or None
        Engine of the baseline stream (one of ``compensation.realtime.ENGINES``;
        default ``"avx2"``, the compiled kernel without its AVX-512 copy), or
        None for none. Where it runs the same copy as the default engine (a CPU
        without AVX-512) it is skipped and the result says so. The paper frame's
        baseline is that engine with ``factorised=False`` (one steering phase per
        channel).

    Returns
    -------
    dict
        JSON-ready. ``cases``: per gate count ``latency`` (arrival to beams) and
        ``service`` (start of processing to beams), each with ``p50_s``,
        ``p95_s``, ``p99_s``, ``max_s``, ``frames``, ``budget_s`` (the frame
        time), ``over_budget`` and ``p95_within_budget``; ``stages`` (p50 and
        p95 of each stage over a second, back-to-back pass of the same frames,
        the Doppler FFT and power of the beams, which the stream leaves to its
        user, included there), ``realtime_factor_p95`` (frame time / p95
        service time), ``cpu`` (percentiles of each frame's CPU seconds, all
        threads: its cost, robust to other processes on the cores) and, with a
        baseline, ``baseline`` (its engine, latency, service and cpu),
        ``speedup_p50`` / ``speedup_p95`` (baseline service time / this one's)
        and ``cpu_ratio_p50`` (baseline CPU p50 / this one's).
        ``load_average`` before and after.
    """
    import compensation
    from compensation.realtime import ENGINES, RealtimeProjector, compiled_isa
    from compensation.stream import RealtimeStream, replay

    n_frames = int(frames)
    if n_frames < 1:
        raise ValueError(f"frames must be a positive count, got {frames!r}")
    if baseline is not None and baseline not in ENGINES:
        raise ValueError(f"baseline must be one of {ENGINES} or None, got {baseline!r}")
    s = ti_setup()
    cfg, arr = s["config"], s["array"]
    cube = s["cube"].astype(np.complex64)
    budget = cfg.frame_duration

    def strapdown():
        return compensation.integrate_imu(*s["imu"], s["slot_times"], lever_arm=LEVER,
                                          velocity="given",
                                          initial_velocity=s["initial_velocity"],
                                          vibration_hz=MOTION_BAND_HZ)

    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    out = {
        "frames": n_frames, "frame_shape": list(cube.shape), "tdm_slots": cfg.num_tx_slots,
        "frame_duration_s": budget, "grid": [int(s["azimuth"].size), int(s["elevation"].size)],
        "clock": "wall (time.perf_counter), every frame (no best-of)",
        "cpu_count": os.cpu_count(), "cpus_of_process": cpus, "compiled_kernel": compiled_isa(),
        "omp_wait_policy": os.environ.get("OMP_WAIT_POLICY", "default"),
        "threading": "the compiled kernel starts its threads per call and joins them (no "
                     "OpenMP team: nothing spins between frames, whatever OMP_WAIT_POLICY)",
        "included": ["Hann range transform of the raw complex64 IF frame at the gated bins "
                     "(DFT of those bins, compiled, one thread)",
                     "strapdown of the frame's IMU samples to its 384 slot poses",
                     "exact projection of the gated cells onto the grid (per-slot poses, "
                     "near focus) into the stream's beam buffer"],
        "excluded": ["Doppler FFT of the beams (in stages.doppler_and_power, not in latency)",
                     "set-up once per geometry", "IF and IMU simulation (the capture)"],
        "replay": "frame i arrives at i * frame_duration_s; latency = its beams' time - its "
                  "arrival (a late frame waits for the one before it)",
        "load_average": {"before": list(os.getloadavg())}, "cases": [],
    }

    def projector(gates, engine):
        return RealtimeProjector(arr.virtual_positions, channel_slot=arr.tx_slot,
                                 threads=threads, wavelength=cfg.center_wavelength,
                                 range_axis=cfg.range_axis(), range_gates=gates,
                                 azimuth=s["azimuth"], elevation=s["elevation"], engine=engine)

    for n_gate in gate_counts:
        g0 = s["target_gate"] - n_gate // 2
        gates = np.arange(g0, g0 + n_gate)
        proj = projector(gates, "auto")
        runs = {"engine": RealtimeStream(proj)}
        base_proj = None
        if baseline is not None and compiled_isa() == "missing" and baseline != "numpy":
            out["baseline"] = f"skipped: engine {baseline!r} needs the compiled kernel, " \
                              "not built here"
        elif baseline is not None:
            base_proj = projector(gates, baseline)
            if base_proj.engine == proj.engine:
                out["baseline"] = f"skipped: engine {baseline!r} runs the same copy " \
                                  f"({proj.engine}) as the default engine here"
                base_proj = None
        if base_proj is not None:
            runs["baseline"] = RealtimeStream(base_proj)
        timing = {k: [] for k in runs}
        for stream in runs.values():
            for _ in range(3):                                       # warm-up
                stream.process(cube, strapdown)
        for first in range(0, n_frames, STREAM_BLOCK):
            block = min(STREAM_BLOCK, n_frames - first)
            for key, stream in runs.items():
                timing[key] += [t for _, t in replay(
                    stream, ((cube, strapdown) for _ in range(block)), frame_period=budget)]
        # the stages apart, back to back (clock read between them)
        shape = (cube.shape[0], n_gate, *out["grid"])
        dop = DopplerPower(shape, threads=proj.threads)
        gated = np.empty((cube.shape[0], arr.num_channels, n_gate), np.complex64)
        beams = np.empty(shape, np.complex64)
        split = {k: [] for k in ("gated_range_transform", "strapdown", "projection",
                                 "doppler_and_power")}
        for _ in range(max(1, min(n_frames, 50))):
            t0 = time.perf_counter()
            proj.gated_range_transform(cube, out=gated)
            t1 = time.perf_counter()
            motion = strapdown()
            t2 = time.perf_counter()
            proj.project(gated, motion, gated=True, out=beams, chirp_weights=dop.chirp_weights)
            t3 = time.perf_counter()
            dop(beams, weighted=True)
            t4 = time.perf_counter()
            for key, dt in zip(split, (t1 - t0, t2 - t1, t3 - t2, t4 - t3), strict=True):
                split[key].append(dt)
        svc = _percentiles([t.service for t in timing["engine"]], budget)
        case = {
            "gates": int(n_gate), "threads": proj.threads, "engine": proj.engine,
            "latency": _percentiles([t.latency for t in timing["engine"]], budget),
            "service": svc, "realtime_factor_p95": budget / svc["p95_s"],
            "cpu": _cpu([t.cpu for t in timing["engine"]]),
            "stages": {k: {"p50_s": float(np.percentile(v, 50)),
                           "p95_s": float(np.percentile(v, 95))} for k, v in split.items()},
        }
        if "baseline" in timing:
            b_svc = _percentiles([t.service for t in timing["baseline"]], budget)
            case["baseline"] = {
                "engine": base_proj.engine, "service": b_svc,
                "latency": _percentiles([t.latency for t in timing["baseline"]], budget),
                "cpu": _cpu([t.cpu for t in timing["baseline"]])}
            case["speedup_p50"] = b_svc["p50_s"] / svc["p50_s"]
            case["speedup_p95"] = b_svc["p95_s"] / svc["p95_s"]
            case["cpu_ratio_p50"] = case["baseline"]["cpu"]["p50_s"] / case["cpu"]["p50_s"]
        out["cases"].append(case)
    if paper:
        out["paper_frame"] = _paper_frame_need(threads, baseline)
    out["load_average"]["after"] = list(os.getloadavg())
    return out


def _paper_frame_need(threads: int | None, baseline: str | None = None) -> dict:
    """Wall time of the paper frame's stream (1 gate, 61 x 61 grid) against its frame time.

    With a ``baseline`` engine also that engine with ``factorised=False`` (one
    steering phase per channel, the form before the lattice one) and the ratio.
    """
    from compensation.realtime import RealtimeProjector, compiled_isa
    from compensation.strapdown import static_motion
    from compensation.stream import RealtimeStream
    from raysim.scenario import scenario_from_case

    case = scenario_from_case("rotation_y")
    cfg, arr = case.radar_config(), case.virtual_array()
    n = PAPER_CHIRPS
    off = np.deg2rad(np.linspace(-30.0, 30.0, 61))
    gate = cfg.num_samples // 4
    k = np.arange(cfg.num_samples)
    # a contiguous frame, as an ADC delivers it (a broadcast view would be copied per frame)
    frame = np.ascontiguousarray(np.broadcast_to(
        np.exp(2j * np.pi * gate * k / cfg.num_samples),
        (n, arr.num_channels, cfg.num_samples)), dtype=np.complex64)
    motion = static_motion(np.arange(n) * cfg.chirp_duration)

    def wall(engine, factorised=True):
        proj = RealtimeProjector(arr.virtual_positions, wavelength=cfg.center_wavelength,
                                 range_axis=cfg.range_axis(), range_gates=[gate], azimuth=off,
                                 elevation=off.copy(), threads=threads, engine=engine,
                                 factorised=factorised)
        stream = RealtimeStream(proj)
        stream.process(frame, motion)                                # warm-up
        walls = []
        for _ in range(3):
            t0 = time.perf_counter()
            stream.process(frame, motion)
            walls.append(time.perf_counter() - t0)
        return float(np.median(walls)) * cfg.num_chirps / n, proj

    seconds, proj = wall("auto")
    out = {"frame_shape": [cfg.num_chirps, arr.num_channels, cfg.num_samples],
           "gates": 1, "grid": [61, 61], "threads": proj.threads, "engine": proj.engine,
           "measured_chirps": n, "wall_s": seconds, "frame_duration_s": cfg.frame_duration,
           "speedup_needed": seconds / cfg.frame_duration,
           "clock": f"wall, median of 3 frames of {n} chirps, scaled by "
                    f"{cfg.num_chirps}/{n} (constant cost per chirp)",
           "layout": "400 channels in one slot on a 20 x 20 lattice: the compiled kernel "
                     "sums them by Horner's rule along rows and across rows (3 steering "
                     "phases per chirp and direction, 400 complex products per gate); the "
                     "NumPy engine by a product with 400 steering phases"}
    if baseline is not None and (baseline == "numpy" or compiled_isa() != "missing"):
        # the baseline engine with one steering phase per channel (the general form)
        b_seconds, b_proj = wall(baseline, factorised=False)
        out["baseline"] = {"engine": b_proj.engine, "factorised": False, "wall_s": b_seconds,
                           "speedup": b_seconds / seconds}
    return out


def _table(result: dict) -> str:
    """Short text table of :func:`bench_stream`'s result (milliseconds)."""
    ms = 1e3
    lines = [f"TI frame {result['frame_shape']}, {result['tdm_slots']} TDM slots, grid "
             f"{result['grid'][0]} x {result['grid'][1]}, frame time "
             f"{result['frame_duration_s'] * ms:.2f} ms; {result['frames']} frames per stream; "
             f"clock {result['clock']}",
             f"kernel {result['compiled_kernel']}, CPUs of the process "
             f"{result['cpus_of_process']} (of {result['cpu_count']}), OMP_WAIT_POLICY "
             f"{result['omp_wait_policy']}, load average before "
             f"{result['load_average']['before'][0]:.2f} after "
             f"{result['load_average']['after'][0]:.2f}",
             "gates  engine    threads  service p50 / p95 / p99 ms   over frame  "
             "latency p95  CPU p50 ms | baseline  service p50 / p95  CPU p50 ms  "
             "speedup p50 / p95  CPU ratio"]
    for c in result["cases"]:
        sv = c["service"]
        row = (f"{c['gates']:>5}  {c['engine']:<8}  {c['threads']:>7}  "
               f"{sv['p50_s'] * ms:7.2f} / {sv['p95_s'] * ms:6.2f} / {sv['p99_s'] * ms:6.2f}"
               f"   {sv['over_budget']:9.1%}  {c['latency']['p95_s'] * ms:11.2f}"
               f"  {c['cpu']['p50_s'] * ms:10.2f} |")
        if "baseline" in c:
            b = c["baseline"]["service"]
            row += (f" {c['baseline']['engine']:<8}  {b['p50_s'] * ms:6.2f} / "
                    f"{b['p95_s'] * ms:6.2f}  {c['baseline']['cpu']['p50_s'] * ms:10.2f}  "
                    f"{c['speedup_p50']:7.2f} / {c['speedup_p95']:5.2f}  "
                    f"{c['cpu_ratio_p50']:9.2f}")
        lines.append(row)
    if isinstance(result.get("baseline"), str):
        lines.append(f"baseline {result['baseline']}")
    pf = result.get("paper_frame")
    if pf:
        line = (f"paper frame {pf['frame_shape']}, 1 gate, {pf['engine']}: "
                f"{pf['wall_s'] * ms:.0f} ms per frame against {pf['frame_duration_s'] * ms:.2f}"
                f" ms, {pf['speedup_needed']:.1f}x short of real time")
        if "baseline" in pf:
            b = pf["baseline"]
            line += (f" (baseline {b['engine']}, one steering phase per channel: "
                     f"{b['wall_s'] * ms:.0f} ms)")
        lines.append(line)
    return "\n".join(lines)


def main(argv=None) -> int:
    """``python -m raysim.bench.realtime``: :func:`bench_stream`, a table, JSON with ``--out``."""
    import argparse
    import json

    ap = argparse.ArgumentParser(
        prog="python -m raysim.bench.realtime",
        description="Real-time stream benchmark: TI frames replayed at the frame rate through "
                    "compensation.RealtimeStream, p50/p95/p99 service and latency per gated-"
                    "cell count, against a baseline engine in the same run.")
    ap.add_argument("--frames", type=int, default=STREAM_FRAMES,
                    help=f"frames per stream and gate count (default {STREAM_FRAMES})")
    ap.add_argument("--gates", default=",".join(map(str, GATE_COUNTS)),
                    help="gated-cell counts, comma separated (default 1,3,8)")
    ap.add_argument("--threads", type=int, default=None,
                    help="projector threads (default: the CPUs of this process, at most 8)")
    ap.add_argument("--baseline", default=BASELINE_ENGINE,
                    help=f"engine of the baseline stream, or 'none' (default {BASELINE_ENGINE})")
    ap.add_argument("--no-paper", action="store_true", help="skip the paper frame")
    ap.add_argument("--out", metavar="FILE.json", help="also write the results as JSON")
    args = ap.parse_args(argv)
    try:
        gates = [int(g) for g in args.gates.split(",")]
    except ValueError:
        ap.error(f"--gates must be comma-separated integers, got {args.gates!r}")
    if min(gates) < 1 or args.frames < 1 or (args.threads is not None and args.threads < 1):
        ap.error("--gates, --frames and --threads must be positive")
    result = bench_stream(frames=args.frames, gate_counts=gates, threads=args.threads,
                          paper=not args.no_paper,
                          baseline=None if args.baseline == "none" else args.baseline)
    print(_table(result))
    if args.out:
        with open(args.out, "w", encoding="utf-8") as f:
            json.dump(result, f, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
