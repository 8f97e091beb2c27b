"""The paper's experiments as named scenarios.

A paper case is plain data: a scenario override (the TOML keys of
:class:`raysim.scenario.Scenario`: target, motion sinusoids, radar, array,
frames, lever arm) and the values the paper reports, in the words of
:mod:`raysim.vocabulary`. :func:`raysim.scenario.scenario_from_case` turns a
case into a :class:`~raysim.scenario.Scenario`; ``raysim simulate --case``,
``raysim report --case`` and ``raysim reproduce`` all render that scenario.

Every case shares :data:`BASE`: the paper's Table 2 radar (the ``[radar]``
defaults), the 20 x 20 half-wavelength virtual UPA, the lever arm
:data:`DEFAULT_LEVER_ARM` and an ideal IMU. Motion phases are zero (every
sinusoid starts at its rest position at ``t = 0``, moving in the positive
direction); the paper states neither phases nor lever arm.

``paper`` maps a chain of :data:`raysim.vocabulary.CHAINS` to the metrics of
:data:`raysim.vocabulary.METRICS` the paper reports for it: ``none`` before
compensation, ``paper`` after (pseudo-velocities are magnitudes in the paper).
"""

from __future__ import annotations

import copy

import numpy as np

__all__ = ["DEFAULT_LEVER_ARM", "BASE", "PAPER_CASES", "get_case", "paper_values"]

#: Radar phase centre in the body frame [m]: 10 cm below the IMU (FRD, +Z down).
DEFAULT_LEVER_ARM = np.array([0.0, 0.0, 0.10])

#: Scenario keys shared by every paper case (merged under each case's ``scenario``).
BASE = {
    "lever_arm_m": [float(v) for v in DEFAULT_LEVER_ARM],
    "radar": {},
    "array": {"kind": "upa", "nx": 20, "ny": 20},
    "imu": {"preset": "ideal"},
}


def _target(range_m: float, az_deg: float, el_deg: float) -> dict:
    """``[scene]`` of one static point target (range [m], direction [deg], 10 dBsm)."""
    return {"kind": "points", "targets": [{"range_m": range_m, "az_deg": az_deg,
                                           "el_deg": el_deg, "rcs_dbsm": 10.0}]}


def _sine(axis: str, amplitude: float, frequency_hz: float) -> dict:
    """One ``[[motion.sinusoids]]`` entry; amplitude in deg (rotations) or m."""
    unit = "amplitude_deg" if axis in ("roll", "pitch", "yaw") else "amplitude_m"
    return {"axis": axis, unit: amplitude, "frequency_hz": frequency_hz, "phase_deg": 0.0}


#: Case name -> ``{"description", "scenario", "paper"}``: ``scenario`` holds the
#: TOML keys of the case (over :data:`BASE`), ``paper`` chain -> metric -> value.
PAPER_CASES: dict[str, dict] = {
    "stationary": {
        "description": "stationary platform, target 15 m, az 20, el 0",
        "scenario": {"scene": _target(15.0, 20.0, 0.0), "motion": {}},
        "paper": {},
    },
    "rotation_y": {
        "description": "pitch (about Y) 10 deg at 20 Hz, target 15 m, az 20, el 0",
        "scenario": {"scene": _target(15.0, 20.0, 0.0),
                     "motion": {"sinusoids": [_sine("pitch", 10.0, 20.0)]}},
        "paper": {"none": {"pseudo_velocity_mps": 1.037, "doppler_width_hz": 211.92,
                           "az_deg": 16.0},
                  "paper": {"pseudo_velocity_mps": 0.074, "doppler_width_hz": 154.53,
                            "width_improvement_pct": 30.4, "az_deg": 20.0}},
    },
    "yaw": {
        "description": "yaw 20 deg at 10 Hz, target 18 m, az 25, el 25, 20 frames",
        "scenario": {"frames": 20, "scene": _target(18.0, 25.0, 25.0),
                     "motion": {"sinusoids": [_sine("yaw", 20.0, 10.0)]}},
        "paper": {"none": {"az_deg": 16.5, "el_deg": 31.0, "entropy_ae_nats": 7.3},
                  "paper": {"az_deg": 25.0, "el_deg": 25.0, "entropy_ae_nats": 6.1}},
    },
    "translation_y": {
        "description": "Y translation 5 cm at 5 Hz, 512 chirps, target 15 m, az 10, el 35",
        "scenario": {"radar": {"num_chirps": 512}, "scene": _target(15.0, 10.0, 35.0),
                     "motion": {"sinusoids": [_sine("y", 0.05, 5.0)]}},
        "paper": {"none": {"pseudo_velocity_mps": 1.552, "doppler_width_hz": 120.96},
                  "paper": {"pseudo_velocity_mps": 0.074, "doppler_width_hz": 78.18,
                            "width_improvement_pct": 35.4}},
    },
    "translation_z": {
        "description": "Z translation 5 cm at 5 Hz, 512 chirps, target 15 m, az 10, el 10",
        "scenario": {"radar": {"num_chirps": 512}, "scene": _target(15.0, 10.0, 10.0),
                     "motion": {"sinusoids": [_sine("z", 0.05, 5.0)]}},
        "paper": {"none": {"pseudo_velocity_mps": 2.740, "doppler_width_hz": 171.10},
                  "paper": {"pseudo_velocity_mps": 0.074, "doppler_width_hz": 81.52,
                            "width_improvement_pct": 52.4}},
    },
}


def _merged(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for k, v in over.items():
        out[k] = _merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k), dict) \
            else copy.deepcopy(v)
    return out


def get_case(name: str) -> dict:
    """A paper case by name: ``{"name", "description", "scenario", "paper"}`` (a copy).

    ``scenario`` is the full override (:data:`BASE` merged with the case's
    keys), ready for :func:`raysim.scenario.validate_scenario`.

    Raises
    ------
    ValueError
        Unknown name; the message lists the valid names.
    """
    if not isinstance(name, str) or name not in PAPER_CASES:
        raise ValueError(f"unknown paper case {name!r}; expected one of {sorted(PAPER_CASES)}")
    case = PAPER_CASES[name]
    return {"name": name, "description": case["description"],
            "scenario": _merged(BASE, case["scenario"]), "paper": copy.deepcopy(case["paper"])}


def paper_values(name: str) -> dict[str, float]:
    """The paper's values of a case, flat: ``"<metric> (<chain>)" -> value``, for display."""
    return {f"{metric} ({chain})": value
            for chain, values in get_case(name)["paper"].items()
            for metric, value in values.items()}
