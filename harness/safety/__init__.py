"""The safety layer: lifecycle, interlocks, fault detectors and the supervisor (pure, clock-free).

The loop builds one :class:`Supervisor` from the profile's ``safety:`` section
(:class:`SafetyConfig`), one :class:`TickHealth` it updates in place, and calls
``Supervisor.update(t, dt, health, raw_force_N)`` once per tick between the
controller and the actuator write. :data:`harness.safety.checks.CHECKS` lists the checks
in the order the supervisor runs them, and :data:`SAFETY_TABLE` says what each does.
"""

from harness.safety.checks import CHECK_NAMES, bit, names_of
from harness.safety.checks_doc import SAFETY_TABLE, SafetyRecord
from harness.safety.config import SafetyConfig, check_config
from harness.safety.events import Action
from harness.safety.health import TickHealth
from harness.safety.lifecycle import ArmRefused, IllegalTransition, ResetRefused, State
from harness.safety.supervisor import SupervisedCommand, Supervisor

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
