"""The search: bracket globally, then refine locally, on the worst case over a set of models.

The cost of a design (:func:`station.design.evaluate.cost`) is rugged: friction makes the
hub stop where it happens to stick, and the sensors count in whole steps, so the 2 %
settling time jumps between plateaus. The search therefore

1. **brackets** the compensator's parameters with a scrambled Sobol sample (seeded; ``2^m``
   points plus the thesis's design; an ``opt`` shaper starts at the ZV shaper of each
   design's own closed-loop mode, :meth:`~station.design.space.DesignSpace.complete`), judged
   on a *screening set*: the nominal model and the models of
   the set farthest from it and from each other in their effects' values (greedy
   farthest-point selection, each effect scaled by its spread over the set);
2. judges the best ``keep`` of them, and the best on the design model alone, on every model;
3. **refines** the best few with Nelder–Mead (scipy, bounded to the unit cube, an initial
   simplex of 0.1 per parameter) on a *working set* of models, each start a task of its own;
   every result is judged on every model, and the model on which each result does worst joins
   the working set (the worst case is found where it is, not where it was guessed: an
   active-set scheme); the next round restarts from the best designs so far (a fresh
   simplex), until a round neither finds a new worst model nor improves the objective.

A design whose linear margins already fail is not simulated (it is out whatever its step).
The objective (:func:`objective`, :func:`robust_objective`) is lexicographic: first every
requirement met on the design model, settling there no later than the thesis's compensator
(a design that fails there is ranked by how close it comes, behind every design that meets
it); then the worst case over the set plus 1 % of the
mean (the mean only breaks ties between designs with the same worst case), where a model
that fails a requirement adds its own cost, and a model on which friction holds the hub
outside the 2 % band (and nothing else fails) adds the settling time into the band it
holds, charged for the held error (:func:`station.design.evaluate.cost`): with dry
friction and no integral action the 2 % band of a small step is reached on some models by
luck alone, and those models must still rank the designs. Everything is a pure function
of the inputs and the seed: the tasks' results come back in order and the reductions are
plain max/mean/sort with ties broken by index, so the design does not depend on the
executor (:mod:`station.design.executor`).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from scipy.optimize import minimize
from scipy.stats import qmc

from station.analysis.metrics import settling_label
from station.design.evaluate import RUN_S, Figures, Requirements, cost, judge, linear_checks, linear_key
from station.design.linear import loop_model
from station.design.space import SECOND_MODE_HZ

MEAN_WEIGHT = 0.01
"""Weight of the mean over the models in the robust objective (a tie-break)."""

DESIGN_MODEL_FIRST = 1e6
"""Added to the objective of a design that fails a requirement on the design model: above any
robust worst case (which is capped below it), so the ranking is lexicographic."""


class Budget(NamedTuple):
    """How much the search may spend.

    Attributes
    ----------
    global_log2 : int or None
        The bracket's Sobol sample has 2**global_log2 points (None: 6 + the number of
        the compensator's parameters, at most 10: 128 points for P, 1024 for lead + accelerometer).
    keep : int
        Bracketed designs judged on every model.
    starts : int
        Nelder–Mead starts in the first round (half as many, at least one, in the later ones).
    maxfev : int
        Evaluations per start.
    rounds : int
        Most active-set rounds.
    screen : int
        Models besides the nominal in the screening set.
    """

    global_log2: int | None = None
    keep: int = 8
    starts: int = 4
    maxfev: int = 120
    rounds: int = 3
    screen: int = 2


class Problem(NamedTuple):
    """What a task needs to judge designs: picklable, no state.

    Attributes
    ----------
    space : station.design.space.DesignSpace
    models : tuple of Model
    amplitude : float
        Step height, encoder counts.
    requirements : Requirements
    run_s : float
        Run length, s.
    bar_s : float or None
        The 2 % settling time to beat on the design model, s: the thesis's compensator's there
        (None: no bar, it does not settle).
    tip_bounds : tuple of float or None
        Per model, the bound on the tip's residual RMS, accelerometer counts
        (:func:`station.design.evaluate.tip_bound`; None: no bound anywhere).
    hub_scales : tuple of float or None
        Per model, what its hub settling (2 %) counts times in the cost
        (:attr:`station.design.evaluate.Requirements.settling_scale`; ``tune``: the thesis's
        compensator's settling on the design model over its settling on that model, so the
        worst case is the worst ratio to the thesis's; None: 1 everywhere).
    """

    space: object
    models: tuple
    amplitude: float
    requirements: Requirements
    run_s: float = RUN_S
    bar_s: float | None = None
    tip_bounds: tuple | None = None
    hub_scales: tuple | None = None

    def model_requirements(self, which=None) -> list[Requirements]:
        """The requirements on each model (``which``: their indices; default all), the tip's bound and the hub's scale its own.

        Parameters
        ----------
        which : sequence of int, optional
            Indices of the models.

        Returns
        -------
        list of Requirements
            One per index in ``which``, in its order: :attr:`requirements` with ``tip_rms`` set to
            that model's :attr:`tip_bounds` entry and ``settling_scale`` to its :attr:`hub_scales`
            entry (each unchanged when there are none).
        """
        which = range(len(self.models)) if which is None else which
        out = []
        for i in which:
            own = {}
            if self.tip_bounds is not None:
                own["tip_rms"] = self.tip_bounds[i]
            if self.hub_scales is not None:
                own["settling_scale"] = self.hub_scales[i]
            out.append(self.requirements._replace(**own))
        return out


class Candidate(NamedTuple):
    """A design judged on every model.

    Attributes
    ----------
    x : ndarray, shape (d,)
        Its unit-cube point.
    figures : tuple of Figures
        One per model of the set.
    costs : tuple of float
        One per model.
    objective : float
        The objective (:func:`objective`: the design model first, then the worst case).
    """

    x: np.ndarray
    figures: tuple
    costs: tuple
    objective: float

    @property
    def worst(self) -> int:
        """Index of the model with the highest cost (the first on a tie)."""
        return int(np.argmax(self.costs))


class SearchResult(NamedTuple):
    """The search's outcome.

    Attributes
    ----------
    best : Candidate
    evaluations : int
        Designs judged on models (one design on one model: the linear checks, and the step
        unless the margins already fail).
    working_set : tuple of int
        The models the last refinement ran on.
    judged : tuple of Candidate
        Every design judged on every model (the trade-off's candidates).
    bracket : tuple of (ndarray, list of Figures)
        The bracket's designs (unit-cube points) and their figures on the screening set.
    screen : tuple of int
        The screening set's model indices.
    """

    best: Candidate
    evaluations: int
    working_set: tuple
    judged: tuple = ()
    bracket: tuple = ()
    screen: tuple = ()


def robust_objective(costs, run_s: float = RUN_S, design_cost: float | None = None) -> float:
    """The lexicographic objective of a design from its costs (module docstring).

    The design model first: when it fails a requirement there (``design_cost`` ≥ ``run_s``),
    :data:`DESIGN_MODEL_FIRST` + ``design_cost`` (+ the mean's tie-break), behind every design
    that meets it. Then the worst case over the models whose cost is below ``run_s`` (every
    requirement met), plus each other model's cost (held by friction: graded by the band it
    holds, :func:`station.design.evaluate.cost`),
    plus :data:`MEAN_WEIGHT` times the mean, capped below :data:`DESIGN_MODEL_FIRST`.

    Parameters
    ----------
    costs : sequence of float
        One model's cost each, the design model's first (:func:`station.design.evaluate.cost`:
        below ``run_s`` exactly when every requirement is met).
    run_s : float
        The run's length, s.
    design_cost : float, optional
        The design model's cost against every requirement, the 2 % band included
        (``cost(..., held=False)``); default ``costs[0]``.

    Returns
    -------
    float
        The objective, s-like (smaller is better): below ``0.5 *`` :data:`DESIGN_MODEL_FIRST`
        when every requirement holds on the design model, at least :data:`DESIGN_MODEL_FIRST`
        otherwise.
    """
    c = np.asarray(costs, dtype=float)
    first = float(c[0]) if design_cost is None else float(design_cost)
    tie = MEAN_WEIGHT * float(c.mean())
    if not first < run_s:
        return DESIGN_MODEL_FIRST + first + tie
    met = c < run_s
    worst_met = float(c[met].max()) if met.any() else 0.0
    return float(min(worst_met + c[~met].sum() + tie, 0.5 * DESIGN_MODEL_FIRST))


def objective(figures, requirements, run_s: float = RUN_S, bar_s: float | None = None) -> float:
    """A design's objective from its figures on the models (:func:`robust_objective`).

    The design model's part: its cost against every requirement, the 2 % band included; a
    design that meets them but settles later there than ``bar_s`` (the thesis's compensator
    on the same model) is no improvement on it and counts as failing, by how much later.

    Parameters
    ----------
    figures : sequence of Figures
        One per model, the design model's first.
    requirements : Requirements or sequence of Requirements
        The same for every model, or one per model (the tip's bound is a model's own).
    run_s : float
        The run's length, s.
    bar_s : float, optional
        The 2 % settling time to beat on the design model, s.

    Returns
    -------
    float
        :func:`robust_objective` of the models' costs, with the design model's part as above.
    """
    reqs = [requirements] * len(figures) if isinstance(requirements, Requirements) else list(requirements)
    first = cost(figures[0], reqs[0], run_s, held=False)
    if bar_s is not None and first < run_s and first > bar_s:
        first = run_s + (first - bar_s)
    return robust_objective([cost(f, r, run_s) for f, r in zip(figures, reqs)], run_s, first)


def _objective(problem: Problem, figures, which=None) -> float:
    return objective(figures, problem.model_requirements(which), problem.run_s, problem.bar_s)


def judge_point(problem: Problem, x, which) -> list[Figures]:
    """A design's figures on some of the problem's models (one task's work).

    Parameters
    ----------
    problem : Problem
    x : array_like, shape (d,)
        Unit-cube point.
    which : sequence of int
        Indices of the models.

    Returns
    -------
    list of Figures
        The design's figures on each model of ``which``, in its order.
    """
    comp = problem.space.compensator_file(problem.space.values(x)).compensator()
    checks = {}  # models that differ in friction or offsets alone share their linear checks
    out = []
    for i in which:
        model = problem.models[i]
        key = linear_key(model)
        if key not in checks:
            checks[key] = linear_checks(model, comp)
        out.append(judge(model, comp, problem.amplitude, problem.run_s, requirements=problem.requirements,
                         linear=checks[key], tip=problem.requirements is None))
    return out


def judge_points(problem: Problem, xs, which) -> list[list[Figures]]:
    """:func:`judge_point` for several points (one task).

    Parameters
    ----------
    problem : Problem
    xs : sequence of array_like
        Unit-cube points.
    which : sequence of int
        Indices of the models.

    Returns
    -------
    list of list of Figures
        One :func:`judge_point` list per point, in the order of ``xs``.
    """
    return [judge_point(problem, x, which) for x in xs]


def bracket_points(problem: Problem, xs, which) -> list[tuple[np.ndarray, list[Figures]]]:
    """Complete the compensator's coordinates into whole points, and judge them (one task).

    Parameters
    ----------
    problem : Problem
    xs : sequence of array_like
        The compensator's coordinates.
    which : sequence of int
        Indices of the models.

    Returns
    -------
    list of (point, figures)
        The whole unit-cube point (an ``opt`` shaper at the ZV of the loop's least damped
        mode on the nominal model) and its figures on the models.
    """
    space = problem.space
    out = []
    for x in xs:
        mode = second = None
        if space.shaper in ("opt", "opt2"):
            bare = space.compensator_file(space.values(space.complete(x, None))).compensator()
            lm = loop_model(problem.models[0])
            poles = np.linalg.eigvals(lm.closed_loop_matrix(bare))
            mode = lm.dominant_mode(bare, poles=poles)
            second = lm.dominant_mode(bare, SECOND_MODE_HZ, poles) if space.shaper == "opt2" else None
        point = space.complete(x, mode, second)
        out.append((point, judge_point(problem, point, which)))
    return out


def _costs(problem: Problem, figs, which=None) -> list[float]:
    return [cost(f, r, problem.run_s) for f, r in zip(figs, problem.model_requirements(which))]


def refine(problem: Problem, x0, which, maxfev: int) -> tuple[np.ndarray, int]:
    """Nelder–Mead from ``x0`` on the robust objective over the models ``which`` (one task).

    Parameters
    ----------
    problem : Problem
    x0 : array_like, shape (d,)
        Start, unit cube.
    which : sequence of int
        The working set's model indices.
    maxfev : int
        Most evaluations.

    Returns
    -------
    x : ndarray, shape (d,)
        The best point found (within the unit cube).
    evaluations : int
        Designs judged on models.
    """
    x0 = np.clip(np.asarray(x0, dtype=float), 0.0, 1.0)
    d = x0.size
    simplex = [x0]
    for i in range(d):
        step = np.zeros(d)
        step[i] = 0.1 if x0[i] <= 0.9 else -0.1
        simplex.append(x0 + step)
    calls = [0]

    def f(x):
        calls[0] += 1
        return _objective(problem, judge_point(problem, x, which), which)

    res = minimize(f, x0, method="Nelder-Mead", bounds=[(0.0, 1.0)] * d,
                   options={"maxfev": int(maxfev), "initial_simplex": np.array(simplex), "xatol": 1e-3,
                            "fatol": 1e-4})
    return np.clip(res.x, 0.0, 1.0), calls[0] * len(which)


def _chunks(items: list, size: int) -> list[list]:
    return [items[i:i + size] for i in range(0, len(items), size)]


def search(problem: Problem, runner, budget: Budget = Budget(), seed: int = 0,
           progress: Callable[[str], None] | None = None) -> SearchResult:
    """Bracket, judge, refine (module docstring).

    Parameters
    ----------
    problem : Problem
    runner : station.design.executor.Runner
        Runs the tasks.
    budget : Budget
        The search's budget.
    seed : int
        The Sobol sample's seed.
    progress : callable, optional
        Called with one line per stage.

    Returns
    -------
    SearchResult
        The best candidate, the evaluation count, the last working set, every candidate judged
        on all models, the bracket and the screening set.
    """
    say = progress or (lambda msg: None)
    space, n_models = problem.space, len(problem.models)
    screen = screening_set(problem.models, budget.screen)
    log2 = budget.global_log2 if budget.global_log2 is not None else min(10, 6 + space.controller_dimension)
    seeds = qmc.Sobol(space.controller_dimension, scramble=True, seed=seed).random_base2(log2)
    seeds = np.vstack([space.thesis_point()[None, :], seeds])
    evaluations = 0

    say(f"bracketing: {len(seeds)} designs on {len(screen)} of {n_models} models")
    tasks = [(problem, chunk, screen) for chunk in _chunks(list(seeds), 16)]
    judged = [pair for part in runner.map(bracket_points, tasks) for pair in part]
    points = [x for x, _ in judged]
    evaluations += len(points) * len(screen)
    ranks = [_objective(problem, f, screen) for _, f in judged]
    ranked = sorted(range(len(points)), key=lambda i: (ranks[i], i))[:budget.keep]
    # and the best on the design model alone: where the set's worst cases pull apart (P and dry
    # friction), the design that works on the model itself must still be among the candidates
    first = problem.model_requirements([0])[0]
    alone = min(range(len(points)), key=lambda i: (cost(judged[i][1][0], first, problem.run_s, held=False), i))
    if alone not in ranked:
        ranked.append(alone)

    everyone = list(range(n_models))

    def judge_all(xs) -> list[Candidate]:
        tasks = [(problem, [x], everyone) for x in xs]
        out = []
        for x, (f,) in zip(xs, runner.map(judge_points, tasks)):
            out.append(Candidate(np.asarray(x, dtype=float), tuple(f), tuple(_costs(problem, f)),
                                 _objective(problem, f)))
        return out

    pool = judge_all([points[i] for i in ranked])
    evaluations += len(ranked) * n_models
    best = min(pool, key=lambda c: c.objective)
    working = sorted(set(screen) | {best.worst})
    for rnd in range(1, budget.rounds + 1):
        starts = _distinct(sorted(pool, key=lambda c: c.objective),
                           budget.starts if rnd == 1 else max(1, budget.starts // 2))
        say(f"refining round {rnd}: {len(starts)} starts on {len(working)} models; best so far: "
            f"{_describe(best)}")
        results = runner.map(refine, [(problem, c.x, working, budget.maxfev) for c in starts])
        evaluations += sum(n for _, n in results)
        found = judge_all([x for x, _ in results])
        evaluations += len(found) * n_models
        pool += found
        before, best = best, min(pool, key=lambda c: c.objective)
        new = {c.worst for c in found} | {best.worst}
        if new <= set(working) and best.objective > before.objective - 1e-3:
            break  # nothing new to learn: every worst model is in, and restarting did not pay
        working = sorted(set(working) | new)
    say(f"done: {_describe(best)}; {evaluations} evaluations")
    return SearchResult(best, evaluations, tuple(working), tuple(pool), tuple(judged), tuple(screen))


def screening_set(models, extra: int) -> list[int]:
    """The nominal model (index 0) and the ``extra`` models farthest from the chosen ones.

    Greedy farthest-point selection over the models' effect values, each effect scaled by
    its range over the set (an absent effect at its neutral value); ties go to the lower index.

    Parameters
    ----------
    models : sequence of Model
    extra : int
        How many besides the nominal.

    Returns
    -------
    list of int
        Sorted model indices: 0 and up to ``extra`` others (fewer when there are fewer models).
    """
    names = sorted({k for m in models for k in m.effect_dict()})
    X = np.array([[m.effect(k) for k in names] for m in models], dtype=float).reshape(len(models), len(names))
    X[~np.isfinite(X)] = 0.0
    span = X.max(axis=0) - X.min(axis=0) if len(models) else np.zeros(len(names))
    X = (X - X.min(axis=0)) / np.where(span > 0, span, 1.0) if len(models) else X
    chosen = [0]
    dist = np.linalg.norm(X - X[0], axis=1)
    while len(chosen) < min(len(models), extra + 1):
        i = int(np.argmax(np.where(np.isin(np.arange(len(models)), chosen), -1.0, dist)))
        chosen.append(i)
        dist = np.minimum(dist, np.linalg.norm(X - X[i], axis=1))
    return sorted(chosen)


def _distinct(cands: list, n: int) -> list:
    out = []
    for c in cands:
        if all(np.max(np.abs(c.x - o.x)) > 1e-6 for o in out):
            out.append(c)
        if len(out) == n:
            break
    return out


def _describe(c: Candidate) -> str:
    """The progress's words for a design: the hub's settling on its costliest model (the cost
    weighs each model's settling by the thesis's there, so that model need not be the one that
    settles last: the final 'worst over the set' is the latest over every model) and the highest
    overshoot over the set."""
    f = c.figures[c.worst]
    settle = "not settled" if f.settling_2pct_s is None else f"{f.settling_2pct_s:.3f} s"
    return (f"costliest model: hub {settling_label(2)} {settle}; overshoot at most "
            f"{max(g.overshoot_pct for g in c.figures):.1f} % over the models")
