"""What the two offline simulators share: per-sample arrays, the sample loop, the last sample, the result.

:func:`harness.simulation.case.run_case` (the ideal sampled-data study) and
:func:`harness.simulation.twin.run_rig_twin` (the same through the rig's sensor, actuator and safety
models) differ only in what one controller sample does. Both record, for every sample
``k = 0 .. n - 1``, the plant state at ``t_k`` and named per-sample values (the columns of
:mod:`harness.signals.columns`), plus one last row at the end of the last interval; both turn
that into the columns and peaks of a :class:`CaseResult`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from harness.signals.peaks import Peaks, peak_responses

#: How many progress reports a case makes (about every 5 %).
_PROGRESS_REPORTS = 20


@dataclass
class CaseResult:
    """One simulated case: time series (canonical columns), peaks and cost."""

    name: str
    columns: dict[str, np.ndarray]
    peaks: Peaks
    integrator_steps: int
    wall_time_s: float
    extra: dict = field(default_factory=dict)


class HasState(Protocol):
    """A plant whose state ``y = (Z, nu)`` the loop records at each sample."""

    @property
    def y(self) -> np.ndarray:
        """The state now (SI)."""


class CaseSamples:
    """Per-sample arrays of one case and the loop that fills them.

    Row ``k`` holds sample ``k`` (time ``k / f_s``); the row after the last sample taken
    holds the end of its interval (see :meth:`close`).

    Parameters
    ----------
    n_samples : int
        Controller samples planned.
    state_size : int
        Length of the plant state ``(Z, nu)``.
    names : sequence of str
        Columns (:mod:`harness.signals.columns` names) recorded per sample besides the state.

    Attributes
    ----------
    states : ndarray, shape (n_samples + 1, state_size)
        The plant state at each sample (SI).
    values : dict of str to ndarray, shape (n_samples + 1,)
        One zero-initialised array per name (SI, the unit the name carries).
    taken : int
        Samples taken: ``n_samples``, or fewer when the case ended early (a trip).
    """

    def __init__(self, n_samples: int, state_size: int, names: Sequence[str]):
        self.n_samples = n_samples
        self.states = np.zeros((n_samples + 1, state_size))
        self.values = {name: np.zeros(n_samples + 1) for name in names}
        self.taken = n_samples

    def run(self, plant: HasState, sample: Callable[[int], bool], progress: Callable[[float], None] | None = None) -> int:
        """Record ``plant.y`` and call ``sample(k)`` for every sample, in order.

        Parameters
        ----------
        plant : object with ``y``
            Its state is copied into :attr:`states` before each sample.
        sample : callable
            ``sample(k) -> bool``: the work of sample ``k`` (read, control, record, advance
            the plant to the next sample); False ends the case after this sample.
        progress : callable, optional
            Called with the fraction done (0 to 1) about every 5 %, and with 1.0 at the end.

        Returns
        -------
        int
            Samples taken (:attr:`taken`).
        """
        states, n_samples = self.states, self.n_samples
        report_every = max(1, n_samples // _PROGRESS_REPORTS)
        for k in range(n_samples):
            states[k] = plant.y
            if not sample(k):
                self.taken = k + 1
                break
            if progress is not None and k % report_every == 0:
                progress(k / n_samples)
        if progress is not None:
            progress(1.0)
        return self.taken

    def close(self, state: np.ndarray, ending: Mapping[str, float] | None = None, held: Iterable[str] = ()) -> int:
        """Fill the row after the last sample taken: the end of its interval.

        Parameters
        ----------
        state : ndarray
            The plant state reached (SI).
        ending : mapping of str to float, optional
            Values at the end, by name (e.g. the force then acting, N).
        held : iterable of str
            Names whose last sample is repeated (a sampled value holds until the next sample);
            names in neither stay zero.

        Returns
        -------
        int
            Rows of the case (``taken + 1``).
        """
        end = self.taken
        self.states[end] = state
        for name in held:
            values = self.values[name]
            values[end] = values[end - 1]
        for name, value in (ending or {}).items():
            self.values[name][end] = value
        return end + 1

    @property
    def rows(self) -> int:
        """Rows of the case: the samples taken and the end of the last interval."""
        return self.taken + 1

    def columns(self, names: Iterable[str]) -> dict[str, np.ndarray]:
        """The recorded ``names`` over the case's rows, in the order given."""
        rows = self.rows
        return {name: self.values[name][:rows] for name in names}


def case_result(
    name: str, columns: dict[str, np.ndarray], total_weight_N: float, integrator_steps: int, started_s: float,
    extra: dict | None = None,
) -> CaseResult:
    """The :class:`CaseResult` of finished columns: their peaks and the wall time since ``started_s``.

    Parameters
    ----------
    name : str
        Case name ("passive", "controlled", "rig twin").
    columns : dict of str to ndarray
        The case's columns (SI), in ``signals.csv`` order.
    total_weight_N : float
        The building's weight (N), for the force in percent of it.
    integrator_steps : int
        Steps the integrator took.
    started_s : float
        :func:`time.perf_counter` when the case started (s).
    extra : dict, optional
        Anything else the case reports.
    """
    peaks = peak_responses(columns, total_weight_N)
    return CaseResult(name, columns, peaks, integrator_steps, time.perf_counter() - started_s, extra or {})
