"""Dense ground points (compensation.ground_dense) and the tilt they give.

Closed forms: the periodic Hann window's DFT has three non-zero bins, 1 and -1/2
either side (Harris, Proc. IEEE 1978, table 1), so the range kernel of a tone on a
cell is 1 there, 1/2 in magnitude one cell off and 0 beyond; linear interpolation of
a phasor ``exp(j psi t / T)`` between two samples a period ``T`` apart is exact to
first order in ``psi``. Synthetic frames: point scatterers on a plane 15 m below,
seen through an attitude off by a known tilt, rendered as their range kernels times
the TDM array's response at every slot's own instant, the platform moving at a
velocity no model knows; the tilt of :func:`compensation.ground_plane.ground_tilt`
against the truth and its stated covariance.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.ground_dense import aligned_snapshot, dense_ground_directions, range_kernel
from compensation.ground_plane import ground_tilt
from compensation.strapdown import static_motion

#: Wavelength [m], range cell [m], cells (= samples of the range FFT), chirp loops.
WAVELENGTH, CELL, CELLS, LOOPS = 3.868e-3, 0.15, 150, 4
#: Slot period [s] (three TDM slots a loop) and the platform's velocity [m/s].
SLOT_S, VELOCITY = 70e-6, np.array([0.4, -0.3, 0.2])
#: Height [m], scatterers and their horizontal extent [m], tilt (tilt_n, tilt_e) [rad].
HEIGHT, SCATTERERS, EXTENT, TILT = 15.0, 30, 11.0, np.deg2rad([0.4, -0.65])
#: Rounding of the kernel's closed form; first-order phase of the interpolation [rad].
KERNEL_TOL, ALIGN_PHASE_TOL = 1e-12, 2e-4
#: Noise-free single scatterer: range [cells] and direction cosine to within.
RANGE_TOL_CELLS, DIRECTION_TOL = 0.01, 1e-4
#: Draws of the synthetic ground, the least of them that give a tilt, and the least of
#: those within the stated 95 % ellipse (chi-square of 2 dof: 5.991; measured: 5 of 5).
DRAWS, MIN_USABLE, MIN_WITHIN, CHI2_95 = 6, 4, 4, 5.991


def _array():
    """xWR18xx virtual array (8 in a row, 4 raised half a wavelength) and its slots."""
    lam = WAVELENGTH
    pos = np.array([[0.5 * lam * i, 0.0, 0.0] for i in range(8)]
                   + [[lam + 0.5 * lam * i, 0.5 * lam, 0.0] for i in range(4)])
    return pos, np.repeat([0, 1, 2], 4)


def _frame(points, amplitudes, pos, slot) -> tuple[np.ndarray, np.ndarray]:
    """Range-compressed frame ``[loop, channel, cell]`` of scatterers at ``points`` [m]
    (from the radar at t = 0, which moves at :data:`VELOCITY`) and the slot instants."""
    t = (np.arange(LOOPS)[:, None] * 3 + slot[None, :]) * SLOT_S              # [loop, ch]
    rel = points[None, None, :, :] - VELOCITY * t[..., None, None]           # [l, c, s, 3]
    r = np.linalg.norm(rel, axis=-1)
    u = rel / r[..., None]
    k = 2 * np.pi / WAVELENGTH
    phase = np.exp(-1j * (2 * k * r + k * np.einsum("lcsi,ci->lcs", u, pos)))
    # the envelope at t = 0: the radar moves 1e-3 of a cell over the frame
    kern = range_kernel(np.arange(CELLS)[None, :] - r[0, 0, :, None] / CELL, CELLS)
    rc = np.einsum("s,lcs,sb->lcb", amplitudes, phase, kern)
    return rc, np.arange(LOOPS * 3) * SLOT_S


def _ground(rng, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``n`` scatterers of the level ground as the tilted attitude sees them, amplitudes."""
    xy = rng.uniform(-EXTENT, EXTENT, size=(n, 2))
    p_w = np.column_stack([xy, np.full(n, HEIGHT)])
    seen = p_w @ Rotation.from_rotvec([TILT[0], TILT[1], 0.0]).as_matrix()
    amp = rng.rayleigh(1.0, n) * np.exp(2j * np.pi * rng.random(n)) / np.linalg.norm(
        seen, axis=1) ** 2
    return seen, amp


def test_range_kernel_is_the_hann_window_dft():
    k = range_kernel(np.arange(-5, 6), CELLS)
    assert abs(k[5] - 1.0) <= KERNEL_TOL
    assert np.all(np.abs(np.abs(k[[4, 6]]) - 0.5) <= KERNEL_TOL)
    assert np.all(np.abs(k[[0, 1, 2, 3, 7, 8, 9, 10]]) <= KERNEL_TOL)


def test_aligned_snapshot_removes_the_slot_delay():
    pos, slot = _array()
    psi = 0.1                      # phase advance per loop [rad]
    t = (np.arange(LOOPS)[:, None] * 3 + slot[None, :]) * SLOT_S
    rc = np.exp(1j * psi * t / (3 * SLOT_S))[..., None]                   # [loop, ch, 1]
    snap = aligned_snapshot(rc, np.arange(LOOPS * 3) * SLOT_S, slot, chirp=1)[:, 0]
    want = np.exp(1j * psi)        # the slot-0 instant of loop 1
    assert np.max(np.abs(np.angle(snap / want))) <= ALIGN_PHASE_TOL
    assert np.max(np.abs(np.angle(rc[1, :, 0] / want))) > 100 * ALIGN_PHASE_TOL  # can fail
    with pytest.raises(ValueError, match="chirp must lie"):
        aligned_snapshot(rc, np.arange(LOOPS * 3) * SLOT_S, slot, chirp=0)


def test_one_scatterer_gives_its_range_and_direction():
    pos, slot = _array()
    u = np.array([0.21, -0.13])
    p = 16.27 * np.array([*u, np.sqrt(1 - u @ u)])
    rc, t = _frame(p[None], np.array([1.0]), pos, slot)
    r, d = dense_ground_directions(rc, pos, static_motion(t), wavelength=WAVELENGTH,
                                   range_axis=np.arange(CELLS) * CELL,
                                   gates=np.arange(90, 130), channel_slot=slot)
    assert r.shape == (1,)
    # the radar moved at VELOCITY until the snapshot's instant (slot 0 of loop 1)
    seen = p - VELOCITY * 3 * SLOT_S
    assert abs(r[0] - np.linalg.norm(seen)) <= RANGE_TOL_CELLS * CELL
    assert np.max(np.abs(d[0] - seen / np.linalg.norm(seen))) <= DIRECTION_TOL


def test_synthetic_ground_tilt_is_covered_by_its_stated_spread():
    """Random level grounds of 30 scatterers (two to four share the cells beyond the
    nadir, as on the flights) seen through TILT, one frame each: the dense fit gives a
    tilt in at least MIN_USABLE of DRAWS, within the stated 95 % ellipse in at least
    MIN_WITHIN (measured: five usable, errors up to 0.30 deg, stated 0.13-0.24 deg)."""
    pos, slot = _array()
    usable = within = 0
    for seed in range(DRAWS):
        rng = np.random.default_rng(seed)
        rc, t = _frame(*_ground(rng, SCATTERERS), pos, slot)
        fit = ground_tilt([rc], pos, [static_motion(t)], wavelength=WAVELENGTH,
                          range_axis=np.arange(CELLS) * CELL, gates=np.arange(60, CELLS),
                          warn=False, channel_slot=slot)
        if not fit.usable:
            continue
        usable += 1
        err = fit.tilt - TILT
        within += float(err @ np.linalg.solve(fit.tilt_covariance, err)) <= CHI2_95
    assert usable >= MIN_USABLE, usable
    assert within >= MIN_WITHIN, (within, usable)


#: Relative agreement of the tilt's covariance from one frame and from that frame repeated.
REPEAT_RTOL = 1e-6


def test_repeated_frames_state_one_look():
    """A hover repeats the same scatterers in the same cells: the same frame given three
    times states the spread of one (the points' covariance times the frames' number)."""
    pos, slot = _array()
    rc, t = _frame(*_ground(np.random.default_rng(0), SCATTERERS), pos, slot)
    kw = dict(wavelength=WAVELENGTH, range_axis=np.arange(CELLS) * CELL,
              gates=np.arange(60, CELLS), warn=False, channel_slot=slot)
    one = ground_tilt([rc], pos, [static_motion(t)], **kw)
    three = ground_tilt([rc] * 3, pos, [static_motion(t)] * 3, **kw)
    assert three.points == 3 * one.points and three.inliers == 3 * one.inliers
    np.testing.assert_allclose(three.tilt, one.tilt, rtol=REPEAT_RTOL)
    np.testing.assert_allclose(three.tilt_covariance, one.tilt_covariance, rtol=REPEAT_RTOL)


def test_range_axis_must_match_the_cells():
    pos, slot = _array()
    rc = np.zeros((LOOPS, len(pos), CELLS), complex)
    with pytest.raises(ValueError, match="range_axis must hold the 150 cells"):
        dense_ground_directions(rc, pos, static_motion(np.arange(LOOPS * 3) * SLOT_S),
                                wavelength=WAVELENGTH, range_axis=np.arange(10) * CELL,
                                gates=np.arange(5), channel_slot=slot)
