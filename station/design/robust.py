"""The set of models a design is judged on: the nominal model and what the diagnosis doubts.

A design is robust to doubt when it meets its requirements on every model of the set
(DESIGN.md "Designing a compensator on a model"). The set is, in this order:

1. the design model (``--model``: a model file, a built-in name or a diagnosis JSON's extended
   model; without it, the first ``--robust`` diagnosis JSON's extended model);
2. every ``--robust`` file: a model file (TOML, or a built-in model's name), or a diagnosis
   JSON (``station diagnose --json``) giving its ``extended_model`` and each of its
   ``alternatives`` (the nominal parameter set with the alternative's effect ``values``);
3. with ``--samples N`` (N > 0), the intervals' box: the diagnosis JSONs' effect ``interval`` s
   when they have any (a dry friction's widened down to none: :data:`LESS_FRICTION`), around
   the design model, otherwise :data:`DEFAULT_DOUBT`, the rig's usual doubt: its corners (every effect at an end of its interval, up to
   :data:`MAX_CORNER_EFFECTS` effects: a worst case often sits in a corner) and N models drawn
   inside it (a Latin hypercube sample, seeded).

Reading everything happens before any design work, and a bad input is one line naming the
file (a JSON with no model, a model that does not load, an unstable plant).
"""

from __future__ import annotations

import itertools
import math
from pathlib import Path
from typing import NamedTuple

import numpy as np

from station.errors import StationError
from station.inputs import load_json
from station.plant.effects import EFFECTS
from station.plant.model import Model, as_model, load_model
from station.plant.parameters import params_from_dict

DEFAULT_DOUBT = (
    ("coulomb_friction", "absolute", 0.0, 16.0),
    ("static_friction", "ratio", 0.7, 1.5),
    ("amp_offset", "absolute", -3.0, 3.0),
    ("param:drive_c", "ratio", 0.6, 1.4),
    ("param:EI", "ratio", 0.9, 1.1),
)
"""The rig's usual doubt when no diagnosis gives intervals: (effect, how, low, high), what the
diagnosis of the rig's four thesis logs leaves open (docs/diagnosis.md).

"absolute": the effect's value drawn in [low, high]: dry friction from none (a rig with less
friction than the estimate: the 2009 session had 1.2 counts) to 16 DAC counts (what the
open-loop pulses alone ask for; the closed loops ask for about 5), an amplifier offset of ±3
counts (the pulses' −2.7, the 2009 session's −1.5). "ratio": the model's own value times
[low, high]: the drive train's damping 0.6-1.4x (the diagnosis's 95 % interval, 2.36-4.47x
tmm-fit around 3.41x, and least squares' 1.98x), the beam's EI ±10 % (the rig model's first
mode is 5 % high: EI x0.9 would close it, and did not pay held out), breakaway friction only
when the model has it. Effects the simulator does not know are left out."""

LESS_FRICTION = ("coulomb_friction", "static_friction")
"""Dry-friction effects whose diagnosed interval is widened down to none: a rig can have less
friction than the estimate (it drifts: docs/diagnosis.md), and a design must not need it."""

SEED = 0
"""Seed of the drawn models."""

DEFAULT_SAMPLES = 20
"""Models drawn from the doubt by default (besides the nominal and any --robust files)."""

MAX_CORNER_EFFECTS = 4
"""The box's corners join the set when the intervals span at most this many effects (16 models)."""


class RobustSet(NamedTuple):
    """The models a design is judged on.

    Attributes
    ----------
    models : tuple of Model
        ``models[0]`` is the design model.
    labels : tuple of str
        Where each comes from ("nominal", a file, "alternative 2 of X.json", "sample 3").
    intervals : dict
        Effect -> (low, high) the samples were drawn from (empty without samples).
    """

    models: tuple
    labels: tuple
    intervals: dict

    def to_json(self) -> list[dict]:
        """Each model as ``{"label", "name", "effects"}``.

        Returns
        -------
        list of dict
            One per model, in set order: ``label`` (str), ``name`` (str) and ``effects`` (effect
            name to value, the effect's own units).
        """
        return [{"label": lab, "name": m.name, "effects": m.effect_dict()} for m, lab in zip(self.models, self.labels)]


class DiagnosisDoubt(NamedTuple):
    """What a diagnosis JSON says about the model (:func:`read_diagnosis`).

    Attributes
    ----------
    model : Model
        Its extended model.
    alternatives : list of Model
        The explanations the data could not tell apart.
    intervals : dict
        Accepted effect -> (low, high), its 95 % interval (empty when the JSON has none).
    """

    model: Model
    alternatives: list
    intervals: dict


def model_from_json(doc, where: str) -> Model:
    """A Model from its JSON form (:meth:`station.plant.model.Model.to_json`).

    Parameters
    ----------
    doc : dict
        ``{"name", "params", "parameters", "n_elements", "effects"}``.
    where : str
        Named in errors (the file and key).

    Returns
    -------
    Model
        The model: its named parameter set with the given values, ``n_elements`` (4 when absent)
        and effects.

    Raises
    ------
    StationError
        Not a model, a bad parameter or effect.
    """
    if not isinstance(doc, dict) or not isinstance(doc.get("parameters"), dict):
        raise StationError(f"{where}: expected a model (name, parameters, n_elements, effects)")
    effects = doc.get("effects") or {}
    if not isinstance(effects, dict):
        raise StationError(f"{where}.effects: expected a table of effect values")
    params = params_from_dict(dict(doc["parameters"]), where)
    try:
        return Model(name=str(doc.get("name", "model")), params=params, n_elements=doc.get("n_elements", 4),
                     effects=tuple(effects.items()), params_source=str(doc.get("params", params.name)))
    except StationError as exc:
        raise StationError(f"{where}: {exc}") from None


def read_diagnosis(path: str | Path) -> DiagnosisDoubt:
    """Read a diagnosis JSON's extended model, alternatives and intervals.

    Parameters
    ----------
    path : str or Path
        ``station diagnose --json`` output (DESIGN.md "Model diagnosis contract").

    Returns
    -------
    DiagnosisDoubt
        The extended model, one model per alternative (the extended model's nominal parameters
        with the alternative's effect values) and the effects' 95 % intervals.

    Raises
    ------
    StationError
        Unreadable, not JSON, or no ``extended_model`` ("no model"); a bad alternative or interval.
    """
    path = Path(path)
    doc = load_json(path, "diagnosis JSON")  # bounded: a regular file, its nesting limited
    if not isinstance(doc, dict) or not isinstance(doc.get("extended_model"), dict):
        raise StationError(f"{path}: no model in this JSON (expected a diagnosis with \"extended_model\", "
                           f"from station diagnose --json)")
    model = model_from_json(doc["extended_model"], f"{path}: extended_model")
    alternatives = []
    for i, alt in enumerate(doc.get("alternatives") or []):
        values = alt.get("values") if isinstance(alt, dict) else None
        if not isinstance(values, dict):
            raise StationError(f"{path}: alternatives[{i}].values: expected a table of effect values")
        try:
            alternatives.append(model.nominal().with_effects(values, name=f"{model.name} alternative {i + 1}"))
        except StationError as exc:
            raise StationError(f"{path}: alternatives[{i}]: {exc}") from None
    intervals = {}
    for i, eff in enumerate(doc.get("effects") or []):
        if not isinstance(eff, dict) or eff.get("interval") is None:
            continue
        iv = eff["interval"]
        ok = isinstance(iv, list) and len(iv) == 2 and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                           and math.isfinite(x) for x in iv) and iv[0] <= iv[1]
        if not ok or eff.get("name") not in EFFECTS:
            raise StationError(f"{path}: effects[{i}].interval: expected [low, high] of a known effect, got {iv!r}")
        intervals[eff["name"]] = (float(iv[0]), float(iv[1]))
    return DiagnosisDoubt(model, alternatives, intervals)


def default_intervals(model: Model) -> dict[str, tuple[float, float]]:
    """:data:`DEFAULT_DOUBT` around a model (effects the simulator knows only).

    Parameters
    ----------
    model : Model
        Its own values scale the "ratio" entries.

    Returns
    -------
    dict of str to (float, float)
        Effect name to (low, high), the effect's units; a "ratio" effect the model does not
        have (neutral 0) is left out.
    """
    out = {}
    for name, how, lo, hi in DEFAULT_DOUBT:
        if name not in EFFECTS:
            continue
        if how == "ratio":
            own = model.effect(name)
            if own == EFFECTS[name].neutral and EFFECTS[name].neutral == 0.0:
                continue  # a ratio of an absent effect is no doubt
            lo, hi = own * lo, own * hi
        out[name] = (lo, hi)
    return out


def sample_models(model: Model, intervals: dict, n: int, seed: int = SEED) -> list[Model]:
    """``n`` models drawn from the intervals around ``model`` (a Latin hypercube, seeded).

    Parameters
    ----------
    model : Model
        The model the drawn effect values replace their own in.
    intervals : dict
        Effect -> (low, high); each value is clipped to the effect's range.
    n : int
        How many, ≥ 0.
    seed : int
        The sample's seed.

    Returns
    -------
    list of Model
        ``n`` models named "``model.name`` sample k", k from 1; empty when ``n`` ≤ 0 or there
        are no intervals.
    """
    from scipy.stats import qmc  # lazy: start-up time (scipy.stats: the tune command's parser imports this module)

    if n <= 0 or not intervals:
        return []
    pts = qmc.LatinHypercube(len(intervals), seed=seed).random(n)
    return [_model_at(model, intervals, row, f"{model.name} sample {k + 1}") for k, row in enumerate(pts)]


def corner_models(model: Model, intervals: dict) -> list[Model]:
    """The models at the corners of the intervals' box (every effect at an end of its interval),
    when there are at most :data:`MAX_CORNER_EFFECTS` effects (else none).

    Parameters
    ----------
    model : Model
        The model the corner values replace their own in.
    intervals : dict
        Effect -> (low, high).

    Returns
    -------
    list of Model
        2**len(intervals) models named "``model.name`` corner k", k from 1; empty without
        intervals or with more than :data:`MAX_CORNER_EFFECTS` effects.
    """
    if not intervals or len(intervals) > MAX_CORNER_EFFECTS:
        return []
    return [_model_at(model, intervals, np.array(row, dtype=float), f"{model.name} corner {k + 1}")
            for k, row in enumerate(itertools.product((0.0, 1.0), repeat=len(intervals)))]


def _model_at(model: Model, intervals: dict, unit, name: str) -> Model:
    """``model`` with each effect of ``intervals`` at its point ``unit`` (0..1 per effect, sorted names)."""
    values = {}
    for eff, x in zip(sorted(intervals), unit):
        lo, hi = intervals[eff]
        spec = EFFECTS[eff]
        values[eff] = float(min(max(lo + x * (hi - lo), spec.lower), spec.upper))
        if eff == "delay":
            values[eff] = float(round(values[eff]))
    if "static_friction" in values or "coulomb_friction" in values:  # breakaway is never below sliding
        values = _breakaway_above_sliding(model, values)
    return model.with_effects(values, name=name)


def _breakaway_above_sliding(model: Model, values: dict) -> dict:
    if "static_friction" not in EFFECTS:
        return values
    vs = values.get("static_friction", model.effect("static_friction"))
    vc = values.get("coulomb_friction", model.effect("coulomb_friction"))
    if vs != EFFECTS["static_friction"].neutral and vs < vc:
        values = dict(values, static_friction=vc)
    return values


def check_stable(model: Model, where: str) -> None:
    """Refuse a model whose linear plant is unstable (a pole outside the unit circle; the
    rigid-body pole at z = 1 is the plant's own integrator).

    Parameters
    ----------
    model : Model
    where : str
        How the message names it.

    Raises
    ------
    StationError
        Naming ``where`` and the pole.
    """
    lam = np.linalg.eigvals(model.linear_plant().Ad)
    worst = lam[np.argmax(np.abs(lam))]
    if abs(worst) > 1.0 + 1e-9:
        raise StationError(f"{where}: the model is unstable (open-loop pole at |z| = {abs(worst):.6g} > 1); "
                           f"no compensator of the rig's structure is designed on it")


def robust_set(model=None, robust=(), samples: int = 0, seed: int = SEED) -> RobustSet:
    """The models a design is judged on (module docstring), each checked.

    Parameters
    ----------
    model : Model, str, Path or None
        The design model: a Model, a built-in name, a model file or a diagnosis JSON (its
        extended model); None: the first diagnosis JSON's extended model, else "tmm-fit".
    robust : sequence of str or Path
        Model files (or built-in names) and diagnosis JSONs.
    samples : int
        Models drawn from the intervals, ≥ 0 (with any, the box's corners join too).
    seed : int
        Their seed.

    Returns
    -------
    RobustSet
        The models in the order of the module docstring, each labelled, the design model first;
        its ``intervals`` those the samples were drawn from (empty when none were drawn).

    Raises
    ------
    StationError
        A file that cannot be read, a JSON with no model, an unstable model.
    """
    docs, files = [], []
    for item in robust:
        if str(item).lower().endswith(".json"):
            docs.append((str(item), read_diagnosis(item)))
        else:
            files.append((str(item), load_model(item)))
    if model is None and docs:
        nominal = docs[0][1].model
    elif isinstance(model, (str, Path)) and str(model).lower().endswith(".json"):
        nominal = read_diagnosis(model).model  # a diagnosis JSON's extended model
    else:
        nominal = as_model(model)
    models, labels = [nominal], ["nominal"]
    for name, m in files:
        models.append(m)
        labels.append(name)
    for name, doc in docs:
        if doc.model != nominal:
            models.append(doc.model)
            labels.append(f"{name}: extended model")
        for i, alt in enumerate(doc.alternatives):
            models.append(alt)
            labels.append(f"{name}: alternative {i + 1}")
    intervals = {}
    for _, doc in docs:
        intervals.update(doc.intervals)
    # less friction than the estimate, and none
    intervals = {k: ((0.0, hi) if k in LESS_FRICTION else (lo, hi)) for k, (lo, hi) in intervals.items()}
    if not intervals:
        intervals = default_intervals(nominal)
    corners = corner_models(nominal, intervals) if samples > 0 else []
    drawn = sample_models(nominal, intervals, samples, seed)
    models += corners + drawn
    labels += [f"corner {k + 1}" for k in range(len(corners))] + [f"sample {k + 1}" for k in range(len(drawn))]
    for m, lab in zip(models, labels):
        check_stable(m, f"model {m.name!r} ({lab})")
    return RobustSet(tuple(models), tuple(labels), intervals if drawn else {})
