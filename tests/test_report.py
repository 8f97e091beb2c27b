"""HTML reports: self-contained, complete, and rendered by headless Chromium when present."""

from __future__ import annotations

import base64
import html
import os
import re
import shutil
import subprocess

import numpy as np
import pytest
from scenario_texts import small_scenario

from raysim.cli import main
from raysim.pipeline.run import render
from raysim.report.html import collect_from_scenario, software_versions, write_report
from raysim.scenario import scenario_from_case
from raysim.vocabulary import MAP_TITLES

SMALL = {"radar.num_chirps": 32, "array.nx": 4, "array.ny": 4,
         "radar.chirp_duration_s": 12.8e-6}
#: A screenshot counts as not blank above this share of non-background pixels.
MIN_INK_FRACTION = 0.03


@pytest.fixture(scope="module")
def report_html(tmp_path_factory):
    s = scenario_from_case("rotation_y").with_values(SMALL)
    path = tmp_path_factory.mktemp("report") / "r.html"
    write_report(collect_from_scenario(s, source="test"), path)
    return path


def test_report_is_self_contained_and_complete(report_html):
    text = report_html.read_text()
    assert text.startswith("<!DOCTYPE html>") and text.rstrip().endswith("</html>")
    # no external resources: every image is an embedded PNG
    assert not re.search(r"""(src|href)=['"](?!data:)""", text)
    pngs = re.findall(r"data:image/png;base64,([A-Za-z0-9+/=]+)", text)
    assert len(pngs) == 5
    for p in pngs:
        assert base64.b64decode(p)[:8] == b"\x89PNG\r\n\x1a\n"
    for needle in (*(f"{t} maps" for t in MAP_TITLES.values()), "Doppler cuts",
                   "pseudo_velocity_mps", "entropy_ae_nats", "Values reported in the paper",
                   "Run parameters", "Software versions", "sionna-rt", "mitsuba", "drjit",
                   "numpy", "none", "Warnings", "Motion: pitch 10 deg @ 20 Hz"):
        assert needle in text, needle


def test_versions_listed():
    v = software_versions()
    assert v["numpy"] == np.__version__
    assert {"sionna-rt", "mitsuba", "drjit", "python"} <= set(v)


def test_report_cli_from_store_and_errors(tmp_path, capsys):
    s = scenario_from_case("stationary").with_values(SMALL)
    render(s, tmp_path / "s.zarr")
    assert main(["report", str(tmp_path / "s.zarr"), "--out", str(tmp_path / "s.html")]) == 0
    assert f"{MAP_TITLES['rd']} maps" in (tmp_path / "s.html").read_text()
    capsys.readouterr()
    assert main(["report", str(tmp_path / "nothing"), "--out", str(tmp_path / "x.html")]) == 2
    assert "expected a Zarr store" in capsys.readouterr().err
    assert main(["report", "--case", "stationary", str(tmp_path / "s.zarr")]) == 2


TILTED = small_scenario("tilted", az_deg=50.0, pitch_deg=30.0, pitch_hz=5.0,
                        pitch_phase_deg=90.0)


def test_report_lists_the_guard_warnings(tmp_path, capsys):
    """Pitch 30 deg (at 5 Hz: within a gyro's full scale), target at azimuth 50 deg: the paper
    chain's small-angle warnings (compensation.guards) appear in the report and on stderr."""
    pytest.importorskip("compensation")
    (tmp_path / "t.toml").write_text(TILTED)
    assert main(["report", "--scenario", str(tmp_path / "t.toml"), "--chains",
                 "none,paper:published", "--out", str(tmp_path / "t.html")]) == 0
    err = capsys.readouterr().err
    text = (tmp_path / "t.html").read_text()
    section = text[text.index("<h2 id='warnings'>"):text.index("<h2>Metrics</h2>")]
    items = re.findall(r"<li class='note'><b>([^<]+)</b>: ([^<]+)</li>", section)
    assert items and {c for c, _ in items} == {"paper:published"}
    assert all(w.startswith("small-angle: ") for _, w in items)
    for chain, w in items:
        assert f"warning: {chain}: {html.unescape(w)}" in err
    assert "<th>paper:published</th>" in text and "Motion: pitch 30 deg @ 5 Hz" in text
    assert main(["report", "--case", "stationary", "--chains", "uncompensated"]) == 2
    assert "--chains: got 'uncompensated'" in capsys.readouterr().err


def _chromium() -> str | None:
    return os.environ.get("RAYSIM_CHROMIUM") or next(
        (p for p in (shutil.which(n) for n in ("chromium", "chromium-browser", "google-chrome"))
         if p), None)


def test_report_renders_in_chromium(report_html, tmp_path):
    chrome = _chromium()
    if chrome is None:
        pytest.skip("chromium is not installed (scripts/check_report_chromium.sh installs it)")
    shot = tmp_path / "shot.png"
    subprocess.run([chrome, "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
                    "--window-size=1200,1800", f"--screenshot={shot}",
                    report_html.resolve().as_uri()], capture_output=True, timeout=120,
                   check=False)
    assert shot.is_file(), "chromium wrote no screenshot"
    import matplotlib.image as mpimg

    img = mpimg.imread(shot)[..., :3]
    assert img.shape[:2] == (1800, 1200)
    ink = np.mean(np.any(np.abs(img - img[0, 0]) > 0.05, axis=-1))
    assert ink > MIN_INK_FRACTION, f"screenshot looks blank ({ink:.3%} non-background pixels)"
    # the figures are drawn: some strongly coloured (viridis) pixels exist
    saturation = img.max(axis=-1) - img.min(axis=-1)
    assert np.mean(saturation > 0.3) > 0.01


# ------------------------------------------------------------ streaming and zoom
def _peak_report_memory(store) -> tuple[int, int]:
    """(peak bytes traced while collecting a report from the lazy store, bytes per frame)."""
    import tracemalloc

    from raysim.io import storage
    from raysim.report.html import collect_from_dataset

    ds = storage.open_store(store, load=False)
    frame_bytes = int(ds["if_data"].isel(frame=0).nbytes)
    tracemalloc.start()
    try:
        data = collect_from_dataset(ds, chains=["none", "paper"], source=str(store))
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert data.num_frames == ds.sizes["frame"] and set(data.result["chains"]) == {"none",
                                                                                   "paper"}
    return peak, frame_bytes


def test_report_streams_the_frames_of_a_store(tmp_path):
    """The peak memory of a report does not grow with the store: 9 frames cost at most
    ~3 frames more than 1 frame (the fixed workspace of maps and IMU is the same)."""
    from raysim.pipeline.run import render
    from raysim.scenario import scenario_from_case

    small = {"radar.num_chirps": 64, "array.nx": 4, "array.ny": 4,
             "radar.chirp_duration_s": 12.8e-6, "imu.preset": "tactical",
             "imu.rate_hz": 20000.0}
    peaks = {}
    for n in (1, 9):
        sc = scenario_from_case("rotation_y").with_values({**small, "frames": n})
        render(sc, tmp_path / f"s{n}.zarr")
        peaks[n], frame_bytes = _peak_report_memory(tmp_path / f"s{n}.zarr")
    assert peaks[9] - peaks[1] < 3 * frame_bytes, (peaks, frame_bytes)
    assert peaks[9] < peaks[1] + 9 * frame_bytes        # far from loading the 9 frames


def test_maps_zoom_on_the_target():
    """Today's maps showed the target as a one-pixel line in 0-35 m x +-16 m/s: the window
    now holds the strong cells and the truth, a few metres and m/s wide."""
    from raysim.processing.maps import Map
    from raysim.report.html import zoom_limits

    r = np.arange(256) * 0.137
    v = np.linspace(-16, 16, 64, endpoint=False)
    power = np.full((256, 64), 1e-6)
    power[60:200, 30:35] = 0.05                          # a clutter ridge near 0 m/s, -13 dB
    power[109:111, 31:34] = 1.0                          # target at 15 m, ~0 m/s
    (xlo, xhi), (ylo, yhi) = zoom_limits(Map(power, ("range", "doppler"),
                                             {"range": r, "doppler": v}), (0.0, 15.0))
    assert xlo < -0.5 and xhi > 0.5 and xhi - xlo <= 8.0   # m/s, of a 32 m/s wide axis
    assert ylo < 60 * 0.137 and yhi > 199 * 0.137 and yhi - ylo < 30.0
    (xlo, xhi), (ylo, yhi) = zoom_limits(Map(power, ("range", "doppler"),
                                             {"range": r, "doppler": v}), (0.0, 15.0),
                                         max_range=20.0)
    assert yhi - ylo < 25.0 and ylo <= 15.0 <= yhi
