"""The force-tracking measures (harness/report/force_tracking.py) on signals whose answer is known, and the report's section."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from harness.recording import write_simulation_case
from harness.recording.reader import RunData
from harness.report import build_report
from harness.report.force_tracking import force_tracking, has_load_cell, run_force_tracking
from harness.report.force_tracking_table import TITLE, force_tracking_table, record_span, run_tracking
from harness.signals.columns import FORCE_COMMAND, FORCE_MEASURED, FORCE_RAW, TIME

DT = 0.002  # the shipped loop's period (s)


def _force(t: np.ndarray) -> np.ndarray:
    """A two-tone force (N) with no special relation to the sample period."""
    return 3000.0 * np.sin(2 * np.pi * 1.3 * t) + 1200.0 * np.sin(2 * np.pi * 3.7 * t + 0.4)


def _times(duration_s: float = 12.0) -> np.ndarray:
    return np.arange(0.0, duration_s, DT)


@pytest.mark.parametrize("delay_samples", [1.0, 2.3, 4.6])
def test_a_delayed_copy_gives_its_delay_within_a_tenth_of_a_sample(delay_samples: float) -> None:
    t = _times()
    result = force_tracking(t, _force(t - delay_samples * DT), _force(t))
    assert result is not None
    assert result.delay_s == pytest.approx(delay_samples * DT, abs=0.1 * DT)
    assert result.correlation > 0.99


def test_a_force_one_sample_late_has_no_error_and_a_later_one_the_error_of_the_extra_lag() -> None:
    # The error is measured[k + 1] - asked[k]: the period's hold is not an error; what lags beyond it is.
    t = _times()
    on_time = force_tracking(t, _force(t - DT), _force(t))
    assert on_time is not None and on_time.rms_error_N == pytest.approx(0.0, abs=1e-6)
    # One tone of amplitude A lagging by tau beyond the hold: an error of amplitude 2 A sin(w tau / 2).
    tone = 2 * np.pi * 2.0 * t  # 2 Hz, 24 whole periods in the 12 s
    late = force_tracking(t, np.sin(tone - 2 * np.pi * 2.0 * 3.0 * DT), np.sin(tone))
    assert late is not None
    expected = 200.0 * math.sin(2 * np.pi * 2.0 * 2.0 * DT / 2.0)  # % of the tone's RMS (and of its peak)
    assert late.rms_error_percent == pytest.approx(expected, rel=0.01)
    assert late.peak_error_percent == pytest.approx(expected, rel=0.01)


@pytest.mark.parametrize("gain", [0.8, 1.25])
def test_a_scaled_copy_gives_the_scale_error_in_percent(gain: float) -> None:
    t = _times()
    asked = _force(t)
    measured = np.concatenate(([0.0], gain * asked[:-1]))  # on time (one sample), the wrong size
    result = force_tracking(t, measured, asked)
    assert result is not None
    assert result.rms_error_percent == pytest.approx(100.0 * abs(gain - 1.0), rel=1e-6)
    assert result.peak_error_percent == pytest.approx(100.0 * abs(gain - 1.0), rel=1e-6)
    assert result.peak_error_N == pytest.approx(abs(gain - 1.0) * np.max(np.abs(asked[:-1])), rel=1e-9)


def test_the_largest_error_is_placed_where_it_happens() -> None:
    t = _times()
    asked = _force(t)
    measured = np.concatenate(([0.0], asked[:-1]))
    measured[2500] += 900.0  # a 900 N spike at t = 5 s
    result = force_tracking(t, measured, asked)
    assert result is not None
    assert result.peak_error_N == pytest.approx(900.0)
    assert result.peak_error_t_s == pytest.approx(t[2500])


def _columns(t: np.ndarray, measured: np.ndarray, raw: np.ndarray, command: np.ndarray) -> dict[str, np.ndarray]:
    return {TIME: t, FORCE_MEASURED: measured, FORCE_RAW: raw, FORCE_COMMAND: command}


def test_run_columns_without_a_load_cell_or_a_force_asked_have_no_tracking() -> None:
    t = _times(2.0)
    force = _force(t)
    no_cell = {TIME: t, FORCE_RAW: force, FORCE_COMMAND: force}
    assert not has_load_cell(no_cell) and run_force_tracking(no_cell) is None
    silent_cell = _columns(t, np.full_like(t, np.nan), force, force)  # a loop that never heard the load cell
    assert not has_load_cell(silent_cell) and run_force_tracking(silent_cell) is None
    passive = _columns(t, np.zeros_like(t), np.zeros_like(t), np.zeros_like(t))
    assert has_load_cell(passive) and run_force_tracking(passive) is None


def test_run_columns_are_compared_with_the_column_asked_for_from_the_start_given() -> None:
    t = _times(6.0)
    raw = _force(t)
    command = 1.5 * raw  # e.g. a compensator's command on top of the controller's force
    measured = np.concatenate(([0.0], raw[:-1]))  # the actuator gives the controller's force
    columns = _columns(t, measured, raw, command)
    against_raw, against_command = run_force_tracking(columns, FORCE_RAW), run_force_tracking(columns, FORCE_COMMAND)
    assert against_raw is not None and against_raw.rms_error_percent == pytest.approx(0.0, abs=1e-9)
    assert against_command is not None and against_command.rms_error_percent == pytest.approx(100.0 / 3.0, rel=1e-6)
    later = run_force_tracking(columns, FORCE_RAW, start_s=2.0)
    assert later is not None and later.samples == int(np.sum(t >= 2.0)) - 1
    with pytest.raises(ValueError, match="asked must be one of"):
        run_force_tracking(columns, "drift_1_m")


# ---------------------------------------------------------------------------- the report's section


def _case(root: Path, case: str, measured: np.ndarray | None, raw: np.ndarray) -> Path:
    """A simulated case folder (record time = loop time) with the force columns, the load cell if given."""
    t = np.arange(raw.size) * DT
    data = {TIME: t, "drift_1_m": 1e-3 * np.sin(t), FORCE_RAW: raw, FORCE_COMMAND: raw}
    if measured is not None:
        data[FORCE_MEASURED] = measured
    metadata = {"total_weight_N": 39855.0, "record": {"name": "synthetic", "duration_s": float(t[-1])},
                "controller": "passive" if case == "passive" else "phi", "profile_name": "nceer_4dof"}
    return write_simulation_case(root / case, case, tuple(data), data, metadata)


def test_the_report_of_a_run_with_a_load_cell_has_the_tracking_table_and_plot(tmp_path: Path) -> None:
    t = _times()
    raw = _force(t)
    measured = np.concatenate(([0.0], 0.9 * raw[:-1]))  # one sample late, 10 % short
    folder = _case(tmp_path, "controlled", measured, raw)
    result = build_report([folder], tmp_path / "out")
    (table,) = [table for table in result.context if table.title == TITLE]
    by_asked = {row[1]: dict(zip(table.headings, row, strict=True)) for row in table.rows}
    row = by_asked["the controller's force"]
    assert float(row["RMS error (% of RMS asked)"]) == pytest.approx(10.0, abs=0.05)
    assert float(row["Peak error (% of peak asked)"]) == pytest.approx(10.0, abs=0.05)
    assert float(row["Delay (ms)"]) == pytest.approx(DT * 1e3, abs=0.1 * DT * 1e3)
    assert float(row["Correlation"]) > 0.99
    assert "force_tracking" in [plot.name for plot in result.plots]
    assert (tmp_path / "out" / "force_tracking.png").is_file()
    assert TITLE in result.summary and TITLE in result.html_path.read_text()


def test_runs_without_a_load_cell_or_a_force_asked_get_no_tracking_section(tmp_path: Path) -> None:
    t = _times(4.0)
    no_cell = _case(tmp_path, "controlled", None, _force(t))
    passive = _case(tmp_path, "passive", np.zeros_like(t), np.zeros_like(t))
    result = build_report([no_cell, passive], tmp_path / "out")
    assert TITLE not in [table.title for table in result.context]
    assert "force_tracking" not in [plot.name for plot in result.plots]
    assert TITLE not in result.summary
    assert force_tracking_table(result.runs) is None


def test_a_run_is_tracked_over_its_record_until_it_trips(tmp_path: Path) -> None:
    t = _times(10.0)
    raw = _force(t)
    measured = np.concatenate(([0.0], raw[:-1]))
    measured[t > 6.0] = 0.0  # after the trip at 6 s the supervisor holds the force at zero, not the controller
    metadata = {"controller": "phi", "record": {"name": "synthetic", "duration_s": 8.0},
                "summary": {"record_start_t_s": 1.0}}
    run = RunData(tmp_path, metadata, {}, (TIME, FORCE_RAW, FORCE_MEASURED),
                  {TIME: t, FORCE_RAW: raw, FORCE_MEASURED: measured}, [], None, False)
    assert record_span(run) == (1.0, 9.0)
    run.events.append({"t_s": 6.0, "kind": "fault", "name": "loop_stall"})
    assert record_span(run) == (1.0, 6.0)
    tracked = run_tracking(run)[FORCE_RAW]
    assert tracked.rms_error_N == pytest.approx(0.0, abs=1e-9)  # nothing after the trip counts
    assert tracked.samples == int(np.sum((t >= 1.0) & (t <= 6.0))) - 1
