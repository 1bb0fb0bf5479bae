"""The diagnosis in words: values with their units, each candidate's evidence sentence and
the summary paragraph of the report."""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from station.analysis.residuals import RunResiduals

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


def format_value(x: float, unit: str) -> str:
    """An effect's value with its unit: whole samples, else 3 significant digits; "∞" when
    infinite; no unit for ratios ("1").

    Parameters
    ----------
    x : float
        The value, in ``unit``.
    unit : str
        The effect's unit (:data:`station.plant.effects.EFFECTS`).
    """
    if not math.isfinite(x):
        return "∞"
    s = f"{x:.0f}" if unit == "samples" else f"{x:.3g}"
    return s + ("" if unit == "1" else f" {unit}")


def signature_evidence(name: str, before: Mapping[str, RunResiduals]) -> str:
    """The nominal model's residual signatures that speak for an effect (at most three).

    Parameters
    ----------
    name : str
        The effect (:data:`SIGNATURE_WORDS`; others: resonances and amplitude ratios).
    before : mapping of str to RunResiduals
        Run name -> residual analysis of the nominal model.
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
    """
    spread = (f" (folds {format_value(min(fold_values), unit)} to {format_value(max(fold_values), unit)})"
              if len(fold_values) > 1 else "")
    words = [f"fitted alone {format_value(alone, unit)}{spread}; on {how} the nominal model plus it "
             f"changes θ RMS {rms_nominal:.2f} -> {rms_alone:.2f} counts "
             f"({gain_pct:+.1f} %), the joint θ+a cost by {cost_gain_pct:+.1f} %"]
    if step is not None:
        words.append(f"accepted at step {step} of forward selection"
                     + (f", {format_value(joint, unit)} in the joint model" if joint is not None else ""))
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
    """
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.1f} %"


def summary_paragraph(diag) -> str:
    """One paragraph naming the cause, its value and the gain.

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned.
    """
    base = diag.nominal_model.name
    if not diag.causes:
        best = diag.effects[0] if diag.effects else None
        extra = "" if best is None else (f" The best candidate, {best.name} = {format_value(best.value, best.unit)}, "
                                         f"changes the θ RMS error on held-out data by {best.gain_pct:+.1f} %, "
                                         "below the significance threshold.")
        return (f"No effect explains the differences between {base} and the runs beyond what sensor "
                f"quantization and noise can: the cause is \"none\" ({diag.validation}).{extra}")
    accepted = {e.name: e for e in diag.effects if e.accepted}
    parts = [f"{n} = {format_value(accepted[n].value, accepted[n].unit)}" for n in diag.causes]
    more = "" if len(parts) == 1 else f", together with {', '.join(parts[1:])}"
    first = accepted[diag.causes[0]]
    value = format_value(first.value, first.unit)
    what = (f"has its {first.name[6:]} off: {value} times the nominal value" if first.name.startswith("param:")
            else f"is missing {first.name}: fitted value {value}")
    return (f"The model {base} {what}{more}. "
            f"On data it was not fitted to ({diag.validation}) the extended model lowers the θ RMS error by "
            f"{diag.gain_pct:.1f} % (NRMSE fit of θ {format_pct(diag.baseline_fit.get('theta'))} → "
            f"{format_pct(diag.extended_fit.get('theta'))}, of a {format_pct(diag.baseline_fit.get('accel'))} → "
            f"{format_pct(diag.extended_fit.get('accel'))}). Evidence: {first.evidence}.")
