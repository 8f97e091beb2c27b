"""Slow-time decimation of arrays of delays (point targets) and of ``raysim flight``.

The band is read from the delays (``raysim.synthesis.dense_decimation``); the
a-posteriori check holds the interpolation to its tolerance. References: the
oracle's own tone sum (``synthesize_if``) on every chirp, and the complex128
direct sum.
"""

from __future__ import annotations

import numpy as np
import pytest

from raysim.echoes.oracle import PointTarget, point_target_delays
from raysim.platform.motion import HoverJitterSpec, hover_jitter, sinusoid
from raysim.radar.arrays import upa
from raysim.radar.config import RadarConfig
from raysim.synthesis import select
from raysim.synthesis.dense_decimation import dense_doppler
from raysim.synthesis.select import synthesize, tones_error
from raysim.synthesis.tones import synthesize_if

#: Interpolation tolerance asked for (relative l2 and worst chirp row).
TOL = 1e-6
#: Gain of the interpolation weights on the exact rows' own rounding (decimate.MAX_GAIN).
MAX_GAIN = 1.5


def _rel(got, ref):
    rows = np.linalg.norm((got - ref).reshape(len(ref), -1), axis=1) / \
        np.linalg.norm(ref.reshape(len(ref), -1), axis=1)
    return float(np.linalg.norm(got - ref) / np.linalg.norm(ref)), float(rows.max())


def _targets(n, seed=1):
    rng = np.random.default_rng(seed)
    return [PointTarget.at(r, az, el) for r, az, el in
            zip(rng.uniform(3, 20, n), rng.uniform(-0.5, 0.5, n), rng.uniform(-0.3, 0.3, n),
                strict=True)]


@pytest.mark.parametrize("trajectory", [hover_jitter(7), sinusoid("z", 1e-4, 200.0)],
                         ids=["hover_jitter", "z_0.1mm_200Hz"])
def test_point_targets_decimated_within_tolerance(trajectory):
    """Every ``auto`` cube of point targets is within the tolerance of the undecimated tone
    sum, plus the rows' own complex64 rounding carried by the weights, or refused."""
    cfg = RadarConfig(num_chirps=128)
    arr = upa(2, 2, wavelength=cfg.wavelength)
    n = 40
    tau, amp = point_target_delays(cfg, arr, trajectory, _targets(n))
    report = []
    got = synthesize(tau, amp, cfg, method="tones", eps=10 * TOL, decimate="auto",
                     decimate_tolerance=TOL, decimation_report=report)
    ref = synthesize_if(tau, amp, cfg)
    assert report and all(g["factor"] > 1 for g in report), report      # decimated
    l2, row = _rel(got, ref)
    bound = TOL + MAX_GAIN * tones_error(n)
    assert l2 <= bound and row <= bound, (l2, row, report)
    # and against the complex128 direct sum on a few channels
    from raysim.synthesis.tones import synthesize_if_direct

    exact = synthesize_if_direct(tau[:, :, :2], amp[:, :, :2], cfg)
    l2, row = _rel(got[:, :2], exact)
    assert l2 <= bound + tones_error(n) and row <= bound + tones_error(n)


@pytest.mark.parametrize("method", ["tones", "nufft"])
def test_chirp_range_into_out(method):
    """A sub-range of chirps added into ``out``, with the tone sum's or FINUFFT's rows."""
    cfg = RadarConfig(num_chirps=160)
    arr = upa(2, 2, wavelength=cfg.wavelength)
    n = 12
    tau, amp = point_target_delays(cfg, arr, hover_jitter(3), _targets(n, seed=5))
    run = range(16, 144)
    ref = synthesize_if(tau[:, 16:144], amp[:, 16:144], cfg)
    out = ref.copy()                                   # something of the same scale to add to
    report = []
    synthesize(tau, amp, cfg, method=method, eps=10 * TOL, decimate="auto",
               decimate_tolerance=TOL, chirps=run, out=out, decimation_report=report)
    assert report and all(g["factor"] > 1 for g in report), report
    l2, row = _rel(out - ref, ref)
    rows_error = MAX_GAIN * (tones_error(n) if method == "tones" else 0.9 * 10 * TOL)
    bound = TOL + rows_error + 2 * tones_error(n)      # the reference's rounding, twice
    assert l2 <= bound and row <= bound + 0.9 * 10 * TOL, (l2, row, report)


def test_band_read_from_the_delays():
    """A single target under a pure vertical sinusoid: the bound covers the instantaneous
    frequency ``2 (2 pi A f_m T) / lambda`` and the Bessel sidebands of the fast part."""
    cfg = RadarConfig(num_chirps=128)
    arr = upa(1, 1, wavelength=cfg.wavelength)
    amp_m, f_m = 1e-4, 200.0
    tau, amp = point_target_delays(cfg, arr, sinusoid("z", amp_m, f_m),
                                   [PointTarget.at(10.0, 0.0, 0.0)])
    band = dense_doppler(tau, amp, cfg, TOL)
    lam = 299_792_458.0 / cfg.carrier_frequency
    inst = 2 * 2 * np.pi * amp_m * f_m * cfg.chirp_interval / lam       # cycles per chirp
    assert band.shape == (1,)
    assert band[0] >= inst                                              # the sidebands add
    assert band[0] <= 0.5


def test_refusal_is_the_exact_render():
    """A band too wide for factor 2 (fast vibration): every chirp exact, bit for bit the
    undecimated tone sum."""
    cfg = RadarConfig(num_chirps=64)
    arr = upa(2, 2, wavelength=cfg.wavelength)
    tau, amp = point_target_delays(cfg, arr, sinusoid("z", 1e-3, 2000.0), _targets(5))
    report = []
    with pytest.warns(select.DecimationRefused):
        select._SAID.clear()
        got = synthesize(tau, amp, cfg, method="tones", eps=10 * TOL, decimate="auto",
                         decimate_tolerance=TOL, decimation_report=report)
    assert [g["factor"] for g in report] == [1]
    assert np.array_equal(got, synthesize_if(tau, amp, cfg))


def _flight(tmp_path, monkeypatch, name, **kw):
    """Write a one-frame flight; returns its IF cube [frame, chirp, channel, sample] as
    handed to the capture writer (before the ADC's quantisation) and the decimation
    report of its synthesis."""
    import raysim.io.ti_dca1000 as dca
    from raysim.pipeline.flight import write_flight

    got, report = {}, []
    real_write, real_synth = dca.write_dca1000, select.synthesize

    def write(path, cube, fmt):
        got["cube"] = np.array(cube)
        return real_write(path, cube, fmt)

    monkeypatch.setattr(dca, "write_dca1000", write)
    monkeypatch.setattr(select, "synthesize",
                        lambda *a, **k: real_synth(*a, **k, decimation_report=report))
    write_flight(tmp_path / name, frames=1, targets="default5", **kw)
    monkeypatch.undo()
    return got["cube"], report


def test_flight_decimated_within_tolerance_and_off_is_the_oracle(tmp_path, monkeypatch):
    """``raysim flight`` with decimation (default ``auto``): within the tolerance of the
    exact flight up to the capture's full-scale normalisation; ``off`` renders with the
    oracle only."""
    import raysim.echoes.oracle as oracle

    still = hover_jitter(0, HoverJitterSpec(vibration_rms=0.0))   # hover without rotors
    auto, report = _flight(tmp_path, monkeypatch, "auto", trajectory=still)
    calls = []
    real = oracle.simulate_point_targets
    monkeypatch.setattr(oracle, "simulate_point_targets",
                        lambda *a, **k: calls.append(1) or real(*a, **k))
    off, off_report = _flight(tmp_path, monkeypatch, "off", trajectory=still, decimate="off")
    assert calls and off_report == []                  # the oracle, no synthesize call
    assert report and all(g["factor"] > 1 for g in report), report
    scale = np.vdot(auto, off) / np.vdot(auto, auto)   # each capture is scaled to full scale
    l2, row = _rel((scale * auto)[0], off[0])
    bound = TOL + MAX_GAIN * tones_error(5)
    assert l2 <= bound and row <= bound, (l2, row, report)


def test_flight_refused_under_rotor_vibration_is_exact(tmp_path, monkeypatch):
    """The default hover jitter's rotor vibration at the flight's TDM chirp interval is too
    fast to decimate 64 chirps: refused with the reason, the cube is the oracle's."""
    monkeypatch.setattr(select, "_SAID", set())
    with pytest.warns(select.DecimationRefused):
        auto, report = _flight(tmp_path, monkeypatch, "auto")
    off, _ = _flight(tmp_path, monkeypatch, "off", decimate="off")
    assert [g["factor"] for g in report] == [1] and report[0]["reason"]
    assert np.array_equal(auto, off)


def test_flight_bad_decimation_input(tmp_path):
    from raysim.cli import main
    from raysim.pipeline.flight import write_flight

    with pytest.raises(ValueError, match="decimate"):
        write_flight(tmp_path / "a", frames=1, decimate="on")
    with pytest.raises(ValueError, match="decimate_tolerance"):
        write_flight(tmp_path / "b", frames=1, decimate_tolerance=0.5)
    assert main(["flight", str(tmp_path / "c"), "--decimate-tolerance", "0", "--frames",
                 "1", "--no-progress"]) == 2
    assert not (tmp_path / "c").exists()
