"""What a run was run with, beside its peaks: the record's facts, the controller's parameters, the loop's timing.

Each function returns a :class:`~harness.report.text_table.TextTable` with one column per run
(a quantity per row), or None when no run has anything to show. The loop timing is the run's
own summary (``metadata.json`` ``summary.timing``), the numbers the console printed at the
end of the run, so console and report agree.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from harness.recording.reader import RunData
from harness.report.text_table import TextTable

Cell = Callable[[RunData], str]
ABSENT = "-"


def _mapping(value: Any) -> Mapping[str, Any]:
    return value if isinstance(value, Mapping) else {}


def _format(value: Any, scale: float = 1.0, digits: int = 3) -> str:
    if isinstance(value, bool) or value is None:
        return ABSENT if value is None else ("yes" if value else "no")
    if isinstance(value, int) and scale == 1.0:
        return str(value)
    if isinstance(value, (int, float)):
        return f"{value * scale:.{digits}f}" if np.isfinite(value) else str(value)
    return str(value)


def _table(title: str, runs: Sequence[RunData], rows: Sequence[tuple[str, Cell]], note: str = "") -> TextTable | None:
    """Rows of (quantity, cell function) against one column per run; rows every run leaves blank are dropped."""
    cells = [(name, tuple(cell(run) for run in runs)) for name, cell in rows]
    kept = tuple((name, *values) for name, values in cells if any(value != ABSENT for value in values))
    if not kept:
        return None
    return TextTable(title, ("Quantity", *(run.label for run in runs)), kept, note)


def record_table(runs: Sequence[RunData]) -> TextTable | None:
    """The processed record each run was fed: name, PGA, PGV, PGD, time scale, duration (``metadata["record"]``)."""

    def fact(key: str, scale: float = 1.0, digits: int = 3) -> Cell:
        return lambda run: _format(_mapping(run.metadata.get("record")).get(key), scale, digits)

    rows = (
        ("Record", lambda run: run.record_name or ABSENT),
        ("PGA (g)", fact("pga_g", 1.0, 3)),
        ("PGV (mm/s)", fact("pgv_m_s", 1e3, 1)),
        ("PGD (mm)", fact("pgd_m", 1e3, 2)),
        ("Time scale (compression)", fact("time_scale", 1.0, 2)),
        ("Duration (s)", fact("duration_s", 1.0, 2)),
    )
    return _table("Record (after processing: time scale, cut, PGA, baseline)", runs, rows)


def _design(run: RunData) -> Mapping[str, Any]:
    control = _mapping(run.profile.get("control"))
    return _mapping(_mapping(control.get("designs")).get(str(run.metadata.get("controller"))))


def _flat(data: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    flat: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, Mapping):
            flat |= _flat(value, f"{prefix}{key}.")
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def _parameter_text(value: Any) -> str:
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_parameter_text(v) for v in value) + "]"
    if isinstance(value, float):
        return f"{value:.6g}"
    return ABSENT if value is None else str(value)


def _sampling(run: RunData, key: str, control_key: str) -> Any:
    sampling = _mapping(run.metadata.get("sampling"))
    return sampling.get(key, _mapping(run.profile.get("control")).get(control_key))


def controller_table(runs: Sequence[RunData]) -> TextTable | None:
    """Each controlled run's controller: name, sampling, and its design's parameters from the run's profile."""
    controlled = [run for run in runs if not run.is_passive and run.metadata.get("controller")]
    if not controlled:
        return None
    rows: list[tuple[str, Cell]] = [
        ("Controller", lambda run: str(run.metadata.get("controller"))),
        ("Sample rate (Hz)", lambda run: _format(_sampling(run, "rate_hz", "rate_hz") or run.metadata.get("rate_hz"), 1.0, 0)),
        ("Transport delay (ms)", lambda run: _format(_sampling(run, "transport_delay_s", "transport_delay_s"), 1e3, 2)),
        ("Friction term", lambda run: _format(_sampling(run, "friction_source", "friction"))),
        ("Design stiffness scale", lambda run: _format(_sampling(run, "design_stiffness_scale", "design_stiffness_scale"),
                                                       1.0, 2)),
    ]
    keys = sorted({key for run in controlled for key in _flat(_design(run))})
    rows += [(f"design: {key}", _design_cell(key)) for key in keys]
    note = "Design parameters from each run's profile.yaml (control.designs.<controller>), SI (p1 in 1/s)."
    return _table("Controller", controlled, rows, note)


def _design_cell(key: str) -> Cell:
    return lambda run: _parameter_text(_flat(_design(run)).get(key)) if key in _flat(_design(run)) else ABSENT


def _timing(run: RunData) -> Mapping[str, Any]:
    return _mapping(_mapping(run.metadata.get("summary")).get("timing"))


def _micro(key: str) -> Cell:
    def cell(run: RunData) -> str:
        if key.startswith("lateness") and _timing(run).get("lockstep"):
            return "not measured"
        return _format(_timing(run).get(key), 1e6, 1)
    return cell


def timing_table(runs: Sequence[RunData]) -> TextTable | None:
    """Loop timing of the real-time runs: the summary the console printed, and the host check."""
    timed = [run for run in runs if _timing(run)]
    if not timed:
        return None
    rows: list[tuple[str, Cell]] = [
        ("Mode", lambda run: "lockstep (not real time)" if _timing(run).get("lockstep") else "real time"),
        ("Ticks", lambda run: _format(_timing(run).get("ticks"))),
        ("Lateness p50 (us)", _micro("lateness_median_s")),
        ("Lateness p99 (us)", _micro("lateness_p99_s")),
        ("Lateness max (us)", _micro("lateness_max_s")),
        ("Compute p50 (us)", _micro("compute_median_s")),
        ("Compute p99 (us)", _micro("compute_p99_s")),
        ("Compute p99.9 (us)", _micro("compute_p999_s")),
        ("Compute max (us)", _micro("compute_max_s")),
        ("CPU of the loop thread p50 (us)", _micro("cpu_median_s")),
        ("Missed periods", lambda run: _format(_timing(run).get("missed_periods"))),
        ("Stalls", lambda run: _format(_timing(run).get("stalls"))),
        ("Stalls ridden through", lambda run: _format(_timing(run).get("stalls_ridden_through"))),
        ("Longest stall (ms)", lambda run: _format(_timing(run).get("longest_stall_s"), 1e3, 1)),
        ("Stall budget (ms)", lambda run: _format(_timing(run).get("stall_budget_s"), 1e3, 1)),
        ("Pre-flight check", _preflight),
    ]
    note = ("Compute = wall-clock time of a tick from its start until its command is sent and its events handed "
            "on, as the console prints it at the end of a run; the compute_s column of signals.csv holds the same "
            "measurement, tick by tick. Missed periods = the whole periods beyond the first between the starts of "
            "two ticks, summed (the overrun column of signals.csv, tick by tick); a stall = a tick with at least "
            "one. In lockstep the loop waits for the rig, so lateness, missed periods and stalls are not measured.")
    return _table("Loop timing", timed, rows, note)


def _preflight(run: RunData) -> str:
    host = _mapping(_mapping(run.metadata.get("summary")).get("host_timing"))
    return str(host.get("verdict", ABSENT)) if host else ABSENT
