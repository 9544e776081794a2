"""Every JSON file of run data parses with a strict parser: ``null``, never ``NaN`` or ``Infinity``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from harness.recording import RunFolder, load_run, strict_json, write_simulation_case
from harness.recording.metadata import write_json_atomic
from harness.report.reference import reference_tables
from harness.runs.run_context import reference_entry
from harness.signals.peaks import Peaks
from harness.simulation.case import CaseResult

NAN, INF = float("nan"), float("inf")


def _strict(path: Path) -> object:
    """What a parser of another language makes of the file (json.loads refusing NaN and Infinity)."""
    return strict_json.loads(path.read_text(encoding="utf-8"))


def test_the_strict_parser_refuses_what_python_writes_by_default() -> None:
    with pytest.raises(ValueError, match="NaN is not JSON"):
        strict_json.loads(json.dumps({"x": NAN}))
    with pytest.raises(ValueError, match="Infinity is not JSON"):
        strict_json.loads(json.dumps([INF]))


def test_non_finite_numbers_become_null_at_any_depth_numpy_included() -> None:
    data = {"a": NAN, "b": [1.0, -INF, {"c": np.float64("nan")}], "d": np.array([1.5, np.nan]), "e": (np.int64(3), INF),
            "f": np.float32(2.5), 4: "key as text"}
    assert strict_json.loads(strict_json.dumps(data)) == {
        "a": None, "b": [1.0, None, {"c": None}], "d": [1.5, None], "e": [3, None], "f": 2.5, "4": "key as text"}


def test_a_default_converts_other_values_and_its_result_is_made_plain_too() -> None:
    assert strict_json.loads(strict_json.dumps({"p": Path("/x")}, str)) == {"p": "/x"}
    assert strict_json.dumps({"v": object()}, lambda value: NAN) == '{"v": null}'
    with pytest.raises(TypeError, match="expected JSON data"):
        strict_json.dumps({"v": object()})


def test_metadata_and_events_of_a_run_folder_are_strict_json(tmp_path: Path) -> None:
    folder = RunFolder.create(tmp_path, "nceer_4dof", "dry-run", {"name": "nceer_4dof"}, ("t_s", "sliding_displacement_m"),
                              metadata={"total_weight_N": 39855.0, "unknown": NAN}).start()
    folder.record_event(0.5, "interlock", "force_rate", {"rate_N_per_s": NAN, "limit": INF})
    folder.finish("tripped", trip_reason="force_tracking", summary={"timing": {"lateness_p99_s": NAN}})
    metadata = _strict(folder.path / "metadata.json")
    assert isinstance(metadata, dict)
    assert metadata["unknown"] is None and metadata["summary"]["timing"]["lateness_p99_s"] is None
    lines = (folder.path / "events.jsonl").read_text(encoding="utf-8").splitlines()
    details = [strict_json.loads(line)["detail"] for line in lines]
    assert {"rate_N_per_s": None, "limit": None} in details
    assert load_run(folder.path).metadata["unknown"] is None


def _case(peaks: Peaks) -> CaseResult:
    return CaseResult(name="passive", columns={}, peaks=peaks, integrator_steps=0, wall_time_s=0.0)


def test_a_dry_runs_reference_peaks_with_nothing_measured_are_null_and_read_back_as_nan(tmp_path: Path) -> None:
    """The issue's metadata.json: ``"measured_force_pct_weight": NaN`` in the reference peaks."""
    t = np.arange(20) * 0.002
    columns = {"t_s": t, "sliding_displacement_m": 1e-3 * np.sin(t), "drift_1_m": 1e-4 * np.sin(t),
               "floor_acceleration_1_m_s2": np.cos(t)}
    folder = write_simulation_case(tmp_path, "dry", tuple(columns), columns, {"total_weight_N": 39855.0})
    passive = Peaks(2e-3, 0.5, (2e-4,), (1.0,), 0.0)  # measured force: NaN, nothing to measure
    assert math.isnan(passive.measured_force_pct_weight)
    metadata_path = folder / "metadata.json"
    metadata = strict_json.loads(metadata_path.read_text())
    assert isinstance(metadata, dict)
    metadata["reference"] = reference_entry(_case(passive), None, None, lockstep=True)
    write_json_atomic(metadata_path, metadata)
    written = _strict(metadata_path)
    assert isinstance(written, dict)
    assert written["reference"]["passive_peaks"]["measured_force_pct_weight"] is None
    tables = reference_tables([load_run(folder)])
    assert tables, "the reference peaks are read back although one of them is null"
    assert tables[0].row("drift_1").values[0] == pytest.approx(0.2)  # mm
