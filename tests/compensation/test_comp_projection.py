"""Beam projection engine, paper-chain steps: references, zero motion, validation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from compensation import (
    beam_projection,
    direction,
    paper_chain,
    range_change,
    rigid_body_projection,
    slow_time_correction,
    static_motion,
    tilt_correction,
    yaw_projection,
)
from compensation.strapdown import PlatformMotion
from raysim.processing.maps import beamform
from raysim.radar.arrays import upa

LAM = 3.8685e-3
#: complex64 round-off bound relative to the peak.
FLOAT_TOL = 2e-6
#: Non-uniform FFT accuracy bound relative to the peak (requested 1e-6).
NUFFT_TOL = 1e-5


def _cube(rng, n=16, m=64, r=5):
    return (rng.standard_normal((n, m, r)) + 1j * rng.standard_normal((n, m, r))).astype(
        np.complex64)


def ref_rigid_body(x, p, rot, disp, lam, rng_m, u):
    """Term-by-term exact matched filter in complex128 (no factorisation)."""
    out = np.zeros(x.shape[0], dtype=complex)
    for n in range(x.shape[0]):
        focal = rng_m * u - disp[n]
        dist = np.linalg.norm(focal)
        v = rot[n].T @ (focal / dist)
        model = np.exp(1j * 2 * np.pi / lam * (2 * (dist - rng_m) - p @ v))
        out[n] = np.vdot(model, x[n]) / p.shape[0]
    return out


def test_static_projection_equals_conventional_beamformer():
    rng = np.random.default_rng(1)
    arr = upa(8, 8, wavelength=LAM)
    x = _cube(rng)
    az, el = np.deg2rad([-20.0, 0.0, 13.0]), np.deg2rad([-5.0, 30.0])
    b = beam_projection(x, arr.virtual_positions, wavelength=LAM, range_axis=np.arange(5.0) + 5,
                        azimuth=az, elevation=el, grid_shape=(8, 8))
    aa, ee = np.meshgrid(az, el, indexing="ij")
    ref = beamform(np.moveaxis(x, 2, 1), arr, LAM, direction(aa, ee).reshape(-1, 3))
    np.testing.assert_allclose(b.data.reshape(ref.shape), ref, atol=FLOAT_TOL * np.abs(ref).max())
    assert b.dims == ("chirp", "range", "azimuth", "elevation")


def test_rigid_body_matches_reference_and_methods_agree():
    rng = np.random.default_rng(2)
    arr = upa(6, 5, wavelength=LAM)
    p = arr.virtual_positions
    x = _cube(rng, n=12, m=30, r=3)
    from scipy.spatial.transform import Rotation

    rot = Rotation.from_rotvec(rng.normal(0, 0.2, (12, 3))).as_matrix()
    disp = rng.normal(0, 0.05, (12, 3))
    motion = PlatformMotion(np.arange(12) * 60e-6, rot, disp, np.zeros((12, 3)),
                            np.zeros((12, 3)), np.zeros(3))
    r_axis = np.array([9.0, 12.0, 15.0])
    az, el = np.deg2rad([10.0, 40.0]), np.deg2rad([-20.0, 5.0])
    kw = dict(wavelength=LAM, range_axis=r_axis, azimuth=az, elevation=el, gate_block=1)
    lat = rigid_body_projection(x, p, motion, grid_shape=(6, 5), method="lattice", **kw)
    nufft = rigid_body_projection(x, p, motion, grid_shape=(6, 5), method="nufft", **kw)
    direct = rigid_body_projection(x, p, motion, method="direct", **kw)
    scale = np.abs(direct.data).max()
    np.testing.assert_allclose(lat.data, direct.data, atol=FLOAT_TOL * scale)
    np.testing.assert_allclose(nufft.data, direct.data, atol=NUFFT_TOL * scale)
    for g in range(3):
        for i, a in enumerate(az):
            for j, e in enumerate(el):
                ref = ref_rigid_body(x[:, :, g], p, rot, disp, LAM, r_axis[g], direction(a, e))
                np.testing.assert_allclose(lat.data[:, g, i, j], ref, atol=1e-5 * scale)


def test_yaw_projection_uses_yaw_only():
    rng = np.random.default_rng(3)
    arr = upa(4, 4, wavelength=LAM)
    x = _cube(rng, n=8, m=16, r=1)
    from scipy.spatial.transform import Rotation

    rot = Rotation.from_euler("ZYX", np.c_[np.linspace(0, 0.3, 8), np.zeros(8), np.zeros(8)])
    motion = PlatformMotion(np.arange(8.0), rot.as_matrix(), np.zeros((8, 3)), np.zeros((8, 3)),
                            np.zeros((8, 3)), [0.0, 0.0, 0.1])
    kw = dict(wavelength=LAM, range_axis=[15.0], azimuth=[0.3], elevation=[0.2])
    y = yaw_projection(x, arr.virtual_positions, motion, **kw)
    e = rigid_body_projection(x, arr.virtual_positions, motion, focus="far", **kw)
    np.testing.assert_allclose(y.data, e.data, atol=1e-5 * np.abs(e.data).max())


def test_rotation_phase_paper_vs_displacement():
    """v_r(t) t equals the integrated displacement only for small rotation angles."""
    t = np.arange(256) * 60e-6
    w0, f = np.deg2rad(10) * 2 * np.pi * 20, 20.0
    pitch = np.deg2rad(10) * np.sin(2 * np.pi * f * t)
    from scipy.spatial.transform import Rotation

    rot = Rotation.from_euler("Y", pitch[:, None]).as_matrix()
    rate = np.zeros((t.size, 3))
    rate[:, 1] = w0 * np.cos(2 * np.pi * f * t)
    motion = PlatformMotion(t, rot, np.zeros((t.size, 3)), np.zeros((t.size, 3)), rate,
                            [0.0, 0.0, 0.1])
    u = direction(np.deg2rad(20), 0.0)
    disp = range_change(motion, u)
    paper = range_change(motion, u, rotation_phase="published")
    np.testing.assert_allclose(disp, -(rot @ [0, 0, 0.1] - [0, 0, 0.1]) @ u, atol=1e-15)
    np.testing.assert_allclose(disp[1:8], paper[1:8], rtol=0.02)         # early: same
    assert np.abs(disp - paper).max() > 1e-3                              # later: not


ARR = upa(5, 4, wavelength=LAM)


@settings(max_examples=6, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31 - 1), n=st.integers(4, 20))
def test_zero_motion_leaves_cube_unchanged(seed, n):
    rng = np.random.default_rng(seed)
    x = _cube(rng, n=n, m=20, r=3)
    motion = static_motion(np.arange(n) * 60e-6, lever_arm=[0.0, 0.0, 0.1])
    u = direction(rng.uniform(-1, 1), rng.uniform(-0.5, 0.5))
    p = ARR.virtual_positions
    np.testing.assert_array_equal(tilt_correction(x, p, motion.attitude, wavelength=LAM), x)
    np.testing.assert_array_equal(slow_time_correction(x, motion, u, wavelength=LAM), x)
    kw = dict(wavelength=LAM, range_axis=[5.0, 6.0, 7.0], azimuth=[0.1, -0.4],
              elevation=[0.0, 0.3], grid_shape=(5, 4))
    ref = beam_projection(x, p, **kw)
    exact = rigid_body_projection(x, p, motion, **kw)
    pap = paper_chain(x, p, motion, direction=u, **kw)
    np.testing.assert_allclose(exact.data, ref.data, atol=FLOAT_TOL * np.abs(ref.data).max())
    np.testing.assert_allclose(pap.data, ref.data, atol=FLOAT_TOL * np.abs(ref.data).max())


def test_if_domain_correction_moves_beat_and_phase():
    """Per-sample IF correction of a delay change restores the reference tone exactly."""
    fc, mu, fs, k = 77e9, 1e9 / 60e-6, 10e6, 600
    t = np.arange(k) / fs
    tau0 = 2 * 15.0 / 299_792_458.0
    dr = np.array([0.0, 0.01, -0.02])
    tau = tau0 + 2 * dr / 299_792_458.0
    s = np.exp(2j * np.pi * (fc * tau[:, None] + mu * tau[:, None] * t))[:, None, :]
    # the radar moving up (-z, NED) by dr lengthens the range to a nadir target by dr
    motion = PlatformMotion(np.arange(3.0), np.broadcast_to(np.eye(3), (3, 3, 3)),
                            np.c_[np.zeros(3), np.zeros(3), -dr], np.zeros((3, 3)),
                            np.zeros((3, 3)), np.zeros(3))
    out = slow_time_correction(s, motion, direction(0.0, 0.0), wavelength=1.0, domain="if",
                               carrier_frequency=fc, chirp_rate=mu, sample_rate=fs)
    ref = np.exp(2j * np.pi * (fc * tau0 + mu * tau0 * t))
    np.testing.assert_allclose(out[:, 0, :], np.broadcast_to(ref, (3, k)), atol=1e-9)


@pytest.mark.parametrize("kwargs, match", [
    (dict(rc="real"), "rc must be a complex cube"),
    (dict(element_positions="short"), r"element_positions must have shape \[8, 3\]"),
    (dict(wavelength=-1.0), "wavelength must be a finite positive"),
    (dict(range_gates=[7]), "range_gates must be integer bin indices"),
    (dict(attitude="bad"), r"attitude must have shape \[4, 3, 3\]"),
    (dict(displacement="nan"), "displacement must be finite"),
    (dict(method="lattice"), "needs grid_shape"),
    (dict(focus="mid"), "focus must be one of"),
    (dict(grid_shape=(3, 3)), "does not match 8 channels"),
])
def test_projection_bad_input(kwargs, match):
    rng = np.random.default_rng(0)
    kw = dict(rc=_cube(rng, n=4, m=8, r=2), element_positions=upa(4, 2, wavelength=LAM)
              .virtual_positions, wavelength=LAM, range_axis=[5.0, 6.0], azimuth=[0.0],
              elevation=[0.0])
    for key, val in kwargs.items():
        if val == "real":
            kw["rc"] = np.ones((4, 8, 2))
        elif val == "short":
            kw["element_positions"] = np.zeros((7, 3))
        elif val == "bad":
            kw["attitude"] = np.zeros((3, 3, 3))
        elif val == "nan":
            kw["displacement"] = np.full((4, 3), np.nan)
        else:
            kw[key] = val
    with pytest.raises(ValueError, match=match):
        beam_projection(kw.pop("rc"), kw.pop("element_positions"), **kw)


def test_beam_cube_to_xarray():
    """BeamCube.to_xarray: the axes of docs/conventions.md, coordinates with units, the data."""
    from compensation.projection import BeamCube

    rng = np.random.default_rng(2)
    shape = (4, 3, 5, 2)
    data = (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)).astype(np.complex64)
    cube = BeamCube(data, np.arange(4) * 1e-4, np.array([10.0, 10.5, 11.0]),
                    np.deg2rad(np.linspace(-20, 20, 5)), np.deg2rad([0.0, 5.0]), LAM,
                    warnings=("hover window", "small-angle"))
    da = cube.to_xarray()
    assert da.dims == ("chirp", "range", "azimuth", "elevation") and da.name == "beams"
    assert da.dtype == np.complex64
    np.testing.assert_array_equal(da.values, data)
    for name, unit in (("range", "m"), ("azimuth", "rad"), ("elevation", "rad")):
        np.testing.assert_array_equal(da[name].values, getattr(cube, name))
        assert da[name].attrs["units"] == unit
    np.testing.assert_array_equal(da["chirp_time"].values, cube.chirp_time)
    assert da["chirp_time"].attrs["units"] == "s"
    assert da.attrs["wavelength_m"] == LAM and da.attrs["warnings"] == "hover window; small-angle"
    back = BeamCube(da.values, da["chirp_time"].values, da["range"].values,
                    da["azimuth"].values, da["elevation"].values, da.attrs["wavelength_m"],
                    tuple(da.attrs["warnings"].split("; ")))
    np.testing.assert_array_equal(back.doppler(), cube.doppler())
    assert back.warnings == cube.warnings
