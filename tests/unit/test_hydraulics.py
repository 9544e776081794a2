"""The servo-hydraulic rig's physics (SPEC 7a, 7b): velocity feedback, saturation, the table under its payload.

Every case integrates the plant's compiled kernel with the rig's hydraulics in its state,
the code the virtual rig and the offline twin run.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.hydraulics import config as hydraulics_config
from harness.hydraulics import cylinder as hy
from harness.model.bearing import BearingConfig
from harness.model.building import BuildingConfig
from harness.model.plant import Plant, TableMotion
from harness.motions.tracking import tracking
from harness.profile import load_profile

PROFILE = load_profile(None)
ACTUATOR = PROFILE.rig.actuator.hydraulics
CYLINDER = ACTUATOR.cylinder
#: No friction: the bearing passes no force, so only the actuator acts between table and base.
FRICTIONLESS = BearingConfig(mu_max=0.0, mu_delta=0.0, a_mu_s_per_m=0.0, yield_displacement_m=2.5e-5, eta=3)
#: A base mat so heavy that it stays still in space while the table moves under it.
IMMOVABLE = BuildingConfig(floor_masses_kg=(958.0,), base_mass_kg=1.0e12, story_stiffness_N_per_m=(0.73e6,),
                           first_mode_damping_ratio=0.01)
STEP_S = 0.002


def _table_at_velocity(velocity_m_s: float, duration_s: float) -> TableMotion:
    """A motion-source table moving at a constant velocity."""
    times = np.arange(0.0, duration_s + 0.01, 0.01)
    return TableMotion(0.01, np.zeros(times.size), np.full(times.size, velocity_m_s), velocity_m_s * times)


def _actuator_plant(table: TableMotion, *, pinned: bool = False, building: BuildingConfig = IMMOVABLE,
                    actuator: hydraulics_config.HydraulicActuatorConfig = ACTUATOR) -> Plant:
    params = hy.pack_rig(actuator, hydraulics_config.TableConfig(model="motion_source"), building.base_mass_kg, pinned, 0.02)
    params[hy.ENABLED] = 1.0
    plant = Plant(building, FRICTIONLESS, table, 1e-6, params)
    plant.reset()
    return plant


def _run(plant: Plant, command_N: float, duration_s: float) -> list[float]:
    forces = []
    for k in range(int(round(duration_s / STEP_S))):
        plant.advance(k * STEP_S, (k + 1) * STEP_S, command_N)
        forces.append(plant.actuator_force(command_N))
    return forces


def _cylinder_state(plant: Plant) -> tuple[float, float]:
    first = plant.i_nu + 1
    return float(plant.y[first + hy.ACTUATOR_PRESSURE]), float(plant.y[first + hy.ACTUATOR_SPOOL])


# ------------------------------------------------------------- velocity feedback


def test_a_blocked_piston_reaches_and_holds_the_commanded_force() -> None:
    plant = _actuator_plant(_table_at_velocity(0.0, 3.0), pinned=True)
    forces = _run(plant, 5000.0, 3.0)
    # The force loop's bandwidth: 63 % after 1 / w_f, plus the valve's lag 2 zeta_v / w_v.
    tau_s = 1.0 / (2.0 * math.pi * ACTUATOR.force_loop_bandwidth_hz)
    valve_lag_s = 2.0 * CYLINDER.valve_damping_ratio / (2.0 * math.pi * CYLINDER.valve_bandwidth_hz)
    rise_s = STEP_S * (1 + int(np.argmax(np.array(forces) >= 5000.0 * (1 - math.exp(-1)))))
    assert tau_s <= rise_s <= tau_s + valve_lag_s + 2 * STEP_S
    # Held, short only of the error that opens the valve for the leakage C_l p_L.
    pressure, _ = _cylinder_state(plant)
    flow_gain = math.sqrt(1.0 - pressure / CYLINDER.supply_pressure_Pa)  # the orifice's, at the load pressure
    opening_per_N = CYLINDER.valve_flow_m3_per_s * flow_gain * ACTUATOR.force_gain_per_N()
    leak_error = CYLINDER.leakage_m3_per_s_Pa * pressure / opening_per_N
    assert 5000.0 - forces[-1] == pytest.approx(leak_error, rel=0.05)
    assert leak_error < 0.01 * 5000.0
    assert max(forces[len(forces) // 2 :]) - min(forces[len(forces) // 2 :]) < 5.0


@pytest.mark.parametrize("sliding_velocity_m_s", [0.05, -0.1, 0.2])
def test_a_piston_driven_at_constant_velocity_loses_force_unless_the_valve_supplies_the_flow(sliding_velocity_m_s: float) -> None:
    # The base mat stays still in space; the table moves, so the piston strokes at the sliding velocity.
    plant = _actuator_plant(_table_at_velocity(-sliding_velocity_m_s, 2.0))
    command = 4000.0
    force = _run(plant, command, 2.0)[-1]
    pressure, spool = _cylinder_state(plant)
    # The valve opens until its flow matches the piston's displacement (plus the leakage) ...
    flow = hy.valve_flow(spool, pressure, plant.rig_params, hy.ACTUATOR_CYLINDER)
    needed = CYLINDER.piston_area_m2 * sliding_velocity_m_s + CYLINDER.leakage_m3_per_s_Pa * pressure
    assert flow == pytest.approx(needed, rel=1e-3)
    # ... and a proportional loop opens it only by a force error: the force lost is that error.
    error = spool / ACTUATOR.force_gain_per_N()
    assert command - force == pytest.approx(error, rel=1e-3)
    # The loss is the loop's damping k_h / w_f times the velocity (SPEC 7a), over the orifice's
    # flow gain at the load pressure (1 at p_L = 0).
    drop = CYLINDER.supply_pressure_Pa - math.copysign(1.0, sliding_velocity_m_s) * pressure
    gain = math.sqrt(drop / CYLINDER.supply_pressure_Pa)
    assert command - force == pytest.approx(ACTUATOR.loop_damping_Ns_per_m() * sliding_velocity_m_s / gain, rel=0.01)


def test_without_the_valve_the_moving_piston_loses_force_at_the_hydraulic_stiffness() -> None:
    # Valve held shut (force loop gain ~0): the oil column alone, a spring of k_h, relaxed
    # only by the leakage over V_t / (4 beta_e C_l).
    shut = dataclasses.replace(ACTUATOR, force_loop_bandwidth_hz=1e-9)
    velocity, duration = 0.01, 0.1
    plant = _actuator_plant(_table_at_velocity(-velocity, 0.2), actuator=shut)
    forces = _run(plant, 0.0, duration)
    relax_s = 1.0 / (CYLINDER.pressure_gain_Pa_per_m3 * CYLINDER.leakage_m3_per_s_Pa)
    expected = -CYLINDER.hydraulic_stiffness_N_per_m * velocity * relax_s * (1.0 - math.exp(-duration / relax_s))
    assert forces[-1] == pytest.approx(expected, rel=1e-3)


# ------------------------------------------------------------------ saturation


def test_pressure_saturation_bounds_the_force_at_area_times_supply() -> None:
    plant = _actuator_plant(_table_at_velocity(0.0, 2.0), pinned=True)
    forces = np.array(_run(plant, 3.0 * CYLINDER.force_capacity_N, 2.0))
    assert forces.max() <= CYLINDER.force_capacity_N * (1 + hydraulics_config.RELIEF_OVERPRESSURE)
    assert forces[-1] > 0.97 * CYLINDER.force_capacity_N


def test_flow_saturation_bounds_the_velocity_at_which_force_is_held() -> None:
    # A loop stiff enough to open the valve fully (a fast valve keeps it stable): below
    # q_nl / A the loop holds the force with a small error, beyond it no gain can.
    stiff = dataclasses.replace(ACTUATOR, force_loop_bandwidth_hz=200.0,
                                cylinder=dataclasses.replace(CYLINDER, valve_bandwidth_hz=2000.0))
    top_speed = CYLINDER.valve_flow_m3_per_s / CYLINDER.piston_area_m2
    slow = _actuator_plant(_table_at_velocity(-0.5 * top_speed, 1.0), actuator=stiff)
    _run(slow, 2000.0, 1.0)
    slow_pressure, slow_spool = _cylinder_state(slow)
    fast = _actuator_plant(_table_at_velocity(-1.5 * top_speed, 1.0), actuator=stiff)
    lost = _run(fast, 2000.0, 1.0)[-1]
    pressure, fast_spool = _cylinder_state(fast)
    slow_flow = hy.valve_flow(slow_spool, slow_pressure, slow.rig_params, hy.ACTUATOR_CYLINDER)
    # Inside the valve's flow the loop finds the opening that feeds the piston: a steady force.
    assert abs(slow_spool) < 1.0
    needed = 0.5 * top_speed * CYLINDER.piston_area_m2 + CYLINDER.leakage_m3_per_s_Pa * slow_pressure
    assert slow_flow == pytest.approx(needed, rel=1e-3)
    assert fast_spool >= 1.0  # beyond it the spool is on its stop, the valve's flow at its limit ...
    # ... and the force is lost: the pressure sits on the relief, within its over-pressure.
    assert -CYLINDER.supply_pressure_Pa * (1 + hydraulics_config.RELIEF_OVERPRESSURE) <= pressure < -CYLINDER.supply_pressure_Pa
    assert lost < -0.99 * CYLINDER.force_capacity_N


def test_the_valve_flow_is_bounded_by_its_stops_and_the_supply() -> None:
    params = hy.pack_rig(ACTUATOR, hydraulics_config.TableConfig(), 1000.0, False, 0.02)
    q_nl, supply = CYLINDER.valve_flow_m3_per_s, CYLINDER.supply_pressure_Pa
    assert hy.valve_flow(5.0, 0.0, params, hy.ACTUATOR_CYLINDER) == pytest.approx(q_nl)
    assert hy.valve_flow(1.0, supply, params, hy.ACTUATOR_CYLINDER) == 0.0  # no drop across the valve, no flow in
    assert hy.valve_flow(-1.0, -supply, params, hy.ACTUATOR_CYLINDER) == 0.0
    assert hy.valve_flow(1.0, -supply, params, hy.ACTUATOR_CYLINDER) == pytest.approx(q_nl * math.sqrt(2.0))


def test_a_disabled_drive_dumps_the_pressure_with_its_decay_time() -> None:
    plant = _actuator_plant(_table_at_velocity(0.0, 2.0), pinned=True)
    held = _run(plant, 5000.0, 1.0)[-1]
    plant.rig_params[hy.ENABLED] = 0.0
    forces = _run(plant, 5000.0, 0.02)
    assert forces[-1] == pytest.approx(held * math.exp(-1.0), rel=0.05)  # 0.02 s: the drive's decay time constant


# ------------------------------------------------------------ the table


def _table_tracking_error(reaction_amplitude_N: float) -> float:
    """RMS displacement tracking error of the servo-hydraulic table, 2 Hz drive, a 2 Hz reaction on it."""
    building = PROFILE.structure
    dt, duration, frequency = 0.001, 3.0, 2.0
    times = np.arange(0.0, duration + dt, dt)
    omega = 2.0 * math.pi * frequency
    amplitude = 0.01
    drive = TableMotion(dt, -amplitude * omega**2 * np.sin(omega * times), amplitude * omega * np.cos(omega * times),
                        amplitude * np.sin(omega * times))
    params = hy.pack_rig(None, PROFILE.rig.table, building.base_mass_kg, False, 0.02)
    plant = Plant(building, PROFILE.bearing, drive, 1e-6, params)
    plant.reset()
    achieved, wanted = [], []
    for k in range(int(duration / STEP_S)):
        t = k * STEP_S
        # A force-source actuator pushes the base mat and, by reaction, the table.
        plant.advance(t, t + STEP_S, reaction_amplitude_N * math.sin(omega * t + 1.0))
        achieved.append(plant.table_now(t + STEP_S)[0])
        wanted.append(drive.state(t + STEP_S)[0])
    return tracking(np.array(achieved[250:]), np.array(wanted[250:]), STEP_S).rms_error


def test_the_tables_tracking_error_grows_with_the_payloads_reaction() -> None:
    errors = [_table_tracking_error(amplitude) for amplitude in (0.0, 5_000.0, 15_000.0)]
    assert errors[0] < errors[1] < errors[2]
    assert errors[2] > 1.5 * errors[0]


def test_a_motion_source_table_follows_its_drive_exactly() -> None:
    building = PROFILE.structure
    drive = TableMotion(0.01, np.zeros(101), np.full(101, 0.1), 0.1 * np.arange(101) * 0.01)
    params = hy.pack_rig(ACTUATOR, hydraulics_config.TableConfig(model="motion_source"), building.base_mass_kg, False, 0.02)
    plant = Plant(building, PROFILE.bearing, drive, 1e-6, params)
    plant.reset()
    plant.advance(0.0, 0.5, 0.0)
    assert plant.table_now(0.5) == pytest.approx(drive.state(0.5))


def test_the_rigs_actuator_delays_limits_and_enables_the_cylinder_of_the_live_plant() -> None:
    from harness.motions.loading import load_motion
    from harness.rig.actuator import HydraulicActuator, make_actuator
    from harness.rig.table import TablePlant

    rig = dataclasses.replace(PROFILE.rig, base_pinned=True)  # blocked: the force reaches the command
    motion = load_motion(PROFILE.record, base_dir=PROFILE.base_dir, name="synthetic", duration_s=2.0)
    table = TablePlant(PROFILE.structure, PROFILE.bearing, motion, 1e-6, rig)
    actuator = make_actuator(rig, rig.physics_substep_s, table)
    assert isinstance(actuator, HydraulicActuator)
    h = rig.physics_substep_s

    def run(command_N: float, enabled: bool, substeps: int) -> float:
        for _ in range(substeps):
            actuator.substep(command_N, enabled)
            table.advance(table.time_s, h, actuator.plant_input(0.0))
        return actuator.force_N

    assert run(50_000.0, False, 200) == 0.0  # disabled: no force, whatever the command
    assert actuator.command_N == 0.0
    actuator.reset()
    run(50_000.0, True, actuator.delay_substeps)
    assert actuator.delay_substeps == 2 and actuator.command_N == 0.0  # 1 ms of transport delay: 2 sub-steps
    run(50_000.0, True, 1)
    assert actuator.command_N == rig.actuator.force_rate_limit_N_per_s * h  # then the command slews at the rate limit
    force = run(50_000.0, True, 400)
    assert actuator.command_N == rig.actuator.force_limit_N  # the command range, reached at the rate limit
    assert 0.9 * rig.actuator.force_limit_N < force <= rig.actuator.force_limit_N * 1.001  # on the held (pre-start) plant
    table.start()
    assert actuator.force_N == pytest.approx(force)  # the state carried across; the shared enable flag still set
    assert table.rig_params[hy.ENABLED] == 1.0
