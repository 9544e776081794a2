"""The checks the supervisor performs inline, with no object of their own: their names and documentation.

Each is a class of class attributes only, like a detector's (``NAME``, ``ACTION``, ``DETECTS``,
``BOUND``, ``RESET``), so that :data:`harness.safety.checks.CHECKS` lists them beside the detectors
and interlocks and the safety table documents them the same way. The supervisor trips or acts
under their ``NAME``.
"""

from __future__ import annotations

from harness.safety.events import Action


class LoopTiming:
    """The loop's own ``t`` and ``dt``; judged first, before any detector sees them."""

    NAME = "loop_timing"
    ACTION = Action.TRIP
    DETECTS = "t not finite, or dt not finite or <= 0"
    BOUND = "same tick"
    RESET = "explicit reset"


class TickException:
    """Reported by the loop (:meth:`~harness.safety.supervisor.Supervisor.report_exception`), from any state."""

    NAME = "tick_exception"
    ACTION = Action.TRIP
    DETECTS = "the tick raised (reported by the loop)"
    BOUND = "same tick"
    RESET = "explicit reset"


class ControllerOutput:
    """The controller's raw force, judged after the detectors and before the stroke trips."""

    NAME = "controller_output"
    ACTION = Action.TRIP
    DETECTS = "controller output not finite (NaN or inf)"
    BOUND = "same tick"
    RESET = "explicit reset"


class StopRamp:
    """The safe stop's ramp: between the force clamp and the rate limit; in ARMED the target is zero."""

    NAME = "stop_ramp"
    ACTION = Action.CLAMP
    DETECTS = "STOPPING: force scaled from 1 to 0 over stopping_ramp_s"
    BOUND = "stopping_ramp_s"
    RESET = "DONE once the force is zero; then reset"
