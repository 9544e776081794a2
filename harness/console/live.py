"""The live console of a run (rich): state, progress, stroke and force against their limits, S, story drifts
and floor accelerations, loop health, and the last few events.

The loop writes a :class:`~harness.loop.status.LoopStatus` (shared memory) every tick. On a
terminal, :class:`LiveConsole` draws it from a child process (:mod:`harness.console.view`),
never from a thread of the loop's process: one render holds the interpreter lock for
milliseconds, which the loop would see as lateness. While the child draws, the loop's
process prints nothing.

Where the console is given and writes to something that is not a terminal (a file, a
``StringIO`` in tests, a pipe), nothing is drawn live: the final panel is printed once, in
process, when the run is over (as rich's ``Live`` did for such files).
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys

from rich.console import Console
from rich.panel import Panel
from rich.table import Table
from rich.text import Text

from drivers.protocol.protocol_values import FaultCode
from harness.loop.status import TABLE_VERDICT_NAMES, LoopStatus
from harness.paths import PROJECT_ROOT
from harness.signals.timing_counts import TimingCounts, stall_words

_STATE_STYLE = {"IDLE": "dim", "ARMED": "yellow", "RUNNING": "green", "STOPPING": "yellow", "DONE": "cyan", "TRIPPED": "bold red"}
#: How long :meth:`LiveConsole.__exit__` waits for the child to draw its last frame and exit (s).
CHILD_EXIT_TIMEOUT_S = 2.0
#: The child's refresh rate (Hz).
REFRESH_HZ = 4.0
#: Width of the stroke and force bars (characters): the panel fits an 80-column terminal.
BAR_WIDTH = 21


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


def fault_name(code: int) -> str:
    """The servo's fault code as a name: ``HEARTBEAT_WATCHDOG (2)``, or ``code 77`` for one the protocol does not name."""
    try:
        return f"{FaultCode(code).name} ({code})"
    except ValueError:
        return f"code {code} (not a FaultCode)"


def _state_text(status: LoopStatus) -> Text:
    state_name = status.state
    state = Text(state_name, style=_STATE_STYLE.get(state_name, ""))
    trip_reason = status.trip_reason
    if trip_reason:
        state.append(f"  ({trip_reason})", style="red")
    fault_code = status.fault_code
    if fault_code:
        state.append(f"  drive fault: {fault_name(fault_code)}", style="bold red")
    return state


def _bar_row(value: float, soft: float, hard: float, text: str, limits: str) -> Text:
    row = Text(text + "  ")
    row.append_text(stroke_bar(value, soft, hard, BAR_WIDTH))
    row.append(f"  {limits}")
    return row


def _story_rows(status: LoopStatus) -> list[tuple[str, str]]:
    """The ``drift mm`` and ``floor acc. m/s²`` rows, top story first; none before any story is published."""
    stories = status.stories()
    if not stories:
        return []
    top_down = list(enumerate(stories, start=1))[::-1]
    drifts = "  ".join(f"s{j} {drift * 1e3:+7.3f}" for j, (drift, _) in top_down)
    accelerations = "  ".join(f"f{j} {accel:+7.3f}" for j, (_, accel) in top_down)
    return [("drift mm", drifts), ("floor acc. m/s²", accelerations)]


#: Style of each table-check verdict (harness/safety/table_record.py).
_VERDICT_STYLE = {"MATCH": "green", "MARGINAL": "bold yellow", "MISMATCH": "bold red"}


def _table_check_text(status: LoopStatus) -> Text:
    """The table against its record: the verdict and the latest measures (the verdict alone before them)."""
    code = status.table_verdict
    name = TABLE_VERDICT_NAMES[code] if 0 <= code < len(TABLE_VERDICT_NAMES) else f"code {code}"
    if name == "OFF":
        return Text("off (no record to compare the table with)", style="dim")
    if name == "WAITING":
        return Text("waiting for enough record motion to judge", style="dim")
    text = Text(name.lower(), style=_VERDICT_STYLE.get(name, ""))
    text.append(f"  correlation {status.table_correlation:.2f}, delay {status.table_delay_s * 1e3:+.1f} ms, "
                f"amplitude {status.table_amplitude_ratio:.2f}")
    return text


def _events_text(status: LoopStatus) -> Text:
    lines = [line.strip() for line in status.recent_events()] or [status.last_event.strip() or "-"]
    return Text("\n".join(lines), overflow="ellipsis", no_wrap=True)


def record_time_text(run_t_s: float, duration_s: float) -> str:
    """The console's record line: record time out of the record, never past it.

    After the record the loop keeps running (its tail, then the force's ramp to zero): that
    time is shown apart, ``40.0 / 40.0 s (100.0 %), then 1.6 s after it``, not as record time.

    Parameters
    ----------
    run_t_s : float
        Time since RUNNING began (s).
    duration_s : float
        The record's duration (s).
    """
    played = min(run_t_s, duration_s) if duration_s > 0 else run_t_s
    done = 0.0 if duration_s <= 0 else played / duration_s
    text = f"{played:6.1f} / {duration_s:.1f} s  ({done * 100:5.1f} %)"
    after = run_t_s - duration_s
    return text + (f", then {after:.1f} s after it (tail, force ramp-down)" if duration_s > 0 and after >= 0.05 else "")


def run_title(profile_name: str, kind: str, metadata: dict, controller: str, rate_hz: float, lockstep: bool) -> str:
    """The live console's title: what the run is, e.g. ``nceer_4dof: identify actuator (blocked), ... at 500 Hz``.

    An identification's session is a dry run or run for its folder (``kind``), but the operator
    watches an identification: its metadata's ``identification`` entry names it.
    """
    identification = metadata.get("identification")
    what = kind
    if isinstance(identification, dict):
        condition = identification.get("condition")
        what = f"identify {identification.get('kind', '')}" + (f" ({condition})" if condition else "")
        what += " on the virtual rig" if kind == "dry-run" else ""
    return f"{profile_name}: {what}, {controller} at {rate_hz:g} Hz" + (" (lockstep)" if lockstep else "")


def status_panel(status: LoopStatus, soft_limit_m: float, hard_limit_m: float, force_limit_N: float, title: str,
                 alerts: tuple[str, ...] = (), notes: tuple[str, ...] = ()) -> Panel:
    """The console's panel for the current contents of ``status``.

    Parameters
    ----------
    status : LoopStatus
    soft_limit_m, hard_limit_m : float
        Stroke limits (m).
    force_limit_N : float
        Force limit (N).
    title : str
    alerts : tuple of str
        Lines shown in red above everything else for the whole run, e.g. the safety
        settings the command line weakened (harness/safety/weakening.py).
    notes : tuple of str
        Lines shown in yellow under the alerts for the whole run, e.g. where the virtual
        rig's truth differs from the design (harness/rig/truth.py).
    """
    s = status
    grid = Table.grid(padding=(0, 2))
    grid.add_column(style="bold", no_wrap=True)
    grid.add_column()
    for alert in alerts:
        grid.add_row(Text("WARNING", style="bold red"), Text(alert, style="bold red"))
    for note in notes:
        grid.add_row(Text("NOTE", style="bold yellow"), Text(note, style="yellow"))
    grid.add_row("state", _state_text(s))
    grid.add_row("record", record_time_text(s.run_t_s, s.duration_s))
    grid.add_row("table check", _table_check_text(s))
    grid.add_row("stroke x_b", _bar_row(s.stroke_m, soft_limit_m, hard_limit_m, f"{s.stroke_m * 1e3:+7.2f} mm",
                                        f"±{soft_limit_m * 1e3:.0f} soft, ±{hard_limit_m * 1e3:.0f} hard"))
    grid.add_row("force", _bar_row(s.force_N, force_limit_N, force_limit_N, f"{s.force_N / 1e3:+7.3f} kN",
                                   f"±{force_limit_N / 1e3:.1f} kN limit"))
    grid.add_row("sliding var. S", f"{s.sliding_variable * 1e3:+8.3f} mm/s")
    for name, values in _story_rows(s):
        grid.add_row(name, values)
    p50, p99 = s.lateness_percentiles()
    grid.add_row("loop lateness", f"p50 {p50 * 1e6:7.1f} us   p99 {p99 * 1e6:7.1f} us")
    grid.add_row("loop stalls", stall_words(TimingCounts(s.missed_periods, s.stalls), s.gaps_past_budget, s.longest_stall_s))
    grid.add_row("frame errors", f"E2E rejects {s.e2e_rejects}   error frames {s.error_frames}   send failures {s.send_failures}")
    grid.add_row("events", _events_text(s))
    return Panel(grid, title=title, subtitle="Ctrl-C: safe stop   Ctrl-C twice: trip")


def _terminal_fd(console: Console) -> int | None:
    """The file descriptor ``console`` writes to, if it is a real terminal; else None."""
    try:
        fd = console.file.fileno()
    except (AttributeError, OSError, ValueError):  # io.UnsupportedOperation is an OSError and a ValueError
        return None
    return fd if os.isatty(fd) else None


def _output_fd(console: Console) -> int | None:
    """The file descriptor ``console`` writes to (terminal or not); None if it has none."""
    try:
        return console.file.fileno()
    except (AttributeError, OSError, ValueError):
        return None


def _explicit_width(console: Console, fd: int) -> int | None:
    """``console``'s width if it differs from what the child would find on ``fd`` (columns); else None.

    A console following its terminal's width is left to the child, which then follows resizes too.
    """
    try:
        columns = os.get_terminal_size(fd).columns
    except OSError:
        return console.width
    return None if console.width == columns else console.width


@contextlib.contextmanager
def _sigint_blocked():
    """Block SIGINT in this thread for the duration (a Ctrl-C meanwhile is delivered afterwards).

    A child started meanwhile inherits the blocked mask through ``exec``, so it cannot be
    interrupted before it has set SIGINT to be ignored (its first statement) and unblocked it.
    """
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    previous = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, previous)


def view_command(status_path: str, soft_limit_m: float, hard_limit_m: float, force_limit_N: float, title: str, *,
                 parent_pid: int, fd: int = 1, width: int | None = None, color_system: str | None = None,
                 force_terminal: bool | None = None, timing_out: str | None = None,
                 alerts: tuple[str, ...] = (), notes: tuple[str, ...] = ()) -> list[str]:
    """The command line of the console's child process (:mod:`harness.console.view`).

    Parameters
    ----------
    status_path : str
        The status block's file.
    soft_limit_m, hard_limit_m, force_limit_N : float
        Limits for the bars (m, m, N).
    title : str
    parent_pid : int
        The child exits (after a last frame) when its parent is no longer this process.
    fd : int
        File descriptor to draw on (inherited).
    width : int, optional
        Fixed width in columns; None follows the terminal.
    color_system : str, optional
        rich's colour system (``standard``, ``256``, ``truecolor``, ``windows``); None for no colour.
    force_terminal : bool, optional
        True draws as on a terminal (cursor movement) even if ``fd`` is not one, False as on a
        file; None lets the child detect it.
    timing_out : str, optional
        Write the child's start-up and render timing (JSON) here when it exits.
    alerts : tuple of str
        Red lines of the panel (:func:`status_panel`).
    notes : tuple of str
        Yellow lines of the panel (:func:`status_panel`).
    """
    command = [sys.executable, "-m", "harness.console.view", f"--status={status_path}",
               f"--soft-limit-m={soft_limit_m!r}", f"--hard-limit-m={hard_limit_m!r}", f"--force-limit-n={force_limit_N!r}",
               f"--title={title}", f"--parent-pid={parent_pid}", f"--fd={fd}", f"--color-system={color_system or 'none'}",
               f"--refresh-hz={REFRESH_HZ!r}"]
    if width is not None:
        command.append(f"--width={width}")
    if force_terminal is not None:
        command.append("--force-terminal" if force_terminal else "--no-force-terminal")
    if timing_out is not None:
        command.append(f"--timing-out={timing_out}")
    command += [f"--alert={alert}" for alert in alerts]
    command += [f"--note={note}" for note in notes]
    return command


def view_environment() -> dict[str, str]:
    """The child's environment: this one, with this checkout first on ``PYTHONPATH``."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, (str(PROJECT_ROOT), env.get("PYTHONPATH"))))
    return env


class LiveConsole:
    """Context manager showing a run's status until it ends, drawn by a child process.

    On entry, if enabled and the console is the default one or writes to a real terminal,
    a child process (:mod:`harness.console.view`) attaches to the status block and draws
    the panel at 4 Hz on the same terminal. On exit the status is marked finished, the
    child draws its last frame and exits (killed after :data:`CHILD_EXIT_TIMEOUT_S`), and
    the status block is closed: **the LiveConsole owns the block for the run** and closes
    it in ``__exit__`` whether enabled or not (the status stays readable afterwards).

    A given console that does not write to a terminal gets no live display: the final
    panel is printed into it once, at exit. If the child cannot be started, one plain line
    says so and nothing is drawn live (never in process: that would disturb the loop).

    Parameters
    ----------
    status : LoopStatus
    soft_limit_m, hard_limit_m, force_limit_N : float
        For the bars (m, m, N).
    title : str
    console : Console, optional
        Where to draw; the default Console (standard output) if None.
    enabled : bool
        False shows nothing (tests, --quiet).
    alerts : tuple of str
        Red lines shown on the panel for the whole run (the safety settings the command line weakened).
    notes : tuple of str
        Yellow lines shown under them for the whole run (where the virtual rig's truth differs from the design).
    """

    def __init__(self, status: LoopStatus, soft_limit_m: float, hard_limit_m: float, force_limit_N: float,
                 title: str, console: Console | None = None, enabled: bool = True,
                 alerts: tuple[str, ...] = (), notes: tuple[str, ...] = ()):
        self.status = status
        self.alerts = tuple(alerts)
        self.notes = tuple(notes)
        self.soft, self.hard, self.force_limit = soft_limit_m, hard_limit_m, force_limit_N
        self.title = title
        self.console_given = console is not None
        self.console = console or Console()
        self.enabled = enabled
        #: The child process drawing the panel, while it runs.
        self.child: subprocess.Popen | None = None
        self._print_final_panel = False

    def __rich__(self) -> Panel:
        return status_panel(self.status, self.soft, self.hard, self.force_limit, self.title, self.alerts, self.notes)

    def wants_child(self) -> bool:
        """Whether the panel is drawn live by a child: enabled, and the default console or a terminal."""
        if not self.enabled:
            return False
        fd = _output_fd(self.console) if not self.console_given else _terminal_fd(self.console)
        return fd is not None

    def __enter__(self) -> LiveConsole:
        if not self.enabled:
            return self
        if self.wants_child():
            self.child = self._start_child()
        else:
            self._print_final_panel = True
        return self

    def _start_child(self) -> subprocess.Popen | None:
        """Start the drawing child on the console's file descriptor; None (and one line) if it cannot start."""
        console = self.console
        fd = _output_fd(console)
        if fd is None:
            console.print("live console unavailable (the console has no file descriptor); the run goes on without it",
                          markup=False, highlight=False)
            return None
        command = view_command(
            self.status.path, self.soft, self.hard, self.force_limit, self.title, parent_pid=os.getpid(), fd=fd,
            width=_explicit_width(console, fd), color_system=console.color_system, force_terminal=console.is_terminal,
            alerts=self.alerts, notes=self.notes,
        )
        try:
            console.file.flush()
            with _sigint_blocked():
                return subprocess.Popen(
                    command, stdin=subprocess.DEVNULL, stdout=None, stderr=None, pass_fds=(fd,) if fd > 2 else (),
                    start_new_session=False, env=view_environment(),
                )
        except (OSError, ValueError, subprocess.SubprocessError) as err:
            console.print(f"live console unavailable ({err}); the run goes on without it", markup=False, highlight=False)
            return None

    def __exit__(self, *exc) -> None:
        try:
            self.status.finished = True
            if self.child is not None:
                self._stop_child()
            elif self._print_final_panel:
                self._print_panel()
        finally:
            self.status.close()

    def _print_panel(self) -> None:
        """Print the final panel here, as wide as its content needs (a captured console is far wider than that)."""
        panel = self.__rich__()
        self.console.print(panel, width=min(self.console.width, self.console.measure(panel).maximum))

    def _stop_child(self) -> None:
        """Wait for the child's last frame; kill it after the timeout; print the panel here if it died early."""
        child, self.child = self.child, None
        if child is None:
            return
        try:
            code = child.wait(timeout=CHILD_EXIT_TIMEOUT_S)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
            self.console.show_cursor(True)
            self.console.print(f"live console did not finish within {CHILD_EXIT_TIMEOUT_S:g} s; stopped it",
                               markup=False, highlight=False)
            return
        if code != 0:
            self.console.show_cursor(True)
            self.console.print(f"live console exited early (status {code}); the final status:", markup=False, highlight=False)
            self._print_panel()
