"""Offline sampled-data simulation: plant, friction estimate and controller, faster than real time.

Sampling follows SPEC 3 exactly: the controller samples its measurements at
``t_k = k / f_s``, and the force it computes is held over ``[t_k, t_k + 1/f_s)``
(zero-order hold), optionally after a further transport delay. The controller,
estimator and plant classes are the ones the real-time loop and the virtual rig use.
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from harness.control.estimator import FrictionEstimator
from harness.model.plant import Plant
from harness.peaks import peak_responses
from harness.signals import Measurements

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


@dataclass
class CaseResult:
    """One simulated case: time series (canonical columns), peaks and cost."""

    name: str
    columns: dict[str, np.ndarray]
    peaks: dict
    integrator_steps: int
    wall_time_s: float
    extra: dict = field(default_factory=dict)


def _integrate_interval(plant: Plant, t0: float, t1: float, pending: deque, active: list[float]) -> None:
    """Advance ``plant`` over ``[t0, t1)``, switching the held force at each pending activation time."""
    t = t0
    while pending and pending[0][0] < t1:
        t_switch, force = pending.popleft()
        if t_switch > t:
            plant.advance(t, t_switch, active[0])
            t = t_switch
        active[0] = force
    plant.advance(t, t1, active[0])


def run_case(
    name: str,
    plant: Plant,
    duration_s: float,
    settings: SamplingSettings,
    controller=None,
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
    """
    started = time.perf_counter()
    plant.reset()
    if estimator is not None:
        estimator.reset()
    if controller is not None:
        controller.reset()
    period = 1.0 / settings.rate_hz
    n_samples = int(round(duration_s * settings.rate_hz))
    times = np.arange(n_samples + 1) * period
    size = plant.y.size
    states = np.empty((n_samples + 1, size))
    applied = np.zeros(n_samples + 1)
    sliding_variable = np.zeros(n_samples + 1)
    equivalent_force = np.zeros(n_samples + 1)
    friction_estimate = np.zeros(n_samples + 1)
    raw_force = np.zeros(n_samples + 1)
    table_x, table_v = plant.table.states(times)
    meas = Measurements()
    pending: deque = deque()
    active = [0.0]
    n_z = size - 1
    delayed = settings.transport_delay_s > 0.0
    use_estimator = settings.friction_source == "estimator"
    report_every = max(1, n_samples // 20)
    for k in range(n_samples):
        t = times[k]
        states[k] = plant.y
        force = 0.0
        if controller is not None:
            plant.measure(t, meas, table_x[k], table_v[k])
            if use_estimator:
                friction = estimator.update(t, period, meas.sliding_velocity_m_s)
            else:
                friction = plant.friction_force(t, table_v[k])
            force = controller.update(t, period, meas, friction, plant.y[:n_z])
            sliding_variable[k] = controller.sliding_variable
            equivalent_force[k] = controller.equivalent_force_N
            friction_estimate[k] = friction
            raw_force[k] = force
        if delayed:
            pending.append((t + settings.transport_delay_s, force))
            while pending and pending[0][0] <= t:
                active[0] = pending.popleft()[1]
            applied[k] = active[0]
            _integrate_interval(plant, t, times[k + 1], pending, active)
        else:
            applied[k] = force
            plant.advance(t, times[k + 1], force)
        if progress is not None and k % report_every == 0:
            progress(k / n_samples)
    states[n_samples] = plant.y
    applied[n_samples] = active[0] if delayed else applied[n_samples - 1]
    columns = plant.responses(times, states, applied)
    if controller is not None:
        columns["sliding_variable_m_s"] = sliding_variable
        columns["equivalent_force_N"] = equivalent_force
        columns["friction_estimate_N"] = friction_estimate
        columns["force_raw_N"] = raw_force
    columns["force_command_N"] = applied
    if progress is not None:
        progress(1.0)
    peaks = peak_responses(columns, plant.building.total_weight_N)
    return CaseResult(name, columns, peaks, plant.steps, time.perf_counter() - started)
