"""Real-time compensation benchmark: a TI-size TDM frame compensated and processed.

:func:`bench_realtime` (key ``realtime_compensation`` of ``raysim bench`` and
``benchmarks/bench_compensation.py``) times, in wall-clock seconds
(``time.perf_counter``) with the CPU seconds of the process next to them, the
chain a radar would run on every frame:

1. Hann range FFT of the IF cube ``[128 chirps, 12 channels, 256 samples]``
   (TI-style 3 Tx x 4 Rx TDM, 51.2 us ramps, frame 19.66 ms);
2. strapdown integration of a 1 kHz IMU record to the pose of every transmit
   slot (``128 x 3`` poses, lever arm 10 cm);
3. exact rigid-body projection of the gated range cells onto a 61 x 61
   azimuth x elevation grid (30 deg half width), each slot with its own pose
   (:class:`compensation.realtime.RealtimeProjector`; its set-up, once per
   geometry, is timed apart);
4. Hann Doppler FFT of the beams and their power.

It reports frames per second against the radar's frame rate for 1, 3 and 8
gated cells, the threads used, the same chain with the direct engine
(:func:`compensation.rigid_body_projection`, ``method="direct"``) and the
largest difference of the beams from it relative to their peak.
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


def ti_setup(*, grid: int = 61, half_width_deg: float = 30.0, target_range: float = 12.0):
    """Frame, IMU record and grid of the benchmark (pitch 10 deg at 20 Hz + heave 2 cm at 5 Hz).

    Returns
    -------
    dict
        ``config``, ``array``, ``cube [chirp, channel, sample]``, ``slot_times
        [chirp * 3]`` [s], ``imu`` (time, gyro, accel), ``initial_velocity``,
        ``azimuth``, ``elevation`` [rad], ``target_gate``.
    """
    from raysim.echoes.oracle import PointTarget, element_times, simulate_point_targets
    from raysim.platform.imu import simulate_imu
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


def bench_realtime(*, quick: bool = True, gate_counts=GATE_COUNTS, threads: int | None = None,
                   repeat: int | None = None) -> dict:
    """Frames per second of the compensated TI-size chain against its frame rate.

    Parameters
    ----------
    quick : bool
        Fewer repeats (3 instead of 7) and the direct engine timed once.
    gate_counts : sequence of int
        Numbers of gated range cells (consecutive, centred on the target).
    threads : int, optional
        Worker threads of the projector (default: the CPUs of this process).
    repeat : int, optional
        Timed repeats (best kept); default from ``quick``.

    Returns
    -------
    dict
        JSON-ready; ``cases`` has one entry per gate count with ``wall_s``,
        ``cpu_s``, ``fps``, ``frame_rate_hz``, ``realtime_factor`` (frame
        duration / wall time, > 1 is faster than real time), the per-stage
        split and the agreement with the direct engine.
    """
    import compensation
    from compensation.realtime import RealtimeProjector
    from raysim.processing.maps import range_compress

    rep = (3 if quick else 7) if repeat is None else max(1, int(repeat))
    s = ti_setup()
    cfg, arr, cube = s["config"], s["array"], s["cube"]
    lam, r_axis = cfg.center_wavelength, cfg.range_axis()

    def strapdown():
        return compensation.integrate_imu(*s["imu"], s["slot_times"], lever_arm=LEVER,
                                          velocity="given",
                                          initial_velocity=s["initial_velocity"])

    rc = range_compress(cube)
    motion = strapdown()
    t_range = best_clocks(lambda: range_compress(cube), rep)[0]
    t_strap = best_clocks(strapdown, rep)[0]
    out = {
        "frame_shape": list(cube.shape), "tdm_slots": cfg.num_tx_slots,
        "frame_duration_s": cfg.frame_duration, "frame_rate_hz": 1.0 / cfg.frame_duration,
        "grid": [int(s["azimuth"].size), int(s["elevation"].size)],
        "clock": "wall (time.perf_counter), best of repeats; cpu_s = time.process_time",
        "repeat": rep, "load_average": list(os.getloadavg()),
        "included": ["Hann range FFT of the whole cube", "strapdown of the IMU to 384 slot poses",
                     "exact projection of the gated cells (per-slot poses, near focus)",
                     "Hann Doppler FFT of the beams and |.|^2"],
        "excluded": ["projector set-up (once per geometry, setup_s)",
                     "IF synthesis and IMU simulation (inputs)"],
        "range_fft_s": t_range, "strapdown_s": t_strap, "cases": [],
    }
    for n_gate in gate_counts:
        g0 = s["target_gate"] - n_gate // 2
        gates = np.arange(g0, g0 + n_gate)
        kw = dict(wavelength=lam, range_axis=r_axis, range_gates=gates,
                  azimuth=s["azimuth"], elevation=s["elevation"])
        w0 = time.perf_counter()
        proj = RealtimeProjector(arr.virtual_positions, channel_slot=arr.tx_slot,
                                 threads=threads, **kw)
        setup_s = time.perf_counter() - w0

        def chain(proj=proj):
            beams = proj.project(range_compress(cube), strapdown())
            return np.abs(beams.doppler()) ** 2

        chain()                                                      # warm-up
        wall, cpu, _ = best_clocks(chain, rep)
        t_proj, _, beams = best_clocks(lambda proj=proj: proj.project(rc, motion), rep)
        t_dopp = best_clocks(lambda beams=beams: np.abs(beams.doppler()) ** 2, rep)[0]

        def direct(kw=kw):
            return compensation.rigid_body_projection(
                rc, arr.virtual_positions, motion, channel_slot=arr.tx_slot, method="direct",
                **kw)

        t_direct, cpu_direct, ref = best_clocks(direct, 1)
        err = float(np.abs(beams.data - ref.data).max() / np.abs(ref.data).max())
        out["cases"].append({
            "gates": int(n_gate), "threads": proj.threads, "setup_s": setup_s,
            "wall_s": wall, "cpu_s": cpu, "fps": 1.0 / wall,
            "realtime_factor": cfg.frame_duration / wall,
            "split_wall_s": {"range_fft": t_range, "strapdown": t_strap, "projection": t_proj,
                             "doppler_and_power": t_dopp},
            "direct_projection_wall_s": t_direct, "direct_projection_cpu_s": cpu_direct,
            "projection_speedup_vs_direct": t_direct / t_proj,
            "max_error_vs_direct": err,
        })
    return out
