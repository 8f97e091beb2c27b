"""Rotating parts: a spinning blade's slow-time phase, micro-Doppler and rendering.

Closed forms. The IF phase of a path of delay ``tau`` at mid-chirp is
``2 pi f_mid tau`` (docs/conventions.md, ``exp(+j 2 pi (mu tau t + f_c tau - mu tau^2/2))``),
so a range bin's slow-time phase follows ``4 pi R(t) / lambda_c`` with ``lambda_c``
the mid-chirp wavelength and ``R(t)`` the exact distance to the rotating point.
A point at ``r`` from the hub, spinning at ``omega``, seen at the angle ``beta``
between the line of sight and the rotor plane, has the sinusoidal micro-Doppler
of peak ``2 omega r cos(beta) / lambda`` (Chen, *The Micro-Doppler Effect in
Radar*, 2nd ed., ch. 4, rotor blades; far field: at 10 m from a 5 cm arm the
near-field term ``r^2 / (2 R^2)`` is 1e-5 relative).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from clutter_grounds import grid_ground, range_profile

from raysim.echoes.moving.rotors import Rotor
from raysim.echoes.moving.scatterers import RigidTrajectory, synthesize_tracks
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig

#: Slow-time phase vs ``4 pi R(t) / lambda_c`` [rad]: the video phase ``pi mu tau^2``
#: changes by 5e-3 rad over the arm's range excursion, the Hann window's centre is
#: half a sample off mid-chirp (3e-3 rad), the cube is complex64 (1e-6 rad).
PHASE_TOL_RAD = 0.03
#: Peak instantaneous Doppler vs ``2 omega r cos(beta) / lambda_c`` [Doppler bins] (the brief's).
DOPPLER_TOL_BINS = 0.1
#: Edge of a rotor's Doppler spectrum vs ``2 omega r_tip cos(beta) / lambda_c`` [bins]: the
#: Hann main lobe's half width (2 bins) plus one bin.
SPAN_TOL_BINS = 3.0
#: Turning-point (Airy) widths the edge may lie beyond ``2 omega r_tip cos(beta) / lambda_c``:
#: ``Ai(3)^2`` is 38 dB below the Airy peak, under EDGE_LEVEL_DB.
AIRY_UNITS = 3.0
#: Level below the spectrum's peak that marks its edges [dB].
EDGE_LEVEL_DB = -30.0
#: Share of a still rotor's power within the Hann main lobe around zero Doppler (a Hann
#: window keeps 99.95 % of a tone's power within 2 bins of it).
STILL_SHARE_MIN = 0.999
#: Flash instant vs the blade across the line of sight [chirps]: the flash lasts about
#: ``lambda / (2 L cos(beta) omega)`` = 2.7 chirps for the 5 cm blades at 40 rev/s.
FLASH_TOL_CHIRPS = 1.0
#: Local maxima above this share of the largest amplitude count as flashes.
FLASH_LEVEL = 0.5
HUB = np.array([2.0, 1.0, 10.0])        # below the radar (boresight +z_W), 10.2 m away


def _axis_at(beta: float) -> np.ndarray:
    """A spin axis whose rotor plane makes the angle ``beta`` with the line of sight to HUB."""
    u = HUB / np.linalg.norm(HUB)
    w = np.cross(u, [1.0, 0.0, 0.0])
    w /= np.linalg.norm(w)
    return math.sin(beta) * u + math.cos(beta) * w          # u . axis = sin(beta)


def _point(axis, r: float, theta) -> np.ndarray:
    """Closed-form position ``[..., 3]`` of a point ``r`` from HUB at the angle ``theta`` about
    ``axis`` from the north direction projected on the rotor plane (Rodrigues' rotation)."""
    n = axis / np.linalg.norm(axis)
    e1 = np.array([1.0, 0.0, 0.0]) - n[0] * n
    e1 /= np.linalg.norm(e1)
    th = np.asarray(theta)[..., None]
    return HUB + r * (np.cos(th) * e1 + np.sin(th) * np.cross(n, e1))


def _cube(rotor, config):
    array = upa(1, 1, wavelength=config.wavelength)
    cube = np.zeros((config.num_chirps, 1, config.num_samples), np.complex64)
    synthesize_tracks([rotor.tracks(config, np.zeros(3))], config, array, out=cube)
    return cube[:, 0]


def test_blade_scatterer_phase_and_doppler_follow_closed_form():
    """One scatterer 5 cm out on a blade at 40 rev/s, beta = 30 deg: phase and peak Doppler."""
    config = RadarConfig(num_chirps=512)
    beta, r = math.radians(30.0), 0.05
    rotor = Rotor("fan", HUB, axis=_axis_at(beta), rate=40.0, blades=1, blade_length=r,
                  scatterers_per_blade=1, start_angle=0.3)
    lam = config.center_wavelength
    assert rotor.max_doppler(lam) < 0.5 / config.chirp_interval        # not aliased
    y = range_profile(_cube(rotor, config))
    k = int(np.argmin(np.abs(config.bin_ranges(config.num_samples) - np.linalg.norm(HUB))))
    phase = np.unwrap(np.angle(y[:, k]))
    t = config.chirp_times()
    dist = np.linalg.norm(_point(rotor.axis, r, rotor.omega * t + 0.3), axis=-1)  # exact R(t)
    closed = 4 * np.pi * dist / lam
    err = (phase - phase[0]) - (closed - closed[0])
    print(f"slow-time phase vs 4 pi R / lambda: max error {np.max(np.abs(err)):.2e} rad "
          f"over a swing of {np.ptp(closed):.1f} rad")
    assert np.ptp(closed) > 20 * np.pi                 # the arm sweeps many wavelengths
    assert np.max(np.abs(err)) < PHASE_TOL_RAD
    # instantaneous Doppler: phase rate between chirps, at the middle of each interval
    f_inst = np.diff(phase) / (2 * np.pi * config.chirp_interval)
    peak = 2 * rotor.omega * r * math.cos(beta) / lam
    bin_hz = config.doppler_resolution
    print(f"peak micro-Doppler {f_inst.max():+.1f} / {f_inst.min():+.1f} Hz, closed form "
          f"+-{peak:.1f} Hz ({peak / bin_hz:.1f} bins)")
    assert abs(f_inst.max() - peak) / bin_hz < DOPPLER_TOL_BINS
    assert abs(f_inst.min() + peak) / bin_hz < DOPPLER_TOL_BINS


def _doppler_power(rotor, config) -> tuple[np.ndarray, np.ndarray]:
    """Doppler axis [Hz] and power of the hub's range bins, summed (Hann in slow time)."""
    y = range_profile(_cube(rotor, config))
    k = int(np.argmin(np.abs(config.bin_ranges(config.num_samples) - np.linalg.norm(HUB))))
    pad = 4
    n = config.num_chirps
    spec = np.fft.fftshift(np.fft.fft(y[:, k - 2:k + 3] * np.hanning(n)[:, None], pad * n,
                                      axis=0), axes=0)
    f = np.fft.fftshift(np.fft.fftfreq(pad * n, config.chirp_interval))
    return f, np.sum(np.abs(spec) ** 2, axis=1)


def test_rotor_doppler_span_and_still_rotor():
    """Two 5 cm blades at 40 rev/s span +-2 omega r_tip cos(beta) / lambda; rate 0 gives 0 Hz."""
    config = RadarConfig(num_chirps=512)
    beta = math.radians(20.0)
    lam, bin_hz = config.center_wavelength, config.doppler_resolution
    spin = Rotor("rotor", HUB, axis=_axis_at(beta), rate=40.0, blades=2, blade_length=0.05)
    assert spin.radii(config.wavelength).size > 40                 # lambda / 4 spacing
    f, p = _doppler_power(spin, config)
    above = f[p > p.max() * 10 ** (EDGE_LEVEL_DB / 10)]
    edge = 2 * spin.omega * spin.blade_length * math.cos(beta) / lam
    # turning-point width: lines J_n(m) of index m = 2 pi edge / omega fall off beyond n = m
    # as Ai(2^(1/3) (n - m) / m^(1/3)) (Abramowitz & Stegun 9.3.23), lines omega / 2 pi apart
    airy = (2 * math.pi * edge / spin.omega / 2) ** (1 / 3) * spin.rate
    hi = SPAN_TOL_BINS * bin_hz + AIRY_UNITS * airy
    print(f"spectrum edges {above.min():+.0f} / {above.max():+.0f} Hz, closed form "
          f"+-{edge:.0f} Hz ({edge / bin_hz:.0f} bins), turning-point width {airy:.0f} Hz")
    for e in (above.max(), -above.min()):
        assert -SPAN_TOL_BINS * bin_hz < e - edge < hi
    spin_share = p[np.abs(f) <= 2 * bin_hz].sum() / p.sum()
    still = Rotor("rotor", HUB, axis=_axis_at(beta), rate=0.0, blades=2, blade_length=0.05)
    f, p = _doppler_power(still, config)
    share = p[np.abs(f) <= 2 * bin_hz].sum() / p.sum()
    print(f"power within 2 bins of 0 Hz: still rotor {share:.6f}, spinning {spin_share:.4f}")
    assert share > STILL_SHARE_MIN
    assert spin_share < 0.5


def test_blade_flashes_when_across_the_line_of_sight():
    """The in-phase scatterers of a blade add up when it lies across the line of sight
    (Chen, ch. 4: the blade's sinc return): the hub bin's amplitude peaks there."""
    config = RadarConfig(num_chirps=512)
    rotor = Rotor("rotor", HUB, axis=_axis_at(math.radians(20.0)), rate=40.0, blades=2,
                  blade_length=0.05)
    y = range_profile(_cube(rotor, config))
    k = int(np.argmin(np.abs(config.bin_ranges(config.num_samples) - np.linalg.norm(HUB))))
    a = np.abs(y[:, k])
    t = config.chirp_times()
    tip = rotor.positions(t, config.wavelength)[rotor.radii(config.wavelength).size - 1]
    g = (tip - HUB) @ (HUB / np.linalg.norm(HUB))          # tip's range offset: 0 at a flash
    across = np.nonzero(np.sign(g[1:]) != np.sign(g[:-1]))[0] + 0.5
    peaks = np.nonzero((a[1:-1] > a[:-2]) & (a[1:-1] >= a[2:])
                       & (a[1:-1] > FLASH_LEVEL * a.max()))[0] + 1
    print(f"flashes at chirps {peaks.tolist()}, blade across the line of sight at "
          f"{across.tolist()}; flash / median amplitude {a.max() / np.median(a):.0f}")
    assert len(peaks) == len(across) >= 2
    assert np.all(np.abs(peaks - across) <= FLASH_TOL_CHIRPS)
    assert a.max() > 10 * np.median(a)


def test_fast_rotor_aliases():
    """Tip Doppler beyond 1 / (2 T_rep) folds back: the chirp-to-chirp phase rate is the
    closed-form micro-Doppler wrapped into +-1 / (2 T_rep)."""
    config = RadarConfig(num_chirps=256)
    lam, bin_hz = config.center_wavelength, config.doppler_resolution
    fast = Rotor("fan", HUB, axis=_axis_at(0.0), rate=60.0, blades=1, blade_length=0.05,
                 scatterers_per_blade=1)
    f_prf = 1.0 / config.chirp_interval
    assert 0.5 * f_prf < fast.max_doppler(lam) < f_prf                 # aliased once
    y = range_profile(_cube(fast, config))
    k = int(np.argmin(np.abs(config.bin_ranges(config.num_samples) - np.linalg.norm(HUB))))
    measured = np.angle(y[1:, k] * np.conj(y[:-1, k])) / (2 * np.pi * config.chirp_interval)
    t = config.chirp_times()
    dist = np.linalg.norm(_point(fast.axis, 0.05, fast.omega * t), axis=-1)
    true = 2 * np.diff(dist) / (lam * config.chirp_interval)           # mean over each interval
    wrapped = (true + 0.5 * f_prf) % f_prf - 0.5 * f_prf
    err = (measured - wrapped + 0.5 * f_prf) % f_prf - 0.5 * f_prf
    print(f"true Doppler up to {np.abs(true).max():.0f} Hz, sampled +-{0.5 * f_prf:.0f} Hz: "
          f"wrapped closed form matched within {np.abs(err).max() / bin_hz:.2e} bins")
    assert np.abs(true).max() > 0.5 * f_prf
    assert np.max(np.abs(err)) / bin_hz < DOPPLER_TOL_BINS


def test_rotor_on_a_trajectory_and_geometry():
    """Scatterers stay at their radii in the rotor plane and ride with a moving hub."""
    traj = RigidTrajectory(start=HUB, heading=math.radians(90.0), speed=4.0)
    rotor = Rotor("prop", traj, axis=[1.0, 0.0, 0.0], rate=10.0, blades=3, blade_length=0.2,
                  root=0.05, scatterers_per_blade=4)
    t = np.array([0.0, 0.013, 0.5])
    p = rotor.positions(t, 3.9e-3)                                     # [12, 3, 3]
    c, _ = traj.pose(t)
    arm = p - c[None]
    radii = np.repeat(rotor.radii(3.9e-3)[None], 3, axis=0).ravel()
    assert np.allclose(np.linalg.norm(arm, axis=-1), radii[:, None])
    axis_w = np.array([0.0, 1.0, 0.0])                                # body x turned east
    assert np.allclose(arm @ axis_w, 0.0, atol=1e-12)
    # a quarter turn later, blade 0's tip is where the closed-form rotation puts it
    tip = rotor.positions(np.array([0.0, 0.025]), 3.9e-3)[3] - traj.pose(
        np.array([0.0, 0.025]))[0]
    assert np.allclose(np.cross(axis_w, tip[0]), tip[1])


@pytest.mark.parametrize("kwargs, match", [
    ({"hub": [0.0, 1.0]}, "hub"),
    ({"axis": [0.0, 0.0, 0.0]}, "axis"),
    ({"blades": 0}, "blades"),
    ({"blade_length": -0.1}, "blade_length"),
    ({"root": 0.2}, "root"),
    ({"scatterers_per_blade": 0}, "scatterers_per_blade"),
    ({"rcs_dbsm": math.nan}, "rcs_dbsm"),
    ({"rcs_per": "disc"}, "rcs_per"),
    ({"rate": math.inf}, "rate"),
])
def test_rotor_bad_values_are_named(kwargs, match):
    args = {"name": "fan", "hub": HUB, "blade_length": 0.1} | kwargs
    with pytest.raises(ValueError, match=match):
        Rotor(**args)


def test_rotor_renders_through_ground_clutter():
    """SceneClutter(movers=[rotor]) with a given ground returns the rotor's tracks."""
    from raysim.echoes.ground.field import FieldSettings
    from raysim.echoes.ground.surface import GroundSurface
    from raysim.echoes.scene_clutter import SceneClutter
    from raysim.platform.motion import stationary

    config = RadarConfig(num_chirps=64)
    ground = GroundSurface.from_meshes([(grid_ground(30.0, 2, 12.0), "dry-soil")])
    rotor = Rotor("fan", HUB, axis=_axis_at(0.0), rate=20.0, blade_length=0.05)
    model = SceneClutter(FieldSettings(shadowing=False), ground=ground, specular=False,
                          ghosts=False, movers=[rotor])
    field = model.field_for(config, upa(1, 1, wavelength=config.wavelength), np.zeros(3),
                            np.eye(3))
    ground_paths = field.paths(config, np.zeros(3), np.eye(3), time=0.0)
    traced = ground_paths.select(np.zeros(ground_paths.num_paths, bool))   # no ray tracing
    _, tracks = model.paths(None, traced, config, upa(1, 1, wavelength=config.wavelength),
                            stationary(), np.zeros(3), time=0.0)
    (tr,) = tracks
    assert set(tr.label) == {"rotor"}
    direct = _cube(rotor, config)
    cube = np.zeros((config.num_chirps, 1, config.num_samples), np.complex64)
    synthesize_tracks(tracks, config, upa(1, 1, wavelength=config.wavelength), out=cube)
    assert np.array_equal(cube[:, 0], direct)
    with pytest.raises(ValueError, match="Rotor"):
        SceneClutter(movers=[object()])


SCENE = '[scene]\nname = "flat_reflectors"\n'
ROTOR = '[[scene.rotors]]\nhub_m = [2.0, 1.0, 10.0]\nrate_rps = 40\nblade_length_m = 0.05\n'


def test_rotor_keys_reach_the_clutter_model():
    from raysim.pipeline.sources import _clutter
    from raysim.scenario import loads_scenario

    sc = loads_scenario(SCENE + ROTOR + "blades = 3\n" + ROTOR.replace(
        "rate_rps = 40", "rate_radps = 62.83185307179586").replace("[2.0", "[4.0")
                        + "speed_mps = 2.0\n")
    fixed, moving = _clutter(sc).movers
    assert isinstance(fixed, Rotor) and isinstance(moving, Rotor)
    assert fixed.blades == 3 and fixed.rate == 40.0 and fixed.blade_length == 0.05
    assert np.array_equal(fixed.hub, HUB)
    assert math.isclose(moving.rate, 10.0)
    assert isinstance(moving.hub, RigidTrajectory) and moving.hub.speed == 2.0


@pytest.mark.parametrize("text, match", [
    (SCENE + ROTOR.replace("rate_rps = 40\n", ""), "rate_rps"),
    (SCENE + ROTOR + "rate_radps = 3.0\n", "rate_radps"),
    (SCENE + ROTOR + "axis = [0, 0, 0]\n", "axis"),
    (SCENE + ROTOR + "root_m = 0.05\n", "root_m"),
    (SCENE + ROTOR + "blades = 0\n", "blades"),
    (SCENE + ROTOR.replace("0.05", "-1"), "blade_length_m"),
    (SCENE + ROTOR + 'rcs_per = "disc"\n', "rcs_per"),
    (SCENE + ROTOR + "spin = 3\n", "spin"),
    (SCENE + '[scene.clutter]\nmode = "sionna"\n' + ROTOR, "mode = 'field'"),
])
def test_rotor_scenario_bad_values_are_named(text, match):
    from raysim.scenario import loads_scenario

    with pytest.raises(ValueError, match=match):
        loads_scenario(text)
