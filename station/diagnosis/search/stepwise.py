"""Stepwise selection of the effects the runs call for: forward selection from the single
effects (:func:`station.diagnosis.search.selection.fit_each_alone`), with a lookahead over its
first step.

Forward selection adds the best effect while it pays (:func:`~station.diagnosis.search.selection.accept`:
the null floor, parsimony and noise), at most :data:`~station.diagnosis.search.selection.MAX_EFFECTS`,
refitting the accepted effects jointly on all fit runs after each; static_friction may
replace an accepted coulomb_friction in place and be downgraded again
(:mod:`station.diagnosis.search.selection`, breakaway friction).

Lookahead (a beam of width 1 + :data:`LOOKAHEAD` over the first step). Greedy forward
selection keeps its first choice, and with two effects hidden the best single effect is
often a proxy for both that the true pair cannot be reached from (Coulomb friction for
viscous friction plus backlash: backlash beside it does not pay, beside viscous friction it
takes the cost to the noise floor; a dead-zone for breakaway friction plus drive damping).
So at the second step the next :data:`LOOKAHEAD` single effects (by their in-sample cost
fitted alone) are tried as first effects too: every other candidate is scanned beside each
on all fit runs on a coarse grid (:func:`~station.diagnosis.search.selection.screen_costs`), the
best of them refined jointly with it as the joint screen refines the chosen one's (below), the
:data:`LOOKAHEAD_TRIALS` pairs whose in-sample cost is below the best pair's beside the
chosen first effect by the parsimony margin (MIN_RELATIVE_GAIN) are fitted per fold and
judged on the validation runs like every second-step candidate, and the best of them all
is accepted by the same rule against the chosen first effect alone. A pair from the
lookahead replaces the first choice; its first effect is then dropped when it does not pay
beside the second (SFFS's conditional exclusion, :func:`_drop`) and selection goes on.
Beside each other first effect, the effects that paid beside the chosen one are refined
jointly too, and a pair's per-fold fits start from the valley so found: a proxy's partner
is often its rival's, far from the rival's value alone (an amplifier offset beside a
dead-zone, and beside a Coulomb friction: 4.2 alone, 11.6 with an offset of 5.9).

Last look. When a later step adds nothing (no candidate is accepted beside two effects),
the lookahead runs once more beside the effects accepted after the first: blind
amp_offset + coulomb_friction + param:drive_c seed 0 took a dead-zone for the friction
and its offset, drive damping beside it, and no offset paid beside both; from breakaway
friction beside the drive damping the offset reaches the hidden triple. On the rig's
four logs the third step adds nothing, so it runs there; with the swap it costs 26 % more
simulations (33 076 against 26 315).

Swap. When forward selection would stop, an accepted effect after the first may be
replaced by one that pays more in its place (:func:`_swap`, SFFS's swap; at most
:data:`SWAPS`): a proxy accepted at a later step, before the effect it stands for could pay
(the actuator pole for a delay of 1 sample, which paid in its place only once breakaway
friction had replaced the Coulomb friction beside them).

Pair start. When no single effect pays and the nominal model's in-sample cost is far from
the noise (:data:`PAIR_START`), pairs are screened from nothing (:func:`_pairs_from_nothing`):
each of the effects that fit best alone with every other on a coarse grid of both, the best
pairs fitted jointly and judged like a step. Some effects act only together: an amplifier
offset above the sliding friction makes the open-loop hub run away unless a breakaway holds
it, so alone the offset, the friction and the breakaway all fit worse than nothing (blind
breakaway_sliding+amp_offset@d0 seeds 0 and 7 ended "none" at J 605 and 543, the hidden
triple's 1.06). The screen costs about 18 000 simulations on four runs, spent only then.

Joint screening. From the second step on, each candidate is scanned on its grid beside the
accepted effects and then refined together with them (:func:`~station.diagnosis.search.selection.screen_costs`
with ``refit``, a short Nelder-Mead: :data:`~station.diagnosis.search.fitting.SCREEN_REFINE`):
held at their values, the accepted effects can hide a partner (an amplifier offset beside a
Coulomb friction fitted alone: the pair's valley has the friction a third higher, and the
offset scanned beside the friction held lowered nothing; blind breakaway 14 over 9 with an
offset of 2.5 at alignment 0 was named Coulomb friction + drive stiffness).

Stuck refits. The accepted effects' joint values on all fit runs are fitted again from a
fold's values when those fit all runs better (:func:`_refit`: the folds' costs are cached),
and an accepted effect refitted to within :data:`NEUTRAL` of no effect is tested for
dropping at the end (:func:`_drop`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from station.diagnosis.search.farm import farm
from station.diagnosis.search.bounded import fit
from station.diagnosis.runs.cost import relative_gain
from station.diagnosis.runs.folds import validation_runs
from station.diagnosis.units import format_quantity
from station.diagnosis.search.fitting import NESTED, SHAPE, fit_beside, fit_set, set_axes
from station.diagnosis.search.selection import (MAX_EFFECTS, MIN_RELATIVE_GAIN, SECOND_STEP_CANDIDATES, Search,
                                                Selection, Singles, Step, Trial, screen_points, accept, credible,
                                                null_floor, screen_costs, trial)
from station.plant.effects import EFFECTS

LOOKAHEAD = 3
"""Single effects beside the chosen one tried as first effects at the second step (module
docstring): those that fit all fit runs best alone (in-sample: a member of a hidden pair may
not pay alone on held-out runs, e.g. viscous friction beside backlash); breakaway and plain
Coulomb friction count as one."""

DROPS = 2
"""Forward steps beyond :data:`MAX_EFFECTS` (and the upgrades in place) that replace a first
effect the lookahead brought and then dropped (:func:`_drop`)."""

LOOKAHEAD_GRID = 2
"""The lookahead scans every second grid point of the candidates beside another first
effect (half the simulations of the chosen one's screen: the pairs a wrong first choice
hides lower the in-sample cost by far more than the coarser grid misses, e.g. 14 against
98 for viscous friction + backlash; every fourth point, a factor 3 apart on a ratio's
axis, lost drive damping beside breakaway friction)."""

NEUTRAL = 0.01
"""An accepted effect whose joint value ends this close to its neutral one (a fraction of
the neutral value, or of the range when that is 0) is tested for dropping at the end: blind
static_friction + param:drive_c seed 3 ended with param:act_K = 1.000 beside them."""

SWAPS = 1
"""Swaps (:func:`_swap`) tried when forward selection would stop."""

LOOKAHEAD_TRIALS = 2
"""Pairs from the lookahead fitted per fold: those with the lowest screened cost, if below
the best pair beside the chosen first effect."""

PAIR_START = 20.0
"""The nominal model's in-sample cost J on the fit runs (1 at the noise floor) from which,
when no single effect pays, pairs are screened from nothing (:func:`_pairs_from_nothing`)."""


def _set_with(accepted: Sequence[str], name: str) -> tuple:
    """The set tried when ``name`` joins the accepted effects: added last, or in place of
    the simpler effect it holds (static_friction in place of coulomb_friction)."""
    simpler = NESTED.get(name)
    return tuple(a for a in accepted if a != simpler) + (name,)


def _family(name: str) -> set[str]:
    """An effect and those nested with it (static_friction and coulomb_friction)."""
    return {name} | {k for k, v in NESTED.items() if v == name} | ({NESTED[name]} if name in NESTED else set())


def _try_sets(search: Search, sets: Mapping, starts: Sequence) -> dict[str, Trial]:
    """Per key, its set of effects fitted per fold (:func:`trial`) from ``starts``."""
    keys = list(sets)
    fitted = farm(lambda names: trial(search.ev, search.folds, names, search.axes, starts), [sets[n] for n in keys],
                  search.ev, search.workers)
    return {keys[i]: tr for i, tr in fitted}


def _joint_trials(search: Search, names: Sequence[str], accepted: list[str], current: Trial,
                  fixed: Mapping[str, float], step: int) -> tuple[dict[str, Trial], float]:
    """The screened candidates (a joint screen: the accepted effects refined with each), each
    fitted per fold jointly with the accepted ones, and the lowest in-sample cost the screen
    reached (the accepted effects' own when none lowers it)."""
    ev = search.ev
    held = {NESTED[a] for a in accepted if a in NESTED}  # coulomb_friction is in an accepted static_friction
    full = len(accepted) >= MAX_EFFECTS  # then only an upgrade in place is left
    open_ = [n for n in names if n not in accepted and n not in held
             and (not full or NESTED.get(n) in accepted)]
    costs = screen_costs(ev, search.axes, open_, fixed, search.fit_runs, refit=current.names, workers=search.workers)
    # a candidate that lowers the in-sample cost by less than the parsimony margin with the
    # others held will not pay it on held-out runs (on the rig's four logs in-sample screen
    # gains of 8-31 % came out at 3-5 % held out)
    c0 = ev.cost(fixed, search.fit_runs)
    pool = [n for n in costs if costs[n] <= (1 - MIN_RELATIVE_GAIN) * c0][:SECOND_STEP_CANDIDATES]
    # an upgrade in place is always tried: the screen holds the sliding level where it is
    pool += [n for n in open_ if NESTED.get(n) in accepted and n not in pool]
    search.say(f"step {step + 1}: screening beside {' + '.join(accepted)} on all fit runs: {', '.join(pool)}")
    trials = _try_sets(search, {n: _set_with(accepted, n) for n in pool}, current.fold_values)
    for n in pool:
        search.say(f"step {step + 1}: {' + '.join(trials[n].names)}: validation cost gain "
                   f"{relative_gain(trials[n].val_weighted, current.val_weighted):.1f} % over {' + '.join(accepted)} "
                   f"({ev.simulations} simulations)")
    return trials, min(costs.values(), default=ev.cost(fixed, search.fit_runs))


def _luck(search: Search):
    """What luck alone reaches around a trial's model (:func:`null_floor` of its fold values)."""
    return lambda tr: null_floor(search.ev, search.folds, tr.fold_values)


def _held(names: Sequence[str]) -> set[str]:
    """The effect values a set holds (a static_friction's sliding level too)."""
    return set(names) | {NESTED[n] for n in names if n in NESTED}


def _lookahead(search: Search, names: Sequence[str], singles: Singles, pool: Sequence[str], accepted: list[str],
               current: Trial, values: Mapping[str, float], bar: float, terms: int,
               partners: Sequence[str] = ()) -> dict[str, dict[str, Trial]]:
    """Other first effects, beside the accepted ones after the first, with the next effect
    that pays most beside them (module docstring): first effect -> {next effect: the set's
    trial}, credible ones only. ``bar`` is the lowest in-sample cost screened beside the
    accepted effects; ``partners`` the effects that paid beside the chosen first effect in
    its joint screen, refined jointly beside each other first effect too (a proxy's partner
    is its rival's: an amplifier offset beside a dead-zone, and beside a Coulomb friction
    whose valley with the offset lies far from its value alone)."""
    ev, runs = search.ev, search.fit_runs
    chosen, kept = accepted[0], accepted[1:]
    keep = {k: v for k, v in values.items() if k in _held(kept)}
    taken = _family(chosen).union(*(_family(k) for k in kept))
    # the first step's credible candidates (a static_friction whose excess did not pay alone is not one)
    fitted = {n: ev.cost(singles.values[n], runs) for n in pool}  # cached: fitted on these runs
    firsts = []
    for n in sorted(fitted, key=fitted.get):
        if len(firsts) >= LOOKAHEAD:
            break
        if n not in taken and fitted[n] < ev.cost({}, runs):
            firsts.append(n)
            taken |= _family(n)
    sets, valleys = [], {}
    for f in firsts:
        others = [n for n in names if n not in _family(f) and n not in _held(kept)]
        start = {**singles.values[f], **keep}
        costs = screen_costs(ev, search.axes, others, start, runs, LOOKAHEAD_GRID)
        # like for like: the bar is the accepted effects refined beside their partners (the
        # joint screen), so the best partner here, and those that paid beside the chosen first
        # effect, are refined beside f too; held at its value alone, f hid its pair (viscous
        # friction 1.97 beside backlash: J 2.9 against act_K + backlash's 1.6, where the hidden
        # 2.15 + 2.57 reach 0.96; Coulomb friction 4.2 alone, beside which no amplifier offset
        # lowers J, where friction 11.6 with an offset of 5.9 reach 26 against a dead-zone
        # with its offset's 49)
        refine = [n for n in dict.fromkeys([*list(costs)[:1], *partners])
                  if n in others and n not in NESTED]
        for n in refine:
            cost, valley = fit_beside(ev, search.axes, (f, *kept), n, runs, start)
            if cost < costs.get(n, np.inf):
                costs[n], valleys[f, n] = cost, valley
        sets += [(cost, f, n) for n, cost in costs.items() if cost < (1 - MIN_RELATIVE_GAIN) * bar]
    sets = sorted(sets)[:LOOKAHEAD_TRIALS]
    step = len(accepted) + 1
    search.say(f"step {step}: lookahead over {', '.join(firsts) or 'no other first effect'} in place of {chosen}: "
               + (", ".join(" + ".join((f, *kept, n)) for _, f, n in sets) or f"nothing below {chosen}'s best")
               + f" ({ev.simulations} simulations)")
    out: dict[str, dict[str, Trial]] = {}
    for _, f, n in sets:
        # from the pair's valley when the joint refinement found it (the fold fits move locally)
        starts = ([dict(valleys[f, n])] * len(current.fold_values) if (f, n) in valleys else
                  [{**fv, **{k: v for k, v in cv.items() if k in _held(kept)}}
                   for fv, cv in zip(singles.trials[f].fold_values, current.fold_values)])
        tr = _try_sets(search, {n: (f, *kept, n)}, starts)[n]
        search.say(f"step {step}: {' + '.join(tr.names)}: validation cost gain "
                   f"{relative_gain(tr.val_weighted, current.val_weighted):.1f} % over {' + '.join(accepted)} "
                   f"({ev.simulations} simulations)")
        out.setdefault(f, {})[n] = tr
    return {f: ok for f, group in out.items() if (ok := credible(group, terms, _luck(search)))}


def _pairs_from_nothing(search: Search, names: Sequence[str], singles: Singles,
                        terms: int) -> dict[str, dict[str, Trial]]:
    """Pairs tried when no single effect pays and the nominal model is far from the noise
    (module docstring, pair start): the :data:`LOOKAHEAD` effects that fit all fit runs best
    alone, each scanned with every other on a coarse grid of both (every
    :data:`LOOKAHEAD_GRID`-th point of each: neither held at its value alone), the
    :data:`LOOKAHEAD_TRIALS` pairs whose lowest cost is below the best single's by the
    parsimony margin fitted jointly from that point on all fit runs and then per fold from
    the valley found: first effect -> {second effect: the pair's trial}, credible ones only."""
    ev, runs, axes = search.ev, search.fit_runs, search.axes
    fitted = {n: ev.cost(singles.values[n], runs) for n in names}
    bar = min(fitted.values(), default=ev.cost({}, runs))
    firsts, taken = [], set()
    for n in sorted(fitted, key=fitted.get):
        if len(firsts) < LOOKAHEAD and n not in taken:
            firsts.append(n)
            taken |= _family(n)
    pairs = [(f, n) for f in firsts for n in names if n not in _family(f)
             and not (n in firsts and firsts.index(n) < firsts.index(f))]

    def lowest(pair):
        f, n = pair
        points = [q for p in screen_points(f, axes, {})[::LOOKAHEAD_GRID]
                  for q in screen_points(n, axes, p)[::LOOKAHEAD_GRID]]
        costs = [ev.cost(q, runs) for q in points]
        k = int(np.argmin(costs))
        return costs[k], points[k]

    scanned = {pairs[i]: out for i, out in farm(lowest, pairs, ev, search.workers)}
    best = sorted((c, pair) for pair, (c, _) in scanned.items() if c < (1 - MIN_RELATIVE_GAIN) * bar)
    best = best[:LOOKAHEAD_TRIALS]
    search.say(f"step 1: no single effect pays, the nominal model's cost {ev.cost({}, runs):.3g} is far from the "
               f"noise: pairs from nothing over {', '.join(firsts)}: "
               + (", ".join(f"{f} + {n} ({c:.3g})" for c, (f, n) in best) or f"nothing below {bar:.3g}")
               + f" ({ev.simulations} simulations)")
    out: dict[str, dict[str, Trial]] = {}
    for _, (f, n) in best:
        valley = fit_set(ev, set_axes((f, n), axes), runs, scanned[f, n][1])
        tr = _try_sets(search, {n: (f, n)}, [dict(valley)] * len(search.folds))[n]
        search.say(f"step 2: {' + '.join(tr.names)}: validation cost gain "
                   f"{relative_gain(tr.val_weighted, singles.trials[f].val_weighted):.1f} % over {f} alone "
                   f"({ev.simulations} simulations)")
        out.setdefault(f, {})[n] = tr
    return {f: ok for f, group in out.items() if (ok := credible(group, terms, _luck(search)))}


def _pays(search: Search, trials: Mapping[str, Trial], current: Trial, terms: int) -> bool:
    """The best of ``trials`` is accepted beside ``current`` (:func:`accept`)."""
    if not trials:
        return False
    best = min(trials.values(), key=lambda tr: tr.val_weighted)
    return accept(current.val_weighted, best.val_weighted, terms, null_floor(search.ev, search.folds,
                                                                             current.fold_values))


def _swap(search: Search, names: Sequence[str], accepted: list[str], current: Trial, values: Mapping[str, float],
          terms: int) -> tuple[str, str, Trial] | None:
    """An accepted effect after the first replaced by another that pays more in its place
    (SFFS's swap), when forward selection would stop: each, latest first, left out, the
    candidates screened jointly beside the rest (:func:`screen_costs` with ``refit``), those
    below the accepted set's in-sample cost fitted per fold; the first whose validation cost
    :func:`accept` takes over the accepted set's, as (left out, in its place, its trial), else
    None. A proxy accepted in a later step stays otherwise: drive stiffness for a delay of 2-4
    samples, beside breakaway friction and an amplifier offset."""
    ev, runs = search.ev, search.fit_runs
    c0 = ev.cost(values, runs)
    for out in reversed(accepted[1:]):
        rest = [a for a in accepted if a != out]
        fixed = {k: v for k, v in values.items() if k in _held(rest)}
        open_ = [n for n in names if n not in _family(out) and n not in _held(rest)
                 and not (n in NESTED and NESTED[n] not in rest)]
        costs = screen_costs(ev, search.axes, open_, fixed, runs, refit=rest, workers=search.workers)
        pool = [n for n in costs if costs[n] < (1 - MIN_RELATIVE_GAIN) * c0][:LOOKAHEAD_TRIALS]
        if not pool:
            continue
        starts = [{k: v for k, v in fv.items() if k in _held(rest)} for fv in current.fold_values]
        trials = _try_sets(search, {n: _set_with(rest, n) for n in pool}, starts)
        n = min(trials, key=lambda k: trials[k].val_weighted)
        search.say(f"swap: {' + '.join(trials[n].names)} in place of {' + '.join(accepted)}: validation cost gain "
                   f"{relative_gain(trials[n].val_weighted, current.val_weighted):.1f} % ({ev.simulations} simulations)")
        if accept(current.val_weighted, trials[n].val_weighted, terms):
            return out, n, trials[n]
    return None


def _swapped(search: Search, names: Sequence[str], accepted: list[str], current: Trial,
             values: Mapping[str, float], steps: list[Step], terms: int) -> tuple[list[str], Trial, dict, list] | None:
    """The accepted effects, their trial, joint values and steps after a swap (:func:`_swap`),
    or None when none pays. The swap is a step of its own, the set it replaced its rival
    (for the alternatives); the step that found nothing before it is forgotten."""
    swapped = _swap(search, names, accepted, current, values, terms) if len(accepted) > 1 else None
    if swapped is None:
        return None
    out, n, tr = swapped
    rest = [a for a in accepted if a != out]
    floor = null_floor(search.ev, search.folds, current.fold_values)
    steps = [st for st in steps if st.chosen is not None] + [Step(rest, {n: tr, out: current}, n, floor, {}, current)]
    accepted = [n if a == out else a for a in accepted]
    values = refit_accepted(search, tr, _refit_start({k: v for k, v in values.items() if k in _held(accepted)}, tr))
    search.say(f"swapped {n} in for {out}: " + ", ".join(
        f"{k} = {format_quantity(v, EFFECTS[k].unit)}" for k, v in values.items()))
    return accepted, tr, values, steps


def _drop(search: Search, name: str, current: Trial, terms: int) -> Trial | None:
    """The accepted set without ``name`` when ``name`` no longer pays beside the others (it
    would not be :func:`accept`-ed added to them; SFFS's conditional exclusion), else None."""
    names = tuple(n for n in current.names if n != name)
    starts = [{k: v for k, v in fv.items() if k not in _held([name])} for fv in current.fold_values]
    without = _try_sets(search, {name: names}, starts)[name]
    if accept(without.val_weighted, current.val_weighted, terms):
        return None
    search.say(f"{name} dropped: it no longer pays beside {' + '.join(names)} (validation cost gain "
               f"{relative_gain(current.val_weighted, without.val_weighted):.1f} %)")
    return without


def _refit_start(values: Mapping[str, float], current: Trial) -> dict:
    """Where the joint refit on all fit runs starts: the accepted values, and for an effect
    new to them the median of its fold values (for a new static_friction its sliding level
    too: the breakaway excess lowers it)."""
    start = {k: v for k, v in values.items() if k in current.fold_values[0]}
    fresh = [k for k in current.fold_values[0] if k not in start]
    if "static_friction" in fresh:
        fresh.append("coulomb_friction")
    for k in fresh:
        start[k] = float(np.median([fv[k] for fv in current.fold_values]))
    return start


def refit_accepted(search: Search, current: Trial, start: Mapping[str, float], values: dict | None = None) -> dict:
    """The accepted effects fitted jointly on all fit runs from ``start`` (or ``values``
    already so fitted); when a fold's values fit all of them better (a stuck refit: blind
    static_friction + param:drive_c seed 3 refitted param:act_K to 1.000 and v_s to 8.7
    where its folds held 16-23), fitted again from those and the lower cost kept. The
    folds' costs are the cached ones.

    Parameters
    ----------
    search : Search
    current : Trial
        The accepted set as fitted per fold.
    start : mapping of str to float
        Where the joint fit starts.
    values : dict, optional
        Values already fitted jointly (then only the fold check runs).

    Returns
    -------
    dict of str to float
        The accepted effects' joint values, each in its effect's unit.
    """
    ev, runs, axes = search.ev, search.fit_runs, set_axes(current.names, search.axes)
    values = fit_set(ev, axes, runs, start) if values is None else values
    best_fold = min(current.fold_values, key=lambda fv: ev.cost(fv, runs))
    if ev.cost(best_fold, runs) < ev.cost(values, runs):
        again = fit_set(ev, axes, runs, best_fold)
        if ev.cost(again, runs) < ev.cost(values, runs):
            search.say("the joint refit from the accepted values was stuck: fitted again from a fold's values")
            values = again
    return values


def _downgrade(search: Search, accepted: list[str], current: Trial, terms: int) -> tuple[list[str], Trial]:
    """After an effect joined an accepted static_friction: the simpler effect in its place
    when the breakaway excess no longer pays beside the others (:func:`credible`)."""
    for name, simpler in NESTED.items():
        if name not in accepted:
            continue
        names = tuple(simpler if n == name else n for n in current.names)
        alt = trial(search.ev, search.folds, names, search.axes, current.fold_values)
        if credible({name: current, simpler: alt}, terms, _luck(search)).get(name) is None:
            search.say(f"{simpler} in place of {name}: the breakaway excess no longer pays beside "
                       f"{' + '.join(n for n in accepted if n != name)}")
            return [simpler if n == name else n for n in accepted], alt
    return accepted, current


def forward_select(search: Search, names: Sequence[str], singles: Singles, nominal: Trial) -> Selection:
    """Add the best effect while it pays (:func:`accept`), at most :data:`MAX_EFFECTS`,
    with a lookahead over the first effect at the second step (module docstring); after
    each, refit the accepted effects jointly on all fit runs. static_friction may replace
    an accepted coulomb_friction (one more step, no new place).

    Parameters
    ----------
    search : Search
    names : sequence of str
        The candidates.
    singles : Singles
        Step 1 (:func:`fit_each_alone`).
    nominal : Trial
        The nominal model's validation errors: where selection starts.

    Returns
    -------
    Selection
        The accepted effects in the order added (empty when none paid), their trial, their
        joint values on all fit runs and every step tried.
    """
    ev, folds = search.ev, search.folds
    terms = ev.terms(validation_runs(folds))
    accepted: list[str] = []
    current = nominal
    values: dict[str, float] = {}
    steps: list[Step] = []
    swaps = SWAPS
    for step in range(MAX_EFFECTS + len(NESTED) + DROPS + SWAPS):
        if step == 0:
            tried = {n: singles.trials[n] for n in names}
        else:
            tried, bar = _joint_trials(search, names, accepted, current, values, step)
        trials = credible(tried, terms, _luck(search))
        set_aside = {n: tr for n, tr in tried.items() if n not in trials}
        pairs = (_lookahead(search, names, singles, list(steps[0].trials), accepted, current, values, bar, terms,
                            [n for n in tried if n not in NESTED])
                 if step == 1 or (1 < step and len(accepted) < MAX_EFFECTS
                                  and not _pays(search, trials, current, terms)) else {})
        if step == 0 and ev.cost({}, search.fit_runs) >= PAIR_START and not _pays(search, trials, current, terms):
            pairs = _pairs_from_nothing(search, names, singles, terms)
        first_step = (trials, set_aside)  # step 1 as screened, before a pair from nothing replaces it
        if not trials and not pairs:
            if set_aside and step > 0:  # kept for the alternatives: a breakaway set aside in place of friction
                steps.append(Step(list(accepted), {}, None, null_floor(ev, folds, current.fold_values), set_aside,
                                  current))
            if not swaps or (swapped := _swapped(search, names, accepted, current, values, steps, terms)) is None:
                break
            swaps, (accepted, current, values, steps) = swaps - 1, swapped
            continue
        best = min(trials, key=lambda n: trials[n].val_weighted) if trials else None
        new_first = None
        for f, group in pairs.items():  # a set from the lookahead replaces the first choice
            n = min(group, key=lambda n: group[n].val_weighted)
            if best is None or group[n].val_weighted < trials[best].val_weighted:
                search.say(f"step {step + 1}: {' + '.join(group[n].names)} beats "
                           f"{' + '.join(trials[best].names) if best else ' + '.join(accepted)}")
                new_first, best, trials, set_aside = f, n, group, {}
        floor = null_floor(ev, folds, current.fold_values)
        search.say(f"step {step + 1}: best {best}, validation cost {trials[best].val_weighted / terms:.3g} per sample, "
                   f"current {current.val_weighted / terms:.3g}, reached by quantization and noise alone "
                   f"{floor / terms:.3g}")
        ok = accept(current.val_weighted, trials[best].val_weighted, terms, floor)
        if ok and new_first is not None and step == 0:  # a pair from nothing: its first effect is step 1's
            # the first effect's own trial stays in its step, credible alone or not (the doubt reads
            # it); the simpler effect it holds is left out: alone, neither paid, so a breakaway alone
            # against plain Coulomb friction alone says nothing of the pair's
            alone = {k: v for k, v in {**first_step[0], new_first: singles.trials[new_first]}.items()
                     if k != NESTED.get(new_first)}
            steps.append(Step([], alone, new_first, floor,
                              {k: v for k, v in first_step[1].items() if k not in _family(new_first)}, current))
            accepted, values, current = [new_first], {}, singles.trials[new_first]
            floor = null_floor(ev, folds, current.fold_values)
        elif ok and new_first is not None:
            old = accepted[0]
            values = {**singles.values[new_first], **{k: v for k, v in values.items() if k in _held(accepted[1:])}}
            accepted = [new_first, *accepted[1:]]
            steps[0].chosen = new_first
            for st in steps[1:]:
                st.before = [new_first if n == old else n for n in st.before]
        steps.append(Step(list(accepted), trials, best if ok else None, floor, set_aside, current))
        if not ok:
            if not swaps or (swapped := _swapped(search, names, accepted, current, values, steps, terms)) is None:
                break
            swaps, (accepted, current, values, steps) = swaps - 1, swapped
            continue
        simpler = NESTED.get(best)
        if simpler in accepted:  # an upgrade in place
            accepted[accepted.index(simpler)] = best
        else:
            accepted.append(best)
        current = trials[best]
        if step > 0 and best not in NESTED:
            accepted, current = _downgrade(search, accepted, current, terms)
        if step == 0 and new_first is not None:
            values = refit_accepted(search, current, dict(current.fold_values[0]))
        elif step == 0:
            values = refit_accepted(search, current, {}, dict(singles.values[best]))
        else:
            values = refit_accepted(search, current, _refit_start(values, current))
        search.say(f"accepted {best} (step {step + 1}): "
                   + ", ".join(f"{n} = {format_quantity(v, EFFECTS[n].unit)}" for n, v in values.items()))
        if new_first is not None and ok:  # the first effect the lookahead brought: does it pay beside the others?
            first = accepted[0]  # new_first, or breakaway/plain friction in its place after a downgrade
            accepted, current, values, steps = _drop_if_unpaid(search, first, _family(first), accepted, current,
                                                               values, steps, terms)
    for name in [n for n in accepted if len(accepted) > 1 and _near_neutral(n, values)]:
        accepted, current, values, steps = _drop_if_unpaid(search, name, {name}, accepted, current, values, steps,
                                                           terms)
    if "static_friction" in accepted:
        current, values = _fit_shape(search, current, values, terms)
    return Selection(accepted, current, values, steps)


def _drop_if_unpaid(search: Search, name: str, family: set[str], accepted: list[str], current: Trial,
                    values: dict, steps: list, terms: int) -> tuple[list[str], Trial, dict, list]:
    """``accepted``, ``current``, ``values`` and ``steps`` without ``name`` when it no longer
    pays beside the others (:func:`_drop`): the steps that chose one of ``family`` are
    forgotten, and the rest refitted jointly on all fit runs; else all as they were."""
    dropped = _drop(search, name, current, terms)
    if dropped is None:
        return accepted, current, values, steps
    accepted = [n for n in accepted if n != name]
    steps = [st for st in steps if st.chosen not in family]
    for st in steps:
        st.before = [n for n in st.before if n not in family]
    values = fit_set(search.ev, set_axes(dropped.names, search.axes), search.fit_runs,
                     {k: v for k, v in values.items() if k in _held(accepted)})
    return accepted, dropped, values, steps


def _near_neutral(name: str, values: Mapping[str, float]) -> bool:
    """An accepted effect refitted jointly to within :data:`NEUTRAL` of no effect at all
    (e.g. an actuator gain the lookahead brought that breakaway friction made 1.000 again):
    worth the test whether it still pays (:func:`_drop`)."""
    spec = EFFECTS[name]
    width = abs(spec.neutral) if spec.neutral else spec.upper - spec.lower
    return abs(values.get(name, spec.neutral) - spec.neutral) <= NEUTRAL * width


def _fit_shape(search: Search, current: Trial, values: dict, terms: int) -> tuple[Trial, dict]:
    """The Stribeck speed of an accepted static_friction, fitted alone with the accepted
    values fixed (per fold, then on all fit runs) and kept only when it pays on the
    validation runs (:func:`accept`); never a cause of its own."""
    ev, folds, axis = search.ev, search.folds, search.axes[SHAPE]
    fold_values, val_sse, total = [], {}, 0.0
    for fold, fixed in zip(folds, current.fold_values):
        fitted = fit(lambda vals: ev.cost(vals, fold.fit), [axis], fixed=fixed).values
        fold_values.append(fitted)
        for i in fold.val:
            val_sse[i] = ev.sse(fitted, i)
            total += ev.weighted(fitted, i)
    shaped = Trial(current.names, fold_values, val_sse, total)
    if not accept(current.val_weighted, shaped.val_weighted, terms):
        search.say(f"{SHAPE}: left at the model's (a fitted one gains {relative_gain(total, current.val_weighted):.1f} %)")
        return current, values
    values = fit(lambda vals: ev.cost(vals, search.fit_runs), [axis], fixed=values).values
    search.say(f"{SHAPE} = {format_quantity(values[SHAPE], EFFECTS[SHAPE].unit)} (validation cost gain "
               f"{relative_gain(total, current.val_weighted):.1f} %)")
    return shaped, values
