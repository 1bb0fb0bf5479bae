"""The cost of a model on measured runs: per-run squared θ and a errors, cached per set of
effects and counted as simulations; the noise levels that normalise them; pooled fits and
gains over validation runs.

Each run's errors are normalised by its noise levels: J_θ = ‖e_θ‖²/(N σ_θ²) and
J_a = ‖e_a‖²/(N σ_a²), with σ_θ the encoder's quantization (1/√12 counts) or more and
σ_a ≥ 0.3 counts, both estimated from the high-frequency part of the nominal model's residual
(:func:`calibrate_noise`). A perfect model has J ≈ 1.

Fits minimise J = Σ_runs (‖e_θ‖²/σ_θ² + ‖e_a‖²/σ_a²) / Σ 2N (:meth:`Evaluator.cost`), or,
as an option (``Evaluator(..., likelihood=True)``, scripts/rig_study.py's default), the
maximum-likelihood cost with an unknown error variance per run and signal, bounded below by
the noise: each run's and signal's error variance is σ² + s² with the model error s² ≥ 0
unknown; profiled out, a run and signal with J_s ≥ 1 costs N·(ln J_s + 1) and one below the
noise floor N·J_s (least squares: fitting the noise better earns nothing more), and
J = exp(Σ N·g(J_s) / Σ N − 1). Above the floor that is the geometric mean of the J_s
(Σ N·ln SSR_s up to constants): every run and signal counts by its samples however badly a
model misses it, where the arithmetic mean lets the run with the largest model error decide
(on the rig's four thesis logs the open-loop pulses carry 93 % of θ's cost and the fit
follows them: docs/diagnosis.md). At the noise floor both are least squares. Held-out
judgement is in noise variances either way (:meth:`Evaluator.weighted`, summed over
validation runs). The option is not the diagnosis's default: blind, it named a small
breakaway excess in 9 of 10 seeds where the arithmetic mean named it in 10 of 10.

Where the accelerometer's gain is a nuisance (a reversed accelerometer, its gain decided
against the nominal model: :func:`station.diagnosis.pipeline.accel_scale`), a is judged up
to each run's own least-squares scale (``Evaluator(..., accel_scale=(lo, hi))``) on the runs
whose controller does not feed it back, and the gain a model then holds is fitted over runs
pooled (:meth:`Evaluator.fit_accel_gain`).
"""

from __future__ import annotations

import itertools
import math
import threading
from contextlib import contextmanager
from collections.abc import Callable, Mapping, Sequence
from typing import NamedTuple

import numpy as np

from station.analysis.residuals import ACCEL_NOISE_STD, THETA_QUANTIZATION_STD, noise_std
from station.diagnosis.runs.cases import RunCase, Simulator, feeds_back_a, simulate_case
from station.signals import check_stop
from station.errors import StationError


def _key(effects: Mapping[str, float]) -> tuple:
    return tuple(sorted((k, float(f"{v:.10g}")) for k, v in effects.items()))


MODELS_KEPT = 1024
"""Models :meth:`Evaluator.model_with` keeps (a fit asks for the same effects on each of its runs)."""


class EvaluatorWork(NamedTuple):
    """What an evaluator did since a mark (:meth:`Evaluator.work_since`).

    Attributes
    ----------
    errors : dict
        Cache key -> (Σ θ error², Σ a error²), counts².
    simulations : int
        Runs simulated.
    """

    errors: dict
    simulations: int


class Evaluator:
    """Simulates runs on the base model with effects and caches their squared errors.

    Parameters
    ----------
    cases : list of RunCase
    model : station.plant.model.Model
        The nominal model; effects are applied with ``model.with_effects``.
    simulate : callable, optional
        ``simulate(case, model) -> (theta, a)``, default :func:`simulate_case`.
    run_effects : callable, optional
        ``run_effects(effects, i) -> effects``: the effects run i is simulated with, given
        the effects asked for (default: the same for every run). Sessions give each run
        its session's values of the effects that drift (:class:`station.diagnosis.sessions.layout.PerSession`).
    likelihood : bool
        :meth:`cost` is the maximum-likelihood cost with an unknown error variance per run
        and signal, or (default) the noise-weighted mean Σ ‖e‖²/σ² / Σ N (module docstring).
    accel_scale : (float, float), optional
        a judged up to each run's own scale, its least-squares scale bounded to this range (a
        factor on the base model's a): where the accelerometer's gain is a nuisance, a
        reversed accelerometer's decided from the data against the nominal model, which the
        search must not lean on (module docstring). Runs whose controller feeds a back (Ga)
        are judged as simulated. None (default): every run as simulated.

    Attributes
    ----------
    simulations : int
        Runs simulated so far (cache misses).
    accel_scale : (float, float) or None
        As the parameter; set to None to judge every run as simulated from then on (the
        errors are cached apart).
    """

    def __init__(self, cases: Sequence[RunCase], model, simulate: Simulator | None = None,
                 run_effects: Callable[[Mapping[str, float], int], Mapping[str, float]] | None = None,
                 likelihood: bool = False, accel_scale: tuple[float, float] | None = None):
        self.cases = list(cases)
        self.likelihood = likelihood
        self.accel_scale = accel_scale
        self.model = model
        self.simulate = simulate or simulate_case
        self.run_effects = run_effects
        self.simulations = 0
        self._cache: dict[tuple, tuple[float, float]] = {}
        self._models: dict[tuple, object] = {}  # one Model per set of effects: its linear part built once
        self._lock = threading.Lock()

    def mark(self) -> tuple[int, int]:
        """Where the evaluator's work stands: a mark for :meth:`work_since`.

        Returns
        -------
        (int, int)
            Errors cached and runs simulated so far.
        """
        return len(self._cache), self.simulations

    def work_since(self, mark: tuple[int, int]) -> EvaluatorWork:
        """The errors computed and the runs simulated since ``mark`` (a forked worker's, for
        the main process: :mod:`station.diagnosis.search.farm`).

        Parameters
        ----------
        mark : (int, int)
            From :meth:`mark`.

        Returns
        -------
        EvaluatorWork
        """
        n, sims = mark
        # the cache only grows, in insertion order: what came after the mark is new
        return EvaluatorWork(dict(itertools.islice(self._cache.items(), n, None)), self.simulations - sims)

    def take_in(self, work: EvaluatorWork) -> None:
        """Add another process's work (:meth:`work_since`): its errors join the cache, its
        simulations the count.

        Parameters
        ----------
        work : EvaluatorWork
        """
        self._cache.update(work.errors)
        self.simulations += work.simulations

    def model_with(self, effects: Mapping[str, float]):
        """The base model with ``effects`` applied (the base model itself for none).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value (:data:`station.plant.effects.EFFECTS`).

        Returns
        -------
        station.plant.model.Model
            The base model with the effects applied.

        Raises
        ------
        StationError
            An unknown effect or a value out of its range (:meth:`station.plant.model.Model.with_effects`).
        """
        if not effects:
            return self.model
        key = tuple(sorted(effects.items()))  # exact values: the model is what is simulated
        model = self._models.get(key)
        if model is None:
            if len(self._models) >= MODELS_KEPT:
                self._models.clear()
            model = self._models[key] = self.model.with_effects(effects)
        return model

    def effects_for(self, effects: Mapping[str, float], i: int) -> Mapping[str, float]:
        """The effects run i is simulated with (``run_effects``; ``effects`` itself without it).

        Parameters
        ----------
        effects : mapping of str to float
            The effects asked for.
        i : int
            Index of the run in ``cases``.

        Returns
        -------
        mapping of str to float
            Effect name to value for run i.
        """
        return effects if self.run_effects is None else self.run_effects(effects, i)

    def predict(self, effects: Mapping[str, float], i: int) -> tuple[np.ndarray, np.ndarray]:
        """Simulated θ and a of run i (not cached).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model.
        i : int
            Index of the run in ``cases``.

        Returns
        -------
        tuple of (ndarray, ndarray)
            Simulated θ (encoder counts) and a (accelerometer counts) of run i, each of shape (N,).

        Raises
        ------
        StopSignal
            SIGINT or SIGTERM arrived (:func:`station.signals.check_stop`).
        StationError
            Effects the model cannot hold (:meth:`model_with`).
        """
        return self.predict_case(self.cases[i], self.effects_for(effects, i))

    def predict_case(self, case: RunCase, effects: Mapping[str, float]) -> tuple[np.ndarray, np.ndarray]:
        """Simulated θ and a of a run (e.g. a copy of one of ``cases`` with another
        controller), counted in :attr:`simulations`, not cached.

        Parameters
        ----------
        case : RunCase
            The run.
        effects : mapping of str to float
            Effect name -> value, applied to the base model.

        Returns
        -------
        tuple of (ndarray, ndarray)
            Simulated θ (encoder counts) and a (accelerometer counts), each of shape (N,).

        Raises
        ------
        StopSignal
            SIGINT or SIGTERM arrived (:func:`station.signals.check_stop`).
        StationError
            Effects the model cannot hold (:meth:`model_with`).
        """
        check_stop()  # SIGINT / SIGTERM: every thread stops before its next simulation
        with self._lock:
            self.simulations += 1
        return self.simulate(case, self.model_with(effects))

    def sse(self, effects: Mapping[str, float], i: int) -> tuple[float, float]:
        """Sum of squared θ and a errors of run i, counts² (inf when the simulation diverges or
        the model cannot be built, e.g. values a model file may not hold).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model.
        i : int
            Index of the run in ``cases``.

        Returns
        -------
        tuple of (float, float)
            Σ(θ_measured − θ_simulated)² and Σ(a_measured − a_simulated)², counts² (each inf when
            not finite).

        Raises
        ------
        StopSignal
            SIGINT or SIGTERM arrived before a simulation (:func:`station.signals.check_stop`).
        """
        effects = self.effects_for(effects, i)  # cached per run's own effects: other sessions' values never miss
        scaled = self.accel_scale is not None and not feeds_back_a(self.cases[i])
        key = (_key(effects), i, scaled)
        hit = self._cache.get(key)
        if hit is None:
            try:
                theta, a = self.predict_case(self.cases[i], effects)
            # a model that cannot be built (values a model may not hold) or run
            except (ArithmeticError, ValueError, np.linalg.LinAlgError, StationError):
                self._cache[key] = hit = (math.inf, math.inf)
                return hit
            c = self.cases[i]
            with np.errstate(all="ignore"):
                st = float(np.sum((c.theta - theta) ** 2))
                if scaled:
                    a = a * least_squares_scale(c.a, a, self.accel_scale)
                sa = float(np.sum((c.a - a) ** 2))
            hit = (st if math.isfinite(st) else math.inf, sa if math.isfinite(sa) else math.inf)
            self._cache[key] = hit
        return hit

    def fit_accel_gain(self, effects: Mapping[str, float], runs: Sequence[int]) -> float:
        """The accelerometer's gain that fits a best over runs, pooled (least squares, each run
        weighted by its noise level), the others held: the gain a model holds after a search that
        judged a up to each run's scale (:attr:`accel_scale`).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model (its accel_gain the reference).
        runs : sequence of int
            Indices of the runs in ``cases``; those whose controller feeds a back are left out.

        Returns
        -------
        float
            The gain, the reference's times the pooled scale, within :attr:`accel_scale`'s
            bounds (the reference's where no run counts or the bounds are None).

        Raises
        ------
        StopSignal
            SIGINT or SIGTERM arrived before a simulation (:func:`station.signals.check_stop`).
        """
        g0 = float({**self.model.effect_dict(), **effects}.get("accel_gain", 1.0))
        if self.accel_scale is None:
            return g0
        ms = ss = 0.0
        for i in runs:
            c = self.cases[i]
            if feeds_back_a(c) or not math.isfinite(c.sigma_a):
                continue
            _, a = self.predict(effects, i)
            ms += float(np.dot(c.a, a)) / c.sigma_a ** 2
            ss += float(np.dot(a, a)) / c.sigma_a ** 2
        if not (ss > 0 and math.isfinite(ms)):
            return g0
        lo, hi = self.accel_scale
        return g0 * min(max(ms / ss, lo), hi)

    def weighted(self, effects: Mapping[str, float], i: int) -> float:
        """‖e_θ‖²/σ_θ² + ‖e_a‖²/σ_a² of run i.

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model.
        i : int
            Index of the run in ``cases``.

        Returns
        -------
        float
            The noise-weighted squared error, dimensionless (inf when the simulation diverged).

        Raises
        ------
        StopSignal
            SIGINT or SIGTERM arrived before a simulation (:func:`station.signals.check_stop`).
        """
        st, sa = self.sse(effects, i)
        c = self.cases[i]
        return st / c.sigma_theta ** 2 + sa / c.sigma_a ** 2

    def terms(self, runs: Sequence[int]) -> int:
        """Error terms over runs: 2N per run (θ and a counted separately).

        Parameters
        ----------
        runs : sequence of int
            Indices of the runs in ``cases``.

        Returns
        -------
        int
            Σ 2·N over the runs.
        """
        return sum(2 * self.cases[i].n for i in runs)

    @contextmanager
    def costed(self, likelihood: bool):
        """:meth:`cost` by the maximum likelihood (True) or least squares (False) inside the
        block, as before after it (the simulations' cache holds errors, not costs: it serves both).

        Parameters
        ----------
        likelihood : bool
            The cost inside the block (as the constructor's ``likelihood``).

        Yields
        ------
        Evaluator
            This evaluator, its :attr:`likelihood` set to ``likelihood``.
        """
        before, self.likelihood = self.likelihood, likelihood
        try:
            yield self
        finally:
            self.likelihood = before

    def cost(self, effects: Mapping[str, float], runs: Sequence[int]) -> float:
        """Normalised cost J over runs that fits minimise (1 ≈ the noise floor): the
        arithmetic mean of the runs' ‖e‖²/σ², or with ``likelihood`` the maximum-likelihood
        cost with an unknown error variance per run and signal, at least its noise level
        (module docstring; a signal with an infinite σ is left out).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, applied to the base model.
        runs : sequence of int
            Indices of the runs in ``cases``.

        Returns
        -------
        float
            J, dimensionless (≈ 1 at the noise floor; inf when a simulation diverged; NaN with no
            finite σ to weigh by).

        Raises
        ------
        StopSignal
            SIGINT or SIGTERM arrived before a simulation (:func:`station.signals.check_stop`).
        """
        if not self.likelihood:
            return sum(self.weighted(effects, i) for i in runs) / self.terms(runs)
        total, terms = 0.0, 0
        for i in runs:
            c = self.cases[i]
            for sse, sigma in zip(self.sse(effects, i), (c.sigma_theta, c.sigma_a)):
                if math.isfinite(sigma):
                    if not math.isfinite(sse):
                        return math.inf
                    j = sse / (c.n * sigma ** 2)
                    total += c.n * (math.log(j) + 1.0 if j >= 1.0 else j)
                    terms += c.n
        return math.exp(total / terms - 1.0) if terms else math.nan


def least_squares_scale(measured: np.ndarray, simulated: np.ndarray, bounds: tuple[float, float]) -> float:
    """The factor k minimising ‖measured − k·simulated‖², clipped to ``bounds`` (1 when the
    simulated signal is zero).

    Parameters
    ----------
    measured, simulated : ndarray, shape (N,)
    bounds : (float, float)
        Least and largest k.

    Returns
    -------
    float
    """
    ss = float(np.dot(simulated, simulated))
    if not ss > 0 or not math.isfinite(ss):
        return 1.0
    return min(max(float(np.dot(measured, simulated)) / ss, bounds[0]), bounds[1])


IGNORED_SIGMA = 1e6
"""σ_a of a run whose a is not used (counts): its a errors weigh nothing beside θ's, and its
noise realisations stay finite numbers."""


def calibrate_noise(ev: Evaluator) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Simulate every run on the nominal model and set each run's noise levels from the
    high-frequency part of its residual (:func:`station.analysis.residuals.noise_std`); a run
    whose a the log audit found to be no tip acceleration, or whose log has none
    (:attr:`station.diagnosis.runs.cases.RunCase.fits_a`), gets :data:`IGNORED_SIGMA` (a model
    that damps its modelled a away must not win by it).

    Parameters
    ----------
    ev : Evaluator
        Its cases' ``sigma_theta`` and ``sigma_a`` are set (counts).

    Returns
    -------
    dict of int to (ndarray, ndarray)
        Run index -> the nominal model's θ and a, shape (N,) each.
    """
    nominal = {}
    for i, c in enumerate(ev.cases):
        theta, a = ev.predict({}, i)
        nominal[i] = (theta, a)
        c.sigma_theta = noise_std(c.theta - theta, THETA_QUANTIZATION_STD)
        c.sigma_a = noise_std(c.a - a, ACCEL_NOISE_STD) if c.fits_a else IGNORED_SIGMA
    return nominal


class PooledFit(NamedTuple):
    """θ RMS error and NRMSE fits over validation runs pooled.

    Attributes
    ----------
    rms_theta : float
        θ RMS error over all their samples, counts.
    theta, accel : float or None
        NRMSE fits of θ and a, % (None when undefined or the model diverged).
    """

    rms_theta: float
    theta: float | None
    accel: float | None

    def fit_pct(self) -> dict:
        """``{"theta": F, "accel": F}``: the contract's fit_pct.

        Returns
        -------
        dict
            ``theta`` and ``accel``: the NRMSE fits, % (None where undefined).
        """
        return {"theta": self.theta, "accel": self.accel}


def pooled(ev: Evaluator, val_sse: Mapping[int, tuple]) -> PooledFit:
    """Pooled θ RMS and NRMSE fits over validation runs, from their cached squared errors.

    Parameters
    ----------
    ev : Evaluator
        Holds the measured runs.
    val_sse : mapping of int to (float, float)
        Run index -> squared θ and a errors of its held-out prediction, counts².

    Returns
    -------
    PooledFit
        θ RMS error over all the runs' samples (encoder counts; NaN with no runs) and the NRMSE
        fits of θ and a, % (None when undefined or not finite).
    """
    idx = sorted(val_sse)
    n = sum(ev.cases[i].n for i in idx)
    st = sum(val_sse[i][0] for i in idx)
    sa = sum(val_sse[i][1] for i in idx)
    th = np.concatenate([ev.cases[i].theta for i in idx])
    ac = np.concatenate([ev.cases[i].a for i in idx])
    dt_, da_ = np.sum((th - th.mean()) ** 2), np.sum((ac - ac.mean()) ** 2)
    fit_t = 100.0 * (1 - math.sqrt(st / dt_)) if dt_ > 0 and math.isfinite(st) else None
    fit_a = 100.0 * (1 - math.sqrt(sa / da_)) if da_ > 0 and math.isfinite(sa) else None
    return PooledFit(math.sqrt(st / n) if n else math.nan, fit_t, fit_a)


def rms_gain(rms_ext: float, rms_nom: float) -> float:
    """100 (1 − RMS_ext/RMS_nom), % (−inf when the extended model diverged, 0 when the
    nominal one is exact).

    Parameters
    ----------
    rms_ext, rms_nom : float
        RMS errors of the extended and the nominal model, counts.

    Returns
    -------
    float
        The gain, % (positive: the extended model's error is smaller).
    """
    if not (math.isfinite(rms_ext) and rms_nom > 0):
        return -math.inf if not math.isfinite(rms_ext) else 0.0
    return 100.0 * (1.0 - rms_ext / rms_nom)


def relative_gain(v1: float, v0: float) -> float:
    """100 (1 − v1/v0), % (0 when v0 is 0: a model that is already exact).

    Parameters
    ----------
    v1, v0 : float
        Cost with and without the change.

    Returns
    -------
    float
        The gain, % (positive: ``v1`` is smaller).
    """
    return 100.0 * (1.0 - v1 / v0) if v0 > 0 else 0.0
