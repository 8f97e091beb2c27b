"""The scene report's simulation with slow-time decimation on (default) and off."""

from __future__ import annotations

import warnings

import pytest

from raysim.synthesis.decimate import check_errors
from raysim.synthesis.select import DECIMATION_EPS_SHARE

pytestmark = pytest.mark.sionna

#: Synthesis tolerance of the report frames compared here (QUICK's nufft_eps).
EPS = 1e-5


def test_report_frames_decimated_within_tolerance(warm_kernels):
    """QUICK flat_reflectors (hover jitter, clutter field): both frames of the twin with
    decimation on are within the stated tolerance (DECIMATION_EPS_SHARE * eps, relative
    l2 and worst chirp row) of the frames rendered without it at the same row tolerance.
    The stationary frame is decimated; where the hover's sideband bound refuses, that
    frame is rendered exactly."""
    from raysim.studies.scene_report import QUICK
    from raysim.studies.scene_report.simulate import report_trajectory, simulate_scene
    from raysim.synthesis import select

    reports: list = []
    real = select.render_checked

    def spy(*a, **k):
        done = real(*a, **k)
        reports.append(list(k["report"]))
        return done

    frames = {}
    for mode, eps in (("off", (1 - DECIMATION_EPS_SHARE) * EPS), ("auto", EPS)):
        st = QUICK.with_values(decimate=mode, nufft_eps=eps, samples_per_src=5000)
        with pytest.MonkeyPatch.context() as mp, warnings.catch_warnings():
            warnings.simplefilter("ignore", select.DecimationRefused)
            mp.setattr(select, "render_checked", spy)
            frames[mode] = simulate_scene(st, report_trajectory(st))
    assert len(reports) == 2                                    # "off" never plans
    assert max(g["factor"] for g in reports[0]) > 1             # stationary: decimated
    for name in ("stationary", "hover"):
        l2, row = check_errors(frames["auto"][name].data, frames["off"][name].data)
        assert l2 <= DECIMATION_EPS_SHARE * EPS and row <= DECIMATION_EPS_SHARE * EPS, \
            (name, l2, row, reports)
