"""The safety layer: lifecycle, interlocks, fault detectors and the supervisor (pure, clock-free).

The loop builds one :class:`Supervisor` from the profile's ``safety:`` section
(:class:`SafetyConfig`), one :class:`TickHealth` it updates in place, and calls
``Supervisor.update(t, dt, health, raw_force_N)`` once per tick between the
controller and the actuator write. :data:`harness.safety.checks.CHECKS` lists the checks
in the order the supervisor runs them, and :data:`SAFETY_TABLE` says what each does.
"""

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from harness.safety.checks import CHECK_NAMES, bit, names_of
    from harness.safety.checks_doc import SAFETY_TABLE, SafetyRecord
    from harness.safety.config import SafetyConfig, check_config
    from harness.safety.events import Action
    from harness.safety.health import TickHealth
    from harness.safety.lifecycle import ArmRefused, IllegalTransition, ResetRefused, State
    from harness.safety.supervisor import SupervisedCommand, Supervisor

#: Where each name of the package lives. The names are loaded on first use (PEP 562), so that
#: importing ``harness.safety.config`` to build the command line's parser does not import the
#: checks and, through them, numba and scipy (``harness --help`` stays fast).
_HOME = {
    "CHECK_NAMES": "checks", "bit": "checks", "names_of": "checks",
    "SAFETY_TABLE": "checks_doc", "SafetyRecord": "checks_doc",
    "SafetyConfig": "config", "check_config": "config",
    "Action": "events", "TickHealth": "health",
    "ArmRefused": "lifecycle", "IllegalTransition": "lifecycle", "ResetRefused": "lifecycle", "State": "lifecycle",
    "SupervisedCommand": "supervisor", "Supervisor": "supervisor",
}


def __getattr__(name: str) -> Any:
    """Load a name of the package from its module on first use."""
    if name not in _HOME:
        raise AttributeError(f"module 'harness.safety' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"harness.safety.{_HOME[name]}"), name)
    globals()[name] = value
    return value


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
