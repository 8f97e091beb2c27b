"""DPCA projection against closed forms.

Data are plane waves with the exact far-field phase of every element,
``x[n, m] = sum_s a_s exp(-j 2 pi / lambda u_s . (2 d_n + R_n p_m))``
(docs/conventions.md: one-way virtual convention, range phase growing with
range), projected with ``focus="far"``, for which the exact chain's model is
exact. Closed forms:

* two scatterers in one beam under a horizontal displacement ``D``: the exact
  chain's outputs change their relative phase by ``-4 pi / lambda D . (u1 - u2)``;
* DPCA with an integer shift ``-2 D / spacing``: the output of the stationary
  reference sub-aperture (``plan.reference_positions``), to float precision;
* with a fractional shift: within the Lagrange bound of
  :func:`compensation.dpca.interpolation_error` of that output, or, band-limited,
  within ``sum_q |w_q| |e_q| / |sum_q w_q|`` of it, ``e_q`` the closed-form error
  of the estimate at each element (:func:`compensation.subaperture_shift.shift_error`,
  two axes ``e_x + e_y + e_x e_y``) for a unit plane wave.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation import (
    DPCABeams,
    PlatformMotion,
    beam_projection,
    direction,
    dpca_plan,
    dpca_projection,
    rigid_body_projection,
    static_motion,
)
from compensation.dpca import interpolation_error, lagrange_weights
from compensation.subaperture_shift import shift_error

LAM = 3.9e-3
K = 2 * np.pi / LAM
#: Virtual element spacing (half a wavelength of ``p_tx + p_rx``) [m]; a horizontal
#: displacement of ``SPACING / 2`` shifts the sub-aperture by one element.
SPACING = LAM / 2
#: complex64 round-off relative to the peak.
FLOAT_TOL = 2e-6
#: Phase round-off of complex64 beam outputs of magnitude >= 0.1 [rad].
PHASE_FLOAT_TOL = 1e-4
T_CHIRP = 60e-6
R_GATE = [15.0]


def _upa(nx, ny):
    ix, iy = np.divmod(np.arange(nx * ny), ny)
    p = np.stack([ix * SPACING, iy * SPACING, np.zeros(nx * ny)], axis=1)
    return p - p.mean(axis=0)


def _motion(disp, att=None):
    disp = np.asarray(disp, dtype=float)
    n = disp.shape[0]
    att = np.broadcast_to(np.eye(3), (n, 3, 3)).copy() if att is None else att
    z = np.zeros((n, 3))
    return PlatformMotion(np.arange(n) * T_CHIRP, att, disp, z, z.copy(), np.zeros(3))


def _cube(p, disp, dirs, amps=None, att=None, slot=None):
    """Plane waves ``[chirp, channel, 1]``; with ``slot``, chirp-slot poses (chirp major)."""
    disp = np.asarray(disp, dtype=float)
    dirs = np.atleast_2d(dirs)
    amps = np.ones(dirs.shape[0]) if amps is None else np.asarray(amps)
    att = np.broadcast_to(np.eye(3), (disp.shape[0], 3, 3)) if att is None else att
    n_slot = 1 if slot is None else int(np.max(slot)) + 1
    pose = np.arange(disp.shape[0]).reshape(-1, n_slot)          # [chirp, slot]
    out = np.zeros((pose.shape[0], p.shape[0], 1), dtype=complex)
    for m in range(p.shape[0]):
        k = pose[:, 0 if slot is None else slot[m]]
        world = 2 * disp[k] + att[k] @ p[m]                       # [chirp, 3]
        out[:, m, 0] = np.exp(-1j * K * world @ dirs.T) @ amps
    return out.astype(np.complex64)


def _dir(az_deg, el_deg):
    return direction(np.deg2rad(az_deg), np.deg2rad(el_deg))


def _beam(fn, x, p, motion, az_deg, el_deg, **kw):
    kw.setdefault("focus", "far")
    return fn(x, p, motion, wavelength=LAM, range_axis=R_GATE, azimuth=np.deg2rad(az_deg),
              elevation=np.deg2rad(el_deg), **kw)


def _stationary(x_ref, plan, az_deg, el_deg):
    """Conventional beams of the reference sub-aperture (no motion)."""
    return beam_projection(x_ref, plan.reference_positions, wavelength=LAM, range_axis=R_GATE,
                           azimuth=np.deg2rad(az_deg), elevation=np.deg2rad(el_deg),
                           focus="far", method="direct").data


def _dpsi(u, u_g):
    """Per-element phase step of ``u`` relative to the beam ``u_g`` along x and y [rad]."""
    return K * (u - u_g)[..., :2] * SPACING


def _bound(u, u_g, order):
    ex, ey = (interpolation_error(v, order) for v in np.moveaxis(_dpsi(u, u_g), -1, 0))
    return ex * (1 + ey) + ey


def _band_bound(plan, u, weights=None, lam=LAM):
    """Stated error of a band-limited beam output for a unit plane wave from ``u``, ``[chirp]``.

    ``sum_q |w_q| (e_x + e_y + e_x e_y) / |sum_q w_q|`` with the closed-form
    errors of the estimates at every element and chirp (any beam direction).
    """
    tx, ty = plan.positions()
    k = 2 * np.pi / lam
    psi = k * plan.lattice[1:] @ np.asarray(u)                    # phase step along a, b
    vis = k * np.linalg.norm(plan.lattice[1:], axis=1)
    (nx, ny), (kx, ky) = plan.full_shape, plan.sub_shape
    ex = shift_error(tx.ravel(), nx, [psi[0]], band=plan.band, visible=vis[0])[:, 0]
    ey = shift_error(ty.ravel(), ny, [psi[1]], band=plan.band, visible=vis[1])[:, 0]
    ex, ey = ex.reshape(tx.shape), ey.reshape(ty.shape)
    e = ex[:, :, None] + ey[:, None, :] + ex[:, :, None] * ey[:, None, :]
    w = np.ones((kx, ky)) if weights is None else np.asarray(weights).reshape(kx, ky)
    return (e * np.abs(w)).sum(axis=(1, 2)) / abs(w.sum())


#: Interpolations of the closed-form tests: (interpolation, Lagrange order).
INTERPOLATIONS = [("lagrange", 1), ("lagrange", 3), ("bandlimited", 3)]


# --- (a) two scatterers in one beam -------------------------------------------------------

BEAM = (4.0, 2.0)                                     # az, el [deg]
U1, U2 = _dir(7.0, 2.0), _dir(1.0, 4.0)
#: Horizontal displacements [element shifts]: rest, integer, two fractional.
SHIFTS_A = np.array([[0.0, 0.0], [1.0, -1.0], [1.37, -0.55], [-0.8, 0.62]])


@pytest.mark.parametrize(("interpolation", "order"), INTERPOLATIONS)
def test_two_scatterers_relative_phase_restored(interpolation, order):
    p = _upa(12, 12)
    disp = np.column_stack([SHIFTS_A * SPACING / 2, np.zeros(len(SHIFTS_A))])
    motion = _motion(disp)
    u_g = _dir(*BEAM)
    ys = {}
    for name, fn in (("exact", rigid_body_projection), ("dpca", dpca_projection)):
        kw = dict(grid_shape=(12, 12))
        if name == "dpca":
            kw.update(order=order, interpolation=interpolation)
        out = [_beam(fn, _cube(p, disp, u), p, motion, [BEAM[0]], [BEAM[1]], **kw)
               for u in (U1, U2)]
        ys[name] = [b.data[:, 0, 0, 0].astype(complex) for b in out]
        plan = getattr(out[0], "plan", None)
    # closed form: relative phase of the exact chain's outputs changes by -4 pi/lam D.(u1-u2)
    e1, e2 = ys["exact"]
    closed = -4 * np.pi / LAM * disp @ (U1 - U2)
    got = np.angle(e1 * np.conj(e2) * np.conj(e1[0] * np.conj(e2[0])))
    np.testing.assert_allclose(got, np.angle(np.exp(1j * closed)), atol=PHASE_FLOAT_TOL)
    assert np.abs(closed).max() > 0.3                  # the exact chain leaves ~0.4 rad
    # DPCA: restored, integer shifts to float precision, fractional within the bound
    d1, d2 = ys["dpca"]
    assert min(np.abs(d1).min(), np.abs(d2).min()) > 0.3          # both inside the beam
    rel = np.angle(d1 * np.conj(d2) * np.conj(d1[0] * np.conj(d2[0])))
    if interpolation == "lagrange":        # relative to each scatterer's beam output
        b1, b2 = _bound(U1, u_g, order) * np.abs(d1[0]), _bound(U2, u_g, order) * np.abs(d2[0])
    else:                                  # relative to each scatterer's amplitude (1)
        b1, b2 = _band_bound(plan, U1), _band_bound(plan, U2)
    bound = np.arcsin(np.minimum(1, b1 / np.abs(d1[0]))) + np.arcsin(
        np.minimum(1, b2 / np.abs(d2[0])))
    integer = np.all(SHIFTS_A == np.rint(SHIFTS_A), axis=1)
    assert np.all(np.abs(rel[integer]) < PHASE_FLOAT_TOL)
    assert np.all(np.abs(rel[~integer]) <= np.broadcast_to(bound, rel.shape)[~integer]
                  + PHASE_FLOAT_TOL)
    assert np.abs(rel).max() < 0.1 * np.abs(closed).max()
    # the beam output of the pair is restored too
    total = d1 + d2
    assert np.all(np.abs(total - total[0]) <= (b1 + b2) * 2 + FLOAT_TOL)


# --- (b) integer displacement: the stationary sub-aperture ---------------------------------


@pytest.mark.parametrize("interpolation", ["lagrange", "bandlimited"])
def test_integer_shift_reproduces_stationary_subaperture(interpolation):
    rng = np.random.default_rng(3)
    p = _upa(10, 8)
    shifts = rng.integers(-2, 3, size=(9, 2)).astype(float)
    disp = np.column_stack([shifts * SPACING / 2, np.zeros(9)])
    dirs = _dir(rng.uniform(-40, 40, 12), rng.uniform(-40, 40, 12))
    amps = rng.standard_normal(12) + 1j * rng.standard_normal(12)
    az, el = np.arange(-40.0, 41.0, 8.0), np.arange(-30.0, 31.0, 10.0)
    beams = _beam(dpca_projection, _cube(p, disp, dirs, amps), p, _motion(disp), az, el,
                  grid_shape=(10, 8), interpolation=interpolation)
    plan = beams.plan
    assert isinstance(beams, DPCABeams)
    np.testing.assert_array_equal(plan.shift, -shifts)            # -2 D / spacing
    assert plan.sub_shape == (10 - 4, 8 - 4)          # N - span (integer: no stencil, no reach)
    assert plan.interpolation == interpolation
    x_ref = np.repeat(_cube(plan.reference_positions, np.zeros((1, 3)), dirs, amps), 9, axis=0)
    ref = _stationary(x_ref, plan, az, el)
    np.testing.assert_allclose(beams.data, ref, atol=FLOAT_TOL * np.abs(ref).max())


# --- (c) fractional displacement within the stated error -----------------------------------


#: Largest error of a beam within 5 deg of the scatterer over the peak, by interpolation
#: (band-limited, uniform weights: measured 7.1e-3; its estimates beyond the array's
#: end elements weigh as much as the others).
MAIN_LOBE_ERROR = {("lagrange", 1): 3e-2, ("lagrange", 3): 1e-3, ("bandlimited", 3): 1e-2}


@pytest.mark.parametrize(("interpolation", "order"), INTERPOLATIONS)
def test_fractional_shift_within_interpolation_bound(interpolation, order):
    rng = np.random.default_rng(4)
    p = _upa(12, 12)
    shifts = rng.uniform(-1.3, 1.3, size=(6, 2))
    disp = np.column_stack([shifts * SPACING / 2, rng.uniform(-1, 1, 6) * 0.0])
    u = _dir(6.0, -3.0)
    az, el = np.arange(-30.0, 31.0, 3.0), np.arange(-15.0, 16.0, 3.0)
    beams = _beam(dpca_projection, _cube(p, disp, u), p, _motion(disp), az, el,
                  grid_shape=(12, 12), order=order, interpolation=interpolation)
    plan = beams.plan
    x_ref = np.repeat(_cube(plan.reference_positions, np.zeros((1, 3)), u), 6, axis=0)
    ref = _stationary(x_ref, plan, az, el)
    ug = direction(*np.meshgrid(np.deg2rad(az), np.deg2rad(el), indexing="ij"))
    if interpolation == "lagrange":
        bound = _bound(u, ug, order)[None, None] * np.abs(ref)
    else:
        bound = _band_bound(plan, u)[:, None, None, None]
    err = np.abs(beams.data - ref)
    assert np.all(err <= bound + FLOAT_TOL)
    # inside the main lobe the error is small: the worst beam within 5 deg of the scatterer
    near = np.linalg.norm(ug - u, axis=-1) < np.deg2rad(5.0)
    worst = (err / np.abs(ref).max())[:, :, near].max()
    assert worst < MAIN_LOBE_ERROR[interpolation, order]


def test_lagrange_weights_and_bound():
    f = np.linspace(0, 0.999, 50)
    for order in (1, 3):
        h = lagrange_weights(f, order)
        np.testing.assert_allclose(h.sum(axis=1), 1.0, atol=1e-12)
        nodes = np.array({1: (0, 1), 3: (-1, 0, 1, 2)}[order])
        for x in (0.05, 0.3, 1.0, 2.5):
            err = np.abs(h @ np.exp(1j * x * nodes) - np.exp(1j * x * f))
            assert err.max() <= interpolation_error(x, order) + 1e-12
    assert interpolation_error(0.5, 1) == pytest.approx(0.5 ** 2 / 8)
    assert interpolation_error(0.5, 3) == pytest.approx(3 * 0.5 ** 4 / 128)


#: Worst error of the band-limited estimate over its design band (0.7 of the visible
#: band) at the middle of 8 elements (measured -37 dB) and half a spacing beyond an end
#: element (measured -5 dB) [dB].
BAND_MID_ERROR_DB, BAND_BEYOND_ERROR_DB = -30.0, 0.0


def test_bandlimited_shift_kernel():
    from compensation.subaperture_shift import shift_channels, shift_kernel

    g = shift_kernel([0.0, 3.0, 7.0, 2.5, -0.5], 8)
    np.testing.assert_array_equal(g[:3], np.eye(8)[[0, 3, 7]])     # integer: the element
    psi = np.linspace(-0.7 * np.pi, 0.7 * np.pi, 301)
    err = shift_error([3.5, 0.25, -0.5], 8, psi)
    mid, edge, beyond = (20 * np.log10(e.max()) for e in err)
    assert mid < BAND_MID_ERROR_DB and mid < edge < beyond < BAND_BEYOND_ERROR_DB
    direct = np.abs(g[3] @ np.exp(-1j * np.outer(np.arange(8), psi)) - np.exp(-1j * 2.5 * psi))
    np.testing.assert_allclose(shift_error([2.5], 8, psi)[0], direct, atol=1e-12)
    with pytest.raises(ValueError, match="band"):
        shift_kernel([0.5], 8, band=1.5)
    # a plane wave inside the band, positions of a 6 x 1 block shifted by 0.4: within the
    # stated error; an axis of one element holds still
    u = 0.3
    x = np.exp(-1j * np.pi * u * np.arange(8))[None, :, None].astype(np.complex64)
    t = (np.arange(6) + 1.4)[None]
    est = shift_channels(x, (8, 1), t, np.zeros((1, 1)))[0, :, 0]
    bound = shift_error(t[0], 8, [np.pi * u])[:, 0]
    assert np.all(np.abs(est - np.exp(-1j * np.pi * u * t[0])) <= bound + FLOAT_TOL)


# --- (d) TDM virtual array -----------------------------------------------------------------


def test_tdm_each_slot_at_its_pose():
    # 2 TX along x (4 spacings apart) x 4 x 8 RX: an 8 x 8 virtual array, TX major
    rx = np.array([[ix * SPACING, iy * SPACING, 0.0] for ix in range(4) for iy in range(8)])
    tx = np.array([[0.0, 0.0, 0.0], [4 * SPACING, 0.0, 0.0]])
    p = (tx[:, None] + rx[None]).reshape(-1, 3)
    slot = np.repeat([0, 1], 32)
    shifts = np.array([[0.0, 0.0], [1.0, 0.0], [-1.0, 1.0], [0.4, -0.3], [-0.7, 0.5]])
    n = len(shifts)
    disp = np.zeros((n, 2, 3))
    disp[:, :, :2] = (shifts * SPACING / 2)[:, None]
    disp[:, 1, 2] = 0.37e-3 * (1 + np.arange(n))            # slot 1 lower: its own pose
    disp = disp.reshape(-1, 3)
    motion = _motion(disp)
    # a scatterer in the beam direction: exactly 1 at every chirp when each slot has its pose
    u_g = _dir(0.0, 0.0)
    on = _beam(dpca_projection, _cube(p, disp, u_g, slot=slot), p, motion, [0.0], [0.0],
               channel_slot=slot)
    np.testing.assert_allclose(on.data[:, 0, 0, 0], 1.0, atol=FLOAT_TOL)
    assert on.plan.sub_shape == (8 - 4, 8 - 4) and on.chirp_time.size == n
    # two scatterers symmetric in azimuth (equal u_z, so the vertical offsets cancel)
    u1, u2 = _dir(6.0, 0.0), _dir(-6.0, 0.0)
    exact = [_beam(rigid_body_projection, _cube(p, disp, u, slot=slot), p, motion, [0.0], [0.0],
                   channel_slot=slot).data[:, 0, 0, 0].astype(complex) for u in (u1, u2)]
    ys = [_beam(dpca_projection, _cube(p, disp, u, slot=slot), p, motion, [0.0], [0.0],
                channel_slot=slot).data[:, 0, 0, 0].astype(complex) for u in (u1, u2)]
    closed = -4 * np.pi / LAM * disp[::2] @ (u1 - u2)
    got = np.angle(exact[0] * np.conj(exact[1]) / (exact[0][0] * np.conj(exact[1][0])))
    np.testing.assert_allclose(got, np.angle(np.exp(1j * closed)), atol=PHASE_FLOAT_TOL)
    rel = np.angle(ys[0] * np.conj(ys[1]) / (ys[0][0] * np.conj(ys[1][0])))
    integer = np.all(shifts == np.rint(shifts), axis=1)
    assert np.all(np.abs(rel[integer]) < PHASE_FLOAT_TOL)
    bound = 2 * np.arcsin(np.minimum(1, _bound(u1, u_g, 3)))
    assert np.all(np.abs(rel) <= bound + PHASE_FLOAT_TOL)
    assert np.abs(closed).max() > 3 * np.abs(rel).max()


# --- (e) failure modes ---------------------------------------------------------------------


def test_displacement_beyond_spare_aperture_raises():
    p = _upa(8, 8)
    disp = np.zeros((3, 3))
    disp[1, 0] = 4.2 * SPACING / 2
    disp[2, 0] = -3.1 * SPACING / 2
    with pytest.raises(ValueError, match="spare aperture"):
        dpca_plan(p, _motion(disp), wavelength=LAM, grid_shape=(8, 8), interpolation="lagrange")
    # band-limited: one element left at a span of 7.3 (positions -0.2 .. 7.1), none at 8.5
    assert dpca_plan(p, _motion(disp), wavelength=LAM, grid_shape=(8, 8)).sub_shape == (1, 8)
    disp[2, 0] = -4.3 * SPACING / 2
    with pytest.raises(ValueError, match="spare aperture"):
        dpca_plan(p, _motion(disp), wavelength=LAM, grid_shape=(8, 8))
    with pytest.raises(ValueError, match="subaperture"):
        dpca_plan(p, _motion(disp[:2] / 4), wavelength=LAM, grid_shape=(8, 8),
                  subaperture=(8, 8))
    for bad in ((8, 8), 5, (0, 3), ("a", 2)):
        with pytest.raises(ValueError, match="subaperture"):
            dpca_plan(p, _motion(disp[:2] / 4), wavelength=LAM, grid_shape=(8, 8),
                      subaperture=bad)


def test_small_subaperture_and_rotation_are_reported():
    p = _upa(12, 12)
    disp = np.zeros((3, 3))
    disp[1, 0] = 5.5 * SPACING / 2
    plan = dpca_plan(p, _motion(disp), wavelength=LAM, grid_shape=(12, 12),
                     interpolation="lagrange")
    # shifts 0 and -5.5: offsets 0 (integer) and -7 .. -4 (cubic stencil around -6)
    assert plan.sub_shape == (12 - 7, 12)
    # band-limited: positions within REACH = 0.6 of the array: indices 5 .. 11
    band = dpca_plan(p, _motion(disp), wavelength=LAM, grid_shape=(12, 12))
    assert band.sub_shape == (7, 12) and band.warnings == ()
    assert any(w.startswith("dpca aperture:") for w in plan.warnings)
    assert plan.gain_loss_db == pytest.approx(10 * np.log10(144 / 60))
    assert plan.resolution_loss == (2.4, 1.0)
    assert plan.beamwidth_sub[0] == pytest.approx(0.886 * LAM / (5 * SPACING))
    # yaw of 10 deg over the frame moves the corner elements by ~0.9 spacing
    att = Rotation.from_euler("Z", np.deg2rad([0.0, 5.0, 10.0])[:, None]).as_matrix()
    x = _cube(p, np.zeros((3, 3)), _dir(0.0, 0.0), att=att)
    beams = _beam(dpca_projection, x, p, _motion(np.zeros((3, 3)), att), [0.0], [0.0],
                  grid_shape=(12, 12))
    rot = [w for w in beams.warnings if w.startswith("dpca rotation:")]
    assert rot and beams.plan.rotation_misplacement > 0.5
    assert 0 < beams.plan.overlap < 1
    np.testing.assert_allclose(beams.data[:, 0, 0, 0], 1.0, atol=FLOAT_TOL)   # beam still exact
    yaw = Rotation.from_euler("Z", np.deg2rad([0.0, 0.5, 1.0])[:, None]).as_matrix()
    small = dpca_plan(p, _motion(np.zeros((3, 3)), yaw), wavelength=LAM, grid_shape=(12, 12))
    assert small.warnings == ()


def test_bad_input_is_named():
    p = _upa(4, 4)
    m = static_motion(np.arange(2) * T_CHIRP)
    x = np.ones((2, 16, 1), dtype=np.complex64)
    with pytest.raises(ValueError, match="order"):
        dpca_plan(p, m, wavelength=LAM, order=2)
    bent = p.copy()
    bent[3, 0] += 1e-4
    with pytest.raises(ValueError, match="lattice"):
        dpca_plan(bent, m, wavelength=LAM)
    with pytest.raises(ValueError, match="distinct"):
        dpca_plan(np.vstack([p, p[:1]]), m, wavelength=LAM)
    with pytest.raises(ValueError, match="weights"):
        _beam(dpca_projection, x, p, m, [0.0], [0.0], weights=np.ones(3))
    with pytest.raises(ValueError, match="method"):
        _beam(dpca_projection, x, p, m, [0.0], [0.0], method="lattice",
              channel_slot=np.zeros(16, dtype=int))
    with pytest.raises(ValueError, match="poses"):
        _beam(dpca_projection, x, p, static_motion(np.arange(3) * T_CHIRP), [0.0], [0.0])
    with pytest.raises(ValueError, match="PlatformMotion"):
        dpca_plan(p, "motion", wavelength=LAM)


# --- (f) zero motion -----------------------------------------------------------------------


def test_zero_motion_is_beamforming_the_subaperture():
    rng = np.random.default_rng(5)
    p = _upa(10, 10)
    x = (rng.standard_normal((6, 100, 3)) + 1j * rng.standard_normal((6, 100, 3))).astype(
        np.complex64)
    m = static_motion(np.arange(6) * T_CHIRP)
    kw = dict(wavelength=LAM, range_axis=[10.0, 12.0, 14.0], azimuth=np.deg2rad([-20.0, 3.0]),
              elevation=np.deg2rad([0.0, 11.0]), grid_shape=(10, 10))
    full = dpca_projection(x, p, m, **kw)
    np.testing.assert_array_equal(full.data, rigid_body_projection(x, p, m, **kw).data)
    assert full.plan.sub_shape == (10, 10) and full.plan.gain_loss_db == 0.0
    attrs = full.to_xarray().attrs
    assert attrs["dpca_sub_shape"] == [10, 10] and attrs["dpca"].startswith("dpca: sub-aperture")
    taper = np.hanning(8)
    sub = dpca_projection(x, p, m, subaperture=(6, 4), **kw,
                          weights=lambda i: taper[i[:, 0]] * taper[i[:, 1]])
    chans = sub.plan.channels((0, 0))
    ix, iy = np.divmod(chans, 10)
    assert (ix.min(), ix.max(), iy.min(), iy.max()) == (2, 7, 3, 6)
    kw["grid_shape"] = (6, 4)
    ref = beam_projection(x[:, chans], p[chans], weights=taper[ix - 2] * taper[iy - 3], **kw)
    np.testing.assert_allclose(sub.data, ref.data, atol=FLOAT_TOL * np.abs(ref.data).max())


# --- the point-target oracle: exact bistatic ranges, IMU-integrated motion -----------------

#: Near-field and range-compression departures from the plane-wave closed form: the
#: second-order range term ``k |D|^2 / R`` (1e-3 rad at 2.5 mm and 12 m) and the
#: aperture's far-field error ``|p|^2 / 8R`` changing with the sub-aperture [rad].
NEAR_FIELD_TOL = 0.02


def _oracle_case(arr, cfg, traj, targets, lever):
    from compensation import integrate_imu
    from raysim.echoes.oracle import simulate_point_targets
    from raysim.platform.imu import simulate_imu
    from raysim.platform.kinematics import element_times
    from raysim.processing.maps import range_compress

    rcs = [range_compress(simulate_point_targets(cfg, arr, [t], traj, lever_arm=lever).data)
           for t in targets]
    times = np.unique(element_times(cfg, arr))
    s = simulate_imu(traj, "ideal", rate=1000.0, start=-0.01, end=times[-1] + 0.01)
    motion = integrate_imu(s.time, s.gyro, s.accel, times, lever_arm=lever, velocity="given",
                           initial_velocity=traj.velocity([0.0])[0])
    return rcs, motion


def test_oracle_two_targets_upa():
    from raysim.echoes.oracle import PointTarget
    from raysim.platform.motion import sinusoid
    from raysim.radar.arrays import upa
    from raysim.radar.config import RadarConfig

    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6)
    arr = upa(12, 12, wavelength=cfg.wavelength)
    lever = np.array([0.0, 0.0, 0.1])
    traj = sinusoid("x", 2.5e-3, 100.0) + sinusoid("y", 1.5e-3, 70.0, phase=1.0)
    az, el = np.deg2rad([4.0, -2.0]), np.deg2rad([1.0, 3.0])
    targets = [PointTarget.at(12.0, a, e, radar_origin=lever) for a, e in zip(az, el,
                                                                            strict=True)]
    rcs, motion = _oracle_case(arr, cfg, traj, targets, lever)
    gate = int(np.argmin(np.abs(cfg.range_axis() - 12.0)))
    kw = dict(wavelength=cfg.center_wavelength, range_axis=cfg.range_axis(), range_gates=[gate],
              azimuth=[np.deg2rad(1.0)], elevation=[np.deg2rad(2.0)], grid_shape=(12, 12))
    p = arr.virtual_positions
    u1, u2 = direction(az[0], el[0]), direction(az[1], el[1])
    d = motion.radar_displacement
    closed = -4 * np.pi / cfg.center_wavelength * (d - d[0]) @ (u1 - u2)

    def rel(ys):
        return np.angle(ys[0] * np.conj(ys[1]) / (ys[0][0] * np.conj(ys[1][0])))

    exact = [rigid_body_projection(rc, p, motion, **kw).data[:, 0, 0, 0] for rc in rcs]
    np.testing.assert_allclose(rel(exact), np.angle(np.exp(1j * closed)), atol=NEAR_FIELD_TOL)
    assert np.abs(closed).max() > 0.3
    beams = [dpca_projection(rc, p, motion, **kw) for rc in rcs]
    assert beams[0].plan.interpolation == "bandlimited"
    # stated error relative to each target's amplitude (its mean channel magnitude)
    amp = [np.abs(rc[0, :, gate]).mean() for rc in rcs]
    d0 = [abs(b.data[0, 0, 0, 0]) for b in beams]
    bound = sum(np.arcsin(np.minimum(1.0, _band_bound(b.plan, u, lam=cfg.center_wavelength)
                                     * a / d))
                for b, u, a, d in zip(beams, (u1, u2), amp, d0, strict=True))
    got = np.abs(rel([b.data[:, 0, 0, 0] for b in beams]))
    assert np.all(got <= bound + NEAR_FIELD_TOL)
    lagrange = [dpca_projection(rc, p, motion, interpolation="lagrange", **kw) for rc in rcs]
    u_g = direction(*np.deg2rad([1.0, 2.0]))
    bound = sum(np.arcsin(min(1.0, float(_bound(u, u_g, 3)))) for u in (u1, u2))
    assert np.abs(rel([b.data[:, 0, 0, 0] for b in lagrange])).max() <= bound + NEAR_FIELD_TOL
    assert beams[0].warnings == () and beams[0].plan.sub_shape[0] < 12


def test_oracle_ti_tdm_array():
    from raysim.echoes.oracle import PointTarget
    from raysim.platform.motion import sinusoid
    from raysim.processing import metrics
    from raysim.radar.arrays import ti_3tx4rx
    from raysim.radar.config import RadarConfig

    cfg = RadarConfig(num_chirps=64, sample_rate=2.5e6, num_tx_slots=3)
    arr = ti_3tx4rx(cfg.wavelength)
    lever = np.array([0.0, 0.0, 0.1])
    traj = sinusoid("x", 1.5e-3, 100.0) + sinusoid("z", 0.02, 5.0)
    az = np.deg2rad([12.0, 2.0])
    targets = [PointTarget.at(12.0, a, 0.0, radar_origin=lever) for a in az]
    rcs, motion = _oracle_case(arr, cfg, traj, targets, lever)
    gate = int(np.argmin(np.abs(cfg.range_axis() - 12.0)))
    kw = dict(wavelength=cfg.center_wavelength, range_axis=cfg.range_axis(), range_gates=[gate],
              azimuth=az[:1], elevation=[0.0], channel_slot=arr.tx_slot, order=1)
    p = arr.virtual_positions
    on = dpca_projection(rcs[0], p, motion, **kw)
    y = on.data[:, 0, 0, 0]
    assert abs(y.mean()) / np.abs(y).mean() > 0.9999                 # each slot at its pose
    pv = metrics.pseudo_velocity(y, cfg.chirp_interval, cfg.center_wavelength)
    assert abs(pv / cfg.velocity_resolution) <= 0.05
    assert on.plan.reference_index.shape[0] < 12 and on.plan.shift[:, 1].max() == 0


# --- clutter: many scatterers in every beam --------------------------------------------------


def _ridge_leakage_db(beams) -> float:
    """Doppler power outside bins -1..+1 of zero over the total, all beams (Hann) [dB]."""
    power = (np.abs(beams.doppler()) ** 2).sum(axis=(1, 2, 3))
    c = power.size // 2
    return float(10 * np.log10(np.delete(power, [c - 1, c, c + 1]).sum() / power.sum()))


def test_clutter_ridge_leakage():
    """Plane-wave clutter within 30 deg of nadir, 2.5 mm x 1.5 mm horizontal hover jitter.

    12 x 12 array, 30 dB Taylor taper on the (sub-)aperture, beams +-20 deg. Measured:
    exact -19.8 dB, dpca Lagrange order 1 -43.0 dB, order 3 -51.0 dB, band-limited
    -52.5 dB (stationary: no leakage). Wider
    clutter (+-50 deg, beams +-40 deg) is limited by the scatterers whose phase step
    relative to the beam exceeds pi / 2 (docs/compensation.md).
    """
    from scipy.signal.windows import taylor

    rng = np.random.default_rng(7)
    n, n_chirp = 12, 64
    p = _upa(n, n)
    ph = np.linspace(0, 2 * np.pi, n_chirp)
    disp = np.zeros((n_chirp, 3))
    disp[:, 0], disp[:, 1] = 1.25e-3 * np.sin(ph), 0.75e-3 * np.cos(1.3 * ph)
    uv = rng.uniform(-1, 1, (3000, 2))
    uv = uv[np.hypot(*uv.T) < np.sin(np.deg2rad(30))][:800]
    u = np.column_stack([uv, np.sqrt(1 - (uv ** 2).sum(axis=1))])
    amps = rng.standard_normal(len(u)) + 1j * rng.standard_normal(len(u))
    x = _cube(p, disp, u, amps)
    grid = np.arange(-20.0, 21.0, 4.0)
    motion = _motion(disp)

    def taper(k):
        return taylor(k, nbar=4, sll=30)

    full = np.outer(taper(n), taper(n)).ravel()
    exact = _beam(rigid_body_projection, x, p, motion, grid, grid, grid_shape=(n, n),
                  weights=full)
    leak, sub = {"exact": _ridge_leakage_db(exact)}, {}
    for interpolation, order in INTERPOLATIONS:
        plan = dpca_plan(p, motion, wavelength=LAM, grid_shape=(n, n), order=order,
                         interpolation=interpolation)
        wx, wy = (taper(k) for k in plan.sub_shape)
        b = _beam(dpca_projection, x, p, motion, grid, grid, grid_shape=(n, n), order=order,
                  interpolation=interpolation,
                  weights=lambda i, wx=wx, wy=wy: wx[i[:, 0]] * wy[i[:, 1]])
        leak[interpolation, order] = _ridge_leakage_db(b)
        sub[interpolation, order] = plan.sub_shape
    assert leak["exact"] > -22
    assert leak["lagrange", 1] < -38 and leak["lagrange", 3] < -48
    # band-limited: the most aperture (10 x 10 against 8 x 10 linear, 6 x 8 cubic), -52.5 dB
    assert sub["bandlimited", 3] == (10, 10) and leak["bandlimited", 3] < -50
