"""Which estimator gives the accepted effects their values: least squares in noise units, or
maximum likelihood with an unknown error variance per run and signal — chosen by the runs
each fold held out.

Forward selection fits every candidate by the noise-weighted least-squares cost (blind, it
names the effects of the vocabulary; :mod:`station.diagnosis.runs.cost`). Once the structure is
chosen, its values are also estimated with the maximum-likelihood cost
(``Evaluator(likelihood=True)``): where the model's errors are far above the sensor noise —
a real rig, whose open-loop pulses carry 93 % of θ's least-squares cost on the four thesis
logs — least squares lets the worst-fitted run decide and the others are outvoted, while the
likelihood counts every run and signal by its samples. Near the noise floor both are least
squares. The estimate whose fold fits predict the held-out runs better (the same noise-
weighted validation cost that judged the structure) is kept, and the rest of the diagnosis
(intervals, alternatives) uses that cost; the choice is said in the progress.
"""

from __future__ import annotations

from typing import NamedTuple

from station.diagnosis.search.selection import Search, Selection, trial
from station.diagnosis.search.stepwise import refit_accepted


class Estimate(NamedTuple):
    """The accepted effects' values and how they were estimated (:func:`choose_estimator`).

    Attributes
    ----------
    selection : Selection
        The selection with its fold fits and values (the likelihood's when it was chosen).
    likelihood : bool
        The maximum-likelihood estimate was kept (the evaluator's cost is left on it).
    note : str
        The comparison in words ("" when nothing was accepted).
    """

    selection: Selection
    likelihood: bool
    note: str


def choose_estimator(search: Search, sel: Selection) -> Estimate:
    """Estimate the accepted effects both ways and keep the one held-out runs prefer.

    Parameters
    ----------
    search : Search
        The diagnosis's runs, folds and axes; its evaluator is left with the chosen cost.
    sel : Selection
        Forward selection's result (least-squares fits).

    Returns
    -------
    Estimate
    """
    ev = search.ev
    names = sel.current.names
    if not sel.accepted or ev.likelihood or set(sel.values) - set(names) - {"coulomb_friction"}:
        return Estimate(sel, ev.likelihood, "")  # (a fitted Stribeck shape is held: least squares' own)
    with ev.costed(likelihood=True):
        ml = trial(ev, search.folds, names, search.axes, sel.current.fold_values)
    if ml.val_weighted >= sel.current.val_weighted:
        note = (f"values by least squares: the maximum-likelihood fits predict the held-out runs no better "
                f"(validation cost {ml.val_weighted / sel.current.val_weighted:.3f}x)")
        search.say(note)
        return Estimate(sel, False, note)
    ev.likelihood = True  # kept: the rest of the diagnosis uses this cost
    values = refit_accepted(search, ml, dict(sel.values))
    note = (f"values by maximum likelihood (an unknown error variance per run and signal): its fold fits "
            f"predict the held-out runs better than least squares (validation cost "
            f"{ml.val_weighted / sel.current.val_weighted:.3f}x)")
    search.say(note)
    return Estimate(Selection(list(sel.accepted), ml, values, sel.steps), True, note)

