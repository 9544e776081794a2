"""The loop's way out: zero force with the drive disabled is the last command on the bus, however the loop ends.

A planted bug that skipped the final command on an exception that is not an ``Exception``
(``KeyboardInterrupt``, ``SystemExit``) passed every test. Here the whole
:class:`~harness.loop.runner.ControlLoop` runs in lockstep with the rig-side node of
tests/unit/test_control_tick.py, arms, runs with force flowing, and is then left by each
way out: an exception raised inside a tick (by the controller) or in the loop around it
(by the lockstep wait), and a normal end. The frames the rig received are decoded in order.
"""

from __future__ import annotations

import pytest

from drivers.protocol.codec import load_protocol
from harness.loop.config import LoopConfig
from harness.loop.runner import ControlLoop
from harness.safety.lifecycle import State
from tests.unit.test_control_tick import PERIOD_S, Bench
from tests.unit.test_trip_actions import Wire

PROTOCOL = load_protocol()
CMD = PROTOCOL["ACTUATOR_CMD"]
HEARTBEAT = PROTOCOL["HEARTBEAT"]
#: RUNNING ticks before the fault: the drive is enabled and force flows by then.
FAULT_AFTER_TICKS = 10
#: A short run: arm, settle 20 ms, 0.2 s of record, no tail.
CONFIG = LoopConfig(settle_s=0.02, tail_s=0.0, after_s=0.01)


class RaisingController:
    """Asks for 2 kN; raises ``exc`` on the FAULT_AFTER_TICKS-th RUNNING tick (``exc`` None: never)."""

    needs_full_state = False

    def __init__(self, bench: Bench, exc: BaseException | None) -> None:
        self.bench, self.exc = bench, exc
        self.running_ticks = 0
        self.sliding_variable = 0.0
        self.equivalent_force_N = 0.0

    def update(self, t, dt, meas, friction, state):
        if self.bench.supervisor.state is State.RUNNING:
            self.running_ticks += 1
            if self.exc is not None and self.running_ticks == FAULT_AFTER_TICKS:
                raise self.exc
        return 2_000.0


class Lockstep:
    """The rig's side of lockstep: publish step ``k``'s frames, let the harness read them; raise at ``raise_at``."""

    def __init__(self, bench: Bench, exc: BaseException | None = None) -> None:
        self.bench, self.exc = bench, exc

    def __call__(self, k: int, timeout_s: float) -> bool:
        b = self.bench
        if self.exc is not None and b.controller.running_ticks == FAULT_AFTER_TICKS:
            raise self.exc
        b.rig_side.poll(b.t)  # the rig takes what the previous tick sent (the tap records it)
        b.t = k * PERIOD_S
        b.publish()
        b.tick.reader.poll(b.t)
        return True


@pytest.fixture
def bench():
    b = Bench()
    yield b
    b.close()


def _loop(bench: Bench, in_tick: BaseException | None, in_loop: BaseException | None = None) -> tuple[ControlLoop, Wire]:
    bench.controller = bench.tick.controller = RaisingController(bench, in_tick)
    wire = Wire()
    bench.rig_side.tap = wire
    loop = ControlLoop(bench.tick, CONFIG, 1.0 / PERIOD_S, 0.2, lockstep=Lockstep(bench, in_loop))
    return loop, wire


def _commands(bench: Bench, wire: Wire) -> list[tuple[bool, float]]:
    """Every ACTUATOR_CMD the rig received, in order, as (enable, force_N)."""
    bench.rig_side.poll(bench.t + PERIOD_S)
    return [(bool(v[CMD.index("enable")]), v[CMD.index("force")]) for v in wire.of(CMD.frame_id)]


def _last_heartbeat_state(wire: Wire) -> State:
    return State(int(wire.of(HEARTBEAT.frame_id)[-1][HEARTBEAT.index("state")]))


def _assert_force_flowed_then_zero_and_disabled(commands: list[tuple[bool, float]]) -> None:
    assert any(enable and force == pytest.approx(2_000.0) for enable, force in commands), "force flowed before the fault"
    assert commands[-1] == (False, 0.0), f"the last command on the bus was {commands[-1]}, expected zero and disabled"


@pytest.mark.parametrize("exc", [KeyboardInterrupt(), SystemExit(3)], ids=["KeyboardInterrupt", "SystemExit"])
def test_a_base_exception_inside_a_tick_leaves_zero_and_disabled_and_trips(bench, exc: BaseException) -> None:
    loop, wire = _loop(bench, in_tick=exc)
    with pytest.raises(type(exc)):
        loop.run()
    _assert_force_flowed_then_zero_and_disabled(_commands(bench, wire))
    assert bench.supervisor.state is State.TRIPPED and bench.supervisor.command.trip_reason == "tick_exception"
    assert type(exc).__name__ in bench.supervisor.trip_detail
    assert _last_heartbeat_state(wire) is State.TRIPPED, "the rig is told the harness tripped"


@pytest.mark.parametrize("exc", [KeyboardInterrupt(), SystemExit(3)], ids=["KeyboardInterrupt", "SystemExit"])
def test_a_base_exception_in_the_loop_between_ticks_leaves_zero_and_disabled(bench, exc: BaseException) -> None:
    loop, wire = _loop(bench, in_tick=None, in_loop=exc)
    with pytest.raises(type(exc)):
        loop.run()
    _assert_force_flowed_then_zero_and_disabled(_commands(bench, wire))
    assert bench.supervisor.state is State.TRIPPED


def test_an_ordinary_exception_in_the_loop_trips_and_leaves_zero_and_disabled(bench) -> None:
    loop, wire = _loop(bench, in_tick=None, in_loop=RuntimeError("the lockstep wait failed"))
    result = loop.run()  # a fault of the loop itself is a trip, not a crash
    assert (result.outcome, result.trip_reason) == ("tripped", "tick_exception")
    assert "RuntimeError" in result.trip_detail
    _assert_force_flowed_then_zero_and_disabled(_commands(bench, wire))
    assert _last_heartbeat_state(wire) is State.TRIPPED


def test_an_ordinary_exception_inside_a_tick_trips_and_leaves_zero_and_disabled(bench) -> None:
    loop, wire = _loop(bench, in_tick=RuntimeError("controller bug"))
    result = loop.run()
    assert (result.outcome, result.trip_reason) == ("tripped", "tick_exception")
    _assert_force_flowed_then_zero_and_disabled(_commands(bench, wire))


def test_a_run_that_completes_ends_zero_and_disabled(bench) -> None:
    loop, wire = _loop(bench, in_tick=None)
    assert loop.run().outcome == "completed"
    _assert_force_flowed_then_zero_and_disabled(_commands(bench, wire))
    assert _last_heartbeat_state(wire) is State.DONE


def test_a_base_exception_inside_a_tick_also_sends_the_trips_estop(bench) -> None:
    import dataclasses

    from harness.loop.tick import ControlTick
    from harness.loop.trip_outputs import SUPERVISOR_SOURCE
    from harness.safety.checks import CHECK_NAMES
    from harness.safety.config import TripActionsConfig
    from harness.safety.supervisor import Supervisor

    safety = dataclasses.replace(bench.supervisor.config, trip_actions=TripActionsConfig(internal=("disable", "estop")))
    bench.supervisor = Supervisor(safety, period_s=PERIOD_S)
    bench.tick = ControlTick(bench.link, bench.controller, bench.tick.estimator, bench.supervisor, None, heartbeat_every=1)
    loop, wire = _loop(bench, in_tick=KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        loop.run()
    _commands(bench, wire)
    estop = PROTOCOL["ESTOP"]
    ids = [fid for fid, _ in wire.frames]
    last_cmd = len(ids) - 1 - ids[::-1].index(CMD.frame_id)
    after = [values for fid, values in wire.frames[last_cmd:] if fid == estop.frame_id]
    assert [(v[estop.index("active")], v[estop.index("source")], v[estop.index("reason")]) for v in after] == [
        (1.0, SUPERVISOR_SOURCE, CHECK_NAMES.index("tick_exception") + 1)
    ], "the ESTOP follows the final zero, disabled command"
