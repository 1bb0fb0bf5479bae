""":func:`diagnose`: the diagnosis's steps in order (read the runs and check them, the nominal
model and the noise levels, every candidate alone, forward selection, the intervals and
alternatives, what remains unexplained, the result)."""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import NamedTuple

from station.diagnosis.runs.cases import NO_A_COLUMN, Simulator, feeds_back_a, load_case, keep_bias, shown_effects
from station.diagnosis.runs.cost import Evaluator, calibrate_noise, pooled, relative_gain, rms_gain
from station.diagnosis.runs.folds import fold_records, make_folds, validation_runs
from station.diagnosis.honesty.doubt import alternatives, effective_terms, effect_interval, interval_method
from station.diagnosis.runs.admission import refuse_repeated_runs, set_aside_beam_tests
from station.diagnosis.answer.records import effect_results, model_predictions, run_reports
from station.diagnosis.answer.result import Diagnosis
from station.diagnosis.search.selection import Search, Trial, fit_each_alone, judge, with_accel_gain
from station.diagnosis.search.estimator import choose_estimator
from station.diagnosis.search.stepwise import forward_select
from station.diagnosis.search.workbench import Bench, nominal_trial, workbench
from station.diagnosis.honesty.unexplained import check_unexplained
from station.errors import StationError
from station.logged.audit import said_once
from station.logged.sensor_evidence import sensor_evidence
from station.logged.sensors import SESSION_HEADERS, decide_faults
from station.plant.effects import EFFECTS
from station.plant.model import as_model


def diagnose(runs: Sequence[str | Path], validate: Sequence[str | Path] = (), model=None,
             progress: Callable[[str], None] | None = None, candidates: Sequence[str] | None = None,
             simulate: Simulator | None = None, workers: int | None = None,
             likelihood_values: bool = True) -> Diagnosis:
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
        ``simulate(case, model) -> (theta, a)`` (default:
        :func:`station.diagnosis.runs.cases.simulate_case`); tests plug in their own.
    workers : int, optional
        Worker processes fitting candidates (and the sets tried beside the accepted effects)
        at once, each forked with the search as it stands (default 1: one after another;
        without ``fork`` always so). The answer is the same; the simulation count may be
        higher (workers do not share what they simulate while they work).
    likelihood_values : bool
        Also estimate the accepted effects' values by maximum likelihood and keep that
        estimate when the held-out runs prefer it (:mod:`station.diagnosis.search.estimator`);
        False: least squares only (``station identify``, whose designs separate structures
        by the least-squares folds' spread).

    Returns
    -------
    Diagnosis
        The cause and causes (effect names, "none" when nothing pays), every candidate's
        value, gains (%) and evidence, the extended model, the fits before and after (%),
        the θ RMS gain on held-out runs (%), the intervals, alternatives and what stays
        unexplained, and each run side by side with the models.

    Raises
    ------
    StationError
        One run without ``validate``, an unreadable or empty log, a bad model, or an
        unknown candidate.

    Examples
    --------
    Two short steps on a simulated rig whose motor has 10 DAC counts of Coulomb friction that
    the nominal model lacks, diagnosed with that one candidate (a few seconds; the whole
    vocabulary takes minutes):

    >>> import tempfile
    >>> from pathlib import Path
    >>> from station.diagnosis import diagnose
    >>> from station.experiment import run_step
    >>> from station.plant import load_model
    >>> rig = load_model("tmm-fit").with_effects({"coulomb_friction": 10.0}, name="rig")
    >>> folder = Path(tempfile.mkdtemp())
    >>> logs = [run_step(controller=c, amplitude=a, duration=0.5, model=rig, out=folder / f"{c}.tsv",
    ...                  figure=False, progress=False).log_path for c, a in (("p", 50), ("lead", 100))]
    >>> diag = diagnose(logs, candidates=["coulomb_friction"], likelihood_values=False)
    >>> diag.causes, diag.validation
    (['coulomb_friction'], 'leave-one-run-out')
    >>> friction = diag.effects[0]
    >>> round(friction.value), friction.unit, friction.interval.lo < 10 < friction.interval.hi
    (10, 'DAC counts', True)
    >>> diag.gain_pct > 50                                        # θ RMS error on held-out runs, %
    True
    """
    runs, validate = list(runs), list(validate)
    _check_runs(runs, validate)
    with workbench("diagnose", candidates, workers) as bench:
        return _diagnose(runs, validate, model, progress, bench, simulate, likelihood_values)


def _check_runs(runs: list, validate: list) -> None:
    if not runs:
        raise StationError("diagnose: no runs given")
    if not validate and len(runs) < 2:
        raise StationError(f"diagnose: leave-one-run-out needs at least two runs, got one ({runs[0]}); "
                           "give more runs or --validate RUN")


class _Nominal(NamedTuple):
    predictions: dict  # run index -> the nominal model's (θ, a)
    trial: Trial       # its validation errors: where forward selection starts


def _nominal(search: Search, how: str) -> _Nominal:
    """The nominal model on every run (which also sets the runs' noise levels) and its
    validation errors."""
    ev, folds = search.ev, search.folds
    predictions = calibrate_noise(ev)
    trial = nominal_trial(ev, folds)
    fit = pooled(ev, trial.val_sse)
    search.say(f"nominal model {ev.model.name}: θ fit {fit.theta:.1f} %, θ RMS {fit.rms_theta:.2f} counts "
               f"on {len(trial.val_sse)} validation run(s) ({how})")
    return _Nominal(predictions, trial)


def _use_runs(runs: list, validate: list) -> tuple[list, int, list[str]]:
    """Load the runs; refuse a run given twice; set hub-held beam tests aside. Returns the
    cases kept (RUNs first), how many are RUNs, and the notes saying what was left out."""
    cases = [load_case(p) for p in runs + validate]
    refuse_repeated_runs(cases, len(runs))
    kept, notes = set_aside_beam_tests(cases)
    n_fit = sum(1 for i in kept if i < len(runs))
    n_val = len(kept) - n_fit
    left = "; ".join(n.split(" is a ")[0] for n in notes)
    why = f" after leaving out the hub-held beam test(s) {left} (a free-hub model cannot simulate a held hub)"
    if n_fit == 0:
        raise StationError(f"diagnose: no run left to fit on{why}")
    if validate and n_val == 0:
        raise StationError(f"diagnose: no --validate run left{why}")
    if not validate and n_fit < 2:
        raise StationError(f"diagnose: leave-one-run-out needs at least two runs, {n_fit} left{why}; "
                           "give more runs or --validate RUN")
    return [cases[i] for i in kept], n_fit, notes


class _Doubt(NamedTuple):
    intervals: dict     # accepted effect -> Interval
    method: str         # interval_method
    alternatives: list  # of Alternative


def _doubt(search: Search, sel, searched, nominal: Trial, judged: dict, final: dict) -> _Doubt:
    """Intervals of the accepted effects (profile likelihood on the fit runs, with the kept
    estimate's cost) and the alternatives the validation data cannot tell apart (the search's
    least-squares answer against the search's other sets: the same estimator on both sides)."""
    if not sel.accepted:
        return _Doubt({}, "", [])
    ev = search.ev
    n_fit = effective_terms(ev, final, search.fit_runs)
    intervals = {}
    for name in sel.accepted:
        iv = effect_interval(ev, search.axes, name, sel.values, search.fit_runs, n_fit,
                             [fv[name] for fv in sel.current.fold_values])
        if iv is not None:
            intervals[name] = iv
            search.say(f"95 % interval of {name}: {iv.lo:.4g} .. {iv.hi:.4g} ({ev.simulations} simulations)")
    n_val = effective_terms(ev, judged, validation_runs(search.folds))
    with ev.costed(likelihood=False):
        alts = alternatives(search, searched, nominal, n_val)
    return _Doubt(intervals, interval_method(n_fit, ev.terms(search.fit_runs), len(search.folds)), alts)


def accel_scale(faults, cases) -> tuple[float, float] | None:
    """The range a's scale is free in during the search (a factor on the base model's a,
    :class:`station.diagnosis.runs.cost.Evaluator`'s ``accel_scale``), or None.

    A reversed accelerometer's gain, or one beyond the fit's search, is decided from the data against the nominal model
    (:func:`station.logged.sensors.decide_faults`: a's ratio over θ's); the effects the search
    accepts change the model's a, and a gain held at that first estimate steers it (the lab's
    April 2009 session: held at −1.22 the third step took the beam's damping for the
    actuator's gain, 56.8 % against 67.5 % on the 13 held-out logs). So a is judged up to each
    run's own scale, within the gain's search range (about the decided gain where that lies
    beyond it: :meth:`station.plant.effects.EffectSpec.search_about`), and the gain is refitted
    beside the accepted effects at the end (:func:`station.diagnosis.search.selection.with_accel_gain`).

    Where a run's controller feeds a back (Ga) the gain shapes its loop, and its θ pins it:
    there the gain stays a candidate the search fits, as any effect (blind, a held first
    estimate 40 % low, a scale free on the other runs, named saturation for the loop's error).

    Parameters
    ----------
    faults : station.logged.sensors.SensorFaults
    cases : sequence of RunCase

    Returns
    -------
    (float, float) or None
        None where no accelerometer gain was decided or a run feeds a back.
    """
    g0 = faults.effects.get("accel_gain")
    if g0 is None or any(feeds_back_a(c) for c in cases):
        return None
    spec = EFFECTS["accel_gain"]
    lo, hi = spec.search_about(g0)
    return lo / abs(g0), hi / abs(g0)


def _diagnose(runs, validate, model, progress, bench: Bench, simulate, likelihood_values) -> Diagnosis:
    t0 = time.perf_counter()
    nominal_model = as_model(model)
    names = bench.names
    cases, n_fit, notes = _use_runs(runs, validate)
    # the sensors' signs and scales first (DESIGN.md): a decided fault is part of the base model
    faults = decide_faults([sensor_evidence(c.run, nominal_model) for c in cases])
    base = nominal_model.with_effects(faults.effects) if faults.effects else nominal_model
    if "accel_offset" in faults.effects:
        for c in cases:
            keep_bias(c)
    names = names + [n for n in faults.to_fit if n not in names]  # pointed at, not decided: fitted
    notes += [f"{c.name}: {NO_A_COLUMN}" for c in cases if not c.a_logged]
    names = shown_effects(names, cases)
    folds, how = make_folds(n_fit, len(cases) - n_fit)
    scale = accel_scale(faults, cases)
    if scale is not None:  # the gain refitted beside every set, not a candidate of its own
        names = [n for n in names if n != "accel_gain"]
    ev = Evaluator(cases, base, simulate, accel_scale=scale)
    search = bench.search(ev, folds, range(n_fit), progress or (lambda msg: None))
    # the signs: said once, decided over the runs
    for line in said_once([(c.name, c.run.audit.lines(skip=SESSION_HEADERS)) for c in cases]):
        search.say(line)
    for line in faults.said():
        search.say(line)
    for note in notes:
        search.say(note)

    nominal = _nominal(search, how)
    singles = fit_each_alone(search, names, nominal.trial)
    sel = forward_select(search, names, singles, nominal.trial)
    searched = sel
    if likelihood_values:
        sel = choose_estimator(search, sel).selection  # (its choice is said in the progress)
    accepted = sel.accepted
    if scale is not None:
        sel = with_accel_gain(ev, folds, search.fit_runs, sel)
        search.say(f"accelerometer gain refitted beside the effects: {sel.values['accel_gain']:.3g} "
                   f"(decided from the data against the nominal model: {faults.effects['accel_gain']:.3g}); "
                   f"the search judged a up to each run's own scale")
    extended = base.with_effects(sel.values,
                                 name=f"{base.name} + {' + '.join(accepted)}" if accepted else None)
    judged, final = model_predictions(ev, folds, nominal.predictions, sel)
    doubt = _doubt(search, sel, searched, nominal.trial, judged, final)
    current, before_trial = sel.current, nominal.trial
    if scale is not None:  # judged from here as the models hold a: the gain refitted, the nominal's decided
        ev.accel_scale = None
        current = judge(ev, folds, current.names, current.fold_values)
        before_trial = judge(ev, folds, (), nominal.trial.fold_values)
    fit_nom, fit_ext = pooled(ev, before_trial.val_sse), pooled(ev, current.val_sse)
    gain = rms_gain(fit_ext.rms_theta, fit_nom.rms_theta) if accepted else 0.0
    cost_gain = relative_gain(current.val_weighted, before_trial.val_weighted) if accepted else 0.0
    unexplained = check_unexplained(ev, sel.values, final)
    search.say("unexplained: " + (unexplained.evidence if unexplained.flag else
                                  "no; the residuals are what encoder rounding and accelerometer noise produce"))
    reports, before = run_reports(ev, folds, nominal.predictions, sel, judged, final)
    effects = effect_results(ev, how, names, singles, sel, nominal.trial, before, doubt.intervals)

    diag = Diagnosis(
        accepted=accepted,
        baseline_fit=fit_nom.fit_pct(), extended_fit=(fit_ext if accepted or scale is not None else fit_nom).fit_pct(),
        gain_pct=float(gain), effects=effects, extended_model=extended, nominal_model=base, runs=reports,
        validation=how, simulations=ev.simulations,
        folds=fold_records(folds, [c.name for c in cases], sel.current.fold_values),
        elapsed_s=time.perf_counter() - t0, cost_gain_pct=float(cost_gain), unexplained=unexplained,
        alternatives=doubt.alternatives, interval_method=doubt.method, notes=notes,
        sensor_faults=faults.refined(extended.effect_dict()),  # the values the saved model holds
        audit=[{"run": c.name, "audit": c.run.audit.to_json(), "controller_source": c.run.source,
                "contradicted": c.run.audit.lines(skip=SESSION_HEADERS)} for c in cases])
    search.say(f"done: cause {diag.cause}, θ gain {gain:.1f} %, {ev.simulations} "  # the cause the answer prints
               f"simulations in {time.perf_counter() - t0:.1f} s")
    return diag
