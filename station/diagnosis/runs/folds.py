"""How candidates are judged on runs they were not fitted to: one fold on the ``--validate``
runs, or leave-one-run-out over the runs."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

LEAVE_ONE_OUT = "leave-one-run-out"
VALIDATION_RUNS = "validation runs"


@dataclass(frozen=True)
class Fold:
    """Fit on ``fit``, judge on ``val`` (run indices).

    Attributes
    ----------
    fit : tuple of int
        Runs the effects are fitted on.
    val : tuple of int
        Runs they are judged on.
    """

    fit: tuple
    val: tuple


def make_folds(n_fit: int, n_validate: int) -> tuple[list[Fold], str]:
    """The folds over runs 0..n_fit−1 (fitted on) and the n_validate runs after them.

    Parameters
    ----------
    n_fit : int
        Runs the candidates are fitted on (indices 0..n_fit−1).
    n_validate : int
        ``--validate`` runs after them (0: leave-one-run-out over the fit runs).

    Returns
    -------
    folds : list of Fold
    how : str
        :data:`VALIDATION_RUNS` or :data:`LEAVE_ONE_OUT`, as the report names it.
    """
    fit_idx = tuple(range(n_fit))
    if n_validate:
        return [Fold(fit_idx, tuple(range(n_fit, n_fit + n_validate)))], VALIDATION_RUNS
    return [Fold(tuple(j for j in fit_idx if j != i), (i,)) for i in fit_idx], LEAVE_ONE_OUT


def validation_runs(folds: Sequence[Fold]) -> list[int]:
    """Every run some fold judges on, in index order.

    Parameters
    ----------
    folds : sequence of Fold

    Returns
    -------
    list of int
        Sorted distinct run indices.
    """
    return sorted({i for f in folds for i in f.val})


def fold_records(folds: Sequence[Fold], names: Sequence[str], values: Sequence[Mapping[str, float]]) -> list[dict]:
    """Per fold, for the JSON: ``{"fit": [run name, ...], "validate": [...], "values": {effect: value}}``.

    Parameters
    ----------
    folds : sequence of Fold
    names : sequence of str
        Run names by index.
    values : sequence of mapping
        Per fold, the accepted effects' values fitted on it.

    Returns
    -------
    list of dict
        One per fold, in order, as above (run names as given, values in each effect's unit).
    """
    return [{"fit": [names[i] for i in f.fit], "validate": [names[i] for i in f.val], "values": dict(v)}
            for f, v in zip(folds, values)]
