"""Offline sampled-data simulation: plant, friction estimate and controller, faster than real time.

Sampling follows SPEC 3 exactly: the controller samples its measurements at
``t_k = k / f_s``, and the force it computes is held over ``[t_k, t_k + 1/f_s)``
(zero-order hold), optionally after a further transport delay. The controller,
estimator and plant classes are the ones the real-time loop and the virtual rig use, and each sample
runs the loop's own step (:func:`harness.loop.step.control_step`), with no compensation and a
pass-through in place of the supervisor.
The per-sample bookkeeping is :class:`harness.simulation.sampled.CaseSamples`, shared with the
rig twin; :class:`CaseResult` is re-exported from there.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from harness.control.compensation import NoCompensation
from harness.control.controllers import Controller
from harness.control.estimator import FrictionEstimator
from harness.loop.step import StepEstimator, StepValues, control_step
from harness.model.plant import Plant
from harness.safety.health import TickHealth
from harness.safety.supervisor import SupervisedCommand
from harness.signals import columns as layout
from harness.simulation.sampled import CaseResult, CaseSamples, case_result

__all__ = ["CaseResult", "FrictionSource", "SamplingSettings", "run_case"]

FrictionSource = Literal["estimator", "model"]


@dataclass(frozen=True)
class SamplingSettings:
    """How the controller is sampled.

    Attributes
    ----------
    rate_hz : float
        Controller sample rate f_s (Hz).
    transport_delay_s : float
        Further delay from sample to force (s); 0 in the reference studies.
    friction_source : {"estimator", "model"}
        The controller's friction term: the online estimator (as on a rig) or the
        plant's own friction force (simulation only).
    """

    rate_hz: float
    transport_delay_s: float = 0.0
    friction_source: FrictionSource = "estimator"


class _HeldForce:
    """The actuator force of a case: each sample's force held over its interval (zero-order hold),
    acting from ``delay_s`` after its sample.

    Parameters
    ----------
    plant : Plant
        Advanced under the acting force.
    delay_s : float
        Transport delay from sample to force (s); 0 for none.
    """

    def __init__(self, plant: Plant, delay_s: float):
        self.plant = plant
        self.delay_s = delay_s
        self.delayed = delay_s > 0.0
        #: The force acting now (N).
        self.acting_N = 0.0
        self._pending: deque[tuple[float, float]] = deque()  # (activation time s, force N)

    def apply(self, t: float, t_next: float, force_N: float) -> float:
        """Hold ``force_N`` (N) from sample time ``t`` (s) on and advance the plant to ``t_next`` (s).

        Returns
        -------
        float
            The force acting at ``t`` (N): ``force_N`` without a delay, an earlier sample's with one.
        """
        if not self.delayed:
            self.acting_N = force_N
            self.plant.advance(t, t_next, force_N)
            return force_N
        pending = self._pending
        pending.append((t + self.delay_s, force_N))
        while pending and pending[0][0] <= t:
            self.acting_N = pending.popleft()[1]
        acting_N = self.acting_N
        self._integrate(t, t_next)
        return acting_N

    def _integrate(self, t0: float, t1: float) -> None:
        """Advance the plant over ``[t0, t1)`` (s), switching the acting force at each pending activation time."""
        pending, t = self._pending, t0
        while pending and pending[0][0] < t1:
            t_switch, force_N = pending.popleft()
            if t_switch > t:
                self.plant.advance(t, t_switch, self.acting_N)
                t = t_switch
            self.acting_N = force_N
        self.plant.advance(t, t1, self.acting_N)


class _PassThrough:
    """The ideal simulator's supervisor: none. The command is the compensated force, always enabled; an
    exception in the step propagates (the ideal case has no safety layer to trip).

    A :class:`harness.loop.step.StepSupervisor`, so the ideal case runs the loop's own step.
    """

    __slots__ = ("command",)

    def __init__(self) -> None:
        self.command = SupervisedCommand()
        self.command.enable = True

    def update(
        self, t: float, dt: float, health: TickHealth, raw_force_N: float, setpoint_N: float | None = None,
    ) -> SupervisedCommand:
        """``raw_force_N`` (N) as it is, in the one preallocated command."""
        command = self.command
        command.t = t
        command.force_N = raw_force_N
        return command

    def report_exception(self, t: float, exc: BaseException) -> SupervisedCommand:
        """Re-raise ``exc``: nothing trips in the ideal case."""
        raise exc


class _PlantFriction:
    """``friction_source: model``: the plant's own friction force as the step's friction term (simulation only).

    The caller sets :attr:`table_velocity_m_s` to the record's table velocity at the sample before each step.
    """

    __slots__ = ("plant", "table_velocity_m_s")

    def __init__(self, plant: Plant) -> None:
        self.plant = plant
        self.table_velocity_m_s = 0.0

    def update(self, t: float, dt: float, sliding_velocity_m_s: float) -> float:
        """The plant's friction force at ``t`` (s), N (the measured sliding velocity is not used)."""
        return self.plant.friction_force(t, self.table_velocity_m_s)


def _control_step(
    plant: Plant, times: np.ndarray, settings: SamplingSettings, controller: Controller, estimator: FrictionEstimator | None,
    values: dict[str, np.ndarray],
) -> Callable[[int, float], float]:
    """The controller's work at sample ``k`` (time ``t``, s): measure, then the loop's step
    (:func:`harness.loop.step.control_step`: estimate, control, no compensation, no supervisor).

    The returned ``control(k, t) -> force_N`` records the controller's internals into ``values``
    (the :data:`harness.signals.columns.SIMULATED_CONTROL` columns).
    """
    period = 1.0 / settings.rate_hz
    table_x, table_v = plant.table.states(times)
    health = TickHealth()
    meas = health.meas
    n_z = plant.y.size - 1
    model_friction = _PlantFriction(plant)
    if settings.friction_source == "estimator":
        assert estimator is not None, "friction_source 'estimator' needs an estimator"
        friction_source: StepEstimator = estimator
    else:
        friction_source = model_friction
    compensator, supervisor, step = NoCompensation(), _PassThrough(), StepValues()
    sliding_variable, equivalent_force = values[layout.SLIDING_VARIABLE], values[layout.EQUIVALENT_FORCE]
    friction_estimate, raw_force = values[layout.FRICTION_ESTIMATE], values[layout.FORCE_RAW]

    def control(k: int, t: float) -> float:
        plant.measure(t, meas, table_x[k], table_v[k])
        model_friction.table_velocity_m_s = table_v[k]
        force = control_step(t, period, health, friction_source, controller, compensator, supervisor, step,
                             plant.y[:n_z]).force_N
        sliding_variable[k] = controller.sliding_variable
        equivalent_force[k] = controller.equivalent_force_N
        friction_estimate[k] = step.friction_N
        raw_force[k] = step.raw_N
        return force

    return control


def run_case(
    name: str,
    plant: Plant,
    duration_s: float,
    settings: SamplingSettings,
    controller: Controller | None = None,
    estimator: FrictionEstimator | None = None,
    progress: Callable[[float], None] | None = None,
) -> CaseResult:
    """Simulate one case from rest.

    Parameters
    ----------
    name : str
        "passive", "controlled", ...
    plant : Plant
        Reset before the run.
    duration_s : float
        Length of the run (s).
    settings : SamplingSettings
    controller : optional
        Object with ``update(t, dt, meas, friction_N, state) -> force``; None is passive
        (bearings only, no actuator force).
    estimator : FrictionEstimator, optional
        Needed when ``settings.friction_source == "estimator"`` and a controller is given.
    progress : callable, optional
        Called with the fraction done, about every 5 %.

    Returns
    -------
    CaseResult
        Columns :func:`harness.signals.columns.simulation_columns` names; ``force_command_N`` is the applied force.
    """
    started = time.perf_counter()
    for part in (plant, estimator, controller):
        if part is not None:
            part.reset()
    n_samples = int(round(duration_s * settings.rate_hz))
    times = np.arange(n_samples + 1) * (1.0 / settings.rate_hz)
    recorded = (*(layout.SIMULATED_CONTROL if controller is not None else ()), layout.FORCE_COMMAND)
    samples = CaseSamples(n_samples, plant.y.size, recorded)
    control = None if controller is None else _control_step(plant, times, settings, controller, estimator, samples.values)
    held = _HeldForce(plant, settings.transport_delay_s)
    applied = samples.values[layout.FORCE_COMMAND]

    def sample(k: int) -> bool:
        t = times[k]
        applied[k] = held.apply(t, times[k + 1], 0.0 if control is None else control(k, t))
        return True

    samples.run(plant, sample, progress)
    rows = samples.close(plant.y, ending={layout.FORCE_COMMAND: held.acting_N})
    columns = plant.responses(times[:rows], samples.states[:rows], applied[:rows])
    columns.update(samples.columns(recorded))
    return case_result(name, columns, plant.building.total_weight_N, plant.steps, started)
