"""Run a recorded run's ticks again: the same tick, loop and supervisor, fed from the run's log.

The replay builds what :func:`harness.runs.session.run_session` builds from a profile (controller,
compensation, friction estimator, supervisor with the table's record check, the tick with its trip
outputs, the loop with its phases and the table link a dry run or a run had), on a
:class:`~harness.replay.feed.ReplayBus` instead of the CAN bus, and runs the loop with the recorded
figures in place of its clock (:class:`~harness.replay.feed.ReplayFeed`). Nothing moves and nothing
is written: the tick has no recorder (its events are kept in memory) and no console.
"""

from __future__ import annotations

import dataclasses
import gc
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from harness.loop.tick_log import DT, MISSED, STALL, TickLog
from harness.profile import Profile
from harness.replay.feed import RecordedRequests, RecordEnded, ReplayBus, ReplayFeed
from harness.replay.recorded import RecordedRun, ReplayRefused


@dataclass
class ReplayedTick:
    """What the loop gave one replayed tick, and where its frames end in :attr:`ReplayBus.sent`."""

    t: float
    dt: float
    lateness_s: float
    stall_s: float
    missed: int
    sent_end: int
    state: int
    trip_reason: str


@dataclass
class ReplayResult:
    """The replayed loop: its ticks, every frame it sent, its events and how it ended."""

    ticks: list[ReplayedTick]
    sent: list[tuple[int, bytes]]
    #: Frames sent before the first tick's (none: the loop starts with the first tick).
    events: list[tuple[float, str, str, str]]
    outcome: str
    trip_reason: str
    #: The loop asked for a tick past the recorded ones (a what-if that outlives the run): it ended there.
    record_ended: bool = False
    #: The replay's own figures that differ from the recorded ones (dt, stall, missed periods): (tick, what).
    figure_differences: list[tuple[int, str]] = field(default_factory=list)
    #: The run folder ``--out`` wrote (None without it).
    out_path: Path | None = None


class _EventKeeper:
    """The tick's recorder in a replay: events are kept for the comparison; rows and events also go to a
    run folder when one is given (``--out``)."""

    def __init__(self, folder: Any = None) -> None:
        self.events: list[tuple[float, str, str, str]] = []
        self.folder = folder

    def record_row(self, values: np.ndarray) -> bool:
        return self.folder.record_row(values) if self.folder is not None else True

    def record_event(self, t: float, kind: str, name: str, detail: str) -> bool:
        self.events.append((t, kind, name, detail))
        return self.folder.record_event(t, kind, name, detail) if self.folder is not None else True


class _Observer(TickLog):
    """The loop's tick record in a replay: compares the loop's figures with the recorded ones and marks each tick's frames."""

    def __init__(self, recorded: np.ndarray, bus: ReplayBus, loop_state):
        self.recorded = recorded
        self.bus = bus
        self.loop_state = loop_state
        self.ticks: list[ReplayedTick] = []
        self.differences: list[tuple[int, str]] = []

    def start(self) -> None:
        """Nothing to mark: the replay's frames start with the first tick."""

    def note(
        self, t: float, dt: float, lateness_s: float, stall_s: float, missed: int, operator_stop: bool,
        operator_trip: bool, bus_gone: bool,
    ) -> None:
        """Keep the replayed tick; note where the loop's own dt, stall or missed periods differ from the recorded ones."""
        k = len(self.ticks)
        record = self.recorded[k]
        if not (dt == record[DT] and stall_s == record[STALL] and missed == record[MISSED]):
            for name, value, at in (("dt_s", dt, DT), ("stall_s", stall_s, STALL), ("missed_periods", missed, MISSED)):
                if not _same(float(value), float(record[at])):
                    self.differences.append((k, f"{name} {value!r} replayed, {float(record[at])!r} recorded"))
        state, reason = self.loop_state()
        self.ticks.append(ReplayedTick(t, dt, lateness_s, stall_s, int(missed), len(self.bus.sent), state, reason))


def _same(a: float, b: float) -> bool:
    return a == b or (math.isnan(a) and math.isnan(b))


def replay_profile(recorded: RecordedRun, overrides: tuple[str, ...] = (), overlay: str | None = None,
                   variant: str | None = None) -> Profile:
    """The run's profile as ``profile.yaml`` recorded it (overlays and ``--set`` included), with a what-if's changes over it."""
    from harness.profile import merge, parse_overrides

    data = dict(recorded.profile_data)
    if variant:
        raise ReplayRefused("--variant names a variant of a profile file; the run's profile is already resolved: "
                            "give the variant's values with --set or --overlay")
    if overlay is not None:
        from harness.profile import _read_overlay  # read and checked as load_profile reads an overlay

        layer, _ = _read_overlay(Path(overlay))
        data = merge(data, layer)
    if overrides:
        data = merge(data, parse_overrides(list(overrides)))
    return Profile.from_resolved(data)


def run_replay(recorded: RecordedRun, profile: Profile, out_dir: Path | None = None,
               changes: tuple[str, ...] = ()) -> ReplayResult:
    """Run ``recorded``'s ticks through the loop built from ``profile``.

    ``out_dir``: write the replayed ticks' rows and events there as a run folder (its ``signals.csv``
    and ``events.jsonl``, no CAN log), for ``harness report RUN_DIR out_dir``; ``changes`` name what a
    what-if changed (its metadata).

    Raises
    ------
    ReplayRefused
        When the run's receive times came from the frames' own timestamps (``can.timestamp_source: message``,
        a wall clock replay cannot read again), or its record is not the one the profile gives.
    """
    from drivers.link import HarnessLink
    from drivers.reader import HarnessReader
    from drivers.writer import HarnessWriter
    from harness.canbus.link import prepare
    from harness.control.factory import build_controller_for_rig, make_compensator, make_friction_estimator
    from harness.loop.runner import ControlLoop
    from harness.loop.tick import ControlTick
    from harness.model.warmup import warm_up
    from harness.realtime.host import Scheduling
    from harness.safety.supervisor import Supervisor

    can_config = profile.can
    if can_config.timestamp_source != "poll":
        raise ReplayRefused(f"{recorded.path}: its receive times were the frames' own timestamps (can.timestamp_source: "
                            f"{can_config.timestamp_source}), read against the wall clock: replay cannot read them again")
    warm_up()
    facts = recorded.facts
    rate_hz = profile.control.rate_hz
    period_s = 1.0 / rate_hz
    protocol, load = prepare(can_config)
    bus = ReplayBus(recorded.frames)
    reader = HarnessReader(bus, protocol, use_msg_timestamp=False, max_frames=can_config.max_frames_per_poll)  # type: ignore[arg-type]
    writer = HarnessWriter(bus, protocol, reader.health)  # type: ignore[arg-type]
    link = HarnessLink(bus, protocol, load, reader.health, reader, writer)  # type: ignore[arg-type]
    _continue_counters(writer, recorded, protocol)
    compensator = make_compensator(profile, controller=profile.control.controller)
    controller = build_controller_for_rig(profile, profile.control.controller)
    estimator = make_friction_estimator(profile)
    supervisor = Supervisor(profile.safety, period_s=period_s)
    duration_s = float(facts["duration_s"])
    if facts.get("table_check"):
        motion = _motion(recorded, profile)
        supervisor.table_record.expect(motion.velocity_m_s, motion.dt_s, duration_s, period_s)
    else:
        supervisor.table_record.ignore(str(facts.get("table_check_off", "")))
    table = _table_link(recorded)
    if table is not None:
        table.attach(link)
    keeper = _EventKeeper(_out_folder(out_dir, recorded, profile, changes) if out_dir is not None else None)
    heartbeat_every = max(1, round(rate_hz / can_config.heartbeat_rate_hz))
    estop_every = max(1, round(rate_hz / can_config.estop_rate_hz))
    tick = ControlTick(link, controller, estimator, supervisor, keeper, heartbeat_every, estop_every,
                       table.stop if table is not None else None, compensator)
    feed = ReplayFeed(recorded.ticks, recorded.loop_start_frame, bus, reader, period_s)
    feed.before_loop()
    observer = _Observer(recorded.ticks, bus, lambda: (int(supervisor.command.state), supervisor.command.trip_reason))
    # nothing of the host's real time: no priority, no pinning, no locked memory; the collector is kept off
    # below without the full collection the loop's start makes (it costs half a second on the frames held)
    realtime = dataclasses.replace(profile.loop.realtime, fifo_priority=0, cpu_affinity=(), lock_memory=False,
                                   disable_gc=False)
    loop_config = dataclasses.replace(profile.loop, realtime=realtime)
    run_is_linked = recorded.metadata.get("kind") == "run" and table is not None
    loop = ControlLoop(tick, loop_config, rate_hz, duration_s, feed.lockstep_wait if recorded.lockstep else None,
                       table.start if table is not None else None, None,
                       table_running=table.running if run_is_linked and table is not None else None,
                       scheduling=Scheduling(asked=0), tick_log=observer)
    loop.scheduler = feed  # type: ignore[assignment]
    loop.signals = RecordedRequests()  # type: ignore[assignment]
    feed.loop = loop
    record_ended = False
    collecting = gc.isenabled()
    gc.disable()
    try:
        result = loop.run()
        outcome, trip_reason = result.outcome, result.trip_reason
        if run_is_linked and table is not None and outcome != "tripped":
            table.stop(feed.elapsed_s)  # as the session does after the loop
    except RecordEnded:
        record_ended = True
        last = observer.ticks[-1] if observer.ticks else None
        outcome, trip_reason = "incomplete", last.trip_reason if last is not None else ""
    finally:
        if collecting:
            gc.enable()
        if keeper.folder is not None:
            keeper.folder.finish("stopped" if record_ended else outcome if outcome in _OUTCOMES else "error",
                                 trip_reason=trip_reason or None,
                                 summary={"record_start_t_s": _record_start(keeper.events)})
    return ReplayResult(observer.ticks, bus.sent, keeper.events, outcome, trip_reason, record_ended, observer.differences,
                        keeper.folder.path if keeper.folder is not None else None)


_OUTCOMES = ("completed", "stopped", "tripped")
#: What a replay's run folder takes over from the run's metadata (the rest describes the replay's own profile).
_KEPT_METADATA = ("controller", "rate_hz", "lockstep", "record", "overlay", "table_link")


def _out_folder(out_dir: Path, recorded: RecordedRun, profile: Profile, changes: tuple[str, ...]):
    """The run folder a replay writes (``--out``): the replayed rows and events, described by its own metadata."""
    from harness.recording import RunFolder
    from harness.signals.columns import CONTROL_ROW

    stroke, force = profile.safety.stroke, profile.safety.force
    metadata = {key: recorded.metadata[key] for key in _KEPT_METADATA if key in recorded.metadata}
    metadata.update(
        total_weight_N=profile.structure.total_weight_N, stroke_soft_limit_m=stroke.soft_limit_m,
        stroke_hard_limit_m=stroke.hard_limit_m, force_limit_N=force.max_force_N,
        replay_of=str(recorded.path.resolve()), what_if=list(changes), open_loop=bool(changes),
    )
    kind = recorded.metadata.get("kind", "dry-run")
    return RunFolder.create(out_dir, f"{profile.name}_replay", kind, profile.resolved_data(), CONTROL_ROW,
                            metadata=metadata, with_can=False).start()


def _record_start(events: list[tuple[float, str, str, str]]) -> float | None:
    """Loop time the replayed run entered RUNNING (s), None if it did not."""
    return next((t for t, kind, name, _ in events if kind == "state" and name == "RUNNING"), None)


def _continue_counters(writer: Any, recorded: RecordedRun, protocol: Any) -> None:
    """Start each sent message's rolling counter where the run's was at the loop's start.

    A counter advances only on a send the bus took, and only those reach ``can.log``: the frames of
    each message sent before the loop, modulo the counter's range, are where it stood.
    """
    from drivers.protocol.e2e import COUNTER_MODULO

    sent: dict[int, int] = {}
    for frame in recorded.frames[: recorded.loop_start_frame]:
        if not frame.rx:
            sent[frame.arbitration_id] = sent.get(frame.arbitration_id, 0) + 1
    for name in ("ACTUATOR_CMD", "HEARTBEAT", "ESTOP", "RIG_CONTROL", "DRIVE_RESET"):
        tx = writer.frame(name)
        tx.counter = sent.get(protocol[name].frame_id, 0) % COUNTER_MODULO


def _table_link(recorded: RecordedRun):
    """The table link the run had: a dry run's virtual table, a run's table controller (``table.link: can``), or none."""
    from harness.loop.table_link import CanTableLink

    kind = recorded.metadata.get("kind")
    if kind == "dry-run":
        return CanTableLink(recorded.lockstep)
    if recorded.metadata.get("table_link") == "can":
        return CanTableLink(False)
    return None


def _motion(recorded: RecordedRun, profile: Profile):
    """The record the table was told to play (the table's record check), refused if it is not the run's."""
    from harness.motions.summary import motion_facts
    from harness.runs.options import prepare_motion

    try:
        motion = prepare_motion(profile)
    except Exception as err:  # noqa: BLE001 - any failure to load it: the check cannot be run again
        raise ReplayRefused(f"{recorded.path}: the run's record cannot be loaded again ({err}); the table's record check "
                            "needs it (set HARNESS_RECORDS_DIR or --records-dir as for the run)") from err
    facts = recorded.metadata.get("record")
    if facts is not None and _plain(motion_facts(motion)) != _plain(facts):
        raise ReplayRefused(f"{recorded.path}: the record loaded again differs from the run's (metadata 'record'); "
                            "the table's record check would not be the run's")
    return motion


def _plain(value: Any) -> Any:
    import json

    from harness.recording.metadata import plain_data

    return json.loads(json.dumps(plain_data(value)))
