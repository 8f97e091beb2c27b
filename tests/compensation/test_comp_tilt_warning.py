"""A tilt given but loosely known is warned: the beams' world angles carry it.

Roll and pitch taken from a sparse or oblique ground can state a spread of degrees
(an oblique radar over a parking lot without the flight controller's attitude:
+-2 deg, a 0.5 deg angle error); the estimate kept them silently because an
attitude was given. Now :func:`compensation.observability.observability_warnings`
names a spread over :data:`~compensation.observability.TILT_WARN_DEG`.
"""

from __future__ import annotations

import numpy as np

from compensation.observability import STATE_NAMES, TILT_WARN_DEG, observability_warnings

#: Directions spread in a cone of 30 deg: no geometry warning of their own.
DIRECTIONS = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, 0.866], [0.0, 0.5, 0.866],
                       [-0.5, 0.0, 0.866], [0.0, -0.5, 0.866]])


def _warnings(tilt_sigma_deg: float, given: bool) -> tuple:
    sig0 = np.ones(len(STATE_NAMES)) * 0.1
    sig = sig0 * 0.01
    sig[3:5] = np.deg2rad(tilt_sigma_deg)
    return observability_warnings((), sig, sig0, given, DIRECTIONS)


def test_a_loose_given_tilt_is_warned_with_its_spread():
    said = [w for w in _warnings(2.0, True) if w.startswith("attitude:")]
    assert len(said) == 1 and "tilt_n +- 2," in said[0] and "carries it" in said[0]


def test_two_axes_each_under_the_bound_but_together_over_it_are_warned():
    """Roll and pitch from a sparse ground at +-0.18 deg each (a flight without the
    controller's attitude, 0.38 deg of angle error measured): together +-0.25 deg."""
    sig0 = np.ones(len(STATE_NAMES)) * 0.1
    sig = sig0 * 0.01
    sig[3:5] = np.deg2rad([0.18, 0.18])
    assert 0.18 < TILT_WARN_DEG
    said = [w for w in observability_warnings((), sig, sig0, True, DIRECTIONS)
            if w.startswith("attitude:")]
    assert len(said) == 1 and "together +- 0.25" in said[0]


def test_a_tight_given_tilt_is_not():
    assert not [w for w in _warnings(0.5 * TILT_WARN_DEG, True) if w.startswith("attitude:")]


def test_no_attitude_keeps_its_own_warning():
    said = [w for w in _warnings(1.4, False) if w.startswith("attitude:")]
    assert len(said) == 1 and "not given" in said[0]
