"""The ``[radar]`` section of scenario files and the base of every section.

Part of the scenario model (:mod:`raysim.scenario.model` uses :class:`RadarSection`):
the FMCW waveform keys and the element pattern with its gain.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

from raysim.radar.config import (
    ANTENNA_GAIN_DBI_RANGE,
    NOISE_FIGURE_DB_RANGE,
    TX_POWER_DBM_RANGE,
)
from raysim.radar.pattern import resolve_element_gain
from raysim.scenario.keys import did_you_mean

__all__ = ["RadarSection"]


def _in_range(value: float, bounds: tuple[float, float], unit: str, what: str) -> float:
    """``value`` if within the physical ``bounds`` (inclusive), else a ValueError saying so."""
    if not bounds[0] <= value <= bounds[1]:
        raise ValueError(f"{what} in the physical range [{bounds[0]:g}, {bounds[1]:g}] {unit}")
    return value


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)


# ----------------------------------------------------------------------- radar
class RadarSection(_Section):
    """``[radar]``: FMCW waveform (defaults: the paper's Table 2).

    See :class:`raysim.radar.config.RadarConfig` for the meaning of every field; the
    file keys carry their unit. Physical ranges: ``tx_power_dbm`` -100 to 60 dBm,
    ``antenna_gain_dbi`` -30 to 50 dBi, ``noise_figure_db`` 0 to 50 dB.

    ``element_pattern``: ``"patch"`` (default, ``cos^q`` with ``q`` from
    ``antenna_gain_dbi``: ``G0 = 2 (q + 1)``, ``cos^4`` at 10 dBi), ``"cos^<q>"``
    (e.g. ``"cos^6"``), ``"tr38901"`` (8 dBi), ``"constant"`` (``antenna_gain_dbi`` in every
    direction)
    or the path of a CSV pattern file (relative to the scenario file; format in
    :meth:`raysim.radar.pattern.TabulatedPattern.from_csv`). Without an explicit
    ``antenna_gain_dbi`` the gain is the pattern's peak; an explicit gain that
    disagrees with it by more than 0.5 dB is refused.

    ``polarisation``: transmit-receive channel of the ground clutter's
    ``sigma0`` (``"VV"`` default, ``"HH"``, ``"HV"``; docs/clutter.md).

    ``mounting_deg``: how the radar sits on the body, as ``--mounting-deg`` of
    ``raysim flight`` and ``raysim compensate``: a preset (``"down"``, the
    default, ``"forward"``, ``"oblique"``) or ``[yaw, pitch, roll]`` [deg], the
    Z-Y-X Euler angles of ``R_BA`` (:mod:`raysim.platform.mounting`). Target
    directions and beams are then in the nominal radar frame N; the lever arm
    is the scenario's ``lever_arm_m`` (in B).
    """

    carrier_frequency_hz: float = Field(77e9, gt=0)
    bandwidth_hz: float = Field(1e9, gt=0)
    chirp_duration_s: float = Field(60e-6, gt=0)
    idle_time_s: float = Field(0.0, ge=0)
    sample_rate_hz: float = Field(10e6, gt=0)
    num_chirps: int = Field(256, ge=4)
    complex_sampling: bool = True
    tx_power_dbm: float = 12.0
    antenna_gain_dbi: float = 10.0
    noise_figure_db: float = 12.0
    frame_period_s: float | None = Field(None, gt=0)
    element_pattern: str = "patch"
    polarisation: Literal["VV", "HH", "HV"] = "VV"
    mounting_deg: str | tuple[float, float, float] | None = None

    _tx_power = field_validator("tx_power_dbm")(
        lambda v: _in_range(v, TX_POWER_DBM_RANGE, "dBm", "a transmit power"))
    _gain = field_validator("antenna_gain_dbi")(
        lambda v: _in_range(v, ANTENNA_GAIN_DBI_RANGE, "dBi", "an antenna gain"))
    _noise_figure = field_validator("noise_figure_db")(
        lambda v: _in_range(v, NOISE_FIGURE_DB_RANGE, "dB", "a noise figure"))

    @field_validator("mounting_deg", mode="before")
    @classmethod
    def _mounting(cls, v):
        """A preset name (lower case) or three finite angles [deg]; None is ``down``."""
        if v is None:
            return v
        from raysim.platform.mounting import MOUNTING_PRESETS, mounting_deg

        try:
            ypr = mounting_deg(v, "radar.mounting_deg")
        except ValueError:
            raise ValueError(f"one of {sorted(MOUNTING_PRESETS)} or [yaw, pitch, roll] "
                             f"(three finite angles [deg])"
                             f"{did_you_mean(v, MOUNTING_PRESETS)}") from None
        name = v.strip().lower() if isinstance(v, str) else None
        return name if name in MOUNTING_PRESETS else ypr

    @property
    def element_gain_dbi(self) -> float:
        """``antenna_gain_dbi`` if given, else the element pattern's peak [dBi] (checked)."""
        return resolve_element_gain(self.element_pattern, self.antenna_gain_dbi,
                                    "antenna_gain_dbi" in self.model_fields_set)

    _pattern = model_validator(mode="after")(lambda self: (self.element_gain_dbi, self)[1])
