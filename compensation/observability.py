"""What a record's Doppler constrains of the radar-inertial state, and the warnings.

The state is that of :mod:`compensation.radar_inertial` (:data:`STATE_NAMES`).
In prior-whitened coordinates ``w = L^-1 x`` (``P0 = L L^T``) the Fisher
information of the radar is ``L^T H^T C^-1 H L``; along an eigenvector of
eigenvalue ``lambda`` the posterior spread is ``1 / sqrt(1 + lambda)`` of the
prior's. A component or direction whose posterior spread stays above
:data:`UNCONSTRAINED_RATIO` of the prior is unconstrained: the scene leaves it
at the prior. The scatterer geometry is judged on its own too: fewer than three
distinct directions, or directions in one row, plane or narrow cone, leave
part of the velocity to the prior.
"""

from __future__ import annotations

import numpy as np

from ._checks import finite_array
from .guards import CompensationWarning

__all__ = ["HELD_WHEN_UNCONSTRAINED", "STATE_NAMES", "TILT_WARN_DEG", "UNCONSTRAINED_RATIO",
           "ObservabilityWarning", "geometry_warnings", "held_mask", "observability",
           "observability_warnings"]

#: Names of the state components, in order (units in the module docstring).
STATE_NAMES = ("velocity_n", "velocity_e", "velocity_d", "tilt_n", "tilt_e", "heading",
               "accel_bias_x", "accel_bias_y", "accel_bias_z", "gyro_bias_x", "gyro_bias_y",
               "gyro_bias_z", "clock_offset", "clock_drift")
#: Posterior over prior spread above which a component (or direction) is unconstrained.
UNCONSTRAINED_RATIO = 0.5
#: Smallest-to-largest singular value of the scatterer directions below which they lie
#: in one row, a plane or a narrow cone [1].
GEOMETRY_CONDITION = 0.15
#: Smallest number of distinct directions that determine a velocity.
MIN_DIRECTIONS = 3
#: Directions closer than this are one scatterer for the geometry check [rad].
SAME_DIRECTION = float(np.deg2rad(1.0))
#: A given tilt (the flight controller's attitude, or roll and pitch from the ground
#: plane) whose estimated spread exceeds this [deg] is warned: every beam's angle in the
#: world carries it, and it is the angle a compensated target is held to. The spread is
#: that of both axes together (their root sum of squares: a beam near the nadir moves by
#: the tilt vector's length).
TILT_WARN_DEG = 0.2


class ObservabilityWarning(CompensationWarning):
    """The scene leaves part of the radar-inertial state unconstrained (kept at its prior)."""


def observability(prior_cov, fisher, *, ratio: float = UNCONSTRAINED_RATIO
                  ) -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Components and directions of the state the measurements leave at the prior.

    Parameters
    ----------
    prior_cov : array_like, shape ``[14, 14]``
    fisher : array_like, shape ``[14, 14]``
        Information of the measurements ``H^T C^-1 H``.
    ratio : float
        :data:`UNCONSTRAINED_RATIO`.

    Returns
    -------
    (tuple of str, tuple of str)
        Names of the unconstrained components (:data:`STATE_NAMES`), and the
        unconstrained eigen-directions of the prior-whitened information as
        ``"0.71 tilt_n + 0.70 accel_bias_y"`` (coefficients in prior spreads).
    """
    p0 = np.asarray(prior_cov, dtype=float)
    f = np.asarray(fisher, dtype=float)
    post = np.linalg.inv(np.linalg.inv(p0) + f)
    names = tuple(n for n, a, b in zip(STATE_NAMES, np.diag(post), np.diag(p0), strict=True)
                  if np.sqrt(a / b) > ratio)
    s = np.sqrt(np.diag(p0))
    lc = np.linalg.cholesky(p0 / np.outer(s, s))          # correlation factor of the prior
    lam, vec = np.linalg.eigh(lc.T @ (f * np.outer(s, s)) @ lc)
    dirs = []
    for k in np.flatnonzero(1.0 / np.sqrt(1.0 + np.maximum(lam, 0.0)) > ratio):
        v = lc @ vec[:, k]
        v = v / np.linalg.norm(v)
        v = v * np.sign(v[np.argmax(np.abs(v))])
        big = [i for i in np.argsort(-np.abs(v)) if abs(v[i]) >= 0.3][:4]
        if any(STATE_NAMES[i] not in names for i in big) or len(big) > 1:
            dirs.append(" + ".join(f"{v[i]:.2f} {STATE_NAMES[i]}" for i in big)
                        .replace("+ -", "- "))
    return names, tuple(dirs)


def geometry_warnings(directions) -> tuple[str, ...]:
    """Warnings on scatterer directions that cannot determine a velocity.

    Parameters
    ----------
    directions : array_like, shape ``[scatterer, 3]``
        Unit directions in W.

    Returns
    -------
    tuple of str
        ``"geometry: ..."`` when fewer than :data:`MIN_DIRECTIONS` distinct
        directions are seen, or when they lie in one row, plane or narrow cone
        (smallest over largest singular value below :data:`GEOMETRY_CONDITION`),
        with the poorly constrained velocity direction.
    """
    u = finite_array("directions", directions, ndim=2)
    distinct: list[np.ndarray] = []
    for d in u:
        if all(np.arccos(np.clip(d @ e, -1.0, 1.0)) > SAME_DIRECTION for e in distinct):
            distinct.append(d)
    n = len(distinct)
    _, sv, vt = np.linalg.svd(np.stack(distinct), full_matrices=True)
    weak = vt[-1] * np.sign(vt[-1][np.argmax(np.abs(vt[-1]))])
    axis = "(" + ", ".join(f"{x:.2f}" for x in weak) + ") (W, north-east-down)"
    if n < MIN_DIRECTIONS:
        return (f"geometry: {n} distinct scatterer direction(s); the Doppler constrains "
                f"the velocity along {n} direction(s) only, the rest (e.g. along {axis}) "
                f"stays at the IMU prior",)
    cond = float(sv[-1] / sv[0]) if sv.size == 3 else 0.0
    if cond < GEOMETRY_CONDITION:
        return (f"geometry: the {n} scatterer directions lie in one row, plane or narrow "
                f"cone (smallest/largest singular value {cond:.3f} < {GEOMETRY_CONDITION}); "
                f"the velocity along {axis} is poorly constrained",)
    return ()


#: Components held at the prior when the radar leaves them unconstrained (the others are
#: estimated along whatever the radar constrains): the attitude, which turns the beams,
#: and what turns or shifts it over the record.
HELD_WHEN_UNCONSTRAINED = ("tilt_n", "tilt_e", "heading", "gyro_bias_x", "gyro_bias_y",
                           "gyro_bias_z", "clock_offset", "clock_drift")


def held_mask(p0: np.ndarray, fisher: np.ndarray) -> np.ndarray:
    """Mask of the components held at their prior: unconstrained ones of
    :data:`HELD_WHEN_UNCONSTRAINED`.

    The tilt and the horizontal accelerometer bias give the same acceleration
    error; when the radar constrains only their sum, the given attitude is kept
    and the bias takes the sum: the velocity is the same, the beams are not
    turned by a split the radar cannot make.
    """
    names, _ = observability(p0, fisher)
    return np.array([n in names and n in HELD_WHEN_UNCONSTRAINED for n in STATE_NAMES])


def observability_warnings(names, sigma, sig0, attitude_given: bool, directions
                           ) -> tuple[str, ...]:
    """Warnings of an estimate: no measurement, geometry, unconstrained velocity, attitude
    not given.

    ``names``: unconstrained components; ``sigma``, ``sig0``: posterior and
    prior spreads ``[14]``; ``directions [measurement, 3]`` (None: no
    measurement kept).
    """
    out: list[str] = []
    if directions is None:
        return ("observability: no Doppler measurement kept; every component stays at "
                "the IMU prior",)
    out.extend(geometry_warnings(directions))
    vel = [n for n in names if n.startswith("velocity")]
    if vel:
        out.append(f"unconstrained: {', '.join(vel)} kept at the IMU prior "
                   f"(+- {sig0[0]:.3g} m/s)")
    if not attitude_given:
        tilt = np.rad2deg(sigma[3:5])
        out.append(f"attitude: not given; the Doppler sees the tilt only through gravity, "
                   f"no better than the accelerometer bias is known: tilt_n +- {tilt[0]:.2g}, "
                   f"tilt_e +- {tilt[1]:.2g} deg (of the nominal attitude's "
                   f"{np.rad2deg(sig0[3]):.3g}); give the attitude")
    elif np.hypot(*np.rad2deg(sigma[3:5])) > TILT_WARN_DEG:
        tilt = np.rad2deg(sigma[3:5])
        out.append(f"attitude: roll and pitch known to tilt_n +- {tilt[0]:.2g}, tilt_e +- "
                   f"{tilt[1]:.2g} deg only (together +- {np.hypot(*tilt):.2g}, over "
                   f"{TILT_WARN_DEG:g}; from the attitude given or the ground plane): every "
                   f"beam's angle in the world carries it")
    return tuple(out)
