"""The result of a diagnosis as typed records: each candidate effect (:class:`EffectResult`),
each run side by side with the models (:class:`RunReport`) and the whole
(:class:`Diagnosis`), with their JSON (DESIGN.md "Model diagnosis contract")."""

from __future__ import annotations

from collections.abc import Mapping

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from station.analysis.residuals import RunResiduals
from station.logged.audit import said_once


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
    value_alone : float
        Fitted alone on all fit runs (equals ``value`` when not accepted).
    interval : Interval or None
        95 % interval of an accepted effect's value (:mod:`station.diagnosis.honesty.doubt`), clipped
        to its range; None for the others.
    at_range_end : bool
        ``value`` sits at an end of the effect's search range (the fit wanted further).
    """

    name: str
    value: float
    unit: str
    gain_pct: float
    cost_gain_pct: float
    accepted: bool
    evidence: str
    fold_values: list = field(default_factory=list)
    value_alone: float = math.nan
    interval: Any = None
    at_range_end: bool = False

    def to_json(self, held: Mapping[str, float] | None = None) -> dict:
        """The effect as DESIGN.md's ``effects`` entry.

        Parameters
        ----------
        held : mapping of str to float, optional
            Effects the extended model holds without accepting them (:attr:`Diagnosis.held`).

        Returns
        -------
        dict
            ``name``, ``value``, ``unit``, ``gain_pct`` and ``cost_gain_pct`` (%, 3 decimals),
            ``evidence``, ``accepted``, ``held`` (in the extended model though not accepted),
            ``value_extended`` (the value in the extended model: ``value`` when accepted, the held
            value, else None), ``fold_values``, ``value_alone``, ``interval`` ([low, high] or None),
            ``interval_at_range_end`` ([bool, bool] or None) and ``at_range_end``; values in the
            effect's unit, None where not finite.
        """
        fin = lambda x: x if math.isfinite(x) else None  # noqa: E731
        iv = self.interval
        held = held or {}
        is_held = not self.accepted and self.name in held
        ext = self.value if self.accepted else held[self.name] if is_held else math.nan
        return {"name": self.name, "value": fin(self.value), "unit": self.unit, "gain_pct": round(self.gain_pct, 3),
                "evidence": self.evidence, "accepted": self.accepted, "held": is_held,
                "value_extended": fin(float(ext)),
                "cost_gain_pct": round(self.cost_gain_pct, 3),
                "fold_values": [fin(v) for v in self.fold_values],
                "value_alone": fin(self.value_alone),
                "interval": None if iv is None else [fin(iv.lo), fin(iv.hi)],
                "interval_at_range_end": None if iv is None else [iv.lo_at_bound, iv.hi_at_bound],
                "at_range_end": self.at_range_end}


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
    a_logged : bool, default True
        False where the log has no a column (``a`` is then zeros, weighing nothing).
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
    a_logged: bool = True

    def to_json(self) -> dict:
        """The run as DESIGN.md's ``runs`` entry (the arrays stay out).

        Returns
        -------
        dict
            ``file``, ``role``, ``controller``, ``alignment``, ``baseline`` and ``extended``
            (``{"fit_pct": {"theta", "accel"}}``, %), ``gain_pct`` (%, 3 decimals), ``metrics`` (each
            model's step metrics as JSON, or None), ``signatures_before``/``signatures_after`` (lists
            of str) and ``notes``.
        """
        m = None if self.metrics is None else {k: (None if v is None else v.to_json()) for k, v in self.metrics.items()}
        return {"file": self.file, "role": self.role, "controller": self.controller, "alignment": self.alignment,
                "baseline": {"fit_pct": self.fit_nominal}, "extended": {"fit_pct": self.fit_extended},
                "gain_pct": round(self.gain_pct, 3), "metrics": m,
                "signatures_before": self.residuals_before.signatures() if self.residuals_before else [],
                "signatures_after": self.residuals_after.signatures() if self.residuals_after else [],
                "notes": list(self.notes)}


@dataclass
class Diagnosis:
    """The result of :func:`station.diagnosis.diagnose` (DESIGN.md "Model diagnosis contract").

    Attributes
    ----------
    accepted : list of str
        The physical effects forward selection accepted, in the order it added them (the
        decided sensor faults are not among them: :attr:`causes` holds both).
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
    unexplained : Unexplained or None
        The extended model's residuals against the sensor model's null
        (:mod:`station.diagnosis.honesty.unexplained`).
    alternatives : list of Alternative
        Other explanations the validation data cannot tell apart (:mod:`station.diagnosis.honesty.doubt`).
    interval_method : str
        How the effects' intervals were found.
    notes : list of str
        How the runs were treated (e.g. a hub-held beam test left out).
    sensor_faults : SensorFaults or None
        The sensor and wiring faults decided from the data before the search
        (:func:`station.logged.sensors.decide_faults`); they are in the nominal and the
        extended model both.
    audit : list of dict
        Per run: ``{"run", "audit", "controller_source", "contradicted"}`` (DESIGN.md "Log audit").
    """

    accepted: list
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
    unexplained: Any = None
    alternatives: list = field(default_factory=list)
    interval_method: str = ""
    notes: list = field(default_factory=list)
    sensor_faults: Any = None
    audit: list = field(default_factory=list)

    @property
    def decided_faults(self) -> dict:
        """The sensor and wiring faults decided from the data (effect -> value; empty: none)."""
        return dict(self.sensor_faults.effects) if self.sensor_faults is not None else {}

    @property
    def wiring_alike(self) -> str:
        """The sensor wiring the data cannot tell from the decided faults' ("" when none):
        said beside the alternatives, which it is not one of (no fit separates it)."""
        return self.sensor_faults.undecided_wiring if self.sensor_faults is not None else ""

    @property
    def held(self) -> dict:
        """Effects the extended model holds that were not accepted as causes (a breakaway's
        sliding level, a decided sensor fault) -> their value there: the one record the
        candidates table, the report and the JSON's ``effects`` (``held``, ``value_extended``)
        read. Empty without an extended model."""
        model = self.extended_model.effect_dict() if self.extended_model is not None else {}
        accepted = {e.name for e in self.effects if e.accepted}
        return {k: v for k, v in model.items() if k not in accepted and any(e.name == k for e in self.effects)}

    @property
    def causes(self) -> list:
        """DESIGN.md's ``causes``, the one definition every output prints: the decided sensor
        faults first, then the accepted effects (:attr:`accepted`)."""
        faults = list(self.decided_faults)
        return faults + [c for c in self.accepted if c not in faults]

    @property
    def cause(self) -> str:
        """DESIGN.md's ``cause``: the first of :attr:`causes`, or "none"."""
        return (self.causes or ["none"])[0]

    def prediction_words(self) -> str:
        """Whether the extended model predicts the runs it was not fitted to better than the
        nominal one (θ RMS, :attr:`gain_pct`), in words: said beside "unexplained" and when
        the model is saved.

        Returns
        -------
        str
            One clause without a final period, naming the validation and the θ RMS gain (%).
        """
        if not self.accepted:
            return "no effect accepted: the extended model is the nominal one"
        how = "better" if self.gain_pct > 0 else "no better" if self.gain_pct == 0 else "worse"
        return (f"on runs it was not fitted to ({self.validation}) the extended model predicts θ "
                f"{abs(self.gain_pct):.1f} % {how} than the nominal model (RMS)" if how != "no better" else
                f"on runs it was not fitted to ({self.validation}) the extended model predicts θ no better "
                f"than the nominal model")

    def audit_lines(self) -> list[str]:
        """What the data contradicted, one line each, to say before anything else: each run's
        contradicted claims, then the sensor faults (and the wiring that reads the same).

        Returns
        -------
        list of str
            The lines, without final periods: each contradicted claim once, with the runs it
            holds for ("audit: 3 of 3 runs: claim", :func:`station.logged.audit.said_once`), then
            "sensor fault, decided from the data: ..." per sensor fault and "sensor wiring, not
            decided by the data: ..." for the wiring that reads the same signs; empty when
            nothing was contradicted.
        """
        lines = said_once([(r["run"], r["contradicted"]) for r in self.audit])
        if self.sensor_faults is not None:
            lines += self.sensor_faults.said()
        return lines

    def to_json(self) -> dict:
        """DESIGN.md's JSON: cause, causes (the decided sensor faults first), audit,
        baseline, extended, gain_pct, effects (each with its interval), unexplained,
        unexplained_evidence, alternatives (+ extras: sensor_faults, validation,
        interval_method, model, extended_model, runs, simulations, elapsed_s, notes).

        Returns
        -------
        dict
            JSON-ready mapping with those keys (percentages rounded to 3 decimals, ``elapsed_s`` in s).
        """
        u = self.unexplained
        return {
            "cause": self.cause,
            "causes": self.causes,
            "audit": self.audit,
            "sensor_faults": self.sensor_faults.to_json() if self.sensor_faults is not None else None,
            "baseline": {"fit_pct": dict(self.baseline_fit)},
            "extended": {"fit_pct": dict(self.extended_fit)},
            "gain_pct": round(self.gain_pct, 3),
            "effects": [e.to_json(self.held) for e in self.effects],
            "unexplained": bool(u.flag) if u is not None else False,
            "unexplained_evidence": u.evidence if u is not None else "",
            "alternatives": [a.to_json() for a in self.alternatives],
            "interval_method": self.interval_method,
            "residual_check": u.to_json() if u is not None else None,
            "notes": list(self.notes),
            "validation": self.validation,
            "cost_gain_pct": round(self.cost_gain_pct, 3),
            "model": self.nominal_model.name,
            "extended_model": self.extended_model.to_json(),
            "runs": [r.to_json() for r in self.runs],
            "folds": self.folds,
            "simulations": self.simulations,
            "elapsed_s": round(self.elapsed_s, 3),
        }
