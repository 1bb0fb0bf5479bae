"""The result records filled from a finished search: each run side by side with the nominal
and the extended model (NRMSE fits, residual tests before and after, step metrics), and
each candidate with its value, gains and evidence."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from station.analysis.fit import fit_pct
from station.analysis.residuals import RunResiduals, run_residuals
from station.diagnosis.runs.cases import RunCase
from station.diagnosis.runs.cost import Evaluator, pooled, relative_gain, rms_gain
from station.diagnosis.runs.folds import Fold
from station.diagnosis.answer.prose import at_range_end, effect_evidence
from station.diagnosis.answer.result import EffectResult, RunReport
from station.diagnosis.search.selection import Selection, Singles, Trial
from station.plant.effects import EFFECTS


def _fit_pct(theta: np.ndarray, a: np.ndarray, pred: Mapping[str, np.ndarray]) -> dict:
    """NRMSE fits {"theta", "accel"} of one run, % to 3 decimals (:func:`station.analysis.fit.fit_pct`)."""
    return fit_pct(theta, pred["theta"], a, pred["a"], digits=3)


def _step_metrics(case: RunCase, nominal: Mapping, final: Mapping) -> dict | None:
    """Step metrics of the rig, the nominal and the final extended model (closed-loop steps)."""
    rig = case.run.step_metrics()
    if rig is None:
        return None
    return {"rig": rig, "nominal": case.run.step_metrics(nominal["theta"]),
            "extended": case.run.step_metrics(final["theta"])}


def _run_report(ev: Evaluator, i: int, role: str, nominal: tuple, extended: tuple, final: tuple,
                sel: Selection) -> RunReport:
    """Run i measured, on the nominal model, on the extended model as judged (held out) and
    on the final one; residual tests before and after."""
    c, changed = ev.cases[i], bool(sel.accepted)
    nom = dict(zip(("theta", "a"), nominal))
    ext = dict(zip(("theta", "a"), extended)) if changed else nom
    fin = dict(zip(("theta", "a"), final)) if changed else nom
    d = c.log.data
    rb = run_residuals(c.theta, c.a, nom["theta"], nom["a"], d["v"], d["u"], c.closed)
    ra = run_residuals(c.theta, c.a, ext["theta"], ext["a"], d["v"], d["u"], c.closed) if changed else rb
    metrics = _step_metrics(c, nom, fin)
    rms_n = float(np.sqrt(np.mean((c.theta - nom["theta"]) ** 2)))
    rms_e = float(np.sqrt(np.mean((c.theta - ext["theta"]) ** 2)))
    return RunReport(c.name, role, c.kind, c.alignment, np.asarray(d["t"]), np.asarray(d["u"]),
                     np.asarray(d["v"]), c.theta, c.a, nom, ext, fin, _fit_pct(c.theta, c.a, nom),
                     _fit_pct(c.theta, c.a, ext), rms_gain(rms_e, rms_n) if changed else 0.0, rb, ra, metrics,
                     list(c.notes), c.a_logged)


def model_predictions(ev: Evaluator, folds: Sequence[Fold], nominal: Mapping[int, tuple],
                      sel: Selection) -> tuple[dict[int, tuple], dict[int, tuple]]:
    """Every run on the extended model: as judged (a validation run on the model fitted
    without it, a fit run on the final one) and on the final model (refitted on all fit
    runs); the nominal model's when nothing was accepted or refitted.

    Parameters
    ----------
    ev : Evaluator
    folds : sequence of Fold
    nominal : mapping of int to (ndarray, ndarray)
        Run index -> the nominal model's θ and a.
    sel : Selection
        What forward selection accepted.

    Returns
    -------
    judged, final : dict of int to (ndarray, ndarray)
        Run index -> θ and a.
    """
    if not sel.accepted and "accel_gain" not in sel.values:  # nothing accepted, nor a reversed gain refitted
        return dict(nominal), dict(nominal)
    final = {i: ev.predict(sel.values, i) for i in range(len(ev.cases))}
    judged = dict(final)
    for f, fold in enumerate(folds):
        for i in fold.val:
            values = sel.current.fold_values[f]
            judged[i] = final[i] if values == sel.values else ev.predict(values, i)
    return judged, final


def run_reports(ev: Evaluator, folds: Sequence[Fold], nominal: Mapping[int, tuple], sel: Selection,
                judged: Mapping[int, tuple],
                final: Mapping[int, tuple]) -> tuple[list[RunReport], dict[str, RunResiduals]]:
    """Every run side by side with the models: a validation run with the extended model as
    fitted without it, a fit run with the final one.

    Parameters
    ----------
    ev : Evaluator
    folds : sequence of Fold
    nominal : mapping of int to (ndarray, ndarray)
        Run index -> the nominal model's θ and a (:func:`station.diagnosis.runs.cost.calibrate_noise`).
    sel : Selection
        What forward selection accepted.
    judged, final : mapping of int to (ndarray, ndarray)
        Run index -> the extended model's θ and a as judged and as finally refitted
        (:func:`model_predictions`).

    Returns
    -------
    reports : list of RunReport
        In the runs' order.
    before : dict of str to RunResiduals
        Run name -> residual analysis of the nominal model.
    """
    reports, before = [], {}
    held_out = {i for fold in folds for i in fold.val}
    for i, c in enumerate(ev.cases):
        report = _run_report(ev, i, "validation" if i in held_out else "fit", nominal[i], judged[i], final[i], sel)
        before[c.name] = report.residuals_before
        reports.append(report)
    return reports, before


def effect_results(ev: Evaluator, how: str, names: Sequence[str], singles: Singles, sel: Selection,
                   nominal: Trial, before: Mapping[str, RunResiduals],
                   intervals: Mapping[str, object] | None = None) -> list[EffectResult]:
    """Every candidate once, best first: the accepted ones in the order they were added,
    then the others by their validation cost alone.

    Parameters
    ----------
    ev : Evaluator
    how : str
        How candidates were judged ("leave-one-run-out" or "validation runs").
    names : sequence of str
        The candidates.
    singles : Singles
        Every candidate fitted alone.
    sel : Selection
        What forward selection accepted.
    nominal : Trial
        The nominal model's validation errors.
    before : mapping of str to RunResiduals
        Run name -> residual analysis of the nominal model.
    intervals : mapping of str to Interval, optional
        Accepted effect -> its 95 % interval (:func:`station.diagnosis.honesty.doubt.profile_interval`).

    Returns
    -------
    list of EffectResult
        One per name of ``names``: the accepted ones first (their joint values, gains in %,
        their intervals), then the rest by their validation cost alone (values fitted alone,
        no interval).
    """
    intervals = intervals or {}
    accepted = sel.accepted
    order = sorted(names, key=lambda n: singles.trials[n].val_weighted)
    rms_nom = pooled(ev, nominal.val_sse).rms_theta
    results = []
    for name in accepted + [n for n in order if n not in accepted]:
        tr = singles.trials[name]
        unit = EFFECTS[name].unit
        rms_alone = pooled(ev, tr.val_sse).rms_theta
        g = rms_gain(rms_alone, rms_nom)
        cg = relative_gain(tr.val_weighted, nominal.val_weighted)
        alone = singles.values[name][name]
        value = sel.values[name] if name in accepted else alone
        fold_values = [fv[name] for fv in tr.fold_values]
        step = accepted.index(name) + 1 if name in accepted else None
        joint = value if (step is not None and len(accepted) > 1) else None
        evidence = effect_evidence(name, unit, alone, fold_values, how, rms_nom, rms_alone, g, cg, step, joint,
                                   before)
        results.append(EffectResult(name, float(value), unit, float(g), float(cg), name in accepted, evidence,
                                    [float(v) for v in fold_values], float(alone),
                                    intervals.get(name) if name in accepted else None, at_range_end(name, value)))
    return results
