"""Where a design's evaluations run: in this process, a local process pool, or a Dask cluster.

Every evaluation goes through a :class:`concurrent.futures.Executor`'s ``map`` (results in
the order of the tasks, whoever computed them): a :class:`~concurrent.futures.ProcessPoolExecutor`
with ``jobs`` workers (``--jobs``), or a Dask distributed cluster's executor
(``--scheduler ADDRESS``: ``dask.distributed.Client(address).get_executor()``). With
``jobs = 1`` and no scheduler the tasks run here, one after the other. Each task is a pure
function of its arguments (no shared state, no clock, no unseeded randomness), so the design
is the same whichever runs it.

BLAS is held to one thread inside each task: the matrices are tiny (the 4-element plant is
22 × 22) and BLAS threads only contend with each other and the compiled sample loop
(docs/benchmarks.md, "Threads").
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import ProcessPoolExecutor
from typing import Any

from threadpoolctl import threadpool_limits

from station.errors import StationError


def one_thread(fn: Callable, *args) -> Any:
    """``fn(*args)`` with BLAS limited to one thread (what every task runs).

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled to the workers).
    *args
        Its arguments.

    Returns
    -------
    object
        What ``fn(*args)`` returns.
    """
    with threadpool_limits(limits=1, user_api="blas"):
        return fn(*args)


class Runner:
    """Maps tasks over the chosen executor, results in task order.

    Parameters
    ----------
    executor : concurrent.futures.Executor or None
        None: run here, in order.
    where : str
        How reports name it ("this process", "2 local processes", "dask scheduler ADDRESS").
    """

    def __init__(self, executor=None, where: str = "this process"):
        self.executor = executor
        self.where = where

    def map(self, fn: Callable, tasks: Iterable[tuple]) -> list:
        """``[fn(*task) for task in tasks]``, each under :func:`one_thread`, possibly in parallel.

        Parameters
        ----------
        fn : callable
            A module-level function.
        tasks : iterable of tuple
            Its argument tuples.

        Returns
        -------
        list
            ``fn(*task)`` for each task, in the order of ``tasks`` whoever computed them.
        """
        tasks = list(tasks)
        if self.executor is None or len(tasks) <= 1:
            return [one_thread(fn, *t) for t in tasks]
        return list(self.executor.map(one_thread, [fn] * len(tasks), *zip(*tasks)))


@contextlib.contextmanager
def open_runner(jobs: int = 1, scheduler: str | None = None) -> Iterator[Runner]:
    """A :class:`Runner` on a process pool (``jobs`` > 1), a Dask cluster (``scheduler``) or here.

    Parameters
    ----------
    jobs : int
        Local worker processes (1: this process).
    scheduler : str, optional
        A Dask distributed scheduler's address (``tcp://host:8786``, or a ``LocalCluster``'s
        ``scheduler_address``); wins over ``jobs``.

    Yields
    ------
    Runner
        The runner; its pool or Dask client is shut down when the ``with`` block ends.

    Raises
    ------
    StationError
        Dask is not installed, or the scheduler cannot be reached (one line naming it).
    """
    if scheduler is not None:
        try:
            from dask.distributed import Client  # lazy: optional dependency (dask.distributed)
        except ImportError:
            raise StationError("--scheduler: needs Dask distributed (pip install 'station[dask]')") from None
        try:
            client = Client(scheduler, timeout=5, set_as_default=False)
        except (OSError, TimeoutError, ValueError) as exc:
            raise StationError(f"--scheduler {scheduler}: cannot connect ({exc})") from None
        try:
            yield Runner(client.get_executor(pure=False), f"dask scheduler {scheduler}")
        finally:
            client.close()
        return
    if jobs <= 1:
        yield Runner(None, "this process")
        return

    with ProcessPoolExecutor(max_workers=int(jobs)) as pool:
        yield Runner(pool, f"{int(jobs)} local processes")
