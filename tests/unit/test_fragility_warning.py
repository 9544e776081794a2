"""Issue 33, item 6: a fragility fit the counts cannot support says so (CSV note, plot legend and line)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from harness.sweep.curves import MIN_CASES_PER_LEVEL, NOT_MEANINGFUL, fragility
from harness.sweep.plots import plot_fragility

LEVELS = np.array([0.1, 0.2, 0.3, 0.4])


def _cases(per_level: int, response_of_level) -> tuple[np.ndarray, np.ndarray]:
    pga = np.repeat(LEVELS, per_level)
    return pga, np.array([response_of_level(level, i % per_level) for i, level in enumerate(pga)])


def test_two_records_per_level_giving_a_step_are_not_a_meaningful_fit() -> None:
    pga, sliding = _cases(2, lambda level, _: 0.1 if level >= 0.3 else 0.05)  # the beta 0.01 curve
    curve = fragility("FSF-I", pga, sliding, limit=0.075)
    assert np.isfinite(curve.theta_g)  # the fit is kept ...
    assert not curve.meaningful and NOT_MEANINGFUL in curve.note and "step" in curve.note  # ... and marked


def test_few_cases_per_level_are_not_meaningful_even_without_a_step() -> None:
    pga, sliding = _cases(2, lambda level, i: 0.1 if level >= 0.3 or (level == 0.2 and i == 0) else 0.05)
    curve = fragility("FSF-I", pga, sliding, limit=0.075)
    assert not curve.meaningful and f"fewer than {MIN_CASES_PER_LEVEL}" in curve.note


def test_enough_graded_cases_give_a_meaningful_fit(tmp_path: Path) -> None:
    per_level = MIN_CASES_PER_LEVEL
    pga, sliding = _cases(per_level, lambda level, i: 0.1 if i < round(per_level * level / 0.5) else 0.05)
    curve = fragility("FSF-I", pga, sliding, limit=0.075)
    assert curve.meaningful and curve.note == ""
    weak = fragility("OF-I", *_cases(2, lambda level, _: 0.1 if level >= 0.3 else 0.05), limit=0.075)
    assert plot_fragility([("stroke", [curve, weak])], tmp_path / "fragility.png", "study").is_file()


def test_the_sweep_report_warns_on_the_console_of_a_fit_that_is_not_meaningful(tmp_path: Path) -> None:
    from harness.commands.sweep import _fragility_warnings
    from harness.sweep.report import ReportSettings, write_fragility
    from harness.sweep.summary import design_labels

    pga, sliding = _cases(2, lambda level, _: 0.1 if level >= 0.3 else 0.05)  # 2 records a level, a step
    n = pga.size
    columns = {"pga_g": pga, "outcome": np.array(["ok"] * n, dtype=object), "controller": np.array(["FSF-I"] * n, dtype=object),
               "record": np.array(["el_centro", "hachinohe"] * (n // 2), dtype=object),
               "passive.sliding_displacement_m": sliding * 0.8, "passive.max_drift_m": np.full(n, 0.01),
               "passive.max_floor_acceleration_m_s2": np.full(n, 5.0), "controlled.sliding_displacement_m": sliding}
    files = write_fragility(columns, design_labels(columns, []), ReportSettings("study", [], 0.075), tmp_path)
    warnings = _fragility_warnings(files)
    assert any(line.startswith(f"fragility of sliding_displacement_m, FSF-I: {NOT_MEANINGFUL}") for line in warnings), warnings
