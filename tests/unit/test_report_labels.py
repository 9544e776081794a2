"""Compared runs are told apart: labels from what differs, unique everywhere, no duplicate CSV headers, no wrapping."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pytest

from harness.recording import canonical_columns, load_runs, write_simulation_case
from harness.report import build_report, summary_text
from harness.report.labels import common_facts, distinct_labels, file_slug
from harness.report.text_table import TextTable

N_STORIES = 3
COLUMNS = canonical_columns(N_STORIES, timing=False)


def _signals(scale: float, controlled: bool, n: int = 400) -> dict[str, np.ndarray]:
    t = np.arange(n) * 0.004
    data = {c: np.zeros(n) for c in COLUMNS}
    data["t_s"] = t
    data["table_acceleration_m_s2"] = 3.0 * np.sin(2 * np.pi * 1.3 * t)
    for j in range(1, N_STORIES + 1):
        data[f"drift_{j}_m"] = scale * 0.002 * j * np.sin(2 * np.pi * 2.3 * t)
        data[f"floor_acceleration_{j}_m_s2"] = scale * (2.0 + j) * np.cos(2 * np.pi * 2.3 * t)
    data["sliding_displacement_m"] = scale * 0.04 * np.sin(2 * np.pi * 0.6 * t)
    data["force_command_N"] = (5000.0 if controlled else 0.0) * np.sin(2 * np.pi * 0.6 * t)
    return data


def _profile(controller: str, p1: float = 10.0) -> dict:
    return {"name": "eight_story", "control": {"controller": controller, "designs": {"OF-I": {"p1_per_s": p1}}}}


def _study(root: Path, name: str, controller: str, record: str = "el_centro", p1: float = 10.0, label: str = "") -> Path:
    """A ``simulate --out`` case set as the command writes it (without the old auto label unless asked)."""
    meta = {"profile_name": "eight_story", "total_weight_N": 4e7,
            "record": {"name": record, "pga_g": 0.3, "pgv_m_s": 0.3, "pgd_m": 0.1, "time_scale": 1.0, "duration_s": 1.6},
            "sampling": {"rate_hz": 250.0, "transport_delay_s": 0.0, "friction_source": "model",
                         "design_stiffness_scale": 1.0, "rig_effects": False}}
    for case, scale, controlled in (("passive", 1.0, False), ("controlled", 0.2, True)):
        extra = {"label": f"{label} {case}"} if label else {}
        write_simulation_case(root / name, case, COLUMNS, _signals(scale, controlled),
                              {**meta, **extra, "controller": controller if controlled else "none"},
                              profile_data=_profile(controller, p1))
    return root / name


def test_two_controllers_of_one_record_are_labelled_by_controller_and_their_passives_by_folder(tmp_path: Path) -> None:
    runs = load_runs([_study(tmp_path, "study_fsf1", "FSF-I"), _study(tmp_path, "study_of1", "OF-I")])
    assert distinct_labels(runs) == ["passive (study_fsf1)", "FSF-I", "passive (study_of1)", "OF-I"]
    assert common_facts(runs) == "eight_story, sim, el_centro, 0.3 g, time/1"


def test_two_records_of_one_controller_are_labelled_by_record(tmp_path: Path) -> None:
    runs = load_runs([_study(tmp_path, "a", "OF-I", "el_centro"), _study(tmp_path, "b", "OF-I", "pacoima")])
    assert distinct_labels(runs) == ["passive el_centro", "OF-I el_centro", "passive pacoima", "OF-I pacoima"]


def test_a_set_override_shows_in_the_label(tmp_path: Path) -> None:
    runs = load_runs([_study(tmp_path, "p10", "OF-I", p1=10.0), _study(tmp_path, "p6", "OF-I", p1=6.0)])
    labels = distinct_labels(runs)
    assert labels[1] == "OF-I p1_per_s=10" and labels[3] == "OF-I p1_per_s=6"
    assert len(set(labels)) == 4


def test_a_given_label_wins_and_the_old_automatic_label_does_not(tmp_path: Path) -> None:
    old = _study(tmp_path, "old", "FSF-I", label="eight_story simulate")  # what earlier versions wrote
    mine = _study(tmp_path, "mine", "OF-I", label="softer surface")
    runs = load_runs([old, mine])
    labels = distinct_labels(runs)
    assert labels[:2] == ["passive", "FSF-I"]
    assert labels[2:] == ["softer surface passive", "softer surface controlled"]
    assert distinct_labels(runs, ["A", None, None, "B"])[0::3] == ["A", "B"]


def test_a_report_of_two_studies_has_distinct_columns_titles_and_file_names(tmp_path: Path) -> None:
    result = build_report([_study(tmp_path, "study_fsf1", "FSF-I"), _study(tmp_path, "study_of1", "OF-I")],
                          tmp_path / "report")
    for path in result.table_files:
        with open(path, newline="") as handle:
            header = next(csv.reader(handle))
        assert len(header) == len(set(header)), f"{path.name} repeats a column: {header}"
    titles = [table.title for table in result.tables]
    assert len(titles) == len(set(titles))
    assert "Passive against controlled: FSF-I" in titles and "Passive against controlled: OF-I" in titles
    assert "Comparison: FSF-I against OF-I" in titles
    assert len({path.name for path in result.table_files}) == len(result.table_files)
    assert any("fsf_i" in path.name for path in result.table_files)
    page = result.html_path.read_text()
    assert "eight_story simulate" not in page


def test_report_labels_given_per_run_folder_apply_to_a_case_set(tmp_path: Path) -> None:
    result = build_report([_study(tmp_path, "a", "FSF-I"), _study(tmp_path, "b", "OF-I")], tmp_path / "r",
                          labels=["stiff", "soft"])
    assert [run.label for run in result.runs] == ["stiff passive", "stiff controlled", "soft passive", "soft controlled"]


@pytest.mark.parametrize("width", [80, 120])
def test_no_report_line_is_wider_than_the_terminal(tmp_path: Path, width: int) -> None:
    sets = [_study(tmp_path, name, controller) for name, controller in (("s1", "FSF-I"), ("s2", "OF-I"), ("s3", "FSF-II"))]
    result = build_report(sets, tmp_path / "report")
    text = summary_text(result, width=width)
    tables = text.split("\nReport: ")[0].split("\n\n")[1:]
    for line in "\n\n".join(tables).splitlines():
        assert len(line) <= width, line
    alone = [line for line in text.splitlines() if line.split()[:3] == ["Quantity", "Unit", "reduction"]]
    assert not alone, "the reduction column landed in a block of its own"


def test_a_text_table_wraps_headings_and_repeats_its_key_columns_in_blocks() -> None:
    table = TextTable("T", ("Quantity", "Unit", *(f"a long heading number {i}" for i in range(6))),
                      (("Story 1 drift", "mm", *("12.345",) * 6),), key_columns=2)
    text = table.to_text(60)
    assert max(len(line) for line in text.splitlines()) <= 60
    assert text.count("Story 1 drift") >= 2  # the key columns come again in the next block
    assert table.to_text().count("Story 1 drift") == 1  # no width: one block


def test_file_slug_keeps_letters_and_digits() -> None:
    assert file_slug("Passive against controlled: FSF-I (study_1)") == "passive_against_controlled_fsf_i_study_1"
