"""One case in a worker: its profile, the simulation exactly as ``harness simulate`` runs it, its row.

The simulation is handed in (:class:`Simulate`): the command passes a function that calls
``harness.runs.simulate.run_study``, the very function ``harness simulate`` calls, so a case
in a sweep and the same case through ``simulate`` give identical peaks. This package sits
below the runs and does not import them (``tests/unit/test_architecture.py``).

A :class:`CaseRunner` is a small picklable object: worker processes and Dask workers get it
with each case (the simulation function travels by reference), load the base profile once
per process (:func:`harness.sweep.resolve.base_profile`) and compile or load the numba
kernels once (:func:`warm_worker`). A case that raises is recorded with its error, and the
sweep goes on; only ``KeyboardInterrupt`` and ``SystemExit`` pass through.
"""

from __future__ import annotations

import os
import socket
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from harness.profile import Profile
from harness.signals.peaks import Peaks
from harness.sweep.cases import CaseSpec
from harness.sweep.resolve import BaseProfile, case_profile
from harness.sweep.rows import outcome_columns, peak_columns


@dataclass(frozen=True)
class SimulatedCase:
    """What a simulation gives a sweep.

    Attributes
    ----------
    peaks : mapping of str to Peaks
        By simulation: ``passive`` and (unless the controller is ``none``) ``controlled``.
    integration_s : float
        Wall time of the time-stepping of those simulations (s): the cost the rest is compared with.
    """

    peaks: Mapping[str, Peaks]
    integration_s: float


#: ``simulate(profile, study_options) -> SimulatedCase``: ``study_options`` are the keyword
#: arguments of ``harness.runs.options.StudyOptions``.
Simulate = Callable[[Profile, dict[str, Any]], SimulatedCase]


def worker_name() -> str:
    """``host:pid`` of this process."""
    return f"{socket.gethostname()}:{os.getpid()}"


def warm_worker() -> str:
    """Compile or load the numba kernels in this process once (a worker's start-up); returns its name."""
    from harness.model.warmup import warm_up

    warm_up()
    return worker_name()


@dataclass(frozen=True)
class CaseRunner:
    """Runs cases of one study: the base profile and the simulation, both picklable."""

    base: BaseProfile
    simulate: Simulate

    def __call__(self, case: CaseSpec) -> dict[str, Any]:
        """The row of ``case`` (:mod:`harness.sweep.rows`); an error is recorded, not raised."""
        started = time.perf_counter()
        columns: dict[str, Any] = {}
        error: BaseException | None = None
        integration_s = 0.0
        try:
            result = self.simulate(case_profile(self.base, case.overrides), case.study_options())
            columns = peak_columns(result.peaks)
            integration_s = result.integration_s
        except Exception as err:  # any failure of one case is that case's outcome
            error = err
        wall_time_s = time.perf_counter() - started
        return {**case.input_columns(), **columns, **outcome_columns(error, wall_time_s, integration_s, worker_name())}

    def warm(self) -> str:
        """Get this process ready for its first case: kernels, base profile, and one short simulation.

        The first case of a fresh process would otherwise pay for loading the base profile and
        for the first import and call of everything a simulation touches (a few tenths of a
        second); a short passive and controlled run of the synthetic record does that up front.
        Best effort: a warm-up that fails leaves the error to the first real case.
        """
        name = warm_worker()
        try:
            profile = case_profile(self.base, ("record.duration_s=0.2",))
            self.simulate(profile, {"record": "synthetic", "duration_s": 0.2})
        except Exception:  # the real cases will report whatever this was
            pass
        return name

    def run_batch(self, cases: list[CaseSpec]) -> list[dict[str, Any]]:
        """The rows of several cases, in order (one task of a Dask engine)."""
        return [self(case) for case in cases]
