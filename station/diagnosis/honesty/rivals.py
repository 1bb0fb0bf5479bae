"""The competing explanations a diagnosis leaves open (:func:`rivals`): what an experiment
design must tell apart from the chosen explanation.

A rival is a set of effects over the nominal model, beside the chosen one (the accepted
effects at their values):

- each of the diagnosis's ``alternatives`` (DESIGN.md: other explanations the validation data
  cannot tell apart, ``{"causes", "values", "gain_pct", "cost_ratio"}``);
- for each accepted effect whose 95 % ``interval`` is wide (half its width more than
  :data:`WIDE_INTERVAL` of the value), the chosen explanation with that effect at each end
  of the interval (the other effects kept: a one-at-a-time bracket, not a profile).

Fallbacks for a diagnosis without those keys: intervals from the jackknife over its folds
(the accepted effects' values fitted with one run left out: value ± 1.96 σ_jack,
σ²_jack = (n−1)/n Σ (v_i − v̄)²), and as alternatives the candidates that alone gained at least
:data:`RUNNER_UP_FRACTION` of what the first accepted effect gained alone, each in its place.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, NamedTuple

from station.diagnosis.units import format_quantity
from station.diagnosis.search.fitting import NESTED, SHAPE
from station.plant.effects import EFFECTS

WIDE_INTERVAL = 0.1
"""An accepted value's 95 % interval is wide when half its width exceeds this fraction of the
value (the target of ``station identify``: each value within 25 %)."""

RUNNER_UP_FRACTION = 0.75
"""Fallback alternatives: candidates whose cost gain alone reached this fraction of the first
accepted effect's."""

JACKKNIFE_Z = 1.96
"""Normal quantile of a 95 % interval (the jackknife fallback)."""


class Rival(NamedTuple):
    """One competing explanation.

    Attributes
    ----------
    effects : dict of str to float
        Effect name -> value over the nominal model.
    label : str
        In words, e.g. "coulomb_friction 15 DAC counts (the 95 % interval's upper end)".
    kind : {"alternative", "interval"}
        Where it came from.
    """

    effects: dict
    label: str
    kind: str


class Rivals(NamedTuple):
    """The chosen explanation and its rivals (:func:`rivals`).

    Attributes
    ----------
    chosen : dict of str to float
        The accepted effects' values ({} for "none").
    label : str
        The chosen explanation in words ("the nominal model" for none).
    rivals : list of Rival
    sources : list of str
        How they were found, in words (e.g. "jackknife intervals over 4 folds").
    wide : list of str
        Accepted effects whose interval is wide.
    """

    chosen: dict
    label: str
    rivals: list
    sources: list
    wide: list


def _get(obj: Any, key: str, default=None):
    """An attribute of a typed record, or a key of its JSON form."""
    if isinstance(obj, Mapping):
        return obj.get(key, default)
    return getattr(obj, key, default)


def describe(effects: Mapping[str, float]) -> str:
    """A set of effects in words: "coulomb_friction 10 DAC counts + param:drive_c 2".

    Parameters
    ----------
    effects : mapping of str to float
        Effect name -> value.

    Returns
    -------
    str
        "name value unit" per effect joined by " + "; "the nominal model" when there are none.
    """
    if not effects:
        return "the nominal model"
    return " + ".join(f"{n} {format_quantity(v, EFFECTS[n].unit)}" for n, v in effects.items())


def jackknife_interval(value: float, fold_values: list[float]) -> tuple[float, float] | None:
    """value ± 1.96 σ_jack over leave-one-run-out fold values (None for fewer than two).

    Parameters
    ----------
    value : float
        The value fitted on all runs.
    fold_values : list of float
        The value fitted in each fold (one run left out each).

    Returns
    -------
    tuple of (float, float) or None
        (low, high) in the value's unit; None with fewer than two finite fold values.
    """
    v = [x for x in fold_values if math.isfinite(x)]
    if len(v) < 2:
        return None
    mean = sum(v) / len(v)
    sigma = math.sqrt((len(v) - 1) / len(v) * sum((x - mean) ** 2 for x in v))
    return value - JACKKNIFE_Z * sigma, value + JACKKNIFE_Z * sigma


def _clip(name: str, x: float, chosen: Mapping[str, float]) -> float:
    """x within the effect's range (a breakaway level no lower than its sliding level)."""
    spec = EFFECTS[name]
    if spec.signed and x < 0:  # a range of the magnitude (a reversed accelerometer)
        return -min(max(-x, spec.lower), spec.upper)
    x = min(max(x, spec.lower, chosen.get(NESTED.get(name, ""), spec.lower)), spec.upper)
    return float(round(x)) if spec.unit == "samples" else x


def _intervals(diag, accepted: list) -> tuple[dict, str]:
    """Each accepted effect's interval: the diagnosis's own, else the jackknife over its folds."""
    out, jack = {}, 0
    folds = getattr(diag, "folds", None) or []
    for e in accepted:
        iv = _get(e, "interval")
        if iv is not None:
            lo, hi = (iv[0], iv[1]) if isinstance(iv, (list, tuple)) and not hasattr(iv, "lo") else (iv.lo, iv.hi)
        else:
            found = jackknife_interval(e.value, [f["values"][e.name] for f in folds if e.name in f.get("values", {})])
            if found is None:
                continue
            (lo, hi), jack = found, len(folds)
        if lo is not None and hi is not None:
            out[e.name] = (float(lo), float(hi))
    how = f"jackknife intervals over {jack} folds (the diagnosis gave none)" if jack else "the diagnosis's 95 % intervals"
    return out, how


def _alternatives(diag, accepted: list) -> tuple[list[dict], str]:
    """The diagnosis's alternatives as {name: value}; else the runner-ups of step 1."""
    alts = getattr(diag, "alternatives", None)
    if alts is not None:
        found = []
        for a in alts:
            values = dict(_get(a, "values") or {})
            causes = list(_get(a, "causes") or values)
            held = [k for n in causes for k in _holds(n) if k not in causes]
            found.append({n: float(values[n]) for n in causes + held if n in values})
        return found, "the diagnosis's alternatives"
    first = accepted[0]
    rest = {n: v for n, v in explanation(diag).items() if n != first.name and n not in _holds(first.name)}
    found = [{**{n: v for n, v in rest.items() if n != e.name}, e.name: e.value}
             for e in diag.effects
             if not e.accepted and e.cost_gain_pct > 0 and e.cost_gain_pct >= RUNNER_UP_FRACTION * first.cost_gain_pct
             and math.isfinite(e.value)]
    return found, (f"candidates that alone gained at least {RUNNER_UP_FRACTION:.0%} of {first.name}'s gain "
                   "(the diagnosis gave no alternatives)")


def _holds(name: str) -> tuple:
    """The values an effect brings along: a static_friction's sliding level and shape."""
    return (NESTED[name], SHAPE) if name in NESTED else ()


def _accepted(diag) -> list:
    """The accepted effects' records, in the order they were added."""
    accepted = [e for e in diag.effects if e.accepted]
    order = diag.accepted
    accepted.sort(key=lambda e: order.index(e.name) if e.name in order else len(order))
    return accepted


def explanation(diag) -> dict:
    """The chosen explanation's values: the accepted effects, in the order they were added, with
    what they hold (a static_friction's sliding level coulomb_friction and stribeck_speed:
    :data:`station.diagnosis.search.fitting.NESTED`, :data:`~station.diagnosis.search.fitting.SHAPE`),
    from the diagnosis's extended model. Simulating, refitting or comparing the accepted
    effects without them would be another model (a breakaway with no sliding level).

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned (or its JSON form).

    Returns
    -------
    dict of str to float
        Effect name to value (its unit): the accepted effects in order, then the effects they
        hold, as in the extended model.
    """
    chosen = {e.name: float(e.value) for e in _accepted(diag)}
    ext = _get(diag, "extended_model")
    ext = ext.effect_dict() if hasattr(ext, "effect_dict") else dict(_get(ext, "effects") or {}) if ext else {}
    for n in list(chosen):
        for k in _holds(n):
            if k in ext and k not in chosen:
                chosen[k] = float(ext[k])
    return chosen


def rivals(diag, wide: float = WIDE_INTERVAL) -> Rivals:
    """The explanations a diagnosis leaves open beside the one it chose (module docstring).

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned (its ``alternatives`` and each
        effect's ``interval`` when it has them).
    wide : float
        Half an interval's width, as a fraction of the value, above which its ends are rivals.

    Returns
    -------
    Rivals
        No rivals when the diagnosis accepted nothing (nothing to tell apart) or singled out
        one explanation with narrow intervals.
    """
    accepted = _accepted(diag)
    chosen = explanation(diag)
    label = describe(chosen)
    if not accepted:
        return Rivals({}, label, [], [], [])
    found: list[Rival] = []
    alts, how_alt = _alternatives(diag, accepted)
    for values in alts:
        if values and values != chosen:
            found.append(Rival(values, f"alternative {describe(values)}", "alternative"))
    intervals, how_iv = _intervals(diag, accepted)
    wide_names = []
    for name, (lo, hi) in intervals.items():
        value = chosen[name]
        if value == 0 or (hi - lo) / 2 <= wide * abs(value):
            continue
        wide_names.append(name)
        for end, x in (("lower", lo), ("upper", hi)):
            x = _clip(name, x, chosen)
            if x != value:
                effects = {**chosen, name: x}
                found.append(Rival(effects, f"{name} {format_quantity(x, EFFECTS[name].unit)} "
                                            f"(the 95 % interval's {end} end)", "interval"))
    sources = [how_alt] if alts else []
    if intervals:
        sources.append(how_iv)
    return Rivals(chosen, label, found, sources, wide_names)
