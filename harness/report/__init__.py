"""Reports from run folders: peak tables, plots, a self-contained HTML page, a text summary.

Public API::

    build_report(run_paths, out_dir=None, progress=None) -> ReportResult
    summary_text(result) -> str
    peak_table(runs), pair_table(passive, controlled), comparison_table(a, b), table_text(table), table_csv(table)
"""

from harness.report.build import ReportResult, build_report, summary_text
from harness.report.figure import PlotFile
from harness.report.peaks import reduction_percent, run_peaks
from harness.report.tables import Table, comparison_table, pair_table, peak_table, table_csv, table_text

__all__ = [
    "PlotFile",
    "ReportResult",
    "Table",
    "build_report",
    "comparison_table",
    "pair_table",
    "peak_table",
    "reduction_percent",
    "run_peaks",
    "summary_text",
    "table_csv",
    "table_text",
]
