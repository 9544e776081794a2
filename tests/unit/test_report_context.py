"""A dry run's report keeps its context: passive reference and reduction, twin, record, controller, timing, events."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from harness.recording import RunFolder, canonical_columns, load_run
from harness.report import build_report, summary_text
from harness.runs.run_context import TARGET_MOTION_FILE, write_dry_run_context
from harness.safety import bit
from harness.signals.peaks import peak_responses, reduction_pct
from harness.simulation.sampled import CaseResult

N = 1000
PERIOD_S = 0.004
START_S = 0.2  # loop time at which the record started
WEIGHT_N = 39855.0
TIMING = {"ticks": N, "missed_periods": 2, "stalls": 1,
          "lateness_median_s": 4e-5, "lateness_p99_s": 9e-5, "lateness_p999_s": 2e-4,
          "lateness_max_s": 3e-4, "compute_median_s": 2e-4, "compute_p99_s": 505e-6, "compute_p999_s": 7e-4,
          "compute_max_s": 9e-4, "cpu_median_s": 1.5e-4, "cpu_p99_s": 3e-4, "cpu_p999_s": 4e-4, "cpu_max_s": 5e-4,
          "stalls_ridden_through": 1, "longest_stall_s": 0.006, "stall_budget_s": 0.02, "lockstep": False}
PROFILE = {"name": "nceer_4dof", "control": {"controller": "phi", "rate_hz": 250.0, "transport_delay_s": 0.0,
                                            "friction": "estimator", "design_stiffness_scale": 1.0,
                                            "designs": {"phi": {"kind": "phi", "p1_per_s": 8.0, "phi": 0.8, "delta": 0.0}}}}


def _motion() -> SimpleNamespace:
    t = np.arange(0, (N - 100) * PERIOD_S, PERIOD_S / 2)
    displacement = 0.03 * np.sin(2 * np.pi * 0.8 * t)
    return SimpleNamespace(t_s=t, accel_m_s2=-(2 * np.pi * 0.8) ** 2 * displacement,
                           velocity_m_s=0.03 * 2 * np.pi * 0.8 * np.cos(2 * np.pi * 0.8 * t), displacement_m=displacement)


def _dry_run(root: Path) -> Path:
    columns = canonical_columns(3)
    record = {"name": "el_centro", "pga_g": 0.34, "pgv_m_s": 0.154, "pgd_m": 0.0686, "time_scale": 2.0, "duration_s": 3.5}
    run = RunFolder.create(root, "nceer_4dof", "dry-run", PROFILE, columns,
                           metadata={"controller": "phi", "rate_hz": 250.0, "lockstep": False, "total_weight_N": WEIGHT_N,
                                     "record": record, "stroke_soft_limit_m": 0.08, "stroke_hard_limit_m": 0.1})
    run.start()
    row = np.zeros(len(columns))
    motion = _motion()
    for k in range(N):
        t = k * PERIOD_S
        values = {
            "t_s": t, "table_displacement_m": 1.01 * np.interp(t - START_S, motion.t_s, motion.displacement_m),
            "drift_1_m": 0.001 * np.sin(3 * t), "drift_2_m": 0.0005 * np.sin(3 * t), "drift_3_m": 0.0004 * np.sin(3 * t),
            "sliding_displacement_m": 0.02 * np.sin(t), "force_raw_N": 3000 * np.sin(t), "force_command_N": 2900 * np.sin(t),
            "interlock_flags": float(bit("force_rate")) if 100 <= k < 110 else 0.0, "compute_s": 2e-4 + 1e-7 * (k % 50),
        }
        for name, value in values.items():
            row[columns.index(name)] = value
        run.record_row(row)
    run.record_event(100 * PERIOD_S, "interlock", "force_rate", "")
    run.record_event(300 * PERIOD_S, "interlock", "force_rate", "")
    run.record_event(2.5, "fault", "drive_fault", "drive_state FAULT, fault_code 2 (HEARTBEAT_WATCHDOG)")
    run.finish("completed", summary={"timing": TIMING, "record_start_t_s": START_S,
                                     "host_timing": {"verdict": "ok"}})
    return run.path


def _case(name: str, drift_scale: float) -> CaseResult:
    t = np.arange(N) * PERIOD_S
    columns = {"t_s": t, "sliding_displacement_m": 0.015 * np.sin(t),
               **{f"drift_{j}_m": drift_scale * 0.001 * np.sin(3 * t) for j in (1, 2, 3)}}
    return CaseResult(name, columns, peak_responses(columns, WEIGHT_N, passive=name == "passive"), 0, 0.0)


@pytest.fixture(scope="module")
def report(tmp_path_factory: pytest.TempPathFactory):
    root = tmp_path_factory.mktemp("dry")
    path = _dry_run(root)
    write_dry_run_context(path, _motion(), _case("passive", 3.0), _case("twin", 1.1), None, lockstep=False)
    return path, build_report([path], root / "report")


def test_the_dry_run_folder_keeps_its_references_and_target_motion(report) -> None:
    path, _ = report
    metadata = json.loads((path / "metadata.json").read_text())
    assert set(metadata["reference"]) >= {"passive_peaks", "twin_peaks", "span_s"}
    assert metadata["target_motion_file"] == TARGET_MOTION_FILE
    header = (path / TARGET_MOTION_FILE).read_text().splitlines()[0]
    assert header == "t_s,table_acceleration_m_s2,table_velocity_m_s,table_displacement_m"
    assert load_run(path).n_rows == N  # the run itself reads as before


def test_the_passive_reference_table_shows_the_reduction_the_console_printed(report) -> None:
    path, result = report
    (table,) = [t for t in result.tables if t.title.startswith("Against the simulated passive reference")]
    row = table.row("drift_1")
    passive = json.loads((path / "metadata.json").read_text())["reference"]["passive_peaks"]["drift_m"][0]
    measured = float(np.max(np.abs(0.001 * np.sin(3 * np.arange(N) * PERIOD_S))))
    assert row.values[0] == pytest.approx(passive * 1e3)
    assert row.values[2] == pytest.approx(reduction_pct(passive, measured))
    twin = [t for t in result.tables if t.title.startswith("Against the rig twin")]
    assert twin and twin[0].row("drift_1").values[3] == pytest.approx(100 * (1 / 1.1 - 1), rel=1e-3)


def test_record_controller_timing_and_target_sections_are_in_the_report_and_the_page(report) -> None:
    _, result = report
    titles = [table.title for table in result.context]
    for expected in ("Record", "Table motion: target against achieved", "Controller", "Loop timing", "Events",
                     "Interlocks that acted"):
        assert any(title.startswith(expected) for title in titles), f"no {expected!r} section in {titles}"
    page = result.html_path.read_text()
    text = summary_text(result)
    for title in titles:
        assert title in text
    for needle in ("p1_per_s", "el_centro", "0.340", "68.60", "Loop timing", "drive_fault", "HEARTBEAT_WATCHDOG"):
        assert needle in page and needle in text, needle
    assert "table_tracking" in [plot.name for plot in result.plots]


def test_console_and_report_agree_on_compute_p99(report) -> None:
    _, result = report
    (timing,) = [t for t in result.context if t.title == "Loop timing"]
    cells = {row[0]: row[1] for row in timing.rows}
    assert cells["Compute p99 (us)"] == f"{TIMING['compute_p99_s'] * 1e6:.1f}" == "505.0"  # what print_timing shows
    assert cells["Missed periods"] == "2" and cells["Stalls"] == "1" and cells["Pre-flight check"] == "ok"


def test_target_against_achieved_names_the_peaks_and_the_tracking_error(report) -> None:
    _, result = report
    (table,) = [t for t in result.context if t.title.startswith("Table motion: target against achieved")]
    displacement = [row for row in table.rows if row[0] == "Peak table displacement"][0]
    target, achieved, difference = (float(cell) for cell in displacement[2:5])
    assert target == pytest.approx(30.0, rel=1e-3) and achieved == pytest.approx(1.01 * target, rel=1e-3)
    assert difference == pytest.approx(1.0, abs=0.06)
    assert float(displacement[5]) > 0  # RMS error of a 1 % scale error


def test_an_interlock_event_without_detail_says_what_acted_and_the_signals(report) -> None:
    _, result = report
    (events,) = [t for t in result.context if t.title.startswith("Events")]
    (force_rate,) = [row for row in events.rows if row[2] == "force_rate"]
    assert force_rate[3] == "2"  # the second rising edge is counted in the first row
    assert "max_force_rate_N_per_s" in force_rate[5] and "controller" in force_rate[5] and "kN" in force_rate[5]
    (interlocks,) = [t for t in result.context if t.title.startswith("Interlocks that acted")]
    assert interlocks.rows[0][:3] == ("force_rate", "10", f"{10 * PERIOD_S:.3f}")


def test_a_simulation_gets_no_timing_or_event_sections(tmp_path: Path) -> None:
    from harness.recording import write_simulation_case

    columns = ("t_s", "drift_1_m")
    write_simulation_case(tmp_path, "passive", columns, {"t_s": np.arange(4.0), "drift_1_m": np.zeros(4)}, {})
    result = build_report([tmp_path / "passive"], tmp_path / "report")
    assert not [t for t in result.context if t.title in ("Loop timing",) or t.title.startswith("Events")]
    assert dataclasses.is_dataclass(result)


def test_a_drive_fault_is_named_from_the_fault_code_in_can_log(tmp_path: Path) -> None:
    import can

    from drivers.protocol.codec import load_protocol
    from drivers.protocol.protocol_values import DriveState, FaultCode

    codec = load_protocol()["ACTUATOR_STATUS"]
    values = {"drive_state": float(DriveState.FAULT), "pressure_ok": 1.0, "fault_code": float(FaultCode.HEARTBEAT_WATCHDOG),
              "force_measured": 0.0}
    payload = codec.encode([values[name] for name in codec.signal_names], counter=1)
    columns = canonical_columns(3)
    run = RunFolder.create(tmp_path, "nceer_4dof", "dry-run", PROFILE, columns, metadata={"controller": "phi"})
    run.start()
    run.record_row(np.zeros(len(columns)))
    run.record_frame(can.Message(timestamp=1.0, arbitration_id=codec.frame_id, data=payload, is_extended_id=False,
                                 is_rx=True, channel="harness"))
    run.record_event(1.0, "fault", "drive_fault", "actuator drive reports a fault")
    run.finish("tripped", trip_reason="drive_fault")
    result = build_report([run.path], tmp_path / "report")
    (events,) = [t for t in result.context if t.title.startswith("Events")]
    assert "HEARTBEAT_WATCHDOG (2)" in events.rows[0][5]
    assert any("drive_fault (servo fault: HEARTBEAT_WATCHDOG (2))" in warning for warning in result.warnings)
