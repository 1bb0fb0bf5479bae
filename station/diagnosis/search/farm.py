"""Independent fits of one search farmed out to worker processes (``workers`` > 1).

The diagnosis's fits are Python around a compiled sample loop: two threads contend for the
GIL and were slower than one on 2 cores (docs/benchmarks.md, "The diagnosis"). Here each
task runs in a forked worker that inherits the search as it stands (the runs, the noise
levels, the errors' cache: nothing is pickled to it), and sends back its result with the
simulations it made; the errors it computed join the main process's cache, so what follows
finds them. The answer is the same as on one thread: each task's fits start from the same
values and simulate the same models.

Without ``fork`` (not Linux), or with one worker, the tasks run one after another in the
calling thread. Stops and lost workers are :mod:`station.pools`' (a stop ends the work
within :data:`station.pools.POLL_S`; the workers are killed).
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from station.diagnosis.runs.cost import Evaluator, EvaluatorWork
from station.pools import process_pool, results, submit_all

_TASKS: tuple[Callable[[Any], Any], Sequence[Any], Evaluator] | None = None
"""The farmed function, its items and the evaluator, set before the workers fork (inherited)."""


def _run(i: int) -> tuple[int, Any, EvaluatorWork]:
    """Task i in a worker: its result, and the errors it computed and the runs it simulated."""
    fn, items, ev = _TASKS
    mark = ev.mark()
    out = fn(items[i])
    return i, out, ev.work_since(mark)


def can_fork() -> bool:
    """Whether worker processes can inherit the search.

    Returns
    -------
    bool
        True where the ``fork`` start method exists (Linux); elsewhere :func:`farm` runs its
        tasks one after another.
    """
    return "fork" in multiprocessing.get_all_start_methods()


def farm(fn: Callable[[Any], Any], items: Sequence[Any], ev: Evaluator, workers: int) -> Iterator[tuple[int, Any]]:
    """``fn(item)`` for every item, on up to ``workers`` forked processes.

    Parameters
    ----------
    fn : callable
        A task of the search (a closure is fine: the workers inherit it).
    items : sequence
        One task each.
    ev : Evaluator
        The search's evaluator: its cache and simulation count take in the workers'.
    workers : int
        Processes at once; 1 (or no ``fork``): one after another here.

    Yields
    ------
    (int, object)
        The item's index and ``fn(item)``, in the items' order.

    Raises
    ------
    station.signals.StopSignal
        SIGINT or SIGTERM arrived (the workers are killed).
    station.pools.WorkerLost
        A worker process died.
    """
    global _TASKS
    items = list(items)
    n = min(int(workers), len(items))
    if n <= 1 or not can_fork():
        for i, item in enumerate(items):
            yield i, fn(item)
        return
    _TASKS = (fn, items, ev)
    try:
        with process_pool(n, multiprocessing.get_context("fork")) as pool:
            futures = submit_all(pool, _run, [(i,) for i in range(len(items))])
            _TASKS = None  # the workers have their copy
            for fut in futures:
                (i, out, work), = results([fut])  # a bounded wait: a stop is answered within 0.1 s
                ev.take_in(work)
                yield i, out
    finally:
        _TASKS = None


__all__ = ["can_fork", "farm"]
