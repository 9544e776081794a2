"""The report's plain-text summary: runs, warnings, every table, and where the files are.

The same text goes to ``summary.txt`` (no width limit) and to the console, at the
console's width: tables then wrap their headings and split their columns into blocks
instead of breaking lines (:class:`~harness.report.text_table.TextTable`).
"""

from __future__ import annotations

import textwrap

from harness.report.result import ReportResult


def _run_lines(result: ReportResult, width: int | None) -> list[str]:
    lines = ["Runs:"]
    for run in result.runs:
        reason = f" ({run.metadata.get('trip_reason')})" if run.metadata.get("trip_reason") else ""
        lines += textwrap.wrap(f"{run.label}: {run.kind}, {run.outcome}{reason}, {run.n_rows} ticks", width or 10_000,
                               initial_indent="  ", subsequent_indent="    ")
        lines.append(f"    {run.path}")
    return lines


def summary_text(result: ReportResult, width: int | None = None) -> str:
    """Runs, warnings, the peak tables, the context tables and the output files, as plain text.

    Parameters
    ----------
    result : ReportResult
    width : int, optional
        Longest line for a table or a paragraph (the terminal's columns); None: no limit.
        Paths are never cut.
    """
    lines = _run_lines(result, width) + result.replay
    if result.warnings:
        lines.append("Warnings:")
        for warning in result.warnings:
            lines += textwrap.wrap(warning, width or 10_000, initial_indent="  ! ", subsequent_indent="    ")
    for table in result.tables:
        lines += ["", table.to_text(width)]
    for context in result.context:
        lines += ["", context.to_text(width)]
    lines += [
        "",
        f"Report: {result.html_path}",
        f"Plots: {len(result.plots)} PNG files, tables: {len(result.table_files)} CSV files in {result.out_dir}",
    ]
    return "\n".join(lines)
