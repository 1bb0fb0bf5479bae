"""Doubt, stated: a 95 % interval for each accepted effect's value and the other
explanations the validation data cannot tell apart (DESIGN.md: each effect's ``interval``,
``alternatives``).

Both judge a cost difference by a likelihood-ratio test whose sample size is the
residuals' effective one. The errors of a model on a run are autocorrelated, so N samples
carry the information of N_eff = N/τ, τ = 1 + 2 Σ_k ρ_k the integrated autocorrelation
time (lags summed while ρ_k > 0); over θ and a of several runs τ is averaged weighted by
each residual's share of the cost (:func:`effective_terms`). With the noise scale unknown
(the misfit J_min scales it), two costs differ significantly when
N_eff · ln(J/J_min) > χ²₁(0.95) = 3.84.

- Interval: the widest of three. (1) The profile likelihood on the fit runs (what noise
  allows; :data:`INTERVAL_METHOD`). The effect's value is scanned outward from its fit in
  the search coordinate (log for ratios, square root for magnitudes; steps doubling from
  1/8 of a grid step, then bisection), the other accepted effects refitted locally at each
  point (warm-started from the previous point: the selection's fit is where the profile
  starts), until N_eff · ln(J/J_min) exceeds 3.84. (2) The range of the values refitted
  without each run (the selection's leave-one-run-out fits: what depends on which runs
  judge it). (3) The fit's resolution, ± 1/16 grid step. Blind (tests/blind, 78 accepted
  values of in-vocabulary cases), the profile alone was far narrower than the error the
  fitting model's coarser integration leaves and held 6 of the hidden values; with (2) and
  (3) 75 (96 %). The interval is clipped to the effect's range and flagged where it
  touches it.
- Alternatives: at each forward-selection step, a rival whose validation cost is within the
  tolerance of the chosen one's — the larger of what luck reaches around the chosen model
  (its :func:`station.diagnosis.search.selection.null_floor`) and the likelihood-ratio
  tolerance J·(exp(3.84/N_eff) − 1) of the held-out residuals, a cost lower than the chosen
  one's included — is another explanation: the accepted set with the chosen effect replaced
  by it, judged on the same folds (refitted per fold when the step was not the last), kept
  when still within the tolerance of the final explanation, and its values refitted jointly
  on all fit runs. The rivals of a step: every other candidate tried in its place; a
  breakaway that :func:`~station.diagnosis.search.selection.credible` set aside because its
  excess did not pay over the sliding level (it fits as well, or better by less than
  selection's margin: the data do not settle it); for a breakaway chosen in place of
  Coulomb friction, plain Coulomb friction again; and after the last accepted step, a
  breakaway tried over the accepted sliding level. A breakaway whose excess is below
  :data:`~station.diagnosis.search.fitting.MIN_EXCESS` is plain Coulomb friction, no rival.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple

import numpy as np
import scipy.optimize

from station.diagnosis.search.bounded import RESOLUTION_STEPS, Axis
from station.diagnosis.runs.cost import Evaluator, pooled, rms_gain
from station.diagnosis.search.fitting import MIN_EXCESS, NESTED, SHAPE, excess_of, refit_explanation
from station.diagnosis.runs.folds import validation_runs
from station.diagnosis.search.selection import (Search, Selection, Step, Trial, accept, excess_fraction,
                                                null_floor, trial)

CHI2_95 = 3.841458820694124
"""χ²₁ at 95 %: the likelihood-ratio threshold of one parameter."""

INTERVAL_METHOD = "profile likelihood"
"""How the intervals are found (the JSON's ``interval_method`` adds the effective sample size)."""

MAX_ALTERNATIVES = 3
"""At most this many alternatives are refitted and reported (the closest first)."""

BISECTIONS = 3
"""Bisections of the bracket where the profile crosses the threshold (1/8 of it left)."""


def integrated_time(e: np.ndarray) -> float:
    """τ = 1 + 2 Σ_k ρ_k of a residual, lags summed while ρ_k > 0 (at most N/4), ≥ 1.

    Parameters
    ----------
    e : ndarray, shape (N,)
        A residual (its mean is removed).

    Returns
    -------
    float
        The integrated autocorrelation time τ, samples (≥ 1; 1 for fewer than 4 samples or an
        all-zero residual).
    """
    e = np.asarray(e, float) - np.mean(e)
    n = e.size
    if n < 4 or not np.any(e):
        return 1.0
    f = np.fft.rfft(e, 2 * n)
    ac = np.fft.irfft(f * np.conj(f), 2 * n)[:n]
    rho = ac / ac[0]
    stop = n // 4
    neg = np.flatnonzero(rho[1:stop] <= 0)
    k = (neg[0] + 1) if neg.size else stop
    return float(max(1.0, 1.0 + 2.0 * np.sum(rho[1:k])))


def effective_terms(ev: Evaluator, predictions: Mapping[int, tuple], runs: Sequence[int]) -> float:
    """N_eff of the noise-weighted cost over runs: the 2N error terms divided by τ averaged
    over the θ and a residuals weighted by their share of the cost.

    Parameters
    ----------
    ev : Evaluator
    predictions : mapping of int to (ndarray, ndarray)
        Run index -> the model's θ and a on it.
    runs : sequence of int

    Returns
    -------
    float
        N_eff, the effective number of independent error terms (≥ 1; 1 when a residual is not
        finite).
    """
    shares, taus = [], []
    for i in runs:
        c = ev.cases[i]
        theta, a = predictions[i]
        for e, sigma in ((c.theta - np.asarray(theta, float), c.sigma_theta), (c.a - np.asarray(a, float), c.sigma_a)):
            if not np.all(np.isfinite(e)):
                return 1.0
            shares.append(float(np.sum(e ** 2)) / sigma ** 2)
            taus.append(integrated_time(e))
    total = sum(shares)
    tau = sum(s * t for s, t in zip(shares, taus)) / total if total > 0 else 1.0
    return max(1.0, ev.terms(runs) / tau)


class Interval(NamedTuple):
    """A 95 % interval of an effect's value, in its unit.

    Attributes
    ----------
    lo, hi : float
    lo_at_bound, hi_at_bound : bool
        The interval reaches the effect's search range there (clipped).
    refits : (float, float) or None
        The lowest and highest value refitted without each run (None: one fold).
    """

    lo: float
    hi: float
    lo_at_bound: bool
    hi_at_bound: bool
    refits: tuple | None = None


def _local_refit(cost: Callable[[dict], float], axes: Sequence[Axis], start: Mapping[str, float]) -> tuple[float, dict]:
    """Refine ``axes`` near ``start`` (one grid step): bounded Brent for one continuous
    axis, Nelder-Mead for several, ±1 for whole-number ones. Returns the best seen."""
    best = [cost(dict(start)), dict(start)]

    def track(vals):
        c = cost(vals)
        if c < best[0]:
            best[0], best[1] = c, dict(vals)
        return c

    cont = [a for a in axes if a.scale != "int"]
    if len(cont) == 1:
        a = cont[0]
        t0 = a.to_unit(start[a.name])
        lo, hi = max(t0 - a.step, a.to_unit(a.lower)), min(t0 + a.step, a.to_unit(a.upper))
        if hi > lo:
            scipy.optimize.minimize_scalar(lambda t: track({**best[1], a.name: a.from_unit(t)}), bounds=(lo, hi),
                                           method="bounded", options={"xatol": 0.05 * a.step, "maxiter": 8})
    elif cont:
        x0 = np.array([a.to_unit(start[a.name]) for a in cont])
        simplex = np.vstack([x0] + [x0 + 0.5 * a.step * np.eye(len(cont))[i] for i, a in enumerate(cont)])

        def f(x):
            return track({**best[1], **{a.name: a.from_unit(t) for a, t in zip(cont, x)}})

        scipy.optimize.minimize(f, x0, method="Nelder-Mead",
                                options={"initial_simplex": simplex, "maxfev": 8 * len(cont) + 4, "fatol": 1e-9})
    for a in axes:
        if a.scale == "int":
            point = dict(best[1])
            for d in (-1.0, 1.0):
                if a.lower <= point[a.name] + d <= a.upper:
                    track({**point, a.name: point[a.name] + d})
    return best[0], best[1]


def _sliding_below(values: Mapping[str, float]) -> dict:
    """Values with each breakaway level's sliding level no higher than it (v_c <= v_s, what a
    model holds): a profile of v_s refits v_c, and of another effect refits both."""
    out = dict(values)
    for n, sliding in NESTED.items():
        if n in out and sliding in out and out[sliding] > out[n]:
            out[sliding] = out[n]
    return out


def profile_interval(ev: Evaluator, axes: Mapping[str, Axis], name: str, values: Mapping[str, float],
                     runs: Sequence[int], n_eff: float) -> Interval | None:
    """The 95 % profile-likelihood interval of one accepted effect (module docstring).

    Parameters
    ----------
    ev : Evaluator
    axes : mapping of str to Axis
    name : str
        The effect.
    values : mapping of str to float
        All accepted effects as fitted on ``runs`` (where the profile starts).
    runs : sequence of int
        The fit runs.
    n_eff : float
        Effective number of error terms (:func:`effective_terms`).

    Returns
    -------
    Interval or None
        None when the fit's cost is not finite.
    """
    ax = axes[name]
    others = [axes[n] for n in values if n not in (name, SHAPE)]  # the shape is held, as the search holds it
    j_min = [ev.cost(values, runs)]
    if not math.isfinite(j_min[0]) or j_min[0] <= 0:
        return None

    def profile(x: float, warm: Mapping[str, float]) -> tuple[float, dict]:
        if not others:
            j, w = ev.cost({**warm, name: x}, runs), dict(warm)
        else:
            j, w = _local_refit(lambda vals: ev.cost(_sliding_below({**vals, name: x}), runs), others,
                                {k: v for k, v in warm.items() if k != name})
            w = _sliding_below({**w, name: x})
        j_min[0] = min(j_min[0], j)
        return j, {**w, name: x}

    def inside(j: float) -> bool:
        return n_eff * math.log(j / j_min[0]) <= CHI2_95 if math.isfinite(j) else False

    ends = []
    for direction in (-1.0, 1.0):
        bound = ax.lower if direction < 0 else ax.upper
        if ax.scale == "int":
            last, x = values[name], values[name]
            warm = dict(values)
            while x != bound:
                x = x + direction
                j, w = profile(x, warm)
                if not inside(j):
                    break
                last, warm = x, w
            ends.append((last, last == bound))
            continue
        t0, tb = ax.to_unit(values[name]), ax.to_unit(bound)
        good, bad, warm, h = t0, None, dict(values), ax.step / 8
        while good != tb:
            t = min(t0 + h, tb) if direction > 0 else max(t0 - h, tb)
            j, w = profile(ax.from_unit(t), warm)
            if not inside(j):
                bad = t
                break
            good, warm, h = t, w, 2 * h
        if bad is not None:
            for _ in range(BISECTIONS):
                mid = 0.5 * (good + bad)
                j, w = profile(ax.from_unit(mid), warm)
                if inside(j):
                    good, warm = mid, w
                else:
                    bad = mid
        ends.append((ax.from_unit(good), good == tb))
    (lo, lo_b), (hi, hi_b) = ends
    return Interval(float(lo), float(hi), bool(lo_b), bool(hi_b))


def effect_interval(ev: Evaluator, axes: Mapping[str, Axis], name: str, values: Mapping[str, float],
                    runs: Sequence[int], n_eff: float, fold_values: Sequence[float]) -> Interval | None:
    """An accepted effect's 95 % interval: the hull of the profile likelihood
    (:func:`profile_interval`: what noise allows), the values refitted without each run
    (what depends on which runs judge it) and the fit's resolution (± :data:`RESOLUTION_STEPS`
    grid steps), clipped to the effect's range.

    Parameters
    ----------
    ev : Evaluator
    axes : mapping of str to Axis
    name : str
        The effect.
    values : mapping of str to float
        All accepted effects as fitted on ``runs``.
    runs : sequence of int
        The fit runs.
    n_eff : float
        Effective number of error terms of the fit runs (:func:`effective_terms`).
    fold_values : sequence of float
        The effect's value fitted per fold (leave-one-run-out refits; one for --validate).

    Returns
    -------
    Interval or None
        The interval in the effect's unit, flagged where it reaches the search range, with the
        refits' (low, high) when there was more than one fold; None when the fit's cost is not
        finite (:func:`profile_interval`).
    """
    prof = profile_interval(ev, axes, name, values, runs, n_eff)
    if prof is None:
        return None
    ax = axes[name]
    value = values[name]
    refits = (float(min(fold_values)), float(max(fold_values))) if len(fold_values) > 1 else None
    lo, hi = prof.lo, prof.hi
    if refits is not None:
        lo, hi = min(lo, refits[0]), max(hi, refits[1])
    if ax.scale != "int":
        c, half = ax.to_unit(value), RESOLUTION_STEPS * ax.step
        lo, hi = min(lo, ax.from_unit(c - half)), max(hi, ax.from_unit(c + half))
    at = lambda x, b: math.isclose(x, b, rel_tol=1e-9, abs_tol=1e-12)  # noqa: E731
    return Interval(float(lo), float(hi), prof.lo_at_bound or at(lo, ax.lower), prof.hi_at_bound or at(hi, ax.upper),
                    refits)


def interval_method(n_eff: float, terms: int, folds: int) -> str:
    """The JSON's ``interval_method``: what the intervals combine, with the effective
    sample size.

    Parameters
    ----------
    n_eff : float
        Effective number of error terms of the fit runs.
    terms : int
        Their error terms (2N per run).
    folds : int
        Leave-one-run-out refits (1: --validate, none).

    Returns
    -------
    str
        One sentence without a final period, naming the χ² threshold and N_eff of ``terms``.
    """
    refits = f", the range of the {folds} values refitted without each run" if folds > 1 else ""
    return (f"{INTERVAL_METHOD} on the fit runs (N_eff·ln(J/J_min) ≤ {CHI2_95:.2f}, N_eff = {n_eff:.0f} of "
            f"{terms} error terms after the residuals' autocorrelation){refits} and the fit's resolution "
            f"(±{RESOLUTION_STEPS:g} grid step), whichever is widest")


class Alternative(NamedTuple):
    """Another explanation the validation data cannot tell apart from the chosen one.

    Attributes
    ----------
    causes : list of str
        The accepted effects with one replaced.
    values : dict of str to float
        Refitted jointly on all fit runs.
    gain_pct : float
        Its θ RMS gain on the validation data (pooled), %.
    cost_ratio : float
        Its validation cost / the chosen explanation's.
    instead_of : str
        The accepted effect it replaces.
    """

    causes: list
    values: dict
    gain_pct: float
    cost_ratio: float
    instead_of: str

    def to_json(self) -> dict:
        """The alternative as DESIGN.md's ``alternatives`` entry.

        Returns
        -------
        dict
            ``causes`` (list of str), ``values`` (effect to value, its unit), ``gain_pct`` (%, 3
            decimals), ``cost_ratio`` (4 decimals) and ``instead_of``.
        """
        return {"causes": list(self.causes), "values": dict(self.values), "gain_pct": round(self.gain_pct, 3),
                "cost_ratio": round(self.cost_ratio, 4), "instead_of": self.instead_of}


def tolerance(cost: float, floor: float, n_eff: float) -> float:
    """How much higher a validation cost (Σ weighted errors) may be and still not be told
    apart: the larger of the luck ``cost − floor`` and cost·(exp(3.84/N_eff) − 1).

    Parameters
    ----------
    cost : float
        The chosen explanation's validation cost.
    floor : float
        What luck alone reaches around it (:func:`station.diagnosis.search.selection.null_floor`).
    n_eff : float
        Effective number of error terms of the validation runs.

    Returns
    -------
    float
        The tolerance, in the cost's units (Σ of noise-weighted squared errors), ≥ 0 when
        ``cost`` ≥ ``floor``.
    """
    return max(cost - floor, cost * math.expm1(CHI2_95 / n_eff))


def _held(names) -> set[str]:
    """The effect values a set of causes holds (a static_friction's sliding level too)."""
    return set(names) | {NESTED[n] for n in names if n in NESTED}


def _distinct(c: str, tr: Trial) -> bool:
    """A rival is another explanation: a breakaway with an excess below MIN_EXCESS (the median
    over its folds) is plain Coulomb friction again."""
    return c not in NESTED or excess_fraction(tr) >= MIN_EXCESS


def _step_rivals(step: Step, accepted: Sequence[str]) -> list[tuple[str, Trial]]:
    """The rivals of an accepted step's choice, each with its trial at that step: every other
    candidate tried in its place, those :func:`~station.diagnosis.search.selection.credible`
    set aside (a breakaway whose excess did not pay), and for an upgrade in place the simpler
    effect it replaced (the model before the step)."""
    out = [(c, tr) for c, tr in {**step.set_aside, **step.trials}.items()
           if c != step.chosen and c not in accepted and _distinct(c, tr)]
    simpler = NESTED.get(step.chosen)
    if simpler is not None and simpler in step.before and step.current is not None:
        out.append((simpler, step.current))
    return out


def _upgrades(step: Step, final: Trial) -> list[tuple[str, Trial]]:
    """After the step that accepted nothing: the upgrades in place it tried (a breakaway over an
    accepted sliding level), each a whole explanation beside the final one."""
    return [(c, tr) for c, tr in {**step.set_aside, **step.trials}.items()
            if NESTED.get(c) in final.names and _distinct(c, tr)
            and set(tr.names) == set(final.names) - {NESTED[c]} | {c}]


def _rival_starts(final: Trial, rival: Trial, chosen: str, c: str) -> list[dict]:
    """Per fold, where a rival's refit starts: the final values without what ``chosen`` holds,
    with what ``c`` holds from the rival's own trial."""
    return [{**{k: v for k, v in fv.items() if k not in _held([chosen])},
             **{k: v for k, v in rv.items() if k in _held([c])}}
            for fv, rv in zip(final.fold_values, rival.fold_values)]


def _paid_by_luck(steps: Sequence[Step], accepted: Sequence[str], terms: int) -> set[tuple[str, str]]:
    """(simpler, chosen) for each accepted breakaway that pays over the plain Coulomb friction
    of its step only when both are judged by their luck
    (:func:`~station.diagnosis.search.selection.credible`), not by their own validation costs:
    the simpler explanation fits within noise, so it stays an alternative whatever the
    tolerance says (blind: Coulomb friction 28.4 named a breakaway of 57.4 over it, with no
    alternative)."""
    out = set()
    for step in steps:
        simpler = NESTED.get(step.chosen)
        if step.chosen in accepted and simpler in step.trials and simpler not in accepted \
                and not accept(step.trials[simpler].val_weighted, step.trials[step.chosen].val_weighted, terms):
            out.add((simpler, step.chosen))
    return out


def alternatives(search: Search, sel: Selection, nominal: Trial, n_eff: float) -> list[Alternative]:
    """The other explanations the validation data cannot tell apart (module docstring).

    Parameters
    ----------
    search : Search
    sel : Selection
        What forward selection accepted, with its steps.
    nominal : Trial
        The nominal model's validation errors (the gains' reference).
    n_eff : float
        Effective number of error terms of the validation runs (held-out residuals of the
        chosen explanation).

    Returns
    -------
    list of Alternative
        Closest first, at most :data:`MAX_ALTERNATIVES`; [] when the data single out one.
    """
    ev, folds, axes = search.ev, search.folds, search.axes
    if not sel.accepted:
        return []
    steps = [s for s in sel.steps if s.chosen is not None]
    floors = [sel.steps[k + 1].floor if k + 1 < len(sel.steps) else None for k in range(len(steps))]
    final = sel.current
    rms_nom = pooled(ev, nominal.val_sse).rms_theta
    close: list[tuple[float, str, str, list, Trial, bool]] = []  # (step cost, rival, instead of, causes, trial, whole)
    luck_only = _paid_by_luck(steps, sel.accepted, ev.terms(validation_runs(folds)))
    tol_final = None
    for k, step in enumerate(steps):
        chosen = step.trials[step.chosen]
        floor = floors[k] if floors[k] is not None else null_floor(ev, folds, chosen.fold_values)
        tol = tolerance(chosen.val_weighted, floor, n_eff)
        last = k == len(steps) - 1
        if last:
            tol_final = tol
        if step.chosen not in sel.accepted:  # downgraded since (a breakaway to plain Coulomb friction)
            continue
        for c, tr in _step_rivals(step, sel.accepted):
            if tr.val_weighted - chosen.val_weighted <= tol or (c, step.chosen) in luck_only:
                names = [c if n == step.chosen else n for n in sel.accepted]
                close.append((tr.val_weighted, c, step.chosen, names, tr, last))
    after = sel.steps[-1] if sel.steps and sel.steps[-1].chosen is None else None
    if after is not None and tol_final is not None:
        for c, tr in _upgrades(after, final):
            if tr.val_weighted - final.val_weighted <= tol_final:
                close.append((tr.val_weighted, c, NESTED[c], [c if n == NESTED[c] else n for n in sel.accepted], tr,
                              True))
    if tol_final is None:
        return []
    result, seen = [], set()
    close = [x for x in sorted(close, key=lambda x: x[0])
             if frozenset(x[3]) not in seen and not seen.add(frozenset(x[3]))]  # one per explanation, its closest
    for _, c, instead, names, tr, whole in close[:MAX_ALTERNATIVES]:
        if not whole:  # judged beside the effects accepted after its step: refitted per fold
            tr = trial(ev, folds, tuple(names), axes, _rival_starts(final, tr, instead, c))
        search.say(f"alternative to {instead}: {' + '.join(names)}, validation cost "
                   f"{tr.val_weighted / final.val_weighted:.3f}× the chosen one's")
        if tr.val_weighted - final.val_weighted > tol_final and (c, instead) not in luck_only:
            continue
        others = [n for n in names if n != c]
        if c in _held(others):  # coulomb_friction beside a static_friction that holds it
            continue
        shape = {SHAPE} if any(n in NESTED for n in others) else set()  # an accepted breakaway's, held
        start = {n: v for n, v in sel.values.items() if n in _held(others) | shape}
        start.update({n: float(np.median([fv[n] for fv in tr.fold_values])) for n in _held([c])
                      if all(n in fv for fv in tr.fold_values)})
        values = refit_explanation(ev, others + [c], search.fit_runs, start, axes)
        if c in NESTED and excess_of(values) < MIN_EXCESS:  # refitted to plain Coulomb friction: no other explanation
            continue
        gain = rms_gain(pooled(ev, tr.val_sse).rms_theta, rms_nom)
        kept = [n for n in names + sorted(_held(names) - set(names)) if n in values]  # v_c of a v_s
        result.append(Alternative(names, {n: float(values[n]) for n in kept}, float(gain),
                                  float(tr.val_weighted / final.val_weighted), instead))
    return sorted(result, key=lambda a: a.cost_ratio)
