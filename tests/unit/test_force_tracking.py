"""The force tracking check against a servo-hydraulic actuator: it expects the velocity feedback the rig leaves.

The measured force comes from the plant's own servo-hydraulic cylinder (the rig's model),
stroked at a sliding velocity while the command steps: the check's model of the
actuator, lag(command - c_eff xdot_b), must accept the healthy actuator, and the check must
still trip when the actuator does not follow that model. ``c_eff`` is the plain force
loop's ``k_h / w_f`` (94 kN s/m), or what the servo controller's velocity feed-forward
leaves, ``(1 - alpha) k_h / w_f`` (0 on the shipped rig, SPEC 7a').
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.hydraulics import config as hydraulics_config
from harness.hydraulics import cylinder as hy
from harness.hydraulics.servo_controller import StrokeVelocityFeedforward
from harness.model.plant import Plant, TableMotion
from harness.profile import load_profile
from harness.safety.actuator_detectors import ForceTracking
from harness.safety.health import TickHealth
from tests.unit.test_hydraulics import FRICTIONLESS, IMMOVABLE

PROFILE = load_profile(None)
FORCE = PROFILE.safety.force
ACTUATOR = PROFILE.rig.actuator.hydraulics
#: The check as a rig whose servo controller has no feed-forward sets it: the plain loop's bleed.
PLAIN = dataclasses.replace(FORCE, velocity_feedforward_gain=0.0)
DT = 0.002
#: The servo controller's sample period inside a tick (the rig's physics sub-step).
SUBSTEP_S = PROFILE.rig.physics_substep_s


class _FeedforwardPlant:
    """The shipped actuator with its servo controller's feed-forward (the profile's LVDT), advanced as the rig does."""

    def __init__(self, plant: Plant, gain: float):
        self.plant = plant
        config = dataclasses.replace(ACTUATOR.feedforward, gain=gain)
        self.feedforward = StrokeVelocityFeedforward(config, ACTUATOR.feedforward_current_per_m_s(), SUBSTEP_S,
                                                     np.random.default_rng(1))
        self.feedforward.reset(0.0)

    def actuator_force(self, command: float) -> float:
        return self.plant.actuator_force(command)

    def advance(self, t0: float, t1: float, command: float) -> None:
        plant = self.plant
        for k in range(int(round((t1 - t0) / SUBSTEP_S))):
            t = t0 + k * SUBSTEP_S
            stroke = plant.y[plant.model.i_base_displacement] - plant.table_now(t)[0]
            plant.rig_params[hy.ACTUATOR_FEEDFORWARD] = self.feedforward.update(stroke)
            plant.advance(t, t + SUBSTEP_S, command)


def _sliding_plant(velocity_m_s: float, duration_s: float) -> Plant:
    """The shipped actuator pushing a base mat that stays still while the table moves at ``-velocity``."""
    times = np.arange(0.0, duration_s + 0.01, 0.01)
    table = TableMotion(0.01, np.zeros(times.size), np.full(times.size, -velocity_m_s), -velocity_m_s * times)
    params = hy.pack_rig(ACTUATOR, hydraulics_config.TableConfig(model="motion_source"), IMMOVABLE.base_mass_kg, False, 0.02)
    params[hy.ENABLED] = 1.0
    plant = Plant(IMMOVABLE, FRICTIONLESS, table, 1e-6, params)
    plant.reset()
    return plant


def _first_trip(detector: ForceTracking, velocity_m_s: float, measured, duration_s: float = 2.0,
                feedforward_gain: float | None = None) -> float | None:
    """Command steps of +-2 kN every 0.25 s; ``measured(command, plant)`` gives the load cell's reading.

    ``feedforward_gain``: the servo controller's velocity feed-forward at that gain (None: a plain loop).
    """
    plant: Plant | _FeedforwardPlant = _sliding_plant(velocity_m_s, duration_s)
    if feedforward_gain is not None:
        plant = _FeedforwardPlant(plant, feedforward_gain)
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


def test_the_plain_loops_check_accepts_a_plain_servo_hydraulic_actuator_while_it_strokes() -> None:
    assert PLAIN.velocity_feedback_Ns_per_m > 0
    for velocity in (0.02, -0.05):  # force lost ~ k_h / w_f * v: up to 4.7 kN, well past the 1.5 kN tolerance
        assert _first_trip(ForceTracking(PLAIN), velocity, _load_cell) is None


def test_a_force_source_model_trips_on_the_same_healthy_plain_actuator() -> None:
    force_source = dataclasses.replace(FORCE, velocity_feedback_Ns_per_m=0.0)
    assert _first_trip(ForceTracking(force_source), 0.05, _load_cell) is not None


def test_the_shipped_check_accepts_the_shipped_actuator_with_its_feedforward_while_it_strokes() -> None:
    # The shipped servo controller cancels the bleed (alpha = 1 through its LVDT): the check expects
    # only what the orifice leaves, c v (1/s - 1).
    assert FORCE.velocity_feedforward_gain == ACTUATOR.feedforward.gain == 1.0
    gain = ACTUATOR.feedforward.gain
    for velocity in (0.05, -0.1, 0.15):
        assert _first_trip(ForceTracking(FORCE), velocity, _load_cell, feedforward_gain=gain) is None
    # The plain loop's expectation trips the same healthy compensated rig: the check must follow the rig as configured.
    assert _first_trip(ForceTracking(PLAIN), 0.05, _load_cell, feedforward_gain=gain) is not None


def test_partial_feedforward_is_accepted_by_the_check_that_expects_its_share() -> None:
    share = dataclasses.replace(FORCE, velocity_feedforward_gain=0.8)
    assert _first_trip(ForceTracking(share), 0.1, _load_cell, feedforward_gain=0.8) is None
    assert _first_trip(ForceTracking(FORCE), 0.1, _load_cell, feedforward_gain=0.8) is not None  # 1.9 kN short


def test_the_orifice_term_of_the_expected_force_follows_the_load_pressure() -> None:
    # At 6 kN pushing along a 0.1 m/s stroke (p_L = 0.4 p_s) full feed-forward still leaves 2.7 kN:
    # beyond the 1.5 kN tolerance, so a linear c_eff = 0 would trip a healthy rig there.
    detector = ForceTracking(FORCE)
    c = FORCE.velocity_feedback_Ns_per_m
    along = detector.bleed_N(0.1, 6000.0)
    assert along == pytest.approx(c * 0.1 * (1.0 / math.sqrt(1.0 - 6000.0 / FORCE.supply_force_N) - 1.0))
    assert along > FORCE.tracking_tolerance_N
    against = detector.bleed_N(0.1, -6000.0)  # pushing against the stroke: the valve passes more, the force is higher
    assert against == pytest.approx(c * 0.1 * (1.0 / math.sqrt(1.0 + 6000.0 / FORCE.supply_force_N) - 1.0))
    assert against < 0.0
    # A load cell reading past 2/3 of A p_s cannot claim more than the working force's bleed.
    assert detector.bleed_N(0.1, 50_000.0) == pytest.approx(c * 0.1 * (math.sqrt(3.0) - 1.0))
    assert ForceTracking(dataclasses.replace(FORCE, supply_force_N=None)).bleed_N(0.1, 6000.0) == 0.0


def test_a_servo_controller_that_lost_its_feedforward_trips_the_check_that_expects_it() -> None:
    # The profile says alpha = 1, the servo controller runs a plain loop: 4.7 kN lost at 0.05 m/s.
    fired = _first_trip(ForceTracking(FORCE), 0.05, _load_cell, feedforward_gain=0.0)
    assert fired is not None and fired <= 0.25


def test_the_check_still_trips_an_actuator_that_does_not_follow_its_model() -> None:
    # A load cell that reads the command while the piston strokes: the force the model says is lost is not.
    fired = _first_trip(ForceTracking(PLAIN), 0.05, lambda command, plant: command)
    assert fired is not None and fired <= 0.25
    # An actuator pushing the wrong way (a swapped servo-valve connection), with or without the feed-forward.
    assert _first_trip(ForceTracking(PLAIN), 0.0, lambda command, plant: -plant.actuator_force(command)) is not None
    assert _first_trip(ForceTracking(FORCE), 0.05, lambda command, plant: -plant.actuator_force(command),
                       feedforward_gain=1.0) is not None


def test_the_expected_force_is_the_lagged_command_less_the_velocity_feedback() -> None:
    detector = ForceTracking(dataclasses.replace(PLAIN, actuator_time_constant_s=0.0))
    health = TickHealth(measured_force_N=0.0)
    health.meas.set(0.0, -0.1, 0.0, 0.0)  # sliding at +0.1 m/s
    detector.command_N = 3000.0
    detector.update(0.0, DT, health)
    assert detector.expected_N() == pytest.approx(3000.0 - PLAIN.velocity_feedback_Ns_per_m * 0.1)
    assert math.isfinite(detector.expected_N())
