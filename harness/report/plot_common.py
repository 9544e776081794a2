"""What every report plot shares: its options, the record-time axis, legends, event marks, scale groups.

Display units: displacements and drifts in mm (or % of the story height), accelerations in
m/s^2, velocities in mm/s, forces in kN (or per unit of weight), loop timing in microseconds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes

from harness.recording.reader import RunData
from harness.report.figure import PlotFile
from harness.report.reference import record_start_s

EVENT_KINDS = ("trip", "fault", "interlock", "warning")
_MAX_EVENT_LABELS = 12
#: Peaks that differ by more than this factor get their own scale (the smaller ones would vanish).
SCALE_SPREAD = 5.0


@dataclass(frozen=True)
class PlotOptions:
    """Choices of the report's plots.

    Attributes
    ----------
    story_height_m : float, optional
        Story height (m): drifts are then drawn as a ratio of it (%), as papers show them.
    """

    story_height_m: float | None = None

    def drift_scale(self) -> tuple[float, str]:
        """Factor from a drift in m to the drawn unit, and the unit's axis text."""
        if self.story_height_m:
            return 100.0 / self.story_height_m, f"drift ratio (% of h = {self.story_height_m:g} m)"
        return 1e3, "drift (mm)"


PlotFunction = Callable[[Sequence[RunData], Path, PlotOptions], "PlotFile | None"]


def record_time(run: RunData) -> np.ndarray:
    """Time axis in record time, so runs of one record line up (a dry run arms and settles first)."""
    return run.signals["t_s"] - record_start_s(run)


def legend(ax: Axes, where: str = "right", source: Axes | None = None) -> None:
    """Legend outside ``ax`` (``"right"`` of it or ``"below"`` it) so it never hides data.

    ``source`` takes the entries from another axes (the panel that draws every run).
    """
    handles, labels = (source or ax).get_legend_handles_labels()
    if not handles:
        return
    if where == "below":
        ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, -0.16), framealpha=0.9)
    else:
        ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, framealpha=0.9)


def mark_events(ax: Axes, run: RunData, colour: str) -> None:
    """A dotted line at every event; a label at the first event of each name only, so labels never pile up."""
    marked = [e for e in run.events if e.get("kind") in EVENT_KINDS and isinstance(e.get("t_s"), (int, float))]
    start = record_start_s(run)
    labelled: set[str] = set()
    for event in marked:
        t = event["t_s"] - start
        ax.axvline(t, color=colour, ls=":", lw=1.2)
        name = f"{event.get('kind')}: {event.get('name')}"
        if name not in labelled and len(labelled) < _MAX_EVENT_LABELS:
            labelled.add(name)
            ax.annotate(name, xy=(t, 1.0), xycoords=("data", "axes fraction"), rotation=90, va="top", ha="right",
                        fontsize=9, color=colour,
                        bbox={"boxstyle": "round,pad=0.2", "fc": "white", "ec": colour, "alpha": 0.85})


def shade_interlocks(ax: Axes, run: RunData, colour: str) -> bool:
    """Shade the ticks where any interlock flag is set; True if there were any."""
    if not run.has("interlock_flags"):
        return False
    active = np.nan_to_num(run["interlock_flags"]) != 0
    if not active.any():
        return False
    band = ax.get_xaxis_transform()
    ax.fill_between(record_time(run), 0, 1, where=active, transform=band, color=colour, alpha=0.12, lw=0,
                    label=f"{run.label}: interlock active")
    return True


def peak_of(run: RunData, columns: Sequence[str]) -> float:
    """Largest finite |value| over the run's ``columns`` (0 if none)."""
    peaks = [np.nanmax(np.abs(run[c])) for c in columns if run.has(c) and np.isfinite(run[c]).any()]
    return float(max(peaks, default=0.0))


def small_runs(peaks: Sequence[float]) -> list[int]:
    """Indices of the runs whose peak is more than :data:`SCALE_SPREAD` times below the largest one."""
    largest = max(peaks, default=0.0)
    return [i for i, peak in enumerate(peaks) if 0.0 < peak < largest / SCALE_SPREAD]
