"""Each pre-arm refusal, whole: the check's name, what was found and what was expected.

The operator reads these lines when a run will not arm; each test makes exactly one check fail
on an otherwise healthy sample and matches the one line it gives.
"""

from __future__ import annotations

import dataclasses
import math

import pytest

from harness.safety.config import SafetyConfig
from harness.safety.health import TickHealth
from harness.safety.prearm import PRE_ARM_CHECKS, pre_arm_failures

CONFIG = SafetyConfig()


def _healthy() -> TickHealth:
    health = TickHealth()
    health.drive_ready = True
    health.pressure_ok = True
    health.e2e_ok = True
    health.table_age_s = health.base_age_s = 0.001
    health.actuator_status_age_s = 0.002
    health.estop_panel_age_s = 0.05
    return health


def test_a_healthy_sample_arms() -> None:
    assert pre_arm_failures(CONFIG, _healthy()) == ()


def _set(**values):
    def apply(health: TickHealth) -> None:
        for name, value in values.items():
            setattr(health.meas if name.endswith(("_m", "_m_s")) else health, name, value)
    return apply


SENSOR_AGE_MS = CONFIG.sensors.max_sensor_age_s * 1e3
FRESH = f"expected 0 <= age <= {SENSOR_AGE_MS:.2f} ms"
STATUS_AGE_MS = CONFIG.actuator.max_status_age_s * 1e3
PANEL_AGE_MS = CONFIG.estop.max_panel_age_s * 1e3
CASES = [
    (_set(table_age_s=0.0305), f"sensors_fresh: table age 30.50 ms, base age 1.00 ms, {FRESH}"),
    (_set(base_age_s=-0.001), f"sensors_fresh: table age 1.00 ms, base age -1.00 ms, {FRESH}"),
    (_set(base_velocity_m_s=math.nan), "sensors_valid: found (0.0, 0.0, 0.0, nan), expected finite values"),
    (_set(e2e_ok=False), "e2e_ok: the newest frame failed its counter/CRC check, expected good frames"),
    (_set(base_displacement_m=0.0123),
     f"stroke_centred: |x_b| = 0.0123 m, expected <= {CONFIG.stroke.arm_tolerance_m:g} m"),
    (_set(drive_ready=False), "actuator_ready: drive ready=False, fault=False, expected ready without fault"),
    (_set(drive_fault=True), "actuator_ready: drive ready=True, fault=True, expected ready without fault"),
    (_set(pressure_ok=False), "hydraulic_pressure: pressure not ok, expected ok"),
    (_set(actuator_status_age_s=0.5),
     f"actuator_status_fresh: status age 500.00 ms, expected 0 <= age <= {STATUS_AGE_MS:.2f} ms"),
    (_set(foreign_command=True), "no_foreign_command: another node sends on the actuator command ID, expected none"),
    (_set(bus_gone=True), "bus_ok: gone=True, bus-off=False, error-passive=False, expected an error-active bus"),
    (_set(bus_off=True), "bus_ok: gone=False, bus-off=True, error-passive=False, expected an error-active bus"),
    (_set(error_passive=True), "bus_ok: gone=False, bus-off=False, error-passive=True, expected an error-active bus"),
    (_set(estop=True), "estop_clear: E-stop asserted, expected released"),
    (_set(operator_stop=True), "no_operator_request: stop=True, trip=False pending, expected none"),
    (_set(operator_trip=True), "no_operator_request: stop=False, trip=True pending, expected none"),
    (_set(estop_panel_age_s=math.inf),
     f"estop_panel_live: newest E-stop panel frame inf ms old, expected 0 <= age <= {PANEL_AGE_MS:.1f} ms (plug the "
     "panel in; safety.estop.panel_required: false declares that none is wired)"),
]


@pytest.mark.parametrize(("fault", "line"), CASES, ids=[line.split(":")[0] + str(i) for i, (_, line) in enumerate(CASES)])
def test_each_refusal_is_one_whole_line(fault, line: str) -> None:
    health = _healthy()
    fault(health)
    assert pre_arm_failures(CONFIG, health) == (line,)


def test_every_check_has_a_case_and_refusals_come_in_the_checks_order() -> None:
    named = {line.split(":")[0] for _, line in CASES}
    assert named | {"config"} == set(PRE_ARM_CHECKS)
    health = _healthy()
    for fault, _ in CASES:
        fault(health)
    names = [line.split(":")[0] for line in pre_arm_failures(CONFIG, health)]
    assert names == [name for name in PRE_ARM_CHECKS if name != "config"]


def test_without_a_wired_panel_its_age_is_not_judged() -> None:
    config = dataclasses.replace(CONFIG, estop=dataclasses.replace(CONFIG.estop, panel_required=False))
    health = _healthy()
    health.estop_panel_age_s = math.inf
    assert pre_arm_failures(config, health) == ()
