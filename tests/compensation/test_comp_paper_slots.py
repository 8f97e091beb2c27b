"""The paper chain with per-slot TDM poses (``channel_slot``)."""

from __future__ import annotations

import numpy as np
import pytest

from compensation import paper_chain
from compensation.strapdown import PlatformMotion

#: Agreement of two complex64 beam cubes computed in different channel orders.
BEAM_RTOL = 1e-5


def _motion(times):
    """A platform pitching and yawing linearly in time, moving along x (pose per time)."""
    from scipy.spatial.transform import Rotation

    t = np.asarray(times, dtype=float)
    att = Rotation.from_euler("ZYX", np.column_stack([0.5 * t, 0.3 * t, 0 * t])).as_matrix()
    pos = np.column_stack([0.2 * t, 0 * t, 0 * t])
    vel = np.tile([0.2, 0.0, 0.0], (t.size, 1))
    rate = np.tile([0.0, 0.3, 0.5], (t.size, 1))
    return PlatformMotion(t, att, pos, vel, rate, np.array([0.0, 0.0, 0.05]))


def test_one_slot_equals_no_slots():
    rng = np.random.default_rng(3)
    rc = (rng.standard_normal((6, 4, 3)) + 1j * rng.standard_normal((6, 4, 3))).astype(
        np.complex64)
    p = np.column_stack([np.arange(4) * 2e-3, np.zeros(4), np.zeros(4)])
    m = _motion(np.arange(6) * 1e-3)
    kw = dict(wavelength=3.9e-3, direction=[0.0, 0.0, 1.0], range_axis=[5.0, 5.1, 5.2],
              azimuth=np.deg2rad([-10.0, 0.0, 20.0]), elevation=[0.0], method="direct")
    a = paper_chain(rc, p, m, **kw)
    b = paper_chain(rc, p, m, channel_slot=np.zeros(4, dtype=int), **kw)
    assert np.allclose(b.data, a.data, rtol=BEAM_RTOL, atol=BEAM_RTOL * np.abs(a.data).max())
    assert np.array_equal(b.chirp_time, a.chirp_time)


def test_each_slot_uses_its_own_pose():
    """Two slots: the result equals the sum of each slot's channels compensated alone
    with that slot's poses, weighted by their share of the channels."""
    rng = np.random.default_rng(4)
    rc = (rng.standard_normal((5, 6, 2)) + 1j * rng.standard_normal((5, 6, 2))).astype(
        np.complex64)
    p = np.column_stack([np.arange(6) * 2e-3, np.zeros(6), np.zeros(6)])
    slot = np.array([0, 0, 0, 0, 1, 1])
    t = (np.arange(5)[:, None] * 2e-3 + np.array([0.0, 1e-3])[None, :]).ravel()
    m = _motion(t)
    kw = dict(wavelength=3.9e-3, direction=[0.0, 0.0, 1.0], range_axis=[5.0, 5.1],
              azimuth=np.deg2rad([-5.0, 15.0]), elevation=[0.0], method="direct")
    got = paper_chain(rc, p, m, channel_slot=slot, **kw)
    want = sum(paper_chain(rc[:, slot == s], p[slot == s], m.select(slice(s, None, 2)),
                           **kw).data * np.mean(slot == s) for s in (0, 1))
    assert np.allclose(got.data, want, rtol=BEAM_RTOL, atol=BEAM_RTOL * np.abs(want).max())
    assert np.array_equal(got.chirp_time, t[::2])
    with pytest.raises(ValueError, match="chirp \\* slots"):
        paper_chain(rc, p, m.select(slice(0, 5)), channel_slot=slot, **kw)


#: Phase agreement [rad] of the published and integrated rotation phases for a constant
#: rate over 20 ms (second-order difference 1/2 w^2 t^2 |r| 4 pi / lambda ~ 3e-3 rad); a
#: published phase counted from each slot's own first ramp would be off by
#: 4 pi v_r dt / lambda ~ 1.6e-2 rad for the slot 1 ms later.
PUBLISHED_PHASE_TOL = 5e-3


def test_published_rotation_phase_counts_from_the_frame_start():
    """Constant pitch rate: v_r (t_n - t_0) equals the integrated lever-arm displacement
    to first order, slot by slot, when t_0 is the frame's first ramp."""
    from scipy.spatial.transform import Rotation

    n, rate, lever = 10, 0.3, np.array([0.0, 0.0, 0.05])
    t = (np.arange(n)[:, None] * 2e-3 + np.array([0.0, 1e-3])[None, :]).ravel()
    att = Rotation.from_euler("y", (rate * t)[:, None]).as_matrix()
    z = np.zeros((t.size, 3))
    m = PlatformMotion(t, att, z, z.copy(), np.tile([0.0, rate, 0.0], (t.size, 1)), lever)
    u = np.array([np.sin(np.deg2rad(20.0)), 0.0, np.cos(np.deg2rad(20.0))])
    rc = np.zeros((n, 8, 1), dtype=np.complex128)
    rc[:, 4:] = 1.0                                   # slot 1 alone: its phase is not diluted
    p = np.column_stack([np.arange(8) * 1.95e-3, np.zeros(8), np.zeros(8)])
    kw = dict(wavelength=3.9e-3, direction=u, range_axis=[5.0], azimuth=[np.deg2rad(20.0)],
              elevation=[0.0], steps=("rotation",), method="direct",
              channel_slot=np.repeat([0, 1], 4))
    a = paper_chain(rc, p, m, rotation_phase="integrated", **kw).data[:, 0, 0, 0]
    b = paper_chain(rc, p, m, rotation_phase="published", **kw).data[:, 0, 0, 0]
    assert np.max(np.abs(np.angle(b / a))) < PUBLISHED_PHASE_TOL
