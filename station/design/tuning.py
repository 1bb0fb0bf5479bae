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
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from threadpoolctl import threadpool_limits

from station.control.designs import CompensatorFile
from station.design.evaluate import Figures, Requirements, friction_held, held_error, judge, violations
from station.design.executor import open_runner
from station.design.hold import design_model_warning, held_summary
from station.design.linear import Margins, loop_model
from station.design.robust import DEFAULT_SAMPLES, SEED, RobustSet, robust_set
from station.design.search import Budget, Problem, judge_points, search
from station.design.space import SHAPERS, STRUCTURES, DesignSpace, thesis_compensator
from station.errors import StationError
from station.plant.modes import modal_summary

DEFAULT_AMPLITUDE = {"p": 50.0, "lead": 100.0, "lead-accel": 200.0}
"""Default step height per structure, encoder counts: the rig's three experiments (thesis)."""

METRICS = ("overshoot_pct", "settling_2pct_s", "settling_thesis_s", "peak_command", "saturated_s")
"""DESIGN.md's metrics, in the JSON's order."""


def check_request(structure: str, amplitude: float, limit: float, overshoot: float, shaper: str,
                  samples: int, jobs: int) -> None:
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

    Raises
    ------
    StationError
    """
    if structure not in STRUCTURES:
        raise StationError(f"--controller {structure}: expected one of {', '.join(STRUCTURES)}")
    if shaper not in SHAPERS:
        raise StationError(f"--shaper {shaper}: expected one of {', '.join(SHAPERS)}")
    checks = (("--amplitude", amplitude, lambda x: x != 0 and abs(x) <= 2048, "a step of 1..2048 encoder counts"),
              ("--limit", limit, lambda x: 0 < x <= 255, "0 < limit <= 255 DAC counts"),
              ("--overshoot", overshoot, lambda x: 0 <= x <= 100, "0..100 %"),
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
    """
    ms = modal_summary(model.linear_params(), model.n_elements)
    return float(ms.antiresonances_hz[0]), float(ms.antiresonance_damping[0])


@dataclass
class TuneResult:
    """A tuned compensator and the evidence for it.

    Attributes
    ----------
    space : DesignSpace
    values : dict
        The design's parameters (:attr:`DesignSpace.parameters`' names).
    file : CompensatorFile
        The compensator file (its path is where it is to be written).
    robust : RobustSet
    figures, baseline : list of Figures
        The tuned and the thesis's compensator on each model of the set (whole runs).
    requirements : Requirements
    amplitude : float
        Step height, encoder counts.
    margins, baseline_margins : Margins
        python-control's margins of the tuned and the thesis's loop on the nominal model.
    evaluations : int
        Designs judged on models by the search.
    elapsed_s : float
    executor : str
        Where the evaluations ran.
    seed : int
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
    verification: Any = field(default=None)

    @property
    def nominal(self):
        """The design model."""
        return self.robust.models[0]

    def met(self) -> list[bool]:
        """Per model: every requirement met."""
        return [not violations(f, self.requirements) for f in self.figures]

    def warnings(self) -> list[str]:
        """One line each: what the user must know about the design beyond its figures (friction
        holding the hub outside the 2 % band on the design model, :mod:`station.design.hold`)."""
        held = design_model_warning(self.space, self.values, self.nominal, self.figures[0], self.requirements)
        return [] if held is None else [held]

    def design_json(self) -> dict:
        """The ``design`` block: structure, parameters, compensator, requirements, search, warnings."""
        comp = self.file.compensator()
        spec = {k: comp.spec[k] for k in ("gth", "ga", "limit") if k in comp.spec}
        if "shaper" in comp.spec:
            spec["shaper"] = comp.spec["shaper"]
        units = {p.name: p.unit for p in self.space.parameters}
        return {"structure": self.space.structure, "shaper": self.space.shaper, "amplitude": self.amplitude,
                "limit": self.space.limit,
                "parameters": {k: {"value": v, "unit": units[k]} for k, v in self.values.items()},
                "mode": None if self.space.mode is None else {"f_hz": self.space.mode[0], "zeta": self.space.mode[1]},
                "compensator": spec, "requirements": self.requirements._asdict(),
                "objective": f"lexicographic: every requirement met on the design model first, settling there no "
                             f"later than the thesis's compensator; then the worst "
                             f"2 % settling time over the {len(self.robust.models)} model(s) (+1 % of the mean), "
                             f"a model where a requirement is not met adding its cost, and a model where friction "
                             f"holds the hub outside the 2 % band (nothing else failing) counting with the settling "
                             f"time into the band it holds, charged for the held error",
                "feasible": all(self.met()), "margins": _margins_json(self.margins),
                "evaluations": self.evaluations, "elapsed_s": round(self.elapsed_s, 3), "executor": self.executor,
                "seed": self.seed, "warnings": self.warnings()}

    def to_json(self, controller: str | Path | None = None) -> dict:
        """DESIGN.md's JSON: controller, design, model, robust, baseline (and verification).

        Parameters
        ----------
        controller : str or Path, optional
            The written compensator file (None: not written).
        """
        nominal = self.nominal
        doc = {"controller": None if controller is None else str(controller),
               "design": self.design_json(),
               "model": {"name": nominal.name, "effects": nominal.effect_dict(), **self.figures[0].to_json()},
               "robust": robust_json(self.robust, self.figures, self.baseline, self.requirements),
               "baseline": {"controller": f"{self.space.structure} (thesis)", **self.baseline[0].to_json(),
                            "margins": _margins_json(self.baseline_margins),
                            "robust": _spread(self.baseline)}}
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


def robust_json(rs: RobustSet, figures, baseline, req: Requirements) -> dict:
    """The ``robust`` block: worst case and spread of the tuned compensator over the set,
    per model with the thesis's beside it, and the models where friction holds the hub outside
    the 2 % band (``friction_held``: :func:`station.design.hold.held_summary`; per model
    ``held_error_counts``, ``held_band_counts``, ``settling_held_s``, None where it is not held).

    Parameters
    ----------
    rs : RobustSet
    figures, baseline : sequence of Figures
        Tuned and thesis, one per model.
    req : Requirements
    """
    per_model = []
    ratios = []
    for m, lab, f, b in zip(rs.models, rs.labels, figures, baseline):
        ratio = None
        if f.settling_2pct_s is not None and b.settling_2pct_s:
            ratio = round(f.settling_2pct_s / b.settling_2pct_s, 4)
            ratios.append(ratio)
        held = friction_held(f, req)
        per_model.append({"label": lab, "name": m.name, "effects": m.effect_dict(), **f.to_json(),
                          "requirements_met": not violations(f, req), "baseline_settling_2pct_s":
                          b.to_json()["settling_2pct_s"], "settling_ratio_to_baseline": ratio,
                          "held_error_counts": held_error(f) if held else None,
                          "held_band_counts": f.rest_band if held else None,
                          "settling_held_s": f.settling_rest_s if held else None})
    out = _spread(figures)
    out.update({"all_met": all(p["requirements_met"] for p in per_model), "friction_held": held_summary(figures, req),
                "settling_ratio_to_baseline": [min(ratios), max(ratios)] if ratios else None,
                "intervals": {k: list(v) for k, v in rs.intervals.items()}, "per_model": per_model})
    return out


def tune(model=None, structure: str = "lead-accel", amplitude: float | None = None, limit: float = 200.0,
         overshoot: float = 5.0, shaper: str = "opt", robust: Sequence[str | Path] = (),
         samples: int = DEFAULT_SAMPLES, jobs: int = 1, scheduler: str | None = None,
         out: str | Path = "tuned.toml", budget: Budget = Budget(), seed: int = SEED,
         progress: Callable[[str], None] | None = None) -> TuneResult:
    """Design a compensator of the rig's structure on a model, robust over a set of models.

    Parameters
    ----------
    model : Model, str, Path or None
        The design model (:func:`station.design.robust.robust_set`).
    structure : {"p", "lead", "lead-accel"}
        The compensator's structure (:mod:`station.design.space`).
    amplitude : float, optional
        Step height, encoder counts (default :data:`DEFAULT_AMPLITUDE` of the structure).
    limit : float
        The compensator's clamp, DAC counts (0 < limit ≤ 255).
    overshoot : float
        Largest overshoot, % (≥ 0).
    shaper : {"none", "zv", "zvd", "opt"}
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

    Returns
    -------
    TuneResult

    Raises
    ------
    StationError
        Bad input (checked before any work): an unknown structure or shaper, an impossible
        amplitude, limit or overshoot, an unreadable or unstable model, a JSON with no model,
        an unreachable scheduler.
    """
    t0 = time.perf_counter()
    amplitude = DEFAULT_AMPLITUDE.get(structure, 100.0) if amplitude is None else amplitude
    check_request(structure, amplitude, limit, overshoot, shaper, samples, jobs)
    rs = robust_set(model, robust, samples, seed)
    nominal = rs.models[0]
    space = DesignSpace(structure, shaper, float(limit), first_mode(nominal) if shaper in ("zv", "zvd") else None)
    req = Requirements(overshoot_pct=float(overshoot))
    say = progress or (lambda msg: None)
    thesis = thesis_compensator(structure, limit)
    everyone = list(range(len(rs.models)))
    with threadpool_limits(limits=1, user_api="blas"), open_runner(jobs, scheduler) as runner:
        say(f"{structure}, step {amplitude:g}, {len(rs.models)} model(s), evaluations in {runner.where}")
        baseline = [judge(m, thesis, float(amplitude)) for m in rs.models] if len(rs.models) < 2 else \
            [f for part in runner.map(_judge_thesis, [(m, structure, limit, float(amplitude)) for m in rs.models])
             for f in part]
        # the bar on the design model: settle no later than the thesis's compensator there
        problem = Problem(space, rs.models, float(amplitude), req, bar_s=baseline[0].settling_2pct_s)
        result = search(problem, runner, budget, seed, say)
        values = space.values(result.best.x)
        final = runner.map(judge_points, [(problem._replace(requirements=None), [result.best.x], everyone)])[0][0]
        executor = runner.where
    file = space.compensator_file(values, name=f"tuned {structure}", path=out)
    lm = loop_model(nominal)
    return TuneResult(space, values, file, rs, list(final), baseline, req, float(amplitude),
                      lm.margins_control(file.compensator()), lm.margins_control(thesis), result.evaluations,
                      time.perf_counter() - t0, executor, seed)


def _judge_thesis(model, structure: str, limit: float, amplitude: float) -> list[Figures]:
    """The thesis's compensator on one model (a task)."""
    return [judge(model, thesis_compensator(structure, limit), amplitude)]
