"""Streaming renders equal one-shot renders, stay within their memory bound and show progress."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from raysim.echoes.oracle import PointTarget, point_target_source, simulate_point_targets
from raysim.platform.motion import sinusoid
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig
from raysim.synthesis.nufft import PathDelays, synthesize_nufft
from raysim.synthesis.streaming import (
    FrameWriter,
    NpyWriter,
    peak_bytes,
    render_frames,
    render_stream,
)

#: complex64 tone synthesis against the oracle (identical code path).
ORACLE_RTOL = 1e-6


@pytest.fixture(scope="module")
def radar():
    return RadarConfig(num_chirps=12, num_frames=3)


@pytest.fixture(scope="module")
def arr(radar):
    return upa(4, 3, wavelength=radar.wavelength)


@pytest.fixture(scope="module")
def targets():
    return [PointTarget.at(15.0, 0.2, 0.1, velocity=(0.3, 0.0, 0.0)),
            PointTarget.at(40.0, -0.4, 0.0)]


def test_frames_equal_oracle(radar, arr, targets):
    traj = sinusoid("y", 1e-3, 6.0)
    got = {}
    stats = render_frames(point_target_source(radar, arr, targets, traj), radar,
                          lambda f, cube: got.__setitem__(f, cube.copy()), frames=3,
                          chirp_block=5, method="tones", eps=1e-5, progress=False)
    assert stats.frames == 3 and stats.chirp_blocks == 9 and stats.method == "tones"
    for f in range(3):
        ref = simulate_point_targets(radar, arr, targets, traj, frame=f).data
        np.testing.assert_allclose(got[f], ref, rtol=0, atol=ORACLE_RTOL * np.abs(ref).max())


def test_npy_store_and_blocks(radar, arr, tmp_path):
    rng = np.random.default_rng(5)
    n = 200
    first = rng.uniform(-20, 20, (n, 3)) + [0, 0, 30]

    def source(frame):
        return PathDelays.for_array(first, first, np.zeros(n), np.ones(n), radar, arr,
                                    frame=frame)

    store = NpyWriter(tmp_path / "if.npy", 2, radar.num_chirps, arr.num_channels,
                      radar.num_samples, first_frame=1)
    calls = []

    def writer(frame, n0, block):
        calls.append((frame, n0, block.shape[0]))
        store(frame, n0, block)

    stats = render_stream(source, radar, writer, frames=[1, 2], chirp_block=5, method="nufft",
                          eps=1e-6, progress=False)
    assert calls == [(1, 0, 5), (1, 5, 5), (1, 10, 2), (2, 0, 5), (2, 5, 5), (2, 10, 2)]
    data = np.load(tmp_path / "if.npy")
    for i, f in enumerate((1, 2)):
        ref = synthesize_nufft(source(f), None, radar, eps=1e-6)
        np.testing.assert_allclose(data[i], ref, atol=1e-6 * np.abs(ref).max())
    assert stats.peak_bytes_estimate >= peak_bytes(n, arr.num_channels, radar.num_samples,
                                                   chirp_block=5)


def test_frame_writer_assembles(radar):
    seen = []
    fw = FrameWriter(lambda f, c: seen.append((f, c.copy())), num_chirps=4)
    fw(0, 0, np.ones((3, 2, 5), np.complex64))
    fw(0, 3, 2 * np.ones((1, 2, 5), np.complex64))
    assert len(seen) == 1 and seen[0][0] == 0
    assert np.all(seen[0][1][:3] == 1) and np.all(seen[0][1][3] == 2)
    with pytest.raises(ValueError, match="num_chirps"):
        fw(1, 3, np.ones((2, 2, 5), np.complex64))


@pytest.mark.parametrize(("kwargs", "word"), [
    (dict(chirp_block=0), "chirp_block"),
    (dict(frames=0), "frames"),
    (dict(method="fast"), "method"),
    (dict(eps=-1.0), "eps"),
])
def test_bad_arguments(radar, arr, targets, kwargs, word):
    with pytest.raises(ValueError, match=word):
        render_stream(point_target_source(radar, arr, targets), radar, lambda *a: None,
                      progress=False, **kwargs)


def test_wrong_source_shape(radar, arr, targets):
    with pytest.raises(ValueError, match="chirps"):
        render_stream(point_target_source(radar.with_(num_chirps=6), arr, targets), radar,
                      lambda *a: None, progress=False)
    with pytest.raises(ValueError, match="source"):
        render_stream(lambda f: 3, radar, lambda *a: None, progress=False)


def test_progress_and_peak_memory_in_subprocess():
    """A 2,000-path, 16-chirp x 64-channel render in a fresh process: tqdm on stderr, and
    the growth of the peak resident set stays below the stated bound (writer discards
    blocks)."""
    code = textwrap.dedent("""
        import numpy as np
        from raysim.radar.arrays import upa
        from raysim.bench.suite import peak_rss
        from raysim.radar.config import RadarConfig
        from raysim.synthesis.nufft import PathDelays
        from raysim.synthesis.streaming import render_stream
        cfg = RadarConfig(num_chirps=16)
        arr = upa(8, 8, wavelength=cfg.wavelength)
        rng = np.random.default_rng(1)
        v = rng.uniform(-10, 10, (2000, 3)) + [0, 0, 30]
        pd = PathDelays.for_array(v, v, np.zeros(2000), np.ones(2000), cfg, arr)
        before, _ = peak_rss(reset=True)
        stats = render_stream(lambda f: pd, cfg, lambda f, n0, b: None, chirp_block=4,
                              method="nufft", eps=1e-5, progress=True)
        _, after = peak_rss()
        print(after - before, stats.peak_bytes_estimate)
    """)
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=True)
    grown, bound = (int(x) for x in res.stdout.split())
    assert "4/4" in res.stderr
    # thread stacks and FINUFFT/FFTW plans come on top of the array estimate
    assert grown < bound + 16 * 2**20


def test_bench_cli_validation_and_atomic_json(tmp_path, capsys):
    from raysim.bench.suite import atomic_write_json
    from raysim.cli import main

    assert main(["bench", "--chart-only"]) == 2
    assert "--chart-only needs --chart" in capsys.readouterr().err
    out = tmp_path / "sub" / "r.json"
    atomic_write_json(out, {"a": np.float32(1.5), "b": np.arange(3)})
    assert out.read_text().startswith("{") and [p for p in tmp_path.joinpath("sub").iterdir()
                                                  if p.name != ".raysim-outputs"] == [out]
