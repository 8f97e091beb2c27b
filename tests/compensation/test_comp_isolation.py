"""`compensation` stands alone: no raysim import, inputs built with plain NumPy."""

from __future__ import annotations

import subprocess
import sys
import textwrap

SCRIPT = textwrap.dedent(r'''
    import sys
    import numpy as np
    from scipy.spatial.transform import Rotation
    import compensation as comp

    c, fc, bw = 299_792_458.0, 77e9, 1e9
    lam = c / (fc + bw / 2)                      # mid-chirp wavelength (range-compressed)
    n_chirp, t_rep = 128, 60e-6
    t = np.arange(n_chirp) * t_rep
    ix, iy = np.divmod(np.arange(64), 8)
    p_virt = np.stack([ix, iy, 0 * ix], 1) * (c / fc / 2)
    p_virt[:, :2] -= p_virt[:, :2].mean(0)
    lever = np.array([0.0, 0.0, 0.1])

    # motion: constant body rate (roll, pitch, yaw) and constant world velocity
    w = np.array([0.4, -0.6, 1.5])                   # rad/s
    vel = np.array([0.3, -0.2, 0.25])                # m/s
    imu_t = np.arange(-0.01, 0.02, 1e-3)
    att = lambda tt: Rotation.from_rotvec(np.outer(tt, w))
    gyro = np.tile(w, (imu_t.size, 1))
    accel = att(imu_t).apply(np.array([0.0, 0.0, -9.80665]), inverse=True)

    # exact range-compressed echo of a point target at 14 m, az 15, el -10 deg
    u = comp.direction(np.deg2rad(15.0), np.deg2rad(-10.0))
    target = lever + 14.0 * u
    R = att(t).as_matrix()
    x_el = (np.outer(t, vel)[:, None, :] + np.einsum("nij,mj->nmi", R, lever + p_virt / 2))
    tau = 2 * np.linalg.norm(target - x_el, axis=-1) / c
    rc = np.exp(2j * np.pi * (fc + bw / 2) * tau).astype(np.complex64)[:, :, None]

    motion = comp.integrate_imu(imu_t, gyro, accel, t, lever_arm=lever, velocity="given",
                                initial_velocity=vel)
    kw = dict(wavelength=lam, range_axis=[14.0], azimuth=[np.deg2rad(15.0)],
              elevation=[np.deg2rad(-10.0)], grid_shape=(8, 8))
    exact = comp.rigid_body_projection(rc, p_virt, motion, **kw).data[:, 0, 0, 0]
    plain = comp.beam_projection(rc, p_virt, **kw).data[:, 0, 0, 0]
    coh = lambda y: abs(y.mean()) / np.abs(y).mean()
    assert coh(exact) > 0.999, coh(exact)
    assert coh(plain) < 0.9, coh(plain)
    bad = sorted(m for m in sys.modules if m == "raysim" or m.startswith("raysim."))
    assert not bad, bad
    print("ok", round(coh(exact), 6), round(coh(plain), 3))
''')


def test_compensation_runs_without_raysim():
    res = subprocess.run([sys.executable, "-c", SCRIPT], capture_output=True, text=True,
                         timeout=120)
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith("ok")


def test_package_sources_do_not_import_raysim():
    import pathlib

    import compensation

    root = pathlib.Path(compensation.__file__).parent
    for path in root.glob("*.py"):
        text = path.read_text()
        assert "import raysim" not in text and "from raysim" not in text, path
