"""Recorded-data I/O: TI DCA1000 captures and IMU CSV logs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from raysim.io import (
    Dca1000Format,
    parse_dca1000,
    read_dca1000,
    read_imu_csv,
    write_dca1000,
    write_imu_csv,
)
from raysim.platform.imu import DEG, STANDARD_GRAVITY, ImuSamples, simulate_imu
from raysim.platform.motion import hover_jitter
from raysim.radar.config import RadarConfig

#: Unit conversions on a CSV round trip (relative, a few ulp).
UNIT_RTOL = 1e-14

LAYOUT_CASES = [(layout, cplx) for layout in ("2lane", "4lane") for cplx in (True, False)]


# ------------------------------------------------------------- TI references
def ref_ti_2lane(words: np.ndarray, num_rx: int, num_samples: int, is_real: bool):
    """TI ``readDCA1000`` (xWR16xx, 2 lanes) transcribed: returns ``[rx, chirp*sample]``."""
    words = words.astype(float)
    if is_real:
        n_chirps = words.size // num_samples // num_rx
        lvds = words.reshape(n_chirps, num_samples * num_rx)
    else:
        n_chirps = words.size // 2 // num_samples // num_rx
        lvds = np.zeros(words.size // 2, complex)
        counter = 0
        for i in range(0, words.size - 1, 4):  # "2I is followed by 2Q"
            lvds[counter] = words[i] + 1j * words[i + 2]
            lvds[counter + 1] = words[i + 1] + 1j * words[i + 3]
            counter += 2
        lvds = lvds.reshape(n_chirps, num_samples * num_rx)
    out = np.zeros((num_rx, n_chirps * num_samples), complex)
    for row in range(num_rx):
        for i in range(n_chirps):
            out[row, i * num_samples:(i + 1) * num_samples] = \
                lvds[i, row * num_samples:(row + 1) * num_samples]
    return out


def ref_ti_4lane(words: np.ndarray, is_real: bool):
    """TI ``readDCA1000`` (xWR14xx, 4 lanes) transcribed: returns ``[lane, chirp*sample]``.

    MATLAB ``reshape(adcData, numLanes*2, [])`` is column-major.
    """
    words = words.astype(float)
    if is_real:
        return words.reshape(-1, 4).T.astype(complex)
    cols = words.reshape(-1, 8).T
    return cols[0:4] + 1j * cols[4:8]


def cube_from_ref(ref: np.ndarray, fmt: Dca1000Format, n_frames: int) -> np.ndarray:
    """Re-index a ``[rx, chirp*sample]`` TI array into ``[frame, loop, tx*rx+rx, sample]``."""
    r, k = fmt.num_rx, fmt.num_samples
    per_rx = ref[:r].reshape(r, n_frames, fmt.num_loops, fmt.num_tx, k)
    return per_rx.transpose(1, 2, 3, 0, 4).reshape(n_frames, fmt.num_loops, fmt.num_channels, k)


def random_cube(fmt: Dca1000Format, n_frames: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    lo, hi = -(2 ** (fmt.adc_bits - 1)), 2 ** (fmt.adc_bits - 1) - 1
    shape = (n_frames, fmt.num_loops, fmt.num_channels, fmt.num_samples)
    re = rng.integers(lo, hi, shape, endpoint=True)
    re.flat[0], re.flat[1] = lo, hi  # extremes of the word
    if not fmt.complex:
        return re.astype(np.complex64)
    im = rng.integers(lo, hi, shape, endpoint=True)
    return (re + 1j * im).astype(np.complex64)


# ------------------------------------------------------------- DCA1000 parse
@pytest.mark.parametrize("cplx", [True, False])
def test_2lane_matches_ti_script(cplx):
    fmt = Dca1000Format(num_samples=8, slot_interval=50e-6, num_rx=4, num_tx=2, num_loops=3,
                        layout="2lane", complex=cplx)
    rng = np.random.default_rng(1)
    words = rng.integers(-32768, 32767, 2 * fmt.words_per_frame, endpoint=True).astype(np.int16)
    cap = parse_dca1000(words, fmt)
    ref = cube_from_ref(ref_ti_2lane(words, 4, 8, is_real=not cplx), fmt, 2)
    np.testing.assert_array_equal(cap.cube, ref.astype(np.complex64))
    assert cap.cube.dtype == np.complex64 and cap.cube.shape == (2, 3, 8, 8)


@pytest.mark.parametrize("cplx", [True, False])
@pytest.mark.parametrize("num_rx", [4, 2])
def test_4lane_matches_ti_script(cplx, num_rx):
    fmt = Dca1000Format(num_samples=6, slot_interval=50e-6, num_rx=num_rx, num_tx=3,
                        num_loops=2, layout="4lane", complex=cplx)
    rng = np.random.default_rng(2)
    words = rng.integers(-32768, 32767, 3 * fmt.words_per_frame, endpoint=True).astype(np.int16)
    cap = parse_dca1000(words, fmt)
    ref = cube_from_ref(ref_ti_4lane(words, is_real=not cplx), fmt, 3)
    np.testing.assert_array_equal(cap.cube, ref.astype(np.complex64))


def test_2lane_complex_word_order_by_hand():
    # one chirp, one rx, 4 samples: file I0 I1 Q0 Q1 I2 I3 Q2 Q3
    fmt = Dca1000Format(num_samples=4, slot_interval=1e-5, num_rx=1)
    words = np.array([1, 2, 10, 20, 3, 4, 30, 40], np.int16)
    cap = parse_dca1000(words, fmt)
    np.testing.assert_array_equal(cap.cube[0, 0, 0], [1 + 10j, 2 + 20j, 3 + 30j, 4 + 40j])


def test_4lane_complex_word_order_by_hand():
    # one chirp, two rx enabled, 1 sample: I(rx0..3) then Q(rx0..3); lanes 2, 3 unused
    fmt = Dca1000Format(num_samples=1, slot_interval=1e-5, num_rx=2, layout="4lane")
    words = np.array([1, 2, 0, 0, 10, 20, 0, 0], np.int16)
    cap = parse_dca1000(words, fmt)
    np.testing.assert_array_equal(cap.cube[0, 0, :, 0], [1 + 10j, 2 + 20j])


@pytest.mark.parametrize("layout, cplx", LAYOUT_CASES)
@pytest.mark.parametrize("num_rx, num_tx", [(4, 3), (3, 2), (1, 1)])
def test_round_trip_exact(tmp_path, layout, cplx, num_rx, num_tx):
    fmt = Dca1000Format(num_samples=16, slot_interval=60e-6, num_rx=num_rx, num_tx=num_tx,
                        num_loops=5, layout=layout, complex=cplx)
    cube = random_cube(fmt, 3, seed=num_rx * 10 + num_tx)
    path = write_dca1000(tmp_path / "adc_data.bin", cube, fmt)
    assert path.stat().st_size == 3 * fmt.bytes_per_frame
    cap = read_dca1000(path, fmt)
    np.testing.assert_array_equal(cap.cube, cube)
    assert cap.path == str(path)
    np.testing.assert_array_equal(cap.channel_tx, np.repeat(np.arange(num_tx), num_rx))
    np.testing.assert_array_equal(cap.channel_rx, np.tile(np.arange(num_rx), num_tx))


def test_read_frame_subset(tmp_path):
    fmt = Dca1000Format(num_samples=8, slot_interval=60e-6, num_rx=3, num_tx=2, num_loops=4,
                        layout="4lane", frame_period=2e-3)
    cube = random_cube(fmt, 6, seed=4)
    path = write_dca1000(tmp_path / "a.bin", cube, fmt)
    full = read_dca1000(path, fmt)
    part = read_dca1000(path, fmt, frames=slice(2, 5))
    np.testing.assert_array_equal(part.cube, cube[2:5])
    np.testing.assert_array_equal(part.chirp_time, full.chirp_time[2:5])
    np.testing.assert_array_equal(read_dca1000(path, fmt, frames=slice(-1, None)).cube,
                                  cube[-1:])
    with pytest.raises(ValueError, match="selects no frame"):
        read_dca1000(path, fmt, frames=slice(6, 9))
    with pytest.raises(ValueError, match="step 1"):
        read_dca1000(path, fmt, frames=slice(0, 6, 2))


def test_4lane_unused_lanes_are_zero_in_file(tmp_path):
    fmt = Dca1000Format(num_samples=4, slot_interval=60e-6, num_rx=2, layout="4lane")
    cube = random_cube(fmt, 1, seed=3)
    path = write_dca1000(tmp_path / "a.bin", cube, fmt)
    words = np.fromfile(path, "<i2").reshape(-1, 8)
    np.testing.assert_array_equal(words[:, [2, 3, 6, 7]], 0)


@pytest.mark.parametrize("adc_bits", [12, 14])
def test_narrow_adc_words_sign_extended(tmp_path, adc_bits):
    fmt = Dca1000Format(num_samples=8, slot_interval=60e-6, num_rx=2, num_tx=2, num_loops=2,
                        adc_bits=adc_bits)
    cube = random_cube(fmt, 2, seed=adc_bits)
    path = write_dca1000(tmp_path / "a.bin", cube, fmt)
    words = np.fromfile(path, "<i2")
    assert words.min() >= 0 and words.max() < 2 ** adc_bits  # unsigned adc_bits words
    np.testing.assert_array_equal(read_dca1000(path, fmt).cube, cube)
    one = parse_dca1000(np.array([2 ** adc_bits - 1, 0, 2 ** (adc_bits - 1), 1], np.int16),
                        Dca1000Format(num_samples=2, slot_interval=1e-5, num_rx=1,
                                      adc_bits=adc_bits))
    np.testing.assert_array_equal(one.cube[0, 0, 0], [-1 - 2 ** (adc_bits - 1) * 1j, 1j])


def test_chirp_timestamps_tdm_order():
    fmt = Dca1000Format(num_samples=2, slot_interval=100e-6, num_rx=1, num_tx=3, num_loops=4,
                        frame_period=5e-3, t0=0.25)
    cap = parse_dca1000(np.zeros(2 * fmt.words_per_frame, np.int16), fmt)
    assert cap.chirp_time.shape == (2, 4, 3)
    assert cap.chirp_time[0, 0, 0] == pytest.approx(0.25)
    assert cap.chirp_time[0, 1, 2] == pytest.approx(0.25 + 5 * 100e-6)
    assert cap.chirp_time[1, 3, 1] == pytest.approx(0.25 + 5e-3 + 10 * 100e-6)
    contiguous = Dca1000Format(num_samples=2, slot_interval=100e-6, num_tx=3, num_loops=4)
    assert contiguous.frame_interval == pytest.approx(1.2e-3)


def test_format_from_radar_config():
    cfg = RadarConfig(num_chirps=32, num_tx_slots=3, idle_time=10e-6)
    fmt = Dca1000Format.from_radar_config(cfg, num_rx=4)
    assert (fmt.num_samples, fmt.num_tx, fmt.num_loops) == (600, 3, 32)
    assert fmt.slot_interval == pytest.approx(70e-6)
    assert fmt.num_channels == 12


# ------------------------------------------------------------ DCA1000 errors
def test_truncated_capture_names_sizes(tmp_path):
    fmt = Dca1000Format(num_samples=8, slot_interval=60e-6, num_rx=4, num_tx=2, num_loops=2)
    cube = random_cube(fmt, 3, seed=0)
    path = write_dca1000(tmp_path / "cut.bin", cube, fmt)
    data = path.read_bytes()
    path.write_bytes(data[:-100])
    size = len(data) - 100
    with pytest.raises(ValueError, match=rf"{size} bytes.*{fmt.bytes_per_frame} bytes.*"
                                         r"2 complete frame\(s\) and \d+ bytes left over"):
        read_dca1000(path, fmt)
    cap = read_dca1000(path, fmt, drop_incomplete=True)
    np.testing.assert_array_equal(cap.cube, cube[:2])
    path.write_bytes(data[:-1])
    with pytest.raises(ValueError, match="odd"):
        read_dca1000(path, fmt)
    path.write_bytes(data[:10])
    with pytest.raises(ValueError, match="less than one frame"):
        read_dca1000(path, fmt, drop_incomplete=True)


@pytest.mark.parametrize("kwargs, match", [
    ({"num_rx": 0}, r"num_rx must be in 1\.\.4, got 0"),
    ({"num_rx": 5}, r"num_rx must be in 1\.\.4, got 5"),
    ({"num_tx": 5}, r"num_tx must be in 1\.\.4"),
    ({"num_loops": 0}, "num_loops"),
    ({"num_samples": 7}, "even"),
    ({"num_samples": 2.0}, "num_samples must be an integer"),
    ({"layout": "3lane"}, r"layout must be one of \('2lane', '4lane'\), got '3lane'"),
    ({"slot_interval": 0.0}, "slot_interval"),
    ({"slot_interval": float("nan")}, "slot_interval"),
    ({"frame_period": 1e-6}, "frame_period"),
    ({"adc_bits": 10}, "adc_bits"),
])
def test_bad_format_raises(kwargs, match):
    args = {"num_samples": 8, "slot_interval": 60e-6} | kwargs
    with pytest.raises(ValueError, match=match):
        Dca1000Format(**args)


def test_writer_validates(tmp_path):
    fmt = Dca1000Format(num_samples=4, slot_interval=60e-6, num_rx=2, num_tx=1, num_loops=2)
    good = np.zeros((1, 2, 2, 4), np.complex64)
    with pytest.raises(ValueError, match="shape"):
        write_dca1000(tmp_path / "a.bin", good[:, :, :1], fmt)
    with pytest.raises(ValueError, match="ADC range"):
        write_dca1000(tmp_path / "a.bin", good + 40000, fmt)
    with pytest.raises(ValueError, match="finite"):
        write_dca1000(tmp_path / "a.bin", good + np.nan, fmt)
    real = Dca1000Format(num_samples=4, slot_interval=60e-6, num_rx=2, num_loops=2, complex=False)
    with pytest.raises(ValueError, match="imaginary"):
        write_dca1000(tmp_path / "a.bin", good + 1j, real)
    with pytest.raises(ValueError, match="Dca1000Format"):
        read_dca1000(tmp_path / "a.bin", {"num_samples": 4})


# ------------------------------------------------------------------ IMU CSV
def _samples() -> ImuSamples:
    return simulate_imu(hover_jitter(3), "consumer_mems", rate=400.0, start=0.0, end=0.25,
                        seed=9)


def test_imu_csv_round_trip_si_exact(tmp_path):
    s = _samples()
    path = write_imu_csv(tmp_path / "imu.csv", s)
    text = path.read_text().splitlines()
    assert text[0].startswith("# ")
    assert text[1] == ("time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,"
                       "accel_x_m_s2,accel_y_m_s2,accel_z_m_s2")
    back = read_imu_csv(path)
    np.testing.assert_array_equal(back.time, s.time)
    np.testing.assert_array_equal(back.gyro, s.gyro)
    np.testing.assert_array_equal(back.accel, s.accel)
    assert back.spec is None and back.truth is None and back.source == str(path)


def test_imu_csv_round_trip_other_units(tmp_path):
    s = _samples()
    path = write_imu_csv(tmp_path / "imu.csv", s, time_unit="ms", gyro_unit="deg_s",
                         accel_unit="g")
    assert "gyro_z_deg_s" in path.read_text() and "accel_x_g" in path.read_text()
    back = read_imu_csv(path)
    np.testing.assert_allclose(back.time, s.time, rtol=UNIT_RTOL)
    np.testing.assert_allclose(back.gyro, s.gyro, rtol=UNIT_RTOL, atol=1e-18)
    np.testing.assert_allclose(back.accel, s.accel, rtol=UNIT_RTOL)


def test_imu_csv_unit_conversion_by_hand(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text(
        "# recorded on the bench\n"
        "temperature_c,accel_z_g,accel_y_mg,accel_x_m_s2,gyro_z_deg_s,gyro_y_deg_s,"
        "gyro_x_rad_s,time_us\n"
        "25.0,-1,1000,0.5,180,-90,0.25,1000\n"
        "25.1,-1.0,0,0.0,0,0,0,2500\n")
    s = read_imu_csv(path)
    np.testing.assert_allclose(s.time, [1e-3, 2.5e-3], rtol=UNIT_RTOL)
    np.testing.assert_allclose(s.gyro[0], [0.25, -math.pi / 2, math.pi], rtol=UNIT_RTOL)
    np.testing.assert_allclose(s.accel[0], [0.5, STANDARD_GRAVITY, -STANDARD_GRAVITY],
                               rtol=UNIT_RTOL)
    assert DEG * 180 == pytest.approx(math.pi)


HEADER = "time_s,gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2"


@pytest.mark.parametrize("body, match", [
    ("time_s,gyro_x_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n0,0,0,0,0,-9.8\n",
     r"missing column\(s\) \['gyro_y_<rad_s\|deg_s>'\]"),
    ("gyro_x_rad_s,gyro_y_rad_s,gyro_z_rad_s,accel_x_m_s2,accel_y_m_s2,accel_z_m_s2\n",
     r"missing column\(s\) \['time_<s\|ms\|us\|ns>'\]"),
    (HEADER + "\n0,0,0,0,0,0,-9.8\n0.1,0,nan,0,0,0,-9.8\n",
     r"row 2 \(line 3\), column 'gyro_y_rad_s': value 'nan' is not finite"),
    (HEADER + "\n0,0,0,0,0,0,-9.8\n0.1,0,0,0,abc,0,-9.8\n",
     r"row 2 \(line 3\), column 'accel_x_m_s2': 'abc' is not a number"),
    (HEADER + "\n0,0,0,0,0,0,-9.8\n0.1,0,0,0,0,0,\n",
     r"row 2 \(line 3\), column 'accel_z_m_s2': '' is not a number"),
    (HEADER + "\n0,0,0,0,0,0,-9.8\n0.1,0,0,0,0,0,-9.8\n0.1,0,0,0,0,0,-9.8\n",
     r"row 3 \(line 4\), column 'time_s': time stamp 0.1 repeats row 2"),
    (HEADER + "\n0,0,0,0,0,0,-9.8\n0.2,0,0,0,0,0,-9.8\n0.1,0,0,0,0,0,-9.8\n",
     r"row 3 \(line 4\), column 'time_s': time stamp 0.1 is earlier than row 2"),
    (HEADER + "\n0,0,0,0,0,0\n", r"row 1 \(line 2\) has 6 fields, the header has 7"),
    (HEADER.replace("gyro_x_rad_s", "gyro_x_rpm") + "\n",
     r"column 'gyro_x_rpm': unknown gyro unit 'rpm'; valid units are \['rad_s', 'deg_s'\]"),
    (HEADER.replace("time_s", "time_min") + "\n", "unknown time unit 'min'"),
    (HEADER + ",gyro_x_deg_s\n", "more than one gyro_x column"),
    (HEADER + "\n", "no data rows"),
    ("# only a comment\n", "no header row"),
])
def test_imu_csv_errors(tmp_path, body, match):
    path = tmp_path / "bad.csv"
    path.write_text(body)
    with pytest.raises(ValueError, match=match):
        read_imu_csv(path)


def test_imu_csv_writer_validates(tmp_path):
    with pytest.raises(ValueError, match=r"gyro_unit must be one of \['rad_s', 'deg_s'\]"):
        write_imu_csv(tmp_path / "x.csv", _samples(), gyro_unit="rpm")
    with pytest.raises(ValueError, match="ImuSamples"):
        write_imu_csv(tmp_path / "x.csv", np.zeros((3, 7)))


@settings(max_examples=40, deadline=None)
@given(layout=st.sampled_from(["2lane", "4lane"]), cplx=st.booleans(),
       num_rx=st.integers(1, 4), num_tx=st.integers(1, 3), num_loops=st.integers(1, 4),
       half_samples=st.integers(1, 5), n_frames=st.integers(1, 3), seed=st.integers(0, 99))
def test_round_trip_property(tmp_path_factory, layout, cplx, num_rx, num_tx, num_loops,
                             half_samples, n_frames, seed):
    fmt = Dca1000Format(num_samples=2 * half_samples, slot_interval=40e-6, num_rx=num_rx,
                        num_tx=num_tx, num_loops=num_loops, layout=layout, complex=cplx)
    cube = random_cube(fmt, n_frames, seed)
    path = write_dca1000(tmp_path_factory.mktemp("dca") / "a.bin", cube, fmt)
    cap = read_dca1000(path, fmt)
    np.testing.assert_array_equal(cap.cube, cube)
    assert cap.chirp_time.shape == (n_frames, num_loops, num_tx)
