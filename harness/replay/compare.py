"""The replayed loop against the run: every frame bit for bit (exact replay), or the commands (what-if replay)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from harness.loop.tick_log import CAN_FRAMES, T
from harness.replay.engine import ReplayResult
from harness.replay.recorded import RecordedRun

#: Event kinds whose detail carries what the wall clock saw (where a stall's time went): compared by time and name only.
_CLOCK_DETAIL_NAMES = frozenset({"stall_past_budget"})


@dataclass
class Outcome:
    """How a run ended: outcome, reason, and the event that ended it (time, kind, name, detail), if any."""

    outcome: str
    reason: str
    event: tuple[float, str, str, str] | None

    def describe(self) -> str:
        text = self.outcome + (f" ({self.reason})" if self.reason else "")
        if self.event is not None:
            t, kind, name, detail = self.event
            text += f" at t = {t:.3f} s: {kind} {name}: {detail}"
        return text


def ending_event(events: Sequence[tuple[float, str, str, str]], reason: str) -> tuple[float, str, str, str] | None:
    """The first event named ``reason`` (the trip's fault, or the safe stop's), None if there is none."""
    if not reason:
        return None
    return next((event for event in events if event[2] == reason), None)


def recorded_events(recorded: RecordedRun) -> list[tuple[float, str, str, str]]:
    """The run's events that the loop's ticks recorded (those with a loop time), in order."""
    return [(float(e["t_s"]), str(e["kind"]), str(e["name"]), str(e["detail"])) for e in recorded.events
            if e.get("t_s") is not None]


def recorded_outcome(recorded: RecordedRun) -> Outcome:
    """The run's outcome, reason and ending event, from its metadata and events."""
    reason = str(recorded.metadata.get("trip_reason") or "")
    return Outcome(str(recorded.metadata.get("outcome")), reason, ending_event(recorded_events(recorded), reason))


def replayed_outcome(result: ReplayResult) -> Outcome:
    """The replayed loop's outcome, reason and ending event."""
    return Outcome(result.outcome, result.trip_reason, ending_event(result.events, result.trip_reason))


def recorded_sent(recorded: RecordedRun) -> tuple[list[list[tuple[int, bytes]]], list[tuple[int, bytes]]]:
    """The frames the run sent in each tick, and after its last tick (the closing disable)."""
    frames = recorded.frames
    bounds = [recorded.loop_start_frame, *(int(b) for b in recorded.ticks[:, CAN_FRAMES])]
    per_tick = [[(f.arbitration_id, f.data) for f in frames[a:b] if not f.rx] for a, b in zip(bounds, bounds[1:], strict=False)]
    after = [(f.arbitration_id, f.data) for f in frames[bounds[-1]:] if not f.rx]
    return per_tick, after


def replayed_sent(result: ReplayResult) -> tuple[list[list[tuple[int, bytes]]], list[tuple[int, bytes]]]:
    """The frames the replayed loop sent in each tick, and after its last."""
    starts = [0, *(tick.sent_end for tick in result.ticks)]
    per_tick = [result.sent[a:b] for a, b in zip(starts, starts[1:], strict=False)]
    return per_tick, result.sent[starts[-1]:]


def describe_frame(protocol: Any, frame: tuple[int, bytes]) -> str:
    """A frame as its message's signals, rolling counter and CRC, with its bytes."""
    frame_id, data = frame
    codec = protocol.by_id.get(frame_id)
    if codec is None:
        return f"ID 0x{frame_id:03X} [{data.hex(' ').upper()}]"
    values = [0.0] * len(codec.signal_names)
    codec.unpack(data, values)
    signals = ", ".join(f"{name} {value:.6g}" for name, value in zip(codec.signal_names, values, strict=True))
    counter, crc = data[1] & 0x0F if len(data) > 1 else -1, data[0] if data else -1
    return f"{codec.name} {signals}, counter {counter}, CRC 0x{crc:02X} [{data.hex(' ').upper()}]"


@dataclass
class ExactReport:
    """Exact replay against the run."""

    recorded_ticks: int
    replayed_ticks: int
    identical: int
    first_difference: tuple[int, list[tuple[int, bytes]], list[tuple[int, bytes]]] | None
    closing_identical: bool
    recorded: Outcome
    replayed: Outcome
    event_difference: str = ""
    figure_differences: list[tuple[int, str]] = field(default_factory=list)

    @property
    def identical_run(self) -> bool:
        """Every tick's frames, the closing frames, the events and the outcome are the run's."""
        return (self.first_difference is None and self.closing_identical and self.replayed_ticks == self.recorded_ticks
                and self.identical == self.recorded_ticks and not self.event_difference
                and (self.recorded.outcome, self.recorded.reason, self.recorded.event)
                == (self.replayed.outcome, self.replayed.reason, self.replayed.event)
                and not self.figure_differences)


def exact_report(recorded: RecordedRun, result: ReplayResult) -> ExactReport:
    """Compare every frame the replay sent with the run's, tick by tick, then the closing frames, events and outcome."""
    run_ticks, run_after = recorded_sent(recorded)
    replay_ticks, replay_after = replayed_sent(result)
    identical = 0
    first = None
    for k, (run_frames, replay_frames) in enumerate(zip(run_ticks, replay_ticks, strict=False)):
        if run_frames == replay_frames:
            identical += 1
        elif first is None:
            first = (k, run_frames, replay_frames)
    if first is None and len(replay_ticks) != len(run_ticks):
        k = min(len(replay_ticks), len(run_ticks))
        first = (k, run_ticks[k] if k < len(run_ticks) else [], replay_ticks[k] if k < len(replay_ticks) else [])
    return ExactReport(
        len(run_ticks), len(replay_ticks), identical, first, run_after == replay_after or result.record_ended,
        recorded_outcome(recorded), replayed_outcome(result), _event_difference(recorded_events(recorded), result.events),
        result.figure_differences,
    )


def _event_difference(run: list[tuple[float, str, str, str]], replay: list[tuple[float, str, str, str]]) -> str:
    """The first event that differs ("" if none): time, kind and name always, the detail where no wall clock is in it."""
    for k, (a, b) in enumerate(zip(run, replay, strict=False)):
        same = a[:3] == b[:3] and (a[2] in _CLOCK_DETAIL_NAMES or a[3] == b[3])
        if not same:
            return f"event {k + 1}: run {a}, replay {b}"
    if len(run) != len(replay):
        return f"the run recorded {len(run)} events of its ticks, the replay {len(replay)}"
    return ""


def exact_lines(report: ExactReport, recorded: RecordedRun, protocol: Any) -> list[str]:
    """What ``harness replay RUN_DIR`` prints."""
    lines = []
    if report.identical_run:
        lines.append(f"replayed {report.replayed_ticks} ticks: {report.identical} identical")
        lines.append(f"recorded outcome: {report.recorded.describe()}")
        lines.append(f"replayed outcome: {report.replayed.describe()}")
        return lines
    lines.append(f"replayed {report.replayed_ticks} ticks of {report.recorded_ticks}: {report.identical} identical")
    if report.first_difference is not None:
        k, run_frames, replay_frames = report.first_difference
        t = float(recorded.ticks[k, T]) if k < len(recorded.ticks) else math.nan
        lines.append(f"first differing tick: {k} (t = {t:.4f} s)")
        lines += [f"  run sent:    {describe_frame(protocol, f)}" for f in run_frames] or ["  run sent:    nothing"]
        lines += [f"  replay sent: {describe_frame(protocol, f)}" for f in replay_frames] or ["  replay sent: nothing"]
    if not report.closing_identical:
        lines.append("the frames sent after the last tick differ")
    if report.figure_differences:
        k, what = report.figure_differences[0]
        lines.append(f"the loop's figures differ from the recorded ones at tick {k}: {what} "
                     f"({len(report.figure_differences)} ticks)")
    if report.event_difference:
        lines.append(f"events differ: {report.event_difference}")
    lines.append(f"recorded outcome: {report.recorded.describe()}")
    lines.append(f"replayed outcome: {report.replayed.describe()}")
    return lines


@dataclass
class WhatIfReport:
    """A what-if replay (open loop) against the run's commands."""

    ticks: int
    first_divergence: tuple[int, float, tuple[float, float], tuple[float, float]] | None
    largest: tuple[float, float, int]
    recorded: Outcome
    replayed: Outcome
    record_ended: bool


def commands(protocol: Any, per_tick: list[list[tuple[int, bytes]]]) -> list[tuple[float, float] | None]:
    """Each tick's ACTUATOR_CMD as (force N, enable), None for a tick that sent none."""
    codec = protocol["ACTUATOR_CMD"]
    force_at, enable_at = codec.index("force"), codec.index("enable")
    values = [0.0] * len(codec.signal_names)
    out: list[tuple[float, float] | None] = []
    for frames in per_tick:
        command = next((data for frame_id, data in frames if frame_id == codec.frame_id), None)
        if command is None:
            out.append(None)
            continue
        codec.unpack(command, values)
        out.append((values[force_at], values[enable_at]))
    return out


def whatif_report(recorded: RecordedRun, result: ReplayResult, protocol: Any) -> WhatIfReport:
    """Where the changed loop's commands first differ from the run's, the largest difference, and how it would have ended."""
    run_commands = commands(protocol, recorded_sent(recorded)[0])
    replay_commands = commands(protocol, replayed_sent(result)[0])
    first = None
    largest = (0.0, math.nan, -1)
    for k, (a, b) in enumerate(zip(run_commands, replay_commands, strict=False)):
        if a == b:
            continue
        t = float(recorded.ticks[k, T])
        if first is None:
            first = (k, t, a or (math.nan, math.nan), b or (math.nan, math.nan))
        if a is not None and b is not None and abs(b[0] - a[0]) > largest[0]:
            largest = (abs(b[0] - a[0]), t, k)
    return WhatIfReport(len(replay_commands), first, largest, recorded_outcome(recorded), replayed_outcome(result),
                        result.record_ended)


def whatif_lines(report: WhatIfReport, changes: Sequence[str]) -> list[str]:
    """What ``harness replay RUN_DIR --set ...`` prints."""
    lines = [
        f"what-if replay with {', '.join(changes)}: OPEN LOOP. Every tick is given the frames the rig sent during the "
        "run; the rig did not answer the changed commands, so after the first difference the measurements are the "
        "run's, not what the changed commands would have produced.",
        f"replayed {report.ticks} ticks",
    ]
    if report.first_divergence is None:
        lines.append("commands: identical to the run's in every tick")
    else:
        k, t, (f_run, e_run), (f_new, e_new) = report.first_divergence
        lines.append(f"commands first differ at tick {k} (t = {t:.4f} s): run {f_run:.1f} N enable {e_run:g}, "
                     f"what-if {f_new:.1f} N enable {e_new:g}")
        size, t_largest, k_largest = report.largest
        if k_largest >= 0:
            lines.append(f"largest force difference: {size:.1f} N at tick {k_largest} (t = {t_largest:.4f} s)")
    lines.append(f"recorded outcome: {report.recorded.describe()}")
    if report.record_ended:
        lines.append(f"what-if: no trip within the recorded ticks (the run's record ended; last state: "
                     f"{report.replayed.reason or 'not tripped'})")
    else:
        lines.append(f"what-if outcome: {report.replayed.describe()}")
    tripped_earlier = _earlier(report)
    if tripped_earlier:
        lines.append(tripped_earlier)
    return lines


def _earlier(report: WhatIfReport) -> str:
    """One line comparing when the what-if ended with when the run did ("" when there is nothing to compare)."""
    a, b = report.recorded.event, report.replayed.event
    if b is None or report.replayed.outcome not in ("tripped", "stopped"):
        return ""
    if a is None:
        return f"the what-if would have {report.replayed.outcome} on {b[2]} at t = {b[0]:.3f} s, where the run did not"
    if b[0] < a[0]:
        return f"the what-if would have {report.replayed.outcome} {a[0] - b[0]:.3f} s earlier than the run, on {b[2]}"
    if b[0] > a[0]:
        return f"the what-if would have {report.replayed.outcome} {b[0] - a[0]:.3f} s later than the run, on {b[2]}"
    return f"the what-if would have {report.replayed.outcome} at the same time as the run, on {b[2]}"
