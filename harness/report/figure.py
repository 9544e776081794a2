"""Figure plumbing shared by the report plots: Agg canvas, sizes, colours, saving.

Figures are built on :class:`matplotlib.figure.Figure` with an explicit Agg canvas,
never through ``pyplot``: no display is needed, no global state is touched, and a
report can be built from any thread. Sizes are fixed in pixels (no tight bounding
box), so every PNG has exactly the size :func:`figure` was asked for.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from harness.recording.reader import RunData

DPI = 100
WIDTH_PX = 1200

#: Colours per run in order; passive runs are drawn in greys so the controlled runs stand out.
RUN_COLOURS = ("#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#e377c2", "#17becf")
PASSIVE_COLOUR = "#7f7f7f"
PASSIVE_SHADES = (PASSIVE_COLOUR, "#404040", "#b0b0b0", "#5f5f5f")

_STYLE: dict[str, Any] = {
    "font.size": 11,
    "axes.titlesize": 12,
    "axes.labelsize": 11,
    "legend.fontsize": 10,
    "axes.grid": True,
    "grid.alpha": 0.3,
}


@dataclass(frozen=True)
class PlotFile:
    """A written plot.

    Attributes
    ----------
    name : str
        Plot identifier, e.g. ``"drift"``.
    title : str
        Caption.
    path : Path
        The PNG file.
    width_px, height_px : int
        Its size in pixels.
    """

    name: str
    title: str
    path: Path
    width_px: int
    height_px: int


def figure(height_px: int, width_px: int = WIDTH_PX) -> Figure:
    """A new Agg-backed figure of exactly ``width_px`` x ``height_px`` pixels with the report style."""
    fig = Figure(figsize=(width_px / DPI, height_px / DPI), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def style() -> dict[Any, Any]:
    """Matplotlib rc settings for :func:`matplotlib.rc_context` (keys typed loosely: matplotlib's stubs want literals)."""
    return dict(_STYLE)


def save(fig: Figure, name: str, title: str, out_dir: Path) -> PlotFile:
    """Write ``fig`` to ``out_dir/<name>.png`` and describe it."""
    path = out_dir / f"{name}.png"
    fig.savefig(path, dpi=DPI, format="png")
    width, height = fig.canvas.get_width_height()
    return PlotFile(name, title, path, int(width), int(height))


def colours(runs: Sequence[RunData]) -> list[str]:
    """One colour per run: greys for the passive runs (the first one mid-grey), distinct colours for the others."""
    result = []
    controlled = passive = 0
    for run in runs:
        if run.is_passive:
            result.append(PASSIVE_SHADES[passive % len(PASSIVE_SHADES)])
            passive += 1
        else:
            result.append(RUN_COLOURS[controlled % len(RUN_COLOURS)])
            controlled += 1
    return result
