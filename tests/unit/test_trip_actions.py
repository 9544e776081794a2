"""A trip leaves the harness as frames on the bus: disable, then ESTOP, then the table stop, in the trip tick.

The E-stop panel's heartbeat: no arming without it, ``estop_lost`` when it stops, and only
the panel's own frames (source 3) count. Asserted on frames decoded from the bus, with the
bench of tests/unit/test_control_tick.py.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from drivers.protocol.busload import bus_load, frame_bits
from drivers.protocol.codec import load_protocol
from drivers.protocol.protocol_values import EstopSource, RigCommand
from harness.canbus.config import CanConfig
from harness.errors import ProfileError
from harness.loop.trip_outputs import SUPERVISOR_SOURCE, TripOutputs
from harness.profile import load_profile
from harness.safety.checks import CHECK_NAMES
from harness.safety.config import EStopConfig, TripActionsConfig, check_config
from harness.safety.lifecycle import ArmRefused, State
from tests.unit.test_control_tick import PERIOD_S, Bench

PROTOCOL = load_protocol()
ESTOP_ID = PROTOCOL["ESTOP"].frame_id
CMD_ID = PROTOCOL["ACTUATOR_CMD"].frame_id
CTRL_ID = PROTOCOL["RIG_CONTROL"].frame_id
STOP_TABLE = RigCommand.STOP_TABLE
#: The rig-side node of these tests echoes the command as the measured force (a force source):
#: the tracking check expects no velocity feedback from it.
SAFETY = load_profile(None, overrides=["safety.force.velocity_feedback_Ns_per_m=0"]).safety


class Wire:
    """What the rig side received, in order: (frame id, decoded values) per frame."""

    def __init__(self) -> None:
        self.frames: list[tuple[int, list[float]]] = []

    def __call__(self, timestamp: float, frame_id: int, flags: int, data, channel: object) -> None:
        codec = PROTOCOL.by_id.get(frame_id)
        values = [0.0] * len(codec.signals) if codec is not None else []
        if codec is not None:
            codec.unpack(bytearray(data), values)
        self.frames.append((frame_id, values))

    def clear(self) -> None:
        self.frames.clear()

    def of(self, frame_id: int) -> list[list[float]]:
        return [values for fid, values in self.frames if fid == frame_id]


def _bench(safety=None, stop_table: bool = True) -> tuple[Bench, Wire]:
    b = Bench(safety)
    if stop_table:
        b.tick.trip_outputs.stop_table = lambda now: b.link.writer.rig_control(STOP_TABLE, False, now)
    wire = Wire()
    b.rig_side.tap = wire
    return b, wire


@pytest.fixture
def benches():
    made = []
    yield made
    for b in made:
        b.close()


def _trip_by_exception(b: Bench, wire: Wire):
    b.run_until_running()
    wire.clear()
    b.controller.raise_next = True
    return b.step()


def test_the_trip_tick_sends_disable_then_estop_then_the_table_stop(benches):
    b, wire = _bench()
    benches.append(b)
    command, sent = _trip_by_exception(b, wire)
    assert command.trip_reason == "tick_exception" and sent == (False, 0.0)
    order = [fid for fid, _ in wire.frames if fid in (CMD_ID, ESTOP_ID, CTRL_ID)]
    assert order == [CMD_ID, ESTOP_ID, CTRL_ID], "zero + disable first, then ESTOP, then the table stop, same tick"
    estop = PROTOCOL["ESTOP"]
    active, source, reason = (wire.of(ESTOP_ID)[0][estop.index(n)] for n in ("active", "source", "reason"))
    assert (active, source, reason) == (1.0, SUPERVISOR_SOURCE, CHECK_NAMES.index("tick_exception") + 1)
    assert wire.of(CTRL_ID)[0][PROTOCOL["RIG_CONTROL"].index("command")] == STOP_TABLE


def test_the_stroke_trip_tick_carries_the_estop_on_the_bus(benches):
    b, wire = _bench()
    benches.append(b)
    b.run_until_running()
    b.controller.force_N = -2_000.0
    for _ in range(200):
        b.v_b = min(0.5, b.v_b + 0.1)
        b.x_b += b.v_b * PERIOD_S
        wire.clear()
        command, sent = b.step()
        if command.state is State.TRIPPED:
            break
    assert command.trip_reason in ("stroke_predictive", "stroke_hard") and sent == (False, 0.0)
    assert len(wire.of(ESTOP_ID)) == 1 and len(wire.of(CTRL_ID)) == 1


def test_the_estop_is_repeated_at_its_rate_while_tripped(benches):
    b, wire = _bench()
    benches.append(b)
    _trip_by_exception(b, wire)
    wire.clear()
    ticks = 100
    for _ in range(ticks):
        b.step()
    every = b.tick.trip_outputs.estop_every
    frames = wire.of(ESTOP_ID)
    assert len(frames) == ticks // every
    assert all(f[PROTOCOL["ESTOP"].index("active")] == 1.0 for f in frames)
    assert len(wire.of(CTRL_ID)) == 0, "the table stop is sent once, on the trip tick"


def test_disable_alone_sends_neither_estop_nor_table_stop(benches):
    b, wire = _bench(dataclasses.replace(SAFETY, trip_actions=TripActionsConfig()))
    benches.append(b)
    command, sent = _trip_by_exception(b, wire)
    assert sent == (False, 0.0)
    for _ in range(20):
        b.step()
    assert wire.of(ESTOP_ID) == [] and wire.of(CTRL_ID) == []


def test_stop_table_without_a_table_link_is_skipped(benches):
    b, wire = _bench(stop_table=False)
    benches.append(b)
    _trip_by_exception(b, wire)
    assert len(wire.of(ESTOP_ID)) == 1 and wire.of(CTRL_ID) == []


def test_trip_actions_must_keep_disable_and_name_known_actions():
    bad = dataclasses.replace(SAFETY, trip_actions=TripActionsConfig(stroke=("estop",)))
    assert any("disable cannot be removed" in p for p in check_config(bad))
    with pytest.raises(ProfileError, match="disable cannot be removed"):
        load_profile(None, overrides=["safety.trip_actions.sensor=[estop, stop_table]"])
    with pytest.raises(ProfileError, match="expected one of"):
        load_profile(None, overrides=["safety.trip_actions.sensor=[disable, pump_off]"])
    with pytest.raises(ProfileError, match="at least 1"):
        load_profile(None, overrides=["safety.trip_actions.sensor=[]"])


def test_a_panel_bound_shorter_than_two_heartbeats_is_refused():
    with pytest.raises(ProfileError, match="max_panel_age_s"):
        load_profile(None, overrides=["safety.estop.max_panel_age_s=0.05"])
    assert load_profile(None, overrides=["safety.estop.max_panel_age_s=0.1"]).safety.estop.max_panel_age_s == 0.1


def test_every_check_that_can_trip_has_a_class():
    from harness.safety.config import TRIP_CLASS_OF

    not_trips = {"force_clamp", "force_rate", "stroke_soft", "stop_ramp",
                 "table_record_mismatch", "table_record_marginal"}  # a safe stop and a warning, never a trip
    assert set(CHECK_NAMES) - not_trips == set(TRIP_CLASS_OF)


# ---------------------------------------------------------------- the E-stop panel's heartbeat


def test_no_arming_without_a_live_panel(benches):
    b, _ = _bench()
    benches.append(b)
    b.publish_panel = False
    for _ in range(3):
        b.step()
    with pytest.raises(ArmRefused, match="estop_panel_live"):
        b.supervisor.arm(b.t, b.tick.health)


def test_a_silent_panel_trips_estop_lost_within_its_bound(benches):
    b, wire = _bench()
    benches.append(b)
    b.run_until_running()
    b.publish_panel = False
    silent_from = b.t
    for _ in range(400):
        command, sent = b.step()
        if command.state is State.TRIPPED:
            break
    assert command.trip_reason == "estop_lost"
    latency = b.t - silent_from
    bound = SAFETY.estop.max_panel_age_s
    assert bound < latency <= bound + 3 * PERIOD_S
    assert sent == (False, 0.0)
    with pytest.raises(Exception, match="panel"):
        b.supervisor.reset(b.t, b.tick.health)  # refused while the panel is silent


def test_a_panel_not_required_arms_and_runs_without_one(benches):
    safety = dataclasses.replace(SAFETY, estop=EStopConfig(panel_required=False))
    b, _ = _bench(safety)
    benches.append(b)
    b.publish_panel = False
    b.run_until_running()
    for _ in range(200):
        command, _ = b.step()
    assert command.state is State.RUNNING


def test_only_the_panels_own_frames_keep_it_alive(benches):
    b, _ = _bench()
    benches.append(b)
    b.publish_panel = False
    for source in (0, 1, 2, 4):  # harness, rig, servo, supervisor: none is the panel
        b.rig.writer.estop(False, b.t, source=source)
        b.step()
    assert b.tick.reader.counters.panel_frames == 0
    assert math.isinf(b.tick.health.estop_panel_age_s)
    b.rig.writer.estop(False, b.t, source=EstopSource.PANEL)
    b.step()
    assert b.tick.reader.counters.panel_frames == 1
    assert b.tick.health.estop_panel_age_s == pytest.approx(0.0, abs=PERIOD_S)


def test_the_bus_load_budget_counts_the_panel_heartbeat_and_the_estop():
    config = CanConfig()
    load = bus_load(PROTOCOL, config.rates_hz(), config.bitrate_bps)
    expected = (config.estop_rate_hz + config.estop_panel_rate_hz) * frame_bits(PROTOCOL["ESTOP"].length)
    assert load.bits_per_s["ESTOP"] == pytest.approx(expected)
    assert load.share <= config.max_bus_load


# ------------------------------------------------------------------ TripOutputs alone
# Against a writer that records or fails: the counters and the failure paths a bus cannot
# produce on demand (a send refused, a send that raises).

EVERY = 3
BOTH = TripActionsConfig(stroke=("disable", "estop", "stop_table"))


class RecordingWriter:
    """Records each ESTOP send as (active, now, source, reason); answers ``result`` or raises it."""

    def __init__(self, result: bool | Exception = True) -> None:
        self.result = result
        self.sent: list[tuple[bool, float, int, int]] = []

    def estop(self, active: bool, now: float, source: int, reason: int) -> bool:
        self.sent.append((active, now, source, reason))
        if isinstance(self.result, Exception):
            raise self.result
        return self.result


class TableStop:
    """Records each table stop's ``now``; raises ``error`` if given."""

    def __init__(self, error: Exception | None = None) -> None:
        self.error = error
        self.calls: list[float] = []

    def __call__(self, now: float) -> None:
        self.calls.append(now)
        if self.error is not None:
            raise self.error


def test_the_trip_tick_sends_the_estop_with_its_reason_and_stops_the_table_once() -> None:
    writer, table = RecordingWriter(), TableStop()
    outputs = TripOutputs(writer, BOTH, EVERY, table)
    outputs.update(State.RUNNING, "", 1.0)
    assert writer.sent == [] and table.calls == []
    outputs.update(State.TRIPPED, "stroke_hard", 1.25)
    assert writer.sent == [(True, 1.25, SUPERVISOR_SOURCE, CHECK_NAMES.index("stroke_hard") + 1)]
    assert table.calls == [1.25]
    assert (outputs.estop_frames, outputs.table_stops, outputs.failures) == (1, 1, 0)
    assert outputs.estop_asserted


def test_the_estop_repeats_every_estop_every_ticks_while_tripped_and_stops_after() -> None:
    writer, table = RecordingWriter(), TableStop()
    outputs = TripOutputs(writer, BOTH, EVERY, table)
    for k in range(1 + 3 * EVERY):
        outputs.update(State.TRIPPED, "stroke_hard", float(k))
    assert [now for _, now, _, _ in writer.sent] == [0.0, 3.0, 6.0, 9.0]
    assert (outputs.estop_frames, outputs.table_stops) == (4, 1)
    outputs.update(State.IDLE, "", 10.0)  # reset: no longer tripped
    assert not outputs.estop_asserted and len(writer.sent) == 4


@pytest.mark.parametrize("result", [False, OSError("ENOBUFS")], ids=["refused", "raised"])
def test_a_failed_estop_send_is_counted_once_per_attempt_and_never_raises(result: bool | Exception) -> None:
    writer = RecordingWriter(result)
    outputs = TripOutputs(writer, BOTH, EVERY)
    for k in range(1 + EVERY):
        outputs.update(State.TRIPPED, "stroke_hard", float(k))
    assert len(writer.sent) == 2
    assert (outputs.estop_frames, outputs.failures) == (0, 2)


def test_a_table_stop_that_raises_is_counted_and_the_trip_stands() -> None:
    writer, table = RecordingWriter(), TableStop(OSError("bus gone"))
    outputs = TripOutputs(writer, BOTH, EVERY, table)
    outputs.update(State.TRIPPED, "stroke_hard", 2.0)
    assert table.calls == [2.0]
    assert (outputs.estop_frames, outputs.table_stops, outputs.failures) == (1, 0, 1)


def test_a_reason_of_no_known_check_sends_nothing_beyond_the_disable() -> None:
    writer, table = RecordingWriter(), TableStop()
    everything = TripActionsConfig(**{group: ("disable", "estop", "stop_table") for group in (
        "stroke", "sensor", "comms", "actuator", "loop", "operator", "internal")})
    outputs = TripOutputs(writer, everything, EVERY, table)
    outputs.update(State.TRIPPED, "no_such_check", 0.0)  # never raises
    assert writer.sent == [] and table.calls == [] and not outputs.estop_asserted


def test_an_estop_every_tick_repeats_on_every_tick() -> None:
    writer = RecordingWriter()
    outputs = TripOutputs(writer, BOTH, 1)
    for k in range(4):
        outputs.update(State.TRIPPED, "stroke_hard", float(k))
    assert [now for _, now, _, _ in writer.sent] == [0.0, 1.0, 2.0, 3.0]
