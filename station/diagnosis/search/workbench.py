"""The set-up every search over runs works in, shared by :func:`station.diagnosis.diagnose`
and :func:`station.diagnosis.sessions.diagnose.diagnose_sessions`: the candidate names
checked before any work, BLAS held to one thread, the modal forms kept in memory, the
:class:`~station.diagnosis.search.selection.Search` and the nominal model's trial."""

from __future__ import annotations

from collections.abc import Callable, Iterable, Iterator, Sequence
from contextlib import contextmanager
from typing import NamedTuple

from threadpoolctl import threadpool_limits

from station.diagnosis.runs.cost import Evaluator
from station.diagnosis.runs.folds import Fold, validation_runs
from station.diagnosis.search.fitting import effect_axes
from station.diagnosis.search.selection import Search, Trial
from station.errors import StationError
from station.plant.diskcache import bulk
from station.plant.effects import CANDIDATES, EFFECTS


def check_candidates(command: str, candidates: Sequence[str] | None) -> list[str]:
    """The candidate effects to try, each a known effect.

    Parameters
    ----------
    command : str
        Names the command in the error ("diagnose", "survey --diagnose").
    candidates : sequence of str or None
        Effect names; None: :data:`station.plant.effects.CANDIDATES`.

    Returns
    -------
    list of str

    Raises
    ------
    StationError
        An unknown effect name.
    """
    names = list(CANDIDATES if candidates is None else candidates)
    for n in names:
        if n not in EFFECTS:
            raise StationError(f"{command}: unknown candidate effect '{n}' (known: {', '.join(EFFECTS)})")
    return names


class Bench(NamedTuple):
    """What a search is set up with (:func:`workbench`).

    Attributes
    ----------
    names : list of str
        The candidate effects, checked.
    workers : int
        Worker processes fitting candidates at once (at least 1).
    """

    names: list[str]
    workers: int

    def search(self, ev: Evaluator, folds: Sequence[Fold], fit_runs: Iterable[int],
               say: Callable[[str], None]) -> Search:
        """The search over ``ev``'s runs with every effect's axis and this bench's workers.

        Parameters
        ----------
        ev : Evaluator
        folds : sequence of Fold
        fit_runs : iterable of int
            The runs the candidates are fitted on.
        say : callable
            Called with one line of progress text.

        Returns
        -------
        Search
        """
        return Search(ev, folds, tuple(fit_runs), effect_axes(ev.model), self.workers, say)


@contextmanager
def workbench(command: str, candidates: Sequence[str] | None, workers: int | None = None) -> Iterator[Bench]:
    """Check the candidates, then run the block with BLAS on one thread and the modal forms
    in memory (:func:`station.plant.diskcache.bulk`: thousands of forms, not via the disk).

    The matrices are tiny (22 x 22): BLAS threads only contend with each other and the
    compiled sample loop (docs/benchmarks.md, "Threads").

    Parameters
    ----------
    command : str
        Names the command in errors.
    candidates : sequence of str or None
        Effect names (:func:`check_candidates`).
    workers : int, optional
        Worker processes fitting candidates at once (default 1).

    Yields
    ------
    Bench

    Raises
    ------
    StationError
        An unknown candidate, before anything starts.
    """
    names = check_candidates(command, candidates)
    with threadpool_limits(limits=1, user_api="blas"), bulk():
        yield Bench(names, max(1, int(workers or 1)))


def nominal_trial(ev: Evaluator, folds: Sequence[Fold]) -> Trial:
    """The nominal model's held-out errors (no effects in any fold): where a search starts.

    Parameters
    ----------
    ev : Evaluator
        With its noise levels set (:func:`station.diagnosis.runs.cost.calibrate_noise`).
    folds : sequence of Fold

    Returns
    -------
    Trial
    """
    val = validation_runs(folds)
    return Trial((), [{} for _ in folds], {i: ev.sse({}, i) for i in val}, sum(ev.weighted({}, i) for i in val))
