"""The live console's child process: draws a run's status from its shared block, at 4 Hz.

Started by :class:`harness.console.live.LiveConsole` as ``python -m harness.console.view``; its
standard output and error are the loop process's, and its panel goes to ``--fd`` (the
parent's console). It ignores SIGINT (Ctrl-C belongs to the loop's process, which stops or
trips the run), attaches to the status block read-only, and redraws until the status is
marked finished or its parent is gone; then it draws a last frame and exits. If the parent
died without closing the block, the child removes the block's file. It runs below the loop
(no real-time policy, niceness +10).

It imports only rich, numpy, :mod:`harness.loop.status` and :mod:`harness.console.live`, so it
starts in a fraction of a second.
"""

import signal

signal.signal(signal.SIGINT, signal.SIG_IGN)  # first of all: a Ctrl-C is for the loop's process
if hasattr(signal, "pthread_sigmask"):
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})  # the parent blocked it around the start

import argparse  # noqa: E402
import json  # noqa: E402
import os  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from collections.abc import Callable  # noqa: E402
from dataclasses import dataclass, field  # noqa: E402
from typing import TextIO  # noqa: E402

from rich.console import Console  # noqa: E402
from rich.live import Live  # noqa: E402

from harness.console.live import LiveConsole  # noqa: E402
from harness.loop.status import LoopStatus  # noqa: E402

#: How often the finished flag and the parent are checked between frames (s).
POLL_S = 0.02


#: Niceness added to this process: the loop's process comes first for the CPU.
NICENESS = 10


def yield_to_the_loop() -> None:
    """Run below the loop: an ordinary (not real-time) policy inherited from the parent is kept,
    a real-time one dropped, and the niceness raised by :data:`NICENESS`."""
    try:
        if os.sched_getscheduler(0) != os.SCHED_OTHER:
            os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        os.nice(NICENESS)
    except (AttributeError, OSError):
        pass


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The command line :func:`harness.console.live.view_command` builds."""
    parser = argparse.ArgumentParser(prog="python -m harness.console.view", description=__doc__.splitlines()[0])
    parser.add_argument("--status", required=True, help="the status block's file")
    parser.add_argument("--soft-limit-m", type=float, required=True)
    parser.add_argument("--hard-limit-m", type=float, required=True)
    parser.add_argument("--force-limit-n", type=float, required=True)
    parser.add_argument("--title", default="")
    parser.add_argument("--parent-pid", type=int, required=True, help="exit when the parent is no longer this process")
    parser.add_argument("--fd", type=int, default=1, help="file descriptor to draw on")
    parser.add_argument("--width", type=int, default=None, help="fixed width (columns); default: the terminal's")
    parser.add_argument("--color-system", default="none", help="standard, 256, truecolor, windows, auto or none")
    parser.add_argument("--force-terminal", action=argparse.BooleanOptionalAction, default=None,
                        help="draw as on a terminal (or, with --no-force-terminal, as on a file); default: detect")
    parser.add_argument("--refresh-hz", type=float, default=4.0)
    parser.add_argument("--timing-out", default=None, help="write start-up and render timing here (JSON) at exit")
    parser.add_argument("--alert", action="append", default=[], help="a red line of the panel (repeatable)")
    parser.add_argument("--note", action="append", default=[], help="a yellow line of the panel (repeatable)")
    return parser.parse_args(argv)


def open_output(fd: int) -> TextIO:
    """A text stream on ``fd``: this process's own standard output or error where it is one of them."""
    if fd == 1:
        return sys.stdout
    if fd == 2:
        return sys.stderr
    return os.fdopen(fd, "w", closefd=False)


def parent_alive(parent_pid: int) -> bool:
    """Whether this process's parent is still ``parent_pid`` (an orphan is re-parented)."""
    return os.getppid() == parent_pid


@dataclass
class FrameLog:
    """When the first frame was drawn (``time.time()``, s) and the thread CPU time of every frame (s)."""

    first_frame_wall_s: float | None = None
    render_cpu_s: list[float] = field(default_factory=list)

    def draw(self, draw_frame: Callable[[], None]) -> None:
        """Call ``draw_frame`` and log its thread CPU time."""
        started = time.thread_time()
        draw_frame()
        self.render_cpu_s.append(time.thread_time() - started)
        if self.first_frame_wall_s is None:
            self.first_frame_wall_s = time.time()

    def write(self, path: str, imported_wall_s: float) -> None:
        """The log and its median and maximum as JSON at ``path``."""
        ordered = sorted(self.render_cpu_s)
        summary = {
            "imported_wall_s": imported_wall_s,
            "first_frame_wall_s": self.first_frame_wall_s,
            "renders": len(ordered),
            "render_cpu_median_s": ordered[len(ordered) // 2] if ordered else None,
            "render_cpu_max_s": ordered[-1] if ordered else None,
            "render_cpu_s": self.render_cpu_s,
        }
        with open(path, "w", encoding="utf-8") as file:
            json.dump(summary, file)


def draw_until_finished(live: Live, status: LoopStatus, parent_pid: int, refresh_hz: float, frames: FrameLog) -> None:
    """Refresh ``live`` at ``refresh_hz`` (Hz) until the status is finished or the parent is gone."""
    period_s = 1.0 / refresh_hz
    next_frame = time.monotonic()
    while not status.finished and parent_alive(parent_pid):
        now = time.monotonic()
        if now >= next_frame:
            frames.draw(live.refresh)
            next_frame = max(next_frame + period_s, now)
        time.sleep(min(POLL_S, max(0.0, next_frame - time.monotonic())))


def main(argv: list[str] | None = None) -> int:
    """Draw until finished; 0 on a normal end, 2 if the status block cannot be opened."""
    imported_wall_s = time.time()
    args = parse_args(argv)
    try:
        status = LoopStatus.attach(args.status)
    except (OSError, ValueError) as err:
        print(f"live console: cannot open the status block: {err}", file=sys.stderr)
        return 2
    color_system = None if args.color_system == "none" else args.color_system
    console = Console(file=open_output(args.fd), width=args.width, color_system=color_system, force_terminal=args.force_terminal)
    view = LiveConsole(status, args.soft_limit_m, args.hard_limit_m, args.force_limit_n, args.title, console=console,
                       enabled=False, alerts=tuple(args.alert), notes=tuple(args.note))
    live = Live(view, console=console, auto_refresh=False, transient=False, redirect_stdout=False, redirect_stderr=False)
    frames = FrameLog()
    try:
        live.start()
        draw_until_finished(live, status, args.parent_pid, args.refresh_hz, frames)
        frames.draw(live.stop)  # the last frame
    except BrokenPipeError:  # nowhere left to draw
        os.dup2(os.open(os.devnull, os.O_WRONLY), args.fd)
    finally:
        parent_gone = not status.finished and not parent_alive(args.parent_pid)
        status.close()
        if parent_gone:
            try:
                os.unlink(args.status)  # its owner died without removing it
            except OSError:
                pass
        if args.timing_out:
            frames.write(args.timing_out, imported_wall_s)
    return 0


if __name__ == "__main__":
    yield_to_the_loop()
    sys.exit(main())
