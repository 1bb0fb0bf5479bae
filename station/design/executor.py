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

Stopping: the local pool is :func:`station.pools.process_pool` (the workers leave SIGINT to
the main process; a stop, or any error, kills them rather than waiting for their tasks) and
results are collected by :func:`station.pools.results`, which answers a stop within 0.1 s
and never cancels a future itself. A scheduler's address is checked
(its form, and that something listens there, within :data:`CONNECT_S`) before a Dask client
is made, so a wrong one is one line at once.
"""

from __future__ import annotations

import contextlib
import socket
from collections.abc import Callable, Iterable, Iterator
from typing import Any

from threadpoolctl import threadpool_limits

from station.errors import StationError
from station.pools import KILL_WAIT_S, process_pool, results, submit_all

CONNECT_S = 2.0
"""How long a scheduler's address may take to accept a connection, s."""


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
        # submit and wait, never Executor.map: its clean-up cancels the futures from this thread,
        # and the pool's thread, failing them after a kill, would meet cancelled ones
        return results(submit_all(self.executor, one_thread, [(fn, *t) for t in tasks]))


def _connect(client_class, address: str):
    """A Dask client of ``address``, or one line. A client whose making failed is still
    collected later: its destructor would wait 10 s to close it and print a traceback (seen
    with a port that answers but is no scheduler), so a half-made one is marked closed here."""
    made = []

    class Recorded(client_class):
        def __init__(self, *args, **kwargs):
            made.append(self)
            super().__init__(*args, **kwargs)

    try:
        return Recorded(address, timeout=5, set_as_default=False)
    except Exception as exc:  # noqa: BLE001 - whatever the far end did (a MemoryError: it sent no frame of Dask's)
        for client in made:
            client.status = "closed"  # (Client.__del__ closes only what is not closed)
            with contextlib.suppress(Exception):
                client._loop_runner.stop()
        made.clear()
        why = (f"something answers there, not as a Dask scheduler ({type(exc).__name__})"
               if isinstance(exc, MemoryError) else f"{exc}" or type(exc).__name__)
        raise StationError(f"--scheduler {address}: cannot connect ({why})") from None


def check_scheduler(address: str) -> None:
    """Refuse a Dask scheduler's address that is malformed or where nothing listens, in one line,
    within :data:`CONNECT_S` (before a client is made: a client that cannot connect retries
    for its whole timeout and leaves a traceback behind when it is collected).

    Parameters
    ----------
    address : str
        ``tcp://HOST:PORT`` (or ``tls://``, or ``HOST:PORT``); another scheme (``inproc://``)
        is left to the client.

    Raises
    ------
    StationError
        ``--scheduler ADDRESS: ...`` saying what is wrong.
    """
    from distributed.comm.addressing import parse_address, parse_host_port  # lazy: optional dependency (dask.distributed)

    try:
        scheme, where = parse_address(address, strict=False)
        if scheme not in ("tcp", "tls"):
            return
        host, port = parse_host_port(where)
    except (ValueError, TypeError) as exc:
        raise StationError(f"--scheduler {address}: not a scheduler's address ({exc}); expected tcp://HOST:PORT") \
            from None
    if not host or not 0 < int(port) < 65536:
        raise StationError(f"--scheduler {address}: not a scheduler's address; expected tcp://HOST:PORT "
                           f"(a port 1..65535)")
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_S).close()
    except OSError as exc:
        raise StationError(f"--scheduler {address}: cannot connect ({exc.strerror or exc})") from None


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
        Dask is not installed, or the scheduler's address is malformed or cannot be reached
        (one line naming it, within :data:`CONNECT_S` when nothing listens there).
    """
    if scheduler is not None:
        try:
            from dask.distributed import Client  # lazy: optional dependency (dask.distributed)
        except ImportError:
            raise StationError("--scheduler: needs Dask distributed (pip install 'station[dask]')") from None
        check_scheduler(scheduler)
        client = _connect(Client, scheduler)
        executor = client.get_executor(pure=False)
        try:
            yield Runner(executor, f"dask scheduler {scheduler}")
        except BaseException:
            executor.shutdown(wait=False)  # the cluster's tasks are released with the client
            raise
        finally:
            client.close(timeout=KILL_WAIT_S * 4)
        return
    if jobs <= 1:
        yield Runner(None, "this process")
        return

    with process_pool(jobs) as pool:
        yield Runner(pool, f"{int(jobs)} local processes")
