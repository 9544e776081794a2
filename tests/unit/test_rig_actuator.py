"""The servo actuator model: step responses, transport delay, rate and force limits, decay."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.rig.actuator import ServoActuator
from harness.rig.config import ActuatorConfig

H = 0.0005


def _run(actuator: ServoActuator, command: float, n: int, enabled: bool = True) -> np.ndarray:
    """Force held over each of ``n`` sub-steps, then the state after them."""
    held = [actuator.substep(command, enabled) for _ in range(n)]
    return np.array(held + [actuator.force_N])


def test_first_order_step_reaches_63_percent_at_tau():
    tau = 0.02
    actuator = ServoActuator(ActuatorConfig(model="first_order", time_constant_s=tau), H, 0.02)
    forces = _run(actuator, 1000.0, 200)
    at_tau = forces[int(round(tau / H))]  # state at t = tau
    assert at_tau == pytest.approx(1000.0 * (1.0 - math.exp(-1.0)), rel=0.02)
    assert forces[0] == 0.0, "the force held over the first sub-step is the state at its start"
    assert forces[-1] == pytest.approx(1000.0 * (1.0 - math.exp(-200 * H / tau)), rel=1e-6)


def test_second_order_settles_to_the_command_with_overshoot_for_low_damping():
    config = ActuatorConfig(model="second_order", bandwidth_hz=20.0, damping_ratio=0.3, force_rate_limit_N_per_s=1e9)
    actuator = ServoActuator(config, H, 0.02)
    forces = _run(actuator, 1000.0, 2000)
    expected_overshoot = math.exp(-math.pi * 0.3 / math.sqrt(1 - 0.3**2))
    assert forces.max() == pytest.approx(1000.0 * (1 + expected_overshoot), rel=0.02)
    assert forces[-1] == pytest.approx(1000.0, rel=1e-3)


def test_ideal_actuator_applies_the_command_after_the_delay():
    config = ActuatorConfig(model="ideal", delay_s=0.002, force_rate_limit_N_per_s=1e12)
    actuator = ServoActuator(config, H, 0.02)
    held = _run(actuator, 500.0, 8)[:-1]
    np.testing.assert_array_equal(held, [0, 0, 0, 0, 500, 500, 500, 500])


def test_force_rate_limit_holds():
    rate = 1e5
    actuator = ServoActuator(ActuatorConfig(model="ideal", force_rate_limit_N_per_s=rate), H, 0.02)
    forces = _run(actuator, 10_000.0, 400)
    steps = np.diff(forces)
    assert np.max(np.abs(steps)) <= rate * H * (1 + 1e-12)
    assert forces[19] == pytest.approx(20 * rate * H), "ramps at the limit (ideal: from the first sub-step on)"


def test_force_limit_holds_for_every_model():
    for model in ("ideal", "first_order", "second_order"):
        config = ActuatorConfig(model=model, force_limit_N=3000.0, force_rate_limit_N_per_s=1e9, damping_ratio=0.2)
        actuator = ServoActuator(config, H, 0.02)
        forces = _run(actuator, -25_000.0, 1000)
        assert forces.min() >= -3000.0 and forces[-1] == pytest.approx(-3000.0), model


def test_disabled_drive_decays_the_force_to_zero():
    actuator = ServoActuator(ActuatorConfig(model="ideal"), H, 0.01)
    _run(actuator, 2000.0, 10)
    forces = _run(actuator, 2000.0, 20, enabled=False)  # 10 ms = one decay time constant
    assert forces[-1] == pytest.approx(2000.0 * math.exp(-1.0), rel=1e-9)
    assert np.all(np.diff(forces) <= 0)
