"""The one control step (harness/loop/step.py): estimate -> control -> compensate -> supervise, and its exception.

The loop's tick, the rig twin and the ideal simulator each wrote the step themselves, and only
the tick caught an exception in it: a controller bug that trips a dry run crashed
``harness simulate --rig-effects`` and a sweep case instead (issue 35, item 1). These tests hold
the twin's case to the tick's trip, and hold the three callers to the one step.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

from harness.control.compensation import NoCompensation
from harness.control.factory import build_controller_for_rig, make_friction_estimator
from harness.loop.ending import run_ending
from harness.loop.step import StepValues, control_step
from harness.loop.timing import CONTROL, GapTrace
from harness.model.plant import Plant, TableMotion
from harness.motions import load_motion
from harness.profile import load_profile
from harness.safety.health import TickHealth
from harness.safety.lifecycle import State
from harness.safety.supervisor import Supervisor
from harness.simulation.case import SamplingSettings, run_case
from harness.simulation.twin import run_rig_twin
from tests.conftest import PROFILES, REPO
from tests.unit.test_control_tick import PERIOD_S, Bench

RATE_HZ = 500.0
RAISE_AT_S = 0.5


class RaisesAt:
    """A rig controller that works until ``at_s`` (s), then raises on every update."""

    def __init__(self, controller, at_s: float) -> None:
        self.inner = controller
        self.at_s = at_s
        self.needs_full_state = controller.needs_full_state

    @property
    def sliding_variable(self) -> float:
        return self.inner.sliding_variable

    @property
    def equivalent_force_N(self) -> float:
        return self.inner.equivalent_force_N

    def reset(self) -> None:
        self.inner.reset()

    def update(self, t, dt, meas, friction, state):
        if t >= self.at_s:
            raise RuntimeError("controller bug")
        return self.inner.update(t, dt, meas, friction, state)


def _tick_ending() -> tuple[str, str]:
    """A dry run's tick whose controller raises: its run's outcome and trip reason."""
    bench = Bench()
    try:
        bench.run_until_running()
        bench.controller.raise_next = True
        command, sent = bench.step()
        assert command.state is State.TRIPPED and sent == (False, 0.0)
        ending = run_ending(bench.supervisor)
        return ending.outcome, ending.reason
    finally:
        bench.close()


def test_a_controller_exception_trips_the_twins_case_as_it_trips_the_ticks_run():
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    motion = load_motion(profile.record, base_dir=profile.base_dir, name="synthetic", duration_s=2.0)
    controller = RaisesAt(build_controller_for_rig(profile, "phi"), RAISE_AT_S)

    result = run_rig_twin(profile, motion, RATE_HZ, controller)  # before the one step: RuntimeError escaped here

    assert (result.extra["outcome"], result.extra["trip_reason"]) == _tick_ending() == ("tripped", "tick_exception")
    columns = result.columns
    raising = round(RAISE_AT_S * RATE_HZ)  # the first sample whose update raised: the case ends after it
    assert len(columns["t_s"]) == raising + 2  # the samples up to it, and the row held after the last one
    assert math.isnan(columns["force_raw_N"][raising])  # the controller gave no force
    assert columns["force_command_N"][raising] == 0.0  # the tripped command: zero force, drive disabled
    assert columns["force_command_N"][raising - 1] != 0.0  # force flowed up to the trip


def test_a_controller_exception_trips_the_twin_and_it_runs_on_after_the_trip():
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    motion = load_motion(profile.record, base_dir=profile.base_dir, name="synthetic", duration_s=2.0)
    controller = RaisesAt(build_controller_for_rig(profile, "phi"), RAISE_AT_S)
    result = run_rig_twin(profile, motion, RATE_HZ, controller, after_trip_s=0.1)
    assert result.extra["outcome"] == "tripped" and result.extra["trip_reason"] == "tick_exception"
    after = result.columns["force_command_N"][round(RAISE_AT_S * RATE_HZ):]
    assert len(after) > 0.1 * RATE_HZ and not after.any()  # zero force every sample after the trip


class Raises:
    """An estimator, controller or compensator part that raises."""

    def update(self, *args):
        raise ValueError("part bug")


class Fixed:
    """A controller asking for a fixed force."""

    needs_full_state = False
    sliding_variable = 0.0
    equivalent_force_N = 0.0

    def __init__(self, force_N: float = 1_000.0) -> None:
        self.force_N = force_N

    def reset(self) -> None:
        pass

    def update(self, t, dt, meas, friction, state):
        return self.force_N


def _running_supervisor() -> tuple[Supervisor, TickHealth]:
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    supervisor = Supervisor(profile.safety, period_s=PERIOD_S)
    health = TickHealth()
    supervisor.arm(0.0, health)
    supervisor.start(0.0)
    return supervisor, health


@pytest.mark.parametrize("failing", ["estimator", "controller", "compensator"])
def test_any_part_raising_trips_through_report_exception_with_nan_for_what_it_did_not_reach(failing):
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    supervisor, health = _running_supervisor()
    parts = {"estimator": make_friction_estimator(profile), "controller": Fixed(), "compensator": NoCompensation()}
    parts[failing] = Raises()
    values = StepValues()
    trace = GapTrace(clock=lambda: 7.0)
    command = control_step(0.0, PERIOD_S, health, parts["estimator"], parts["controller"], parts["compensator"],
                           supervisor, values, trace=trace)
    assert command is supervisor.command  # the supervisor's one command, not a new object
    assert command.state is State.TRIPPED and command.trip_reason == "tick_exception"
    assert (command.force_N, command.enable) == (0.0, False)
    assert math.isnan(values.friction_N) == (failing == "estimator")
    assert math.isnan(values.raw_N) == (failing in ("estimator", "controller"))
    assert trace.marks[CONTROL + 1] == 0.0  # CONTROL is marked only when the compensated command is ready


def test_a_step_overwrites_its_values_and_marks_control():
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    supervisor, health = _running_supervisor()
    values = StepValues()
    trace = GapTrace(clock=lambda: 7.0)
    estimator = make_friction_estimator(profile)
    command = control_step(0.0, PERIOD_S, health, estimator, Fixed(), NoCompensation(), supervisor, values, trace=trace)
    assert command is supervisor.command and command.state is State.RUNNING
    assert values.raw_N == 1_000.0 and math.isfinite(values.friction_N)
    assert trace.marks[CONTROL + 1] == 7.0
    control_step(PERIOD_S, PERIOD_S, health, Raises(), Fixed(), NoCompensation(), supervisor, values)
    assert math.isnan(values.friction_N) and math.isnan(values.raw_N)  # nothing of the step before is left


class SeesState(Fixed):
    """A full-state controller: it remembers the state it was handed."""

    needs_full_state = True
    seen = None

    def update(self, t, dt, meas, friction, state):
        self.seen = state
        return self.force_N


def test_the_step_hands_the_plants_state_to_a_full_state_controller():
    """Offline, the full-state controllers (the paper's LQR sliding surfaces) read the plant's true state Z."""
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    supervisor, health = _running_supervisor()
    controller, state = SeesState(), np.arange(8.0)
    control_step(0.0, PERIOD_S, health, make_friction_estimator(profile), controller, NoCompensation(), supervisor,
                 StepValues(), state)
    assert controller.seen is state


def test_the_ideal_simulator_has_no_safety_layer_so_an_exception_still_escapes():
    # The ideal case's pass-through supervisor re-raises: its behaviour is what it was before the one step.
    profile = load_profile(PROFILES / "nceer_4dof.yaml")
    motion = load_motion(profile.record, base_dir=profile.base_dir, name="synthetic", duration_s=1.0)
    plant = Plant(profile.structure, profile.bearing, TableMotion.from_motion(motion), rtol=profile.simulation.rtol)
    controller = RaisesAt(Fixed(), 0.2)
    with pytest.raises(RuntimeError, match="controller bug"):
        run_case("controlled", plant, 1.0, SamplingSettings(RATE_HZ), controller, make_friction_estimator(profile))


# ---------------------------------------------------------------------- architecture
STEP_CALLERS = ("harness/loop/tick.py", "harness/simulation/twin.py", "harness/simulation/case.py")


def _called_names(source: str) -> set[str]:
    """The names of every function called in ``source`` (``f(...)`` and ``x.f(...)``)."""
    names = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Call):
            func = node.func
            names.add(func.id if isinstance(func, ast.Name) else func.attr if isinstance(func, ast.Attribute) else "")
    return names


@pytest.mark.parametrize("path", STEP_CALLERS)
def test_the_tick_the_twin_and_the_ideal_simulator_call_the_one_step(path):
    source = (REPO / path).read_text()
    assert "control_step" in _called_names(source), f"{path} does not call harness.loop.step.control_step"
    assert "from harness.loop.step import" in source
    for written_out in ("controller.update(", "estimator.update(", "supervisor.update(", "compensate("):
        assert written_out not in source, f"{path} writes the step's {written_out!r} itself: call control_step"


def test_the_step_is_written_once():
    step = (REPO / "harness/loop/step.py").read_text()
    assert "controller.update(" in step and "supervisor.report_exception(" in step
    others = [path for path in Path(REPO / "harness").rglob("*.py")
              if "controller.update(" in path.read_text() and path.name != "step.py"]
    assert others == [], f"the control step written again in {others}"
