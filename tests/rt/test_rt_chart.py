"""Ray-tracing knobs of the speed-versus-accuracy chart (reduced frame, < 60 s)."""

from __future__ import annotations

import pytest

pytestmark = pytest.mark.sionna


def test_rt_knobs_measured_and_drawn(warm_kernels, monkeypatch, tmp_path):
    from raysim.bench import speed_chart as sa

    d = sa.rt_defaults()
    assert d == {"samples_per_src": 100_000, "max_depth": 3, "retrace_every": None}
    # small frame and sample counts; the default sample count is added by measure_rt_knobs
    monkeypatch.setattr(sa, "RT_CHIRPS", {True: 8, False: 8})
    monkeypatch.setattr(sa, "RT_ARRAY", 2)
    monkeypatch.setattr(sa, "RT_SAMPLES", {True: (1_000,), False: (1_000,)})
    monkeypatch.setattr(sa, "RT_REFERENCE_SAMPLES", 100_000)
    monkeypatch.setattr(sa, "RT_DEPTHS", (1, 2))
    monkeypatch.setattr(sa, "RT_RETRACE", {True: (None, 4), False: (None, 4)})
    knobs = sa.measure_rt_knobs(quick=True, log=lambda m: None, threads=2)
    assert [k["knob"] for k in knobs] == ["rt_samples", "rt_depth", "rt_retrace"]
    for k in knobs:
        assert sum(s["default"] for s in k["settings"]) == 1, k["knob"]
        ref = [s for s in k["settings"] if s.get("reference")]
        assert len(ref) == 1 and ref[0]["rel_error"] == 0.0, k["knob"]
        assert all(s["s_per_frame"] > 0 and s["paths"] > 0 for s in k["settings"])
        assert isinstance(k["default_on_front"], bool)
    samples = knobs[0]["settings"]
    assert [s["setting"] for s in samples] == ["1e3", "1e5"]
    assert samples[0]["rel_error"] > 0 and samples[0]["paths"] < samples[1]["paths"]
    # a re-trace every 4 chirps makes two traces and re-samples the diffuse clutter
    retrace = {s["setting"]: s for s in knobs[2]["settings"]}
    assert retrace["every 4"]["paths"] > retrace["once"]["paths"]
    assert retrace["every 4"]["rel_error"] > 0
    measured = {"quick": True, "knobs": knobs,
                "not_measured": {"example": "a skipped knob is noted under the panels"}}
    png = tmp_path / "rt_chart.png"
    sa.draw_chart(measured, png)
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_tube_density_knob(rt_backend):
    """SBR tube density as a chart knob: tubes grow with density, one default, RCS in 1 dB."""
    import raysim.bench.speed_chart as sa
    from raysim.echoes.po.paths import TUBES_PER_WAVELENGTH

    knob = sa.measure_tube_density(quick=True)
    assert knob["knob"] == "tube_density"
    tubes = [s["tubes"] for s in knob["settings"]]
    assert tubes == sorted(tubes) and tubes[0] < tubes[-1]
    (default,) = [s for s in knob["settings"] if s["default"]]
    assert default["setting"] == f"{TUBES_PER_WAVELENGTH:g}/lambda"
    # 1 dB on the closed form (the engine's canonical-target tolerance), as a power ratio
    assert all(s["rel_error"] < 10 ** 0.1 - 1 for s in knob["settings"])
