"""The live console of a run (rich): state, progress, stroke against its limits, force, S, loop health.

It reads a :class:`~harness.loop.runner.LoopStatus` that the loop overwrites in place;
rich's own refresh thread draws it a few times a second, so the loop never waits for
the terminal.
"""

from __future__ import annotations

from rich.console import Console, Group
from rich.live import Live
from rich.panel import Panel
from rich.table import Table
from rich.text import Text

from harness.loop.runner import LoopStatus
from harness.loop.timing import TimingStats

_STATE_STYLE = {"IDLE": "dim", "ARMED": "yellow", "RUNNING": "green", "STOPPING": "yellow", "DONE": "cyan", "TRIPPED": "bold red"}


def stroke_bar(stroke_m: float, soft_m: float, hard_m: float, width: int = 41) -> Text:
    """A centred bar from -hard to +hard with the soft limits marked and the stroke as a cursor."""
    text = Text()
    half = width // 2
    position = half + int(round(max(-1.0, min(1.0, stroke_m / hard_m)) * half))
    soft_cells = int(round(soft_m / hard_m * half))
    for i in range(width):
        offset = abs(i - half)
        style = "green" if offset < soft_cells else "yellow" if offset < half else "red"
        char = "█" if i == position else ("|" if offset == soft_cells else "─")
        text.append(char, style="bold white" if i == position else style)
    return text


class LiveConsole:
    """Context manager showing a run's status until it ends.

    Parameters
    ----------
    status : LoopStatus
    timing : TimingStats, optional
        For lateness percentiles (read by the refresh thread).
    soft_limit_m, hard_limit_m, force_limit_N : float
        For the bars.
    title : str
    console : Console, optional
    enabled : bool
        False prints nothing (tests, --quiet).
    """

    def __init__(self, status: LoopStatus, soft_limit_m: float, hard_limit_m: float, force_limit_N: float,
                 title: str, timing: TimingStats | None = None, console: Console | None = None, enabled: bool = True):
        self.status = status
        self.timing = timing
        self.soft, self.hard, self.force_limit = soft_limit_m, hard_limit_m, force_limit_N
        self.title = title
        self.console = console or Console()
        self.enabled = enabled
        self._live: Live | None = None

    def __rich__(self) -> Panel:
        s = self.status
        grid = Table.grid(padding=(0, 2))
        grid.add_column(style="bold")
        grid.add_column()
        style = _STATE_STYLE.get(s.state, "")
        state = Text(s.state, style=style)
        if s.trip_reason:
            state.append(f"  ({s.trip_reason})", style="red")
        grid.add_row("state", state)
        done = 0.0 if s.duration_s <= 0 else min(1.0, s.run_t_s / s.duration_s)
        grid.add_row("record", f"{s.run_t_s:6.1f} / {s.duration_s:.1f} s  ({done * 100:5.1f} %)")
        stroke = stroke_bar(s.stroke_m, self.soft, self.hard)
        stroke.append(f"  {s.stroke_m * 1e3:+7.2f} mm (soft {self.soft * 1e3:.0f}, hard {self.hard * 1e3:.0f})")
        grid.add_row("stroke x_b", stroke)
        force = stroke_bar(s.force_N, self.force_limit, self.force_limit)
        force.append(f"  {s.force_N / 1e3:+7.3f} kN (limit {self.force_limit / 1e3:.1f})")
        grid.add_row("force", force)
        grid.add_row("sliding var. S", f"{s.sliding_variable * 1e3:+8.3f} mm/s")
        p50 = p99 = 0.0
        if self.timing is not None:
            p50, p99 = self.timing.recent_percentiles()
        grid.add_row("loop lateness", f"p50 {p50 * 1e6:7.1f} us   p99 {p99 * 1e6:7.1f} us   overruns {s.overruns}")
        grid.add_row("frame errors", f"E2E rejects {s.e2e_rejects}   error frames {s.error_frames}   send failures {s.send_failures}")
        grid.add_row("last event", Text(s.last_event or "-", overflow="ellipsis", no_wrap=True))
        return Panel(grid, title=self.title, subtitle="Ctrl-C: safe stop   Ctrl-C twice: trip")

    def __enter__(self) -> "LiveConsole":
        if self.enabled:
            self._live = Live(self, console=self.console, refresh_per_second=4, transient=False)
            self._live.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        if self._live is not None:
            self._live.refresh()
            self._live.__exit__(*exc)
            self._live = None


def render_once(console: LiveConsole) -> Group:
    """The panel as a renderable (for tests and final summaries)."""
    return Group(console.__rich__())
