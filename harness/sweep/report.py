"""A sweep's report: summary tables as CSV and Markdown, IDA and fragility curves as CSV and PNG.

``harness sweep STUDY.yaml --report DIR`` writes it after the sweep, ``harness sweep --summarize
RESULTS --report DIR`` from a results folder at any time (the study's report settings are
in its ``sweep.json``). Files:

==========================  =========================================================
``summary.csv``             median, min and max % reduction per design and record (and all)
``peaks.csv``               median peak responses per design, beside the passive case
``summary.md``              both tables in Markdown
``ida.csv``, ``ida.png``    largest drift and sliding displacement against PGA, per design
``fragility.csv``           exceedance counts per level and the lognormal fit per design
``fragility.png``           the fragility curves (stroke limit, and drift limit if given)
==========================  =========================================================

The curves need two PGA levels at least; a study of one level gets the tables only.
"""

from __future__ import annotations

import csv
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from harness.sweep.curves import design_curves, design_fragilities
from harness.sweep.plots import plot_fragility, plot_ida
from harness.sweep.rows import MAX_DRIFT, SLIDING
from harness.sweep.summary import (
    SHORT_PEAKS,
    SHORT_REDUCTION,
    Columns,
    ValueTable,
    design_labels,
    peaks_by_design,
    reduction_by_design,
)


@dataclass(frozen=True)
class ReportSettings:
    """What the report needs of the study: its name, grid axes and fragility limits (m)."""

    study: str
    grid_keys: list[str] = field(default_factory=list)
    stroke_limit_m: float | None = None
    drift_limit_m: float | None = None

    def to_json(self) -> dict[str, Any]:
        return asdict(self)

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> ReportSettings:
        return cls(**{key: data[key] for key in ("study", "grid_keys", "stroke_limit_m", "drift_limit_m") if key in data})


def write_table_csv(table: ValueTable, path: Path) -> Path:
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(table.header)
        writer.writerows(table.rows)
    return path


def _ida_rows(name: str, curves) -> list[list[Any]]:
    return [[name, c.design, level, n, med, lo, hi]
            for c in curves for level, n, med, lo, hi in zip(c.pga_g, c.count, c.median, c.p16, c.p84, strict=True)]


def write_ida(columns: Columns, labels: np.ndarray, settings: ReportSettings, folder: Path) -> list[Path]:
    """``ida.csv`` and ``ida.png`` (largest story drift and sliding displacement against PGA)."""
    drift, sliding = design_curves(columns, labels, MAX_DRIFT), design_curves(columns, labels, SLIDING)
    header = ["response", "design", "pga_g", "cases", "median", "p16", "p84"]
    table = ValueTable("IDA", header, _ida_rows(MAX_DRIFT, drift) + _ida_rows(SLIDING, sliding))
    return [write_table_csv(table, folder / "ida.csv"),
            plot_ida(drift, sliding, folder / "ida.png", f"{settings.study}: incremental dynamic analysis")]


def write_fragility(columns: Columns, labels: np.ndarray, settings: ReportSettings, folder: Path) -> list[Path]:
    """``fragility.csv`` and ``fragility.png`` for the stroke limit and, if given, the drift limit."""
    panels = []
    if settings.stroke_limit_m is not None:
        title = f"sliding displacement > {settings.stroke_limit_m * 1e3:g} mm (stroke limit)"
        panels.append((SLIDING, settings.stroke_limit_m, title))
    if settings.drift_limit_m is not None:
        panels.append((MAX_DRIFT, settings.drift_limit_m, f"largest story drift > {settings.drift_limit_m * 1e3:g} mm"))
    if not panels:
        return []
    curves = [(title, design_fragilities(columns, labels, name, limit)) for name, limit, title in panels]
    rows = [[name, limit, c.design, level, n, k, c.theta_g, c.beta, c.note]
            for (name, limit, _), (_, found) in zip(panels, curves, strict=True)
            for c in found for level, n, k in zip(c.pga_g, c.count, c.exceeded, strict=True)]
    header = ["response", "limit_m", "design", "pga_g", "cases", "exceeded", "theta_g", "beta", "note"]
    return [write_table_csv(ValueTable("fragility", header, rows), folder / "fragility.csv"),
            plot_fragility(curves, folder / "fragility.png", f"{settings.study}: fragility, lognormal fit")]


def write_report(columns: Columns, settings: ReportSettings, folder: Path) -> tuple[list[Path], list[ValueTable]]:
    """Every file of the report into ``folder`` (created); returns the files and the two short summary tables."""
    folder.mkdir(parents=True, exist_ok=True)
    labels = design_labels(columns, settings.grid_keys)
    tables = [reduction_by_design(columns, settings.grid_keys), peaks_by_design(columns, settings.grid_keys)]
    files = [write_table_csv(tables[0], folder / "summary.csv"), write_table_csv(tables[1], folder / "peaks.csv")]
    short = [tables[0].select(SHORT_REDUCTION), tables[1].select(SHORT_PEAKS)]
    markdown = "\n\n".join(f"### {table.title}\n\n{table.to_markdown()}" for table in short)
    (folder / "summary.md").write_text(markdown + "\n")
    files.append(folder / "summary.md")
    pga = columns["pga_g"]
    if np.unique(pga[np.isfinite(pga)]).size >= 2:  # a curve against PGA needs two levels at least
        files += write_ida(columns, labels, settings, folder)
        files += write_fragility(columns, labels, settings, folder)
    return files, short


def load_settings(results: Path) -> ReportSettings:
    """The report settings a sweep saved in ``results/sweep.json``."""
    data = json.loads((results / "sweep.json").read_text())
    return ReportSettings.from_json(data.get("report", {"study": data.get("study", results.name)}))
