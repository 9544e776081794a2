"""Catalog, records directory precedence, RecordConfig, load_motion and the table-limit check."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from harness.config.schema import build, to_data
from harness.errors import ProfileError, RecordError
from harness.motions import (
    CATALOG,
    ENV_RECORDS_DIR,
    RecordConfig,
    TableLimitError,
    TableLimits,
    check_table_limits,
    list_records,
    load_motion,
    load_raw,
    process_record,
    records_dir_from,
    resolve_record,
    synthetic_record,
    synthetic_seed,
)

DATA_DIR = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "ground_motions"
needs_data = pytest.mark.skipif(
    not DATA_DIR.is_dir(), reason=f"real ground motions not found at {DATA_DIR.resolve()} (shared data set absent)"
)


def _fake_dir(tmp_path: Path) -> Path:
    """A records directory with a tiny El Centro stand-in and one extra file."""
    rows = "".join(f"{i * 0.01:.2f},{0.1 * np.sin(i / 3):.6f}\n" for i in range(200))
    (tmp_path / "elcentro_1940_NS.csv").write_text("t_s,accel_g\n" + rows)
    (tmp_path / "my_quake.csv").write_text("t_s,accel_g\n" + rows)
    (tmp_path / "notes.md").write_text("not a record")
    return tmp_path


# --- catalog ----------------------------------------------------------------------------------


@needs_data
@pytest.mark.parametrize("name", sorted(CATALOG))
def test_catalog_names_resolve_to_the_shared_files(name):
    assert resolve_record(name, DATA_DIR) == DATA_DIR / CATALOG[name].filename


@pytest.mark.parametrize("name", ["el_centro", "elcentro_1940_NS", "elcentro_1940_NS.csv"])
def test_name_stem_and_file_name_resolve(tmp_path, name):
    folder = _fake_dir(tmp_path)
    assert resolve_record(name, folder) == folder / "elcentro_1940_NS.csv"


def test_a_path_resolves_without_a_directory(tmp_path):
    path = _fake_dir(tmp_path) / "my_quake.csv"
    assert resolve_record(str(path), None) == path


def test_missing_record_message_names_everything_a_user_needs(tmp_path):
    with pytest.raises(RecordError) as info:
        resolve_record("pacoima", tmp_path)
    text = str(info.value)
    for needed in (
        "'pacoima'", str(tmp_path.resolve()), "pacoima_1971_S16E.csv",
        "el_centro", "hachinohe", "RSN6", "RSN77", "PARI", "synthetic",
    ):
        assert needed in text


def test_missing_directory_and_unset_directory_are_said(tmp_path):
    with pytest.raises(RecordError, match="does not exist"):
        resolve_record("el_centro", tmp_path / "nope")
    with pytest.raises(RecordError, match=f"no records directory is set.*{ENV_RECORDS_DIR}"):
        resolve_record("el_centro", None)


def test_a_missing_path_is_reported_as_a_file(tmp_path):
    with pytest.raises(RecordError, match="record file .*missing.csv does not exist"):
        resolve_record(str(tmp_path / "missing.csv"), None)


def test_synthetic_names():
    assert synthetic_seed("synthetic") == 0
    assert synthetic_seed("synthetic:17") == 17
    assert synthetic_seed("el_centro") is None
    with pytest.raises(RecordError, match="whole-number seed"):
        synthetic_seed("synthetic:abc")
    with pytest.raises(RecordError, match="generated"):
        resolve_record("synthetic", None)


def test_list_records_reports_availability_extra_files_and_synthetic(tmp_path):
    listing = {entry.name: entry for entry in list_records(_fake_dir(tmp_path))}
    assert listing["el_centro"].available and listing["el_centro"].path == tmp_path / "elcentro_1940_NS.csv"
    assert not listing["pacoima"].available
    assert listing["my_quake"].available
    assert "notes" not in listing
    assert listing["synthetic"].available and listing["synthetic"].path is None


def test_list_records_without_a_directory():
    listing = list_records(None)
    assert [e.name for e in listing if e.available] == ["synthetic", "white_noise"]  # the generated ones


# --- records directory precedence ----------------------------------------------------------------


def test_records_dir_precedence_flag_then_env_then_profile(tmp_path):
    env = {ENV_RECORDS_DIR: "/from/env"}
    assert records_dir_from("/from/flag", "/from/profile", env) == Path("/from/flag")
    assert records_dir_from(None, "/from/profile", env) == Path("/from/env")
    assert records_dir_from(None, "/from/profile", {}) == Path("/from/profile")
    assert records_dir_from(None, None, {}) is None
    assert records_dir_from(None, "data", {}, base_dir=tmp_path) == tmp_path / "data"
    assert records_dir_from(None, "data", {ENV_RECORDS_DIR: ""}, base_dir=tmp_path) == tmp_path / "data"


# --- RecordConfig -------------------------------------------------------------------------------


def test_record_config_defaults_and_units():
    config = build(RecordConfig, {"pga_g": "0.34 g", "duration_s": "0.5 min", "time_scale": 2}, source="p.yaml", path="record")
    assert config.name == "synthetic" and config.seed == 0 and config.records_dir is None
    assert config.pga_g == pytest.approx(0.34) and config.duration_s == pytest.approx(30.0)
    assert to_data(config)["time_scale"] == 2.0


@pytest.mark.parametrize(
    ("data", "message"),
    [
        ({"pga_g": 0}, "record.pga_g"),
        ({"time_scale": -1}, "record.time_scale"),
        ({"duration_s": "3 kg"}, "record.duration_s"),
        ({"seed": 1.5}, "record.seed"),
        ({"accel_unit": "furlong/s^2"}, "accel_unit"),
        ({"name": ""}, "name"),
        ({"records": "x"}, "unknown key 'records'"),
    ],
)
def test_record_config_refusals(data, message):
    with pytest.raises(ProfileError, match=message):
        build(RecordConfig, data, source="p.yaml", path="record")


# --- load_motion ---------------------------------------------------------------------------------


def test_load_motion_synthetic_defaults_to_a_30_s_run():
    motion = load_motion(RecordConfig(seed=4), base_dir=".")
    assert motion.duration_s == pytest.approx(30.0)
    assert motion.name == "synthetic:4"
    assert motion.pga_g == pytest.approx(0.3, rel=1e-9)


def test_load_motion_cli_overrides_win(tmp_path):
    config = RecordConfig(name="synthetic:1", pga_g=0.2, time_scale=1.0, duration_s=10.0)
    motion = load_motion(config, base_dir=tmp_path, name="synthetic:2", pga_g=0.4, time_scale=2.0, duration_s=5.0)
    assert motion.name == "synthetic:2"
    assert motion.pga_g == pytest.approx(0.4, rel=1e-9)
    assert motion.time_scale == 2.0 and motion.duration_s == pytest.approx(5.0)


def test_load_motion_profile_relative_records_dir_and_env(tmp_path):
    (tmp_path / "records").mkdir()
    folder = _fake_dir(tmp_path / "records")
    config = RecordConfig(name="el_centro", records_dir="records", pga_g=0.1)
    motion = load_motion(config, base_dir=tmp_path, env={})
    assert motion.name == "el_centro" and motion.source == str(folder / "elcentro_1940_NS.csv")
    with pytest.raises(RecordError, match="el_centro"):
        load_motion(config, base_dir=tmp_path, env={ENV_RECORDS_DIR: str(tmp_path / "empty")})


def test_load_motion_name_as_a_profile_relative_path(tmp_path):
    _fake_dir(tmp_path)
    motion = load_motion(RecordConfig(name="./my_quake.csv"), base_dir=tmp_path, env={})
    assert motion.name == "my_quake"


@needs_data
def test_load_motion_rig_configuration_from_the_shared_records():
    config = RecordConfig(name="hachinohe", records_dir=str(DATA_DIR), pga_g=0.23, time_scale=2.0, duration_s=30.0)
    motion = load_motion(config, base_dir=".", env={})
    assert motion.dt_s == pytest.approx(0.01) and motion.duration_s == pytest.approx(30.0)
    assert motion.pga_g == pytest.approx(0.23, rel=1e-9)


@needs_data
def test_load_raw_original_needs_and_takes_a_unit():
    path = DATA_DIR / "hachinohe_1968_NS__aki32_Hachinohe-NS.csv"
    with pytest.raises(RecordError, match="unit is not stated"):
        load_raw(str(path), None)
    assert load_raw(str(path), None, accel_unit="gal").pga_g == pytest.approx(0.2342, abs=5e-5)


# --- table limits -----------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def motion():
    return process_record(synthetic_record(seed=9, duration_s=20.0), pga_g=0.3)


def test_table_limits_from_profile_data_with_units():
    limits = build(TableLimits, {"stroke_limit_m": "150 mm", "velocity_limit_m_s": "50 cm/s", "acceleration_limit_g": 1.5})
    assert limits.stroke_limit_m == pytest.approx(0.15) and limits.velocity_limit_m_s == pytest.approx(0.5)


@pytest.mark.parametrize(
    ("data", "key"),
    [
        ({"stroke_limit_m": 0, "velocity_limit_m_s": 1, "acceleration_limit_g": 1}, "stroke_limit_m"),
        ({"stroke_limit_m": 0.1, "velocity_limit_m_s": -1, "acceleration_limit_g": 1}, "velocity_limit_m_s"),
        ({"stroke_limit_m": 0.1, "velocity_limit_m_s": 1}, "acceleration_limit_g"),
    ],
)
def test_table_limits_refusals(data, key):
    with pytest.raises(ProfileError, match=key):
        build(TableLimits, data)


def test_a_motion_within_the_limits_passes(motion):
    check_table_limits(motion, TableLimits(motion.pgd_m * 1.01, motion.pgv_m_s * 1.01, motion.pga_g * 1.01))


def test_each_exceeded_limit_is_named_with_needed_and_available(motion):
    limits = TableLimits(stroke_limit_m=motion.pgd_m / 2, velocity_limit_m_s=10.0, acceleration_limit_g=0.25)
    with pytest.raises(TableLimitError) as info:
        check_table_limits(motion, limits)
    excesses = {e.limit.split()[0]: e for e in info.value.excesses}
    assert set(excesses) == {"stroke", "acceleration"}
    assert excesses["stroke"].needed == motion.pgd_m and excesses["stroke"].available == limits.stroke_limit_m
    assert excesses["acceleration"].needed == pytest.approx(0.3) and excesses["acceleration"].available == 0.25
    text = str(info.value)
    assert f"{motion.pgd_m:.4g} m" in text and f"{limits.stroke_limit_m:.4g} m" in text and "0.25 g" in text
    assert isinstance(info.value, RecordError)


def test_velocity_limit_alone(motion):
    with pytest.raises(TableLimitError, match=r"velocity \(peak \|xd_0\|\)") as info:
        check_table_limits(motion, TableLimits(1.0, motion.pgv_m_s * 0.9, 2.0))
    assert len(info.value.excesses) == 1
