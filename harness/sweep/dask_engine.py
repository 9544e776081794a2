"""The Dask engine: cases as tasks of a ``dask.distributed`` cluster, an existing one or a ``LocalCluster``.

Imported only for ``--scheduler`` or ``--local-cluster`` (``pip install '.[cluster]'``): the
local engine does not need Dask. Each task runs a small batch of cases
(:meth:`CaseRunner.run_batch`), so the scheduler's per-task cost (about a millisecond) is
spread over several cases; at most two batches per worker thread are in flight. Workers warm
their numba kernels once, before the first case (``Client.run``). Dask's nannies start
workers with one BLAS/OpenMP thread each (``distributed.nanny.pre-spawn-environ``), as the
local engine does.

On a cluster, every worker must import this same harness (install the project there) and
read the record files at the paths the study resolves (a shared file system). Starting those
workers with ``DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False`` spares each case the workers'
statistical profiler, as the ``LocalCluster`` here does.
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator
from itertools import islice
from typing import Any

from harness.sweep.cases import CaseSpec
from harness.sweep.engines import IN_FLIGHT_PER_WORKER, EngineError, Prepare, Row
from harness.sweep.worker import CaseRunner, warm_worker

#: How long to wait for a scheduler to answer (s).
CONNECT_TIMEOUT_S = 30


def _distributed() -> Any:
    try:
        import distributed
    except ImportError as err:
        raise EngineError(
            "the Dask engine needs dask.distributed, which is not installed; install the optional extra: "
            "pip install '.[cluster]' (or run without --scheduler/--local-cluster: the local engine needs no Dask)"
        ) from err
    return distributed


class DaskEngine:
    """Cases on a Dask cluster.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler (``tcp://HOST:8786``); None starts a ``LocalCluster``.
    workers : int, optional
        Worker processes of the ``LocalCluster`` (one thread each); ignored with ``scheduler``.
    batch : int
        Cases per task.
    prepare : callable, optional
        Run once on every worker before the first case (default: load the numba kernels).
    """

    def __init__(self, scheduler: str | None = None, workers: int | None = None, batch: int = 4,
                 prepare: Prepare | None = None):
        distributed = _distributed()
        self.batch = max(1, batch)
        self._cluster = None
        try:
            if scheduler is None:
                import dask

                # The workers' statistical profiler samples every thread every 10 ms, holding the
                # interpreter lock the case needs; a sweep does not use it (see README, SLURM).
                dask.config.set({"distributed.worker.profile.enabled": False})
                self._cluster = distributed.LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                )
                self.client = distributed.Client(self._cluster)
            else:
                self.client = distributed.Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except OSError as err:
            raise EngineError(f"cannot reach the Dask scheduler {scheduler}: {err}") from err
        self.workers = max(1, sum(self.client.nthreads().values()))
        where = "a LocalCluster" if scheduler is None else f"the scheduler {scheduler}"
        self.description = f"Dask, {self.workers} worker thread{'s' if self.workers > 1 else ''} on {where}"
        self.client.run(prepare or warm_worker)

    def rows(self, runner: CaseRunner, cases: Iterable[CaseSpec]) -> Iterator[Row]:
        distributed = _distributed()
        queue = iter(cases)
        window = IN_FLIGHT_PER_WORKER * self.workers

        def submit(count: int) -> list[Any]:
            batches = (list(islice(queue, self.batch)) for _ in range(count))
            return [self.client.submit(runner.run_batch, batch, pure=False) for batch in batches if batch]

        running = distributed.as_completed(submit(window))
        for future in running:
            rows = future.result()
            for more in submit(1):
                running.add(more)
            yield from rows

    def close(self) -> None:
        self.client.close()
        if self._cluster is not None:
            self._cluster.close()
