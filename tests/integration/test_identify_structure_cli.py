"""``harness identify structure`` on the command line: a good run, and the inputs it refuses with exit status 2."""

from __future__ import annotations

import json

import pytest
import yaml

from harness import exit_codes
from harness.cli import main
from harness.profile import load_profile
from harness.signals import columns as layout
from tests.identify_synthetic import measured, simulate, table_motion, write_run

DESIGN = load_profile()


@pytest.fixture(scope="module")
def columns():
    return measured(simulate(DESIGN.structure, DESIGN.bearing, table_motion("white_noise:0.5-20:0.1", None, 30.0)), DESIGN)


def test_it_prints_the_modes_and_writes_the_three_files(columns, tmp_path, capsys):
    folder = write_run(tmp_path, "noise", columns, DESIGN)
    out = tmp_path / "ident"
    status = main(["identify", "structure", str(folder), "--out", str(out), "--band-hz", "1,20"])
    printed = capsys.readouterr().out
    assert status == exit_codes.OK, printed
    assert "band 1-20 Hz" in printed and printed.count("(determined)") == 3
    assert "mode 1: 2.28" in printed  # the profile's 2.28 Hz first mode
    assert {p.name for p in out.iterdir()} == {"identified.yaml", "identification.json", "frf.png"}
    overlay = yaml.safe_load((out / "identified.yaml").read_text())
    assert overlay["structure"]["story_stiffness_N_per_m"] == pytest.approx(DESIGN.structure.story_stiffness_N_per_m, rel=0.1)
    assert json.loads((out / "identification.json").read_text())["band_hz"] == [1.0, 20.0]


def test_a_missing_folder_is_refused_naming_it(tmp_path, capsys):
    missing = tmp_path / "nowhere"
    status = main(["identify", "structure", str(missing), "--out", str(tmp_path / "ident")])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert str(missing) in err and "no such folder" in err


def test_a_folder_without_the_floor_accelerations_is_refused_naming_the_run(columns, tmp_path, capsys):
    folder = write_run(tmp_path, "no_top_floor", columns, DESIGN, leave_out=(layout.floor_acceleration(3),))
    out = tmp_path / "ident"
    status = main(["identify", "structure", str(folder), "--out", str(out)])
    err = capsys.readouterr().err
    assert status == exit_codes.INPUT_ERROR
    assert str(folder) in err and "floor_acceleration_3_m_s2" in err and "absolute acceleration of floor 3" in err
    assert not (out / "identified.yaml").exists()


def test_a_bad_band_is_refused_by_the_option_parser(tmp_path, capsys):
    status = main(["identify", "structure", str(tmp_path), "--out", str(tmp_path / "ident"), "--band-hz", "20,1"])
    assert status == exit_codes.INPUT_ERROR
    assert "LOW < HIGH" in capsys.readouterr().err


@pytest.mark.slow
def test_a_run_whose_base_mat_never_moved_determines_nothing_and_is_refused(tmp_path, capsys):
    from harness.model.plant import TableMotion

    still = measured(simulate(DESIGN.structure, DESIGN.bearing, TableMotion.at_rest(10.0, 0.01)), DESIGN)
    folder = write_run(tmp_path, "at_rest", still, DESIGN)  # only the sensors' noise in the floors
    out = tmp_path / "ident"
    status = main(["identify", "structure", str(folder), "--out", str(out)])
    captured = capsys.readouterr()
    assert status == exit_codes.INPUT_ERROR
    assert "determine neither the story stiffness nor the damping" in captured.err and "unexplained" in captured.err
    assert captured.out.count("(not determined)") == 3
    assert "nothing determined" in (out / "identified.yaml").read_text()  # no value from noise
