"""Ground clutter as Doppler measurements: stationary scatterers beyond the range window.

The radar-inertial estimate (:mod:`compensation.radar_inertial`) corrects the
IMU integration with the residual range rates ``v_r = -u . dv`` of stationary
scatterers in blocks of chirps; the velocity error ``dv`` is constrained only
along the spread of their directions ``u``. The scatterers detected in the
compensated cells may lie in a narrow cone (a few targets ahead or below), which
leaves the velocity across it to the IMU's prior. The ground clutter beyond those
cells is seen in every direction: the dense ground points of the first frame
(:func:`compensation.ground_dense.dense_ground_directions`) give its scatterers'
ranges and directions, and :func:`ground_scatterers` picks the strongest,
spread over the bearings about boresight.

A ground cell holds two to four scatterers, and a beam at one of them takes in
the others through the array's sidelobes: compensated for the wrong direction,
their Doppler is ``-(u_other - u) . v`` (``v`` the platform's velocity), which
would pull the slope. So the measurement (:func:`ground_measurements`) is the
slow-time slope of the plane-wave amplitude itself: at every chirp loop the
cell's channels (one instant, :func:`compensation.ground_dense.aligned_snapshot`)
are fitted by least squares as the sum of the plane waves of every dense point
within :data:`NEIGHBOUR_CELLS` cells, each steered through that loop's attitude;
the point's amplitude is compensated for the radar phase centre's motion along its
direction, ``exp(+j 4 pi / lambda u . x_R(t))`` (the phase ``-4 pi / lambda u . x_R``
of a stationary scatterer, the sign of the project's range phase), and its slope
over every block (:func:`compensation.ego_velocity.slow_time_velocity`) is the
same residual range rate as :func:`compensation.calibration.doppler_measurements`
gives, after the same motion, over the same blocks. A point whose cell its plane
waves do not explain (a scatterer the dense fit did not track) is left out
(:data:`MIN_FIT_PURITY`).

Assumed: the ground is at rest. A mover among the points (a car in the clutter)
is an outlier of the static-world consensus and the Huber weights of the
estimate, as a moving target among the detections is; a ground that moves as a
whole (water, swaying vegetation) is not detected here.

What it cannot do: the plane waves are those of a planar array in A (element
positions with ``z = 0``); the ground must lie in the cells given (beyond the
window for a down-looking radar); a cell whose scatterers the dense fit did not
resolve gives nothing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._checks import finite_array, positive
from .ego_velocity import slow_time_velocity
from .ground_dense import (
    DENSE_ANGLE_SIGMA,
    SNAPSHOT_CHIRP,
    aligned_snapshot,
    dense_ground_directions,
    steering,
)
from .mounting import radar_frame_motion, world_directions
from .radar_inertial import GROUND_GROUP, MAX_MEASUREMENTS, DopplerMeasurements
from .strapdown import PlatformMotion

__all__ = ["GROUND_DOPPLER_COUNT", "MIN_FIT_PURITY", "GroundScatterer", "ground_measurements",
           "ground_scatterers"]

#: Default most ground scatterers added to the Doppler measurements.
GROUND_DOPPLER_COUNT = 12
#: Least fraction of its cell's power the cell's plane waves must explain in the first
#: frame (the rest, scatterers not tracked, would leak into the amplitude).
MIN_FIT_PURITY = 0.97
#: Least fraction of its cell's power the point's own plane wave must hold (a weak
#: wave beside strong ones takes their fit errors).
MIN_SHARE = 0.2
#: Cells either side whose dense points enter a cell's fit (the Hann range kernel
#: spreads a scatterer over about three cells).
NEIGHBOUR_CELLS = 2
#: Bearing sectors about boresight (direction cosines ``(u_x, u_y)``) the scatterers are
#: picked from in turn, strongest first: spread, not the one bright corner.
BEARING_SECTORS = 8


@dataclass(frozen=True)
class GroundScatterer:
    """A ground scatterer of the Doppler measurements and the plane waves beside it.

    Attributes
    ----------
    gate : int
        Range cell of its range.
    direction : ndarray, shape ``[3]``
        Unit direction [1] in the frame of the motion's attitude (W, or N of a
        mounted radar).
    others : ndarray, shape ``[wave, 3]``
        Directions of the other plane waves fitted with it in its cell.
    """

    gate: int
    direction: np.ndarray
    others: np.ndarray


def ground_scatterers(rc, element_positions, motion: PlatformMotion, *, wavelength: float,
                      range_axis, gates=None, channel_slot=None,
                      count: int = GROUND_DOPPLER_COUNT,
                      **projection) -> list[GroundScatterer]:
    """Stationary ground scatterers of a frame for the Doppler measurements.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        One range-compressed frame (the record's first).
    element_positions : array_like, shape ``[channel, 3]``
        Virtual positions in A [m] (a planar array, ``z = 0``).
    motion : PlatformMotion
        Motion of the frame as the beams see it (in N for a mounted radar,
        :func:`compensation.mounting.radar_frame_motion`), one pose per slot with
        ``channel_slot``.
    wavelength : float
        [m].
    range_axis : array_like, shape ``[range]``
        Range of every cell of ``rc`` [m] (uniform).
    gates : array_like of int, optional
        Cells where the ground lies (for a down-looking radar those beyond the
        compensated window); None: no ground, nothing returned.
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM slot of every channel.
    count : int
        Most scatterers returned.
    **projection
        The beams' other options (``grid_shape``, ``method``, ``focus`` of
        :func:`compensation.rigid_body_projection`), accepted with them and not
        needed: the plane waves are fitted to snapshots of the channels.

    Returns
    -------
    list of GroundScatterer
        Picked from :data:`BEARING_SECTORS` sectors in turn, strongest first, among
        the dense points whose cell's plane waves explain :data:`MIN_FIT_PURITY` of
        its power, of which the point's own holds :data:`MIN_SHARE`; empty where none.
    """
    unknown = set(projection) - {"grid_shape", "method", "focus"}
    if unknown:
        raise ValueError(f"options: got {sorted(unknown)}, expected only the projection's "
                         f"grid_shape, method, focus")
    if gates is None:
        return []
    x = np.asarray(rc)
    if x.ndim != 3:
        raise ValueError(f"rc must have shape [chirp, channel, range], got {x.shape}")
    p = finite_array("element_positions", element_positions, shape=(x.shape[1], 3))
    lam = positive("wavelength", wavelength)
    r_axis = finite_array("range_axis", range_axis, shape=(x.shape[2],))
    g = np.asarray(gates, dtype=int).ravel()
    if int(count) != count or count < 0:
        raise ValueError(f"count: got {count!r}, expected a whole number >= 0")
    if g.size and (g.min() < 0 or g.max() >= x.shape[2]):
        raise ValueError(f"gates must lie in 0..{x.shape[2] - 1}, got {g.min()}..{g.max()}")
    if g.size == 0 or count == 0:
        return []
    r, u = dense_ground_directions(x, p, motion, wavelength=lam, range_axis=r_axis, gates=g,
                                   channel_slot=channel_slot)
    if r.size == 0:
        return []
    cell = np.rint((r - r_axis[0]) / (r_axis[1] - r_axis[0])).astype(int)
    snap = aligned_snapshot(x, motion.time, channel_slot)                # [channel, range]
    slots = 1 if channel_slot is None else int(np.max(channel_slot)) + 1
    att = motion.attitude[slots * SNAPSHOT_CHIRP]
    cands, power = [], []
    for i in np.flatnonzero(np.isin(cell, g)):
        near = np.flatnonzero(np.abs(cell - cell[i]) <= NEIGHBOUR_CELLS)
        waves = np.vstack([u[i], u[near[near != i]]])
        y = snap[:, cell[i]]
        c, share, purity = _fit(y, waves @ att, p, lam)
        if purity >= MIN_FIT_PURITY and share >= MIN_SHARE:
            cands.append(GroundScatterer(int(cell[i]), u[i], waves[1:]))
            power.append(abs(c[0]) ** 2)
    if not cands:
        return []
    ua = np.array([s.direction for s in cands]) @ att                 # into A: R^T u
    bearing = np.arctan2(ua[:, 1], ua[:, 0]) + np.pi
    sector = np.minimum((bearing / (2 * np.pi) * BEARING_SECTORS).astype(int),
                        BEARING_SECTORS - 1)
    power = np.asarray(power)
    queues = [list(np.flatnonzero(sector == s)[np.argsort(-power[sector == s])])
              for s in range(BEARING_SECTORS)]
    picked: list[int] = []
    while len(picked) < count and any(queues):
        heads = sorted((q.pop(0) for q in queues if q), key=lambda i: -power[i])
        picked.extend(heads[:int(count) - len(picked)])
    return [cands[i] for i in picked]


def _fit(y: np.ndarray, waves_a: np.ndarray, positions: np.ndarray, wavelength: float):
    """Least-squares amplitudes ``[wave]`` of plane waves (directions in A ``[wave, 3]``)
    in the channels ``y`` ``[channel]``, the first wave's share of the power and the
    fraction of the power the waves explain."""
    s = steering(waves_a[:, 0], waves_a[:, 1], positions, wavelength).T    # [channel, wave]
    c = np.linalg.lstsq(s, y, rcond=None)[0]
    total = max(float(np.vdot(y, y).real), np.finfo(float).tiny)
    resid = y - s @ c
    return c, float(np.sum(np.abs(s[:, 0] * c[0]) ** 2)) / total, \
        1.0 - float(np.vdot(resid, resid).real) / total


def ground_measurements(meas: DopplerMeasurements, rcs, positions, motions,
                        ground: list[GroundScatterer], *, wavelength: float,
                        channel_slot=None, mounting=None) -> DopplerMeasurements:
    """Measurements ``meas`` with the ground scatterers' residual range rates appended.

    Parameters
    ----------
    meas : DopplerMeasurements
        Those of the detected scatterers (:func:`compensation.calibration.doppler_measurements`)
        after ``motions``: their blocks (frame and window) are the ground's.
    rcs : sequence of ndarray, each shape ``[chirp, channel, range]``
    positions : array_like, shape ``[channel, 3]``
        Virtual element positions in A [m].
    motions : sequence of PlatformMotion
        Body motion of each frame (W), one pose per slot with ``channel_slot``.
    ground : list of GroundScatterer
        From :func:`ground_scatterers` (directions in N of ``mounting``).
    wavelength : float
        [m].
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM slot of every channel.
    mounting : array_like, shape ``[3, 3]``, optional
        ``R_BA`` of a mounted radar (:mod:`compensation.mounting`).

    Returns
    -------
    DopplerMeasurements
        ``meas`` then one per ground scatterer, block and frame: the slope of its
        compensated plane-wave amplitude over the block's chirp loops (the first loop
        of a frame has no loop before it to align the slots with and is left out), its
        spread (no smaller than the least of ``meas``: a plane wave's amplitude is
        measured no better than the best beam), and its direction in W with the
        covariance of :data:`compensation.ground_dense.DENSE_ANGLE_SIGMA` across it, in
        group :data:`compensation.batch_solve.GROUND_GROUP` (its spreads scaled by their
        own reduced chi-square in the estimate).
        The first scatterers only where all would give more than
        :data:`compensation.radar_inertial.MAX_MEASUREMENTS` in all.
    """
    blocks = np.unique(np.column_stack([meas.frame, meas.window]), axis=0).shape[0]
    ground = ground[:max(0, (MAX_MEASUREMENTS - meas.frame.size) // max(blocks, 1))]
    if not ground:
        return meas
    p = np.asarray(positions, dtype=float)
    lam = positive("wavelength", wavelength)
    slots = 1 if channel_slot is None else int(np.max(channel_slot)) + 1
    u_n = np.array([s.direction for s in ground])
    cov = DENSE_ANGLE_SIGMA ** 2 * (np.eye(3) - np.einsum("si,sj->sij", u_n, u_n))
    u_w, cov_w = world_directions(u_n, mounting, cov)
    d, r, s, fr, win, dc = [], [], [], [], [], []
    for k, m in enumerate(motions):
        seen = radar_frame_motion(m, mounting)
        loops = np.arange(1, np.asarray(rcs[k]).shape[0])
        t = seen.time[slots * loops]                                       # slot-0 instants
        x_r = seen.radar_position[slots * loops]                           # [loop, 3]
        att = seen.attitude[slots * loops]                                 # [loop, 3, 3]
        snaps = np.stack([aligned_snapshot(rcs[k], seen.time, channel_slot, n) for n in loops])
        amp = np.empty((len(ground), loops.size), dtype=complex)
        for j, gs in enumerate(ground):
            waves = np.vstack([gs.direction, gs.others])
            for n in range(loops.size):
                amp[j, n] = _fit(snaps[n, :, gs.gate], waves @ att[n], p, lam)[0][0]
            amp[j] *= np.exp(4j * np.pi / lam * (x_r @ gs.direction))
        sel = meas.frame == k
        for lo, hi in np.unique(meas.window[sel], axis=0):
            blk = (t >= lo - 1e-12) & (t <= hi + 1e-12)
            if np.count_nonzero(blk) < 4:
                continue
            for j in range(len(ground)):
                vr, sig = slow_time_velocity(amp[j, blk], t[blk], lam)
                d.append(u_w[j])
                r.append(vr)
                s.append(max(sig, float(np.min(meas.sigma))))
                fr.append(k)
                win.append((lo, hi))
                dc.append(cov_w[j])
    if not d:
        return meas
    dcov = meas.direction_cov
    if dcov is None:
        dcov = np.zeros((meas.frame.size, 3, 3))
    return DopplerMeasurements(np.vstack([meas.directions, d]),
                               np.concatenate([meas.range_rate, r]),
                               np.concatenate([meas.sigma, s]),
                               np.concatenate([meas.frame, fr]),
                               np.vstack([meas.window, win]), np.concatenate([dcov, dc]),
                               np.concatenate([meas.group, np.full(len(r), GROUND_GROUP)]))
