"""Which effects the runs call for, the search's parts: every candidate fitted alone per
fold, sets of effects fitted per fold and judged on held-out runs (:func:`trial`), the
in-sample screen of candidates beside accepted effects, and the acceptance rule: a step is
accepted only when it pays on held-out data beyond what quantization and noise reach by
luck. The order of the search (forward selection, at most :data:`MAX_EFFECTS`, with a
lookahead over its first effect) is :mod:`station.diagnosis.search.stepwise`'s.

Acceptance: the pooled validation cost must fall by at least :data:`MIN_RELATIVE_GAIN`
(parsimony: an effect must pay for itself) and by at least :data:`MIN_NOISE_GAIN` noise
variances per sample, both measured from the lower of the current model's cost and the
cost that tiny perturbations of it reach by luck (:data:`NULL_PERTURBATIONS`); otherwise the
answer is "none". Fits are grid bracketing then local refinement
(:func:`station.diagnosis.search.bounded.fit`).

Breakaway friction (:mod:`station.diagnosis.search.fitting`) is one step fitted as its sliding
level plus an excess; :func:`credible` names it over plain Coulomb friction only when the
excess pays for itself (:data:`~station.diagnosis.search.fitting.NESTED`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from station.diagnosis.search.farm import farm
from station.diagnosis.search.bounded import Axis
from station.diagnosis.search.fitting import (EXCESS, MIN_EXCESS, NESTED, excess_of, fit_beside, fit_set, set_axes,
                                              unstick)
from station.diagnosis.runs.cost import Evaluator, pooled, relative_gain, rms_gain
from station.diagnosis.runs.folds import Fold
from station.diagnosis.units import format_quantity
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

SMALL_EXCESS = 0.25
"""A breakaway excess (v_s − v_c) / v_s below this is what luck reaches beside plain Coulomb
friction in a stick-slip cost (blind, a 4096-count encoder beside Coulomb friction 9.17: a
breakaway of 10.8 over 9.12, 16 %); :func:`credible` judges it against the luck around the
Coulomb friction alone."""

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
        Worker processes fitting candidates at once (:func:`station.diagnosis.search.farm.farm`).
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
    (:mod:`station.diagnosis.honesty.doubt`).

    Attributes
    ----------
    before : list of str
        The effects accepted before this step.
    trials : dict of str to Trial
        Every credible candidate tried at this step (jointly with ``before``).
    chosen : str or None
        The one accepted (None: nothing paid, selection stopped).
    floor : float
        What luck alone reaches around the model before this step (:func:`null_floor`).
    set_aside : dict of str to Trial
        Candidates tried and set aside by :func:`credible` (a breakaway that did not pay for
        its excess over the sliding level): rivals still, when they fit as well.
    current : Trial or None
        The model before this step (the rival of an upgrade in place).
    """

    before: list
    trials: dict
    chosen: str | None
    floor: float
    set_aside: dict = field(default_factory=dict)
    current: Trial | None = None


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

    Returns
    -------
    Trial
        ``names``, the values fitted per fold, each validation run's squared θ and a errors
        (counts²) and their noise-weighted sum.
    """
    fold_values = [fit_set(ev, set_axes(names, axes), fold.fit, start) for fold, start in zip(folds, starts)]
    return judge(ev, folds, names, unstick(ev, folds, names, axes, fold_values))


def judge(ev: Evaluator, folds: Sequence[Fold], names: tuple, fold_values: Sequence[Mapping]) -> Trial:
    """Judge a set of effects as fitted per fold on each fold's validation runs.

    Parameters
    ----------
    ev : Evaluator
    folds : sequence of Fold
    names : tuple of str
        The effects fitted.
    fold_values : sequence of mapping
        Per fold, the values fitted on its fit runs.

    Returns
    -------
    Trial
    """
    val_sse, total = {}, 0.0
    for fold, values in zip(folds, fold_values):
        for i in fold.val:
            val_sse[i] = ev.sse(values, i)
            total += ev.weighted(values, i)
    return Trial(names, list(fold_values), val_sse, total)


def with_accel_gain(ev: Evaluator, folds: Sequence[Fold], fit_runs: Sequence[int], sel: Selection) -> Selection:
    """The selection holding the accelerometer's gain refitted beside its effects, on all fit
    runs and per fold on the fold's, where the search judged a up to each run's own scale
    (:attr:`station.diagnosis.runs.cost.Evaluator.accel_scale`): the gain a saved model holds
    and a held-out run is predicted with.

    Parameters
    ----------
    ev : Evaluator
    folds : sequence of Fold
    fit_runs : sequence of int
    sel : Selection

    Returns
    -------
    Selection
        A copy: its ``values`` and its current trial's ``fold_values`` hold ``accel_gain``
        (the trial's validation errors as the search judged them).
    """
    values = {**sel.values, "accel_gain": ev.fit_accel_gain(sel.values, fit_runs)}
    fold_values = [{**fv, "accel_gain": ev.fit_accel_gain(fv, fold.fit)}
                   for fv, fold in zip(sel.current.fold_values, folds)]
    current = Trial(sel.current.names, fold_values, sel.current.val_sse, sel.current.val_weighted)
    return Selection(sel.accepted, current, values, sel.steps)


def screen(ev: Evaluator, axes: Mapping[str, Axis], names: Sequence[str], fixed: Mapping[str, float],
           runs: Sequence[int]) -> list[str]:
    """The effects worth a joint trial beside the accepted ones: the best
    :data:`SECOND_STEP_CANDIDATES` of :func:`screen_costs`, best first. An effect that did
    not pay alone may pay beside another.

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

    Returns
    -------
    list of str
        At most :data:`SECOND_STEP_CANDIDATES` effect names, lowest cost first; empty when none
        lowers the cost.
    """
    return list(screen_costs(ev, axes, names, fixed, runs))[:SECOND_STEP_CANDIDATES]


def screen_costs(ev: Evaluator, axes: Mapping[str, Axis], names: Sequence[str], fixed: Mapping[str, float],
                 runs: Sequence[int], every: int = 1, refit: Sequence[str] = (), workers: int = 1) -> dict[str, float]:
    """Each effect scanned on its grid with ``fixed`` held (in-sample, on ``runs``): the
    lowest cost it reaches, for those that lower the cost of ``fixed`` alone, best first.
    With ``refit``, those effects of ``fixed`` are refined jointly with each candidate after its
    scan (:func:`~station.diagnosis.search.fitting.fit_beside`): a joint screen.

    Parameters
    ----------
    ev : Evaluator
    axes : mapping of str to Axis
    names : sequence of str
        The effects scanned.
    fixed : mapping of str to float
        The effects held at their values.
    runs : sequence of int
        The runs the cost is summed over.
    every : int, optional
        Scan every so many grid points (2: half the simulations, a coarser look).
    refit : sequence of str, optional
        Effects of ``fixed`` refined jointly with each candidate (static_friction's screen,
        over the excess grid, holds them).
    workers : int, optional
        Worker processes screening candidates at once (:func:`~station.diagnosis.search.farm.farm`;
        the same costs with any number).

    Returns
    -------
    dict of str to float
        Effect name to the lowest normalised cost J (dimensionless) it reaches, only those
        below the cost of ``fixed`` alone, in increasing order of cost.
    """
    c0 = ev.cost(fixed, runs)

    def lowest(n: str) -> float:
        if refit and n != "static_friction":
            return fit_beside(ev, axes, refit, n, runs, fixed)[0]
        return min(ev.cost(point, runs) for point in screen_points(n, axes, fixed)[::every])

    names = list(names)
    best = {names[i]: c for i, c in farm(lowest, names, ev, workers)}
    return {n: best[n] for n in sorted((n for n in names if best[n] < c0), key=best.get)}


def screen_points(name: str, axes: Mapping[str, Axis], fixed: Mapping[str, float]) -> list[dict]:
    """The values :func:`screen` tries for one effect beside ``fixed``: its grid; for
    static_friction the excess grid over an accepted sliding level, else its grid with
    the sliding level at half of it.

    Parameters
    ----------
    name : str
        The effect scanned (:data:`station.plant.effects.EFFECTS`).
    axes : mapping of str to Axis
        Every effect's axis (:func:`~station.diagnosis.search.fitting.effect_axes`).
    fixed : mapping of str to float
        The effects held, each in its effect's unit; copied into every point.

    Returns
    -------
    list of dict
        One effect-value mapping per grid point (``fixed`` plus the scanned effect, and for
        static_friction its sliding level), in the grid's order.
    """
    if name != "static_friction":
        return [{**fixed, name: float(g)} for g in axes[name].grid()]
    if "coulomb_friction" in fixed:
        v_c = fixed["coulomb_friction"]
        return [{**fixed, name: v_c + float(e)} for e in EXCESS.grid()]
    return [{**fixed, "coulomb_friction": 0.5 * float(g), name: float(g)} for g in axes[name].grid()]


def perturbed(name: str, values: Mapping[str, float], factor: float) -> float:
    """An effect's value scaled by a tiny factor, kept inside the range the fit searches (about
    the value where a model holds one past it, a gain the data decided): a value fitted on its
    bound is perturbed inward (divided by the factor instead).

    Parameters
    ----------
    name : str
        The effect (:data:`station.plant.effects.EFFECTS`).
    values : mapping of str to float
        The current values, the base model's own among them (the effect's neutral value
        when absent from both).
    factor : float
        Close to 1 (:data:`NULL_PERTURBATIONS`).

    Returns
    -------
    float
    """
    spec = EFFECTS[name]
    v = values.get(name, spec.neutral)
    for x in (v * factor, v / factor):
        if x == spec.neutral or spec.searched(x, about=v):
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

    Returns
    -------
    float
        Σ over the validation runs of the lowest noise-weighted error, dimensionless (the units
        of :attr:`Trial.val_weighted`).
    """
    total = 0.0
    for fold, values in zip(folds, fold_values):
        for i in fold.val:
            best = ev.weighted(values, i)
            for name, factor in NULL_PERTURBATIONS:
                best = min(best, ev.weighted({**values, name: perturbed(name, {**ev.model.effect_dict(), **values}, factor)}, i))
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

    Returns
    -------
    bool
        True when ``v1`` is finite and lowers the reference by at least
        :data:`MIN_RELATIVE_GAIN` relatively and :data:`MIN_NOISE_GAIN` per error term.
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

    Returns
    -------
    Singles
        Per candidate, in the order of ``names``: its trial and its value fitted alone on all
        fit runs.
    """
    ev, folds, fit_runs = search.ev, search.folds, search.fit_runs
    # a fold fitted on all fit runs (the --validate one) already holds the value on all of them
    whole = next((k for k, f in enumerate(folds) if f.fit == fit_runs), None)

    def alone(name):
        tr = trial(ev, folds, (name,), search.axes, [{}] * len(folds))
        return tr, (tr.fold_values[whole] if whole is not None
                    else fit_set(ev, set_axes((name,), search.axes), fit_runs, {}))

    rms_nom = pooled(ev, nominal.val_sse).rms_theta
    trials, values = {}, {}
    for k, (tr, vals) in farm(alone, names, ev, search.workers):
        name = names[k]
        trials[name], values[name] = tr, vals
        g = rms_gain(pooled(ev, tr.val_sse).rms_theta, rms_nom)
        cg = relative_gain(tr.val_weighted, nominal.val_weighted)
        search.say(f"[{k + 1}/{len(names)}] {name} = {format_quantity(vals[name], EFFECTS[name].unit)}: "
                   f"validation θ gain {g:.1f} %, cost gain {cg:.1f} % ({ev.simulations} simulations)")
    return Singles(trials, values)


def excess_fraction(tr: Trial) -> float:
    """(v_s − v_c) / v_s of a trial's static_friction, the median over its folds (0 without one).

    Parameters
    ----------
    tr : Trial

    Returns
    -------
    float
        The median fraction, dimensionless, in [0, 1]; 0 when no fold has a static_friction.
    """
    fr = [excess_of(v) for v in tr.fold_values if v.get("static_friction", 0.0) > 0]
    return float(np.median(fr)) if fr else 0.0


def credible(trials: Mapping[str, Trial], terms: int,
             floor: Callable[[Trial], float] | None = None) -> dict[str, Trial]:
    """The trials without a candidate that does not pay for its extra parameter over the
    simpler one it holds (:data:`NESTED`): a static_friction whose breakaway excess is
    below :data:`MIN_EXCESS`, or which does not :func:`accept` over coulomb_friction tried
    beside the same effects. Stick-slip's cost is so jagged that 0.2 % perturbations find
    30 % lower costs on some held-out runs, so with ``floor`` the comparison counts luck: an
    excess below :data:`SMALL_EXCESS`, which luck reaches beside plain Coulomb friction, must
    pay against what luck reaches around the Coulomb friction (as every step is judged); a
    larger one is judged luck against luck, the breakaway's floor against the Coulomb
    friction's (the Coulomb friction's floor alone set aside true breakaways of 10.9 over 5.0
    and 7.4 over 4.3, blind, whose own floors are lower still).

    Parameters
    ----------
    trials : mapping of str to Trial
        Candidate -> its trial in this step.
    terms : int
        Error terms of the validation runs.
    floor : callable, optional
        ``floor(trial) -> float``: what luck alone reaches around a trial's model
        (:func:`null_floor` of its fold values), for the simpler one and the candidate alike;
        without it their own costs.

    Returns
    -------
    dict of str to Trial
        A copy of ``trials`` without the candidates that do not pay over the simpler one.
    """
    out = dict(trials)
    for name, tr in trials.items():
        simpler = NESTED.get(name)
        if simpler is None:
            continue
        if excess_fraction(tr) < MIN_EXCESS:
            del out[name]
        elif simpler in trials:
            base = trials[simpler]
            v0, v1 = base.val_weighted, tr.val_weighted
            if floor is not None and v1 < v0:
                v0 = min(v0, floor(base))
                if excess_fraction(tr) >= SMALL_EXCESS:
                    v1 = min(v1, floor(tr))
            if not accept(v0, v1, terms):
                del out[name]
    return out
