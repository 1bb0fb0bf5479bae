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

Breakaway friction is one step: the static_friction candidate is fitted as its sliding
level coulomb_friction plus a breakaway excess (:data:`EXCESS`), so it brings
coulomb_friction along (v_s >= v_c by construction) and takes one of the
:data:`MAX_EFFECTS` places (the rig's suspected amp_offset + breakaway friction +
param:drive_c fits in three). It is chosen over plain Coulomb friction only when the
excess pays for itself (:func:`accept` of the one over the other, :data:`NESTED`); once
coulomb_friction is accepted, static_friction is tried in its place (an upgrade that takes
no new place), and once static_friction is, coulomb_friction is no more a candidate; when
a later effect joins it, static_friction is judged again against coulomb_friction in its
place (a downgrade when the excess no longer pays). An accepted static_friction's
stribeck_speed is fitted last with the accepted values fixed and kept only when it pays on
the validation runs (:func:`station.diagnosis.search.stepwise.forward_select`); else it stays the model's (default 0.05 rad/s).

The cost of stick-slip has several valleys in (v_c, v_s): a broad one of plain Coulomb
friction (excess near 0) and the true one, under a count wide in v_c. A breakaway fit that
ends with an excess below :data:`MIN_EXCESS` is stuck: it is fitted again from the best
sliding levels of :data:`SLIDING_STARTS` on the excess grid (:data:`EXCESS_STARTS`), and
in a trial a fold stuck while another fold is not starts again from that fold's values
(folds share most runs). Only stuck fits pay for the extra starts.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np

from station.diagnosis.search.bounded import Axis, axis_for, fit
from station.diagnosis.runs.cost import Evaluator, pooled, relative_gain, rms_gain
from station.diagnosis.runs.folds import Fold
from station.diagnosis.units import format_quantity
from station.plant.effects import EFFECTS
from station.pools import results

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

EXCESS = Axis("static_friction-coulomb_friction", 0.0,
              EFFECTS["static_friction"].upper - EFFECTS["coulomb_friction"].upper, "sqrt")
"""The breakaway excess v_s - v_c, DAC counts: static_friction's second axis beside
coulomb_friction's (module docstring)."""

SLIDING_STARTS = (1.0, 0.7, 0.5, 1.3)
"""The sliding levels, as fractions of the start's coulomb_friction, a breakaway excess is
bracketed at: a Coulomb friction fitted alone lands between v_c and v_s (on the rig's
four thesis logs 16 counts, where breakaway lets it fall to 6-8: issue 17); fitted beside
drive damping it may land below v_c (blind static_friction + param:drive_c, seed 2: 3.9
for 4.9, where the cost's valley in v_c is under a count wide)."""

EXCESS_STARTS = 2
"""Sliding levels of :data:`SLIDING_STARTS` a breakaway excess is fitted from (the best on
the excess grid), keeping the lowest cost: the cost of stick-slip has several valleys. The
next start is tried only when the fit so far is stuck at an excess below
:data:`MIN_EXCESS` (blind static_friction + param:drive_c, seeds 2 and 5: 2-3 %, the hidden
8-57 %)."""

ZOOM = 0.5
"""A breakaway excess e is fitted again on a grid over (1 ± ZOOM)·e: where the P loop's
motor sticks depends on v_s in steps, and the cost's valley at the right v_s is a few
percent wide, narrower than the excess axis's grid."""

SHAPE = "stribeck_speed"
"""static_friction's shape setting: fitted last, beside an accepted static_friction only."""

NESTED = {"static_friction": "coulomb_friction"}
"""A candidate -> the simpler candidate it holds as a special case (no breakaway excess)."""

MIN_EXCESS = 0.1
"""static_friction is named only when its breakaway excess is at least this fraction of v_s
(median over the folds): the cost of stick-slip is so jagged in v_c (a twentieth of a count
moves it by 20 % near the noise floor) that a second friction axis finds lower points by
luck, with an excess of a few percent, where plain Coulomb friction is hidden."""

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
    (:mod:`station.diagnosis.honesty.doubt`).

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


def effect_axes(model=None) -> dict[str, Axis]:
    """How every effect of the vocabulary is searched (its range and grid spacing).

    Parameters
    ----------
    model : station.plant.model.Model, optional
        The base model: a signed effect it holds negative (a reversed accelerometer decided
        from the data, :mod:`station.logged.sensors`) is searched on its negative side.

    Returns
    -------
    dict of str to Axis
    """
    held = model.effect_dict() if model is not None else {}
    axes = {}
    for name, s in EFFECTS.items():
        flip = s.signed and held.get(name, s.neutral) < 0
        axes[name] = (axis_for(name, -s.upper, -s.lower, -s.neutral) if flip else
                      axis_for(name, s.lower, s.upper, s.neutral))
    return axes


def set_axes(names: Sequence[str], axes: Mapping[str, Axis]) -> list[Axis]:
    """The axes a set of effects is fitted on, in order: each effect's own, static_friction
    as coulomb_friction's and :data:`EXCESS` (module docstring).

    Parameters
    ----------
    names : sequence of str
        The effects fitted together (the one being added last).
    axes : mapping of str to Axis
        Every effect's axis (:func:`effect_axes`).

    Returns
    -------
    list of Axis
        The axes in the order of ``names``, static_friction contributing two
        (coulomb_friction's and :data:`EXCESS`).
    """
    out = []
    for n in names:
        out += [axes["coulomb_friction"], EXCESS] if n == "static_friction" else [axes[n]]
    return out


def _as_effects(coords: Mapping[str, float]) -> dict:
    """Axis coordinates -> effect values (v_s = v_c + excess)."""
    values = dict(coords)
    if EXCESS.name in values:
        values["static_friction"] = values.get("coulomb_friction", 0.0) + values.pop(EXCESS.name)
    return values


def _as_coords(values: Mapping[str, float]) -> dict:
    """Effect values -> axis coordinates (the excess of a static_friction)."""
    coords = dict(values)
    if "static_friction" in coords:
        excess = coords.pop("static_friction") - coords.get("coulomb_friction", 0.0)
        coords[EXCESS.name] = min(max(excess, EXCESS.lower), EXCESS.upper)
    return coords


def fit_set(ev: Evaluator, axes: Sequence[Axis], runs: Sequence[int], start: Mapping[str, float]) -> dict:
    """Effect values that minimise the cost over runs.

    Parameters
    ----------
    ev : Evaluator
    axes : sequence of Axis
        The effects fitted together (:func:`set_axes`).
    runs : sequence of int
        The runs fitted on.
    start : mapping of str to float
        Starting effect values (others start at their grid's best point). A breakaway
        excess without a starting sliding level starts from coulomb_friction fitted with
        the others at their start.

    Returns
    -------
    dict of str to float
        Effect name to fitted value, each in its unit (a breakaway excess given back as
        static_friction = coulomb_friction + excess, DAC counts).
    """
    axes = list(axes)
    start = dict(start)
    names = [a.name for a in axes]
    if EXCESS.name in names and "coulomb_friction" not in start:
        sliding = [a for a in axes if a.name == "coulomb_friction"]
        fixed = {a.name: start[a.name] for a in axes if a.name in start}
        start.update(fit(lambda vals: ev.cost(vals, runs), sliding, fixed=fixed).values)
    coords = _as_coords(start)
    best = _fit_from(ev, axes, runs, coords) if EXCESS.name not in names or EXCESS.name in coords else None
    if EXCESS.name in names and (best is None or _stuck(best.values)):
        # from the best sliding levels on the excess grid, while stuck (EXCESS_STARTS)
        for point in _sliding_starts(ev, axes, runs, {k: v for k, v in coords.items() if k != EXCESS.name}):
            if best is not None and not _stuck(best.values):
                break
            res = _fit_from(ev, axes, runs, point)
            if best is None or res.cost < best.cost:
                best = res
    return _as_effects(best.values)


def _stuck(coords: Mapping[str, float]) -> bool:
    """A breakaway fit ended at an excess too small to name (:data:`MIN_EXCESS`)."""
    return _excess_of(_as_effects(coords)) < MIN_EXCESS


def _excess_of(values: Mapping[str, float]) -> float:
    """(v_s − v_c) / v_s of a static_friction (0 without one)."""
    v_s = values.get("static_friction", 0.0)
    return (v_s - values.get("coulomb_friction", 0.0)) / v_s if v_s > 0 else 0.0


def _fit_from(ev: Evaluator, axes: Sequence[Axis], runs: Sequence[int], coords: Mapping[str, float]):
    """One start of :func:`fit_set` (in axis coordinates): the fit, and for a breakaway
    excess once more on a finer excess grid around the best (stick-slip's narrow valleys)."""
    res = fit(lambda vals: ev.cost(_as_effects(vals), runs), axes, start=coords)
    if EXCESS.name in res.values:
        e = res.values[EXCESS.name]
        zoom = Axis(EXCESS.name, max(EXCESS.lower, (1 - ZOOM) * e), min(EXCESS.upper, (1 + ZOOM) * e), "linear")
        if zoom.upper > zoom.lower:
            fine = fit(lambda vals: ev.cost(_as_effects(vals), runs),
                       [a for a in axes if a.name != EXCESS.name] + [zoom], start=res.values)
            if fine.cost < res.cost:
                res = fine
    return res


def refit_explanation(ev: Evaluator, names: Sequence[str], runs: Sequence[int], values: Mapping[str, float],
                      axes: Mapping[str, Axis]) -> dict:
    """An explanation's effects refitted on runs from its values, as the search fits them: the
    named effects on :func:`set_axes` (a static_friction as its sliding level coulomb_friction
    and breakaway excess, both refitted), every other value (a static_friction's
    stribeck_speed) held; never worse than ``values`` when they hold every named effect
    (returned when they fit better). The
    one way to refit an explanation outside the search: fitting
    ``[axes[n] for n in values]`` would refit v_s without its sliding level, or v_c past v_s.

    Parameters
    ----------
    ev : Evaluator
    names : sequence of str
        The explanation's effects (a diagnosis's ``causes``).
    runs : sequence of int
        The runs fitted on.
    values : mapping of str to float
        Where the fit starts: the explanation's values with what they hold (a diagnosis's
        ``extended_model.effect_dict()``); those not fitted are held.
    axes : mapping of str to Axis
        Every effect's axis (:func:`effect_axes`).

    Returns
    -------
    dict of str to float
        The fitted effects with the held values.
    """
    fitted = set(names) | {NESTED[n] for n in names if n in NESTED}
    held = {k: v for k, v in values.items() if k not in fitted}

    class _Holding:  # the cost with the held values applied (all fit_set asks of an Evaluator)
        def cost(self, vals, rs):
            return ev.cost({**held, **vals}, rs)

    start = {k: v for k, v in values.items() if k in fitted}
    refit = {**held, **fit_set(_Holding(), set_axes(names, axes), runs, start)}
    # the grid brackets the last axis afresh and may leave the start's valley: never worse than the start
    holding = _Holding()
    if set(names) <= set(values) and holding.cost(dict(values), runs) < holding.cost(refit, runs):
        return dict(values)
    return refit


def _sliding_starts(ev: Evaluator, axes: Sequence[Axis], runs: Sequence[int], coords: Mapping[str, float]) -> list[dict]:
    """Starts (axis coordinates) for a breakaway excess: the sliding level of ``coords``
    times each of :data:`SLIDING_STARTS` with the excess of :data:`EXCESS`'s grid that costs
    least there, the :data:`EXCESS_STARTS` lowest, best first."""
    base = {a.name: coords[a.name] for a in axes if a.name in coords}
    sliding = next(a for a in axes if a.name == "coulomb_friction")
    points = []
    for v_c in sorted({min(f * base["coulomb_friction"], sliding.upper) for f in SLIDING_STARTS}):
        grid = [{**base, "coulomb_friction": v_c, EXCESS.name: float(e)} for e in EXCESS.grid()]
        points.append(min((ev.cost(_as_effects(p), runs), k, p) for k, p in enumerate(grid))[::2])
    return [p for _, p in sorted(points, key=lambda cp: cp[0])[:EXCESS_STARTS]]


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
    fold_values = _unstick(ev, folds, names, axes, fold_values)
    val_sse, total = {}, 0.0
    for fold, values in zip(folds, fold_values):
        for i in fold.val:
            val_sse[i] = ev.sse(values, i)
            total += ev.weighted(values, i)
    return Trial(names, fold_values, val_sse, total)


def _unstick(ev: Evaluator, folds: Sequence[Fold], names: tuple, axes: Mapping[str, Axis],
             fold_values: list[dict]) -> list[dict]:
    """Folds whose breakaway excess is stuck below :data:`MIN_EXCESS` while another fold's
    is not, fitted again from that fold's values (the lower cost on their fit runs kept):
    folds share most runs, and stick-slip's jagged cost leaves some in a valley of plain
    Coulomb friction (blind static_friction + param:drive_c seed 9: three of four folds at
    1-7 % excess, the hidden 32 %)."""
    free = [fv for fv in fold_values if "static_friction" in fv and not _stuck(_as_coords(fv))]
    if not free:
        return fold_values
    out = []
    for fold, fv in zip(folds, fold_values):
        if "static_friction" in fv and _stuck(_as_coords(fv)):
            start = min(free, key=lambda other: ev.cost(other, fold.fit))
            again = fit_set(ev, set_axes(names, axes), fold.fit, start)
            fv = again if ev.cost(again, fold.fit) < ev.cost(fv, fold.fit) else fv
        out.append(fv)
    return out


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
                 runs: Sequence[int], every: int = 1) -> dict[str, float]:
    """Each effect scanned on its grid with ``fixed`` held (in-sample, on ``runs``): the
    lowest cost it reaches, for those that lower the cost of ``fixed`` alone, best first.

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

    Returns
    -------
    dict of str to float
        Effect name to the lowest normalised cost J (dimensionless) it reaches, only those
        below the cost of ``fixed`` alone, in increasing order of cost.
    """
    c0 = ev.cost(fixed, runs)
    best = {n: min(ev.cost(point, runs) for point in _screen_points(n, axes, fixed)[::every]) for n in names}
    return {n: best[n] for n in sorted((n for n in names if best[n] < c0), key=best.get)}


def _screen_points(name: str, axes: Mapping[str, Axis], fixed: Mapping[str, float]) -> list[dict]:
    """The values :func:`screen` tries for one effect beside ``fixed``: its grid; for
    static_friction the excess grid over an accepted sliding level, else its grid with
    the sliding level at half of it."""
    if name != "static_friction":
        return [{**fixed, name: float(g)} for g in axes[name].grid()]
    if "coulomb_friction" in fixed:
        v_c = fixed["coulomb_friction"]
        return [{**fixed, name: v_c + float(e)} for e in EXCESS.grid()]
    return [{**fixed, "coulomb_friction": 0.5 * float(g), name: float(g)} for g in axes[name].grid()]


def perturbed(name: str, values: Mapping[str, float], factor: float) -> float:
    """An effect's value scaled by a tiny factor, kept inside its range: a value fitted on
    its bound is perturbed inward (divided by the factor instead).

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
        if spec.admits(x):
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
    with ThreadPoolExecutor(search.workers) as pool:
        futures = [pool.submit(alone, name) for name in names]
        for k, (name, fut) in enumerate(zip(names, futures), 1):
            (tr, vals), = results([fut])  # a bounded wait: a stop is answered within 0.1 s
            trials[name], values[name] = tr, vals
            g = rms_gain(pooled(ev, tr.val_sse).rms_theta, rms_nom)
            cg = relative_gain(tr.val_weighted, nominal.val_weighted)
            search.say(f"[{k}/{len(names)}] {name} = {format_quantity(vals[name], EFFECTS[name].unit)}: "
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
    fr = [_excess_of(v) for v in tr.fold_values if v.get("static_friction", 0.0) > 0]
    return float(np.median(fr)) if fr else 0.0


def credible(trials: Mapping[str, Trial], terms: int) -> dict[str, Trial]:
    """The trials without a candidate that does not pay for its extra parameter over the
    simpler one it holds (:data:`NESTED`): a static_friction whose breakaway excess is
    below :data:`MIN_EXCESS`, or which does not :func:`accept` over coulomb_friction tried
    beside the same effects.

    Parameters
    ----------
    trials : mapping of str to Trial
        Candidate -> its trial in this step.
    terms : int
        Error terms of the validation runs.

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
        if excess_fraction(tr) < MIN_EXCESS or (
                simpler in trials and not accept(trials[simpler].val_weighted, tr.val_weighted, terms)):
            del out[name]
    return out
