"""Which effects the runs call for: every candidate fitted alone per fold, then forward
selection (at most :data:`MAX_EFFECTS`, joint refit of all accepted effects at each step),
each step accepted only when it pays on held-out data beyond what quantization and noise
reach by luck.

Acceptance: the pooled validation cost must fall by at least :data:`MIN_RELATIVE_GAIN`
(parsimony: an effect must pay for itself) and by at least :data:`MIN_NOISE_GAIN` noise
variances per sample, both measured from the lower of the current model's cost and the
cost that tiny perturbations of it reach by luck (:data:`NULL_PERTURBATIONS`); otherwise the
answer is "none". Fits are grid bracketing then local refinement
(:func:`station.analysis.fitting.fit`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

from station.analysis.fitting import Axis, axis_for, fit
from station.diagnosis.cost import Evaluator, pooled, relative_gain, rms_gain
from station.diagnosis.folds import Fold, validation_runs
from station.diagnosis.prose import format_value
from station.plant.effects import EFFECTS

MIN_RELATIVE_GAIN = 0.05
"""An effect is accepted only when it lowers the pooled validation cost by this fraction."""

MIN_NOISE_GAIN = 0.1
"""... and by at least this many noise variances per sample (θ and a counted separately):
encoder rounding and accelerometer noise cannot explain it."""

MAX_EFFECTS = 3
"""Forward selection stops after this many accepted effects."""

SECOND_STEP_CANDIDATES = 6
"""From the second forward step on, only this many of the best single effects are tried
jointly with the accepted ones (the rest did not pay alone)."""

NULL_PERTURBATIONS = (("accel_gain", 0.996), ("accel_gain", 0.998), ("accel_gain", 1.002), ("accel_gain", 1.004),
                      ("param:act_K", 0.998), ("param:act_K", 1.002), ("param:EI", 0.998), ("param:EI", 1.002))
"""Perturbations of the current model far too small to be a cause (0.2-0.4 %): what they
change in the validation cost is what quantization and noise alone do (e.g. the rounding
of θ and a, and in an accelerometer-feedback loop the measured noise, send a closed loop
along another path)."""


@dataclass
class Search:
    """What every step of the search shares.

    Attributes
    ----------
    ev : Evaluator
        The runs and the cached cost.
    folds : list of Fold
    fit_runs : tuple of int
        All runs the candidates are fitted on (the reported values are fitted on them).
    axes : dict of str to Axis
        How each effect is searched (:func:`effect_axes`).
    workers : int
        Threads fitting candidates at once.
    say : callable
        Called with one line of progress text.
    """

    ev: Evaluator
    folds: list
    fit_runs: tuple
    axes: dict
    workers: int = 1
    say: Callable[[str], None] = lambda msg: None


@dataclass
class Trial:
    """A set of effects fitted per fold and judged on the folds' validation runs.

    Attributes
    ----------
    names : tuple of str
    fold_values : list of dict
        Per fold: effect name -> value fitted on its fit runs.
    val_sse : dict of int to (float, float)
        Run index -> squared θ and a errors of its held-out prediction, counts².
    val_weighted : float
        Σ noise-weighted errors over the validation runs.
    """

    names: tuple
    fold_values: list
    val_sse: dict
    val_weighted: float


@dataclass
class Singles:
    """Every candidate fitted alone (step 1).

    Attributes
    ----------
    trials : dict of str to Trial
        Per candidate, in the candidates' order.
    values : dict of str to dict
        Per candidate, its value fitted alone on all fit runs ({name: value}).
    """

    trials: dict
    values: dict


@dataclass
class Step:
    """One step of forward selection, kept for the alternatives
    (:mod:`station.diagnosis.doubt`).

    Attributes
    ----------
    before : list of str
        The effects accepted before this step.
    trials : dict of str to Trial
        Every candidate tried at this step (jointly with ``before``).
    chosen : str or None
        The one accepted (None: nothing paid, selection stopped).
    floor : float
        What luck alone reaches around the model before this step (:func:`null_floor`).
    """

    before: list
    trials: dict
    chosen: str | None
    floor: float


@dataclass
class Selection:
    """What forward selection accepted.

    Attributes
    ----------
    accepted : list of str
        In the order they were added.
    current : Trial
        The accepted set as fitted per fold (the nominal model's trial when none).
    values : dict of str to float
        The accepted effects refitted jointly on all fit runs.
    steps : list of Step
        Every step tried, in order.
    """

    accepted: list
    current: Trial
    values: dict
    steps: list = field(default_factory=list)


def effect_axes() -> dict[str, Axis]:
    """How every effect of the vocabulary is searched (its range and grid spacing)."""
    return {name: axis_for(name, s.lower, s.upper, s.neutral) for name, s in EFFECTS.items()}


def fit_set(ev: Evaluator, axes: Sequence[Axis], runs: Sequence[int], start: Mapping[str, float]) -> dict:
    """Effect values that minimise the cost over runs.

    Parameters
    ----------
    ev : Evaluator
    axes : sequence of Axis
        The effects fitted together.
    runs : sequence of int
        The runs fitted on.
    start : mapping of str to float
        Starting values (others start at their grid's best point).
    """
    res = fit(lambda vals: ev.cost(vals, runs), axes, start=start)
    return res.values


def trial(ev: Evaluator, folds: Sequence[Fold], names: tuple, axes: Mapping[str, Axis],
          starts: Sequence[Mapping]) -> Trial:
    """Fit a set of effects on each fold's fit runs and judge it on its validation runs.

    Parameters
    ----------
    ev : Evaluator
    folds : sequence of Fold
    names : tuple of str
        The effects fitted together.
    axes : mapping of str to Axis
    starts : sequence of mapping
        Per fold, starting values.
    """
    fold_values, val_sse, total = [], {}, 0.0
    for fold, start in zip(folds, starts):
        values = fit_set(ev, [axes[n] for n in names], fold.fit, start)
        fold_values.append(values)
        for i in fold.val:
            val_sse[i] = ev.sse(values, i)
            total += ev.weighted(values, i)
    return Trial(names, fold_values, val_sse, total)


def screen(ev: Evaluator, axes: Mapping[str, Axis], names: Sequence[str], fixed: Mapping[str, float],
           runs: Sequence[int]) -> list[str]:
    """The effects worth a joint trial beside the accepted ones: each scanned on its grid
    with the accepted effects fixed (all fit runs); the best :data:`SECOND_STEP_CANDIDATES`
    that lower the cost, best first. An effect that did not pay alone may pay beside another.

    Parameters
    ----------
    ev : Evaluator
    axes : mapping of str to Axis
    names : sequence of str
        The effects not accepted yet.
    fixed : mapping of str to float
        The accepted effects' values.
    runs : sequence of int
        The fit runs.
    """
    c0 = ev.cost(fixed, runs)
    best = {}
    for n in names:
        best[n] = min(ev.cost({**fixed, n: float(g)}, runs) for g in axes[n].grid())
    keep = sorted((n for n in names if best[n] < c0), key=best.get)
    return keep[:SECOND_STEP_CANDIDATES]


def perturbed(name: str, values: Mapping[str, float], factor: float) -> float:
    """An effect's value scaled by a tiny factor, kept inside its range: a value fitted on
    its bound is perturbed inward (divided by the factor instead).

    Parameters
    ----------
    name : str
        The effect (:data:`station.plant.effects.EFFECTS`).
    values : mapping of str to float
        The current values (the effect's neutral value when absent).
    factor : float
        Close to 1 (:data:`NULL_PERTURBATIONS`).
    """
    spec = EFFECTS[name]
    v = values.get(name, spec.neutral)
    for x in (v * factor, v / factor):
        if spec.lower <= x <= spec.upper:
            return x
    return v


def null_floor(ev: Evaluator, folds: Sequence[Fold], fold_values: Sequence[Mapping[str, float]]) -> float:
    """The validation cost reached by luck alone: per validation run the lowest weighted
    error over :data:`NULL_PERTURBATIONS` of the current model (as fitted per fold), summed.

    Parameters
    ----------
    ev : Evaluator
    folds : sequence of Fold
    fold_values : sequence of mapping
        Per fold, the current model's effect values.
    """
    total = 0.0
    for fold, values in zip(folds, fold_values):
        for i in fold.val:
            best = ev.weighted(values, i)
            for name, factor in NULL_PERTURBATIONS:
                best = min(best, ev.weighted({**values, name: perturbed(name, values, factor)}, i))
            total += best
    return total


def accept(v0: float, v1: float, terms: int, floor: float | None = None) -> bool:
    """Pays on validation data beyond parsimony and noise (module docstring).

    Parameters
    ----------
    v0, v1 : float
        Validation cost (Σ weighted errors) of the current model and with the candidate.
    terms : int
        Error terms of the validation runs (2N per run).
    floor : float, optional
        What luck alone reaches around the current model (:func:`null_floor`), the
        reference when lower than ``v0``.
    """
    if not math.isfinite(v1) or v0 <= 0:
        return False
    ref = v0 if floor is None else min(v0, floor)
    return (1.0 - v1 / ref) >= MIN_RELATIVE_GAIN and (ref - v1) / terms >= MIN_NOISE_GAIN


def fit_each_alone(search: Search, names: Sequence[str], nominal: Trial) -> Singles:
    """Step 1: every candidate fitted alone per fold and on all fit runs.

    Parameters
    ----------
    search : Search
    names : sequence of str
        The candidates.
    nominal : Trial
        The nominal model's (no effects) validation errors.
    """
    ev, folds, fit_runs = search.ev, search.folds, search.fit_runs
    # a fold fitted on all fit runs (the --validate one) already holds the value on all of them
    whole = next((k for k, f in enumerate(folds) if f.fit == fit_runs), None)

    def alone(name):
        tr = trial(ev, folds, (name,), search.axes, [{}] * len(folds))
        return tr, (tr.fold_values[whole] if whole is not None else fit_set(ev, [search.axes[name]], fit_runs, {}))

    rms_nom = pooled(ev, nominal.val_sse).rms_theta
    trials, values = {}, {}
    with ThreadPoolExecutor(search.workers) as pool:
        for k, (name, (tr, vals)) in enumerate(zip(names, pool.map(alone, names)), 1):
            trials[name], values[name] = tr, vals
            g = rms_gain(pooled(ev, tr.val_sse).rms_theta, rms_nom)
            cg = relative_gain(tr.val_weighted, nominal.val_weighted)
            search.say(f"[{k}/{len(names)}] {name} = {format_value(vals[name], EFFECTS[name].unit)}: "
                       f"validation θ gain {g:.1f} %, cost gain {cg:.1f} % ({ev.simulations} simulations)")
    return Singles(trials, values)


def _joint_trials(search: Search, names: Sequence[str], accepted: list[str], current: Trial,
                  fixed: Mapping[str, float], step: int) -> dict[str, Trial]:
    """The screened candidates, each fitted per fold jointly with the accepted ones."""
    ev = search.ev
    pool = screen(ev, search.axes, [n for n in names if n not in accepted], fixed, search.fit_runs)
    search.say(f"step {step + 1}: screening beside {' + '.join(accepted)} on all fit runs: {', '.join(pool)}")
    with ThreadPoolExecutor(search.workers) as ex:
        futures = {n: ex.submit(trial, ev, search.folds, tuple(accepted) + (n,), search.axes, current.fold_values)
                   for n in pool}
    trials = {n: f.result() for n, f in futures.items()}
    for n in pool:
        search.say(f"step {step + 1}: {' + '.join(accepted + [n])}: validation cost gain "
                   f"{relative_gain(trials[n].val_weighted, current.val_weighted):.1f} % over {' + '.join(accepted)} "
                   f"({ev.simulations} simulations)")
    return trials


def forward_select(search: Search, names: Sequence[str], singles: Singles, nominal: Trial) -> Selection:
    """Add the best effect while it pays (:func:`accept`), at most :data:`MAX_EFFECTS`;
    after each, refit the accepted effects jointly on all fit runs.

    Parameters
    ----------
    search : Search
    names : sequence of str
        The candidates.
    singles : Singles
        Step 1 (:func:`fit_each_alone`).
    nominal : Trial
        The nominal model's validation errors: where selection starts.
    """
    ev, folds = search.ev, search.folds
    terms = ev.terms(validation_runs(folds))
    accepted: list[str] = []
    current = nominal
    values: dict[str, float] = {}
    steps: list[Step] = []
    for step in range(MAX_EFFECTS):
        if step == 0:
            trials = {n: singles.trials[n] for n in names}
        else:
            trials = _joint_trials(search, names, accepted, current, values, step)
        if not trials:
            break
        best = min(trials, key=lambda n: trials[n].val_weighted)
        floor = null_floor(ev, folds, current.fold_values)
        search.say(f"step {step + 1}: best {best}, validation cost {trials[best].val_weighted / terms:.3g} per sample, "
                   f"current {current.val_weighted / terms:.3g}, reached by quantization and noise alone "
                   f"{floor / terms:.3g}")
        ok = accept(current.val_weighted, trials[best].val_weighted, terms, floor)
        steps.append(Step(list(accepted), trials, best if ok else None, floor))
        if not ok:
            break
        accepted.append(best)
        current = trials[best]
        if step == 0:
            values = dict(singles.values[best])
        else:
            values = fit_set(ev, [search.axes[n] for n in accepted], search.fit_runs, values)
        search.say(f"accepted {best} (step {step + 1}): "
                   + ", ".join(f"{n} = {format_value(v, EFFECTS[n].unit)}" for n, v in values.items()))
    return Selection(accepted, current, values, steps)
