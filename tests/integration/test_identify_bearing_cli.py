"""``harness identify bearing`` on the command line: a good run, and the inputs it refuses with exit status 2."""

from __future__ import annotations

import dataclasses
import json

import pytest
import yaml

from harness import exit_codes
from harness.cli import main
from harness.profile import load_profile
from harness.signals import columns as layout
from tests.identify_synthetic import measured, simulate, table_motion, write_run

DESIGN = load_profile()
TRUTH = dataclasses.replace(DESIGN.bearing, mu_max=0.072, mu_delta=0.025, a_mu_s_per_m=110.0)


@pytest.fixture(scope="module")
def quake_columns():
    return measured(simulate(DESIGN.structure, TRUTH, table_motion("synthetic:2", 0.34, 20.0)), DESIGN)


def test_it_prints_what_it_found_and_writes_the_three_files(quake_columns, tmp_path, capsys):
    folder = write_run(tmp_path, "quake", quake_columns, DESIGN)
    out = tmp_path / "ident"
    status = main(["identify", "bearing", str(folder), "--out", str(out)])
    printed = capsys.readouterr().out
    assert status == exit_codes.OK, printed
    assert "mu_max = 0.07" in printed and printed.count("not determined") == 0
    assert {p.name for p in out.iterdir()} == {"identified.yaml", "identification.json", "friction.png"}
    overlay = yaml.safe_load((out / "identified.yaml").read_text())
    assert overlay["bearing"]["mu_max"] == pytest.approx(0.072, rel=0.1)
    assert overlay["bearing"]["a_mu_s_per_m"] == pytest.approx(110.0, rel=0.1)
    assert json.loads((out / "identification.json").read_text())["command"] == "identify bearing"


def test_a_missing_folder_is_refused_naming_it(tmp_path, capsys):
    missing = tmp_path / "no_such_run"
    status = main(["identify", "bearing", str(missing), "--out", str(tmp_path / "ident")])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert str(missing) in err and "expected a run folder" in err
    assert not (tmp_path / "ident" / "identified.yaml").exists()


def test_a_folder_without_the_columns_is_refused_naming_the_run_and_what_was_expected(quake_columns, tmp_path, capsys):
    missing = (layout.floor_acceleration(2), layout.FORCE_MEASURED)
    folder = write_run(tmp_path, "no_floors", quake_columns, DESIGN, leave_out=missing)
    status = main(["identify", "bearing", str(folder), "--out", str(tmp_path / "ident")])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert str(folder) in err
    assert "floor_acceleration_2_m_s2" in err and "force_measured_N" in err and "the load cell" in err
    assert "floor_acceleration_1_m_s2 (" not in err  # only what is missing is named as missing
    assert not (tmp_path / "ident" / "identified.yaml").exists()


def test_a_folder_that_is_no_run_is_refused(tmp_path, capsys):
    (tmp_path / "empty").mkdir()
    status = main(["identify", "bearing", str(tmp_path / "empty"), "--out", str(tmp_path / "ident")])
    assert status == exit_codes.INPUT_ERROR
    assert "metadata.json" in capsys.readouterr().err


def test_runs_that_never_slid_are_refused_after_saying_why(tmp_path, capsys):
    still = measured(simulate(DESIGN.structure, TRUTH, table_motion("synthetic:3", 0.02, 6.0)), DESIGN)
    folder = write_run(tmp_path, "still", still, DESIGN)
    out = tmp_path / "ident"
    status = main(["identify", "bearing", str(folder), "--out", str(out)])
    captured = capsys.readouterr()
    assert status == exit_codes.INPUT_ERROR
    assert "determine none" in captured.err and "no run slid" in captured.err
    assert captured.out.count("not determined") == 4
    record = json.loads((out / "identification.json").read_text())  # written all the same, to look at
    assert record["determined"] == [] and record["per_run"][0]["slid"] is False
    assert "nothing determined" in (out / "identified.yaml").read_text()
