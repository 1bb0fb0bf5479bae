"""What :func:`station.design.tuning.tune` hands back: the tuned compensator and the evidence for it.

:class:`TuneResult` holds the design (its parameters, its compensator file with the design
model's record), the tuned and the thesis's compensator judged on every model of the set, the
margins, and the hub-tip trade-off (:class:`TradeOff`); its JSON is DESIGN.md's ``station tune
--json`` (:meth:`TuneResult.to_json`, :func:`robust_json`: the worst case and the spread over the
set, per model the tuned and the thesis's side by side).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from station.control.designs import CompensatorFile
from station.design.evaluate import Figures, Requirements, friction_held, held_error, violations
from station.design.hold import design_model_warning, held_summary
from station.design.linear import Margins
from station.design.robust import SEED, RobustSet
from station.design.space import DEFAULT_HUB_RATIO, DEFAULT_TIP_RMS, DesignSpace

METRICS = ("overshoot_pct", "settling_2pct_s", "settling_thesis_s", "peak_command", "saturated_s",
           "tip_settling_2pct_s", "tip_residual_rms", "tip_residual_peak")
"""DESIGN.md's metrics, in the JSON's order."""


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
    hub_ratio : float
        The bar on the design model: its hub settling (2 %) at most this multiple of the thesis's.
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
    hub_ratio: float = DEFAULT_HUB_RATIO
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
        settles = self.baseline[0].settling_2pct_s is not None
        bar = (f"the hub's settling (2 %) there at most {self.hub_ratio:g}x the thesis compensator's" if settles else
               "the thesis's compensator does not settle there (no bar on the hub)")
        relative = " relative to the thesis compensator's on the same model" if settles else ""
        req = self.requirements._asdict()
        req.pop("settling_scale", None)  # a model's own, not the user's
        req["tip_rms"] = self.tip_rms
        req["hub_ratio"] = self.hub_ratio
        return {"structure": self.space.structure, "shaper": self.space.shaper, "filter": self.space.filter,
                "amplitude": self.amplitude, "limit": self.space.limit,
                "parameters": {k: {"value": v, "unit": units[k]} for k, v in self.values.items()},
                "mode": None if self.space.mode is None else {"f_hz": self.space.mode[0], "zeta": self.space.mode[1]},
                "compensator": spec, "requirements": req,
                "design_model": None if self.file.design is None else self.file.design._asdict(),
                "objective": f"lexicographic: every requirement met on the design model first (the tip's residual "
                             f"RMS from 0.6 s after the step at most "
                             f"{'no bound' if self.tip_rms is None else f'{self.tip_rms:g}x the thesis compensator'}"
                             f"'s there), {bar}; then the worst over the {len(self.robust.models)} model(s) of the "
                             f"hub's settling (2 %){relative} (+1 % of the mean), a model where a requirement is not "
                             f"met adding its cost, and a model where friction holds the hub outside the 2 % band "
                             f"(nothing else failing) counting with the settling time into the band it holds, "
                             f"charged for the held error",
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
