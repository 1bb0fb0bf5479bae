""":func:`tune`: a compensator of the rig's structure designed on a model and judged on a set of models.

The steps (DESIGN.md "Designing a compensator on a model"): check every input and read every
model (:mod:`station.design.robust`) before any work; judge the thesis's compensator on the
set (the baseline, and where the screening starts); search (:mod:`station.design.search`)
through an executor (:mod:`station.design.executor`); judge the result on every model with
whole simulated runs; report the margins by python-control. :func:`station.design.verify.verify`
then runs it as a real ``station step`` on the simulated rig.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from station.control.designs import DesignRecord
from station.design.evaluate import Figures, Requirements, judge, tip_bound
from station.design.executor import open_runner
from station.design.front import pareto, spread_along, trade_point
from station.design.linear import loop_model
from station.design.result import TradeOff, TuneResult
from station.design.robust import DEFAULT_SAMPLES, SEED, robust_set
from station.design.search import Budget, Problem, SearchResult, judge_points, objective, refine, search
from station.design.space import (DEFAULT_FILTER, DEFAULT_HUB_RATIO, DEFAULT_SHAPER, DEFAULT_TIP_RMS, FILTERS,
                                  SHAPERS, STRUCTURES, DesignSpace, thesis_compensator)
from station.errors import StationError
from station.plant.modes import modal_summary
from station.rig import CLAMP, DAC_LIMIT, DEFAULT_AMPLITUDE, DEFAULT_SOFT_LIMIT, THESIS_STEPS


FRONT_DESIGNS = 12
"""Designs of the bracket's own trade-off front judged on every model besides the search's
(:func:`tune`'s ``front``)."""

FRONT_BOUNDS = (0.5, 0.75, 1.5, 2.0, 3.0, None)
"""Other bounds on the tip (multiples of the thesis's residual RMS; None: none) the trade-off
refines a design for, besides the one asked for: each a short Nelder–Mead from the best design
so far under that bound, so the front reaches both ways from the chosen design."""


def check_request(structure: str, amplitude: float, limit: float, overshoot: float, shaper: str,
                  samples: int, jobs: int, tip_rms: float | None = DEFAULT_TIP_RMS, filter: str = DEFAULT_FILTER,
                  hub_ratio: float = DEFAULT_HUB_RATIO) -> None:
    """Refuse a request that cannot be designed, before any work (one line naming the value).

    Parameters
    ----------
    structure : str
        "p", "lead" or "lead-accel".
    amplitude : float
        Step height, encoder counts: finite, not 0, within ±2048 (the soft limit).
    limit : float
        The clamp, DAC counts: 0 < limit ≤ 255.
    overshoot : float
        Largest overshoot, %: 0 ≤ overshoot ≤ 100.
    shaper : str
        One of :data:`station.design.space.SHAPERS`.
    samples : int
        Drawn models, 0..1000.
    jobs : int
        Local processes, 1..64.
    tip_rms : float or None
        The tip's bound, a multiple of the thesis's: 0 < tip_rms ≤ 100 (None: no bound).
    filter : str
        One of :data:`station.design.space.FILTERS`.
    hub_ratio : float
        The bar on the design model's hub settling (2 %), a multiple of the thesis's: 0 < hub_ratio ≤ 10.

    Raises
    ------
    StationError
    """
    if structure not in STRUCTURES:
        raise StationError(f"--controller {structure}: expected one of {', '.join(STRUCTURES)}")
    if shaper not in SHAPERS:
        raise StationError(f"--shaper {shaper}: expected one of {', '.join(SHAPERS)}")
    if filter not in FILTERS:
        raise StationError(f"--filter {filter}: expected one of {', '.join(FILTERS)}")
    if filter == "damper" and structure != "lead-accel":
        raise StationError(f"--filter damper: the damper is in the accelerometer filter Ga, so --controller "
                           f"lead-accel only, not {structure}")
    checks = (("--amplitude", amplitude, lambda x: x != 0 and abs(x) <= DEFAULT_SOFT_LIMIT,
               f"a step of 1..{DEFAULT_SOFT_LIMIT:g} encoder counts"),
              ("--limit", limit, lambda x: 0 < x <= DAC_LIMIT, f"0 < limit <= {DAC_LIMIT:g} DAC counts"),
              ("--overshoot", overshoot, lambda x: 0 <= x <= 100, "0..100 %"),
              ("--tip-rms", 1.0 if tip_rms is None else tip_rms, lambda x: 0 < x <= 100,
               "0 < ratio <= 100 of the thesis's compensator's"),
              ("--hub-ratio", hub_ratio, lambda x: 0 < x <= 10, "0 < ratio <= 10 of the thesis's compensator's"),
              ("--samples", samples, lambda x: 0 <= x <= 1000 and x == int(x), "a whole number 0..1000"),
              ("--jobs", jobs, lambda x: 1 <= x <= 64 and x == int(x), "a whole number 1..64"))
    for name, value, ok, what in checks:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or not ok(value):
            raise StationError(f"{name} {value}: impossible (expected {what})")


def first_mode(model) -> tuple[float, float]:
    """(f Hz, ζ) of the model's first hub-held beam mode (the θ/v antiresonance), for ZV/ZVD.

    Parameters
    ----------
    model : station.plant.model.Model

    Returns
    -------
    tuple of (float, float)
        (frequency, Hz; damping ratio ζ, dimensionless) of the first antiresonance of θ/v.
    """
    ms = modal_summary(model.linear_params(), model.n_elements)
    return float(ms.antiresonances_hz[0]), float(ms.antiresonance_damping[0])


def design_record(model, nominal, robust=(), out: str | Path = "tuned.toml") -> DesignRecord:
    """The compensator file's ``[design]`` record: the design model's name, or its file's path
    relative to the compensator file's folder, and the sha256 of its canonical TOML.

    Parameters
    ----------
    model : Model, str, Path or None
        What ``tune`` was given as the design model.
    nominal : Model
        The design model as loaded.
    robust : sequence of path
        The ``--robust`` files (without ``model``, a diagnosis JSON's extended model is the design model).
    out : str or Path
        Where the compensator file goes.

    Returns
    -------
    DesignRecord
        The design model's name or relative path (str) and the sha256 (hex) of the loaded
        model's canonical TOML.
    """
    text = None if model is None else str(model) if isinstance(model, (str, Path)) else None
    if text is not None and text.lower().endswith(".toml"):
        name = os.path.relpath(Path(text).resolve(), Path(out).resolve().parent)
    elif text is not None and not text.lower().endswith(".json"):
        name = text  # a built-in model's name
    elif model is None and not any(str(r).lower().endswith(".json") for r in robust):
        name = "tmm-fit"
    else:
        name = nominal.name  # a Model object or a diagnosis's extended model: no file to point at
    return DesignRecord.of(name, nominal.to_toml())


def tune(model=None, structure: str = "lead-accel", amplitude: float | None = None, limit: float = CLAMP,
         overshoot: float = 5.0, shaper: str = DEFAULT_SHAPER, robust: Sequence[str | Path] = (),
         samples: int = DEFAULT_SAMPLES, jobs: int = 1, scheduler: str | None = None,
         out: str | Path = "tuned.toml", budget: Budget = Budget(), seed: int = SEED,
         progress: Callable[[str], None] | None = None, tip_rms: float | None = DEFAULT_TIP_RMS,
         filter: str = DEFAULT_FILTER, front: int = FRONT_DESIGNS,
         hub_ratio: float = DEFAULT_HUB_RATIO) -> TuneResult:
    """Design a compensator of the rig's structure on a model, robust over a set of models.

    The design model first: every requirement met there and the hub's settling (2 %) at most
    ``hub_ratio`` times the thesis's compensator's there; then the worst case over the set of
    each model's hub settling (2 %) relative to the thesis's compensator's on that model (the
    hidden rigs' bar is such a ratio), a model that fails a requirement adding its cost
    (:mod:`station.design.search`).

    Parameters
    ----------
    model : Model, str, Path or None
        The design model (:func:`station.design.robust.robust_set`).
    structure : {"p", "lead", "lead-accel"}
        The compensator's structure (:mod:`station.design.space`).
    amplitude : float, optional
        Step height, encoder counts (default: the thesis's step of the structure, :data:`station.rig.THESIS_STEPS`).
    limit : float
        The compensator's clamp, DAC counts (0 < limit ≤ 255).
    overshoot : float
        Largest overshoot, % (≥ 0).
    shaper : {"none", "zv", "zvd", "opt", "opt2"}
        Reference shaper (:mod:`station.design.space`).
    robust : sequence of path
        Model files and diagnosis JSONs judged beside the model.
    samples : int
        Models drawn from the doubt (≥ 0).
    jobs : int
        Local worker processes (1: this process).
    scheduler : str, optional
        A Dask scheduler's address (wins over ``jobs``).
    out : str or Path
        Where the compensator file will be written (recorded in it; nothing is written here).
    budget : Budget
        The search's budget.
    seed : int
        Seed of the drawn models and of the search's sample.
    progress : callable, optional
        Called with one line per stage.
    tip_rms : float or None
        Largest tip residual RMS (accelerometer, from 0.6 s after the step) on each model, a
        multiple of the thesis's compensator's there (at least the accelerometer's noise,
        :func:`station.design.evaluate.tip_bound`); None: no bound.
    filter : {"none", "notch", "rolloff"}
        What Gth holds beside the structure's gain (:mod:`station.design.space`).
    front : int
        Designs of the bracket's trade-off front judged on every model for the trade-off (≥ 0;
        with any, one design more is refined for each other bound on the tip, :data:`FRONT_BOUNDS`).
    hub_ratio : float
        The bar on the design model: its hub settling (2 %) at most this multiple of the thesis's
        compensator's there (default :data:`~station.design.space.DEFAULT_HUB_RATIO`; 1: no later
        than the thesis's). A design that misses it ranks behind every one that meets it.

    Returns
    -------
    TuneResult
        The design's parameters and compensator file (not written), the tuned and the
        thesis's compensator's figures on every model of the set, the margins, the
        trade-off between hub and tip, and what the search spent; not yet verified.

    Raises
    ------
    StationError
        Bad input (checked before any work): an unknown structure, shaper or filter, an
        impossible amplitude, limit, overshoot, tip bound or hub ratio, an unreadable or unstable model, a
        JSON with no model, an unreachable scheduler.

    Examples
    --------
    A P gain for a 50-count step on the rig's model with at most 5 % overshoot, on the model
    alone and with a small search budget (a few seconds; ``station tune``'s defaults judge a
    set of models and take minutes):

    >>> from station.design import Budget, tune
    >>> result = tune("tmm-fit", structure="p", amplitude=50, shaper="none", samples=0, front=0,
    ...               tip_rms=None, budget=Budget(global_log2=3, keep=2, starts=1, maxfev=12, rounds=1))
    >>> list(result.values), result.met()                         # every requirement met on the model
    (['kp'], [True])
    >>> tuned, thesis = result.figures[0], result.baseline[0]
    >>> tuned.overshoot_pct <= 5, round(thesis.overshoot_pct)     # the thesis's kp = 2 overshoots 40 %
    (True, 40)
    >>> print(result.file.to_toml())                              # doctest: +ELLIPSIS
    name = "tuned p"
    ...
    """
    t0 = time.perf_counter()
    amplitude = THESIS_STEPS.get(structure, DEFAULT_AMPLITUDE) if amplitude is None else amplitude
    check_request(structure, amplitude, limit, overshoot, shaper, samples, jobs, tip_rms, filter, hub_ratio)
    rs = robust_set(model, robust, samples, seed)
    nominal = rs.models[0]
    space = DesignSpace(structure, shaper, float(limit), first_mode(nominal) if shaper in ("zv", "zvd") else None,
                        filter)
    req = Requirements(overshoot_pct=float(overshoot))
    say = progress or (lambda msg: None)
    thesis = thesis_compensator(structure, limit)
    everyone = list(range(len(rs.models)))
    with threadpool_limits(limits=1, user_api="blas"), open_runner(jobs, scheduler) as runner:
        say(f"{structure}, step {amplitude:g}, {len(rs.models)} model(s), evaluations in {runner.where}")
        baseline = [judge(m, thesis, float(amplitude)) for m in rs.models] if len(rs.models) < 2 else \
            [f for part in runner.map(_judge_thesis, [(m, structure, limit, float(amplitude)) for m in rs.models])
             for f in part]
        bounds = None if tip_rms is None else tuple(tip_bound(tip_rms, b.tip_residual_rms) for b in baseline)
        problem = Problem(space, rs.models, float(amplitude), req, bar_s=_bar(baseline[0], hub_ratio),
                          tip_bounds=bounds, hub_scales=hub_scales(baseline))
        result = search(problem, runner, budget, seed, say)
        values = space.values(result.best.x)
        whole = problem._replace(requirements=None)
        final = runner.map(judge_points, [(whole, [result.best.x], everyone)])[0][0]
        tradeoff = _tradeoff(problem, result, baseline, runner, front, say, budget, tip_rms)
        executor = runner.where
    file = space.compensator_file(values, name=f"tuned {structure}", path=out,
                                  design=design_record(model, nominal, robust, out))
    lm = loop_model(nominal)
    return TuneResult(space, values, file, rs, list(final), baseline, req, float(amplitude),
                      lm.margins_control(file.compensator()), lm.margins_control(thesis), result.evaluations,
                      time.perf_counter() - t0, executor, seed, tip_rms, bounds, tradeoff, hub_ratio)


def _bar(thesis: Figures, hub_ratio: float) -> float | None:
    """The design model's bar, s: ``hub_ratio`` times the thesis's hub settling (2 %) there (None: it does not settle)."""
    return None if thesis.settling_2pct_s is None else hub_ratio * thesis.settling_2pct_s


def hub_scales(baseline: Sequence[Figures]) -> tuple[float, ...] | None:
    """Per model, what its hub settling (2 %) is multiplied by in the cost: the thesis's
    compensator's settling on the design model over its settling on that model, so the worst
    case over the set is the worst ratio to the thesis's on the same model (in the design
    model's seconds).

    Parameters
    ----------
    baseline : sequence of Figures
        The thesis's compensator on each model, the design model's first.

    Returns
    -------
    tuple of float or None
        One scale per model (1 where the thesis's does not settle); None when the thesis's does
        not settle on the design model (the worst case is then in plain seconds).
    """
    ref = baseline[0].settling_2pct_s
    if ref is None:
        return None
    return tuple(1.0 if b.settling_2pct_s is None else ref / b.settling_2pct_s for b in baseline)


def _tradeoff(problem: Problem, result: SearchResult, baseline, runner, n: int, say, budget: Budget = Budget(),
              tip_rms: float | None = DEFAULT_TIP_RMS) -> TradeOff:
    """The trade-off: the search's designs judged on every model; ``n`` more spread along the
    bracket's own front on the screening set; and, with ``n`` > 0, one design refined for each
    other bound on the tip (:data:`FRONT_BOUNDS`), all judged on every model."""
    screen = list(result.screen)
    reqs_screen = problem.model_requirements(screen)
    base_screen = [baseline[i] for i in screen]
    seen = [c.x for c in result.judged]
    bracket = [(x, trade_point(x, f, base_screen, reqs_screen, problem.run_s)) for x, f in result.bracket]
    front = pareto([p for _, p in bracket])
    picks = [bracket[front[k]][0] for k in spread_along([bracket[i][1].hub_ratio for i in front], n)]
    everyone = list(range(len(problem.models)))
    others = [r for r in FRONT_BOUNDS if r != tip_rms] if n > 0 else []
    if others:
        say(f"trade-off: {len(others)} designs refined for other bounds on the tip, {len(picks)} of the bracket's "
            f"front, on {len(everyone)} models")
        tasks = []
        for r in others:
            bounded = problem._replace(tip_bounds=None if r is None else
                                       tuple(tip_bound(r, b.tip_residual_rms) for b in baseline))
            start = min(result.judged, key=lambda c: objective(c.figures, bounded.model_requirements(), bounded.run_s,
                                                               bounded.bar_s))
            tasks.append((bounded, start.x, list(result.working_set), max(20, budget.maxfev // 2)))
        picks += [x for x, _ in runner.map(refine, tasks)]
    kept = []
    for x in picks:
        if all(np.max(np.abs(x - y)) > 1e-9 for y in seen + kept):
            kept.append(x)
    picks = kept
    extra = runner.map(judge_points, [(problem, [x], everyone) for x in picks])
    reqs = problem.model_requirements()
    xs = seen + picks
    figs = [c.figures for c in result.judged] + [f for (f,) in extra]
    points = [trade_point(x, f, baseline, reqs, problem.run_s) for x, f in zip(xs, figs)]
    chosen = next(i for i, c in enumerate(result.judged) if c is result.best)
    return TradeOff(points, [problem.space.values(x) for x in xs], pareto(points), chosen)


def _judge_thesis(model, structure: str, limit: float, amplitude: float) -> list[Figures]:
    """The thesis's compensator on one model (a task)."""
    return [judge(model, thesis_compensator(structure, limit), amplitude)]
