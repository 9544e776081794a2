"""The control step, written once: estimate -> control -> compensate -> supervise.

The loop's tick (:mod:`harness.loop.tick`), the rig twin (:mod:`harness.simulation.twin`) and the
ideal simulator (:mod:`harness.simulation.case`) all call :func:`control_step`, so what a dry run
does between reading the sensors and writing the command is what a simulation does, including
what an exception does: any exception raised in the step goes to ``supervisor.report_exception``,
where a :class:`~harness.safety.supervisor.Supervisor` trips the run (reason ``tick_exception``,
zero force, drive disabled) instead of letting it escape. (The ideal simulator, which has no
safety layer, passes a pass-through that re-raises it.)

The step allocates nothing of its own: the caller allocates one :class:`StepValues` and one
supervisor's command before the run, and the step overwrites them.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Protocol

import numpy as np

from harness.control.compensation import Compensator, compensate
from harness.control.controllers import Controller
from harness.loop.timing import CONTROL
from harness.safety.supervisor import SupervisedCommand

if TYPE_CHECKING:
    from harness.loop.timing import GapTrace
    from harness.safety.health import TickHealth


class StepEstimator(Protocol):
    """The friction term of the step: ``update(t, dt, sliding_velocity_m_s) -> friction_N``."""

    def update(self, t: float, dt: float, sliding_velocity_m_s: float) -> float:
        """The friction force (N) at loop time ``t`` (s) after a step ``dt`` (s)."""
        ...


class StepSupervisor(Protocol):
    """What the step needs of a supervisor (:class:`harness.safety.supervisor.Supervisor`)."""

    @property
    def command(self) -> SupervisedCommand:
        """The command of the previous step (overwritten by every update)."""
        ...

    def update(
        self, t: float, dt: float, health: TickHealth, raw_force_N: float, setpoint_N: float | None = None,
    ) -> SupervisedCommand:
        """Supervise one step and return the command to write."""
        ...

    def report_exception(self, t: float, exc: BaseException) -> SupervisedCommand:
        """An exception was caught in the step at loop time ``t`` (s): trip (a supervisor may re-raise)."""
        ...


class StepValues:
    """What one step computed besides the command, for the caller's record; one object, overwritten each step.

    Attributes
    ----------
    friction_N : float
        The estimator's friction force (N); NaN if the step failed before it.
    raw_N : float
        The controller's force (N), the supervisor's setpoint; NaN if the step failed before it.
    """

    __slots__ = ("friction_N", "raw_N")

    def __init__(self) -> None:
        self.friction_N = math.nan
        self.raw_N = math.nan


def control_step(
    t: float, dt: float, health: TickHealth, estimator: StepEstimator, controller: Controller,
    compensator: Compensator, supervisor: StepSupervisor, values: StepValues, state: np.ndarray | None = None,
    trace: GapTrace | None = None,
) -> SupervisedCommand:
    """One control step: estimate -> control -> compensate -> supervise; an exception trips.

    Parameters
    ----------
    t : float
        Loop time of the step (s).
    dt : float
        Step (s): the controller's sample period.
    health : TickHealth
        This step's health record, already filled; ``health.meas`` is the measurement the
        estimator and the controller read (SI). The compensator's flags are written into it.
    estimator : StepEstimator
        ``update(t, dt, sliding_velocity_m_s) -> friction_N`` (N).
    controller : Controller
        ``update(t, dt, meas, friction_N, state) -> force_N`` (N).
    compensator : Compensator
        Turns the controller's force into the command the supervisor shapes (N);
        :class:`harness.control.compensation.NoCompensation` for the force as is.
    supervisor : StepSupervisor
        Supervises the compensated command; its ``report_exception(t, exc)`` is called with any
        exception raised in the step.
    values : StepValues
        Overwritten with the friction (N) and the controller's force (N); NaN for what the step
        did not reach.
    state : ndarray, optional
        The plant's true state Z handed to the controller (offline studies only); None on a rig.
    trace : GapTrace, optional
        The tick's trace: its CONTROL part is marked when the compensated command is ready,
        before supervision (not on a step that raised before it).

    Returns
    -------
    SupervisedCommand
        The supervisor's command (its one preallocated object): the supervised force (N) and
        drive enable, or the tripped command (zero force, drive disabled) after an exception.
    """
    values.friction_N = values.raw_N = math.nan
    try:
        values.friction_N = friction = estimator.update(t, dt, health.meas.sliding_velocity_m_s)
        values.raw_N = raw = controller.update(t, dt, health.meas, friction, state)
        force = compensate(compensator, t, dt, raw, health.meas, supervisor.command, health)
        if trace is not None:
            trace.mark(CONTROL)
        return supervisor.update(t, dt, health, force, raw)  # the setpoint is the controller's force
    except Exception as exc:  # noqa: BLE001 - any failure in the step trips; it never kills the process
        return supervisor.report_exception(t, exc)
