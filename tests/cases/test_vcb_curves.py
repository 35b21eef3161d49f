"""Travel-curve files and the breaker analyser's quantities (camopt/cases/vcb/curves.py)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from camopt.cases.vcb.curves import (
    MAX_SAMPLES,
    TravelCurve,
    VelocityPoints,
    analyse,
    check_scale,
    column_name,
    noise_level,
    read_curve,
)
from camopt.errors import ConfigError
from tests.cases.vcb_ode import CURVES

GAP = 11e-3


def _ramp(n: int = 200, noise: float = 0.0, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A curve at rest for 5 ms, then 18 mm at 1.5 m/s (12 ms), then at rest (ms, mm)."""
    t = np.round(np.arange(n) * 0.2, 9)  # ms
    s = np.clip((t - 5.0) * 1.5, 0.0, 18.0)
    return t, s + noise * np.random.default_rng(seed).standard_normal(n)


def _write(path, t, s, header="time_ms,travel_mm"):
    path.write_text(header + "\n" + "".join(f"{a},{b}\n" for a, b in zip(t, s)))
    return path


def test_reads_both_unit_spellings_to_the_same_si_curve(tmp_path):
    t, s = _ramp()
    a = read_curve(_write(tmp_path / "a.csv", t, s))
    b = read_curve(_write(tmp_path / "b.csv", t / 1e3, s / 1e3, "time_s,travel_m"))
    np.testing.assert_allclose(a.time, b.time, rtol=1e-12)
    np.testing.assert_allclose(a.travel, b.travel, rtol=1e-12, atol=1e-15)
    assert a.time[-1] == pytest.approx(39.8e-3)
    assert a.travel.max() == pytest.approx(18e-3)


def test_other_channels_are_ignored_and_the_zero_is_the_rest_before_motion(tmp_path):
    t, s = _ramp()
    path = tmp_path / "c.csv"
    path.write_text("coil_a,time_ms,travel_mm\n" + "".join(
        f"0.5,{a},{b + 0.3}\n" for a, b in zip(t, s)))
    curve = read_curve(path)
    assert curve.travel[0] == pytest.approx(0.0, abs=1e-12)
    assert curve.travel.max() == pytest.approx(18e-3)


@pytest.mark.parametrize("text, where", [
    ("", "empty file"),
    ("0,0\n0.1,0.2\n", "no header"),
    ("time,travel\n0,0\n", "need a header"),
    ("time_ms,travel_mm\n0,0\n0.1\n", "line 3: 1 fields"),
    ("time_ms,travel_mm\n0,0\n0.1,abc\n", "line 3: travel_mm: not a number"),
    ("time_ms,travel_mm\n0,0\n0.1,nan\n", "line 3: travel_mm: nan"),
])
def test_malformed_files_are_one_line_naming_the_file(tmp_path, text, where):
    path = tmp_path / "bad.csv"
    path.write_text(text)
    with pytest.raises(ConfigError, match=where) as info:
        read_curve(path)
    assert str(info.value).startswith(str(path)) and "\n" not in str(info.value)


def test_repeated_or_falling_times_name_the_line(tmp_path):
    t, s = _ramp()
    t2 = t.copy()
    t2[50] = t2[49]
    with pytest.raises(ConfigError, match="line 52: time_ms 9.8 repeats"):
        read_curve(_write(tmp_path / "dup.csv", t2, s))
    t2[50] = t2[49] - 0.1
    with pytest.raises(ConfigError, match="line 52: .* goes back"):
        read_curve(_write(tmp_path / "back.csv", t2, s))


@settings(max_examples=25, deadline=None)
@given(st.integers(1, 198), st.sampled_from(["swap", "repeat"]))
def test_any_time_out_of_order_is_refused(k, how):
    """Property: swapping two neighbouring times, or repeating one, anywhere is refused."""
    import tempfile
    from pathlib import Path

    t, s = _ramp()
    if how == "swap":
        t[k], t[k + 1] = t[k + 1], t[k]
    else:
        t[k + 1] = t[k]
    with tempfile.TemporaryDirectory() as d:
        with pytest.raises(ConfigError, match="times must increase"):
            read_curve(_write(Path(d) / "x.csv", t, s))


def test_metres_in_a_mm_column_and_a_still_curve_are_refused(tmp_path):
    t, s = _ramp()
    with pytest.raises(ConfigError, match="metres in a _mm column"):
        read_curve(_write(tmp_path / "m.csv", t, s / 1e3))
    rng = np.random.default_rng(1)
    with pytest.raises(ConfigError, match="never moves"):
        read_curve(_write(tmp_path / "still.csv", t, 0.01 * rng.standard_normal(t.size)))


def test_too_long_curves_are_refused(tmp_path):
    t, s = _ramp()
    with pytest.raises(ConfigError, match="too long a curve"):  # microseconds in a _ms column
        read_curve(_write(tmp_path / "s.csv", t * 1e3, s))
    n = MAX_SAMPLES + 1
    path = tmp_path / "long.csv"
    path.write_text("time_ms,travel_mm\n" + "0,0\n" * n)
    with pytest.raises(ConfigError, match=f"{n} samples, more than"):
        read_curve(path)


def test_noise_level_estimates_white_noise_on_a_smooth_curve():
    """sigma from the second differences' MAD: 0.02 mm within 10 % on 4,000 samples."""
    t = np.linspace(0, 0.04, 4000)
    s = 0.009 * (1 - np.cos(np.pi * t / 0.04))
    noisy = s + 0.02e-3 * np.random.default_rng(3).standard_normal(t.size)
    assert noise_level(noisy) == pytest.approx(0.02e-3, rel=0.1)


def test_analyser_quantities_of_a_ramp_are_exact():
    """A straight ramp at 1.5 m/s from 5 ms to 18 mm, then a 0.4 mm over-travel peak that
    settles back at 18 mm and a dip to 17.7 mm: closing time at the 11 mm gap
    5 + 11 / 1.5 ms, velocity 1.5 m/s between any points, TT 18.4, wipe 7.4, OT 0.4,
    rebound 0.7 mm."""
    t = np.arange(0, 40.0, 0.1)  # ms
    s = np.clip((t - 5.0) * 1.5, 0.0, 18.0)
    s[t >= 20] = 18.0
    s[np.isclose(t, 20.0)] = 18.4
    s[np.isclose(t, 22.0)] = 17.7
    q = analyse(t * 1e-3, s * 1e-3, GAP, VelocityPoints.last_third(GAP))
    assert q.closing_time == pytest.approx((5 + 11 / 1.5) * 1e-3, rel=1e-12)
    assert q.contact_velocity == pytest.approx(1.5, rel=1e-9)
    assert q.total_travel == pytest.approx(18.4e-3)
    assert q.contact_wipe == pytest.approx(7.4e-3)
    assert q.over_travel == pytest.approx(0.4e-3)
    assert q.rebound == pytest.approx(0.7e-3)
    model = analyse(t * 1e-3, s * 1e-3, GAP, VelocityPoints(2e-3, 4e-3), rebounds=False)
    assert model.contact_velocity == pytest.approx(1.5, rel=1e-9)
    assert model.over_travel is None and model.rebound is None
    assert any("not computed by the model" in n for n in model.notes)


def test_the_shipped_curves_read():
    for name in ("vendor", "stiff"):
        curve = read_curve(CURVES / f"{name}.csv")
        assert 17.5e-3 < curve.travel.max() < 18.5e-3
        assert curve.noise == pytest.approx(0.02e-3, rel=0.25)


@pytest.mark.parametrize("header, name", [
    ("Time [ms]", "time_ms"), ("Travel (mm)", "travel_mm"), ("time/s", "time_s"),
    (" TIME_MS ", "time_ms"), ("Travel [ cm ]", "travel_cm"), ("cam angle [deg]",
                                                               "cam_angle_deg"),
    ("Coil A", "coil_a")])
def test_analyser_headers_read_as_column_names(header, name):
    assert column_name(header) == name


def test_an_analyser_export_with_semicolons_and_decimal_commas_reads_as_the_csv(tmp_path):
    """'Time [ms];Coil [A];Travel [mm]' with decimal commas: the same SI curve as the
    plain time_ms,travel_mm file (exactly: the same decimal text)."""
    t, s = _ramp(noise=0.01)
    plain = read_curve(_write(tmp_path / "a.csv", t, s))
    path = tmp_path / "export.txt"
    path.write_text("Time [ms];Coil [A];Travel [mm]\n" + "".join(
        f"{a};0,5;{b}\n".replace(".", ",") for a, b in zip(t, s)))
    export = read_curve(path)
    np.testing.assert_array_equal(export.time, plain.time)
    np.testing.assert_array_equal(export.travel, plain.travel)
    assert export.columns == ("time_ms", "travel_mm")


def test_seconds_in_a_ms_column_and_the_reverse_are_refused_naming_the_mix_up(tmp_path):
    t, s = _ramp()
    with pytest.raises(ConfigError, match="too short for a closing .seconds in a _ms column"):
        read_curve(_write(tmp_path / "s.csv", t / 1e3, s))
    with pytest.raises(ConfigError, match="too long a curve .milliseconds in a _s column"):
        read_curve(_write(tmp_path / "m.csv", t, s, "time_s,travel_mm"))


@pytest.mark.parametrize("scale, header, message", [
    (0.1, "time_ms,travel_mm", "centimetres in a _mm column"),
    (1.0, "time_ms,travel_m", "millimetres in a _m column"),
    (10.0, "time_ms,travel_cm", "millimetres in a _cm column"),
])
def test_a_travel_unlike_the_designs_stroke_is_refused(tmp_path, scale, header, message):
    """The ramp's 18 mm against an 18 mm stroke passes; the same numbers in other units
    (a tenth, a thousand or ten times the stroke) are refused, naming the likely mix-up."""
    t, s = _ramp(noise=0.01)
    check_scale(read_curve(_write(tmp_path / "ok.csv", t, s)), 18e-3,
                VelocityPoints.last_third(GAP))
    curve = read_curve(_write(tmp_path / "x.csv", t, s * scale, header))
    with pytest.raises(ConfigError, match=message):
        check_scale(curve, 18e-3, VelocityPoints.last_third(GAP))


def test_a_contact_velocity_out_of_a_closings_range_is_refused(tmp_path):
    """The ramp (1.5 m/s) timed 20 times too fast (30 m/s) or 40 times too slow
    (0.0375 m/s; built directly: as a file it would last over 1 s and be refused
    before): refused, naming the time column and the likely mix-up."""
    t, s = _ramp(n=4000)
    fast = read_curve(_write(tmp_path / "f.csv", t / 20, s))
    with pytest.raises(ConfigError, match="time_ms: the contact velocity reads 30 m/s.*"
                       "seconds in a _ms column"):
        check_scale(fast, 18e-3, VelocityPoints.last_third(GAP))
    slow = TravelCurve("s.csv", t * 40e-3, s * 1e-3, 0.0, ("time_s", "travel_mm"))
    with pytest.raises(ConfigError, match="time_s: .* 0.0375 m/s.*milliseconds in a _s"):
        check_scale(slow, 18e-3, VelocityPoints.last_third(GAP))


def test_over_travel_is_read_above_the_noise_not_from_raw_maxima():
    """A closing that settles with a 0.013 mm over-travel under 0.03 mm noise at 10 kHz:
    the raw maximum less the rest reads ~0.1 mm (the noise's own extreme); the smoothed
    reading is under 0.05 mm and the total travel within 0.02 mm of the truth. A clear
    0.4 mm over-travel lasting 2 ms is read within 0.05 mm."""
    t = np.arange(0, 60.0, 0.1)  # ms
    s = 18.0 * np.clip((t - 10.0) / 15.0, 0.0, 1.0) ** 2 * (3 - 2 * np.clip((t - 10) / 15, 0, 1))
    for bump, limit in ((0.013, 0.05), (0.4, 0.05)):
        clean = s + bump * np.exp(-(((t - 27.0) / 1.0) ** 2))
        noisy = clean + 0.03 * np.random.default_rng(5).standard_normal(t.size)
        q = analyse(t * 1e-3, noisy * 1e-3, GAP, VelocityPoints.last_third(GAP))
        raw = noisy.max() - np.median(noisy[-30:])
        assert q.over_travel / 1e-3 == pytest.approx(bump, abs=limit), (bump, raw)
        # within 0.03 mm (a noise level; the raw maximum reads ~0.1 mm high)
        assert q.total_travel / 1e-3 == pytest.approx(18.0 + bump, abs=0.03)
        if bump < 0.03:
            assert raw > 0.06  # what a raw maximum would have read
