"""The ``[synthesis]`` section of scenario files: slow-time decimation of IF synthesis.

Part of the scenario model (:mod:`raysim.scenario.model` uses :class:`SynthesisSection`).
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from raysim.scenario.radar import _Section

__all__ = ["SynthesisSection", "DECIMATE_MODES"]

#: Values of ``synthesis.decimate`` (and of ``--decimate``).
DECIMATE_MODES = ("auto", "off")


class SynthesisSection(_Section):
    """``[synthesis]``: how ray-traced paths become IF cubes (docs/speed.md).

    ``decimate``: ``"auto"`` (default) renders exact rows on a subset of the
    chirps and interpolates the others along slow time, with a factor bounded
    by the platform motion's Doppler and sideband spectrum and checked on a few
    channels rendered at every chirp; where that check cannot meet the tolerance
    every chirp is rendered exactly (the reason is printed once). ``"off"``
    renders every chirp exactly.

    ``decimate_tolerance``: relative l2 error, and worst chirp row, of the
    interpolation against the undecimated render; default (omitted) 0.1 x the
    synthesis tolerance (``DECIMATION_EPS_SHARE`` of
    :mod:`raysim.synthesis.select`).
    """

    decimate: Literal["auto", "off"] = "auto"
    decimate_tolerance: float | None = Field(None, gt=0, le=0.1)
