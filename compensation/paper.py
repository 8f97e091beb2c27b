"""The published IMU-driven compensation chain, step by step.

Steps (each selectable in :func:`paper_chain`):

``"translation"``
    Chirp-by-chirp slow-time phase for the body translation ``T_n`` projected
    on the target direction ``u``: the range change is ``dR_n = -T_n . u``
    (X/Y translation ``dp . u``, Z translation ``dz cos(az) cos(el)``, which is
    ``dz u_z``: one formula covers both of the paper's cases).
``"rotation"``
    Radial motion of the radar phase centre caused by rotation of the lever
    arm. ``rotation_phase="integrated"`` (default) uses the integrated
    displacement ``dR_n = -((R_n - I) r_IR) . u``. ``rotation_phase="published"``
    uses the published form, the instantaneous radial velocity times the
    elapsed time, ``dR_n = v_r(t_n) (t_n - t_0)`` with
    ``v_r = -(omega_B x r_IR) . u``; it equals the integral only while the
    rate is constant over the frame.
``"tilt"``
    Element-wise spatial phase for roll and pitch, small-angle and boresight
    form as published (``S' = S exp(-j 2 pi / lambda m d dbeta)``), in our
    convention ``exp(-j 2 pi / lambda (p_x theta - p_y phi))`` with pitch
    ``theta`` and roll ``phi`` (Euler Z-Y-X) of each chirp.
``"yaw"``
    Chirp-wise beam projection onto a fixed global grid:
    ``W_n = exp(-j 2 pi / lambda P^T u_B)`` with ``u_B = Rz(gamma_n)^T u_G``,
    ``y = W^H X``.

Assumption checks (:mod:`compensation.guards`): :func:`paper_chain` returns
``"small-angle"`` and ``"paper rotation phase"`` entries in
``BeamCube.warnings`` when the tilt correction or the published rotation
phase leaves more than half a beamwidth of angle error or a quarter
wavelength of range error towards ``direction``; :func:`tilt_correction`
issues them as :class:`~compensation.guards.CompensationWarning`.

Sign conventions are ours (docs/conventions.md): the IF phase grows with range
(``+4 pi R / lambda``), so every slow-time correction is
``exp(-j 4 pi dR_n / lambda)``; the paper writes the propagation phase with
the opposite sign.
"""

from __future__ import annotations

import warnings as _warnings
from typing import Literal

import numpy as np

from ._checks import channel_slots, choice, finite_array, positive
from .geometry import euler_zyx, yaw_matrices
from .guards import CompensationWarning, merge, rotation_phase_warnings, small_angle_warnings
from .projection import BeamCube, beam_projection
from .strapdown import PlatformMotion

#: Speed of light [m/s].
SPEED_OF_LIGHT = 299_792_458.0

#: Steps of the published chain, in the order they are applied.
PAPER_STEPS = ("tilt", "translation", "rotation", "yaw")


def _check_motion(motion, n_chirp: int) -> None:
    if not isinstance(motion, PlatformMotion):
        raise ValueError(f"motion must be a compensation.PlatformMotion, got {type(motion)!r}")
    if motion.num_chirps != n_chirp:
        raise ValueError(f"motion has {motion.num_chirps} chirp times but the cube has "
                         f"{n_chirp} chirps")


def _unit(name: str, u) -> np.ndarray:
    u = finite_array(name, u, shape=(3,))
    norm = np.linalg.norm(u)
    if not 0.99 < norm < 1.01:
        raise ValueError(f"{name} must be a unit vector (az/el direction in W), got norm {norm}")
    return u / norm


def range_change(motion: PlatformMotion, direction, *,
                 components=("translation", "rotation"),
                 rotation_phase: Literal["integrated", "published"] = "integrated"
                 ) -> np.ndarray:
    """Platform-induced range change of a static target, per chirp.

    Parameters
    ----------
    motion : PlatformMotion
    direction : array_like, shape ``[3]``
        Target direction ``u`` in W (unit) at the nominal attitude.
    components : sequence of {"translation", "rotation"}
        Contributions to include.
    rotation_phase : {"integrated", "published"}
        Integrated lever-arm displacement (default) or the published
        ``v_r(t_n) (t_n - t_0)``.

    Returns
    -------
    ndarray, shape ``[chirp]``
        ``dR_n`` [m], positive when the range grows.
    """
    u = _unit("direction", direction)
    for c in components:
        choice("components entry", c, ("translation", "rotation"))
    choice("rotation_phase", rotation_phase, ("integrated", "published"))
    dr = np.zeros(motion.num_chirps)
    if "translation" in components:
        dr -= motion.translation_displacement @ u
    if "rotation" in components:
        if rotation_phase == "integrated":
            dr -= motion.rotation_displacement @ u
        else:
            v_r = -(np.cross(motion.angular_rate, motion.lever_arm) @ u)
            dr += v_r * (motion.time - motion.time[0])
    return dr


def slow_time_correction(cube, motion: PlatformMotion, direction, *, wavelength: float,
                         components=("translation", "rotation"),
                         rotation_phase: Literal["integrated", "published"] = "integrated",
                         domain: Literal["range", "if"] = "range",
                         carrier_frequency: float | None = None,
                         chirp_rate: float | None = None,
                         sample_rate: float | None = None) -> np.ndarray:
    """Chirp-by-chirp phase correction of the platform motion towards one direction.

    Parameters
    ----------
    cube : ndarray, shape ``[chirp, ...]``
        Range-compressed ``[chirp, channel, range]`` (``domain="range"``), any
        ``[chirp, ...]`` slow-time data, or raw IF ``[chirp, channel, sample]``
        (``domain="if"``).
    motion : PlatformMotion
    direction : array_like, shape ``[3]``
        Target direction in W (from angle estimation).
    wavelength : float
        Wavelength of range-compressed data, ``c / (f_c + B / 2)`` [m]
        (ignored for ``domain="if"``).
    components, rotation_phase
        See :func:`range_change`.
    domain : {"range", "if"}
        ``"range"``: multiply chirp ``n`` by ``exp(-j 4 pi dR_n / lambda)``.
        ``"if"``: exact per-sample form on raw IF,
        ``exp(-j 2 pi (f_c + mu t_k) 2 dR_n / c)``, which also moves the beat
        frequency back; needs ``carrier_frequency``, ``chirp_rate`` and
        ``sample_rate``.

    Returns
    -------
    ndarray, same shape as ``cube``, complex64 for complex64 input
    """
    x = np.asarray(cube)
    _check_motion(motion, x.shape[0])
    choice("domain", domain, ("range", "if"))
    dr = range_change(motion, direction, components=components, rotation_phase=rotation_phase)
    ctype = np.complex64 if x.dtype == np.complex64 else np.complex128
    if domain == "range":
        lam = positive("wavelength", wavelength)
        corr = np.exp(-4j * np.pi * dr / lam).astype(ctype)
        return x * corr.reshape((-1,) + (1,) * (x.ndim - 1))
    if x.ndim != 3:
        raise ValueError(f'domain="if" needs cube of shape [chirp, channel, sample], got '
                         f'{x.shape}')
    fc = positive("carrier_frequency", carrier_frequency)
    mu = positive("chirp_rate", chirp_rate)
    fs = positive("sample_rate", sample_rate)
    t = np.arange(x.shape[-1]) / fs
    corr = np.exp(-2j * np.pi * (fc + mu * t)[None, :] * (2.0 * dr / SPEED_OF_LIGHT)[:, None])
    return x * corr.astype(ctype)[:, None, :]


def tilt_correction(cube, element_positions, attitude, *, wavelength: float,
                    direction=None) -> np.ndarray:
    """Element-wise spatial phase correction of roll and pitch (small angle, as published).

    Parameters
    ----------
    cube : ndarray, shape ``[chirp, channel, ...]``
        Range-compressed (or IF) data.
    element_positions : ndarray, shape ``[channel, 3]``
        Virtual positions ``p_tx + p_rx`` in A [m].
    attitude : ndarray, shape ``[chirp, 3, 3]``
        ``R_WB`` per chirp; roll ``phi`` and pitch ``theta`` are its Z-Y-X
        Euler angles.
    wavelength : float
        [m]; the mid-chirp wavelength for range-compressed data.
    direction : array_like, shape ``[3]``, optional
        Target direction in W. When given, a residual angle error above half
        the 3 dB beamwidth towards it is reported (see below).

    Returns
    -------
    ndarray, same shape as ``cube``

    Warns
    -----
    CompensationWarning
        ``"small-angle: ..."`` when roll or pitch exceeds
        :data:`~compensation.guards.SMALL_ANGLE_TILT_LIMIT` or the residual
        towards ``direction`` (:func:`compensation.guards.tilt_residual`)
        exceeds half the beamwidth.

    Notes
    -----
    A small rotation ``theta`` changes the body-frame direction of a target
    near boresight by ``-theta x e_z``, i.e. the element phase
    ``-2 pi / lambda v . p`` by ``+2 pi / lambda (p_x theta - p_y phi)``; the
    correction multiplies by the conjugate. The published form neglects the
    ``cos(az)`` factor of an off-boresight target and the small-angle error,
    so a residual bias of order ``theta (1 - cos az)`` remains: for a pitch
    ``theta`` and a target at azimuth ``az`` the corrected direction is
    ``asin(sin(az - theta) + theta)``.
    """
    x, p, lam, att = _tilt_inputs(cube, element_positions, attitude, wavelength)
    u = None if direction is None else _unit("direction", direction)
    for w in small_angle_warnings(att, p, u, wavelength=lam):
        _warnings.warn(w, CompensationWarning, stacklevel=2)
    return _apply_tilt(x, p, lam, att)


def _tilt_inputs(cube, element_positions, attitude, wavelength):
    x = np.asarray(cube)
    if x.ndim < 2:
        raise ValueError(f"cube must have shape [chirp, channel, ...], got {x.shape}")
    p = finite_array("element_positions", element_positions, shape=(x.shape[1], 3))
    lam = positive("wavelength", wavelength)
    att = np.asarray(attitude, dtype=float)
    if att.shape != (x.shape[0], 3, 3):
        raise ValueError(f"attitude must have shape [{x.shape[0]}, 3, 3], got {att.shape}")
    return x, p, lam, att


def _apply_tilt(x: np.ndarray, p: np.ndarray, lam: float, att: np.ndarray) -> np.ndarray:
    ypr = euler_zyx(att)
    pitch, roll = ypr[:, 1], ypr[:, 2]
    phase = 2.0 * np.pi / lam * (np.outer(pitch, p[:, 0]) - np.outer(roll, p[:, 1]))
    ctype = np.complex64 if x.dtype == np.complex64 else np.complex128
    corr = np.exp(-1j * phase).astype(ctype)
    return x * corr.reshape(corr.shape + (1,) * (x.ndim - 2))


def yaw_projection(rc, element_positions, motion: PlatformMotion, *, wavelength: float,
                   range_axis, azimuth, elevation, range_gates=None,
                   grid_shape: tuple[int, int] | None = None,
                   method: Literal["auto", "nufft", "lattice", "direct"] = "auto",
                   weights=None) -> BeamCube:
    """The paper's chirp-wise beam projection for yaw onto a fixed global grid.

    ``y_n(u_G) = W_n^H x_n / M`` with ``W_n = exp(-j 2 pi / lambda P^T Rz(gamma_n)^T u_G)``;
    only the yaw ``gamma_n`` of the attitude is used, no translation phase.

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
    element_positions : ndarray, shape ``[channel, 3]``
    motion : PlatformMotion
    wavelength, range_axis, azimuth, elevation, range_gates, grid_shape, method, weights
        See :func:`compensation.projection.beam_projection`.

    Returns
    -------
    BeamCube
        ``warnings`` are those of ``motion``.
    """
    _check_motion(motion, np.shape(rc)[0])
    yaw = motion.euler()[:, 0]
    return beam_projection(rc, element_positions, wavelength=wavelength, range_axis=range_axis,
                           azimuth=azimuth, elevation=elevation, range_gates=range_gates,
                           chirp_time=motion.time, attitude=yaw_matrices(yaw), focus="far",
                           grid_shape=grid_shape, method=method,
                           weights=weights).with_warnings(motion.warnings)


def paper_chain(rc, element_positions, motion: PlatformMotion, *, wavelength: float,
                direction, range_axis, azimuth, elevation, range_gates=None,
                steps=PAPER_STEPS,
                rotation_phase: Literal["integrated", "published"] = "integrated",
                grid_shape: tuple[int, int] | None = None,
                method: Literal["auto", "nufft", "lattice", "direct"] = "auto",
                weights=None, channel_slot=None) -> BeamCube:
    """The published compensation chain on a range-compressed cube.

    Applies, as selected in ``steps``: the tilt (roll/pitch) element phase, the
    slow-time phase of translation and lever-arm rotation towards
    ``direction``, and the yaw beam projection (without ``"yaw"`` the beams
    are a conventional beam scan of the corrected cube).

    Parameters
    ----------
    rc : ndarray, shape ``[chirp, channel, range]``
        Range-compressed cube.
    element_positions : ndarray, shape ``[channel, 3]``
    motion : PlatformMotion
    wavelength : float
        Mid-chirp wavelength [m].
    direction : array_like, shape ``[3]``
        Target direction in W for the slow-time correction (the paper applies
        it per target after angle estimation).
    range_axis, azimuth, elevation, range_gates, grid_shape, method, weights
        See :func:`compensation.projection.beam_projection`.
    steps : sequence of {"tilt", "translation", "rotation", "yaw"}
    rotation_phase : {"integrated", "published"}
        See :func:`range_change`.
    channel_slot : array_like of int, shape ``[channel]``, optional
        TDM transmit slot of each channel (0 .. slots-1). ``motion`` then holds
        the pose at every transmit slot, chirp major, slot minor
        (``motion.num_chirps == chirp * slots``), and every step uses, for each
        channel, the pose of its own slot: the tilt phase and the slow-time
        phase of that pose, and the yaw projection of each slot's channels
        (summed with their share of ``weights``, as
        :func:`compensation.exact.rigid_body_projection` does).

    Returns
    -------
    BeamCube
        ``data [chirp, range, azimuth, elevation]``, ``chirp_time`` the slot-0
        times with ``channel_slot``. ``warnings``: those of ``motion``, plus
        ``"small-angle: ..."`` (with ``"tilt"``) when roll or pitch exceeds
        :data:`~compensation.guards.SMALL_ANGLE_TILT_LIMIT` or the tilt
        correction leaves an angle error above half the 3 dB beamwidth towards
        ``direction`` at some chirp, and ``"paper rotation phase: ..."`` (with
        ``"rotation"`` and ``rotation_phase="published"``) when the published
        phase departs from the integrated lever-arm displacement by more than
        :data:`~compensation.guards.ROTATION_PHASE_LIMIT`.
    """
    x = np.asarray(rc)
    for s in steps:
        choice("steps entry", s, PAPER_STEPS)
    if channel_slot is not None:
        return _paper_chain_slots(x, element_positions, motion, channel_slot, wavelength=wavelength,
                                  direction=direction, range_axis=range_axis, azimuth=azimuth,
                                  elevation=elevation, range_gates=range_gates, steps=steps,
                                  rotation_phase=rotation_phase, method=method, weights=weights)
    _check_motion(motion, x.shape[0])
    u = None if direction is None else _unit("direction", direction)
    found: tuple[str, ...] = ()
    if "tilt" in steps:
        x, p, lam, att = _tilt_inputs(x, element_positions, motion.attitude, wavelength)
        found += small_angle_warnings(att, p, u, wavelength=lam)
        x = _apply_tilt(x, p, lam, att)
    comps = tuple(c for c in ("translation", "rotation") if c in steps)
    if comps:
        x = slow_time_correction(x, motion, direction, wavelength=wavelength, components=comps,
                                 rotation_phase=rotation_phase)
        if "rotation" in comps and rotation_phase == "published":
            found += rotation_phase_warnings(motion, _unit("direction", direction),
                                             wavelength=float(wavelength))
    if "yaw" in steps:
        beams = yaw_projection(x, element_positions, motion, wavelength=wavelength,
                               range_axis=range_axis, azimuth=azimuth, elevation=elevation,
                               range_gates=range_gates, grid_shape=grid_shape, method=method,
                               weights=weights)
    else:
        beams = beam_projection(x, element_positions, wavelength=wavelength,
                                range_axis=range_axis, azimuth=azimuth, elevation=elevation,
                                range_gates=range_gates, chirp_time=motion.time, focus="far",
                                grid_shape=grid_shape, method=method, weights=weights)
    return beams.with_warnings(merge(motion.warnings, found))


def _paper_chain_slots(x, element_positions, motion: PlatformMotion, channel_slot, *,
                       wavelength, direction, range_axis, azimuth, elevation, range_gates, steps,
                       rotation_phase, method, weights) -> BeamCube:
    """:func:`paper_chain` with the pose of each channel's own TDM slot (see there)."""
    if x.ndim != 3:
        raise ValueError(f"rc must have shape [chirp, channel, range], got {x.shape}")
    p = finite_array("element_positions", element_positions, shape=(x.shape[1], 3))
    slot = channel_slots(channel_slot, x.shape[1])
    n_slot = int(slot.max()) + 1
    if not isinstance(motion, PlatformMotion) or motion.num_chirps != x.shape[0] * n_slot:
        raise ValueError(f"with {n_slot} TDM slots motion must be a PlatformMotion with "
                         f"chirp * slots = {x.shape[0] * n_slot} poses (chirp major), got "
                         f"{getattr(motion, 'num_chirps', type(motion).__name__)}")
    w = np.ones(x.shape[1]) if weights is None else np.asarray(weights, dtype=float)
    if w.shape != (x.shape[1],):
        raise ValueError(f"weights must have shape [{x.shape[1]}], got {w.shape}")
    lam = positive("wavelength", wavelength)
    u = None if direction is None else _unit("direction", direction)
    found: tuple[str, ...] = ()
    if "tilt" in steps:
        found += small_angle_warnings(motion.attitude, p, u, wavelength=lam)
    comps = tuple(c for c in ("translation", "rotation") if c in steps)
    if "rotation" in comps and rotation_phase == "published":
        found += rotation_phase_warnings(motion, _unit("direction", direction), wavelength=lam)
    total, out = float(w.sum()), None
    if method == "auto":
        method = "direct"            # one slot's channels rarely form a grid
    for s in range(n_slot):
        sel = np.flatnonzero(slot == s)
        if sel.size == 0:
            continue
        m = motion.select(slice(s, None, n_slot))
        xs = x[:, sel]
        if "tilt" in steps:
            xs = _apply_tilt(xs, p[sel], lam, m.attitude)
        if comps:
            xs = slow_time_correction(xs, m, direction, wavelength=lam, components=comps,
                                      rotation_phase=rotation_phase)
            if "rotation" in comps and rotation_phase == "published":
                # v_r(t_n) (t_n - t_0) counts from the first ramp of the frame (slot 0),
                # not from this slot's first ramp: add the slot's own start offset
                v_r = -(np.cross(m.angular_rate, m.lever_arm) @ u)
                dr = v_r * (m.time[0] - motion.time[0])
                xs = xs * np.exp(-4j * np.pi * dr / lam).astype(xs.dtype)[:, None, None]
        common = dict(wavelength=lam, range_axis=range_axis, azimuth=azimuth,
                      elevation=elevation, range_gates=range_gates, method=method,
                      weights=w[sel])
        if "yaw" in steps:
            part = yaw_projection(xs, p[sel], m, **common)
        else:
            part = beam_projection(xs, p[sel], chirp_time=m.time, focus="far", **common)
        share = np.float32(float(w[sel].sum()) / total)
        out = part.data * share if out is None else out + part.data * share
    return BeamCube(out.astype(np.complex64, copy=False), motion.time[::n_slot], part.range,
                    part.azimuth, part.elevation, part.wavelength,
                    merge(motion.warnings, found))
