"""Reading run folders back, refusing what is not one, and whole-array simulation cases."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from harness.recording import (
    RunFolder,
    RunFolderError,
    load_run,
    load_runs,
    write_simulation_case,
)
from harness.signals.columns import (
    canonical_columns,
    count_stories,
    drift,
    floor_acceleration,
    unit_of,
)

COLUMNS = ("t_s", "drift_1_m", "drift_2_m", "force_command_N")


def _arrays(n: int = 200, amplitude: float = 0.01) -> dict[str, np.ndarray]:
    t = np.arange(n) * 0.01
    return {
        "t_s": t,
        "drift_1_m": amplitude * np.sin(2 * np.pi * t),
        "drift_2_m": 0.5 * amplitude * np.sin(2 * np.pi * t),
        "force_command_N": 100.0 * np.cos(t),
    }


def _finished_run(tmp_path: Path) -> Path:
    run = RunFolder.create(tmp_path, "p", "dry-run", {"a": 1}, COLUMNS)
    run.start()
    data = _arrays(20)
    for i in range(20):
        run.record_row(tuple(data[c][i] for c in COLUMNS))
    run.finish("completed")
    return run.path


def _edit_metadata(folder: Path, **changes: object) -> None:
    path = folder / "metadata.json"
    meta = json.loads(path.read_text())
    for key, value in changes.items():
        if value is None:
            meta.pop(key, None)
        else:
            meta[key] = value
    path.write_text(json.dumps(meta))


def test_simulation_cases_are_two_complete_run_folders(tmp_path: Path) -> None:
    passive = write_simulation_case(
        tmp_path / "sim", "passive", COLUMNS, _arrays(), {"controller": "passive", "total_weight_N": 1e4}
    )
    controlled = write_simulation_case(tmp_path / "sim", "controlled", COLUMNS, _arrays(amplitude=0.004), {"controller": "eq23"})
    assert passive == tmp_path / "sim" / "passive"
    runs = load_runs([tmp_path / "sim"])
    assert [r.case for r in runs] == ["passive", "controlled"]
    assert runs[0].is_passive and not runs[1].is_passive
    assert all(r.kind == "simulation" and r.outcome == "completed" and not r.incomplete for r in runs)
    np.testing.assert_allclose(runs[1]["drift_1_m"], _arrays(amplitude=0.004)["drift_1_m"], rtol=1e-11, atol=1e-15)
    assert load_run(controlled).metadata["controller"] == "eq23"
    assert runs[0].metadata["total_weight_N"] == 1e4


def test_simulation_case_accepts_a_2d_array_and_events(tmp_path: Path) -> None:
    table = np.column_stack([_arrays()[c] for c in COLUMNS])
    events = [{"t_s": 1.0, "kind": "warning", "name": "stroke_soft_limit", "detail": {"x_b_m": 0.04}}]
    folder = write_simulation_case(tmp_path, "controlled", COLUMNS, table, {}, profile_data={"k": (1, 2)}, events=events)
    run = load_run(folder)
    np.testing.assert_allclose(run["force_command_N"], table[:, 3], rtol=1e-11)
    assert run.events[0]["name"] == "stroke_soft_limit" and run.events[0]["detail"] == {"x_b_m": 0.04}
    assert run.profile == {"k": [1, 2]}


@pytest.mark.parametrize(
    ("arrays", "message"),
    [
        ({"t_s": np.zeros(3)}, "missing"),
        ({**_arrays(), "extra_m": np.zeros(200)}, "extra"),
        ({**_arrays(), "drift_1_m": np.zeros(5)}, "one length"),
        (np.zeros((5, 3)), r"expected \(n, 4\)"),
    ],
)
def test_simulation_case_refuses_arrays_that_do_not_fit_the_columns(tmp_path: Path, arrays: object, message: str) -> None:
    with pytest.raises(RunFolderError, match=message):
        write_simulation_case(tmp_path, "passive", COLUMNS, arrays, {})


def test_simulation_case_refuses_to_overwrite(tmp_path: Path) -> None:
    write_simulation_case(tmp_path, "passive", COLUMNS, _arrays(), {})
    with pytest.raises(RunFolderError, match="already exists"):
        write_simulation_case(tmp_path, "passive", COLUMNS, _arrays(), {})


def test_load_run_on_a_case_set_names_the_cases(tmp_path: Path) -> None:
    write_simulation_case(tmp_path, "passive", COLUMNS, _arrays(), {})
    write_simulation_case(tmp_path, "controlled", COLUMNS, _arrays(), {})
    with pytest.raises(RunFolderError, match=r"set of run folders \(passive, controlled\)"):
        load_run(tmp_path)


def test_signals_csv_is_plain_csv_with_unit_named_columns(tmp_path: Path) -> None:
    folder = _finished_run(tmp_path)
    with open(folder / "signals.csv", newline="") as handle:
        rows = list(csv.reader(handle))
    assert tuple(rows[0]) == COLUMNS
    assert len(rows) == 21 and all(len(r) == 4 for r in rows)
    assert float(rows[2][0]) == pytest.approx(0.01)


def test_a_torn_last_line_is_dropped_with_a_warning(tmp_path: Path) -> None:
    folder = _finished_run(tmp_path)
    with open(folder / "signals.csv", "a") as handle:
        handle.write("0.2,0.00")
    run = load_run(folder)
    assert run.n_rows == 20
    assert any("torn last line" in w for w in run.warnings)


@pytest.mark.parametrize(
    ("changes", "message"),
    [
        ({"format_version": 2}, "found format_version 2, expected 1"),
        ({"format_version": None}, "found format_version None, expected 1"),
        ({"format": "something-else"}, "not a harness run folder"),
    ],
)
def test_unknown_or_older_format_is_an_error(tmp_path: Path, changes: dict, message: str) -> None:
    folder = _finished_run(tmp_path)
    _edit_metadata(folder, **changes)
    with pytest.raises(RunFolderError, match=message):
        load_run(folder)


def test_missing_files_and_non_folders_are_errors(tmp_path: Path) -> None:
    folder = _finished_run(tmp_path)
    (folder / "events.jsonl").unlink()
    with pytest.raises(RunFolderError, match="missing events.jsonl"):
        load_run(folder)
    with pytest.raises(RunFolderError, match="no such folder"):
        load_run(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(RunFolderError, match="found no metadata.json"):
        load_run(tmp_path / "empty")
    (tmp_path / "bad").mkdir()
    (tmp_path / "bad" / "metadata.json").write_text("{not json")
    with pytest.raises(RunFolderError, match="cannot read it as JSON"):
        load_run(tmp_path / "bad")


def test_header_that_disagrees_with_metadata_is_an_error(tmp_path: Path) -> None:
    folder = _finished_run(tmp_path)
    text = (folder / "signals.csv").read_text().replace("drift_2_m", "drift_3_m", 1)
    (folder / "signals.csv").write_text(text)
    with pytest.raises(RunFolderError, match="expected the columns in metadata.json"):
        load_run(folder)


def test_missing_column_lookup_names_what_exists(tmp_path: Path) -> None:
    run = load_run(_finished_run(tmp_path))
    assert run.has("drift_1_m") and not run.has("drift_1_m", "lateness_s")
    with pytest.raises(KeyError, match="has no column 'lateness_s'"):
        run["lateness_s"]


def test_canonical_columns_and_units() -> None:
    names = canonical_columns(3)
    assert names[0] == "t_s" and len(set(names)) == len(names)
    assert drift(3) in names and floor_acceleration(1) in names and "drift_4_m" not in names
    assert count_stories(names) == 3
    assert "lateness_s" not in canonical_columns(1, timing=False)
    some = ("floor_acceleration_2_m_s2", "sliding_velocity_m_s", "drift_1_m", "force_raw_N", "t_s", "state")
    assert [unit_of(n) for n in some] == [
        "m/s^2",
        "m/s",
        "m",
        "N",
        "s",
        "1",
    ]
    with pytest.raises(ValueError, match="at least 1"):
        canonical_columns(0)
