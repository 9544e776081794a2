"""The peak-response table of SPEC 5 as a rich Table: passive beside controlled, with % reduction."""

from __future__ import annotations

from collections.abc import Mapping

from rich.table import Table

from harness.peaks import reduction_pct


def _fmt(value: float, scale: float, digits: int) -> str:
    return f"{value * scale:.{digits}f}"


def peak_table(passive: Mapping, controlled: Mapping | None, title: str, labels: tuple[str, str] = ("passive", "controlled")) -> Table:
    """Rows per story and for the base mat; columns passive, controlled and % reduction.

    Parameters
    ----------
    passive, controlled : mapping
        Peaks as returned by :func:`harness.peaks.peak_responses`; ``controlled`` may be None.
    title : str
    labels : tuple of str
        Column names of the two cases (e.g. ("simulate", "dry run")).
    """
    table = Table(title=title, title_justify="left")
    table.add_column("response", style="bold")
    table.add_column("unit")
    table.add_column(labels[0], justify="right")
    if controlled is not None:
        table.add_column(labels[1], justify="right")
        table.add_column("reduction %", justify="right")

    def row(name: str, unit: str, p: float, c: float | None, scale: float, digits: int) -> None:
        cells = [name, unit, _fmt(p, scale, digits)]
        if controlled is not None:
            reduction = reduction_pct(p, c)
            cells += [_fmt(c, scale, digits), "-" if reduction is None else f"{reduction:.1f}"]
        table.add_row(*cells)

    n = len(passive["drift_m"])
    for j in range(n, 0, -1):
        c_drift = controlled["drift_m"][j - 1] if controlled else None
        row(f"story {j} drift", "mm", passive["drift_m"][j - 1], c_drift, 1e3, 3)
    for j in range(n, 0, -1):
        c_acc = controlled["floor_acceleration_m_s2"][j - 1] if controlled else None
        row(f"floor {j} abs. acceleration", "m/s²", passive["floor_acceleration_m_s2"][j - 1], c_acc, 1.0, 3)
    c = controlled or {}
    row("base mat acceleration", "m/s²", passive["base_acceleration_m_s2"], c.get("base_acceleration_m_s2"), 1.0, 3)
    row("sliding displacement x_b", "mm", passive["sliding_displacement_m"], c.get("sliding_displacement_m"), 1e3, 2)
    cells = ["peak force", "% weight", f"{passive['peak_force_pct_weight']:.2f}"]
    if controlled is not None:
        cells += [f"{controlled['peak_force_pct_weight']:.2f}", ""]
    table.add_row(*cells)
    return table
