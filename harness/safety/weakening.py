"""Which way each safety setting weakens, and what the command line weakened.

A profile's ``safety:`` section is the profile's own choice: what its file says (with what it
``extends``, and the ``--variant`` chosen, since a variant is written in the same file). The
command line's ``--set`` may change it; making it *stricter* needs nothing, making it *weaker*
needs ``--allow-weaker-safety`` and is then recorded (``metadata.json``, the live console, the
outcome line). :data:`DIRECTIONS` says, for every field, which change is the weaker one;
``tests/unit/test_safety_weakening.py`` fails if a field of :class:`SafetyConfig` has no entry.

Directions (docs/SAFETY.md, "Which change weakens a safety setting"):

- ``larger`` -- a limit, tolerance, age, persistence time, count allowed, filter time constant or
  stopping time: larger lets more through or acts later. ``None`` (no value) counts as infinite.
- ``smaller`` -- a look-ahead (``stroke.stop_time_s``), a claimed actuator lag (smaller widens the
  blind time :func:`~harness.safety.config.check_config` allows), a sliding window of a
  "more than N within window_s" detector (a shorter window allows a higher fault rate), the
  event ring (a smaller one overwrites more of the record).
- ``milder`` -- a detector action: trip, then safe_stop, then indicate.
- ``fewer`` -- a list of trip actions: dropping any action the profile lists.
- ``off`` -- a requirement switched from true to false.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal

from harness.errors import ProfileError
from harness.safety.config import SafetyConfig

Direction = Literal["larger", "smaller", "milder", "fewer", "off"]

#: The command-line flag that accepts a weakening.
FLAG = "--allow-weaker-safety"

#: Severity of a detector action; a lower rank is milder.
ACTION_RANK: dict[str, int] = {"indicate": 0, "safe_stop": 1, "trip": 2}

#: For every field of the ``safety:`` section (``section.field``), the change that weakens it.
DIRECTIONS: dict[str, Direction] = {
    "stroke.soft_limit_m": "larger",
    "stroke.fade_band_m": "larger",  # outward force reaches zero further out
    "stroke.hard_limit_m": "larger",
    "stroke.stop_time_s": "smaller",  # a shorter look-ahead trips later
    "stroke.arm_tolerance_m": "larger",
    "force.max_force_N": "larger",
    "force.max_force_rate_N_per_s": "larger",
    "force.max_flow_term_N": "larger",
    "force.load_cell_limit_N": "larger",
    "force.load_cell_limit_time_s": "larger",
    "force.tracking_tolerance_N": "larger",
    "force.tracking_time_s": "larger",
    "force.actuator_time_constant_s": "smaller",  # a faster claimed actuator widens the stall budget
    "force.velocity_feedback_Ns_per_m": "larger",  # a larger claimed force deficit at speed hides more of a real one
    "force.velocity_feedforward_gain": "smaller",  # a smaller claimed cancellation claims a larger deficit at speed
    "force.supply_force_N": "smaller",  # a smaller A p_s claims a larger deficit when the force pushes along the stroke
    "force.tracking_action": "milder",
    "force.actuator_rating_N": "larger",  # None (no rating declared) is the weakest
    "force.oscillation_corner_hz": "larger",  # a higher corner hides a limit cycle between the two
    "force.oscillation_window_s": "larger",  # a longer window acts later
    "force.oscillation_limit_N": "larger",
    "force.oscillation_action": "milder",
    "sensors.max_sensor_age_s": "larger",
    "sensors.displacement_range_m": "larger",
    "sensors.velocity_range_m_s": "larger",
    "sensors.jump_limit_m": "larger",
    "sensors.jump_limit_m_s": "larger",
    "sensors.stuck_samples": "larger",
    "sensors.disagree_tolerance_m_s": "larger",
    "sensors.disagree_time_s": "larger",
    "sensors.disagree_filter_s": "larger",  # a slower filter hides and delays a disagreement
    "sensors.sign_flip_floor_m_s": "larger",
    "sensors.sign_flip_time_s": "larger",
    "sensors.polarity_floor_m_s": "larger",
    "sensors.polarity_window_s": "larger",  # a longer window acts later
    "comms.max_e2e_rejects": "larger",
    "comms.e2e_window_s": "smaller",  # "more than N within the window": a shorter window allows a higher rate
    "comms.max_error_frames": "larger",
    "comms.error_frame_window_s": "smaller",
    "comms.error_frame_action": "milder",
    "comms.error_passive_action": "milder",
    "comms.max_send_failures": "larger",
    "comms.send_failure_window_s": "smaller",
    "actuator.max_status_age_s": "larger",
    "run.stopping_ramp_s": "larger",  # the force stays on longer after a stop (check_config bounds it below)
    "run.max_stall_s": "larger",
    "run.event_capacity": "smaller",  # a smaller ring overwrites more events of the record
    "trip_actions.stroke": "fewer",
    "trip_actions.sensor": "fewer",
    "trip_actions.comms": "fewer",
    "trip_actions.actuator": "fewer",
    "trip_actions.loop": "fewer",
    "trip_actions.operator": "fewer",
    "trip_actions.internal": "fewer",
    "estop.panel_required": "off",
    "estop.max_panel_age_s": "larger",
}


@dataclass(frozen=True)
class Weakening:
    """One safety setting the command line made weaker than the profile's own value.

    Attributes
    ----------
    key : str
        Full key path, e.g. ``safety.stroke.stop_time_s``.
    profile_value : object
        The profile's own value (file, extends, variant).
    value : object
        The value the run uses.
    direction : str
        Which change weakens this field (:data:`DIRECTIONS`).
    """

    key: str
    profile_value: Any
    value: Any
    direction: Direction

    def describe(self) -> str:
        """``safety.stroke.stop_time_s 0.05 -> 0.02`` (the profile's value, then the run's)."""
        return f"{self.key} {_text(self.profile_value)} -> {_text(self.value)}"

    def as_dict(self) -> dict[str, Any]:
        """Plain data for ``metadata.json``."""
        return {"key": self.key, "profile_value": _plain(self.profile_value), "value": _plain(self.value),
                "direction": self.direction}


def _text(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, tuple):
        return "[" + ", ".join(map(str, value)) + "]"
    return "null" if value is None else str(value)


def _plain(value: Any) -> Any:
    return list(value) if isinstance(value, tuple) else value


def safety_fields(config: SafetyConfig | None = None) -> dict[str, Any]:
    """Every field of a safety configuration as ``{"section.field": value}``.

    Parameters
    ----------
    config : SafetyConfig, optional
        Default: the code's defaults.
    """
    config = config if config is not None else SafetyConfig()
    values: dict[str, Any] = {}
    for section in dataclasses.fields(config):
        group = getattr(config, section.name)
        for item in dataclasses.fields(group):
            values[f"{section.name}.{item.name}"] = getattr(group, item.name)
    return values


def is_weaker(direction: Direction, old: Any, new: Any) -> bool:
    """True if changing a field from ``old`` to ``new`` weakens it in ``direction``.

    Raises
    ------
    ValueError
        For an unknown direction.
    """
    if old == new:
        return False
    if direction in ("larger", "smaller"):
        before, after = (math.inf if v is None else v for v in (old, new))
        return after > before if direction == "larger" else after < before
    if direction == "milder":
        return ACTION_RANK[new] < ACTION_RANK[old]
    if direction == "fewer":
        return not set(old) <= set(new)
    if direction == "off":
        return bool(old) and not new
    raise ValueError(f"unknown direction {direction!r}, expected one of larger, smaller, milder, fewer, off")


def weakenings(own: SafetyConfig, used: SafetyConfig, directions: Mapping[str, Direction] = DIRECTIONS) -> tuple[Weakening, ...]:
    """Every field of ``used`` weaker than in ``own``, in the order of the configuration.

    Parameters
    ----------
    own : SafetyConfig
        The profile's own safety section.
    used : SafetyConfig
        The safety section the run uses (after ``--set``).
    directions : mapping
        Field -> direction; default :data:`DIRECTIONS`.

    Raises
    ------
    KeyError
        If a field has no direction (a new field must be given one).
    """
    before, after = safety_fields(own), safety_fields(used)
    return tuple(
        Weakening(f"safety.{name}", before[name], after[name], directions[name])
        for name in before
        if is_weaker(directions[name], before[name], after[name])
    )


def require_acknowledged(weakened: tuple[Weakening, ...], allowed: bool, source: str | None = None) -> None:
    """Refuse a weakening the command line did not acknowledge with :data:`FLAG`.

    Parameters
    ----------
    weakened : tuple of Weakening
        What the overrides weakened (``Profile.safety_weakened``).
    allowed : bool
        Whether :data:`FLAG` was given.
    source : str, optional
        The profile file, for the message.

    Raises
    ------
    ProfileError
        Listing each weakened key with the profile's value and the new one.
    """
    if weakened and not allowed:
        listed = "; ".join(item.describe() for item in weakened)
        raise ProfileError(
            f"--overlay/--set weaken the profile's safety settings (profile's value -> new value): {listed}; expected the "
            f"profile's values or stricter ones, or {FLAG} to run with them anyway (recorded in metadata.json)",
            source,
        )


def summary(weakened: tuple[Weakening, ...]) -> str:
    """One line for the console and the outcome: ``"safety weakened (--allow-weaker-safety): ..."``."""
    return f"safety weakened ({FLAG}): " + "; ".join(item.describe() for item in weakened)
