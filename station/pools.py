"""Process pools that stop at once, and waits that answer a signal: the one plumbing of every
command that farms work out (``station survey``'s replays, ``station tune``'s evaluations).

A stop must end the command within a second (DESIGN.md "Run outcome": 130 / 143, one line),
whatever the workers are doing:

- a worker leaves SIGINT to the main process (a terminal's Ctrl-C reaches the whole process
  group: no traceback per worker) and dies at once on SIGTERM (the main process's Python
  handler, inherited on fork, would raise inside the worker's queue reading)
  (:func:`worker_signals`, the pools' initializer);
- the main process never blocks on a result without a bound: it waits :data:`POLL_S` at a
  time and looks for a pending stop in between (:func:`results`, :func:`as_finished`), so a
  signal is answered even when it woke another thread than the waiting one;
- when the work stops (a signal, or any other error), the workers are killed, not waited
  for (:func:`abandon`): a task of a large model set runs for seconds, and a worker may be
  blocked writing a result nobody reads any more. No future is cancelled by the main
  process before the kill, so the pool's own thread fails every pending one without an
  ``InvalidStateError``;
- a worker that dies on its own (killed from outside, out of memory, crashed) breaks the whole
  pool: every task not yet finished fails with ``BrokenProcessPool``. :func:`results` and
  :func:`submit_all` say it in one line (:class:`WorkerLost`, exit code 1); :func:`as_finished`'s
  caller sees it per future (:func:`lost`) and may run those tasks again in a new pool
  (``station survey``). A signal sent to the process group kills the workers as it reaches the
  main process: where the pool broke with a stop pending, the stop is raised, not the loss.

The workers are started under :func:`station.signals.shielded`: a fork runs the at-fork hooks
(logging's module lock is taken before and released after it), where a stop raised by the
handler would be swallowed and leave the lock held.

Imports only :mod:`station.signals` and :mod:`station.errors`.
"""

from __future__ import annotations

import concurrent.futures as cf
import contextlib
import signal
from collections.abc import Iterable, Iterator, Sequence
from concurrent.futures.process import BrokenProcessPool
from typing import Any

from station.errors import StationError
from station.signals import check_stop, shielded

POLL_S = 0.1
"""Longest wait for a result before looking for a pending stop, s."""

KILL_WAIT_S = 0.5
"""How long each killed worker is waited for, s (SIGKILL: it is gone within milliseconds)."""


LOST = ("a worker process ended abruptly (killed from outside, out of memory or crashed) before its task "
        "finished; the work stopped, nothing written")
"""What :class:`WorkerLost` says."""


class WorkerLost(StationError):
    """A worker process of the pool ended abruptly (killed, out of memory or crashed) before
    its task finished: the work stopped (exit code 1: not the user's input).

    Parameters
    ----------
    message : str, optional
        The line for the user (default :data:`LOST`).
    """

    exit_code = 1

    def __init__(self, message: str = LOST):
        super().__init__(message)


def lost(future: cf.Future) -> bool:
    """Whether a done future failed because its pool broke (a worker died), not by its own task.

    Parameters
    ----------
    future : Future
        Done.
    """
    return not future.cancelled() and isinstance(future.exception(), BrokenProcessPool)


def worker_signals() -> None:
    """A worker process's signals (a pool's initializer): SIGINT ignored (the main process
    answers it), SIGTERM the default action (the worker ends at once)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


def abandon(pool: cf.ProcessPoolExecutor) -> None:
    """Stop a process pool now: pending tasks dropped, running ones killed with their workers.

    Parameters
    ----------
    pool : concurrent.futures.ProcessPoolExecutor
        The pool (no further use after this).
    """
    kill = getattr(pool, "kill_workers", None)  # Python 3.14 has it
    if kill is not None:
        kill()
        return
    # before 3.14 the pool offers no way to stop a running task: its worker processes are
    # killed (the pool's own thread then fails their futures and closes its queues)
    workers = list((getattr(pool, "_processes", None) or {}).values())
    thread = getattr(pool, "_executor_manager_thread", None)  # shutdown() forgets it
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in workers:
        try:
            proc.kill()
        except (OSError, ValueError):
            pass
    for proc in workers:
        try:
            proc.join(KILL_WAIT_S)
        except (OSError, ValueError, AssertionError):
            pass
    # the pool's own thread ends now, not in the interpreter's exit hook (Python < 3.14 joins it
    # there, where a stop signal interrupted the join: "Exception ignored ... _python_exit").
    # Its wakeup leaves the hook even when the thread outlives the wait (a busy machine): the
    # hook's wakeup() raced the thread closing that pipe ("Exception ignored in: <module
    # 'threading'>", CI, 1 run in many). With its workers killed the thread ends by itself,
    # and the interpreter still joins it, a non-daemon thread. (It is taken before shutdown(),
    # which drops the pool's reference on Python 3.11: before, neither was done.)
    if thread is not None:
        with contextlib.suppress(RuntimeError):
            thread.join(KILL_WAIT_S)
        getattr(cf.process, "_threads_wakeups", {}).pop(thread, None)


@contextlib.contextmanager
def process_pool(workers: int, context=None) -> Iterator[cf.ProcessPoolExecutor]:
    """A process pool of ``workers`` (each with :func:`worker_signals`), shut down when the block
    ends: waited for after normal work, abandoned (:func:`abandon`) when the block raises.

    Parameters
    ----------
    workers : int
        Worker processes, ≥ 1.
    context : multiprocessing context, optional
        How the workers start (default: the platform's); with ``fork`` every worker is
        forked as the block begins, so it inherits the state of that moment.

    Yields
    ------
    concurrent.futures.ProcessPoolExecutor
        Submit with ``pool.submit``; collect with :func:`results` or :func:`as_finished`.
    """
    pool = cf.ProcessPoolExecutor(max_workers=int(workers), mp_context=context, initializer=worker_signals)
    try:
        # the workers start with the first task: never a stop inside the fork's hooks
        with shielded():
            pool.submit(int).result()
        yield pool
    except BaseException:
        abandon(pool)
        raise
    pool.shutdown(wait=True)


def submit_all(pool, fn, tasks: Iterable[tuple]) -> list[cf.Future]:
    """Submit ``fn(*task)`` for each task, a stop held until every submission is in
    (:func:`station.signals.shielded`): ``submit`` puts the task on the pool's queues under their
    locks, and a stop raised by the handler between a lock's acquire and its release leaves it
    held; the pool's own thread then waits for it for ever, and so does the interpreter's exit
    (a ``tune`` stopped in CI hung in ``concurrent.futures.process._python_exit``).

    Parameters
    ----------
    pool : Executor
        A process pool, a thread pool or a Dask client's executor.
    fn : callable
        Picklable for a process pool.
    tasks : iterable of tuple
        Argument tuples.

    Returns
    -------
    list of Future
        In the order of ``tasks``.

    Raises
    ------
    station.signals.StopSignal
        A signal arrived during the submissions (raised after them; the caller's pool is
        abandoned as for any stop), also when it killed a worker and so broke the pool
        mid-submission (a process group's SIGTERM reaches the workers too).
    WorkerLost
        A worker process died during the submissions, no signal pending (one line, exit code 1).
    """
    try:
        with shielded():
            return [pool.submit(fn, *task) for task in tasks]
    except BrokenProcessPool:  # the block's own error: a stop held meanwhile is the cause, and comes first
        check_stop()
        raise WorkerLost() from None


def _wait(futures: Iterable[cf.Future], return_when: str) -> tuple[set, set]:
    """``concurrent.futures.wait`` in :data:`POLL_S` steps, a pending stop raised between them."""
    pending = set(futures)
    while True:
        done, pending = cf.wait(pending, timeout=POLL_S, return_when=return_when)
        if done or not pending:
            return done, pending
        check_stop()


def results(futures: Sequence[cf.Future]) -> list[Any]:
    """Every future's result, in their order (a task's exception raised as it is).

    Parameters
    ----------
    futures : sequence of Future
        From ``submit`` on a process pool, a thread pool or a Dask client's executor.

    Returns
    -------
    list
        ``[f.result() for f in futures]``.

    Raises
    ------
    station.signals.StopSignal
        A signal arrived while waiting (within :data:`POLL_S`); nothing is cancelled here.
    WorkerLost
        A worker process died and broke the pool (one line, exit code 1), no signal pending.
    """
    out = []
    for f in futures:
        if not f.done():
            _wait([f], cf.ALL_COMPLETED)
        if lost(f):
            check_stop()  # a signal that killed the worker too: the stop is what happened
            raise WorkerLost() from None
        out.append(f.result())
    return out


def as_finished(futures: Iterable[cf.Future]) -> Iterator[cf.Future]:
    """The futures as they finish (``concurrent.futures.as_completed``, answering a stop within
    :data:`POLL_S`).

    Parameters
    ----------
    futures : iterable of Future
        Submitted work.

    Yields
    ------
    Future
        Each one once, done.

    Raises
    ------
    station.signals.StopSignal
        A signal arrived while waiting.
    """
    pending = set(futures)
    while pending:
        done, pending = _wait(pending, cf.FIRST_COMPLETED)
        yield from done
