"""The commands' output captured to a file or a pipe, --quiet, --json -, and the smaller items of issue 21.

Every command here runs through :func:`harness.cli.main` with its standard output captured (not
a terminal) and no ``$COLUMNS``, as in a lab's log file or a pipe.
"""

from __future__ import annotations

import json
import textwrap
from pathlib import Path

import pytest

from harness import exit_codes
from harness.cli import main
from tests.conftest import PROFILES

EIGHT = PROFILES / "eight_story.yaml"


@pytest.fixture(autouse=True)
def captured(monkeypatch):
    """Output to a pipe with no width given: what rich would otherwise cut at 80 columns."""
    monkeypatch.delenv("COLUMNS", raising=False)


def _lines(text: str) -> list[str]:
    return [line for line in text.strip().splitlines() if line.strip()]


@pytest.fixture(scope="module")
def sweep_results(tmp_path_factory) -> Path:
    """A two-case sweep's results folder (two designs, so the summary has its long design labels)."""
    folder = tmp_path_factory.mktemp("sweep")
    study = folder / "study.yaml"
    study.write_text(f"profile: {EIGHT}\n" + textwrap.dedent("""\
        name: captured
        options: {duration_s: 1}
        axes:
          records: ["synthetic:4"]
          pga_g: [0.25]
          controllers: [FSF-I]
          set: {control.design_stiffness_scale: [0.7, 1.3]}
        """))
    assert main(["sweep", str(study), "--workers", "0", "--out", str(folder / "results"), "--quiet"]) == exit_codes.OK
    return folder / "results"


def test_a_sweep_summary_in_a_pipe_is_not_cut(sweep_results: Path, tmp_path: Path, capsys) -> None:
    assert main(["sweep", "--summarize", str(sweep_results), "--report", str(tmp_path)]) == exit_codes.OK
    out = capsys.readouterr().out
    assert "…" not in out
    for heading in ("drift median %", "floor accel max %", "sliding median %", "force max % W"):
        assert heading in out, heading
    assert "FSF-I, design_stiffness_scale=0.7" in out and "FSF-I, design_stiffness_scale=1.3" in out


def test_quiet_sweep_prints_its_outcome_line_only(sweep_results: Path, tmp_path: Path, capsys) -> None:
    assert main(["sweep", "--summarize", str(sweep_results), "--report", str(tmp_path), "--quiet"]) == exit_codes.OK
    assert _lines(capsys.readouterr().out) == [f"wrote {tmp_path}/summary.csv, {tmp_path}/peaks.csv, {tmp_path}/summary.md"]


def test_quiet_simulate_prints_its_outcome_line_only(tmp_path: Path, capsys) -> None:
    path = tmp_path / "out.json"
    assert main(["simulate", "eight_story", "--duration", "1", "--controller", "FSF-I", "--json", str(path),
                 "--quiet"]) == exit_codes.OK
    (line,) = _lines(capsys.readouterr().out)
    assert line.startswith("simulated 2 x 1.0 s in ") and line.endswith(f"; wrote {path}")
    assert main(["simulate", "eight_story", "--duration", "1", "--record", "synthetic:1,synthetic:2",
                 "--controller", "FSF-I", "--quiet"]) == exit_codes.OK
    (line,) = _lines(capsys.readouterr().out)
    assert line.startswith("simulated 2 studies (2 records x 1 controller) in ")


def test_quiet_report_prints_its_outcome_line_only(tmp_path: Path, capsys) -> None:
    assert main(["simulate", "eight_story", "--duration", "1", "--controller", "FSF-I", "--out", str(tmp_path / "study"),
                 "--quiet"]) == exit_codes.OK
    capsys.readouterr()
    assert main(["report", str(tmp_path / "study"), "--out", str(tmp_path / "report"), "--quiet"]) == exit_codes.OK
    (line,) = _lines(capsys.readouterr().out)
    assert line.startswith("wrote ") and line.endswith(f"plots and {tmp_path / 'report' / 'report.html'}")


def test_json_dash_writes_standard_output_and_the_rest_to_standard_error(tmp_path: Path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(["simulate", "eight_story", "--duration", "1", "--controller", "FSF-I", "--json", "-"]) == exit_codes.OK
    out, err = capsys.readouterr()
    document = json.loads(out)  # nothing but the document on standard output
    assert document["controller"] == "FSF-I" and document["record"]["duration_s"] == pytest.approx(1.0)
    assert "story 8 drift" in err and "wrote standard output" in err
    assert not (tmp_path / "-").exists()
    assert main(["simulate", "eight_story", "--duration", "1", "--record", "synthetic:1,synthetic:2",
                 "--controller", "FSF-I", "--json", "-", "--quiet"]) == exit_codes.OK
    out, _ = capsys.readouterr()
    assert [run["record"]["name"] for run in json.loads(out)["runs"]] == ["synthetic:1", "synthetic:2"]
    assert not (tmp_path / "-").exists()


def test_the_simulate_header_names_the_variant(capsys) -> None:
    assert main(["simulate", "eight_story", "--variant", "a_mu_0.5", "--controller", "OF-II", "--duration", "1"]) == 0
    header = _lines(capsys.readouterr().out)[0]
    assert header.startswith("eight_story (variant a_mu_0.5)  record synthetic:0")


@pytest.mark.parametrize("name", ["robustness_table2", "profiles/studies/robustness_table2.yaml",
                                  "studies/robustness_table2.yaml"])
def test_a_shipped_study_is_found_by_name_from_outside_the_checkout(name: str, tmp_path: Path, monkeypatch, capsys,
                                                                   records_dir: Path) -> None:  # El Centro: a real record
    monkeypatch.chdir(tmp_path)
    assert main(["sweep", name, "--plan", "--out", str(tmp_path / "results")]) == exit_codes.OK, capsys.readouterr().err
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("robustness_table2: 3 cases (")  # the count, from the axes at once
    assert any(line.startswith(f"robustness_table2: 3 cases, 0 already in {tmp_path / 'results'}") for line in lines)
