"""Issue 30, data: an identification's results are never mixed across runs, nor made of data it must not use.

- A result folder holding an earlier identification's files is refused (exit 2) unless ``--force``,
  which removes them first: the actuator's fit then sees this run's responses only (item 5).
- The same run given twice (a byte-identical copy) and a run whose outcome is ``incomplete`` are
  refused, naming them (item 6).
- A NaN row is refused by the identification, naming its line, and named by ``harness report``.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from harness import exit_codes
from harness.cli import main
from harness.model.plant import TableMotion
from harness.profile import load_profile
from harness.signals import columns as layout
from tests.identify_synthetic import measured, simulate, table_motion, write_run

DESIGN = load_profile()
#: A short excitation of the actuator (lockstep): enough bins for a fit, a few seconds a condition.
SHORT = ["--duration", "4", "--resolution-hz", "1", "--quiet"]


@pytest.fixture(scope="module")
def noise_run(tmp_path_factory) -> Path:
    """A white-noise run that determines the structure."""
    columns = measured(simulate(DESIGN.structure, DESIGN.bearing, table_motion("white_noise:0.5-20:0.1", None, 20.0)), DESIGN)
    return write_run(tmp_path_factory.mktemp("runs"), "noise", columns, DESIGN)


@pytest.fixture(scope="module")
def still_run(tmp_path_factory) -> Path:
    """A run whose base mat never moved: its floors hold only the sensors' noise, which determines nothing."""
    columns = measured(simulate(DESIGN.structure, DESIGN.bearing, TableMotion.at_rest(10.0, 0.01)), DESIGN)
    return write_run(tmp_path_factory.mktemp("runs"), "at_rest", columns, DESIGN)


def _message(err: str) -> str:
    return " ".join(err.split())  # rich wraps long lines


def _run_folders(folder: Path) -> list[Path]:
    return sorted(p for p in folder.iterdir() if p.is_dir() and (p / "metadata.json").is_file())


def test_a_second_identification_into_the_same_folder_is_refused_unless_force(noise_run, tmp_path, capsys):
    out = tmp_path / "ident"
    assert main(["identify", "structure", str(noise_run), "--out", str(out), "--band-hz", "1,20"]) == exit_codes.OK
    first = {name: (out / name).read_bytes() for name in ("identified.yaml", "identification.json")}
    capsys.readouterr()
    status = main(["identify", "structure", str(noise_run), "--out", str(out), "--band-hz", "1,18"])
    message = _message(capsys.readouterr().err)
    assert status == exit_codes.INPUT_ERROR
    assert str(out) in message and "already holds the results of an earlier identification" in message
    assert "identification.json" in message and "--force" in message
    assert {name: (out / name).read_bytes() for name in first} == first  # nothing replaced
    status = main(["identify", "structure", str(noise_run), "--out", str(out), "--band-hz", "1,18", "--force"])
    assert status == exit_codes.OK
    assert json.loads((out / "identification.json").read_text())["band_hz"] == [1.0, 18.0]


def test_a_bearing_identification_is_refused_before_fitting_into_an_earlier_result_folder(noise_run, tmp_path, capsys):
    out = tmp_path / "ident"
    out.mkdir()
    (out / "identified.yaml").write_text("bearing:\n  mu_max: 0.1\n")
    status = main(["identify", "bearing", str(noise_run), "--out", str(out)])
    assert status == exit_codes.INPUT_ERROR
    assert "identified.yaml" in _message(capsys.readouterr().err)
    assert (out / "identified.yaml").read_text() == "bearing:\n  mu_max: 0.1\n"
    assert sorted(p.name for p in out.iterdir()) == ["identified.yaml"]


def test_the_same_run_twice_is_refused(still_run, tmp_path, capsys):
    """The issue's reproduction: the run alone fails the quality gate; with its copy it passed it."""
    copy = shutil.copytree(still_run, tmp_path / "copy")
    out = tmp_path / "ident"
    status = main(["identify", "structure", str(still_run), str(copy), "--out", str(out)])
    message = _message(capsys.readouterr().err)
    assert status == exit_codes.INPUT_ERROR
    assert str(still_run) in message and str(copy) in message and "the same signals.csv" in message
    assert not out.exists()
    status = main(["identify", "bearing", str(still_run), str(still_run), "--out", str(out)])
    assert status == exit_codes.INPUT_ERROR and "the same signals.csv" in _message(capsys.readouterr().err)


def test_an_incomplete_run_is_refused_naming_it(noise_run, tmp_path, capsys):
    run = shutil.copytree(noise_run, tmp_path / "died")
    metadata = json.loads((run / "metadata.json").read_text())
    (run / "metadata.json").write_text(json.dumps({**metadata, "outcome": "incomplete"}))
    status = main(["identify", "structure", str(run), "--out", str(tmp_path / "ident")])
    message = _message(capsys.readouterr().err)
    assert status == exit_codes.INPUT_ERROR
    assert str(run) in message and "'incomplete'" in message and "expected a run that ended" in message


def _with_a_nan_row(run: Path, folder: Path, line: int) -> Path:
    copy = shutil.copytree(run, folder)
    lines = (copy / "signals.csv").read_text().split("\n")
    width = len(lines[0].split(","))
    lines[line - 1] = lines[line - 1].split(",")[0] + ",nan" * (width - 1)
    (copy / "signals.csv").write_text("\n".join(lines))
    return copy


def test_a_nan_row_is_refused_by_the_identification_and_named_by_the_report(noise_run, tmp_path, capsys):
    run = _with_a_nan_row(noise_run, tmp_path / "nan_row", 501)
    status = main(["identify", "structure", str(run), "--out", str(tmp_path / "ident")])
    message = _message(capsys.readouterr().err)
    assert status == exit_codes.INPUT_ERROR  # was a ValueError from least_squares (exit 1)
    assert str(run) in message and "line 501 of signals.csv" in message and layout.BASE_ACCELERATION in message
    status = main(["report", str(run), "--out", str(tmp_path / "report")])
    captured = capsys.readouterr()
    assert status == exit_codes.OK
    warned = _message(captured.out + captured.err)
    assert "run nan_row: 1 row(s) of signals.csv hold NaN or Inf (line 501)" in warned
    assert "line 501" in (tmp_path / "report" / "summary.txt").read_text()


def test_a_simulated_case_with_its_unsampled_last_row_gives_no_nan_warning(tmp_path, capsys):
    """The one place NaN belongs: a controlled case's controller internals in its last row (logs/README.md)."""
    from harness.recording import load_run

    assert main(["simulate", "--duration", "1", "--quiet", "--out", str(tmp_path / "sim")]) == exit_codes.OK
    assert not load_run(tmp_path / "sim" / "controlled").warnings


@pytest.mark.slow
def test_an_actuator_identification_fits_this_runs_responses_only(tmp_path, capsys):
    """Item 5: a blocked response of an earlier run in DIR was fitted with this run's, its error reported as current."""
    out = tmp_path / "frf"
    assert main(["identify", "actuator", "--out", str(out), "--blocked", *SHORT]) == exit_codes.OK
    assert (out / "frf_blocked.csv").is_file()
    earlier = _run_folders(out)
    capsys.readouterr()
    status = main(["identify", "actuator", "--out", str(out), *SHORT])
    message = _message(capsys.readouterr().err)
    assert status == exit_codes.INPUT_ERROR
    assert "frf_blocked.csv" in message and "--force" in message
    assert _run_folders(out) == earlier  # refused before anything moved: no new run
    assert main(["identify", "actuator", "--out", str(out), "--force", *SHORT]) == exit_codes.OK
    assert not (out / "frf_blocked.csv").exists() and (out / "frf.csv").is_file()
    record = json.loads((out / "identification.json").read_text())
    assert [error["condition"] for error in record["fit_error"]] == ["free"]
    assert len(record["runs"]) == 1
    assert set(json.loads((out / "excitation.json").read_text())["conditions"]) == {"free"}
