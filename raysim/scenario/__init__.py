"""Scenarios: one TOML file describes a whole simulation run.

Modules
-------
``model``
    :class:`Scenario` and its sections (``[radar]``, ``[array]``, ``[scene]``,
    ``[motion]``, ``[imu]``, ``[output]``), validated with pydantic;
    :func:`validate_scenario` turns plain data into a :class:`Scenario`.
    Conversions to the library's SI objects: :meth:`Scenario.radar_config`,
    :meth:`Scenario.virtual_array`, :meth:`Scenario.trajectory`,
    :meth:`Scenario.imu_spec`.
``reader``
    :func:`load_scenario` (a file), :func:`loads_scenario` (TOML text),
    :func:`scenario_from_case` (a paper case).
``paper_cases``
    The paper's experiments, read from the TOML data files ``cases/<name>.toml``
    (scenario keys and the values the paper reports): :data:`PAPER_CASES`,
    :func:`get_case`, :func:`paper_values`.
``radar``, ``meshes``
    The ``[radar]`` section and the ``[[scene.meshes]]`` entries.
``keys``
    Dotted key paths (:func:`get_key`, :func:`set_key`,
    :func:`parse_assignment` for ``--set``), TOML output (:func:`dumps_toml`)
    and validation messages that name the key, the value and what was expected.

File units follow docs/conventions.md: SI with the unit in the key name
(``range_m``, ``sample_rate_hz``), angles in degrees (``az_deg``).
"""

from raysim.scenario.keys import (
    did_you_mean,
    dumps_toml,
    format_validation_error,
    get_key,
    parse_assignment,
    parse_value,
    set_key,
)
from raysim.scenario.model import (
    ANGLE_AXES,
    TRANSLATION_AXES,
    ArraySection,
    HoverJitterSection,
    ImuSection,
    MotionSection,
    OutputSection,
    Scenario,
    SceneSection,
    SensorErrorsSection,
    SinusoidSpec,
    TargetSpec,
    validate_scenario,
)
from raysim.scenario.paper_cases import DEFAULT_LEVER_ARM, PAPER_CASES, get_case, paper_values
from raysim.scenario.radar import RadarSection
from raysim.scenario.reader import load_scenario, loads_scenario, scenario_from_case

__all__ = [
    "RadarSection", "ArraySection", "TargetSpec", "SceneSection", "SinusoidSpec",
    "HoverJitterSection", "MotionSection", "SensorErrorsSection", "ImuSection",
    "OutputSection", "Scenario", "load_scenario", "loads_scenario", "validate_scenario",
    "scenario_from_case", "set_key", "get_key", "dumps_toml", "format_validation_error",
    "ANGLE_AXES", "TRANSLATION_AXES", "parse_value", "parse_assignment", "did_you_mean",
    "PAPER_CASES", "DEFAULT_LEVER_ARM", "get_case", "paper_values",
]
