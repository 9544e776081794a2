"""What the tick hands the controller and the friction estimator: its time, its step, this tick's
measurements and this tick's friction estimate (mutation survivors: the tick's test controllers
ignored their arguments, so dropping any of them passed)."""

from __future__ import annotations

import math

import pytest

from tests.unit.test_control_tick import PERIOD_S, Bench


class Recording:
    """A controller that keeps what it was handed and asks for nothing."""

    needs_full_state = False

    def __init__(self) -> None:
        self.calls: list[tuple] = []
        self.sliding_variable = 0.0
        self.equivalent_force_N = 0.0

    def update(self, t, dt, meas, friction, state):
        self.calls.append((t, dt, meas.base_displacement_m, meas.sliding_velocity_m_s, friction, state))
        return 0.0


class RecordingEstimator:
    """Stands in for the friction estimator: keeps its arguments, answers a force that names the tick."""

    def __init__(self) -> None:
        self.calls: list[tuple[float, float, float]] = []
        self.nu = 0.0  # the recorded row's hysteretic variable

    def update(self, t: float, dt: float, sliding_velocity_m_s: float) -> float:
        self.calls.append((t, dt, sliding_velocity_m_s))
        return 100.0 + len(self.calls)

    def reset(self) -> None:
        self.calls.clear()


@pytest.fixture
def bench():
    b = Bench()
    yield b
    b.close()


def test_the_controller_and_the_estimator_get_this_ticks_time_step_and_measurements(bench) -> None:
    controller, estimator = Recording(), RecordingEstimator()
    bench.tick.controller = controller
    bench.tick.estimator = estimator
    bench.x_b, bench.v_b = 0.004, 0.02
    for _ in range(5):
        bench.step()
    assert len(controller.calls) == len(estimator.calls) == 5
    for k, (handed, estimated) in enumerate(zip(controller.calls, estimator.calls, strict=True)):
        (t, dt, x_b, v_b, friction, state), (te, dte, ve) = handed, estimated
        assert t == te == pytest.approx(k * PERIOD_S) and dt == dte == PERIOD_S
        assert x_b == pytest.approx(0.004, abs=1e-5), "this tick's base-mat displacement"
        assert v_b == ve == pytest.approx(0.02, abs=1e-4), "this tick's sliding velocity, to both"
        assert friction == 100.0 + k + 1, "this tick's friction estimate reaches the controller"
        assert state is None and math.isfinite(friction)
