"""Pre-arm checks: everything that must hold before the drive may be enabled.

Arming is not a per-tick operation, so these checks may allocate. Each failure is
one sentence naming the check, what was found and what was expected.
"""

from __future__ import annotations

import math

from harness.safety.config import SafetyConfig, check_config
from harness.safety.health import TickHealth

#: Names of the pre-arm checks, in the order they are evaluated.
PRE_ARM_CHECKS: tuple[str, ...] = (
    "config",
    "sensors_fresh",
    "sensors_valid",
    "e2e_ok",
    "stroke_centred",
    "actuator_ready",
    "hydraulic_pressure",
    "actuator_status_fresh",
    "no_foreign_command",
    "bus_ok",
    "estop_clear",
    "no_operator_request",
    "estop_panel_live",
)


def _sensor_failures(config: SafetyConfig, health: TickHealth) -> list[str]:
    failed = []
    max_age = config.sensors.max_sensor_age_s
    if not (0.0 <= health.table_age_s <= max_age and 0.0 <= health.base_age_s <= max_age):
        failed.append(
            f"sensors_fresh: table age {health.table_age_s * 1e3:.2f} ms, base age {health.base_age_s * 1e3:.2f} ms, "
            f"expected 0 <= age <= {max_age * 1e3:.2f} ms"
        )
    meas = health.meas
    values = (meas.table_displacement_m, meas.table_velocity_m_s, meas.base_displacement_m, meas.base_velocity_m_s)
    if not all(math.isfinite(v) for v in values):
        failed.append(f"sensors_valid: found {values}, expected finite values")
    if not health.e2e_ok:
        failed.append("e2e_ok: the newest frame failed its counter/CRC check, expected good frames")
    x_b = meas.sliding_displacement_m
    tolerance = config.stroke.arm_tolerance_m
    if not abs(x_b) <= tolerance:
        failed.append(f"stroke_centred: |x_b| = {abs(x_b):.6g} m, expected <= {tolerance:g} m")
    return failed


def _actuator_failures(config: SafetyConfig, health: TickHealth) -> list[str]:
    failed = []
    if not health.drive_ready or health.drive_fault:
        failed.append(
            f"actuator_ready: drive ready={health.drive_ready}, fault={health.drive_fault}, expected ready without fault"
        )
    if not health.pressure_ok:
        failed.append("hydraulic_pressure: pressure not ok, expected ok")
    max_age = config.actuator.max_status_age_s
    if not 0.0 <= health.actuator_status_age_s <= max_age:
        failed.append(
            f"actuator_status_fresh: status age {health.actuator_status_age_s * 1e3:.2f} ms, "
            f"expected 0 <= age <= {max_age * 1e3:.2f} ms"
        )
    if health.foreign_command:
        failed.append("no_foreign_command: another node sends on the actuator command ID, expected none")
    return failed


def _bus_and_operator_failures(health: TickHealth) -> list[str]:
    failed = []
    if health.bus_gone or health.bus_off or health.error_passive:
        failed.append(
            f"bus_ok: gone={health.bus_gone}, bus-off={health.bus_off}, error-passive={health.error_passive}, "
            "expected an error-active bus"
        )
    if health.estop:
        failed.append("estop_clear: E-stop asserted, expected released")
    if health.operator_stop or health.operator_trip:
        failed.append(
            f"no_operator_request: stop={health.operator_stop}, trip={health.operator_trip} pending, expected none"
        )
    return failed


def _panel_failures(config: SafetyConfig, health: TickHealth) -> list[str]:
    """No arming without a live E-stop panel, unless the profile says explicitly that none is wired."""
    estop = config.estop
    if not estop.panel_required or 0.0 <= health.estop_panel_age_s <= estop.max_panel_age_s:
        return []
    return [
        f"estop_panel_live: newest E-stop panel frame {health.estop_panel_age_s * 1e3:.1f} ms old, expected "
        f"0 <= age <= {estop.max_panel_age_s * 1e3:.1f} ms (plug the panel in; safety.estop.panel_required: false "
        "declares that none is wired)"
    ]


def pre_arm_failures(config: SafetyConfig, health: TickHealth) -> tuple[str, ...]:
    """Evaluate every pre-arm check; return the failures (empty when arming is allowed).

    Parameters
    ----------
    config : SafetyConfig
        The safety configuration (its consistency is one of the checks).
    health : TickHealth
        The loop's latest health sample (sensor freshness, stroke, actuator, bus, operator).

    Returns
    -------
    tuple of str
        One entry per failed check, each starting with the check's name from :data:`PRE_ARM_CHECKS`.
    """
    failed = [f"config: {problem}" for problem in check_config(config)]
    failed += _sensor_failures(config, health)
    failed += _actuator_failures(config, health)
    failed += _bus_and_operator_failures(health)
    failed += _panel_failures(config, health)
    return tuple(failed)
