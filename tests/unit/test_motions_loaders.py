"""Loaders: every real file in ../shared/data/ground_motions, format variants, and every bad input."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness.errors import RecordError
from harness.motions import G_M_S2, RawRecord, load_record, normalize_accel_unit

DATA_DIR = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "ground_motions"
needs_data = pytest.mark.skipif(
    not DATA_DIR.is_dir(), reason=f"real ground motions not found at {DATA_DIR.resolve()} (shared data set absent)"
)

# (file, accel_unit to pass, dt [s], npts, PGA [g]) - dt, npts and PGA as stated in the data set's README/headers.
REAL_FILES = [
    ("elcentro_1940_NS.csv", None, 0.01, 4000, 0.3129),
    ("elcentro_1940_NS__PEER_IELC180.AT2", None, 0.01, 4000, 0.3129),
    ("elcentro_1940_NS_classic.csv", None, 0.02, 2688, 0.3484),
    ("elcentro_1940_NS_classic__kakemotokeita_sample.csv", "gal", 0.02, 2688, 0.3484),
    ("hachinohe_1968_NS.csv", None, 0.02, 3001, 0.2342),
    ("hachinohe_1968_NS__aki32_Hachinohe-NS.csv", "cm/s^2", 0.02, 3001, 0.2342),
    ("pacoima_1971_S16E.csv", None, 0.01, 4172, 1.2190),
    ("pacoima_1971_S16E__RSN77_SFERN_PUL164.AT2", None, 0.01, 4172, 1.2190),
]


@needs_data
@pytest.mark.parametrize(("filename", "unit", "dt", "npts", "pga"), REAL_FILES, ids=[f[0] for f in REAL_FILES])
def test_every_real_file_loads_with_its_stated_step_length_and_pga(filename, unit, dt, npts, pga):
    record = load_record(DATA_DIR / filename, accel_unit=unit)
    assert record.dt_s == pytest.approx(dt, rel=1e-9)
    assert record.n_samples == npts
    assert record.pga_g == pytest.approx(pga, abs=5e-5)
    assert not record.accel_m_s2.flags.writeable


@needs_data
def test_el_centro_csv_pga_equals_the_readme_value():
    assert round(load_record(DATA_DIR / "elcentro_1940_NS.csv").pga_g, 4) == 0.3129


@needs_data
@pytest.mark.parametrize(
    ("normalized", "original", "unit"),
    [
        ("elcentro_1940_NS.csv", "elcentro_1940_NS__PEER_IELC180.AT2", None),
        ("pacoima_1971_S16E.csv", "pacoima_1971_S16E__RSN77_SFERN_PUL164.AT2", None),
        ("hachinohe_1968_NS.csv", "hachinohe_1968_NS__aki32_Hachinohe-NS.csv", "gal"),
        ("elcentro_1940_NS_classic.csv", "elcentro_1940_NS_classic__kakemotokeita_sample.csv", "cm/s^2"),
    ],
)
def test_original_and_normalized_files_hold_the_same_samples(normalized, original, unit):
    a = load_record(DATA_DIR / normalized)
    b = load_record(DATA_DIR / original, accel_unit=unit)
    assert a.dt_s == pytest.approx(b.dt_s)
    np.testing.assert_allclose(a.accel_m_s2, b.accel_m_s2, rtol=1e-6, atol=1e-6)


@needs_data
@pytest.mark.parametrize(
    "filename", ["hachinohe_1968_NS__aki32_Hachinohe-NS.csv", "elcentro_1940_NS_classic__kakemotokeita_sample.csv"]
)
def test_originals_without_a_stated_unit_refuse_to_guess(filename):
    with pytest.raises(RecordError, match="unit is not stated") as info:
        load_record(DATA_DIR / filename)
    assert "accel_unit" in str(info.value)


# --- format variants ---------------------------------------------------------------------


def _write(tmp_path: Path, name: str, text: str) -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def _rows(values, dt=0.01, fmt="{t:.4f},{a}") -> str:
    return "".join(fmt.format(t=i * dt, a=a) + "\n" for i, a in enumerate(values))


VALUES = [0.0, 0.1, -0.2, 0.05, 0.3, -0.1, 0.0, 0.02, -0.04, 0.01, 0.0, 0.0]


@pytest.mark.parametrize(
    ("header", "unit", "factor"),
    [
        ("t_s,accel_g", None, G_M_S2),
        ("time_s,acc_m_s2", None, 1.0),
        ("t,acc", "m/s^2", 1.0),
        ("t,acc", "gal", 0.01),
        ("t [s],a [cm/s^2]", None, 0.01),
        ("time (s),acceleration (g)", "g", G_M_S2),
        ("t_s,acc_gal", None, 0.01),
    ],
)
def test_two_column_units_come_from_header_or_argument(tmp_path, header, unit, factor):
    path = _write(tmp_path, "r.csv", "# a comment\n" + header + "\n" + _rows(VALUES))
    record = load_record(path, accel_unit=unit)
    np.testing.assert_allclose(record.accel_m_s2, np.array(VALUES) * factor)
    assert record.dt_s == pytest.approx(0.01)


def test_time_in_milliseconds_is_converted(tmp_path):
    path = _write(tmp_path, "r.csv", "t_ms,accel_g\n" + _rows(VALUES, dt=5.0, fmt="{t:g},{a}"))
    assert load_record(path).dt_s == pytest.approx(0.005)


@pytest.mark.parametrize("sep", [" ", "\t", ";", "   "])
def test_separators_and_headerless_data_with_explicit_unit(tmp_path, sep):
    path = _write(tmp_path, "r.txt", _rows(VALUES, fmt="{t:.2f}" + sep + "{a}"))
    record = load_record(path, accel_unit="g")
    np.testing.assert_allclose(record.accel_m_s2, np.array(VALUES) * G_M_S2)


def test_trailing_empty_fields_bom_and_blank_lines_are_tolerated(tmp_path):
    text = "\ufefft,acc,,,\n\n" + _rows(VALUES, fmt="{t:.2f},{a},,,,")
    path = _write(tmp_path, "r.csv", text)
    assert load_record(path, accel_unit="gal").n_samples == len(VALUES)


def _at2(line4: str, values, unit_line="ACCELERATION TIME HISTORY IN UNITS OF G") -> str:
    body = "".join(f"{v:15.7E}" + ("\n" if i % 5 == 4 else "") for i, v in enumerate(values))
    return f"PEER RECORD\nSOME EVENT\n{unit_line}\n{line4}\n{body}\n"


@pytest.mark.parametrize(
    "line4", ["NPTS=  12, DT= .01000 SEC", "NPTS= 12 DT= 0.01", "npts=12, dt=0.01", "   12    .0100    NPTS, DT"]
)
def test_at2_npts_dt_variants(tmp_path, line4):
    record = load_record(_write(tmp_path, "r.AT2", _at2(line4, VALUES)))
    assert record.dt_s == pytest.approx(0.01)
    np.testing.assert_allclose(record.accel_m_s2, np.array(VALUES) * G_M_S2, atol=1e-9)


def test_at2_is_recognised_by_content_and_fortran_d_exponents_parse(tmp_path):
    text = _at2("NPTS=  12, DT= .01000 SEC", VALUES).replace("E", "D")
    record = load_record(_write(tmp_path, "r.txt", text))
    np.testing.assert_allclose(record.accel_m_s2, np.array(VALUES) * G_M_S2, atol=1e-9)


def test_name_defaults_to_stem_and_can_be_given(tmp_path):
    path = _write(tmp_path, "quake_7.csv", "t_s,accel_g\n" + _rows(VALUES))
    assert load_record(path).name == "quake_7"
    assert load_record(path, name="x").name == "x"


def test_accel_unit_aliases():
    assert normalize_accel_unit("GAL") == "cm/s^2"
    assert normalize_accel_unit("m_s2") == "m/s^2"
    with pytest.raises(RecordError, match="unknown acceleration unit"):
        normalize_accel_unit("ft/s^2")


def test_raw_record_refuses_bad_step_and_shape():
    with pytest.raises(RecordError, match="time step"):
        RawRecord("x", 0.0, np.zeros(20), "test")
    with pytest.raises(RecordError, match="1-D"):
        RawRecord("x", 0.01, np.zeros((2, 20)), "test")


# --- bad inputs -----------------------------------------------------------------------------

GOOD_HEADER = "t_s,accel_g\n"
BAD_FILES = {
    "empty": ("", {}, "is empty"),
    "blank": ("  \n\n \n", {}, "is empty"),
    "wrong_header": ("foo,bar\n" + _rows(VALUES), {}, "expected a header like"),
    "three_column_header": ("t,acc,vel\n" + _rows(VALUES), {}, "found 3 columns"),
    "missing_unit": ("t,acc\n" + _rows(VALUES), {}, "unit is not stated"),
    "unknown_unit": ("t_s,acc_furlong\n" + _rows(VALUES), {}, "unknown acceleration unit"),
    "conflicting_unit": (GOOD_HEADER + _rows(VALUES), {"accel_unit": "gal"}, "header states acceleration in g"),
    "text_value": (GOOD_HEADER + _rows(VALUES[:5]) + "0.0500,abc\n" + _rows(VALUES[:5]), {}, r":7: expected a number"),
    "nan": (GOOD_HEADER + _rows(VALUES[:3] + ["nan"] + VALUES[4:]), {}, r":5: the acceleration is 'nan'"),
    "inf": (GOOD_HEADER + _rows(VALUES[:3] + ["inf"] + VALUES[4:]), {}, r":5: the acceleration is 'inf'"),
    "too_short": (GOOD_HEADER + _rows(VALUES[:5]), {}, "found 5 samples, expected at least 10"),
    "huge": (GOOD_HEADER + _rows(VALUES[:4] + [341.7] + VALUES[5:]), {}, r":6: acceleration 341.7 g exceeds 10 g"),
    "three_values": (GOOD_HEADER + _rows(VALUES) + "0.12,0.1,0.2\n", {}, r":14: expected 2 values"),
    "single_column_without_dt": ("\n".join(map(str, VALUES)), {"accel_unit": "g"}, "needs a 'dt=...' header"),
    "header_only": ("# nothing\n" + GOOD_HEADER, {}, "no data rows"),
    "comments_only": ("# nothing\n# more\n", {}, "no data lines"),
    "keyed_without_dt": ("npts=12\n" + "\n".join(map(str, VALUES)), {"accel_unit": "g"}, "without 'dt="),
    "keyed_count_mismatch": ("dt=0.01\nndata=13\n" + "\n".join(map(str, VALUES)), {"accel_unit": "g"}, "ndata=13, found 12"),
    "keyed_peak_mismatch": ("Max.acc=1.0\ndt=0.01\n" + "\n".join(map(str, VALUES)), {"accel_unit": "g"}, "Max.acc=1.0"),
    "keyed_negative_dt": ("dt=-0.01\n" + "\n".join(map(str, VALUES)), {"accel_unit": "g"}, "expected dt > 0"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_malformed_text_files_are_refused_with_a_clear_message(tmp_path, case):
    text, kwargs, message = BAD_FILES[case]
    path = _write(tmp_path, f"{case}.csv", text)
    with pytest.raises(RecordError, match=message) as info:
        load_record(path, **kwargs)
    assert str(path) in str(info.value)


def test_non_uniform_time_names_the_line(tmp_path):
    times = [0.0, 0.01, 0.02, 0.03, 0.045, 0.05, 0.06, 0.07, 0.08, 0.09, 0.10, 0.11]
    text = GOOD_HEADER + "".join(f"{t},{a}\n" for t, a in zip(times, VALUES, strict=True))
    with pytest.raises(RecordError, match=r":6: non-uniform time step") as info:
        load_record(_write(tmp_path, "r.csv", text))
    assert "0.045" in str(info.value)


def test_missing_sample_breaks_the_grid(tmp_path):
    times = [i * 0.01 for i in range(13) if i != 7]
    text = GOOD_HEADER + "".join(f"{t:.2f},0.01\n" for t in times)
    with pytest.raises(RecordError, match=r":9: non-uniform time step"):
        load_record(_write(tmp_path, "r.csv", text))


def test_rounded_time_stamps_of_an_irrational_step_are_accepted(tmp_path):
    text = GOOD_HEADER + "".join(f"{i / 3:.3f},0.01\n" for i in range(3000))
    assert load_record(_write(tmp_path, "r.csv", text)).dt_s == pytest.approx(1 / 3, rel=1e-5)


def test_a_slowly_drifting_clock_is_refused(tmp_path):
    times = np.cumsum(np.r_[0.0, np.full(600, 0.0099), np.full(600, 0.0101)])
    text = GOOD_HEADER + "".join(f"{t:.6f},0.01\n" for t in times)
    with pytest.raises(RecordError, match="non-uniform time step"):
        load_record(_write(tmp_path, "r.csv", text))


@pytest.mark.parametrize(
    ("times", "line"), [([0.0, 0.01, 0.01] + [0.02 + 0.01 * i for i in range(10)], 4), ([0.0, 0.01, 0.005], 4)]
)
def test_repeated_or_decreasing_time_is_refused(tmp_path, times, line):
    text = GOOD_HEADER + "".join(f"{t},0.01\n" for t in times) + "".join(f"{1 + i},0.0\n" for i in range(10))
    with pytest.raises(RecordError, match=rf":{line}: time .* does not advance"):
        load_record(_write(tmp_path, "r.csv", text))


def test_binary_junk_is_refused(tmp_path):
    path = tmp_path / "junk.AT2"
    path.write_bytes(np.random.default_rng(1).bytes(2048) + b"\x00")
    with pytest.raises(RecordError, match="not a text file"):
        load_record(path)


def test_missing_file_says_where_it_looked(tmp_path):
    with pytest.raises(RecordError, match="does not exist") as info:
        load_record(tmp_path / "nope.csv")
    assert str(tmp_path.resolve()) in str(info.value)


def test_directory_is_not_a_record(tmp_path):
    with pytest.raises(RecordError, match="is a directory"):
        load_record(tmp_path)


@pytest.mark.parametrize(
    ("line4", "values", "unit_line", "message"),
    [
        ("NPTS=  13, DT= .01000 SEC", VALUES, "IN UNITS OF G", "NPTS=13, but the file holds 12"),
        ("NPTS=  12, DT= .01000 SEC", VALUES[:11] + [float("nan")], "IN UNITS OF G", "'NAN'|'nan'"),
        ("NPTS=  12, DT= -.0100 SEC", VALUES, "IN UNITS OF G", "expected DT > 0"),
        ("NPTS=  12, DT= .01000 SEC", VALUES, "IN UNITS OF CM/S/S", "expected acceleration 'IN UNITS OF G'"),
        ("NPTS=  12, DT= .01000 SEC", VALUES[:4] + [12.0] + VALUES[5:], "IN UNITS OF G", "exceeds 10 g"),
        ("NO POINTS HERE", VALUES, "IN UNITS OF G", "expected an AT2 line like"),
    ],
)
def test_bad_at2_files(tmp_path, line4, values, unit_line, message):
    with pytest.raises(RecordError, match=message):
        load_record(_write(tmp_path, "r.AT2", _at2(line4, values, unit_line)))


def test_at2_with_a_contradicting_unit_argument(tmp_path):
    with pytest.raises(RecordError, match="AT2 files are in g"):
        load_record(_write(tmp_path, "r.AT2", _at2("NPTS=  12, DT= .01", VALUES)), accel_unit="gal")


def test_a_file_is_parsed_once_per_version_and_its_samples_are_read_only(tmp_path):
    """A sweep loads the same record for every case: parse it once, and never let a case change it."""
    path = _write(tmp_path, "rec.csv", "time (s),acceleration (g)\n" + _rows(VALUES))
    first, again = load_record(path), load_record(path)
    assert first is again
    with pytest.raises(ValueError):
        first.accel_m_s2[1] = 0.0
    doubled = [2.0 * v for v in VALUES] + [0.0]
    path.write_text("time (s),acceleration (g)\n" + _rows(doubled))
    changed = load_record(path)
    assert changed is not first
    np.testing.assert_allclose(changed.accel_m_s2, np.array(doubled) * G_M_S2)
