"""A beam cell's scatterer between the beams, and the Doppler the grid leaves it
(compensation.cell_directions, and the displacement autofocus's velocity fit).

Beams of an 8 x 2 half-wavelength virtual array (a TI board's two rows, the second
from its raised transmitter), formed at a 2 deg azimuth and 5 deg elevation
grid, of point scatterers between the beams (one beyond the grid's last elevation),
while the radar moves with ``v`` and the motion has been removed at each beam's own
direction: beam ``u_b`` holds ``sum_e exp(j k (u_s - u_b) . x_e) exp(-j k2 (u_s - u_b) . v t)``
(``x_e`` virtual positions, ``k = 2 pi / lambda``, ``k2 = 2 k``; the phase grows with
range, docs/conventions.md, so the radar's advance ``v t`` along ``u_s`` less the
``u_b . v t`` removed leaves ``-k2 (u_s - u_b) . v t``). Its closed form is
``(u_s - u_b) . v``; no velocity error is in the data.
"""

from __future__ import annotations

import numpy as np
import pytest

from compensation.autofocus_displacement import estimate_displacement
from compensation.cell_directions import beam_offset_doppler, refined_directions
from compensation.geometry import direction, grid_directions
from compensation.projection import BeamCube

LAM = 299_792_458.0 / 77e9
K2 = 4 * np.pi / LAM
#: Scatterers (azimuth, elevation) [deg], one a range gate; the last beyond the grid's
#: highest elevation (5 deg).
SCATTERERS = ((-21.3, 1.7), (6.8, -3.1), (14.2, 5.6), (-2.6, -1.2), (27.9, 2.9))
AZ = np.deg2rad(np.arange(-40.0, 41.0, 2.0))
EL = np.deg2rad(np.array([-5.0, 0.0, 5.0]))
#: Radar velocity over the frame [m/s] (a drift across the beams).
V = np.array([0.3, 0.25, -0.05])
#: Refined direction within this of the scatterer's [deg] (a 3-beam parabola over a
#: main lobe some 15 deg wide).
DIRECTION_TOL_DEG = 0.3
#: Velocity error found with the grid's Doppler taken off: within this many stated sigma
#: of zero and under VELOCITY_TOL_MPS [m/s] (measured 2.7 mm/s on the elevation axis the
#: two rows barely span); without it the fit invents at least INVENTED_MPS (measured
#: 59 mm/s, its own spread inflated by the misfit to 89 mm/s).
COVER_SIGMAS, VELOCITY_TOL_MPS, INVENTED_MPS = 3.0, 5e-3, 2e-2


def _beams(n_chirps: int = 64, dt: float = 2e-4, noise: float = 1e-3) -> BeamCube:
    rng = np.random.default_rng(7)
    xe = np.array([(x, y, 0.0) for x in (np.arange(8) - 3.5) * LAM / 2
                   for y in (0.0, LAM / 2)])                               # [element, 3]
    t = np.arange(n_chirps) * dt
    ub = grid_directions(AZ, EL)                                         # [az, el, 3]
    data = np.zeros((n_chirps, len(SCATTERERS), AZ.size, EL.size), complex)
    for r, (a, e) in enumerate(SCATTERERS):
        du = direction(np.deg2rad(a), np.deg2rad(e)) - ub                  # [az, el, 3]
        steer = np.exp(1j * K2 / 2 * np.einsum("abi,ei->abe", du, xe)).sum(axis=2)
        data[:, r] = steer[None] * np.exp(-1j * K2 * (du @ V)[None] * t[:, None, None])
    data += noise * (rng.normal(size=data.shape) + 1j * rng.normal(size=data.shape))
    return BeamCube(data.astype(np.complex64), t, np.arange(len(SCATTERERS)) * 0.2 + 5.0,
                    AZ, EL, LAM)


def _cells(beams: BeamCube) -> np.ndarray:
    """Each scatterer's strongest beam cell (flat index into ``[range, az, el]``)."""
    p = np.mean(np.abs(beams.data) ** 2, axis=0)
    return np.array([np.ravel_multi_index((r, *np.unravel_index(np.argmax(p[r]), p[r].shape)),
                                          p.shape) for r in range(p.shape[0])])


def test_refined_directions_between_and_beyond_the_beams():
    beams = _beams()
    u = refined_directions(beams, _cells(beams))
    truth = np.array([direction(np.deg2rad(a), np.deg2rad(e)) for a, e in SCATTERERS])
    err = np.rad2deg(np.arccos(np.clip(np.sum(u * truth, axis=1), -1, 1)))
    assert np.all(err <= DIRECTION_TOL_DEG), err
    ia = np.unravel_index(_cells(beams), beams.data.shape[1:])[2]
    assert EL[ia[2]] == EL[-1]                       # the last scatterer beyond the edge


def test_beam_offset_doppler_is_the_closed_form():
    beams = _beams()
    cells = _cells(beams)
    _, ia, ie = np.unravel_index(cells, beams.data.shape[1:])
    ub = direction(AZ[ia], EL[ie])
    truth = np.array([direction(np.deg2rad(a), np.deg2rad(e)) for a, e in SCATTERERS])
    got = beam_offset_doppler(beams, cells, ub, V)
    closed = (truth - ub) @ V
    # the refined directions' error times |v|
    assert np.all(np.abs(got - closed) <= np.deg2rad(DIRECTION_TOL_DEG) * np.linalg.norm(V))
    assert np.abs(closed).max() > 5e-3                 # mm/s: what the fit would take


def test_stationary_velocity_fit_takes_the_grids_doppler_off():
    """No velocity error in the data: with the radar's velocity the fit finds none (within
    its stated sigma); without, it takes the grid's Doppler for one."""
    beams = _beams()
    with_v = estimate_displacement(beams, doppler="stationary", radar_velocity=V)
    without = estimate_displacement(beams, doppler="stationary")
    assert with_v.cells == without.cells >= len(SCATTERERS)
    assert np.all(np.abs(with_v.velocity) <= COVER_SIGMAS * with_v.velocity_sigma), (
        with_v.velocity, with_v.velocity_sigma)
    assert np.abs(with_v.velocity).max() <= VELOCITY_TOL_MPS
    assert np.abs(without.velocity).max() >= INVENTED_MPS


def test_radar_velocity_shape_is_named():
    with pytest.raises(ValueError, match="radar_velocity"):
        estimate_displacement(_beams(), doppler="stationary", radar_velocity=[0.1, 0.2])
