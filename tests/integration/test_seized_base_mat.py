"""A base mat that seizes at peak sliding velocity: the pressure transient of a blocked piston (issue 31, item 2).

The shipped rig's control actuator (its cylinder, valve and force loop, the compiled rates of
harness/hydraulics/cylinder.py, and its servo controller's velocity feed-forward through the stroke
LVDT's delay and filter, harness/hydraulics/servo_controller.py) strokes at a steady sliding velocity
under the harness's command at its bound, and the piston is blocked at once. The harness's own
flow term (``model`` compensation on a plain loop) acts on the measured velocity through the
sensor's delay and a tick before it sees the stop. docs/SAFETY.md, "What max_force_N must bound",
derives the bound these runs are held to and gives their figures (``seize_peak_N``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.hydraulics.config import RELIEF_OVERPRESSURE
from harness.hydraulics.cylinder import ACTUATOR_CYLINDER, cylinder_rates, force_loop_current, pack_rig
from harness.hydraulics.servo_controller import StrokeVelocityFeedforward
from harness.profile import load_profile
from harness.safety.actuator_detectors import LoadCellLimit
from harness.safety.health import TickHealth

PROFILE = load_profile()
RIG, FORCE = PROFILE.rig, PROFILE.safety.force
HYDRAULICS = RIG.actuator.hydraulics
PERIOD_S = 1.0 / PROFILE.control.rate_hz
SENSOR_DELAY_S = 0.001  # the base mat's sensor message delay of the shipped profile (rig.sensors, delay_s)
SUBSTEP_S = RIG.physics_substep_s
INNER = 20  # RK4 steps per physics sub-step: well inside the 75 Hz valve and the oil column


def _rk4(y: np.ndarray, h: float, current: float, velocity: float, params: np.ndarray) -> None:
    k = [np.zeros(3) for _ in range(4)]
    cylinder_rates(y, k[0], 0, current, velocity, 0.0, params, ACTUATOR_CYLINDER)
    cylinder_rates(y + 0.5 * h * k[0], k[1], 0, current, velocity, 0.0, params, ACTUATOR_CYLINDER)
    cylinder_rates(y + 0.5 * h * k[1], k[2], 0, current, velocity, 0.0, params, ACTUATOR_CYLINDER)
    cylinder_rates(y + h * k[2], k[3], 0, current, velocity, 0.0, params, ACTUATOR_CYLINDER)
    y += h / 6.0 * (k[0] + 2.0 * k[1] + 2.0 * k[2] + k[3])


def seize_peak_N(velocity_m_s: float, feedforward_gain: float, harness_flow_Ns_per_m: float,
                 settle_s: float = 0.3, after_s: float = 0.1) -> tuple[float, float]:
    """Peak load-cell force after the seize, and the force just before it (N).

    The harness commands ``max_force_N`` along the stroke plus, when ``harness_flow_Ns_per_m`` > 0, a flow
    term on the sliding velocity it reads (sampled each tick, ``SENSOR_DELAY_S`` old), bounded by
    ``max_flow_term_N``; the rig's servo controller adds its feed-forward at ``feedforward_gain``.
    """
    hydraulics = dataclasses.replace(HYDRAULICS, feedforward=dataclasses.replace(HYDRAULICS.feedforward, gain=feedforward_gain))
    params = pack_rig(hydraulics, RIG.table, 1.0, False, RIG.drive.decay_time_constant_s)
    area = hydraulics.cylinder.piston_area_m2
    feedforward = StrokeVelocityFeedforward(hydraulics.feedforward, hydraulics.feedforward_current_per_m_s(), SUBSTEP_S,
                                            np.random.default_rng(1))
    feedforward.reset(0.0)
    gain = hydraulics.force_gain_per_N()
    y = np.zeros(3)
    stroke, command = 0.0, 0.0
    seize_at = settle_s
    steps = round((settle_s + after_s) / SUBSTEP_S)
    per_tick = round(PERIOD_S / SUBSTEP_S)
    before, peak = 0.0, 0.0
    for n in range(steps):
        t = n * SUBSTEP_S
        velocity = velocity_m_s if t < seize_at else 0.0
        if n % per_tick == 0:  # the harness's tick: the velocity it reads is SENSOR_DELAY_S old
            read = velocity_m_s if t - SENSOR_DELAY_S < seize_at else 0.0
            flow = min(FORCE.max_flow_term_N, harness_flow_Ns_per_m * read)
            command = FORCE.max_force_N + flow
        current = force_loop_current(gain, command, area * y[0], feedforward.update(stroke)) if n else 0.0
        for _ in range(INNER):
            _rk4(y, SUBSTEP_S / INNER, current, velocity, params)
        stroke += velocity * SUBSTEP_S
        force = area * y[0]
        if t < seize_at:
            before = force
        else:
            peak = max(peak, force)
    return peak, before


def transient_bound_N(velocity_m_s: float, feedforward_gain: float, harness_flow_Ns_per_m: float) -> float:
    """docs/SAFETY.md's bound: the command's blocked-piston force plus the feed-forward's stale flow.

    ``max_force_N + min(max_flow_term_N, c_h v) + k_h * alpha * v * (tau_lvdt + tau_filter + tau_valve)``,
    capped by the relief valves at ``A p_s`` (1.02 of it, their overpressure).
    """
    cylinder, feedforward = HYDRAULICS.cylinder, HYDRAULICS.feedforward
    stale_s = (feedforward.lvdt.delay_s + 1.0 / (2.0 * math.pi * feedforward.velocity_filter_hz)
               + 2.0 * HYDRAULICS.cylinder.valve_damping_ratio / (2.0 * math.pi * cylinder.valve_bandwidth_hz))
    transient = cylinder.hydraulic_stiffness_N_per_m * feedforward_gain * velocity_m_s * stale_s
    flow = min(FORCE.max_flow_term_N, harness_flow_Ns_per_m * velocity_m_s)
    return min(FORCE.max_force_N + flow + transient, (1.0 + RELIEF_OVERPRESSURE) * cylinder.force_capacity_N)


CASES = {
    # the shipped rig: its servo controller's feed-forward, no harness flow term
    "rig_feedforward": (HYDRAULICS.feedforward.gain, 0.0),
    # a plain loop with the harness's model compensation: its flow term k_h / w_f on the velocity read
    "plain_loop_model": (0.0, HYDRAULICS.loop_damping_Ns_per_m()),
}


#: 0.24 m/s: the peak sliding velocity of the default dry run (synthetic 0.34 g, lockstep, 12 s, ``model``).
@pytest.mark.parametrize("velocity_m_s", [0.05, 0.1, 0.2, 0.24])
@pytest.mark.parametrize("case", sorted(CASES))
def test_a_base_mat_that_seizes_at_peak_sliding_velocity_stays_within_the_derived_bound(case: str, velocity_m_s: float):
    gain, flow = CASES[case]
    peak, before = seize_peak_N(velocity_m_s, gain, flow)
    bound = transient_bound_N(velocity_m_s, gain, flow)
    assert peak <= bound, f"{case} at {velocity_m_s} m/s: peak {peak:.0f} N, bound {bound:.0f} N"
    assert peak > before  # the seize does raise the force: the case exercises the transient


def test_the_load_cell_limit_trips_a_seize_that_carries_the_load_cell_beyond_it():
    """At the measured peak sliding velocity, 0.24 m/s, with the rig's feed-forward the blocked piston
    passes load_cell_limit_N: the check trips it."""
    peak, _ = seize_peak_N(0.24, HYDRAULICS.feedforward.gain, 0.0)
    assert peak > FORCE.load_cell_limit_N
    det, health = LoadCellLimit(FORCE), TickHealth()
    health.measured_force_N = peak
    n = round(FORCE.load_cell_limit_time_s / PERIOD_S)
    assert [det.update(k * PERIOD_S, PERIOD_S, health) for k in range(n + 1)][-1]


# ---------------------------------------------------------------- the same case on the rig twin
#: The default dry run's record (synthetic, 0.34 g), 12 s: long enough to hold its peak sliding velocity.
TWIN_DURATION_S = 12.0
#: What the twin runs on after the seize; the drive's pressure decays in rig.drive.decay_time_constant_s (20 ms).
AFTER_SEIZE_S = 0.2
TWIN_CASES = {
    # the shipped rig: its servo controller's feed-forward, no harness compensation
    "rig_feedforward": [],
    # a plain loop with the harness's model compensation (its flow term bounded by max_flow_term_N)
    "plain_loop_model": ["rig.actuator.hydraulics.feedforward.gain=0", "safety.force.velocity_feedforward_gain=0",
                         "control.compensation=model"],
}


def _twin(overrides: list[str], duration_s: float, after_trip_s: float = 0.0):
    from harness.control.factory import build_controller_for_rig
    from harness.runs.options import prepare_motion
    from harness.simulation.twin import run_rig_twin

    profile = load_profile(overrides=[f"record.duration_s={TWIN_DURATION_S}", *overrides])
    return run_rig_twin(profile, prepare_motion(profile), profile.control.rate_hz, build_controller_for_rig(profile, "phi"),
                        duration_s=duration_s, after_trip_s=after_trip_s)


@pytest.mark.parametrize("case", sorted(TWIN_CASES))
def test_a_base_mat_seized_at_peak_sliding_velocity_on_the_twin_keeps_the_load_cell_within_the_derived_bound(case: str):
    """The whole loop on the rig twin: the phi controller drives the base mat, the bearings seize (``rig.faults``
    kind ``seize``) at the record's peak sliding velocity, and the load cell's peak after it is held to the
    bound of docs/SAFETY.md for the command the harness was sending; beyond ``load_cell_limit_N`` it must trip."""
    overrides = TWIN_CASES[case]
    free = _twin(overrides, TWIN_DURATION_S)
    sliding = free.columns["sliding_velocity_m_s"]
    peak_at = int(np.argmax(np.abs(sliding)))
    seize_s = float(free.columns["t_s"][peak_at]) - SENSOR_DELAY_S  # the reading is the sensor's delay old
    seized = _twin([*overrides, f"rig.faults=[{{kind: seize, start_s: {seize_s!r}}}]"], seize_s + AFTER_SEIZE_S,
                   after_trip_s=AFTER_SEIZE_S)
    velocity = abs(seized.extra["seized_at_velocity_m_s"])
    assert velocity > 0.5 * abs(sliding[peak_at])  # the seize stopped the base mat near its peak velocity
    times, load_cell = seized.columns["t_s"], np.abs(seized.columns["force_measured_N"])
    before, after = load_cell[times < seize_s][-1], load_cell[times >= seize_s]
    gain = HYDRAULICS.feedforward.gain if not overrides else 0.0
    flow = HYDRAULICS.loop_damping_Ns_per_m() if "control.compensation=model" in overrides else 0.0
    bound = transient_bound_N(velocity, gain, flow)
    assert after.max() > before  # the blocked piston does load the cell
    assert after.max() <= bound, f"{case}: peak {after.max():.0f} N at {velocity:.3f} m/s, bound {bound:.0f} N"
    if after.max() > FORCE.load_cell_limit_N + 1.0:  # held beyond it for load_cell_limit_time_s: the check trips
        assert seized.extra["outcome"] == "tripped"
