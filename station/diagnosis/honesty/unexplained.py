"""What the extended model still leaves unexplained: its θ and a residuals on every run
against what the sensor model alone produces around it (DESIGN.md "Model diagnosis
contract": ``unexplained``, ``unexplained_evidence``).

The null is parametric: the extended model is simulated again as the rig would have run it
if it were the truth, with the sensor model's realisations — accelerometer noise of the
run's σ_a (rounded to counts as the rig's sensor does, and going round the loop where the
controller feeds a back) and tiny perturbations of the model
(:data:`station.diagnosis.search.selection.NULL_PERTURBATIONS`: where quantization sends a closed
loop along another path) — and the same statistics are measured on those replicates:

- θ: the fraction of samples where θ differs from the extended model by
  :data:`THETA_COUNTS` counts or more. Two rounded readings of the same motion differ by at
  most one count, so this fraction is ~0 for a model that is right; a run is structured
  when it reaches :data:`THETA_FRACTION` and :data:`NULL_FACTOR` times the replicates'
  largest.
- a: the RMS of the residual below :data:`LOWPASS_HZ` (what the accelerometer's white
  noise hardly reaches); structured when it exceeds :data:`ACCEL_FACTOR` times the
  replicates' largest.

The thresholds were calibrated blind (tests/blind: clean cases, every effect of the
vocabulary, pairs, against effects outside it; scripts/validate_diagnosis.py) with margins
on both sides. When structure remains, what it follows is measured on the structured runs
pooled (each run weighted equally): the share of the residual's variance explained by
position θ (binned, so a cyclic error shows; a period is named when a sinusoid in θ
explains it), hub speed (binned), the command's sign, a drift in time (a line per run) and
a constant offset per run.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from typing import NamedTuple

import numpy as np
import scipy.signal

from station.diagnosis.runs.cost import Evaluator
from station.diagnosis.search.selection import NULL_PERTURBATIONS, perturbed
from station.rig import DT
from station.rounding import sensor_count, sensor_counts

THETA_COUNTS = 2.0
"""θ off by this many counts or more cannot be encoder rounding (at most one count)."""

THETA_FRACTION = 0.08
"""A run's θ is structured when at least this fraction of its samples is off by
:data:`THETA_COUNTS` (blind calibration: at most 0.016 in every run of 70 clean and
in-vocabulary cases, their null replicates at most 0.025; at least 0.23 in the worst run
of each of 30 out-of-vocabulary cases)."""

NULL_FACTOR = 3.0
"""... and at least this many times the largest fraction of the null replicates."""

LOWPASS_HZ = 25.0
"""The a residual's structured part lies below this frequency, Hz."""

ACCEL_FACTOR = 8.0
"""A run's a is structured when the RMS of its residual below :data:`LOWPASS_HZ` exceeds
this many times the null replicates' largest (blind calibration, 70 clean and
in-vocabulary cases: at most 2.2, the imperfect fits of the accelerometer's large signal;
out-of-vocabulary cases reach 3.5-25 in their worst run)."""

NOISE_REPLICATES = 3
"""Accelerometer noise realisations per run (beside the perturbation replicates)."""

FOLLOW_SHARE = 0.2
"""A regressor is named when it explains at least this share of the residual's variance."""

POSITION_BINS = 32
SPEED_BINS = 16


@dataclasses.dataclass(frozen=True)
class SignalCheck:
    """One residual of one run against the null.

    Attributes
    ----------
    signal : {"theta", "a"}
    rms : float
        RMS of the residual (measured − extended model), counts.
    noise : float
        The run's noise level for this signal, counts (σ_θ or σ_a).
    statistic : float
        θ: fraction of samples off by :data:`THETA_COUNTS` or more; a: RMS of the
        residual below :data:`LOWPASS_HZ`, counts.
    null : float
        The same statistic's largest value over the null replicates.
    threshold : float
        Where structure starts.
    """

    signal: str
    rms: float
    noise: float
    statistic: float
    null: float
    threshold: float

    @property
    def structured(self) -> bool:
        return bool(self.statistic >= self.threshold)

    def to_json(self) -> dict:
        """The check as the report's JSON holds it.

        Returns
        -------
        dict
            ``signal``; ``rms``, ``noise``, ``statistic``, ``null`` and ``threshold`` rounded to 4
            decimals (units as the attributes); ``structured`` (bool).
        """
        return {"signal": self.signal, "rms": round(self.rms, 4), "noise": round(self.noise, 4),
                "statistic": round(self.statistic, 4), "null": round(self.null, 4),
                "threshold": round(self.threshold, 4), "structured": self.structured}


class RunCheck(NamedTuple):
    """A run's θ and a residual checks.

    Attributes
    ----------
    run : str
        The run's file name.
    controller : str
    theta, accel : SignalCheck
    """

    run: str
    controller: str
    theta: SignalCheck
    accel: SignalCheck


class Follower(NamedTuple):
    """What a residual follows.

    Attributes
    ----------
    what : str
        "position θ", "hub speed", "the command's sign", "time (a drift)" or "a constant
        offset per run".
    share : float
        Share of the residual's variance it explains, 0..1.
    detail : str
        E.g. "periodic every ≈ 120 counts" ("" when nothing more).
    """

    what: str
    share: float
    detail: str = ""


@dataclasses.dataclass(frozen=True)
class Unexplained:
    """The residual check of an extended model.

    Attributes
    ----------
    flag : bool
        Structure remains that the sensor model cannot produce.
    evidence : str
        In words: which runs and signals, how large against the noise and the null, what
        it follows ("" when nothing remains).
    runs : list of RunCheck
    follows : list of Follower
        Best first (empty when nothing remains).
    replicates : int
        Null replicates per run.
    """

    flag: bool
    evidence: str
    runs: list
    follows: list
    replicates: int

    def to_json(self) -> dict:
        """Per run checks and the followers (the report's details).

        Returns
        -------
        dict
            ``runs`` (one ``{"run", "theta", "a"}`` per run, the checks as
            :meth:`SignalCheck.to_json`), ``follows`` (``{"what", "share", "detail"}``, share a
            fraction of the variance, 3 decimals) and ``replicates``.
        """
        return {"runs": [{"run": r.run, "theta": r.theta.to_json(), "a": r.accel.to_json()} for r in self.runs],
                "follows": [{"what": f.what, "share": round(f.share, 3), "detail": f.detail} for f in self.follows],
                "replicates": self.replicates}


class _NoisyAccel:
    """The log's controller reading the accelerometer through a noise realisation."""

    def __init__(self, inner, noise: np.ndarray):
        self.inner, self.noise, self.k = inner, noise, 0
        self.name = getattr(inner, "name", "")

    def reset(self) -> None:
        self.inner.reset()
        self.k = 0

    def step(self, u: float, theta: float, a: float):
        n = self.noise[min(self.k, self.noise.size - 1)]
        self.k += 1
        return self.inner.step(u, theta, sensor_count(a + n))


def _feeds_a_back(case) -> bool:
    return case.closed and getattr(case.controller, "ga", None) is not None


def lowpass(x: np.ndarray, fs: float) -> np.ndarray:
    """Zero-phase 4th-order Butterworth low-pass at :data:`LOWPASS_HZ` (the signal itself
    when too short).

    Parameters
    ----------
    x : ndarray, shape (N,)
    fs : float
        Sample rate, Hz.

    Returns
    -------
    ndarray, shape (N,)
        The filtered signal, in ``x``'s units; ``x`` itself when it has fewer than 30 samples
        or the cut-off is not below Nyquist.
    """
    if x.size < 30 or LOWPASS_HZ >= 0.5 * fs:
        return x
    sos = scipy.signal.butter(4, LOWPASS_HZ, "lowpass", fs=fs, output="sos")
    return scipy.signal.sosfiltfilt(sos, x)


def _theta_stat(e: np.ndarray) -> float:
    return float(np.mean(np.abs(e) >= THETA_COUNTS)) if e.size else 0.0


def _rms(x: np.ndarray) -> float:
    return float(np.sqrt(np.mean(x ** 2))) if x.size else 0.0


def null_replicates(ev: Evaluator, values: Mapping[str, float], i: int, prediction: tuple,
                    rng: np.random.Generator) -> list[tuple[np.ndarray, np.ndarray]]:
    """What the rig would have logged for run i if the extended model were the truth: θ and
    a (rounded, with the run's accelerometer noise) of each null replicate.

    Parameters
    ----------
    ev : Evaluator
    values : mapping of str to float
        The extended model's effects.
    i : int
        The run.
    prediction : (ndarray, ndarray)
        The extended model's θ and a on run i.
    rng : numpy.random.Generator
        Draws the noise realisations.

    Returns
    -------
    list of tuple of (ndarray, ndarray)
        One (θ in encoder counts, a in accelerometer counts, rounded) pair per replicate, each
        of shape (N,): first one per :data:`NULL_PERTURBATIONS` entry, then
        :data:`NOISE_REPLICATES` noise realisations.
    """
    c = ev.cases[i]
    sigma = float(c.sigma_a)
    out = []
    for name, factor in NULL_PERTURBATIONS:
        theta, a = ev.predict({**values, name: perturbed(name, {**ev.model.effect_dict(), **values}, factor)}, i)
        out.append((theta, sensor_counts(a + sigma * rng.standard_normal(a.size))))
    loop = _feeds_a_back(c)
    for _ in range(NOISE_REPLICATES):
        noise = sigma * rng.standard_normal(c.n)
        if loop:
            noisy = dataclasses.replace(c, controller=_NoisyAccel(c.controller, noise))
            theta, a = ev.predict_case(noisy, values)
        else:
            theta, a = prediction
        out.append((np.asarray(theta, float), sensor_counts(np.asarray(a, float) + noise)))
    return out


def check_run(ev: Evaluator, values: Mapping[str, float], i: int, prediction: tuple,
              rng: np.random.Generator) -> RunCheck:
    """Run i's θ and a residuals of the extended model against the null replicates.

    Parameters
    ----------
    ev : Evaluator
    values : mapping of str to float
        The extended model's effects.
    i : int
        The run.
    prediction : (ndarray, ndarray)
        The extended model's θ and a on run i.
    rng : numpy.random.Generator

    Returns
    -------
    RunCheck
        The run's name, kind and its θ and a :class:`SignalCheck` (statistic, the null's
        largest and the threshold).
    """
    c = ev.cases[i]
    fs = 1.0 / c.log.dt
    theta_hat, a_hat = (np.asarray(x, float) for x in prediction)
    et, ea = c.theta - theta_hat, c.a - a_hat
    reps = null_replicates(ev, values, i, (theta_hat, a_hat), rng)
    finite = [(t, a) for t, a in reps if np.all(np.isfinite(t)) and np.all(np.isfinite(a))]
    null_t = max((_theta_stat(t - theta_hat) for t, _ in finite), default=0.0)
    null_a = max((_rms(lowpass(a - a_hat, fs)) for _, a in finite), default=0.0)
    theta = SignalCheck("theta", _rms(et), float(c.sigma_theta), _theta_stat(et), null_t,
                        max(THETA_FRACTION, NULL_FACTOR * null_t))
    accel = SignalCheck("a", _rms(ea), float(c.sigma_a), _rms(lowpass(ea, fs)), null_a,
                        ACCEL_FACTOR * max(null_a, float(c.sigma_a) * math.sqrt(2 * LOWPASS_HZ / fs)))
    return RunCheck(c.name, c.kind, theta, accel)


def _share(e: np.ndarray, w: np.ndarray, pred: np.ndarray) -> float:
    mean = np.sum(w * e) / np.sum(w)
    sst = float(np.sum(w * (e - mean) ** 2))
    return 0.0 if sst <= 0 else float(1.0 - np.sum(w * (e - pred) ** 2) / sst)


def _binned(e: np.ndarray, w: np.ndarray, idx: np.ndarray) -> np.ndarray:
    s = np.bincount(idx, weights=w * e)
    n = np.bincount(idx, weights=w)
    return (s / np.maximum(n, 1e-300))[idx]


def _period(e, w, theta, run, span) -> tuple[float, float]:
    """The period (counts, at most half the θ span: two periods seen) of the sinusoid in θ
    that explains the most beyond an offset per run, and the share it adds."""
    runs = np.unique(run)
    dummies = (run[:, None] == runs[None, :]).astype(float)
    sw = np.sqrt(w)
    offsets = _binned(e, w, run.astype(int))
    base = _share(e, w, offsets)
    best = (math.nan, 0.0)
    if span < 16.0 or runs.size < 2:  # a period is claimed only when several runs show it
        return best
    for period in np.geomspace(8.0, span / 2.0, 48):
        ph = 2 * math.pi * theta / period
        x = np.column_stack([dummies, np.cos(ph), np.sin(ph)])
        coef, *_ = np.linalg.lstsq(x * sw[:, None], e * sw, rcond=None)
        gain = _share(e, w, x @ coef) - base
        if gain > best[1]:
            best = (float(period), gain)
    return best


def follows(parts: Sequence[tuple]) -> list[Follower]:
    """What a residual follows, pooled over runs (each run weighted equally).

    Parameters
    ----------
    parts : sequence of (e, theta, v, t)
        Per run: residual, measured θ (encoder counts), command v (DAC counts) and time
        (s), arrays of shape (N,).

    Returns
    -------
    list of Follower
        Those explaining at least :data:`FOLLOW_SHARE` of the variance, best first, at
        most three.
    """
    es, ths, sps, sgs, ts, rs, ws = [], [], [], [], [], [], []
    for k, (e, theta, v, t) in enumerate(parts):
        e, theta, t = (np.asarray(x, float) for x in (e, theta, t))
        if e.size < 25:
            continue
        dt = float(np.median(np.diff(t))) if t.size > 1 else DT
        smooth = scipy.signal.savgol_filter(theta, 21, 2, deriv=1) / dt
        es.append(e)
        ths.append(theta)
        sps.append(smooth)
        sgs.append(np.sign(np.asarray(v, float)))
        ts.append(t)
        rs.append(np.full(e.size, k))
        ws.append(np.full(e.size, 1.0 / (e.size * max(float(np.var(e)), 1e-12))))
    if not es:
        return []
    e, theta, speed, sign, t, run, w = map(np.concatenate, (es, ths, sps, sgs, ts, rs, ws))
    span = float(np.ptp(theta))
    found = []
    if span > 0:
        idx = np.digitize(theta, np.linspace(theta.min(), theta.max(), POSITION_BINS + 1)[1:-1])
        share = _share(e, w, _binned(e, w, idx))
        detail = ""
        period, pshare = _period(e, w, theta, run, span)
        if pshare >= max(0.15, 0.5 * share):
            detail = (f"periodic every ≈ {period:.0f} counts: a sinusoid in θ adds {100 * pshare:.0f} % to an "
                      "offset per run")
        found.append(Follower("position θ", share, detail))
    edges = np.unique(np.quantile(speed, np.linspace(0, 1, SPEED_BINS + 1)[1:-1]))
    found.append(Follower("hub speed", _share(e, w, _binned(e, w, np.digitize(speed, edges)))))
    found.append(Follower("the command's sign", _share(e, w, _binned(e, w, np.digitize(sign, [-0.5, 0.5])))))
    line = np.zeros_like(e)
    for k in np.unique(run):
        m = run == k
        line[m] = np.polyval(np.polyfit(t[m], e[m], 1), t[m])
    drift, offset = _share(e, w, line), _share(e, w, _binned(e, w, run.astype(int)))
    # a line per run holds an offset per run: name the drift only when its slope adds to it
    found.append(Follower("time (a drift)", drift) if drift >= offset + 0.1
                 else Follower("a constant offset per run", offset))
    found = [f for f in found if f.share >= FOLLOW_SHARE]
    return sorted(found, key=lambda f: -f.share)[:3]


def _run_words(r: RunCheck) -> str:
    words = []
    if r.theta.structured:
        words.append(f"θ off by {THETA_COUNTS:.0f}+ counts in {100 * r.theta.statistic:.0f} % of the samples "
                     f"(RMS {r.theta.rms:.3g} counts, encoder noise {r.theta.noise:.2f}; the sensor model alone: "
                     f"at most {100 * r.theta.null:.1f} %)")
    if r.accel.structured:
        words.append(f"a's residual below {LOWPASS_HZ:g} Hz {r.accel.statistic:.3g} counts RMS, "
                     f"{r.accel.statistic / max(r.accel.null, 1e-9):.0f}× what accelerometer noise reaches around "
                     "the model")
    return f"{r.run} ({r.controller}): " + "; ".join(words)


def describe(runs: Sequence[RunCheck], found: Sequence[Follower], signal: str) -> str:
    """The evidence sentence: the structured runs (largest first, at most three) and what
    the residual follows.

    Parameters
    ----------
    runs : sequence of RunCheck
    found : sequence of Follower
    signal : {"theta", "a"}
        Which residual the followers describe.

    Returns
    -------
    str
        The sentence(s), ending with a period; empty when no run is structured.
    """
    bad = [r for r in runs if r.theta.structured or r.accel.structured]
    if not bad:
        return ""
    bad.sort(key=lambda r: -(r.theta.statistic / max(r.theta.threshold, 1e-9)
                             + r.accel.statistic / max(r.accel.threshold, 1e-9)))
    text = (f"{len(bad)} of {len(runs)} runs keep structure that encoder rounding and accelerometer noise "
            "cannot produce around the extended model: " + "; ".join(_run_words(r) for r in bad[:3])
            + (f"; and {len(bad) - 3} more" if len(bad) > 3 else "") + ".")
    if found:
        name = "θ" if signal == "theta" else "a"
        parts = [f"{f.what} ({100 * f.share:.0f} %" + (f"; {f.detail}" if f.detail else "") + ")" for f in found]
        text += f" What remains in {name} follows " + ", then ".join(parts) + " (share of its variance explained)."
    else:
        text += " It follows none of position, hub speed, the command's sign or time clearly."
    return text


def check_unexplained(ev: Evaluator, values: Mapping[str, float], predictions: Mapping[int, tuple],
                      seed: int = 0) -> Unexplained:
    """Compare the extended model's residuals on every run with the null replicates (module
    docstring) and say what remains.

    Parameters
    ----------
    ev : Evaluator
        The runs (their noise levels set) and the base model.
    values : mapping of str to float
        The extended model's effects (refitted on all fit runs).
    predictions : mapping of int to (ndarray, ndarray)
        Run index -> the extended model's θ and a on it.
    seed : int
        Of the noise realisations (the check is deterministic for a seed).

    Returns
    -------
    Unexplained
    """
    rng = np.random.default_rng(seed)
    checks = [check_run(ev, values, i, predictions[i], rng) for i in range(len(ev.cases))]
    flag = any(r.theta.structured or r.accel.structured for r in checks)
    found, signal = [], "theta"
    if flag:
        theta_runs = [i for i, r in enumerate(checks) if r.theta.structured]
        signal = "theta" if theta_runs else "a"
        idx = theta_runs or [i for i, r in enumerate(checks) if r.accel.structured]
        parts = []
        for i in idx:
            c = ev.cases[i]
            th, a = predictions[i]
            e = c.theta - th if signal == "theta" else lowpass(c.a - a, 1.0 / c.log.dt)
            parts.append((e, c.theta, c.log.data["v"], c.log.data["t"]))
        found = follows(parts)
    replicates = len(NULL_PERTURBATIONS) + NOISE_REPLICATES
    return Unexplained(flag, describe(checks, found, signal), checks, found, replicates)
