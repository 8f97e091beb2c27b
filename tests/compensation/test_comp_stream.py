"""RealtimeStream: raw IF frames in, the direct engine's beams out; replay timing; refusals."""

from __future__ import annotations

import numpy as np
import pytest

from compensation import RealtimeProjector, RealtimeStream, rigid_body_projection
from compensation.strapdown import static_motion
from compensation.stream import FrameTiming, latency_summary, replay
from tests.compensation.test_comp_realtime import (
    ENGINE_CASES,
    LAM,
    RANGE_TOL,
    RT_TOL,
    _motion,
    _ti_positions,
)

K = 64                                 # samples per chirp
R_AXIS = 2.0 + np.arange(K) * 0.1      # range of each bin [m]
GATES = [5, 6, 7, 40]


def _if_frame(rng, n_chirp, *, real=False):
    """IF frame [chirp, 12, K]: tones at bins 6 and 40.3 with random phases, plus noise."""
    s = np.arange(K)
    tone = 3.0 * np.exp(2j * np.pi * 6 * s / K) + np.exp(2j * np.pi * 40.3 * s / K)
    x = tone[None, None] * np.exp(1j * rng.uniform(0, 6.3, (n_chirp, 12, 1))) + \
        0.1 * (rng.standard_normal((n_chirp, 12, K)) + 1j * rng.standard_normal((n_chirp, 12, K)))
    return (x.real if real else x).astype(np.float32 if real else np.complex64)


def _projector(engine="auto", gates=GATES):
    p, slot = _ti_positions()
    return RealtimeProjector(p, channel_slot=slot, wavelength=LAM, range_axis=R_AXIS,
                             azimuth=np.deg2rad([-20.0, 0.0, 15.0, 30.0]),
                             elevation=np.deg2rad([-5.0, 0.0, 10.0]), range_gates=gates,
                             threads=2, engine=engine), p, slot


@pytest.mark.parametrize("engine", ENGINE_CASES)
@pytest.mark.parametrize("real", [False, True])
def test_stream_equals_direct_engine_on_the_range_fft_of_each_frame(engine, real):
    """Frame after frame: stream(samples) = rigid_body_projection(range_compress(samples)).

    The chain's two steps are checked apart as well: the transform of the gated
    bins only against the whole range FFT at those bins (``RANGE_TOL``), and the
    beams against the direct engine on the whole FFT (``RT_TOL``, float32
    rounding); the beam buffer is reused, each frame's beams are its own.
    """
    from raysim.processing.maps import range_compress

    rng = np.random.default_rng(21)
    proj, p, slot = _projector(engine, gates=[5, 6, 7, 31] if real else GATES)
    stream = RealtimeStream(proj)
    n = 6
    frames = [(_if_frame(rng, n, real=real), _motion(rng, 3 * n)) for _ in range(3)]
    previous = None
    for (x, motion), beams in zip(frames, stream(frames), strict=True):
        rc = range_compress(x)
        gated = stream._gated
        assert np.abs(gated - rc[:, :, proj.gates]).max() < RANGE_TOL * np.abs(rc).max()
        ref = rigid_body_projection(rc, p, motion, channel_slot=slot, method="direct",
                                    wavelength=LAM, range_axis=R_AXIS, azimuth=proj.azimuth,
                                    elevation=proj.elevation, range_gates=proj.gates)
        assert beams.data.shape == ref.data.shape and beams.data.dtype == np.complex64
        assert np.abs(beams.data - ref.data).max() < RT_TOL * np.abs(ref.data).max()
        np.testing.assert_allclose(beams.chirp_time, ref.chirp_time)
        assert beams.warnings == ref.warnings
        if previous is not None:
            assert beams.data is previous          # one buffer, overwritten frame after frame
        previous = beams.data
    assert stream.frames == 3


@pytest.mark.parametrize("engine", ENGINE_CASES)
def test_callable_motion_overlapping_the_range_transform_gives_the_same_beams(engine):
    """A callable motion runs while the kernel's thread takes the range transform: the
    beams are those of the same motion given as a PlatformMotion, bit for bit; a callable
    that raises leaves the stream usable."""
    rng = np.random.default_rng(25)
    proj, _, _ = _projector(engine)
    x, m = _if_frame(rng, 6), _motion(rng, 18)
    direct = RealtimeStream(proj, copy=True).process(x, m).data
    stream = RealtimeStream(proj, copy=True)
    np.testing.assert_array_equal(stream.process(x, lambda: m).data, direct)

    def broken():
        raise RuntimeError("IMU record ends early")

    with pytest.raises(RuntimeError, match="IMU record ends early"):
        stream.process(x, broken)
    np.testing.assert_array_equal(stream.process(x, lambda: m).data, direct)


def test_static_tone_at_a_gate_gives_unit_beams_closed_form():
    """Static platform, one unit tone at bin 6 on every channel, no window: beam 1 at broadside.

    Closed form: the DFT of ``exp(2 pi j 6 s / K)`` at bin 6 over ``K`` is 1 (window
    none, divided by its sum); all channels in phase and a static platform at
    focus far away give a broadside beam of ``|1|`` (Fresnel term of the 6 mm
    array at 2.6 m below 1e-5 rad).
    """
    p, _ = _ti_positions()
    proj = RealtimeProjector(p[:4], wavelength=LAM, range_axis=R_AXIS, azimuth=[0.0],
                             elevation=[0.0], range_gates=[6])
    tone = np.exp(2j * np.pi * 6 * np.arange(K) / K)
    x = np.broadcast_to(tone, (8, 4, K)).astype(np.complex64)
    beams = RealtimeStream(proj, window=None, copy=True).process(
        x, lambda: static_motion(np.arange(8) * 5e-5))
    np.testing.assert_allclose(np.abs(beams.data), 1.0, atol=1e-5)


def test_copy_gives_each_frame_its_own_array_and_chirp_weights_apply():
    rng = np.random.default_rng(22)
    proj, _, _ = _projector()
    w = np.hanning(6)
    stream = RealtimeStream(proj, copy=True, chirp_weights=w)
    plain = RealtimeStream(proj)
    x1, x2 = _if_frame(rng, 6), _if_frame(rng, 6)
    m = _motion(rng, 18)
    a, b = stream.process(x1, m), stream.process(x2, m)
    assert a.data is not b.data
    ref = plain.process(x1, m).data * w.astype(np.float32)[:, None, None, None]
    assert np.abs(a.data - ref).max() < RT_TOL * np.abs(ref).max()


def test_replay_paces_frames_and_measures_latency_from_arrival():
    """A fake clock: frames 10 ms apart, processing 4 ms then 25 ms then 4 ms."""
    rng = np.random.default_rng(23)
    proj, _, _ = _projector()
    now = [100.0]
    cost = iter([0.004, 0.025, 0.004, 0.004])
    slept = []

    def clock():
        return now[0]

    def sleep(dt):
        slept.append(dt)
        now[0] += dt

    class Slow(RealtimeStream):
        def process(self, samples, motion):
            now[0] += next(cost)
            return super().process(samples, motion)

    x, m = _if_frame(rng, 6), _motion(rng, 18)
    cpu = iter(np.arange(8) * 0.003)                      # 3 ms of CPU per frame
    out = list(replay(Slow(proj), [(x, m)] * 4, frame_period=0.010, clock=clock, sleep=sleep,
                      cpu_clock=lambda: next(cpu)))
    timing = [t for _, t in out]
    assert all(isinstance(t, FrameTiming) for t in timing)
    # frame 0 at 100.000 done 100.004; frame 1 at 100.010 done 100.035; frame 2 arrived at
    # 100.020, starts 100.035, done 100.039 (latency 19 ms); frame 3 at 100.030 done 100.043
    np.testing.assert_allclose([t.latency for t in timing], [0.004, 0.025, 0.019, 0.013],
                               atol=1e-12)
    np.testing.assert_allclose([t.service for t in timing], [0.004, 0.025, 0.004, 0.004],
                               atol=1e-12)
    np.testing.assert_allclose([t.cpu for t in timing], [0.003] * 4, atol=1e-12)
    np.testing.assert_allclose(slept, [0.006])
    s = latency_summary([t.latency for t in timing], budget=0.010)
    assert s["frames"] == 4 and s["p50_s"] == pytest.approx(0.016)
    assert s["p99_s"] <= s["max_s"] == pytest.approx(0.025)
    assert s["over_budget"] == 0.75 and s["p95_within_budget"] is False


def test_bad_input_is_refused():
    rng = np.random.default_rng(24)
    proj, _, _ = _projector()
    stream = RealtimeStream(proj)
    m = _motion(rng, 18)
    with pytest.raises(ValueError, match="projector must be a compensation.RealtimeProjector"):
        RealtimeStream("projector")
    with pytest.raises(ValueError, match=r"samples must be an IF frame .* shape \(6, 12\)"):
        stream.process(np.zeros((6, 12), np.complex64), m)
    with pytest.raises(ValueError, match="samples must be an IF cube"):
        stream.process(np.zeros((6, 5, K), np.complex64), m)
    with pytest.raises(ValueError, match="motion must hold chirp"):
        stream.process(_if_frame(rng, 6), _motion(rng, 17))
    with pytest.raises(ValueError, match="each frame must be a pair"):
        list(stream([_if_frame(rng, 6)]))
    with pytest.raises(ValueError, match="frame_period must be a positive number.*-1"):
        list(replay(stream, [], frame_period=-1))
    with pytest.raises(ValueError, match="stream must be a compensation.RealtimeStream"):
        list(replay(proj, [], frame_period=0.01))
    with pytest.raises(ValueError, match="out must be a C-contiguous complex64 array"):
        proj.gated_range_transform(_if_frame(rng, 6), out=np.empty((6, 12, 3), np.complex64))
    with pytest.raises(ValueError, match="seconds must be finite per-frame times"):
        latency_summary([0.01, np.nan])


def test_bench_stream_json_has_the_percentiles_per_gate_count():
    """Schema of ``raysim bench``'s ``realtime`` key on a tiny run (no timing asserted)."""
    import json

    from raysim.bench.realtime import bench_stream

    got = json.loads(json.dumps(bench_stream(frames=3, gate_counts=(1, 2), threads=1,
                                             paper=False)))
    assert got["frames"] == 3 and got["frame_duration_s"] > 0
    assert "wall" in got["clock"] and got["included"] and got["load_average"]["after"]
    assert [c["gates"] for c in got["cases"]] == [1, 2]
    for case in got["cases"]:
        for key in ("latency", "service"):
            row = case[key]
            assert {"p50_s", "p95_s", "p99_s", "max_s", "frames", "budget_s", "over_budget",
                    "p95_within_budget"} <= set(row)
            assert row["frames"] == 3 and 0 < row["p50_s"] <= row["p95_s"] <= row["p99_s"]
        assert case["realtime_factor_p95"] > 0 and case["threads"] == 1
        assert set(case["stages"]) == {"gated_range_transform", "strapdown", "projection",
                                       "doppler_and_power"}
        assert case["cpu"]["frames"] == 3 and case["cpu"]["p50_s"] > 0
        # the baseline stream (engine "avx2") where it runs another copy than the default
        if case["engine"] in ("avx512",):
            assert case["baseline"]["engine"] == "avx2"
            assert case["baseline"]["service"]["frames"] == 3
            assert case["speedup_p95"] > 0 and case["cpu_ratio_p50"] > 0
        else:
            assert "baseline" not in case and got["baseline"].startswith("skipped")
    with pytest.raises(ValueError, match="frames must be a positive count, got 0"):
        bench_stream(frames=0)
    with pytest.raises(ValueError, match="baseline must be one of"):
        bench_stream(frames=1, baseline="fast")

