"""The servo controller's velocity feed-forward (SPEC 7a') on a known plant.

A base mat too heavy to move, a table at constant velocity: the piston strokes at a known
velocity. The feed-forward's current comes from :class:`StrokeVelocityFeedforward` on the
plant's true stroke each sub-step and the plant's compiled kernel applies the law, as the
virtual rig and the twin do (:class:`harness.rig.actuator.HydraulicActuator`).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.hydraulics import config as hydraulics_config
from harness.hydraulics import cylinder as hy
from harness.hydraulics.config import StrokeLvdtConfig, VelocityFeedforwardConfig
from harness.hydraulics.servo_controller import StrokeVelocityFeedforward, steady_bleed_N
from harness.model.plant import Plant, TableMotion
from tests.unit.test_hydraulics import ACTUATOR, CYLINDER, FRICTIONLESS, IMMOVABLE  # the same known plant

SUBSTEP_S = 0.0005
#: Ideal sensing: no noise, no quantization, no delay (the filter's lag settles at constant velocity).
IDEAL_LVDT = StrokeLvdtConfig(noise_std_m=0.0, quantization_m=0.0, delay_s=0.0)


def _run(velocity_m_s: float, command_N: float, gain: float, *, lvdt: StrokeLvdtConfig = IDEAL_LVDT,
         true_valve_flow_ratio: float = 1.0, duration_s: float = 1.5) -> tuple[float, Plant]:
    """The steady force (N) with the piston stroking at ``velocity_m_s`` under ``command_N``."""
    times = np.arange(0.0, duration_s + 0.01, 0.01)
    table = TableMotion(0.01, np.zeros(times.size), np.full(times.size, -velocity_m_s), -velocity_m_s * times)
    true = dataclasses.replace(ACTUATOR, cylinder=dataclasses.replace(
        CYLINDER, valve_flow_m3_per_s=CYLINDER.valve_flow_m3_per_s * true_valve_flow_ratio))
    params = hy.pack_rig(true, hydraulics_config.TableConfig(model="motion_source"), IMMOVABLE.base_mass_kg, False, 0.02)
    params[hy.ENABLED] = 1.0
    plant = Plant(IMMOVABLE, FRICTIONLESS, table, 1e-7, params)
    plant.reset()
    config = VelocityFeedforwardConfig(gain=gain, velocity_filter_hz=50.0, lvdt=lvdt)
    feedforward = StrokeVelocityFeedforward(config, ACTUATOR.feedforward_current_per_m_s(), SUBSTEP_S,
                                            np.random.default_rng(0))
    feedforward.reset(0.0)
    i_yb = plant.model.i_base_displacement
    for k in range(int(round(duration_s / SUBSTEP_S))):
        t = k * SUBSTEP_S
        stroke = plant.y[i_yb] - plant.table_now(t)[0]
        params[hy.ACTUATOR_FEEDFORWARD] = feedforward.update(stroke)
        plant.advance(t, t + SUBSTEP_S, command_N)
    return plant.actuator_force(command_N), plant


def _pressure(plant: Plant) -> float:
    return float(plant.y[plant.i_nu + 1 + hy.ACTUATOR_PRESSURE])


@pytest.mark.parametrize("velocity_m_s", [0.1, -0.1])
def test_full_feedforward_cancels_a_constant_velocity_bleed_at_no_load(velocity_m_s: float) -> None:
    bleed = ACTUATOR.loop_damping_Ns_per_m() * velocity_m_s  # 9.4 kN at 0.1 m/s without feed-forward
    plain, plant = _run(velocity_m_s, 0.0, 0.0)
    # alpha = 0: the plain loop's c v / s, s the orifice's factor at the load pressure the bleed itself makes.
    damping = ACTUATOR.loop_damping_Ns_per_m()
    assert -plain == pytest.approx(steady_bleed_N(damping, velocity_m_s, _pressure(plant), CYLINDER.supply_pressure_Pa, 0.0),
                                   rel=0.01)
    assert abs(plain) > 0.75 * abs(bleed)
    compensated, plant = _run(velocity_m_s, 0.0, 1.0)
    # alpha = 1, ideal sensing: what is left is the orifice's term at the small load pressure that remains.
    assert abs(compensated) < 0.005 * abs(bleed)
    expected = -steady_bleed_N(ACTUATOR.loop_damping_Ns_per_m(), velocity_m_s, _pressure(plant), CYLINDER.supply_pressure_Pa, 1.0)
    assert compensated == pytest.approx(expected, abs=5.0)


@pytest.mark.parametrize("gain", [0.5, 0.8])
def test_partial_feedforward_leaves_the_share_of_the_bleed_it_does_not_cancel(gain: float) -> None:
    force, plant = _run(0.1, 0.0, gain)
    damping = ACTUATOR.loop_damping_Ns_per_m()
    assert -force == pytest.approx(steady_bleed_N(damping, 0.1, _pressure(plant), CYLINDER.supply_pressure_Pa, gain), rel=0.01)
    # (1 - alpha) c v over the orifice's factor: the bleed's own load pressure aids the flow, so a little less.
    assert 0.7 * (1.0 - gain) * damping * 0.1 < -force < (1.0 - gain) * damping * 0.1
    assert ACTUATOR.velocity_feedback_Ns_per_m() == pytest.approx(0.0)  # the profile's alpha = 1
    half = dataclasses.replace(ACTUATOR, feedforward=dataclasses.replace(ACTUATOR.feedforward, gain=gain))
    assert half.velocity_feedback_Ns_per_m() == pytest.approx((1.0 - gain) * ACTUATOR.loop_damping_Ns_per_m())


@pytest.mark.parametrize("velocity_m_s", [0.1, -0.1])
def test_at_load_pressure_the_orifice_leaves_a_residual_of_the_sqrt_factor(velocity_m_s: float) -> None:
    command = 5_000.0  # p_L = 6.9 MPa, a third of the supply
    force, plant = _run(velocity_m_s, command, 1.0)
    pressure = _pressure(plant)
    s = math.sqrt(1.0 - math.copysign(1.0, velocity_m_s) * pressure / CYLINDER.supply_pressure_Pa)
    predicted = ACTUATOR.loop_damping_Ns_per_m() * velocity_m_s * (1.0 / s - 1.0)
    assert command - force == pytest.approx(predicted, rel=0.03)
    # Size: 22 % of the plain bleed when the force pushes along the stroke, -11 % against it ...
    assert abs(predicted) > 0.1 * ACTUATOR.loop_damping_Ns_per_m() * 0.1
    # ... and the sign that always lowers |u|: the feed-forward's flow is short when the load
    # pressure resists the flow, long when it helps.
    assert 0.0 < force < command


def test_a_valve_gain_above_the_nominal_overcompensates() -> None:
    # The plant's valve passes 30 % more than the controller's nominal K_q: the feed-forward
    # opens it by the nominal share, so it supplies 1.3 x the flow and the force rises above the command.
    force, plant = _run(0.1, 0.0, 1.0, true_valve_flow_ratio=1.3)
    true_damping = ACTUATOR.loop_damping_Ns_per_m()  # K_p follows the true valve (tuned on the rig): c is unchanged
    expected = -steady_bleed_N(true_damping, 0.1, _pressure(plant), CYLINDER.supply_pressure_Pa, 1.0, 1.3)
    assert force == pytest.approx(expected, rel=0.03)
    assert force > 0.2 * true_damping * 0.1  # ~0.3 c v, less the orifice's share


def test_the_lvdts_delay_and_filter_leave_a_lag_not_a_steady_error() -> None:
    lvdt = StrokeLvdtConfig(noise_std_m=3e-6, quantization_m=3.1e-6, delay_s=0.0005)  # the profile's class
    force, _ = _run(0.1, 0.0, 1.0, lvdt=lvdt)
    assert abs(force) < 0.02 * ACTUATOR.loop_damping_Ns_per_m() * 0.1  # the noise's share at steady velocity


def test_the_filtered_derivative_measures_the_velocity_with_its_delay() -> None:
    config = VelocityFeedforwardConfig(gain=1.0, velocity_filter_hz=50.0,
                                       lvdt=StrokeLvdtConfig(noise_std_m=0.0, quantization_m=0.0, delay_s=0.002))
    feedforward = StrokeVelocityFeedforward(config, 2.0, SUBSTEP_S, np.random.default_rng(0))
    feedforward.reset(0.0)
    currents = [feedforward.update(0.1 * k * SUBSTEP_S) for k in range(1, 400)]
    assert currents[3] == 0.0  # the LVDT's 2 ms: 4 samples before the ramp shows
    assert currents[4] > 0.0
    assert currents[-1] == pytest.approx(2.0 * 0.1, rel=1e-6)  # gain x A / q_nl x v at steady velocity
