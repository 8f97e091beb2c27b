"""Slow-time decimation where the pipeline synthesises, and its banded interpolation.

The render's frozen paths (:func:`raysim.echoes.rt.reproject.synthesize_paths`, the
way ``render_scene``, the scene report and the scene calibration synthesise) are
decimated by default (``decimate="auto"``). The decimated cube is held to the stated
tolerance against the undecimated cube whose rows are rendered at the same row
tolerance (relative l2 and worst chirp row), ``"off"`` to the undecimated call of
before bit for bit, and a refusal renders every chirp exactly and says why once.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from raysim.platform.motion import hover_jitter
from raysim.radar.arrays import upa
from raysim.radar.config import SPEED_OF_LIGHT, RadarConfig
from raysim.synthesis import decimate as dm
from raysim.synthesis import select, slowtime
from raysim.synthesis.select import DECIMATION_EPS_SHARE, DecimationRefused

EPS = 1e-5
LEVER = np.array([0.05, 0.0, 0.1])
#: Banded against whole-matrix interpolation: the same products summed in another order,
#: float32 (about taps x 2^-24 of the largest term).
BANDED_TOL = 2e-6


def _pathset(n: int, seed: int = 4):
    """Hand-made static scatterers below the radar (no Sionna needed)."""
    from raysim.echoes.rt.trace import PathSet

    rng = np.random.default_rng(seed)
    first = rng.uniform([-8, -8, 6], [8, 8, 20], (n, 3))
    length = 2 * np.linalg.norm(first, axis=1)
    amp = rng.normal(size=n) + 1j * rng.normal(size=n)
    return PathSet(first, first.copy(), length * 0, amp, np.zeros((n, 3)), np.zeros(n),
                   np.full((n, 1), 16, np.uint32), np.full(n, 16, np.uint32),
                   np.zeros((n, 2, 2), complex), length / SPEED_OF_LIGHT, np.zeros(3),
                   np.zeros(3), 0.0, {})


@pytest.fixture(scope="module")
def frame():
    cfg = RadarConfig(num_chirps=128)
    return cfg, upa(2, 2, wavelength=cfg.wavelength), hover_jitter(7), _pathset(300)


def _render(frame, monkeypatch=None, reports=None, **kw):
    from raysim.echoes.rt import reproject as rp

    cfg, arr, traj, paths = frame
    if monkeypatch is not None:
        real = rp.synthesize
        monkeypatch.setattr(rp, "synthesize", lambda *a, **k: real(
            *a, **k, decimation_report=reports))
    cube, _ = rp.synthesize_paths(paths, cfg, arr, traj, LEVER, compact=True, **kw)
    if monkeypatch is not None:
        monkeypatch.undo()
    return cube


def test_render_decimated_within_tolerance_of_undecimated(frame, monkeypatch):
    """Hover jitter, per-chirp element gains: "auto" decimates and stays within the
    stated tolerance (default DECIMATION_EPS_SHARE * eps, and a given one) of the
    undecimated cube rendered at the same row tolerance."""
    off = _render(frame, eps=(1 - DECIMATION_EPS_SHARE) * EPS, decimate="off")
    for tol in (None, 1e-5):
        reports: list = []
        auto = _render(frame, monkeypatch, reports, eps=EPS, decimate_tolerance=tol)
        stated = DECIMATION_EPS_SHARE * EPS if tol is None else tol
        assert reports and max(g["factor"] for g in reports) > 1, reports
        assert sum(g["exact_chirps"] for g in reports) < 128
        l2, row = dm.check_errors(auto, off)
        assert l2 <= stated and row <= stated, (l2, row, reports)
    # and within the synthesis tolerance of the undecimated render at eps
    l2, row = dm.check_errors(_render(frame, eps=EPS), _render(frame, eps=EPS, decimate="off"))
    assert l2 <= EPS and row <= EPS


def test_off_is_the_undecimated_call(frame):
    """decimate="off" is synthesize(PathDelays.from_pathset(...)) without decimation,
    bit for bit (the call of the compact way before decimation was on)."""
    from raysim.synthesis.paths import PathDelays

    cfg, arr, traj, paths = frame
    src = PathDelays.from_pathset(paths, cfg, arr, traj, lever_arm=LEVER, gain="per_chirp")
    before = select.synthesize(src, None, cfg, method="auto", eps=EPS,
                               out=np.zeros((128, 4, cfg.num_samples), np.complex64),
                               chirps=range(128))
    assert np.array_equal(_render(frame, eps=EPS, decimate="off"), before)
    assert np.array_equal(_render(frame, eps=EPS, decimate=1), before)


def test_refusal_renders_exactly_and_says_why_once(frame, monkeypatch):
    cfg, arr, traj, paths = frame
    short = (cfg.with_(num_chirps=16), arr, traj, paths)
    monkeypatch.setattr(select, "_SAID", set())
    with pytest.warns(DecimationRefused, match="too few chirps"):
        auto = _render(short, eps=EPS)
    assert np.array_equal(auto, _render(short, eps=EPS, decimate="off"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", DecimationRefused)
        _render(short, eps=EPS)                                 # said once


def test_command_line_states_a_refusal_in_one_line(frame, monkeypatch, capsys):
    """A command whose render refuses decimation says so on one line of stderr (the
    command, what was refused and why, that every chirp was rendered exactly), not as a
    Python warning with its file, line and source; other warnings keep their form."""
    cfg, arr, traj, paths = frame
    short = (cfg.with_(num_chirps=16), arr, traj, paths)
    monkeypatch.setattr(select, "_SAID", set())

    def job(_args):
        _render(short, eps=EPS)
        warnings.warn("something else", UserWarning, stacklevel=1)
        return 0

    err, shown = _run_command(monkeypatch, capsys, "render", job)
    assert err == ["raysim render: note: slow-time decimation refused, every chirp rendered "
                   "exactly: too few chirps (16 < 64)"]
    assert shown == ["something else"]                                # the usual way


def _run_command(monkeypatch, capsys, name: str, job) -> tuple[list, list]:
    """``raysim NAME`` running ``job``: (stderr lines, messages of the warnings shown the
    usual way)."""
    import argparse

    import raysim.cli as cli

    def parser():
        p = argparse.ArgumentParser(prog="raysim")
        p.add_subparsers(dest="command").add_parser(name).set_defaults(func=job)
        return p

    monkeypatch.setattr(cli, "build_parser", parser)
    with warnings.catch_warnings(record=True) as shown:
        warnings.simplefilter("always")
        assert cli.main([name]) == 0
    return capsys.readouterr().err.splitlines(), [str(w.message) for w in shown]


def test_bad_decimation_input(frame):
    cfg, arr, traj, paths = frame
    for bad in ({"decimate": "on"}, {"decimate": 0}, {"decimate_tolerance": 0.5},
                {"decimate_tolerance": -1e-6}):
        with pytest.raises(ValueError, match="decimate"):
            _render(frame, eps=EPS, **bad)
    with pytest.raises(ValueError, match="decimate_tolerance"):
        select.synthesize(np.zeros((1, 2, 1)), 1.0, cfg.with_(num_chirps=2),
                          decimate_tolerance=True)


@pytest.mark.parametrize("band,factor", [(0.01, 16), (0.05, 6), (0.15, 2)])
def test_banded_interpolation_equals_the_whole_matrix(band, factor):
    """scatter_add and interpolate by runs of chirps equal the whole-matrix product."""
    plan = dm._plan_band(128, band, 1e-6, factor)
    assert plan.factor == factor
    rng = np.random.default_rng(factor)
    exact = (rng.normal(size=(plan.exact.size, 3, 50))
             + 1j * rng.normal(size=(plan.exact.size, 3, 50))).astype(np.complex64)
    dense = np.zeros((128, 3, 50), np.complex64)
    slowtime.scatter_add_dense(dense, exact, plan)
    banded = np.zeros_like(dense)
    slowtime.scatter_add(banded, exact, plan, col_block=64)     # several column blocks
    assert np.array_equal(banded[plan.exact], dense[plan.exact])
    l2, row = dm.check_errors(banded, dense)
    assert l2 <= BANDED_TOL and row <= BANDED_TOL
    rows = np.zeros_like(dense)
    rows[plan.exact] = exact
    slowtime.interpolate(rows, plan)
    l2, row = dm.check_errors(rows, dense)
    assert l2 <= BANDED_TOL and row <= BANDED_TOL
    # every interpolated chirp is in exactly one block, each block on fewer exact rows
    # than the whole matrix once the frame is long against the taps
    parts = slowtime.blocks(plan, rows=8)
    covered = np.concatenate([np.arange(128)[c] for seg, *_ in parts for c, _ in seg])
    assert np.array_equal(covered, plan.missing)
    assert sum(w.size for *_, w in parts) < plan.weights.size


def test_amplitude_band_of_a_tone():
    """A per-chirp amplitude exp(j 2 pi f n) has the instantaneous band f:
    (2 sin(pi f) + 4 sin(pi f)^2) / (2 pi), between f sinc(f) and f (1 + 2 pi f)."""
    n = np.arange(128)
    for f in (0.003, 0.02, 0.1):
        got = dm.amplitude_band(np.exp(2j * np.pi * f * n)[None, :])[0]
        s = np.sin(np.pi * f)
        assert got == pytest.approx((2 * s + 4 * s * s) / (2 * np.pi), rel=1e-9)
        assert f * np.sinc(f) <= got <= f * (1 + 2 * np.pi * f)
    assert dm.amplitude_band(np.ones((2, 128)), 1e-6).tolist() == [0.0, 0.0]


def test_scenario_and_command_line_settings(tmp_path):
    """[synthesis] decimate / decimate_tolerance: validated in scenarios, read by the
    report settings, refused with exit status 2 by the command line when out of range."""
    from raysim.cli import main
    from raysim.pipeline.sources import decimation
    from raysim.scenario import validate_scenario
    from raysim.studies.scene_report import QUICK

    base = {"scene": {"kind": "points", "targets": [{"range_m": 10.0}]}}
    sc = validate_scenario(base)
    assert decimation(sc) == {"decimate": "auto", "decimate_tolerance": None}
    sc = validate_scenario({**base, "synthesis": {"decimate": "off",
                                                  "decimate_tolerance": 1e-6}})
    assert decimation(sc) == {"decimate": "off", "decimate_tolerance": 1e-6}
    for bad, key in (({"decimate": "on"}, "synthesis.decimate"),
                     ({"decimate_tolerance": 0.5}, "synthesis.decimate_tolerance")):
        with pytest.raises(ValueError, match=key):
            validate_scenario({**base, "synthesis": bad})
    st = QUICK.with_values(decimate="off", decimate_tolerance=2e-6)
    assert (st.decimate, st.decimate_tolerance) == ("off", 2e-6)
    path = tmp_path / "s.toml"
    path.write_text('[[scene.targets]]\nrange_m = 10.0\n')
    assert main(["render", str(path), "--out", str(tmp_path / "o.zarr"),
                 "--decimate-tolerance", "0.5"]) == 2
    assert not (tmp_path / "o.zarr").exists()


def test_check_is_not_fooled_by_float32_grid_rounding():
    """2e4 static paths on the kernel's float32 grid: each exact row carries rounding of
    about 1e-7 sqrt(1 + paths w / nf) ~ 1e-6 (kernel_error's grid term) that differs from
    row to row and does not interpolate. The check renders its channels on a float64
    grid, so it measures the interpolation alone: decimated, and within the tolerance of
    the float64-grid render."""
    from raysim.bench.workloads import hover_paths
    from raysim.radar.config import PAPER_RADAR
    from raysim.synthesis import kernel

    if not kernel.available():
        pytest.skip("fused kernel not built")
    cfg = PAPER_RADAR.with_(num_chirps=128)
    arr = upa(2, 1, wavelength=cfg.wavelength)
    pd = hover_paths(20_000, cfg, arr, hover_jitter(7), LEVER, seed=3)
    pd = pd.select(~np.any(pd.velocity != 0, axis=1))
    rows_eps = (1 - DECIMATION_EPS_SHARE) * EPS
    err, design = kernel.kernel_error(pd.num_paths, rows_eps, cfg.num_samples)
    assert not design.double_grid                       # the float32 grid is used
    report: list = []
    got = select.synthesize(pd, None, cfg, method="kernel", eps=EPS, decimate="auto",
                            decimation_report=report)
    # the a-priori factor stands (a float32-grid check halved it to 2 here)
    assert report[0]["factor"] > 2 and "halved" not in report[0]["reason"], report
    exact = np.zeros_like(got)
    select._render_chirps(pd, cfg, "kernel", rows_eps, np.arange(128), exact, None,
                          double_grid=True)
    l2, row = dm.check_errors(got, exact)
    assert l2 <= DECIMATION_EPS_SHARE * EPS and row <= DECIMATION_EPS_SHARE * EPS


def test_command_line_states_its_own_warnings_in_one_line(monkeypatch, capsys):
    """Warnings of raysim and compensation (their classes, or a plain one raised in their
    code) reach the user as one line each, ``raysim COMMAND: warning: TEXT``: no file,
    line or source of the call; another library's warning keeps its form."""
    from compensation.guards import CompensationWarning
    from raysim.radar import pattern

    def job(_args):
        warnings.warn("clock: a test\n  of two lines", CompensationWarning, stacklevel=1)
        warnings.warn_explicit("plain, from raysim", UserWarning, pattern.__file__, 1)
        warnings.warn("from elsewhere", UserWarning, stacklevel=1)
        return 0

    err, shown = _run_command(monkeypatch, capsys, "flight", job)
    assert err == ["raysim flight: warning: clock: a test of two lines",
                   "raysim flight: warning: plain, from raysim"]
    assert shown == ["from elsewhere"]
