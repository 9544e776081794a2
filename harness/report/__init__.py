"""Reports from run folders and the peak tables of every command: tables, plots, one HTML page, a summary.

Public API::

    build_report(run_paths, out_dir=None, progress=None, labels=None, plot_options=None) -> ReportResult
    summary_text(result, width=None) -> str
    distinct_labels(runs) -> list[str]       # labels from what differs between runs
    PeakTable: .to_rich(), .to_text(), .to_html(), .to_csv()
    reduction_table(passive_peaks, controlled_peaks, title, labels)   # the consoles' table
    runs_table(runs), pair_table(passive, controlled), comparison_table(a, b)

Names are imported on first use, so a command that only prints a peak table (``harness
simulate``) does not load matplotlib.
"""

from __future__ import annotations

from importlib import import_module
from typing import Any

#: Public name -> the module defining it.
_EXPORTS = {
    "PeakRow": "harness.report.peak_table",
    "PeakTable": "harness.report.peak_table",
    "PlotFile": "harness.report.figure",
    "ReportResult": "harness.report.result",
    "build_report": "harness.report.build",
    "comparison_table": "harness.report.tables",
    "distinct_labels": "harness.report.labels",
    "pair_table": "harness.report.tables",
    "reduction_table": "harness.report.tables",
    "runs_table": "harness.report.tables",
    "summary_text": "harness.report.summary",
}

__all__ = [
    "PeakRow",
    "PeakTable",
    "PlotFile",
    "ReportResult",
    "build_report",
    "comparison_table",
    "distinct_labels",
    "pair_table",
    "reduction_table",
    "runs_table",
    "summary_text",
]


def __getattr__(name: str) -> Any:
    """Import a public name from its module on first use (PEP 562)."""
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(_EXPORTS[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
