"""Experiment design: of the candidate experiments, the one whose predicted outputs differ most
between the chosen explanation and its rivals (:func:`choose_experiment`).

Each candidate (:func:`station.diagnosis.identify.experiments.candidate_experiments`) is simulated on
the chosen model and on every rival exactly as the device will run it
(:func:`station.plant.simulate`: the experiment's controller with the rig's clamp, alignment
1, the device's command quantization, θ and a rounded as the sensors do). A rival r is
separated from the chosen model by

    S_r = Σ_k (θ_r[k] − θ_0[k])² / σ_θ² + (a_r[k] − a_0[k])² / σ_a²,

the noise-normalised squared difference the diagnosis's cost would see (σ_θ the encoder's
quantization, σ_a the accelerometer's noise): with white sensor noise, S_r is twice the
log-likelihood ratio by which the run tells the two apart. The score of a candidate is
Σ_r ln(1 + S_r), which rewards separating every rival over separating one by a lot (as a
D-optimal design maximises the log-determinant of the information). A candidate is feasible
when, on every model, the predicted |θ| stays within :data:`SOFT_LIMIT_MARGIN` of the soft
limit and the encoder moves less than half the fail-safe's step bound per tick; open loop
within the clamp.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from station.analysis.residuals import ACCEL_NOISE_STD, THETA_QUANTIZATION_STD
from station.diagnosis.identify.experiments import Experiment, candidate_experiments
from station.diagnosis.honesty.rivals import Rivals
from station.plant import simulate
from station.rig import CLAMP, DEFAULT_SOFT_LIMIT

SOFT_LIMIT_MARGIN = 0.8
"""A candidate's predicted |θ| must stay below this fraction of the soft limit on every model."""

MAX_STEP = 40.0
"""The fail-safe's encoder step bound, counts per tick (``station step --max-step``); a
candidate's predicted steps must stay below half of it."""

MIN_SEPARATION = 10.0
"""A rival counts as separable by an experiment when S_r reaches this many noise variances."""


class Prediction(NamedTuple):
    """An experiment's outputs predicted on one model.

    Attributes
    ----------
    theta, a : ndarray, shape (N,)
        Encoder and accelerometer counts.
    """

    theta: np.ndarray
    a: np.ndarray


class Candidate(NamedTuple):
    """A candidate experiment as the design judged it.

    Attributes
    ----------
    experiment : Experiment
    feasible : bool
        Within the soft limit, the step bound and the clamp on every model.
    separations : list of float
        S_r per rival (module docstring), noise variances.
    score : float
        Σ ln(1 + S_r) (0 when not feasible).
    note : str
        Why it is not feasible ("" when it is).
    """

    experiment: Experiment
    feasible: bool
    separations: list
    score: float
    note: str = ""


class Design(NamedTuple):
    """The chosen experiment and why (:func:`choose_experiment`).

    Attributes
    ----------
    experiment : Experiment or None
        None when no candidate is feasible or none separates any rival by
        :data:`MIN_SEPARATION`.
    why : str
        In words: which rivals it separates, by how many counts of θ or a and how many times
        the noise.
    candidates : list of Candidate
        Every candidate judged, best first.
    predictions : dict of str to Prediction
        The chosen experiment on the chosen model (first, "<its label> (chosen)") and on each
        rival (its label).
    """

    experiment: Experiment | None
    why: str
    candidates: list
    predictions: dict


def predict(model, experiment: Experiment, command: str = "round", limit: float = CLAMP) -> Prediction:
    """An experiment on a model as the device runs it (module docstring).

    Parameters
    ----------
    model : station.plant.model.Model
    experiment : Experiment
    command : {"round", "trunc", "none"}
        The device's command quantization (v1 rounds, the legacy firmware truncates).
    limit : float
        The controller's clamp, ±DAC counts.

    Returns
    -------
    Prediction
        Simulated θ (encoder counts) and a (accelerometer counts), each of shape (N,), N the
        experiment's ticks.
    """
    res = simulate(model, experiment.controller_object(limit), experiment.u(), alignment=1, command=command)
    return Prediction(np.asarray(res.theta, float), np.asarray(res.a, float))


def separation(p: Prediction, q: Prediction, sigma_theta: float = THETA_QUANTIZATION_STD,
               sigma_a: float = ACCEL_NOISE_STD) -> float:
    """S = Σ (Δθ/σ_θ)² + (Δa/σ_a)² between two predictions, noise variances (inf when one diverged).

    Parameters
    ----------
    p, q : Prediction
    sigma_theta, sigma_a : float
        Sensor noise levels, counts.

    Returns
    -------
    float
        S, in noise variances (dimensionless, ≥ 0; inf when not finite).
    """
    with np.errstate(all="ignore"):
        s = float(np.sum((p.theta - q.theta) ** 2) / sigma_theta ** 2 + np.sum((p.a - q.a) ** 2) / sigma_a ** 2)
    return s if math.isfinite(s) else math.inf


def _feasible(experiment: Experiment, preds: Sequence[Prediction], soft_limit: float, limit: float) -> str:
    """"" when the experiment is safe on every model, else why not."""
    if not experiment.closed and experiment.amplitude > limit:
        return f"open-loop amplitude {experiment.amplitude:g} above the clamp {limit:g}"
    for p in preds:
        if not (np.all(np.isfinite(p.theta)) and np.all(np.isfinite(p.a))):
            return "a model diverges"
        peak = float(np.max(np.abs(p.theta)))
        if peak > SOFT_LIMIT_MARGIN * soft_limit:
            return f"predicted |θ| {peak:.0f} counts, beyond {SOFT_LIMIT_MARGIN:.0%} of the soft limit {soft_limit:g}"
        if p.theta.size > 1 and float(np.max(np.abs(np.diff(p.theta)))) > MAX_STEP / 2:
            return "predicted encoder steps beyond half the fail-safe bound"
    return ""


def judge(experiment: Experiment, chosen: Prediction, others: Sequence[Prediction], soft_limit: float,
          limit: float, sigma_theta: float = THETA_QUANTIZATION_STD, sigma_a: float = ACCEL_NOISE_STD) -> Candidate:
    """One candidate's feasibility, separations and score (module docstring).

    Parameters
    ----------
    experiment : Experiment
    chosen : Prediction
        On the chosen model.
    others : sequence of Prediction
        On each rival.
    soft_limit : float
        Encoder soft limit, counts.
    limit : float
        The clamp, ±DAC counts.
    sigma_theta, sigma_a : float
        Sensor noise levels, counts.

    Returns
    -------
    Candidate
        The experiment, whether feasible, S per rival (noise variances), the score
        Σ ln(1 + S) (0 when infeasible) and the reason it is not feasible ("" when it is).
    """
    note = _feasible(experiment, [chosen, *others], soft_limit, limit)
    seps = [separation(chosen, q, sigma_theta, sigma_a) for q in others]
    score = 0.0 if note else float(sum(math.log1p(s) for s in seps))
    return Candidate(experiment, not note, seps, score, note)


def _why(experiment: Experiment, label: str, rivals, preds: dict, seps: Sequence[float],
         sigma_theta: float, sigma_a: float) -> str:
    """The chosen experiment in words: per rival, the largest difference in θ or a (whichever is
    more times its noise) and the separation."""
    base = next(iter(preds.values()))  # the chosen model's, first
    parts = []
    for r, s in sorted(zip(rivals, seps), key=lambda x: -x[1]):
        q = preds[r.label]
        dth, da = float(np.max(np.abs(q.theta - base.theta))), float(np.max(np.abs(q.a - base.a)))
        if dth / sigma_theta >= da / sigma_a:
            big = f"{dth:.3g} counts of θ ({dth / sigma_theta:.0f}× the encoder's {sigma_theta:.2f}-count noise)"
        else:
            big = f"{da:.3g} counts of a ({da / sigma_a:.0f}× the accelerometer's {sigma_a:.2f}-count noise)"
        parts.append(f"{r.label} differs from {label} by up to {big}, separation {s:.3g} noise variances")
    return f"{experiment.label}: " + "; ".join(parts)


def choose_experiment(base, rv: Rivals, candidates: Sequence[Experiment] | None = None, command: str = "round",
                      soft_limit: float = DEFAULT_SOFT_LIMIT, limit: float = CLAMP, sigma_theta: float = THETA_QUANTIZATION_STD,
                      sigma_a: float = ACCEL_NOISE_STD) -> Design:
    """The candidate experiment that best separates the rivals from the chosen explanation.

    Parameters
    ----------
    base : station.plant.model.Model
        The nominal model; the chosen explanation and each rival are its effects over it.
    rv : Rivals
        What the diagnosis leaves open (:func:`station.diagnosis.honesty.rivals.rivals`).
    candidates : sequence of Experiment, optional
        Default :func:`station.diagnosis.identify.experiments.candidate_experiments`.
    command : {"round", "trunc", "none"}
        The device's command quantization.
    soft_limit : float
        Encoder soft limit of the runs, counts.
    limit : float
        The controller's clamp, ±DAC counts.
    sigma_theta, sigma_a : float
        Sensor noise levels, counts (the encoder's quantization, the accelerometer's noise).

    Returns
    -------
    Design
        ``experiment`` None (and ``why`` saying so) when there are no rivals, no feasible
        candidate, or none separates a rival by :data:`MIN_SEPARATION`.
    """
    candidates = list(candidate_experiments() if candidates is None else candidates)
    if not rv.rivals:
        return Design(None, "no rivals: the diagnosis singles out one explanation", [], {})
    chosen_model = base.with_effects(rv.chosen) if rv.chosen else base
    models = [base.with_effects(r.effects) for r in rv.rivals]
    judged, preds_of = [], {}
    for exp in candidates:
        p0 = predict(chosen_model, exp, command, limit)
        others = [predict(m, exp, command, limit) for m in models]
        judged.append(judge(exp, p0, others, soft_limit, limit, sigma_theta, sigma_a))
        preds_of[exp] = {f"{rv.label} (chosen)": p0, **{r.label: q for r, q in zip(rv.rivals, others)}}
    judged.sort(key=lambda c: -c.score)
    best = next((c for c in judged if c.feasible), None)
    if best is None:
        return Design(None, "no candidate experiment is safe on every model (soft limit, clamp)", judged, {})
    if max(best.separations, default=0.0) < MIN_SEPARATION:
        return Design(None, f"no candidate experiment separates any rival from {rv.label} by {MIN_SEPARATION:g} "
                            f"noise variances (best: {best.experiment.label}, "
                            f"{max(best.separations, default=0.0):.3g})", judged, {})
    preds = preds_of[best.experiment]
    why = _why(best.experiment, rv.label, rv.rivals, preds, best.separations, sigma_theta, sigma_a)
    return Design(best.experiment, why, judged, preds)
