"""Cost of motion compensation relative to the bare FFT chain on the same paper frame.

Both chains start from the same IF cube ``[chirp, channel, sample]`` (the
paper's 256 x 400 x 600 rotation-about-Y frame) and produce the same products:

* bare: range FFT of the whole cube, Doppler FFT of the whole cube, the
  range-Doppler power map (summed over channels), and an angle-Doppler cube at
  the gated range cells (Doppler spectra beamformed onto the global grid);
* compensated: the same range FFT, Doppler FFT and range-Doppler map (used for
  detection and gating), plus strapdown integration of the IMU samples, the
  exact rigid-body projection of the gated cells onto the same grid for every
  chirp, and the Doppler FFT of the beams.

Prints one JSON object with the timings (wall clock, ``time.perf_counter``,
best of ``--repeat`` interleaved runs; NumPy/SciPy/BLAS default threads, i.e.
all CPUs of the process) and the ratio, plus (key ``realtime``, unless
``--no-realtime``) :func:`raysim.bench.realtime.bench_realtime`: a
TI-size TDM frame compensated and processed (range transform of the gated
cells, strapdown, exact projection with the compiled real-time kernel, Doppler
FFT and power), frames per second against its frame rate, wall and CPU seconds
per frame and per stage, for 1, 3 and 8 gated cells (``--realtime-threads``
worker threads; ``--realtime-only`` skips the paper-frame ratio).

This ratio is not the ``processing.compensated_over_bare`` of ``raysim bench``:
that one times the paper chain (four steps, static motion, 121 x 31 beams, 20
gates) in CPU seconds against a bare chain of only the range and Doppler FFTs;
here the exact chain (strapdown included, 61 x 61 beams, 3 gates) is timed in
wall seconds against a bare chain that also forms the range-Doppler map and
the angle-Doppler beams of the same gates. Both are in the JSON (``measures``).
Run: ``python -m raysim.bench.compensation_speed [--gates 3] [--grid-step-deg 2]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numpy as np

from compensation import integrate_imu, rigid_body_projection
from raysim.echoes.oracle import simulate_point_targets
from raysim.pipeline.sources import point_targets
from raysim.platform.imu import simulate_imu
from raysim.processing.maps import az_el_grid, doppler_fft, range_compress, steering_matrix
from raysim.scenario import scenario_from_case


def _best(fn, repeat: int) -> tuple[float, object]:
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", default="rotation_y")
    ap.add_argument("--gates", type=int, default=3, help="gated range cells around the target")
    ap.add_argument("--grid-half-width-deg", type=float, default=30.0)
    ap.add_argument("--grid-step-deg", type=float, default=1.0)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--no-realtime", action="store_true", help="skip the TI-size real-time case")
    ap.add_argument("--realtime-only", action="store_true",
                    help="only the TI-size real-time case (no paper-frame ratio)")
    ap.add_argument("--realtime-threads", type=int, default=None,
                    help="worker threads of the real-time case (default: CPUs, at most 8)")
    args = ap.parse_args(argv)
    if args.no_realtime and args.realtime_only:
        raise ValueError("--no-realtime and --realtime-only exclude each other; expected one")
    if args.realtime_only:
        result = {"realtime": _realtime(args)}
        print(json.dumps(result, indent=2))
        return result

    case = scenario_from_case(args.case)
    cfg, arr, traj = case.radar_config(), case.virtual_array(), case.trajectory()
    frame = simulate_point_targets(cfg, arr, point_targets(case), traj,
                                   lever_arm=case.lever_arm)
    tgt = case.scene.targets[0]
    target_range, target_az, target_el = (tgt.range_m, np.deg2rad(tgt.az_deg),
                                          np.deg2rad(tgt.el_deg))
    cube = frame.data
    tc = frame.chirp_times
    imu = simulate_imu(traj, "ideal", rate=1000.0, start=tc[0] - 0.02,
                       end=tc[-1] + 0.02).to_arrays()
    lam = cfg.center_wavelength
    r_axis = cfg.range_axis()
    g0 = int(np.argmin(np.abs(r_axis - target_range)))
    gates = np.arange(g0 - args.gates // 2, g0 - args.gates // 2 + args.gates)
    n = int(round(args.grid_half_width_deg / args.grid_step_deg))
    off = np.deg2rad(np.arange(-n, n + 1) * args.grid_step_deg)
    az, el = target_az + off, target_el + off
    steer = steering_matrix(arr, lam, az_el_grid(az, el)).conj().T.astype(np.complex64)

    def front_end():
        rc = range_compress(cube)                                   # [chirp, channel, range]
        spec = doppler_fft(rc, axis=0)                              # [doppler, channel, range]
        rd = np.einsum("dcr,dcr->rd", spec, spec.conj()).real       # [range, doppler]
        return rc, spec, rd

    def bare():
        rc, spec, rd = front_end()
        ad = [(spec[:, :, g] @ steer) / arr.num_channels for g in gates]   # [doppler, D]
        return rd, np.abs(np.stack(ad, axis=1)) ** 2

    def compensated():
        rc, spec, rd = front_end()
        motion = integrate_imu(*imu, tc, lever_arm=case.lever_arm, velocity="given",
                               initial_velocity=traj.velocity([tc[0]])[0])
        beams = rigid_body_projection(rc, arr.virtual_positions, motion, wavelength=lam,
                                      range_axis=r_axis, azimuth=az, elevation=el,
                                      range_gates=gates, grid_shape=arr.grid_shape)
        return rd, np.abs(beams.doppler()) ** 2

    rc_fixed = range_compress(cube)

    def projection_only(rc=rc_fixed):
        motion = integrate_imu(*imu, tc, lever_arm=case.lever_arm, velocity="given",
                               initial_velocity=traj.velocity([tc[0]])[0])
        return rigid_body_projection(rc, arr.virtual_positions, motion, wavelength=lam,
                                     range_axis=r_axis, azimuth=az, elevation=el,
                                     range_gates=gates, grid_shape=arr.grid_shape).doppler()

    bare(), compensated()                                            # warm-up
    # interleave the two chains so that load changes on a shared machine hit both
    t_bare = t_comp = float("inf")
    for _ in range(args.repeat):
        t_bare = min(t_bare, _best(bare, 1)[0])
        t_comp = min(t_comp, _best(compensated, 1)[0])
    t_proj, _ = _best(projection_only, args.repeat)
    result = {
        "case": case.name, "cube_shape": list(cube.shape), "gates": int(gates.size),
        "directions": int(az.size * el.size), "grid_step_deg": args.grid_step_deg,
        "bare_s": t_bare, "compensated_s": t_comp, "ratio": t_comp / t_bare,
        "strapdown_plus_projection_s": t_proj, "repeat": args.repeat,
        "clock": "wall (time.perf_counter), best of repeat, interleaved",
        "threads": "NumPy/SciPy/BLAS defaults (all CPUs of the process)",
        "measures": {
            "bare": "range FFT + Doppler FFT of the whole cube + range-Doppler map + "
                    "angle-Doppler beams (steering-matrix product) at the gated cells",
            "compensated": "range FFT + Doppler FFT + range-Doppler map + strapdown + exact "
                           "rigid-body projection (engine 'auto': NUFFT on the 20 x 20 grid) of "
                           "the gated cells for every chirp + Doppler FFT of the beams",
        },
        "cpu_count": os.cpu_count(), "load_average": list(os.getloadavg()),
        "python": platform.python_version(), "numpy": np.__version__,
    }
    if not args.no_realtime:
        result["realtime"] = _realtime(args)
    print(json.dumps(result, indent=2))
    return result


def _realtime(args) -> dict:
    from raysim.bench.realtime import bench_realtime

    return bench_realtime(quick=args.repeat < 5, repeat=args.repeat,
                          threads=args.realtime_threads)


if __name__ == "__main__":
    main()
