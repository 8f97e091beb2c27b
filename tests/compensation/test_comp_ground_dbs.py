"""Ground tilt over a dense ground from range-Doppler cells (compensation.ground_dbs).

Synthetic frames as in ``test_comp_ground_dense.py``: point scatterers on a level
ground 15 m below, seen through an attitude off by a known tilt, rendered as their
range kernels times the TDM array's response at every slot's own instant (the
exact range of every slot, so the Doppler is the geometry's ``2 v . u / lambda``),
the platform swaying at a hover's velocity over the 64 loops of a frame. The
ground is dense: most range cells hold more scatterers than one snapshot's
one-to-three plane waves explain, so the range cells alone give fewer points
than a plane needs; the range-Doppler cells split the rings.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from compensation.ground_dbs import doppler_ground_directions, doppler_spectra
from compensation.ground_dense import dense_ground_directions, range_kernel
from compensation.ground_looks import GroundLook
from compensation.ground_plane import MIN_GROUND_POINTS, GroundPlane, fit_ground_plane, ground_tilt
from compensation.ground_refit import GroundRetilt
from compensation.radar_inertial import DEFAULT_TILT_SIGMA
from compensation.strapdown import static_motion

#: Wavelength [m], range cell [m], cells (= samples of the range FFT), chirp loops.
WAVELENGTH, CELL, CELLS, LOOPS = 3.868e-3, 0.15, 150, 64
#: Slot period [s] (three TDM slots a loop) and the platform's sway [m/s] (the flights'
#: hover: 0.15-0.25 m/s horizontally).
SLOT_S, VELOCITY = 70e-6, np.array([0.2, -0.15, 0.1])
#: Height [m], scatterers and their horizontal extent [m] (0.31 per m^2, the flights'
#: ``parking_lot`` field of 200: two to five in a range cell's ring beyond the
#: nadir, more than one snapshot's plane-wave fit splits), tilt (tilt_n, tilt_e) [rad].
HEIGHT, SCATTERERS, EXTENT, TILT = 15.0, 150, 11.0, np.deg2rad([0.8, -0.6])
#: Draws of the dense ground (each FRAMES frames, the sway turned a third of a turn from
#: one to the next) and the least of them that must give a tilt from the range-Doppler
#: cells (measured: seeds 0-3 all, 20-41 points; one draw keeps the test near 5 s).
DRAWS, FRAMES, MIN_USABLE = 1, 3, 1
#: Chi-square of 2 degrees of freedom at three sigma (99.73 %): the stated covariance
#: must cover the error within it.
CHI2_3SIGMA = 11.83
#: Direction cosine along the velocity and range [cells] of one scatterer to within
#: (noise free: the Doppler filter keeps the range kernel's shape).
DIRECTION_TOL, RANGE_TOL_CELLS = 1e-3, 0.02


def _array():
    """xWR18xx virtual array (8 in a row, 4 raised half a wavelength) and its slots."""
    lam = WAVELENGTH
    pos = np.array([[0.5 * lam * i, 0.0, 0.0] for i in range(8)]
                   + [[lam + 0.5 * lam * i, 0.5 * lam, 0.0] for i in range(4)])
    return pos, np.repeat([0, 1, 2], 4)


def _frame(points, amplitudes, pos, slot, velocity=VELOCITY) -> tuple[np.ndarray, np.ndarray]:
    """Range-compressed frame ``[loop, channel, cell]`` of scatterers at ``points`` [m]
    (from the radar at t = 0, which moves at ``velocity`` [m/s]) and the slot instants."""
    t = (np.arange(LOOPS)[:, None] * 3 + slot[None, :]) * SLOT_S              # [loop, ch]
    k = 2 * np.pi / WAVELENGTH
    r0 = np.linalg.norm(points, axis=1)
    u = points / r0[:, None]
    # the range to first order in the radar's displacement (3 mm over the frame at 15 m:
    # the second order is 3e-7 m) and the array's phases along the directions at t = 0
    r = r0[None, None, :] - t[..., None] * (u @ velocity)[None, None, :]      # [l, c, s]
    phase = np.exp(-1j * (2 * k * r + k * (u @ pos.T).T[None, :, :]))     # [l, c, s]
    kern = range_kernel(np.arange(CELLS)[None, :] - r0[:, None] / CELL, CELLS)
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


def test_one_scatterer_in_its_doppler_cell():
    """A lone scatterer: one point, at its range and direction (the strongest of the
    Doppler cells its window's main lobe spans)."""
    pos, slot = _array()
    u = np.array([0.31, -0.12])
    p = 17.13 * np.array([*u, np.sqrt(1 - u @ u)])
    rc, t = _frame(p[None], np.array([1.0]), pos, slot)
    r, d, pose = doppler_ground_directions(rc, pos, static_motion(t), wavelength=WAVELENGTH,
                                           range_axis=np.arange(CELLS) * CELL,
                                           gates=np.arange(100, 140), channel_slot=slot)
    assert r.shape == (1,) and pose == 3 * (LOOPS // 2)
    assert abs(r[0] - 17.13) <= RANGE_TOL_CELLS * CELL
    assert np.max(np.abs(d[0] - p / 17.13)) <= DIRECTION_TOL


def test_dense_ground_tilt_from_range_doppler_cells():
    """Dense level grounds seen through TILT, the platform swaying: the range cells of
    one snapshot give fewer points than a plane needs (no tilt); with the range-Doppler
    cells at least MIN_USABLE of DRAWS give a tilt, every one within three sigma of its
    stated covariance (measured over seeds 0-3: chi-square 0.15-2.5, errors up to
    0.41 deg at 0.28 stated)."""
    pos, slot = _array()
    kw = dict(wavelength=WAVELENGTH, range_axis=np.arange(CELLS) * CELL,
              gates=np.arange(95, CELLS), channel_slot=slot)
    usable = 0
    for seed in range(DRAWS):
        ground = _ground(np.random.default_rng(seed), SCATTERERS)
        frames = [_frame(*ground, pos, slot, Rotation.from_rotvec(
            [0.0, 0.0, 2 * np.pi * f / FRAMES]).apply(VELOCITY)) for f in range(FRAMES)]
        motions = [static_motion(t) for _, t in frames]
        r, _ = dense_ground_directions(frames[0][0], pos, motions[0], **kw)
        assert r.size < MIN_GROUND_POINTS              # the snapshot's cells are too full
        fit = ground_tilt([rc for rc, _ in frames], pos, motions, warn=False, **kw)
        if not fit.usable:
            continue
        usable += 1
        assert fit.source == "range+doppler" == fit.report()["point_cells"]
        err = fit.tilt - TILT
        assert float(err @ np.linalg.solve(fit.tilt_covariance, err)) <= CHI2_3SIGMA, (
            seed, np.rad2deg(err), np.rad2deg(fit.tilt_sigma))
    assert usable >= MIN_USABLE, usable


def test_doppler_spectra_need_two_loops():
    with pytest.raises(ValueError, match="two or more chirps"):
        doppler_spectra(np.zeros((1, 12, 150), complex), np.arange(3) * SLOT_S,
                        np.repeat([0, 1, 2], 4))


def test_a_tilt_vaguer_than_the_prior_is_refused():
    """Points that fix the tilt worse than the radar-inertial prior (5 deg): a level
    plane of 12 points over +-3 m with 1 m spreads (stated tilt spread about 11 deg)
    gives no tilt, and says why."""
    rng = np.random.default_rng(0)
    xy = rng.uniform(-3.0, 3.0, size=(12, 2))
    p = np.column_stack([xy, np.full(12, HEIGHT)])
    fit = fit_ground_plane(p, np.broadcast_to(np.eye(3), (12, 3, 3)), warn=False)
    assert np.all(fit.tilt_sigma >= DEFAULT_TILT_SIGMA) and not fit.usable
    assert any("prior's 5 deg" in w for w in fit.warnings)


def test_range_doppler_refit_states_no_less_than_the_first_fit():
    """The calibration's refit turns the same points by a few tenths of a degree: for
    range-Doppler points (few a jackknife sector) it states no less spread than the
    first fit did; range-cell points keep the refit's own."""
    rng = np.random.default_rng(0)
    xy = rng.uniform(-8.0, 8.0, size=(40, 2))
    look = GroundLook(0, 0, np.eye(3), np.column_stack([xy, np.full(40, HEIGHT)]),
                      np.broadcast_to(1e-4 * np.eye(3), (40, 3, 3)).copy())
    first_cov = np.diag(np.deg2rad([2.0, 1.5]) ** 2)
    motions = [static_motion(np.arange(LOOPS * 3) * SLOT_S)]
    for source in ("range", "range+doppler"):
        first = GroundPlane(np.zeros(2), first_cov, HEIGHT, np.array([0.0, 0.0, 1.0]), 40, 40,
                            1.0, 0.01, looks=(look,), source=source)
        _, cov = GroundRetilt(first, np.eye(3))(motions, first_cov)
        covers = np.linalg.eigvalsh(cov - first_cov).min() >= -1e-12 * first_cov.max()
        assert covers == (source == "range+doppler"), (source, np.rad2deg(np.sqrt(np.diag(cov))))


def test_gates_must_lie_in_the_cells():
    pos, slot = _array()
    rc = np.zeros((LOOPS, len(pos), CELLS), complex)
    with pytest.raises(ValueError, match="gates must lie in 0..149, got 140..150"):
        doppler_ground_directions(rc, pos, static_motion(np.arange(LOOPS * 3) * SLOT_S),
                                  wavelength=WAVELENGTH, range_axis=np.arange(CELLS) * CELL,
                                  gates=np.arange(140, 151), channel_slot=slot)
