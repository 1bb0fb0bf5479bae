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
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from threadpoolctl import threadpool_limits

from station.control.designs import CompensatorFile, DesignRecord
from station.design.evaluate import Figures, Requirements, friction_held, held_error, judge, tip_bound, violations
from station.design.executor import open_runner
from station.design.front import pareto, spread_along, trade_point
from station.design.hold import design_model_warning, held_summary
from station.design.linear import Margins, loop_model
from station.design.robust import DEFAULT_SAMPLES, SEED, RobustSet, robust_set
from station.design.search import Budget, Problem, SearchResult, judge_points, objective, refine, search
from station.design.space import (DEFAULT_FILTER, DEFAULT_SHAPER, DEFAULT_TIP_RMS, FILTERS, SHAPERS, STRUCTURES,
                                  DesignSpace, thesis_compensator)
from station.errors import StationError
from station.plant.modes import modal_summary
from station.rig import CLAMP, DAC_LIMIT, DEFAULT_AMPLITUDE, DEFAULT_SOFT_LIMIT, THESIS_STEPS

METRICS = ("overshoot_pct", "settling_2pct_s", "settling_thesis_s", "peak_command", "saturated_s",
           "tip_settling_2pct_s", "tip_residual_rms", "tip_residual_peak")
"""DESIGN.md's metrics, in the JSON's order."""

FRONT_DESIGNS = 12
"""Designs of the bracket's own trade-off front judged on every model besides the search's
(:func:`tune`'s ``front``)."""

FRONT_BOUNDS = (0.5, 0.75, 1.5, 2.0, 3.0, None)
"""Other bounds on the tip (multiples of the thesis's residual RMS; None: none) the trade-off
refines a design for, besides the one asked for: each a short Nelder–Mead from the best design
so far under that bound, so the front reaches both ways from the chosen design."""


def check_request(structure: str, amplitude: float, limit: float, overshoot: float, shaper: str,
                  samples: int, jobs: int, tip_rms: float | None = DEFAULT_TIP_RMS, filter: str = DEFAULT_FILTER) -> None:
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


@dataclass
class TradeOff:
    """The designs judged on every model, and the front between hub and tip (:mod:`station.design.front`).

    Attributes
    ----------
    points : list of TradePoint
    values : list of dict
        Each point's parameters.
    front : list of int
        Indices of the front's points, by hub ratio.
    chosen : int
        Index of the chosen design.
    """

    points: list
    values: list
    front: list
    chosen: int

    def point_json(self, i: int) -> dict:
        """One point: parameters, both ratios, worst overshoot, hub settling, tip RMS, met, chosen, on the front.

        Parameters
        ----------
        i : int
            Its index in :attr:`points`.

        Returns
        -------
        dict
            ``parameters`` (name to value, rounded to 6 decimals), ``hub_ratio`` and ``tip_ratio``
            (dimensionless), ``overshoot_pct`` (%), ``settling_2pct_s`` (s), ``tip_residual_rms``
            (accelerometer counts), each None when not finite; ``requirements_met``, ``others_met``,
            ``chosen`` and ``on_front`` (bool).
        """
        p = self.points[i]

        def num(x):
            return None if not math.isfinite(x) else round(float(x), 6)
        return {"parameters": {k: round(v, 6) for k, v in self.values[i].items()}, "hub_ratio": num(p.hub_ratio),
                "tip_ratio": num(p.tip_ratio), "overshoot_pct": num(p.overshoot_pct),
                "settling_2pct_s": num(p.hub_s), "tip_residual_rms": num(p.tip_rms),
                "requirements_met": p.met, "others_met": p.others_met, "chosen": i == self.chosen,
                "on_front": i in self.front}

    def to_json(self) -> dict:
        """``axes``, ``designs`` (how many were judged on every model), ``front`` (its points) and ``chosen``.

        Returns
        -------
        dict
            ``axes`` (list of two str), ``designs`` (int), ``front`` (list of :meth:`point_json`
            dicts, in front order) and ``chosen`` (a :meth:`point_json` dict).
        """
        return {"axes": ["worst hub settling (2 %) / the thesis's", "worst tip residual RMS / the thesis's"],
                "designs": len(self.points), "front": [self.point_json(i) for i in self.front],
                "chosen": self.point_json(self.chosen)}


@dataclass
class TuneResult:
    """A tuned compensator and the evidence for it.

    Attributes
    ----------
    space : DesignSpace
    values : dict
        The design's parameters (:attr:`DesignSpace.parameters`' names).
    file : CompensatorFile
        The compensator file (its path is where it is to be written; its ``design`` record
        names the design model).
    robust : RobustSet
    figures, baseline : list of Figures
        The tuned and the thesis's compensator on each model of the set (whole runs).
    requirements : Requirements
        The requirements (``tip_rms`` None: the tip's bound is per model, ``tip_bounds``).
    amplitude : float
        Step height, encoder counts.
    margins, baseline_margins : Margins
        python-control's margins of the tuned and the thesis's loop on the nominal model.
    evaluations : int
        Designs judged on models by the search.
    elapsed_s : float
    executor : str
    seed : int
    tip_rms : float or None
        The tip's requirement, a multiple of the thesis's compensator's RMS (None: none).
    tip_bounds : tuple of float or None
        Per model, the bound on the tip's residual RMS, accelerometer counts.
    tradeoff : TradeOff or None
        The hub-tip trade-off.
    verification : Any
        :class:`station.design.verify.Verification` once verified (None before).
    """

    space: DesignSpace
    values: dict
    file: CompensatorFile
    robust: RobustSet
    figures: list
    baseline: list
    requirements: Requirements
    amplitude: float
    margins: Margins
    baseline_margins: Margins
    evaluations: int
    elapsed_s: float
    executor: str
    seed: int = SEED
    tip_rms: float | None = DEFAULT_TIP_RMS
    tip_bounds: tuple | None = None
    tradeoff: TradeOff | None = None
    verification: Any = field(default=None)

    @property
    def nominal(self):
        """The design model."""
        return self.robust.models[0]

    def model_requirements(self) -> list[Requirements]:
        """The requirements on each model, the tip's bound its own.

        Returns
        -------
        list of Requirements
            One per model of the set, in its order.
        """
        if self.tip_bounds is None:
            return [self.requirements] * len(self.figures)
        return [self.requirements._replace(tip_rms=b) for b in self.tip_bounds]

    def met(self) -> list[bool]:
        """Per model: every requirement met.

        Returns
        -------
        list of bool
            One per model of the set, in its order.
        """
        return [not violations(f, r) for f, r in zip(self.figures, self.model_requirements())]

    def warnings(self) -> list[str]:
        """One line each: what the user must know about the design beyond its figures (friction
        holding the hub outside the 2 % band on the design model, :mod:`station.design.hold`).

        Returns
        -------
        list of str
            The warning lines, without trailing newlines; empty when there is nothing to say.
        """
        held = design_model_warning(self.space, self.values, self.nominal, self.figures[0],
                                    self.model_requirements()[0])
        return [] if held is None else [held]

    def design_json(self) -> dict:
        """The ``design`` block: structure, parameters, compensator, requirements, search, warnings.

        Returns
        -------
        dict
            JSON-ready: the structure, shaper, filter, amplitude (encoder counts) and clamp (DAC
            counts); each parameter's ``value`` and ``unit``; the mode (Hz, ζ); the compensator's
            spec; the requirements; the design model record; the objective in words; ``feasible``;
            the margins (dB, degrees, rad/s); evaluations, ``elapsed_s`` (s), executor, seed and
            :meth:`warnings`.
        """
        comp = self.file.compensator()
        spec = {k: comp.spec[k] for k in ("gth", "ga", "limit") if k in comp.spec}
        if "shaper" in comp.spec:
            spec["shaper"] = comp.spec["shaper"]
        units = {p.name: p.unit for p in self.space.parameters}
        req = self.requirements._asdict()
        req["tip_rms"] = self.tip_rms
        return {"structure": self.space.structure, "shaper": self.space.shaper, "filter": self.space.filter,
                "amplitude": self.amplitude, "limit": self.space.limit,
                "parameters": {k: {"value": v, "unit": units[k]} for k, v in self.values.items()},
                "mode": None if self.space.mode is None else {"f_hz": self.space.mode[0], "zeta": self.space.mode[1]},
                "compensator": spec, "requirements": req,
                "design_model": None if self.file.design is None else self.file.design._asdict(),
                "objective": f"lexicographic: every requirement met on the design model first (the tip's residual "
                             f"RMS from 0.6 s after the step at most "
                             f"{'no bound' if self.tip_rms is None else f'{self.tip_rms:g}x the thesis compensator'}"
                             f"'s there), settling there no later than the thesis's compensator; then the worst "
                             f"2 % settling time over the {len(self.robust.models)} model(s) (+1 % of the mean), "
                             f"a model where a requirement is not met adding its cost, and a model where friction "
                             f"holds the hub outside the 2 % band (nothing else failing) counting with the settling "
                             f"time into the band it holds, charged for the held error",
                "feasible": all(self.met()), "margins": _margins_json(self.margins),
                "evaluations": self.evaluations, "elapsed_s": round(self.elapsed_s, 3), "executor": self.executor,
                "seed": self.seed, "warnings": self.warnings()}

    def to_json(self, controller: str | Path | None = None) -> dict:
        """DESIGN.md's JSON: controller, design, model, robust, baseline, tradeoff (and verification).

        Parameters
        ----------
        controller : str or Path, optional
            The written compensator file (None: not written).

        Returns
        -------
        dict
            JSON-ready: ``controller`` (str or None), ``design`` (:meth:`design_json`), ``model``
            (the design model's name, effects and figures), ``robust`` (:func:`robust_json`),
            ``baseline`` (the thesis's compensator's figures, margins and spread), ``tradeoff``
            (:meth:`TradeOff.to_json` or None), and ``verification`` when there is one.
        """
        nominal = self.nominal
        doc = {"controller": None if controller is None else str(controller),
               "design": self.design_json(),
               "model": {"name": nominal.name, "effects": nominal.effect_dict(), **self.figures[0].to_json()},
               "robust": robust_json(self.robust, self.figures, self.baseline, self.model_requirements()),
               "baseline": {"controller": f"{self.space.structure} (thesis)", **self.baseline[0].to_json(),
                            "margins": _margins_json(self.baseline_margins),
                            "robust": _spread(self.baseline)},
               "tradeoff": None if self.tradeoff is None else self.tradeoff.to_json()}
        if self.verification is not None:
            doc["verification"] = self.verification.to_json()
        return doc


def _margins_json(m: Margins) -> dict:
    def num(x):
        return None if not math.isfinite(x) else round(float(x), 4)
    return {"gain_margin_db": num(m.gain_margin_db), "phase_margin_deg": num(m.phase_margin_deg),
            "crossover_rad_s": num(m.crossover_rad_s)}


def _spread(figures: Sequence[Figures]) -> dict:
    """Worst value and [min, max] of each metric over models (None where a model did not settle)."""
    worst, spread = {}, {}
    for key in METRICS:
        vals = [getattr(f, key) for f in figures]
        known = [v for v in vals if v is not None and math.isfinite(v)]
        unknown = len(vals) - len(known)
        spread[key] = [min(known), max(known)] if known else None
        worst[key] = None if unknown or not known else max(known)
    settled = sum(f.settling_2pct_s is not None for f in figures)
    return {"worst": worst, "spread": spread, "settled": settled, "models": len(figures)}


def _ratio(a, b) -> float | None:
    return None if a is None or not b or not math.isfinite(a) or not math.isfinite(b) else round(a / b, 4)


def robust_json(rs: RobustSet, figures, baseline, req) -> dict:
    """The ``robust`` block: worst case and spread of the tuned compensator over the set,
    per model with the thesis's beside it (its metrics under ``baseline``, the tip's and the
    hub's ratios), and the models where friction holds the hub outside the 2 % band
    (``friction_held``: :func:`station.design.hold.held_summary`; per model
    ``held_error_counts``, ``held_band_counts``, ``settling_held_s``, None where it is not held).

    Parameters
    ----------
    rs : RobustSet
    figures, baseline : sequence of Figures
        Tuned and thesis, one per model.
    req : Requirements or sequence of Requirements
        The same for every model, or one per model (the tip's bound its own).

    Returns
    -------
    dict
        ``worst``, ``spread`` ([min, max]), ``settled`` and ``models`` over the set's figures;
        ``all_met`` (bool); ``friction_held`` (:func:`~station.design.hold.held_summary`);
        ``settling_ratio_to_baseline`` and ``tip_rms_ratio_to_baseline`` ([min, max], None when
        no model gives one); ``intervals`` (effect to [low, high]); and ``per_model``, one dict
        per model in set order.
    """
    reqs = [req] * len(figures) if isinstance(req, Requirements) else list(req)
    per_model = []
    ratios, tip_ratios = [], []
    for m, lab, f, b, r in zip(rs.models, rs.labels, figures, baseline, reqs):
        ratio = _ratio(f.settling_2pct_s, b.settling_2pct_s)
        if ratio is not None:
            ratios.append(ratio)
        tip = _ratio(f.tip_residual_rms, b.tip_residual_rms)
        if tip is not None:
            tip_ratios.append(tip)
        held = friction_held(f, r)
        per_model.append({"label": lab, "name": m.name, "effects": m.effect_dict(), **f.to_json(),
                          "requirements_met": not violations(f, r), "tip_rms_bound": r.tip_rms,
                          "baseline_settling_2pct_s": b.to_json()["settling_2pct_s"],
                          "settling_ratio_to_baseline": ratio, "tip_rms_ratio_to_baseline": tip,
                          "baseline": b.to_json(),
                          "held_error_counts": held_error(f) if held else None,
                          "held_band_counts": f.rest_band if held else None,
                          "settling_held_s": f.settling_rest_s if held else None})
    out = _spread(figures)
    out.update({"all_met": all(p["requirements_met"] for p in per_model),
                "friction_held": held_summary(figures, reqs),
                "settling_ratio_to_baseline": [min(ratios), max(ratios)] if ratios else None,
                "tip_rms_ratio_to_baseline": [min(tip_ratios), max(tip_ratios)] if tip_ratios else None,
                "intervals": {k: list(v) for k, v in rs.intervals.items()}, "per_model": per_model})
    return out


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
         filter: str = DEFAULT_FILTER, front: int = FRONT_DESIGNS) -> TuneResult:
    """Design a compensator of the rig's structure on a model, robust over a set of models.

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
        impossible amplitude, limit, overshoot or tip bound, an unreadable or unstable model, a
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
    check_request(structure, amplitude, limit, overshoot, shaper, samples, jobs, tip_rms, filter)
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
        # the bar on the design model: settle no later than the thesis's compensator there
        problem = Problem(space, rs.models, float(amplitude), req, bar_s=baseline[0].settling_2pct_s,
                          tip_bounds=bounds)
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
                      time.perf_counter() - t0, executor, seed, tip_rms, bounds, tradeoff)


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
