"""One model structure fitted on the runs of several sessions, and which of its effects drift
between them (DESIGN.md "Sessions and drift").

Every effect of a structure is either *shared* (one value for all sessions) or *drifting*
(one value per session: the key ``NAME@k`` for session k,
:func:`station.diagnosis.sessions.layout.key`). The
:class:`~station.diagnosis.runs.cost.Evaluator` simulates each run with its own session's values
(:class:`~station.diagnosis.sessions.layout.PerSession`), and caches per run: a session's value
never costs another session's runs a simulation.

1. **Structure** (:func:`select_structure`): the diagnosis's forward selection
   (:mod:`station.diagnosis.search.selection`: at most :data:`~station.diagnosis.search.selection.MAX_EFFECTS`
   effects, each accepted only when it lowers the held-out cost beyond
   :func:`~station.diagnosis.search.selection.accept`'s parsimony and what luck reaches) on all
   sessions' runs pooled, every candidate with a value per session. With every effect per
   session the fits are the sessions' own (:func:`fit_structure`), and the choice of
   effects is judged on all sessions' held-out runs together.
2. **Drift** (:func:`decide_drift`): for each accepted effect, the same structure with that
   effect's value shared by all sessions (the others still per session) is fitted and
   judged on the same folds; the effect drifts when its per-session values lower the
   held-out cost beyond the same acceptance rule, measured from the shared model (and what
   tiny perturbations of it reach by luck), *and* the sessions' values stand apart: the
   ranges of their leave-one-run-out refits are disjoint for at least two sessions
   (:func:`session_refits`; near the noise floor, stick-slip makes the held-out cost jump by
   tens of percent for value changes far below any drift). The others are shared; the
   final structure (shared + drifting) is judged once more and refitted on all runs.

Folds: leave-one-run-out over all runs (:func:`station.diagnosis.runs.folds.make_folds`). A
session with no run left in a fold (a session of one run) gets, in that fold, the mean of
the other sessions' values (in the search coordinate).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from station.diagnosis.search.bounded import fit
from station.diagnosis.runs.cost import pooled, relative_gain, rms_gain
from station.diagnosis.runs.folds import Fold, validation_runs
from station.diagnosis.units import format_quantity
from station.diagnosis.search.selection import (
    MAX_EFFECTS,
    SECOND_STEP_CANDIDATES,
    Search,
    Trial,
    accept,
    null_floor,
)
from station.diagnosis.sessions.layout import Layout, PerSession, as_held, key
from station.plant.effects import EFFECTS


@dataclass
class Decision:
    """Whether one accepted effect drifts between sessions, with its numbers.

    Attributes
    ----------
    name : str
    drifts : bool
        Its per-session values pay on held-out runs (module docstring, step 2).
    cost_gain_pct : float
        How much per-session values lower the held-out θ + a cost against one shared
        value, % (negative: they raise it).
    theta_gain_pct : float
        The same for the pooled held-out θ RMS, %.
    ranges : list of (float, float)
        Per session, the range of its leave-one-run-out refits with every effect per session.
    apart : bool
        Two sessions' ranges are disjoint.
    luck_gain_pct : float
        How much lower than the shared model's held-out cost tiny perturbations of it reach
        by luck (:func:`luck_floor`), % (0 when they reach nothing lower).
    shared_value : float
        Its value when shared by all sessions (fitted on all runs with the others per session).
    """

    name: str
    drifts: bool
    cost_gain_pct: float
    theta_gain_pct: float
    luck_gain_pct: float
    shared_value: float
    ranges: list
    apart: bool

    def pay(self, shared: str | None = None) -> str:
        """What per-session values pay, in words.

        Parameters
        ----------
        shared : str or None
            The shared value in words; None where the sentence has said it already.

        Returns
        -------
        str
            "per-session values lower the held-out θ + a cost by 43.0 % (θ RMS 25.5 %) against
            one shared value (6.79 DAC counts)", or "... raise ... by ...".
        """
        against = "one shared value" + ("" if shared is None else f" ({shared})")
        if self.cost_gain_pct >= 0:
            return (f"per-session values lower the held-out θ + a cost by {self.cost_gain_pct:.1f} % (θ RMS "
                    f"{self.theta_gain_pct:.1f} %) against {against}")
        return f"per-session values raise the held-out θ + a cost by {-self.cost_gain_pct:.1f} % against {against}"


@dataclass
class DriftResult:
    """The structure, the drift decisions and the final values.

    Attributes
    ----------
    accepted : list of str
        The structure's effects, in the order forward selection added them.
    shared, drifting : list of str
        Its effects with one value, and with a value per session.
    decisions : list of Decision
        One per accepted effect ([] with one session).
    values : dict of str to float
        Shared names and per-session keys (:func:`station.diagnosis.sessions.layout.key`), fitted on all runs.
    nominal, final : Trial
        The nominal model's and the final structure's held-out errors.
    separate : dict of str to float
        Every accepted effect per session (per-session keys), fitted on all runs: the
        structure before the drift decisions.
    refit_values : dict of str to list of list of float
        Per accepted effect, per session, its leave-one-run-out refits with every effect
        per session (:func:`session_refits`).
    """

    accepted: list
    shared: list
    drifting: list
    decisions: list
    values: dict
    nominal: Trial
    final: Trial
    separate: dict
    refit_values: dict

    def session_effects(self, s: int) -> dict[str, float]:
        """Session s's effects: the shared values and its own drifting ones.

        Parameters
        ----------
        s : int
            The session's index.

        Returns
        -------
        dict of str to float
            Plain effect names (no session keys) to values, each in its unit.
        """
        return PerSession([s])(self.values, 0)

    def refits(self, name: str, s: int) -> list[float]:
        """An accepted effect's value in session s with every effect per session, refitted
        leaving each run out (:func:`session_refits`).

        Parameters
        ----------
        name : str
            An accepted effect.
        s : int
            The session's index.

        Returns
        -------
        list of float
            One value per fold whose fit runs hold runs of session s, in the effect's unit.

        Raises
        ------
        KeyError
            ``name`` is not an accepted effect.
        """
        return list(self.refit_values[name][s])


def session_axes(search: Search, names: Sequence[str], sessions: int) -> None:
    """Add to ``search.axes`` every per-session key of ``names`` (each searched as its effect).

    Parameters
    ----------
    search : Search
    names : sequence of str
        Effects of the vocabulary.
    sessions : int
        How many sessions.
    """
    for n in names:
        for s in range(sessions):
            search.axes[key(n, s)] = dataclasses.replace(search.axes[n], name=key(n, s))


def _mean_value(search: Search, name: str, values: Sequence[float]) -> float:
    """The mean of an effect's values in its search coordinate (a ratio's geometric mean)."""
    axis = search.axes[name]
    return axis.from_unit(sum(axis.to_unit(v) for v in values) / len(values))


def fit_structure(search: Search, layout: Layout, shared: Sequence[str], drifting: Sequence[str],
                  runs: Sequence[int], start: Mapping[str, float]) -> dict[str, float]:
    """Values of a structure fitted on runs (:func:`station.diagnosis.search.bounded.fit`: the last
    name of each fit bracketed on its grid, then refined).

    The shared effects are fitted on all runs with the per-session values fixed at their
    start; then each session's values on its own runs with the shared ones fixed. Without
    shared effects that is each session's own joint fit. A session without a run among
    ``runs`` gets the mean of the other sessions' values.

    Parameters
    ----------
    search : Search
        Its axes hold the per-session keys (:func:`session_axes`).
    layout : Layout
    shared, drifting : sequence of str
        The effects with one value, and with a value per session.
    runs : sequence of int
        The runs fitted on.
    start : mapping of str to float
        Starting values of every key but the last shared name (the last drifting one's
        per-session keys, when nothing is shared).

    Returns
    -------
    dict of str to float
        Shared names and per-session keys.
    """
    ev, axes = search.ev, search.axes
    members = [[i for i in runs if i in g] for g in layout.groups]
    present = [s for s in range(layout.sessions) if members[s]]
    values = dict(start)
    if shared:
        fixed = {key(n, s): values[key(n, s)] for n in drifting for s in present}
        res = fit(lambda v: ev.cost(v, runs), [axes[n] for n in shared], start=values, fixed=fixed)
        values.update({n: res.values[n] for n in shared})
    for s in present if drifting else ():
        names = [key(n, s) for n in drifting]
        res = fit(lambda v, rs=members[s]: ev.cost(v, rs), [axes[k] for k in names], start=values,
                  fixed={n: values[n] for n in shared})
        values.update({k: res.values[k] for k in names})
    out = {k: values[k] for k in [key(n, s) for n in drifting for s in present] + list(shared)}
    for s in range(layout.sessions):
        if not members[s]:
            for n in drifting:
                out[key(n, s)] = _mean_value(search, n, [out[key(n, p)] for p in present])
    return out


def structure_trial(search: Search, layout: Layout, shared: Sequence[str], drifting: Sequence[str],
                    starts: Sequence[Mapping[str, float]]) -> Trial:
    """A structure fitted on each fold's fit runs and judged on its validation runs.

    Parameters
    ----------
    search : Search
    layout : Layout
    shared, drifting : sequence of str
    starts : sequence of mapping
        Per fold, starting values (:func:`fit_structure`).

    Returns
    -------
    Trial
        ``shared + drifting`` as its names, the values fitted per fold (shared names and
        per-session keys), each validation run's squared errors (counts²) and their
        noise-weighted sum.
    """
    ev = search.ev
    fold_values, val_sse, total = [], {}, 0.0
    for fold, start in zip(search.folds, starts):
        values = fit_structure(search, layout, shared, drifting, fold.fit, start)
        fold_values.append(values)
        for i in fold.val:
            val_sse[i] = ev.sse(values, i)
            total += ev.weighted(values, i)
    return Trial(tuple(shared) + tuple(drifting), fold_values, val_sse, total)


def session_refits(search: Search, layout: Layout, trial: Trial, name: str) -> list[list[float]]:
    """Per session, an effect's values fitted per session in the folds whose fit runs hold
    runs of that session (leaving one run out; a session of one run: its one fit).

    Parameters
    ----------
    search : Search
    layout : Layout
    trial : Trial
        Fitted with ``name`` per session.
    name : str
        The effect.

    Returns
    -------
    list of list of float
        Per session in layout order, the effect's values (its unit), one per fold whose fit
        runs hold runs of that session.
    """
    return [[fv[key(name, s)] for fold, fv in zip(search.folds, trial.fold_values) if set(fold.fit) & set(g)]
            for s, g in enumerate(layout.groups)]


def luck_floor(search: Search, trial: Trial) -> float:
    """What quantization and noise alone reach around a trial's held-out predictions
    (:func:`station.diagnosis.search.selection.null_floor` on each run's own effects).

    Parameters
    ----------
    search : Search
    trial : Trial

    Returns
    -------
    float
        Σ over the held-out runs of the lowest noise-weighted error, dimensionless (the units
        of :attr:`Trial.val_weighted`).
    """
    ev = search.ev
    folds, values = [], []
    for fold, v in zip(search.folds, trial.fold_values):
        for i in fold.val:
            folds.append(Fold(fold.fit, (i,)))
            values.append(dict(ev.effects_for(v, i)))
    return null_floor(ev, folds, values)


def _screen(search: Search, layout: Layout, names: Sequence[str], fixed: Mapping[str, float]) -> list[str]:
    """The effects worth a joint trial beside the accepted ones: each scanned on its grid
    (one value for all sessions per grid point, the best point taken per session) with the
    accepted effects fixed; the best :data:`SECOND_STEP_CANDIDATES` that lower the cost."""
    ev, runs = search.ev, search.fit_runs
    c0 = sum(ev.weighted(fixed, i) for i in runs)
    best = {}
    for n in names:
        per_point = [[sum(ev.weighted({**fixed, n: float(g)}, i) for i in grp) for grp in layout.groups]
                     for g in search.axes[n].grid()]
        best[n] = sum(min(p[s] for p in per_point) for s in range(layout.sessions))
    keep = sorted((n for n in names if best[n] < c0), key=best.get)
    return keep[:SECOND_STEP_CANDIDATES]


def _fixed(search: Search) -> Sequence[Mapping[str, float]]:
    """Per session, the sensor faults its runs are simulated under (:class:`PerSession`'s)."""
    return getattr(search.ev.run_effects, "fixed", ())


def _values_text(values: Mapping[str, float], names: Sequence[str], session_names: Sequence[str],
                 fixed: Sequence[Mapping[str, float]] = ()) -> str:
    """The values as the sessions' models hold them: a size searched beside a sensor that reads
    the other way (``fixed``: per session its decided faults) with that session's sign."""
    def faults(s):
        return fixed[s] if s < len(fixed) else {}

    def shared(n, v):  # the sign every session gives it, or the size where they differ
        held = {as_held(n, v, faults(s)) for s in range(len(session_names))}
        return held.pop() if len(held) == 1 else v

    parts = []
    for n in names:
        unit = EFFECTS[n].unit
        if n in values:
            parts.append(f"{n} = {format_quantity(shared(n, values[n]), unit)}")
        else:
            parts.append(f"{n} = " + ", ".join(f"{format_quantity(as_held(n, values[key(n, s)], faults(s)), unit)} ({name})"
                                               for s, name in enumerate(session_names) if key(n, s) in values))
    return "; ".join(parts)


@dataclass
class Structure:
    """What :func:`select_structure` found.

    Attributes
    ----------
    accepted : list of str
        In the order they were added.
    current : Trial
        The accepted effects, each per session, as fitted per fold (the nominal trial when none).
    values : dict of str to float
        Their per-session values fitted on all runs.
    """

    accepted: list
    current: Trial
    values: dict


def select_structure(search: Search, layout: Layout, names: Sequence[str], nominal: Trial,
                     session_names: Sequence[str]) -> Structure:
    """Forward selection with every candidate per session (module docstring, step 1).

    Parameters
    ----------
    search : Search
    layout : Layout
    names : sequence of str
        The candidates.
    nominal : Trial
        The nominal model's held-out errors: where selection starts.
    session_names : sequence of str
        For the progress lines.

    Returns
    -------
    Structure
        The accepted effects in order (empty when none pays), their per-session trial and
        their per-session values on all runs.
    """
    ev, folds, all_runs = search.ev, search.folds, search.fit_runs
    terms = ev.terms(validation_runs(folds))
    accepted: list[str] = []
    current, values = nominal, {}
    rms_nom = pooled(ev, nominal.val_sse).rms_theta
    for step in range(MAX_EFFECTS):
        pool = list(names) if step == 0 else _screen(search, layout, [n for n in names if n not in accepted], values)
        if step:
            search.say(f"step {step + 1}: screening beside {' + '.join(accepted)}: {', '.join(pool) or 'nothing'}")
        trials = {}
        for k, n in enumerate(pool, 1):
            trials[n] = structure_trial(search, layout, (), accepted + [n], current.fold_values)
            search.say(f"step {step + 1} [{k}/{len(pool)}] {' + '.join(accepted + [n])} per session: held-out "
                       f"θ gain {rms_gain(pooled(ev, trials[n].val_sse).rms_theta, rms_nom):.1f} %, cost gain "
                       f"{relative_gain(trials[n].val_weighted, current.val_weighted):.1f} % "
                       f"({ev.simulations} simulations)")
        if not trials:
            break
        best = min(trials, key=lambda n: trials[n].val_weighted)
        floor = luck_floor(search, current)
        ok = accept(current.val_weighted, trials[best].val_weighted, terms, floor)
        search.say(f"step {step + 1}: best {best}, held-out cost {trials[best].val_weighted / terms:.3g} per sample, "
                   f"current {current.val_weighted / terms:.3g}, reached by quantization and noise alone "
                   f"{floor / terms:.3g}: {'accepted' if ok else 'not accepted'}")
        if not ok:
            break
        accepted.append(best)
        current = trials[best]
        values = fit_structure(search, layout, (), accepted, all_runs, values)
        search.say(f"structure: {_values_text(values, accepted, session_names, _fixed(search))}")
    return Structure(accepted, current, values)


def decide_drift(search: Search, layout: Layout, structure: Structure, nominal: Trial,
                 session_names: Sequence[str]) -> DriftResult:
    """Which accepted effects drift (module docstring, step 2), and the final values.

    Parameters
    ----------
    search : Search
    layout : Layout
    structure : Structure
        :func:`select_structure`'s result.
    nominal : Trial
        The nominal model's held-out errors.
    session_names : sequence of str
        For the progress lines.

    Returns
    -------
    DriftResult
        The structure split into shared and drifting effects, one decision per accepted effect
        (none with fewer than two sessions or no effect), the final values on all runs, the
        trials and the leave-one-run-out refits.
    """
    ev, all_runs = search.ev, search.fit_runs
    accepted = list(structure.accepted)
    terms = ev.terms(validation_runs(search.folds))
    if layout.sessions < 2 or not accepted:
        values = ({n: structure.values[key(n, 0)] for n in accepted} if layout.sessions == 1 else {})
        refits = {n: session_refits(search, layout, structure.current, n) for n in accepted}
        return DriftResult(accepted, accepted, [], [], values, nominal, structure.current, dict(structure.values), refits)
    per_session = structure.current
    rms_per = pooled(ev, per_session.val_sse).rms_theta
    decisions, tried = [], {}
    for n in accepted:
        others = [m for m in accepted if m != n]
        tr = structure_trial(search, layout, (n,), others, per_session.fold_values)
        tried[n] = tr
        floor = luck_floor(search, tr)
        ranges = [(min(v), max(v)) for v in session_refits(search, layout, per_session, n)]
        apart = max(lo for lo, _ in ranges) > min(hi for _, hi in ranges)
        drifts = accept(tr.val_weighted, per_session.val_weighted, terms, floor) and apart
        shared_value = fit_structure(search, layout, (n,), others, all_runs, structure.values)[n]
        d = Decision(n, drifts, relative_gain(per_session.val_weighted, tr.val_weighted),
                     rms_gain(rms_per, pooled(ev, tr.val_sse).rms_theta),
                     max(0.0, relative_gain(floor, tr.val_weighted)), shared_value, ranges, apart)
        decisions.append(d)
        search.say(f"drift of {n}: {d.pay(format_quantity(shared_value, EFFECTS[n].unit) + ', fitted for this test')}"
                   f", luck alone by {d.luck_gain_pct:.1f} %; leave-one-run-out refits "
                   + ", ".join(f"{format_quantity(lo, EFFECTS[n].unit)}..{format_quantity(hi, EFFECTS[n].unit)} ({name})"
                               for (lo, hi), name in zip(ranges, session_names))
                   + f"{'' if apart else ' overlap'}: {'drifts' if drifts else 'shared'} ({ev.simulations} simulations)")
    shared = [d.name for d in decisions if not d.drifts]
    drifting = [d.name for d in decisions if d.drifts]
    start = dict(structure.values)
    for n in shared:
        start[n] = _mean_value(search, n, [structure.values[key(n, s)] for s in range(layout.sessions)])
    if not shared:
        final = per_session
    elif len(shared) == 1:
        final = tried[shared[0]]
    else:
        starts = [{**start, **fv} for fv in per_session.fold_values]
        for fv, st in zip(per_session.fold_values, starts):
            for n in shared:
                st[n] = _mean_value(search, n, [fv[key(n, s)] for s in range(layout.sessions)])
        final = structure_trial(search, layout, shared, drifting, starts)
    values = fit_structure(search, layout, shared, drifting, all_runs, start)
    search.say(f"final: {_values_text(values, accepted, session_names, _fixed(search))}; held-out θ gain "
               f"{rms_gain(pooled(ev, final.val_sse).rms_theta, pooled(ev, nominal.val_sse).rms_theta):.1f} % "
               f"({ev.simulations} simulations)")
    refits = {n: session_refits(search, layout, per_session, n) for n in accepted}
    return DriftResult(accepted, shared, drifting, decisions, values, nominal, final, dict(structure.values), refits)


def finite(x: float) -> float | None:
    """``x``, or None when it is not finite (for JSON).

    Parameters
    ----------
    x : float

    Returns
    -------
    float or None
        ``float(x)`` when finite, else None.
    """
    return float(x) if math.isfinite(x) else None
