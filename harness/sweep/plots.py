"""The sweep's figures: IDA curves and fragility curves, as PNG files (matplotlib, Agg backend).

Display units: drifts and displacements in mm, PGA in g. The passive case is grey and
dashed; each design has its own colour, the same in every figure.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no display (a worker or a cluster node has none)
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from harness.sweep.curves import MIN_CASES_PER_LEVEL, NOT_MEANINGFUL, PASSIVE_DESIGN, Fragility, IdaCurve  # noqa: E402

MM_PER_M = 1000.0
DPI = 110


MARKERS = ("o", "s", "^", "D", "v", "P", "X", "*")
#: A log scale for drift when the largest median is this many times the smallest (controlled vs passive).
LOG_SPREAD = 20.0


def _style(index: int, design: str) -> dict:
    """Colour, line style, marker and width of a design: grey dashed for the passive case.

    Widths shrink and markers change from one design to the next, so that designs whose
    curves coincide (the sliding displacement of two designs that both hold the base still)
    still show each one.
    """
    if design == PASSIVE_DESIGN:
        return {"color": "0.45", "ls": "--", "marker": "o", "lw": 1.6, "ms": 4}
    return {"color": f"C{index % 10}", "ls": "-", "marker": MARKERS[index % len(MARKERS)],
            "lw": max(0.8, 3.0 - 0.7 * index), "ms": max(3.0, 7.0 - 1.2 * index)}


def _log_if_spread(ax, curves: Sequence[IdaCurve]) -> None:
    medians = np.concatenate([c.median for c in curves]) if curves else np.array([])
    positive = medians[np.isfinite(medians) & (medians > 0)]
    if positive.size and positive.max() / positive.min() > LOG_SPREAD:
        ax.set_yscale("log")


def _ida_panel(ax, curves: Sequence[IdaCurve], ylabel: str) -> None:
    for i, curve in enumerate(curves):
        style = _style(i - 1, curve.design)
        ax.plot(curve.pga_g, curve.median * MM_PER_M, label=curve.design, **style)
        if len(curve.pga_g) > 1:
            ax.fill_between(curve.pga_g, curve.p16 * MM_PER_M, curve.p84 * MM_PER_M, color=style["color"], alpha=0.12, lw=0)
    ax.set_xlabel("PGA (g)")
    ax.set_ylabel(ylabel)
    ax.set_xlim(left=0)
    _log_if_spread(ax, curves)
    if ax.get_yscale() == "linear":
        ax.set_ylim(bottom=0)
    ax.grid(True, which="both", alpha=0.3)


def plot_ida(drift: Sequence[IdaCurve], sliding: Sequence[IdaCurve], path: Path, title: str) -> Path:
    """Two panels, largest story drift and sliding displacement against PGA: median and 16-84 % band."""
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.6), constrained_layout=True)
    _ida_panel(axes[0], drift, "largest story drift (mm)")
    _ida_panel(axes[1], sliding, "sliding displacement |x_b| (mm)")
    axes[0].set_title("peak story drift: median, 16-84 % band")
    axes[1].set_title("peak sliding displacement: median, 16-84 % band")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(4, len(labels)), fontsize=8, frameon=False)
    fig.suptitle(title)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def _fragility_panel(ax, curves: Sequence[Fragility], title: str) -> None:
    top = max((float(np.max(c.pga_g)) for c in curves if len(c.pga_g)), default=1.0)
    grid = np.linspace(top / 200, top * 1.15, 200)
    for i, curve in enumerate(curves):
        style = _style(i - 1, curve.design)
        fit = f"theta {curve.theta_g:.3g} g, beta {curve.beta:.2f}" if np.isfinite(curve.theta_g) else curve.note
        if np.isfinite(curve.theta_g) and not curve.meaningful:
            fit += f" ({NOT_MEANINGFUL})"
        ax.plot(curve.pga_g, curve.share, ls="none", marker=style["marker"], ms=style["ms"] + 1, color=style["color"],
                label=f"{curve.design}: {fit}")
        line = style["ls"] if curve.meaningful else ":"  # a fit the counts do not support: dotted, and said
        ax.plot(grid, curve.fitted(grid), ls=line, lw=style["lw"], color=style["color"])
    if any(np.isfinite(curve.theta_g) and not curve.meaningful for curve in curves):
        title += (f"\ndotted: {NOT_MEANINGFUL} (a step, or fewer than {MIN_CASES_PER_LEVEL} cases a level;"
                  "\nfragility.csv's note says which)")
    ax.set_xlabel("PGA (g)")
    ax.set_ylabel("P(exceeding)")
    ax.set_ylim(-0.03, 1.03)
    ax.set_xlim(0, top * 1.15)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc="best")


def plot_fragility(panels: Sequence[tuple[str, Sequence[Fragility]]], path: Path, title: str) -> Path:
    """One panel per limit: observed share of cases exceeding it (points) and the lognormal fit (lines)."""
    fig, axes = plt.subplots(1, len(panels), figsize=(5.8 * len(panels), 4.6), constrained_layout=True, squeeze=False)
    for ax, (panel_title, curves) in zip(axes[0], panels, strict=True):
        _fragility_panel(ax, curves, panel_title)
    fig.suptitle(title)
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path
