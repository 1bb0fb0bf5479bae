"""The diagnosis in words: values with their units, each candidate's evidence sentence and
the summary paragraph of the report."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from station.analysis.residuals import RunResiduals
from station.diagnosis.search.bounded import RESOLUTION_STEPS, axis_for
from station.diagnosis.units import format_quantity
from station.plant.effects import EFFECTS

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


def signature_evidence(name: str, before: Mapping[str, RunResiduals]) -> str:
    """The nominal model's residual signatures that speak for an effect (at most three).

    Parameters
    ----------
    name : str
        The effect (:data:`SIGNATURE_WORDS`; others: resonances and amplitude ratios).
    before : mapping of str to RunResiduals
        Run name -> residual analysis of the nominal model.

    Returns
    -------
    str
        Up to three "run: signature" phrases joined by "; "; empty when no signature matches.
    """
    words = SIGNATURE_WORDS.get(name, ("Hz", "× the model"))
    found = []
    for file, res in before.items():
        for s in res.signatures():
            if any(w in s for w in words):
                found.append(f"{file}: {s}")
    return "; ".join(found[:3])


def effect_evidence(name: str, unit: str, alone: float, fold_values: Sequence[float], how: str,
                    rms_nominal: float, rms_alone: float, gain_pct: float, cost_gain_pct: float,
                    step: int | None, joint: float | None, before: Mapping[str, RunResiduals]) -> str:
    """A candidate's evidence: its fit, its gains on held-out data, whether forward selection
    accepted it, and the residual signatures that point to it.

    Parameters
    ----------
    name, unit : str
        The effect and its unit.
    alone : float
        Its value fitted alone on all fit runs.
    fold_values : sequence of float
        Its value fitted alone in each fold (a spread is given for more than one).
    how : str
        How it was judged ("leave-one-run-out" or "validation runs").
    rms_nominal, rms_alone : float
        Pooled validation θ RMS error of the nominal model and of the nominal model plus
        the effect alone, counts.
    gain_pct, cost_gain_pct : float
        θ RMS gain and joint θ + a cost gain of the effect alone, %.
    step : int or None
        The forward-selection step that accepted it (1-based); None when not accepted.
    joint : float or None
        Its value in the joint model, when other effects were accepted beside it.
    before : mapping of str to RunResiduals
        Run name -> residual analysis of the nominal model.

    Returns
    -------
    str
        One sentence without a final period: the fit (with the folds' spread), the held-out
        gains, the selection's verdict and any signatures, joined by "; ".
    """
    spread = (f" (folds {format_quantity(min(fold_values), unit)} to {format_quantity(max(fold_values), unit)})"
              if len(fold_values) > 1 else "")
    words = [f"fitted alone {format_quantity(alone, unit)}{spread}; on {how} the nominal model plus it "
             f"changes θ RMS {rms_nominal:.2f} -> {rms_alone:.2f} counts "
             f"({gain_pct:+.1f} %), the joint θ+a cost by {cost_gain_pct:+.1f} %"]
    if step is not None:
        words.append(f"accepted at step {step} of forward selection"
                     + (f", {format_quantity(joint, unit)} in the joint model" if joint is not None else ""))
    else:
        words.append("not accepted (below the significance threshold or a better effect explains the same)")
    sig = signature_evidence(name, before)
    if sig:
        words.append(f"signatures: {sig}")
    return "; ".join(words)


def format_pct(x: float | None) -> str:
    """A percentage with one decimal, "n/a" when undefined.

    Parameters
    ----------
    x : float or None
        The value, %.

    Returns
    -------
    str
        E.g. "12.3 %"; "n/a" when ``x`` is None or not finite.
    """
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.1f} %"


EFFECT_WORDS = {
    "coulomb_friction": "dry (Coulomb) friction on the motor",
    "deadzone": "a dead-zone in the amplifier",
    "saturation": "amplifier saturation",
    "delay": "extra delay of the command",
    "backlash": "backlash (free play) in the drive train",
    "beam_damping": "the beam's damping",
    "accel_gain": "the accelerometer's sensitivity",
    "static_friction": "breakaway (static) friction on the motor",
    "viscous_friction": "viscous friction on the motor",
    "amp_offset": "an amplifier offset",
}
"""Plain words for the effects of the vocabulary (others are shown by their code name)."""

PARAMETER_WORDS = {
    "mu": "beam mass per length", "EI": "beam bending stiffness (EI)", "drive_k": "drive-train stiffness",
    "drive_c": "drive-train damping", "clamp_k": "clamp stiffness", "clamp_c": "clamp damping",
    "J_base": "base inertia", "m_accel": "accelerometer mass", "J_accel": "accelerometer rotary inertia",
    "act_K": "actuator gain", "act_p": "actuator pole (the motor's own damping)",
}
"""Plain words for the parameters a param:NAME ratio scales."""

OVERSHOOT_POINTS = 3.0
"""A model's step overshoot is on target within this many percentage points of the rig's
(issue 17)."""


def at_range_end(name: str, value: float) -> bool:
    """The value sits at an end of the effect's search range, within the fit's resolution
    (:data:`station.diagnosis.search.bounded.RESOLUTION_STEPS` grid steps): the fit wanted further.
    The neutral value ("no effect", e.g. no friction at 0) does not count.

    Parameters
    ----------
    name : str
        An effect of :data:`station.plant.effects.EFFECTS`.
    value : float
        Its value, in its unit.

    Returns
    -------
    bool
        True at either end (a signed effect by its magnitude); False for an unknown effect, a
        value that is not finite, or the neutral value.
    """
    spec = EFFECTS.get(name)
    if spec is None or not math.isfinite(value) or math.isclose(value, spec.neutral, rel_tol=1e-6, abs_tol=1e-9):
        return False
    if spec.signed:  # a range of the magnitude, either sign (a reversed accelerometer)
        value = abs(value)
    ax = axis_for(name, spec.lower, spec.upper, spec.neutral)
    return any(abs(ax.to_unit(value) - ax.to_unit(b)) <= RESOLUTION_STEPS * ax.step for b in (spec.lower, spec.upper))


def plain_name(name: str) -> str:
    """An effect in plain words with its code name, e.g. "drive-train damping
    (param:drive_c)"; the code name alone when no words are known.

    Parameters
    ----------
    name : str
        The effect's code name.

    Returns
    -------
    str
        "words (code name)", or ``name`` itself.
    """
    words = PARAMETER_WORDS.get(name[6:]) if name.startswith("param:") else EFFECT_WORDS.get(name)
    return f"{words} ({name})" if words else name


def plain_value(name: str, value: float, unit: str) -> str:
    """An effect's value as a person reads it: ratios as "1.98× nominal" (param:NAME) or
    "0.92× the model's" (accel_gain), the beam damping as "ζ = 0.021", the rest with their
    unit (:func:`format_quantity`).

    Parameters
    ----------
    name : str
        The effect's code name.
    value : float
        Its value, in ``unit``.
    unit : str
        Its unit (:data:`station.plant.effects.EFFECTS`).

    Returns
    -------
    str
        The value in words, e.g. "1.98× nominal", "ζ = 0.021" or "12.5 DAC counts".
    """
    if not math.isfinite(value):
        return format_quantity(value, unit)
    if name.startswith("param:"):
        return f"{value:.3g}× nominal"
    if name == "accel_gain":
        return f"{value:.3g}× the model's"
    if name == "beam_damping":
        return f"ζ = {value:.3g}"
    return format_quantity(value, unit)


def interval_words(name: str, interval, unit: str) -> str:
    """ "95 % interval 1.54–3.16", with the range's end named where the interval reaches it.

    Parameters
    ----------
    name : str
        The effect's code name.
    interval : Interval or None
        :class:`station.diagnosis.honesty.doubt.Interval`.
    unit : str
        The effect's unit.

    Returns
    -------
    str
        The phrase, with its unit (none for a dimensionless "1", whole numbers for samples);
        empty when ``interval`` is None.
    """
    if interval is None:
        return ""
    fmt = (lambda x: f"{x:.0f}") if unit == "samples" else (lambda x: f"{x:.3g}")  # noqa: E731
    suffix = "" if unit == "1" else f" {unit}"
    ends = [w for w, at in (("lower", interval.lo_at_bound), ("upper", interval.hi_at_bound)) if at]
    note = f", reaching the {' and '.join(ends)} end of its search range" if ends else ""
    r = getattr(interval, "refits", None)
    if r is not None and (math.isclose(r[0], interval.lo) or math.isclose(r[1], interval.hi)):
        note += f"; refitted without each run {fmt(r[0])}–{fmt(r[1])}: it depends on which runs judge it"
    return f"95 % interval {fmt(interval.lo)}–{fmt(interval.hi)}{suffix}{note}"


def cause_words(effect) -> str:
    """An accepted effect as the answer names it: plain words, code name, value with its
    95 % interval, flagged when the fit sits at its search range's end.

    Parameters
    ----------
    effect : EffectResult

    Returns
    -------
    str
        The phrase, e.g. "drive-train damping (param:drive_c) 1.98× nominal (95 % interval
        1.54–3.16)", without a final period.
    """
    text = f"{plain_name(effect.name)} {plain_value(effect.name, effect.value, effect.unit)}"
    iv = interval_words(effect.name, effect.interval, effect.unit)
    if iv:
        text += f" ({iv})"
    if effect.at_range_end:
        text += " — at the end of its search range: the data want it further"
    return text


def target_notes(diag) -> list[str]:
    """Where the extended model misses its targets: a closed-loop step's overshoot more
    than :data:`OVERSHOOT_POINTS` points from the rig's, and θ residuals that stay far from
    white (more than a quarter of the autocorrelation lags outside the 99 % band).

    Parameters
    ----------
    diag : Diagnosis

    Returns
    -------
    list of str
        One note per run whose overshoot is missed (points of %), then one note for the runs
        whose θ residual is far from white; each without a final period; empty when every
        target is met.
    """
    notes = []
    for r in diag.runs:
        m = r.metrics
        if m is None or m.get("rig") is None or m.get("extended") is None:
            continue
        off = m["extended"].overshoot_pct - m["rig"].overshoot_pct
        if abs(off) > OVERSHOOT_POINTS:
            notes.append(f"overshoot target missed on {r.file}: the extended model {m['extended'].overshoot_pct:.1f} % "
                         f"against the rig's {m['rig'].overshoot_pct:.1f} % ({off:+.1f} points; target within "
                         f"±{OVERSHOOT_POINTS:g})")
    far = [r for r in diag.runs if r.residuals_after is not None and r.residuals_after.theta.outside_pct > 25.0]
    if far:
        lo, hi = (f(r.residuals_after.theta.outside_pct for r in far) for f in (min, max))
        span = f"{lo:.0f} %" if round(lo) == round(hi) else f"{lo:.0f}–{hi:.0f} %"
        notes.append(f"the extended model's θ residual is far from white on {len(far)} of {len(diag.runs)} runs "
                     f"({span} of the autocorrelation lags to 25 samples outside the 99 % band)")
    return notes


def answer_points(diag) -> list[tuple[str, str]]:
    """The answer, point by point: (label, sentence) for what the data contradicted (the log
    audit and the sensor faults, first), the cause, the gain on held-out data, what is still unexplained, the alternatives, the targets missed and how the runs
    were treated.

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned.

    Returns
    -------
    list of tuple of (str, str)
        (label, sentence) pairs in the order above; labels among "Audit", "Cause", "Gain",
        "Still unexplained", "Alternatives", "Target missed", "Residuals", "Note"; each
        sentence ends with a period.
    """
    base = diag.nominal_model.name
    points = [("Audit", line + ".") for line in diag.audit_lines()]
    # the causes as every output names them (Diagnosis.causes): the decided faults lead, each
    # said once (one the fit refined with the fit's interval)
    accepted = {e.name: e for e in diag.effects if e.accepted}
    faults = "; ".join(cause_words(accepted[k]) if k in accepted else
                       f"{plain_name(k)} {plain_value(k, v, EFFECTS[k].unit)}" for k, v in diag.decided_faults.items())
    if not diag.accepted:
        best = diag.effects[0] if diag.effects else None
        extra = "" if best is None else (f" The best candidate, {plain_name(best.name)} "
                                         f"{plain_value(best.name, best.value, best.unit)}, changes the θ RMS error "
                                         f"on held-out data by {best.gain_pct:+.1f} %, below the significance threshold.")
        points.append(("Cause", (f"the sensor faults decided from the data, {faults}; beside them no physical effect "
                                 f"explains the differences between {base} and the runs" if faults else
                                 f"none: no effect explains the differences between {base} and the runs")
                       + f" beyond what sensor quantization and noise can ({diag.validation}).{extra}"))
    else:
        physical = [cause_words(accepted[n]) for n in diag.accepted if n not in diag.decided_faults]
        first, more = (physical or [""])[0], physical[1:]
        points.append(("Cause", (f"the sensor faults decided from the data, {faults}" if faults else "")
                       + ("; then " if faults and first else "" if first else "; no physical effect beside them")
                       + first + (f", together with {'; '.join(more)}" if more else "") + "."))
        points.append(("Gain", f"on runs it was not fitted to ({diag.validation}) the extended model lowers the θ RMS "
                               f"error by {diag.gain_pct:.1f} % (θ fit {format_pct(diag.baseline_fit.get('theta'))} → "
                               f"{format_pct(diag.extended_fit.get('theta'))}, a fit "
                               f"{format_pct(diag.baseline_fit.get('accel'))} → "
                               f"{format_pct(diag.extended_fit.get('accel'))})."))
    u = diag.unexplained
    if u is not None:
        points.append(("Still unexplained", f"{u.evidence} ({diag.prediction_words()})" if u.flag else
                       "nothing: the remaining θ and a residuals are what encoder rounding and accelerometer noise "
                       "produce around the model."))
    if diag.accepted:
        if diag.alternatives:
            alts = "; ".join(f"{' + '.join(a.causes)} (instead of {a.instead_of}; validation cost {a.cost_ratio:.3f}× "
                             f"the chosen one's, θ gain {a.gain_pct:.1f} %)" for a in diag.alternatives)
            points.append(("Alternatives", f"the validation data cannot tell this apart from {alts}."))
        else:
            points.append(("Alternatives", "none: no other explanation comes as close on the validation data"
                           + (f" (beside the sensor wiring the data cannot decide: {diag.wiring_alike})"
                              if diag.wiring_alike else "") + "."))
    for note in target_notes(diag):
        points.append(("Target missed" if note.startswith("overshoot") else "Residuals", note + "."))
    for note in diag.notes:
        points.append(("Note", note + "."))
    return points


def summary_paragraph(diag) -> str:
    """The answer in one paragraph (:func:`answer_points` joined): the cause in plain words
    and code name with its value and 95 % interval, the gain on held-out data, what is still
    unexplained, the alternatives, the targets missed and how the runs were treated.

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned.

    Returns
    -------
    str
        "label: sentence" for each point, joined by spaces.
    """
    return " ".join(f"{label}: {text}" for label, text in answer_points(diag))
