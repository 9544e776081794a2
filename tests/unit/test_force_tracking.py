"""The force tracking check against a servo-hydraulic actuator: it expects the natural velocity feedback.

The measured force comes from the plant's own servo-hydraulic cylinder (the rig's model),
stroked at a sliding velocity while the command steps: the check's model of the
actuator, lag(command - (k_h / w_f) xdot_b), must accept the healthy actuator, and the
check must still trip when the actuator does not follow that model.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.model import hydraulics as hy
from harness.model.plant import Plant, TableMotion
from harness.profile import load_profile
from harness.safety.actuator_detectors import ForceTracking
from harness.safety.health import TickHealth
from tests.unit.test_hydraulics import FRICTIONLESS, IMMOVABLE

PROFILE = load_profile(None)
FORCE = PROFILE.safety.force
ACTUATOR = PROFILE.rig.actuator.hydraulics
DT = 0.002


def _sliding_plant(velocity_m_s: float, duration_s: float) -> Plant:
    """The shipped actuator pushing a base mat that stays still while the table moves at ``-velocity``."""
    times = np.arange(0.0, duration_s + 0.01, 0.01)
    table = TableMotion(0.01, np.zeros(times.size), np.full(times.size, -velocity_m_s), -velocity_m_s * times)
    params = hy.pack_rig(ACTUATOR, hy.TableConfig(model="motion_source"), IMMOVABLE.base_mass_kg, False, 0.02)
    params[hy.ENABLED] = 1.0
    plant = Plant(IMMOVABLE, FRICTIONLESS, table, 1e-6, params)
    plant.reset()
    return plant


def _first_trip(detector: ForceTracking, velocity_m_s: float, measured, duration_s: float = 2.0) -> float | None:
    """Command steps of +-2 kN every 0.25 s; ``measured(command, plant)`` gives the load cell's reading."""
    plant = _sliding_plant(velocity_m_s, duration_s)
    health = TickHealth()
    health.meas.set(0.0, -velocity_m_s, 0.0, 0.0)  # table velocity, base still: sliding at +velocity
    for k in range(int(round(duration_s / DT))):
        t = k * DT
        command = 2000.0 if (k * DT) % 0.5 < 0.25 else -2000.0
        health.measured_force_N = measured(command, plant)
        detector.command_N = command
        if detector.update(t, DT, health):
            return t
        plant.advance(t, t + DT, command)
    return None


def _load_cell(command: float, plant: Plant) -> float:
    return plant.actuator_force(command)


def test_the_shipped_check_accepts_the_shipped_servo_hydraulic_actuator_while_it_strokes() -> None:
    assert FORCE.velocity_feedback_Ns_per_m > 0
    for velocity in (0.02, -0.05):  # force lost ~ k_h / w_f * v: up to 4.7 kN, well past the 1.5 kN tolerance
        assert _first_trip(ForceTracking(FORCE), velocity, _load_cell) is None


def test_a_force_source_model_trips_on_the_same_healthy_actuator() -> None:
    force_source = dataclasses.replace(FORCE, velocity_feedback_Ns_per_m=0.0)
    assert _first_trip(ForceTracking(force_source), 0.05, _load_cell) is not None


def test_the_check_still_trips_an_actuator_that_does_not_follow_its_model() -> None:
    # A load cell that reads the command while the piston strokes: the force the model says is lost is not.
    fired = _first_trip(ForceTracking(FORCE), 0.05, lambda command, plant: command)
    assert fired is not None and fired <= 0.25
    # An actuator pushing the wrong way (a swapped servo-valve connection).
    assert _first_trip(ForceTracking(FORCE), 0.0, lambda command, plant: -plant.actuator_force(command)) is not None


def test_the_expected_force_is_the_lagged_command_less_the_velocity_feedback() -> None:
    detector = ForceTracking(dataclasses.replace(FORCE, actuator_time_constant_s=0.0))
    health = TickHealth(measured_force_N=0.0)
    health.meas.set(0.0, -0.1, 0.0, 0.0)  # sliding at +0.1 m/s
    detector.command_N = 3000.0
    detector.update(0.0, DT, health)
    assert detector.expected_N() == pytest.approx(3000.0 - FORCE.velocity_feedback_Ns_per_m * 0.1)
    assert math.isfinite(detector.expected_N())
