"""Console output shared by the commands: progress, kernel compilation, loop timing, outcome."""

from __future__ import annotations

from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn


def progress_bar(console: Console, enabled: bool):
    return Progress(
        TextColumn("{task.description:<12}"), BarColumn(), TextColumn("{task.percentage:>5.1f} %"),
        TimeRemainingColumn(), console=console, transient=True, disable=not enabled,
    )


def compile_kernels(console: Console) -> None:
    """Compile the numba kernels up front; the spinner shows only when numba's cache does not hold them."""
    from harness.kernel_cache import kernels_cached
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
        f"{timing['cpu_median_s'] * 1e6:.1f} us); missed periods {timing['overruns']}"
    )
    if "stall_budget_s" in timing and not timing.get("lockstep", False):
        console.print(
            f"stalls ridden through {timing['stalls_ridden_through']}, longest gap between ticks "
            f"{timing['longest_stall_s'] * 1e3:.1f} ms (stall budget {timing['stall_budget_s'] * 1e3:.1f} ms)"
        )


#: Trips that, against a virtual rig in real time, come from host timing rather than the rig.
_HOST_TIMING_ON_A_VIRTUAL_RIG = ("sensor_stale", "actuator_status_stale")


def print_outcome(console: Console, session, virtual_rig: bool = False, weakened: tuple = ()) -> None:
    from harness.report.table_check import table_check
    from harness.safety.operator_detectors import HOST_TIMING_REMEDIES
    from harness.safety.weakening import summary

    style = {"completed": "green", "tripped": "bold red", "stopped": "yellow"}.get(session.outcome, "red")
    reason = f" ({escape(session.trip_reason)})" if session.trip_reason else ""
    lost = f", [bold red]but the record is incomplete[/]: {escape(session.record_problem)}; repeat the test for its data" \
        if session.record_problem else ""
    check = table_check(session.loop.table_record)  # the table against the record it was told (harness/safety/table_record.py)
    doubtful = ", [bold yellow]with a warning: the table check is marginal[/]" if check.verdict == "marginal" else ""
    console.print(f"outcome: [{style}]{session.outcome}[/]{reason}{lost}{doubtful}; run folder {session.run_path}")
    if session.loop.trip_detail and not (check.verdict == "mismatch" and session.trip_reason == "table_record_mismatch"):
        console.print(f"  {escape(session.loop.trip_detail)}", highlight=False)  # (the check's own line says it then)
    if check.line:
        check_style = {"mismatch": "bold red", "marginal": "bold yellow", "match": "green"}.get(check.verdict, "")
        text = escape(check.line)
        console.print(f"  [{check_style}]{text}[/]" if check_style else f"  {text}", highlight=False)
    realtime = not session.loop.timing.get("lockstep", False)
    if virtual_rig and realtime and session.trip_reason in _HOST_TIMING_ON_A_VIRTUAL_RIG:
        console.print(
            "  on a virtual rig this is host timing: the rig process was not scheduled in time to publish; "
            + HOST_TIMING_REMEDIES, highlight=False,
        )
    for line in session.loop.realtime_report:
        console.print(f"  {line}")
    if weakened:
        console.print(f"  [bold red]{escape(summary(weakened))}[/]", highlight=False)


def print_host_timing(console: Console):
    def show(timing) -> None:
        style = {"ok": "green", "marginal": "yellow"}.get(timing.verdict, "bold red")
        console.print(f"pre-flight: {escape(timing.summary()[:-len(timing.verdict)])}[{style}]{timing.verdict}[/]",
                      highlight=False)

    return show
