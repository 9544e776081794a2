"""The safety layer: lifecycle, interlocks, fault detectors and the supervisor (pure, clock-free).

The loop builds one :class:`Supervisor` from the profile's ``safety:`` section
(:class:`SafetyConfig`), one :class:`TickHealth` it updates in place, and calls
``Supervisor.update(t, dt, health, raw_force_N)`` once per tick between the
controller and the actuator write. See :mod:`harness.safety.supervisor` for the
order of the checks and :data:`SAFETY_TABLE` for what each check does.
"""

from harness.safety.config import SafetyConfig, check_config
from harness.safety.events import CHECK_NAMES, Action, bit, names_of
from harness.safety.health import TickHealth
from harness.safety.lifecycle import ArmRefused, IllegalTransition, ResetRefused, State
from harness.safety.supervisor import SupervisedCommand, Supervisor
from harness.safety.table import SAFETY_TABLE, SafetyRecord

__all__ = [
    "CHECK_NAMES",
    "SAFETY_TABLE",
    "Action",
    "ArmRefused",
    "IllegalTransition",
    "ResetRefused",
    "SafetyConfig",
    "SafetyRecord",
    "State",
    "SupervisedCommand",
    "Supervisor",
    "TickHealth",
    "bit",
    "check_config",
    "names_of",
]
