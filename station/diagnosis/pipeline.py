"""Model diagnosis: what the model gets wrong on measured runs, which effect causes it,
the extended model, and the gain on runs it was not fitted to (DESIGN.md "Model
diagnosis contract", issue 8).

Method (the vocabulary of MATLAB's System Identification Toolbox: ``compare``, ``resid``,
grey-box estimation with physical parameters and bounds, honest validation data):

1. Every run is simulated as the rig ran it (:func:`station.modelrun.simulate_log`: the
   log's controller, reference, clamp, detected alignment and command quantization; the
   logged v in open loop).
2. The cost of a model on a set of runs judges θ and a together, each error normalised by
   its own noise level: J = Σ_runs (‖e_θ‖²/σ_θ² + ‖e_a‖²/σ_a²) / Σ 2N, with σ_θ the
   encoder's quantization (1/√12 counts) or more and σ_a ≥ 0.3 counts, both estimated from
   the high-frequency part of the nominal model's residual
   (:func:`station.analysis.residuals.noise_std`). A perfect model has J ≈ 1.
3. Each candidate effect is fitted on the fit runs (grid bracketing, then local
   refinement: :mod:`station.analysis.fitting`) and judged on runs it was not fitted to:
   the ``validate`` runs, or leave-one-run-out over the runs.
4. Acceptance (forward selection, at most three effects, joint refit of all accepted
   effects at each step): the pooled validation cost must fall by at least
   :data:`MIN_RELATIVE_GAIN` (parsimony: an effect must pay for itself) and by at least
   :data:`MIN_NOISE_GAIN` noise variances per sample, both measured from the lower of the
   current model's cost and the cost that tiny perturbations of it reach by luck
   (:data:`NULL_PERTURBATIONS`: quantization and noise alone); otherwise the answer is
   "none".
5. The reported values are refitted on all fit runs.
"""

from __future__ import annotations

import math
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from station.analysis.fit import nrmse_fit
from station.analysis.fitting import Axis, axis_for, fit
from station.analysis.metrics import step_metrics
from station.analysis.residuals import (
    ACCEL_NOISE_STD,
    THETA_QUANTIZATION_STD,
    RunResiduals,
    noise_std,
    run_residuals,
)
from station.errors import StationError
from station.reference import classify_reference

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

Simulator = Callable[["RunCase", Any], tuple[np.ndarray, np.ndarray]]
"""``simulate(case, model) -> (theta, a)``: a run's simulated θ and a on a model."""


@dataclass
class RunCase:
    """One measured run, ready to be simulated as the rig ran it.

    Attributes
    ----------
    path : str
    log : station.runlog.RunLog
    controller : Compensator, OpenLoop or None
        The log's controller (None: driven by the logged v).
    alignment : int or None
        Detected computational delay d (None for open loop).
    closed : bool
        Closed-loop run.
    theta, a : ndarray, shape (N,)
        Measured θ (encoder counts; relative to its first sample in open loop) and a
        (accelerometer counts, its at-rest offset before the first command removed).
    sigma_theta, sigma_a : float
        Noise levels the errors are normalised by, counts.
    notes : list of str
    """

    path: str
    log: Any
    controller: Any
    alignment: int | None
    closed: bool
    theta: np.ndarray
    a: np.ndarray
    sigma_theta: float = THETA_QUANTIZATION_STD
    sigma_a: float = ACCEL_NOISE_STD
    notes: list = field(default_factory=list)

    @property
    def n(self) -> int:
        return int(self.theta.size)

    @property
    def name(self) -> str:
        return Path(self.path).name

    @property
    def kind(self) -> str:
        """The controller's name ("p", "lead", "lead-accel", "open-loop", ...)."""
        return getattr(self.controller, "name", None) or ("open-loop" if not self.closed else "unknown")


def load_case(path: str | Path) -> RunCase:
    """Read a log and find how the rig ran it (controller, alignment).

    Parameters
    ----------
    path : str or Path
        A run log (any format :func:`station.runlog.read_log` reads).

    Raises
    ------
    StationError
        Unreadable log (:class:`station.runlog.RunLogError`), a log without rows, or a
        malformed controller in its header.
    """
    from station.control import OpenLoop
    from station.replay import detect_alignment, log_controller
    from station.runlog import read_log

    log = read_log(path)
    if len(log) < 50:
        raise StationError(f"{path}: {len(log)} rows; a diagnosis needs a run of at least 50 samples")
    controller, notes = log_controller(log)
    data = log.data
    closed = controller is not None and not isinstance(controller, OpenLoop)
    alignment = None
    if closed:
        alignment, dv, _ = detect_alignment(controller, data["u"], data["theta"], data["a"], data["v"])
        if dv > 1e-3:
            notes.append(f"the log's controller does not reproduce its v (max |dv| = {dv:.3g} counts)")
    elif controller is None:
        notes.append("the log does not name its controller: the model is driven by the logged v")
    theta = np.asarray(data["theta"], float)
    if not closed:
        theta = theta - theta[0]
    a = np.asarray(data["a"], float)
    moving = np.flatnonzero(np.asarray(data["v"], float) != 0)
    rest = int(moving[0]) if moving.size else a.size
    offset = float(np.mean(a[:rest])) if rest >= 5 else 0.0
    if abs(offset) >= 0.5:
        notes.append(f"accelerometer offset {offset:.2f} counts at rest (before the first command) removed")
        a = a - offset
    return RunCase(str(path), log, controller, alignment, closed, theta, a, notes=notes)


def simulate_case(case: RunCase, model) -> tuple[np.ndarray, np.ndarray]:
    """θ and a of a run simulated on a model as the rig ran it (:func:`station.modelrun.simulate_log`).

    Parameters
    ----------
    case : RunCase
        The run (:func:`load_case`).
    model : Model
        The model to simulate it on.
    """
    from station.modelrun import simulate_log

    run = simulate_log(case.log, case.controller, case.alignment, model)
    return run.prediction["theta"], run.prediction["a"]


def _key(effects: Mapping[str, float]) -> tuple:
    return tuple(sorted((k, float(f"{v:.10g}")) for k, v in effects.items()))


class Evaluator:
    """Simulates runs on the base model with effects and caches their squared errors.

    Parameters
    ----------
    cases : list of RunCase
    model : station.plant.model.Model
        The nominal model; effects are applied with ``model.with_effects``.
    simulate : callable, optional
        ``simulate(case, model) -> (theta, a)``, default :func:`simulate_case`.

    Attributes
    ----------
    simulations : int
        Runs simulated so far (cache misses).
    """

    def __init__(self, cases: Sequence[RunCase], model, simulate: Simulator | None = None):
        self.cases = list(cases)
        self.model = model
        self.simulate = simulate or simulate_case
        self.simulations = 0
        self._cache: dict[tuple, tuple[float, float]] = {}
        self._lock = threading.Lock()

    def model_with(self, effects: Mapping[str, float]):
        """The base model with ``effects`` applied (the base model itself for none).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value (:data:`station.plant.effects.EFFECTS`).
        """
        return self.model.with_effects(effects) if effects else self.model

    def predict(self, effects: Mapping[str, float], i: int) -> tuple[np.ndarray, np.ndarray]:
        """Simulated θ and a of run i (not cached).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model.
        i : int
            Index of the run in ``cases``.
        """
        with self._lock:
            self.simulations += 1
        return self.simulate(self.cases[i], self.model_with(effects))

    def sse(self, effects: Mapping[str, float], i: int) -> tuple[float, float]:
        """Sum of squared θ and a errors of run i, counts² (inf when the simulation diverges).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model.
        i : int
            Index of the run in ``cases``.
        """
        key = (_key(effects), i)
        hit = self._cache.get(key)
        if hit is None:
            try:
                theta, a = self.predict(effects, i)
            except (ArithmeticError, ValueError, np.linalg.LinAlgError):  # a model that cannot be built or run
                self._cache[key] = hit = (math.inf, math.inf)
                return hit
            c = self.cases[i]
            with np.errstate(all="ignore"):
                st = float(np.sum((c.theta - theta) ** 2))
                sa = float(np.sum((c.a - a) ** 2))
            hit = (st if math.isfinite(st) else math.inf, sa if math.isfinite(sa) else math.inf)
            self._cache[key] = hit
        return hit

    def weighted(self, effects: Mapping[str, float], i: int) -> float:
        """‖e_θ‖²/σ_θ² + ‖e_a‖²/σ_a² of run i.

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model.
        i : int
            Index of the run in ``cases``.
        """
        st, sa = self.sse(effects, i)
        c = self.cases[i]
        return st / c.sigma_theta ** 2 + sa / c.sigma_a ** 2

    def cost(self, effects: Mapping[str, float], runs: Sequence[int]) -> float:
        """Normalised cost J over runs (1 ≈ the noise floor).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model.
        runs : sequence of int
            Indices of the runs in ``cases``.
        """
        total = sum(self.weighted(effects, i) for i in runs)
        return total / sum(2 * self.cases[i].n for i in runs)


@dataclass(frozen=True)
class Fold:
    """Fit on ``fit``, judge on ``val`` (run indices).

    Attributes
    ----------
    fit : tuple of int
        Runs the effects are fitted on.
    val : tuple of int
        Runs they are judged on.
    """

    fit: tuple
    val: tuple


@dataclass
class _Trial:
    """A set of effects fitted per fold and judged on the folds' validation runs."""

    names: tuple
    fold_values: list            # per fold: {name: value}
    val_sse: dict                # run index -> (sse_theta, sse_a) of its held-out prediction
    val_weighted: float          # Σ weighted errors over validation runs


@dataclass(frozen=True)
class EffectResult:
    """One candidate effect in a diagnosis.

    Attributes
    ----------
    name, unit : str
        As in the vocabulary (station.plant.effects.EFFECTS).
    value : float
        In the extended (joint) model when accepted, else fitted alone on all fit runs.
    gain_pct : float
        θ RMS gain on the validation data of the nominal model plus this effect alone, %.
    cost_gain_pct : float
        Gain of the joint θ + a cost (noise-normalised) of that model, %.
    accepted : bool
    evidence : str
        In words: the fit, the gains and the signatures that point to it.
    fold_values : list of float
        The value fitted alone in each fold.
    """

    name: str
    value: float
    unit: str
    gain_pct: float
    cost_gain_pct: float
    accepted: bool
    evidence: str
    fold_values: list = field(default_factory=list)

    def to_json(self) -> dict:
        value = self.value if math.isfinite(self.value) else None
        return {"name": self.name, "value": value, "unit": self.unit, "gain_pct": round(self.gain_pct, 3),
                "evidence": self.evidence, "accepted": self.accepted,
                "cost_gain_pct": round(self.cost_gain_pct, 3),
                "fold_values": [v if math.isfinite(v) else None for v in self.fold_values]}


@dataclass
class RunReport:
    """One run in a diagnosis: measured, nominal and extended side by side.

    Attributes
    ----------
    file : str
    role : {"validation", "fit"}
        Judged on ("validation": held out in leave-one-run-out, or a --validate run).
    controller : str
    alignment : int or None
    t, u, v, theta, a : ndarray
        Measured (θ relative in open loop; a without its at-rest offset).
    nominal, extended, final : dict of ndarray
        θ and a of the nominal model, of the extended model as fitted without this run
        (validation runs; the final model for fit runs) and of the final extended model.
    fit_nominal, fit_extended : dict
        NRMSE fits {"theta", "accel"}, %.
    gain_pct : float
        θ RMS gain of ``extended`` over ``nominal``, %.
    residuals_before, residuals_after : RunResiduals
    metrics : dict of StepMetrics or None
        "rig", "nominal", "extended" (final model), for closed-loop step runs.
    notes : list of str
    """

    file: str
    role: str
    controller: str
    alignment: int | None
    t: np.ndarray = field(repr=False)
    u: np.ndarray = field(repr=False)
    v: np.ndarray = field(repr=False)
    theta: np.ndarray = field(repr=False)
    a: np.ndarray = field(repr=False)
    nominal: dict = field(repr=False)
    extended: dict = field(repr=False)
    final: dict = field(repr=False)
    fit_nominal: dict = field(default_factory=dict)
    fit_extended: dict = field(default_factory=dict)
    gain_pct: float = 0.0
    residuals_before: RunResiduals | None = field(default=None, repr=False)
    residuals_after: RunResiduals | None = field(default=None, repr=False)
    metrics: dict | None = None
    notes: list = field(default_factory=list)

    def to_json(self) -> dict:
        m = None if self.metrics is None else {k: (None if v is None else v.to_json()) for k, v in self.metrics.items()}
        return {"file": self.file, "role": self.role, "controller": self.controller, "alignment": self.alignment,
                "baseline": {"fit_pct": self.fit_nominal}, "extended": {"fit_pct": self.fit_extended},
                "gain_pct": round(self.gain_pct, 3), "metrics": m,
                "signatures_before": self.residuals_before.signatures() if self.residuals_before else [],
                "signatures_after": self.residuals_after.signatures() if self.residuals_after else [],
                "notes": list(self.notes)}


@dataclass
class Diagnosis:
    """The result of :func:`diagnose` (DESIGN.md "Model diagnosis contract").

    Attributes
    ----------
    cause : str
        The best accepted effect, or "none".
    causes : list of str
        Accepted effects in the order forward selection added them.
    baseline_fit, extended_fit : dict
        NRMSE fit {"theta", "accel"} (%) over all validation samples pooled, of the
        nominal and the extended model.
    gain_pct : float
        100 (1 − RMS_ext/RMS_nom) of the θ error over all validation samples pooled.
    effects : list of EffectResult
        Every candidate evaluated, once, best first (accepted ones first).
    extended_model : station.plant.model.Model
        The nominal model plus the accepted effects, refitted on all fit runs.
    nominal_model : station.plant.model.Model
    runs : list of RunReport
    validation : str
        "leave-one-run-out" or "validation runs".
    simulations : int
        Runs simulated (the cost of the diagnosis).
    elapsed_s : float
    cost_gain_pct : float
        Gain of the joint noise-normalised θ + a cost on the validation data, %.
    folds : list of dict
        Per fold: fit and validation run names and the accepted effects' values.
    """

    cause: str
    causes: list
    baseline_fit: dict
    extended_fit: dict
    gain_pct: float
    effects: list
    extended_model: Any
    nominal_model: Any
    runs: list
    validation: str
    simulations: int = 0
    elapsed_s: float = 0.0
    cost_gain_pct: float = 0.0
    folds: list = field(default_factory=list)

    def to_json(self) -> dict:
        """DESIGN.md's JSON: cause, causes, baseline, extended, gain_pct, effects (+ extras:
        validation, model, extended_model, runs, simulations, elapsed_s)."""
        return {
            "cause": self.cause,
            "causes": list(self.causes),
            "baseline": {"fit_pct": dict(self.baseline_fit)},
            "extended": {"fit_pct": dict(self.extended_fit)},
            "gain_pct": round(self.gain_pct, 3),
            "effects": [e.to_json() for e in self.effects],
            "validation": self.validation,
            "cost_gain_pct": round(self.cost_gain_pct, 3),
            "model": self.nominal_model.name,
            "extended_model": self.extended_model.to_json(),
            "runs": [r.to_json() for r in self.runs],
            "folds": self.folds,
            "simulations": self.simulations,
            "elapsed_s": round(self.elapsed_s, 3),
        }


# --- the search ---------------------------------------------------------------------------

def _axes() -> dict[str, Axis]:
    from station.plant.effects import EFFECTS

    return {name: axis_for(name, s.lower, s.upper, s.neutral) for name, s in EFFECTS.items()}


def _fit_set(ev: Evaluator, axes: list[Axis], runs: Sequence[int], start: Mapping[str, float]) -> dict:
    res = fit(lambda vals: ev.cost(vals, runs), axes, start=start)
    return res.values


def _trial(ev: Evaluator, folds: Sequence[Fold], names: tuple, axes: dict, starts: Sequence[Mapping]) -> _Trial:
    fold_values, val_sse, total = [], {}, 0.0
    for fold, start in zip(folds, starts):
        values = _fit_set(ev, [axes[n] for n in names], fold.fit, start)
        fold_values.append(values)
        for i in fold.val:
            val_sse[i] = ev.sse(values, i)
            total += ev.weighted(values, i)
    return _Trial(names, fold_values, val_sse, total)


def _screen(ev: Evaluator, axes: dict, names: Sequence[str], fixed: Mapping[str, float],
            runs: Sequence[int]) -> list[str]:
    """The effects worth a joint trial beside the accepted ones: each scanned on its grid
    with the accepted effects fixed (all fit runs); the best :data:`SECOND_STEP_CANDIDATES`
    that lower the cost, best first. An effect that did not pay alone may pay beside another."""
    c0 = ev.cost(fixed, runs)
    best = {}
    for n in names:
        best[n] = min(ev.cost({**fixed, n: float(g)}, runs) for g in axes[n].grid())
    keep = sorted((n for n in names if best[n] < c0), key=best.get)
    return keep[:SECOND_STEP_CANDIDATES]


def _pooled(ev: Evaluator, val_sse: Mapping[int, tuple]) -> dict:
    """Pooled θ RMS and NRMSE fits over validation runs."""
    idx = sorted(val_sse)
    n = sum(ev.cases[i].n for i in idx)
    st = sum(val_sse[i][0] for i in idx)
    sa = sum(val_sse[i][1] for i in idx)
    th = np.concatenate([ev.cases[i].theta for i in idx])
    ac = np.concatenate([ev.cases[i].a for i in idx])
    dt_, da_ = np.sum((th - th.mean()) ** 2), np.sum((ac - ac.mean()) ** 2)
    fit_t = 100.0 * (1 - math.sqrt(st / dt_)) if dt_ > 0 and math.isfinite(st) else None
    fit_a = 100.0 * (1 - math.sqrt(sa / da_)) if da_ > 0 and math.isfinite(sa) else None
    return {"rms_theta": math.sqrt(st / n) if n else math.nan, "theta": fit_t, "accel": fit_a}


def _gain(rms_ext: float, rms_nom: float) -> float:
    if not (math.isfinite(rms_ext) and rms_nom > 0):
        return -math.inf if not math.isfinite(rms_ext) else 0.0
    return 100.0 * (1.0 - rms_ext / rms_nom)


NULL_PERTURBATIONS = (("accel_gain", 0.996), ("accel_gain", 0.998), ("accel_gain", 1.002), ("accel_gain", 1.004),
                      ("param:act_K", 0.998), ("param:act_K", 1.002), ("param:EI", 0.998), ("param:EI", 1.002))
"""Perturbations of the current model far too small to be a cause (0.2-0.4 %): what they
change in the validation cost is what quantization and noise alone do (e.g. the rounding
of θ and a, and in an accelerometer-feedback loop the measured noise, send a closed loop
along another path)."""


def _null_floor(ev: Evaluator, folds: Sequence[Fold], fold_values: Sequence[Mapping[str, float]]) -> float:
    """The validation cost reached by luck alone: per validation run the lowest weighted
    error over :data:`NULL_PERTURBATIONS` of the current model (as fitted per fold), summed."""
    from station.plant.effects import EFFECTS

    total = 0.0
    for fold, values in zip(folds, fold_values):
        for i in fold.val:
            best = ev.weighted(values, i)
            for name, factor in NULL_PERTURBATIONS:
                v = values.get(name, EFFECTS[name].neutral) * factor
                best = min(best, ev.weighted({**values, name: v}, i))
            total += best
    return total


def _rel_gain(v1: float, v0: float) -> float:
    """100 (1 − v1/v0), % (0 when v0 is 0: a model that is already exact)."""
    return 100.0 * (1.0 - v1 / v0) if v0 > 0 else 0.0


def _accept(v0: float, v1: float, terms: int, floor: float | None = None) -> bool:
    """Pays on validation data beyond parsimony and noise (module docstring, step 4).

    v0, v1: validation cost of the current model and with the candidate; floor: what luck
    alone reaches around the current model (:func:`_null_floor`), the reference when lower.
    """
    if not math.isfinite(v1) or v0 <= 0:
        return False
    ref = v0 if floor is None else min(v0, floor)
    return (1.0 - v1 / ref) >= MIN_RELATIVE_GAIN and (ref - v1) / terms >= MIN_NOISE_GAIN


def _fmt(x: float, unit: str) -> str:
    if not math.isfinite(x):
        return "∞"
    s = f"{x:.0f}" if unit == "samples" else f"{x:.3g}"
    return s + ("" if unit == "1" else f" {unit}")


SIGNATURE_WORDS = {
    "coulomb_friction": ("sticks", "steady-state"),
    "deadzone": ("sticks", "steady-state"),
    "backlash": ("sticks", "steady-state"),
    "delay": ("lagging",),
    "saturation": ("× the model",),
    "beam_damping": ("decays",),
    "param:clamp_c": ("decays",),
    "accel_gain": (),
}
"""Which residual signatures speak for which effect (words of RunResiduals.signatures)."""


def _signature_evidence(name: str, before: Mapping[str, RunResiduals]) -> str:
    words = SIGNATURE_WORDS.get(name, ("Hz", "× the model"))
    found = []
    for file, res in before.items():
        for s in res.signatures():
            if any(w in s for w in words):
                found.append(f"{file}: {s}")
    return "; ".join(found[:3])


# --- diagnose -------------------------------------------------------------------------------

def diagnose(runs: Sequence[str | Path], validate: Sequence[str | Path] = (), model=None,
             progress: Callable[[str], None] | None = None, candidates: Sequence[str] | None = None,
             simulate: Simulator | None = None, workers: int | None = None) -> Diagnosis:
    """Find what the model gets wrong on measured runs, name the cause and measure the gain.

    Parameters
    ----------
    runs : sequence of path
        Run logs (ours or the rig's) the candidates are fitted on.
    validate : sequence of path, optional
        Runs they are judged on. Without them: leave-one-run-out over ``runs`` (at least two).
    model : Model, str, Path or None
        The nominal model (:func:`station.plant.model.as_model`; None: "tmm-fit").
    progress : callable, optional
        Called with one line of text per step of a long fit (the CLI prints it to stderr).
    candidates : sequence of str, optional
        Effect names to try (default :data:`station.plant.effects.CANDIDATES`).
    simulate : callable, optional
        ``simulate(case, model) -> (theta, a)`` (default: :func:`simulate_case`); tests
        plug in their own.
    workers : int, optional
        Threads fitting candidates at once (default 1). The compiled sample loop releases
        the GIL but building models and scoring runs hold it: on 2 shared cores two
        threads were slower (the rig's four logs: 10.7 s with one, 17.0 s with two,
        scripts/bench_diagnose.py at load average 3).

    Returns
    -------
    Diagnosis

    Raises
    ------
    StationError
        One run without ``validate``, an unreadable or empty log, a bad model, or an
        unknown candidate.
    """
    from threadpoolctl import threadpool_limits

    # the matrices are tiny (22 x 22): BLAS threads only contend with each other and the
    # compiled sample loop (measured 3x slower on a loaded 2-core machine)
    with threadpool_limits(limits=1, user_api="blas"):
        return _diagnose(runs, validate, model, progress, candidates, simulate, workers)


def _diagnose(runs, validate, model, progress, candidates, simulate, workers) -> Diagnosis:
    from station.plant.effects import CANDIDATES, EFFECTS
    from station.plant.model import as_model

    t0 = time.perf_counter()
    say = progress or (lambda msg: None)
    runs, validate = list(runs), list(validate)
    if not runs:
        raise StationError("diagnose: no runs given")
    if not validate and len(runs) < 2:
        raise StationError(f"diagnose: leave-one-run-out needs at least two runs, got one ({runs[0]}); "
                           "give more runs or --validate RUN")
    base = as_model(model)
    names = list(CANDIDATES if candidates is None else candidates)
    for n in names:
        if n not in EFFECTS:
            raise StationError(f"diagnose: unknown candidate effect '{n}' (known: {', '.join(EFFECTS)})")
    workers = max(1, int(workers or 1))
    axes = _axes()
    cases = [load_case(p) for p in runs + validate]
    ev = Evaluator(cases, base, simulate)
    fit_idx = tuple(range(len(runs)))
    if validate:
        folds = [Fold(fit_idx, tuple(range(len(runs), len(cases))))]
        how = "validation runs"
    else:
        folds = [Fold(tuple(j for j in fit_idx if j != i), (i,)) for i in fit_idx]
        how = "leave-one-run-out"

    # noise levels from the nominal residual's high-frequency part
    nominal_pred = {}
    for i, c in enumerate(cases):
        theta, a = ev.predict({}, i)
        nominal_pred[i] = (theta, a)
        c.sigma_theta = noise_std(c.theta - theta, THETA_QUANTIZATION_STD)
        c.sigma_a = noise_std(c.a - a, ACCEL_NOISE_STD)
    val_idx = sorted({i for f in folds for i in f.val})
    terms = sum(2 * cases[i].n for i in val_idx)
    nominal_sse = {i: ev.sse({}, i) for i in val_idx}
    v_nom = sum(ev.weighted({}, i) for i in val_idx)
    pooled_nom = _pooled(ev, nominal_sse)
    say(f"nominal model {base.name}: θ fit {pooled_nom['theta']:.1f} %, θ RMS {pooled_nom['rms_theta']:.2f} counts "
        f"on {len(val_idx)} validation run(s) ({how})")

    # step 1: every candidate alone
    single: dict[str, _Trial] = {}
    single_all: dict[str, dict] = {}
    def alone(name):
        tr = _trial(ev, folds, (name,), axes, [{}] * len(folds))
        return tr, (tr.fold_values[0] if validate else _fit_set(ev, [axes[name]], fit_idx, {}))

    with ThreadPoolExecutor(workers) as pool:
        for k, (name, (tr, values)) in enumerate(zip(names, pool.map(alone, names)), 1):
            single[name], single_all[name] = tr, values
            g = _gain(_pooled(ev, tr.val_sse)["rms_theta"], pooled_nom["rms_theta"])
            say(f"[{k}/{len(names)}] {name} = {_fmt(values[name], EFFECTS[name].unit)}: "
                f"validation θ gain {g:.1f} %, cost gain {_rel_gain(tr.val_weighted, v_nom):.1f} % "
                f"({ev.simulations} simulations)")

    # forward selection with joint refits
    accepted: list[str] = []
    current = _Trial((), [{} for _ in folds], nominal_sse, v_nom)
    order = sorted(names, key=lambda n: single[n].val_weighted)
    final_values: dict[str, float] = {}
    for step in range(MAX_EFFECTS):
        if step == 0:
            trials = {n: single[n] for n in names}
        else:
            pool = _screen(ev, axes, [n for n in names if n not in accepted], final_values, fit_idx)
            say(f"step {step + 1}: screening beside {' + '.join(accepted)} on all fit runs: {', '.join(pool)}")
            with ThreadPoolExecutor(workers) as ex:
                futures = {n: ex.submit(_trial, ev, folds, tuple(accepted) + (n,), axes, current.fold_values)
                           for n in pool}
            trials = {n: f.result() for n, f in futures.items()}
            for n in pool:
                say(f"step {step + 1}: {' + '.join(accepted + [n])}: validation cost gain "
                    f"{_rel_gain(trials[n].val_weighted, current.val_weighted):.1f} % over {' + '.join(accepted)} "
                    f"({ev.simulations} simulations)")
        if not trials:
            break
        best = min(trials, key=lambda n: trials[n].val_weighted)
        floor = _null_floor(ev, folds, current.fold_values)
        say(f"step {step + 1}: best {best}, validation cost {trials[best].val_weighted / terms:.3g} per sample, "
            f"current {current.val_weighted / terms:.3g}, reached by quantization and noise alone {floor / terms:.3g}")
        if not _accept(current.val_weighted, trials[best].val_weighted, terms, floor):
            break
        accepted.append(best)
        current = trials[best]
        # the values refitted on all fit runs (jointly)
        if step == 0:
            final_values = dict(single_all[best])
        else:
            final_values = _fit_set(ev, [axes[n] for n in accepted], fit_idx, final_values)
        say(f"accepted {best} (step {step + 1}): "
            + ", ".join(f"{n} = {_fmt(v, EFFECTS[n].unit)}" for n, v in final_values.items()))
    extended = base.with_effects(final_values, name=f"{base.name} + {' + '.join(accepted)}" if accepted else None)

    pooled_ext = _pooled(ev, current.val_sse)
    gain = _gain(pooled_ext["rms_theta"], pooled_nom["rms_theta"]) if accepted else 0.0
    cost_gain = _rel_gain(current.val_weighted, v_nom) if accepted else 0.0

    # per-run reports (residual analysis before and after)
    reports, before = [], {}
    fold_of = {i: f for f, fold in enumerate(folds) for i in fold.val}
    for i, c in enumerate(cases):
        role = "validation" if i in fold_of else "fit"
        ext_vals = current.fold_values[fold_of[i]] if (i in fold_of and accepted) else final_values
        nom = dict(zip(("theta", "a"), nominal_pred[i]))
        ext = dict(zip(("theta", "a"), ev.predict(ext_vals, i))) if accepted else nom
        fin = dict(zip(("theta", "a"), ev.predict(final_values, i))) if accepted else nom
        d = c.log.data
        rb = run_residuals(c.theta, c.a, nom["theta"], nom["a"], d["v"], d["u"], c.closed)
        ra = run_residuals(c.theta, c.a, ext["theta"], ext["a"], d["v"], d["u"], c.closed) if accepted else rb
        before[c.name] = rb
        metrics = None
        ref = classify_reference(d["u"])
        if c.closed and ref["kind"] == "step":
            uf = float(d["u"][-1])
            metrics = {"rig": step_metrics(d["t"], d["theta"], uf), "nominal": step_metrics(d["t"], nom["theta"], uf),
                       "extended": step_metrics(d["t"], fin["theta"], uf)}

        def fits(pred):
            out = {}
            for key, meas, sim in (("theta", c.theta, pred["theta"]), ("accel", c.a, pred["a"])):
                f = nrmse_fit(meas, sim) if np.all(np.isfinite(sim)) else float("-inf")
                out[key] = None if np.isnan(f) else round(float(f), 3)
            return out

        rms_n = float(np.sqrt(np.mean((c.theta - nom["theta"]) ** 2)))
        rms_e = float(np.sqrt(np.mean((c.theta - ext["theta"]) ** 2)))
        reports.append(RunReport(c.name, role, c.kind, c.alignment, np.asarray(d["t"]), np.asarray(d["u"]),
                                 np.asarray(d["v"]), c.theta, c.a, nom, ext, fin, fits(nom), fits(ext),
                                 _gain(rms_e, rms_n) if accepted else 0.0, rb, ra, metrics, list(c.notes)))

    # the candidates, best first
    results = []
    for name in accepted + [n for n in order if n not in accepted]:
        tr = single[name]
        unit = EFFECTS[name].unit
        g = _gain(_pooled(ev, tr.val_sse)["rms_theta"], pooled_nom["rms_theta"])
        cg = _rel_gain(tr.val_weighted, v_nom)
        value = final_values[name] if name in accepted else single_all[name][name]
        folds_v = [fv[name] for fv in tr.fold_values]
        spread = f" (folds {_fmt(min(folds_v), unit)} to {_fmt(max(folds_v), unit)})" if len(folds_v) > 1 else ""
        words = [f"fitted alone {_fmt(single_all[name][name], unit)}{spread}; on {how} the nominal model plus it "
                 f"changes θ RMS {pooled_nom['rms_theta']:.2f} -> {_pooled(ev, tr.val_sse)['rms_theta']:.2f} counts "
                 f"({g:+.1f} %), the joint θ+a cost by {cg:+.1f} %"]
        if name in accepted:
            words.append(f"accepted at step {accepted.index(name) + 1} of forward selection"
                         + (f", {_fmt(value, unit)} in the joint model" if len(accepted) > 1 else ""))
        else:
            words.append("not accepted (below the significance threshold or a better effect explains the same)")
        sig = _signature_evidence(name, before)
        if sig:
            words.append(f"signatures: {sig}")
        results.append(EffectResult(name, float(value), unit, float(g), float(cg), name in accepted,
                                    "; ".join(words), [float(v) for v in folds_v]))

    say(f"done: cause {accepted[0] if accepted else 'none'}, θ gain {gain:.1f} %, {ev.simulations} simulations "
        f"in {time.perf_counter() - t0:.1f} s")
    return Diagnosis(
        cause=accepted[0] if accepted else "none", causes=accepted,
        baseline_fit={"theta": pooled_nom["theta"], "accel": pooled_nom["accel"]},
        extended_fit=({"theta": pooled_ext["theta"], "accel": pooled_ext["accel"]} if accepted
                      else {"theta": pooled_nom["theta"], "accel": pooled_nom["accel"]}),
        gain_pct=float(gain), effects=results, extended_model=extended, nominal_model=base, runs=reports,
        validation=how, simulations=ev.simulations,
        folds=[{"fit": [cases[i].name for i in f.fit], "validate": [cases[i].name for i in f.val],
                "values": dict(v)} for f, v in zip(folds, current.fold_values)], elapsed_s=time.perf_counter() - t0, cost_gain_pct=float(cost_gain))
