"""The ``compensation`` package, unchanged, on ray-traced frames.

A hovering radar over the ``flat_reflectors`` scene is rendered by the ray
tracer (:func:`raysim.echoes.rt.render.render_scene`); the IF cube, the virtual
element positions and the chirp times go, as plain arrays, through
``compensation.integrate_imu`` (ideal IMU), ``compensation.rigid_body_projection``
and ``compensation.paper_chain``. For every corner reflector the compensated
slow-time signal must look like the stationary platform's: Doppler peak at
zero and the stationary mainlobe width; without compensation it does not.
"""

from __future__ import annotations

import numpy as np
import pytest

from raysim.platform.motion import hover_jitter, sinusoid, stationary
from raysim.processing import maps as processing
from raysim.processing import metrics
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig
from raysim.vocabulary import REFERENCE

pytestmark = pytest.mark.sionna

#: Ideal IMU: integrated radar position vs truth [m] and attitude [rad].
POSE_TOL_M = 1e-6
POSE_TOL_RAD = 1e-6
#: Compensated pseudo-velocity of a static reflector [Doppler bins].
PSEUDO_VELOCITY_TOL_BINS = 0.05
#: Compensated / stationary Doppler mainlobe width, exact chain (relative).
EXACT_WIDTH_TOL = 0.02
#: The same for the paper chain (far-field and small-angle approximations).
PAPER_WIDTH_TOL = 0.05
#: Lever arm of the radar phase centre [m].
LEVER = np.array([0.0, 0.0, 0.10])


@pytest.fixture(scope="module")
def hover_frames(warm_kernels):
    """Stationary and hovering ray-traced frames of the reflectors, plus the IMU pose."""
    from compensation import integrate_imu
    from raysim.echoes.rt.render import render_scene
    from raysim.echoes.rt.scenes import load_scene
    from raysim.echoes.rt.trace import MonostaticTracer
    from raysim.platform.imu import simulate_imu

    config = RadarConfig(num_chirps=64, idle_time=940e-6)           # 64 ms frame
    array = upa(8, 8, wavelength=config.wavelength)
    scene = load_scene("flat_reflectors", frequency=config.carrier_frequency)
    # hover jitter plus a gust: centimetres of translation and degrees of tilt in 64 ms
    motion = (hover_jitter(7) + sinusoid("pitch", np.deg2rad(3.0), 4.0)
              + sinusoid("x", 0.02, 4.0) + sinusoid("z", 0.01, 3.0))
    tracer = MonostaticTracer(specular=False, diffuse=False)        # the four reflectors
    frames = {name: render_scene(scene, config, array, traj, LEVER, tracer=tracer)
              for name, traj in (("stationary", stationary()), ("hover", motion))}
    t = config.chirp_times()
    imu = simulate_imu(motion, "ideal", rate=4000.0, start=t[0] - 1e-3, end=t[-1] + 1e-3)
    pose = integrate_imu(*imu.to_arrays(), t, lever_arm=LEVER, reference_time=t[0],
                         initial_attitude=motion.attitude([t[0]]).as_matrix()[0],
                         initial_position=motion.position([t[0]])[0], velocity="given",
                         initial_velocity=motion.velocity([t[0]])[0])
    return {"config": config, "array": array, "scene": scene, "motion": motion,
            "frames": frames, "pose": pose}


def _targets(data):
    """(name, range, unit direction in W) of every reflector from the nominal phase centre."""
    out = []
    for t in data["scene"].targets:
        v = t.position - LEVER
        r = float(np.linalg.norm(v))
        out.append((t.name, r, v / r))
    return out


def test_ideal_imu_pose_matches_truth(hover_frames):
    """integrate_imu on the simulated ideal IMU reproduces the radar's trajectory."""
    pose, motion = hover_frames["pose"], hover_frames["motion"]
    t = hover_frames["config"].chirp_times()
    truth = motion.point_world(t, LEVER)[:, 0]
    assert np.abs(pose.radar_position - truth).max() < POSE_TOL_M
    d_att = pose.attitude - motion.attitude(t).as_matrix()
    assert np.abs(d_att).max() < POSE_TOL_RAD
    # the motion is large enough to matter: centimetres within the frame
    assert np.ptp(truth, axis=0).max() > 0.01


def _slow_time(data, chain, name_r_u):
    """Slow-time signal of one reflector's beam: ``chain`` (``none``, ``paper``, ``exact``)
    on the hovering frame, or :data:`REFERENCE` (``none`` on the stationary frame)."""
    from compensation import beam_projection, paper_chain, rigid_body_projection
    from compensation.geometry import az_el

    config, array = data["config"], data["array"]
    _, r, u = name_r_u
    frame = data["frames"]["stationary" if chain == REFERENCE else "hover"]
    rc = processing.range_compress(frame.data)                 # plain ndarray [chirp, ch, range]
    r_axis = config.range_axis()
    gate = int(np.argmin(np.abs(r_axis - r)))
    az, el = (float(x) for x in az_el(u))
    kw = dict(wavelength=config.center_wavelength, range_axis=r_axis, azimuth=[az],
              elevation=[el], range_gates=[gate], grid_shape=array.grid_shape)
    pos = array.virtual_positions
    if chain in (REFERENCE, "none"):
        bc = beam_projection(rc, pos, chirp_time=frame.chirp_times, **kw)
    elif chain == "exact":
        bc = rigid_body_projection(rc, pos, data["pose"], **kw)
    else:
        bc = paper_chain(rc, pos, data["pose"], direction=u, **kw)
    return bc.data[:, 0, 0, 0]


@pytest.mark.parametrize("chain", ["exact", "paper"])
def test_compensation_restores_every_reflector(hover_frames, chain):
    """Exact and paper chains: pseudo-velocity ~ 0 and stationary mainlobe width per reflector."""
    config = hover_frames["config"]
    dt = config.chirp_interval
    bin_hz = config.doppler_resolution
    tol = EXACT_WIDTH_TOL if chain == "exact" else PAPER_WIDTH_TOL
    for target in _targets(hover_frames):
        ref = _slow_time(hover_frames, REFERENCE, target)
        unc = _slow_time(hover_frames, "none", target)
        comp = _slow_time(hover_frames, chain, target)
        w_ref = metrics.doppler_mainlobe_width(ref, dt)
        w_unc = metrics.doppler_mainlobe_width(unc, dt)
        w_comp = metrics.doppler_mainlobe_width(comp, dt)
        pv_unc = metrics.doppler_peak_frequency(unc, dt) / bin_hz
        pv_comp = metrics.doppler_peak_frequency(comp, dt) / bin_hz
        print(f"{chain} {target[0]}: width {w_ref / bin_hz:.3f} (stationary) "
              f"{w_unc / bin_hz:.3f} (hover) {w_comp / bin_hz:.3f} (compensated) bins; "
              f"Doppler peak {pv_unc:+.3f} -> {pv_comp:+.3f} bins")
        assert w_ref / bin_hz == pytest.approx(1.44, rel=0.02)
        assert abs(pv_comp) < PSEUDO_VELOCITY_TOL_BINS
        assert w_comp == pytest.approx(w_ref, rel=tol)
        # without compensation the reflector is off zero Doppler by bins, or smeared
        assert abs(pv_unc) > 0.5 or w_unc > 1.2 * w_ref


def test_compensation_inputs_are_plain_arrays(hover_frames):
    """The package takes the ray-traced frame's arrays as they are: no raysim types needed."""
    from compensation import rigid_body_projection

    config, array = hover_frames["config"], hover_frames["array"]
    frame = hover_frames["frames"]["hover"]
    rc = processing.range_compress(frame.data)
    assert isinstance(rc, np.ndarray) and rc.dtype == np.complex64
    bc = rigid_body_projection(rc, np.asarray(array.virtual_positions), hover_frames["pose"],
                               wavelength=config.center_wavelength,
                               range_axis=config.range_axis(), azimuth=np.deg2rad([-10, 0, 10]),
                               elevation=[0.0], range_gates=np.arange(95, 105),
                               grid_shape=array.grid_shape)
    assert bc.data.shape == (config.num_chirps, 10, 3, 1)
    assert np.all(np.isfinite(bc.data))
