"""Where the cases run: in this process, in local worker processes (the default), or on a Dask cluster.

Every engine takes a :class:`~harness.sweep.worker.CaseRunner` and an iterable of cases and
yields one row per case as cases finish (in any order), keeping only a small window of cases
in flight, so a study of 220,000 cases never sits in memory as tasks.

- :class:`InlineEngine`: this process, one case after the other (``--workers 0``: debugging).
- :class:`LocalEngine`: ``concurrent.futures.ProcessPoolExecutor`` with ``spawn``ed workers,
  each of which loads the numba kernels once as it starts (:func:`warm_worker`). BLAS and
  OpenMP run single-threaded in the workers (one process per core is the parallelism; the
  threads would only fight over the cores). Needs nothing but the standard library.
- :class:`DaskEngine`: a ``dask.distributed`` client, of an existing scheduler
  (``--scheduler tcp://HOST:8786``) or of a ``LocalCluster`` it starts; Dask is imported only
  here, only then (``pip install '.[cluster]'``).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from contextlib import contextmanager
from itertools import islice
from typing import Any, Protocol

from harness.errors import HarnessError
from harness.sweep.cases import CaseSpec
from harness.sweep.worker import CaseRunner, warm_worker, worker_name

Row = dict[str, Any]

#: Variables that keep numerical libraries to one thread in a worker process.
SINGLE_THREAD_ENV = {name: "1" for name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS")}
#: Cases in flight per worker: enough to keep a worker busy while its last row travels back.
IN_FLIGHT_PER_WORKER = 2


class EngineError(HarnessError, RuntimeError):
    """An engine cannot start: Dask missing, a scheduler that does not answer."""


#: What a worker runs once as it starts, after the kernels: :meth:`CaseRunner.warm`.
Prepare = Callable[[], Any]


class Engine(Protocol):
    """Runs cases and yields their rows as they finish."""

    description: str
    workers: int

    def rows(self, runner: CaseRunner, cases: Iterable[CaseSpec]) -> Iterator[Row]: ...

    def close(self) -> None: ...


class InlineEngine:
    """Cases in this process, in order."""

    workers = 1
    description = "this process"

    def __init__(self, prepare: Prepare | None = None):
        (prepare or warm_worker)()

    def rows(self, runner: CaseRunner, cases: Iterable[CaseSpec]) -> Iterator[Row]:
        for case in cases:
            yield runner(case)

    def close(self) -> None:
        pass


def _start_local_worker(prepare: Prepare | None) -> None:
    """A local worker's start: Ctrl-C is the parent's to handle (it stops the pool), then the warm-up."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    (prepare or warm_worker)()


@contextmanager
def _environment(values: dict[str, str]) -> Iterator[None]:
    """``os.environ`` with ``values`` set (worker processes started meanwhile inherit them), restored after."""
    saved = {name: os.environ.get(name) for name in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for name, value in saved.items():
            if value is None:
                os.environ.pop(name, None)
            else:
                os.environ[name] = value


class LocalEngine:
    """Worker processes on this machine (``concurrent.futures``), each warmed once.

    Parameters
    ----------
    workers : int
        Worker processes (default: every core).
    prepare : callable, optional
        Run by each worker as it starts (default: load the numba kernels); picklable.
    """

    def __init__(self, workers: int | None = None, prepare: Prepare | None = None):
        self.workers = workers or os.cpu_count() or 1
        self.description = f"{self.workers} local worker process{'es' if self.workers > 1 else ''}"
        with _environment(SINGLE_THREAD_ENV):  # spawn copies the environment when each worker starts
            self._pool = ProcessPoolExecutor(self.workers, mp_context=multiprocessing.get_context("spawn"),
                                             initializer=_start_local_worker, initargs=(prepare,))
            self._start_all()

    def _start_all(self) -> None:
        """Start every worker now, inside the single-thread environment, and wait until each is warm."""
        for future in [self._pool.submit(worker_name) for _ in range(self.workers)]:
            future.result()

    def rows(self, runner: CaseRunner, cases: Iterable[CaseSpec]) -> Iterator[Row]:
        pending: set[Future[Row]] = set()
        queue = iter(cases)
        window = IN_FLIGHT_PER_WORKER * self.workers
        while True:
            pending.update(self._pool.submit(runner, case) for case in islice(queue, window - len(pending)))
            if not pending:
                return
            done, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                yield future.result()

    def close(self) -> None:
        self._pool.shutdown(wait=True, cancel_futures=True)
