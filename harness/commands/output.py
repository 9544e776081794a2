"""Console output shared by the commands: the console itself, progress, kernel compilation, loop timing, outcome.

Output captured to a file or a pipe is as wide as its longest line (:func:`command_console`):
nothing is wrapped or cut at the 80 columns rich assumes when it sees no terminal. ``--quiet``
silences the console (``Console.quiet``) except for what :func:`print_always` prints: the
command's outcome line, its errors and its questions.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn

from harness.commands.options import STDOUT
from harness.signals.timing_counts import TimingCounts, stall_words

#: Width of a command's output when it is not a terminal (characters): no line is wrapped or cut, and
#: tables keep every column in one block. ``$COLUMNS`` still sets it when given.
CAPTURED_WIDTH = 10_000


class CommandConsole(Console):
    """The console of a command: a rich Console whose questions are asked even under ``--quiet``."""

    def input(self, prompt: Any = "", **kwargs: Any) -> str:
        """Ask, even under ``--quiet``; a Ctrl-C at the question stops the command before anything moves."""
        from harness.loop.operator import interruptible

        with speaking(self), interruptible("at the question before arming"):
            return super().input(prompt, **kwargs)


def command_console(stderr: bool = False, quiet: bool = False) -> Console:
    """The console a command prints to: at the terminal's width, or :data:`CAPTURED_WIDTH` when captured.

    Parameters
    ----------
    stderr : bool
        Print to standard error instead of standard output.
    quiet : bool
        ``--quiet``: print only what :func:`print_always` prints.
    """
    console = CommandConsole(stderr=stderr, quiet=quiet)
    if not console.is_terminal and "COLUMNS" not in os.environ:
        console.width = CAPTURED_WIDTH
    return console


@contextmanager
def speaking(console: Console) -> Iterator[Console]:
    """``console`` with ``--quiet`` lifted for the block."""
    quiet, console.quiet = console.quiet, False
    try:
        yield console
    finally:
        console.quiet = quiet


def print_always(console: Console, *objects: Any, **kwargs: Any) -> None:
    """Print even under ``--quiet``: the outcome line, an error, a product the command was asked for."""
    with speaking(console):
        console.print(*objects, **kwargs)


def json_console(console: Console, json_path: str | None) -> Console:
    """Where the rest of a command's output goes: ``console``, or standard error when ``--json -`` takes standard output."""
    if json_path != STDOUT:
        return console
    return command_console(stderr=True, quiet=console.quiet)


def write_json(path: str, document: Any) -> str:
    """Write ``document`` as indented JSON to the file ``path``, or to standard output for ``-``; where it went."""
    from harness.recording import strict_json  # here: the command line starts without the recording package

    text = strict_json.dumps(document, indent=2) + "\n"  # NaN as null: valid JSON for every parser
    if path == STDOUT:
        sys.stdout.write(text)
        sys.stdout.flush()
        return "standard output"
    Path(path).write_text(text, encoding="utf-8")
    return path


def progress_bar(console: Console, enabled: bool):
    return Progress(
        TextColumn("{task.description:<12}"), BarColumn(), TextColumn("{task.percentage:>5.1f} %"),
        TimeRemainingColumn(), console=console, transient=True, disable=not enabled,
    )


def compile_kernels(console: Console) -> None:
    """Compile the numba kernels up front; the spinner shows only when numba's cache does not hold them."""
    from harness.model.kernel_cache import kernels_cached
    from harness.model.warmup import warm_up

    if kernels_cached():  # loaded from the cache in about half a second: nothing to announce
        warm_up()
        return
    with console.status("compiling the integration kernels (after a change of their source, about a minute) ..."):
        warm_up()


def print_timing(console: Console, timing: dict, rate_hz: float) -> None:
    if not timing.get("ticks"):
        return
    console.print(
        f"loop at {rate_hz:g} Hz: {timing['ticks']} ticks, lateness median {timing['lateness_median_s'] * 1e6:.1f} us, "
        f"p99 {timing['lateness_p99_s'] * 1e6:.1f} us, max {timing['lateness_max_s'] * 1e6:.0f} us; compute median "
        f"{timing['compute_median_s'] * 1e6:.1f} us, p99 {timing['compute_p99_s'] * 1e6:.1f} us (CPU of the loop thread: median "
        f"{timing['cpu_median_s'] * 1e6:.1f} us)"
    )
    if "stall_budget_s" in timing and not timing.get("lockstep", False):
        counts = TimingCounts(timing["missed_periods"], timing["stalls"])
        console.print(
            f"loop stalls: {stall_words(counts, timing.get('gaps_past_budget', 0), timing['longest_stall_s'])} "
            f"(stall budget {timing['stall_budget_s'] * 1e3:.1f} ms; each past it a stall_past_budget event)"
        )


#: Trips that, against a virtual rig in real time, come from host timing rather than the rig.
_HOST_TIMING_ON_A_VIRTUAL_RIG = ("sensor_stale", "actuator_status_stale")


def print_outcome(console: Console, session, virtual_rig: bool = False, weakened: tuple = ()) -> None:
    """The outcome line (printed even under ``--quiet``, with any weakened safety setting), then its details."""
    from harness.report.table_check import table_check
    from harness.safety.operator_detectors import HOST_TIMING_REMEDIES
    from harness.safety.weakening import summary

    style = {"completed": "green", "tripped": "bold red", "stopped": "yellow"}.get(session.outcome, "red")
    reason = f" ({escape(session.trip_reason)})" if session.trip_reason else ""
    lost = f", [bold red]record lost[/]: {escape(session.record_problem)}; repeat the test for its data" \
        if session.record_problem else ""
    check = table_check(session.loop.table_record)  # the table against the record it was told (harness/safety/table_record.py)
    base = _base_sensor_sign(session, check.verdict)
    doubtful = {"marginal": ", [bold yellow]with a warning: the table check is marginal[/]",
                "waiting": ", [bold yellow]with a warning: the table check never judged[/]"}.get(check.verdict, "")
    if base is not None and base.warns:
        what = " moved against the table" if base.verdict == "against_table" else "'s sign was not judged"
        doubtful += f", [bold yellow]with a warning: the base-mat sensor{what}[/]"
    weakened_text = f"; [bold red]{escape(summary(weakened))}[/]" if weakened else ""
    print_always(console, f"outcome: [{style}]{session.outcome}[/]{reason}{lost}{doubtful}; run folder "
                 f"{escape(str(session.run_path))}{weakened_text}")
    if session.loop.trip_detail and not (check.verdict == "mismatch" and session.trip_reason == "table_record_mismatch"):
        console.print(f"  {escape(session.loop.trip_detail)}", highlight=False)  # (the check's own line says it then)
    if check.line:
        check_style = {"mismatch": "bold red", "marginal": "bold yellow", "waiting": "bold yellow",
                       "match": "green"}.get(check.verdict, "")
        text = escape(check.line)
        console.print(f"  [{check_style}]{text}[/]" if check_style else f"  {text}", highlight=False)
    if base is not None:
        console.print(f"  [{'bold yellow' if base.warns else 'green'}]{escape(base.line)}[/]", highlight=False)
    realtime = not session.loop.timing.get("lockstep", False)
    if virtual_rig and realtime and session.trip_reason in _HOST_TIMING_ON_A_VIRTUAL_RIG:
        console.print(
            "  on a virtual rig this is host timing: the rig process was not scheduled in time to publish; "
            + HOST_TIMING_REMEDIES, highlight=False,
        )
    for line in session.loop.realtime_report:
        console.print(f"  {line}")


def _base_sensor_sign(session, table_verdict: str):
    """The base-mat sensor's sign over the run's record (harness/report/sensor_signs.py), or None.

    None for a run with no record to judge by (an identification: the table check is off), for one the
    table check found playing something else (the table's own signal is then no reference), and for a
    run folder whose signals cannot be read (its record problem is reported on its own).
    """
    from harness.errors import HarnessError
    from harness.recording import load_run
    from harness.report.sensor_signs import run_base_sensor_sign

    if table_verdict not in ("match", "marginal", "waiting") or session.loop.record_start_t_s is None:
        return None
    try:
        return run_base_sensor_sign(load_run(session.run_path))
    except (OSError, HarnessError, KeyError, ValueError):
        return None


def print_host_timing(console: Console):
    def show(timing) -> None:
        style = {"ok": "green", "marginal": "yellow"}.get(timing.verdict, "bold red")
        console.print(f"pre-flight: {escape(timing.summary()[:-len(timing.verdict)])}[{style}]{timing.verdict}[/]",
                      highlight=False)

    return show
