"""A model of the rig: a parameter set, an element count and effects (DESIGN.md "Model file").

One object everywhere a model is used (simulated device, replay, compare, bode, modes,
diagnosis) and one TOML file::

    name = "rig-2013"            # free text
    params = "tmm-fit"           # a built-in parameter set, or a path relative to this file
    n_elements = 4
    [effects]                    # optional; names and units of station.plant.effects
    coulomb_friction = 5.0
    static_friction = 9.0        # breakaway level (>= coulomb_friction)
    stribeck_speed = 0.05        # rad/s of the motor: static_friction's Stribeck curve
    "param:drive_c" = 2.0
    accel_gain = -1.2            # a sensor fault: an accelerometer read with the opposite sign
    accel_mounted = 0            # a configuration: no accelerometer on the beam (1, the default: on it)

Built-in models live in ``station/plant/models/<name>.toml`` ("tmm-fit": the nominal
4-element model). ``params`` may also be an inline table of the parameter set's fields
(what :meth:`Model.to_toml` writes for a set that is not a file).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from station.rig import DT
from station.errors import StationError
from station.plant.discrete import DiscretePlant
from station.inputs import TomlDoc, exists, load_toml
from station.plant.effects import EFFECTS, check_effects
from station.plant.kernel import ModelPlant
from station.plant.modal import LinearForm, linear_form  # noqa: F401 (LinearForm re-exported: it lived here)
from station.plant.modes import hub_held_modes, with_beam_damping
from station.plant.parameters import PARAMS_DIR, Params, builtin_params, load_params, params_from_dict
from station.ranges import N_ELEMENTS, RangeError

MODELS_DIR = Path(__file__).resolve().parent / "models"
"""Folder of the built-in models (``<name>.toml``)."""

SUBSTEPS = 10
"""Default sub-steps per sample when friction or backlash act (tests/test_model_simulate.py
shows the θ of a 2 s run converged to well under a count at this grid)."""

_KEYS = ("name", "params", "n_elements", "effects")

STABLE_TOLERANCE = 1e-6
"""How far above 1 a sampled eigenvalue's modulus may be before :func:`load_model` refuses
the model (the plant is passive: every mode decays or, the rigid-body one, stays)."""


@dataclass(frozen=True)
class Model:
    """A parameter set, an element count and effects.

    Attributes
    ----------
    name : str
        Free text shown in reports and log headers.
    params : Params
        The nominal parameter set (param:NAME ratios are not folded in).
    n_elements : int, default 4
        Beam elements, 1..100.
    effects : tuple of (str, float) pairs
        Sorted by name, no neutral values (see :meth:`effect_dict`); validated with
        :func:`station.plant.effects.check_effects`.
    params_source : str, default "tmm-fit"
        Where ``params`` came from: a built-in set's name or a file path.
    """

    name: str
    params: Params
    n_elements: int = 4
    effects: tuple[tuple[str, float], ...] = ()
    params_source: str = "tmm-fit"

    def __post_init__(self) -> None:
        try:
            n = N_ELEMENTS.check(self.n_elements)
        except RangeError as exc:
            raise StationError(f"model {self.name!r}: n_elements: {exc}", key="n_elements") from None
        values = check_effects(dict(self.effects), f"model {self.name!r}")
        pairs = tuple(sorted((k, v) for k, v in values.items() if v != EFFECTS[k].neutral))
        object.__setattr__(self, "n_elements", n)
        object.__setattr__(self, "effects", pairs)
        object.__setattr__(self, "_memo", {})

    # the linear part, remembered per model: a fit simulates one model on several runs, and
    # the module's caches would hash the parameter set again for each (not pickled)
    def __getstate__(self) -> dict:
        return {k: v for k, v in self.__dict__.items() if k != "_memo"}

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state, _memo={})

    def effect_dict(self) -> dict[str, float]:
        """The effects as {name: value} (only non-neutral ones)."""
        return dict(self.effects)

    def effect(self, name: str) -> float:
        """The value of one effect, its neutral value when absent.

        Parameters
        ----------
        name : str
            An effect of :data:`station.plant.effects.EFFECTS`.
        """
        return self.effect_dict().get(name, EFFECTS[name].neutral)

    def with_effects(self, effects: Mapping[str, float], name: str | None = None) -> Model:
        """A copy with ``effects`` updated over this model's (a neutral value removes one).

        Parameters
        ----------
        effects : mapping of str to float
            Effect name -> value, in the effect's unit.
        name : str, optional
            The copy's name (default: this model's).

        Raises
        ------
        StationError
            Unknown effect or value out of range.
        """
        merged = self.effect_dict()
        merged.update(check_effects(effects, f"model {name or self.name!r}"))
        return dataclasses.replace(self, name=self.name if name is None else name, effects=tuple(merged.items()))

    def nominal(self) -> Model:
        """The same parameter set and element count, without effects."""
        return dataclasses.replace(self, effects=())

    @property
    def has_plant_effects(self) -> bool:
        """True when friction or backlash act (sub-stepped simulation)."""
        return any(EFFECTS[k].kind == "plant" for k, _ in self.effects)

    def linear_params(self) -> Params:
        """The parameter set of the linear part: param:NAME ratios applied (and the
        accelerometer's mass taken off with ``accel_mounted`` 0), then the beam damping (``beam_beta``) that gives the beam_damping effect's first-mode ζ.

        A beam_damping at or below :meth:`beam_damping_floor` leaves ``beam_beta`` = 0
        (:func:`load_model` refuses a file that asks for less; a fit's search may try it).
        """
        memo = self._memo.get("params")
        if memo is None:
            linear = tuple((k, v) for k, v in self.effects if EFFECTS[k].kind == "linear")
            memo = self._memo["params"] = _linear_params(self.params, self.n_elements, linear)
        return memo

    def beam_damping_floor(self) -> float:
        """The first-mode damping ratio of the linear part without beam damping (param:NAME
        ratios applied, ``beam_beta`` = 0): the lowest ``beam_damping`` this model can have.

        Returns
        -------
        float
            Damping ratio of the first hub-held mode, 1 (tmm-fit, 4 elements: 0.0054).
        """
        p = dataclasses.replace(_ratio_params(self.params, self.effect_dict()), beam_beta=0.0)
        return float(hub_held_modes(p, self.n_elements).damping[0])

    def linear_form(self, dt: float = DT, substeps: int | None = None) -> LinearForm:
        """The modal form of the linear part, cached per (parameters, elements, dt, sub-steps).

        Parameters
        ----------
        dt : float
            Sample time, s.
        substeps : int, optional
            Sub-steps per sample when friction or backlash act (default :data:`SUBSTEPS`);
            ignored (1) without them.
        """
        m = (SUBSTEPS if substeps is None else int(substeps)) if self.has_plant_effects else 0
        key = ("form", float(dt), m)
        memo = self._memo.get(key)
        if memo is None:
            memo = self._memo[key] = linear_form(self.linear_params(), self.n_elements, float(dt), m)
        return memo

    def linear_plant(self, dt: float = DT) -> DiscretePlant:
        """The linear part sampled by exact ZOH (what a frequency response or the
        small-signal closed loop can show; friction, backlash and the amplifier's
        effects are left out).

        Parameters
        ----------
        dt : float, default 0.002
            Sample time, s.

        Returns
        -------
        DiscretePlant
            On :meth:`linear_params` and this model's element count, at rest.
        """
        return DiscretePlant(self.linear_params(), n_elements=self.n_elements, dt=dt)

    def plant(self, dt: float = DT, substeps: int | None = None) -> ModelPlant:
        """A plant stepped tick by tick with this model's effects (for the simulated device).

        Parameters
        ----------
        dt : float, default 0.002
            Sample time, s.
        substeps : int, optional
            Sub-steps per sample for friction and backlash (default: the kernel's choice).

        Returns
        -------
        station.plant.kernel.ModelPlant
            ``reset()``, ``outputs() -> (theta, a)``, ``advance(v)``; equal to
            :func:`station.plant.simulate` sample for sample.
        """
        return ModelPlant(self, dt, substeps)

    def to_json(self) -> dict[str, Any]:
        """JSON-able description for log headers and reports: name, params (source),
        parameters (the set's values), n_elements, effects."""
        return {"name": self.name, "params": self.params_source, "parameters": _params_dict(self.params),
                "n_elements": self.n_elements, "effects": self.effect_dict()}

    def to_toml(self) -> str:
        """The model file's text (DESIGN.md "Model file"); :func:`load_model` reads it back."""
        lines = [f"name = {json.dumps(self.name)}"]
        inline = not _source_gives(self.params_source, self.params)
        if not inline:
            lines.append(f"params = {json.dumps(self.params_source)}")
        lines.append(f"n_elements = {self.n_elements}")
        if self.effects:
            lines += ["", "[effects]"]
            lines += [f"{json.dumps(k)} = {_toml_float(v)}" for k, v in self.effects]
        if inline:
            lines += ["", "[params]"]
            for k, v in _params_dict(self.params).items():
                lines.append(f"{k} = {json.dumps(v) if isinstance(v, str) else _toml_float(v)}")
        return "\n".join(lines) + "\n"

    def save(self, path: str | Path) -> None:
        """Write :meth:`to_toml` to ``path``.

        Parameters
        ----------
        path : str or Path
            The TOML file to write (DESIGN.md "Model file").
        """
        Path(path).write_text(self.to_toml())


def _params_dict(params: Params) -> dict[str, Any]:
    return {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}


def _toml_float(x: float) -> str:
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return repr(float(x))


def _source_gives(source: str, params: Params) -> bool:
    try:
        return load_params(source) == params
    except StationError:
        return False


def _is_path(text: str) -> bool:
    return text.endswith(".toml") or "/" in text or "\\" in text


def builtin_models() -> list[str]:
    """Names of the built-in models (``station/plant/models/*.toml``)."""
    return sorted(p.stem for p in MODELS_DIR.glob("*.toml"))


def load_model(name_or_path: str | Path = "tmm-fit", n_elements: int | None = None,
               params: str | Path | None = None) -> Model:
    """Read a model: a built-in's name or a model file (DESIGN.md "Model file"), bounded.

    The file is read by :func:`station.inputs.load_toml` (a regular file of at most 1 MB,
    UTF-8, nested at most 8 deep); every field is checked before the model is used: the
    element count against :data:`station.ranges.N_ELEMENTS`, the parameter set's fields
    against :data:`station.plant.parameters.PARAM_RANGES`, each effect against
    :data:`station.plant.effects.EFFECTS`; a ``beam_damping`` below the first-mode damping
    the set has without beam damping is out of range (DESIGN.md), and the sampled plant
    (:meth:`Model.linear_form`, cached for the run that follows) must come out finite and
    stable. What the file asks for is what runs, or the file is refused.

    Parameters
    ----------
    name_or_path : str or Path, default "tmm-fit"
        A built-in model's name (``station/plant/models/<name>.toml``) or a path to a
        TOML model file.
    n_elements : int, optional
        Overrides the file's element count (``--elements``).
    params : str or Path, optional
        Overrides the file's parameter set (``--params``): a built-in set's name or a
        parameter-set file.

    Returns
    -------
    Model

    Raises
    ------
    StationError
        Missing file, not a regular file, too large, not UTF-8, invalid or too deeply
        nested TOML, unknown key, a value of the wrong type, an unknown effect or a value
        out of range: one line naming the file, line and key.
    """
    text_name = str(name_or_path)
    path = Path(text_name) if _is_path(text_name) else MODELS_DIR / f"{text_name}.toml"
    if not _is_path(text_name) and not exists(path):
        raise StationError(f"{path}: model file not found (built-in models: {', '.join(builtin_models())})",
                           file=path)
    doc = load_toml(path, "model file")
    raw = doc.data
    if not raw:  # nothing said: it would run as tmm-fit, silently (a file emptied by mistake)
        raise StationError(f"{path}: an empty model file: expected at least one of {', '.join(_KEYS)} "
                           f"(a file that names nothing is no model)", file=path)
    unknown = [k for k in raw if k not in _KEYS]
    if unknown:
        raise doc.error(unknown[0], f"unknown key (expected {', '.join(_KEYS)})")
    name = raw.get("name", path.stem)
    if not isinstance(name, str):
        raise doc.error("name", f"expected a string, got {name!r}")
    if n_elements is not None:  # the caller's override, not the file's
        try:
            n = N_ELEMENTS.check(n_elements)
        except RangeError as exc:
            raise StationError(f"n_elements: {exc}", key="n_elements") from None
    else:
        try:
            n = N_ELEMENTS.check(raw.get("n_elements", 4))
        except RangeError as exc:
            raise doc.error("n_elements", str(exc)) from None
    p, source = _read_params(doc, name, params)
    effects = raw.get("effects", {})
    if not isinstance(effects, dict):
        raise doc.error("effects", "expected a table [effects]")
    for key, value in effects.items():
        try:
            check_effects({key: value})
        except StationError as exc:
            raise doc.error(key, str(exc), "effects") from None
    try:
        check_effects(effects)  # the rules between effects (static_friction >= coulomb_friction)
    except StationError as exc:
        raise doc.error("static_friction", str(exc), "effects") from None
    model = Model(name=name, params=p, n_elements=n, effects=tuple(effects.items()), params_source=source)
    _check_runs_as_written(model, doc)
    return model


def _read_params(doc: TomlDoc, name: str, override: str | Path | None) -> tuple[Params, str]:
    """The model file's parameter set (or the override) and where it came from."""
    path, raw = doc.path, doc.data
    if override is not None:
        return load_params(override), str(override)
    source = raw.get("params", "tmm-fit")
    if isinstance(source, dict):
        p = params_from_dict({"name": name, **source}, f"{path} [params]", lambda key: doc.line_of(key, "params"))
        return p, f"{path} [params]"
    if not isinstance(source, str):
        raise doc.error("params", f"expected a parameter set's name or path, got {source!r}")
    if _is_path(source):
        if not Path(source).is_absolute():
            source = str((path.parent / source).resolve())  # relative to the model file
    elif not exists(PARAMS_DIR / f"{source}.toml"):
        raise doc.error("params", f"unknown parameter set {source!r} (built-in sets: {', '.join(builtin_params())})")
    try:
        return load_params(source), source
    except StationError as exc:  # the set's own file at fault: say which model file named it
        raise doc.error("params", str(exc)) from None


def _check_runs_as_written(model: Model, doc: TomlDoc) -> None:
    """Refuse a model that would not run as its file says: a beam_damping below what its
    parameter set has without beam damping (it would be ignored), or a parameter set
    whose FEM matrices are not finite numbers."""
    zeta = model.effect_dict().get("beam_damping")
    if zeta is not None:
        floor = model.beam_damping_floor()
        if zeta < floor:
            raise doc.error("beam_damping", f"{zeta:g} is below {floor:.4g}, the first-mode damping ratio of the "
                            f"parameter set without beam damping ({model.n_elements} elements, its param:NAME "
                            f"ratios applied): out of range (a lower damping is param:clamp_c < 1)", "effects")
    try:  # the form the simulation steps (cached: the run that follows reuses it)
        form = model.linear_form()
        arrays = (form.lam, form.bm, form.bp, form.cm, form.co, form.vinv)
        finite = all(np.all(np.isfinite(x)) for x in arrays) and math.isfinite(form.gw_v + form.gw_p)
        radius = float(np.max(np.abs(form.lam))) if finite and form.lam.size else 0.0
        why = "" if finite else " (not finite numbers)"
    except (ArithmeticError, ValueError, np.linalg.LinAlgError) as exc:
        finite, radius, why = False, 0.0, f" ({type(exc).__name__}: {str(exc)[:200]})"
    if finite and radius > 1.0 + STABLE_TOLERANCE:  # a passive plant: rounding has taken over
        finite, why = False, f" (a sampled eigenvalue of modulus {radius:.6g} > 1: the matrices are too ill-conditioned)"
    if not finite:
        raise StationError(f"{doc.path}: parameter set {model.params_source!r} with {model.n_elements} elements"
                           f"{' and these effects' if model.effects else ''} gives a FEM plant that cannot be "
                           f"computed{why}", file=doc.path, key="params")


def as_model(model: Model | str | Path | None, n_elements: int | None = None,
             params: str | Path | None = None) -> Model:
    """A Model as given, or loaded by :func:`load_model` (None: "tmm-fit").

    Parameters
    ----------
    model : Model, str, Path or None
        A Model, a built-in model's name or a model file; None: "tmm-fit".
    n_elements : int, optional
        Overrides the model's element count.
    params : str or Path, optional
        A parameter set (name or file) replacing the model's.
    """
    if isinstance(model, Model):
        if n_elements is not None:
            model = dataclasses.replace(model, n_elements=n_elements)
        if params is not None:
            model = dataclasses.replace(model, params=load_params(params), params_source=str(params))
        return model
    return load_model("tmm-fit" if model is None else model, n_elements, params)


# --- the linear part, cached ------------------------------------------------------------

def _ratio_params(params: Params, values: Mapping[str, float]) -> Params:
    """The parameter set with the param:NAME ratios of ``values`` applied, and without the
    accelerometer's mass and rotary inertia when ``accel_mounted`` is 0."""
    ratios = {k.split(":", 1)[1]: v for k, v in values.items() if k.startswith("param:")}
    if values.get("accel_mounted", 1.0) == 0.0:  # taken off the beam: no ratio brings it back
        ratios.update(m_accel=0.0, J_accel=0.0)
    return dataclasses.replace(params, **{k: getattr(params, k) * r for k, r in ratios.items()}) if ratios else params


@functools.lru_cache(maxsize=512)
def _linear_params(params: Params, n_elements: int, linear: tuple[tuple[str, float], ...]) -> Params:
    values = dict(linear)
    p = _ratio_params(params, values)
    b = values.get("viscous_friction")
    if b:
        p = with_viscous_friction(p, b)
    zeta = values.get("beam_damping")
    if zeta is not None:
        try:
            p = with_beam_damping(p, zeta, n_elements)
        except ValueError:  # below the floor: only a fit's search gets here (load_model refuses it)
            p = dataclasses.replace(p, beam_beta=0.0)
    return p


def with_viscous_friction(params: Params, b: float) -> Params:
    """The parameter set whose motor has the extra viscous friction torque k_tau·b·ω.

    The actuator's damping is c_m = act_p·J_m with J_m = k_tau/num, num = act_K·|2πj +
    act_p| (DESIGN.md): act_p grows by b·num and act_K shrinks so that num, hence J_m, stays
    the same, which adds exactly k_tau·b to c_m (to rounding).

    Parameters
    ----------
    params : Params
    b : float
        Viscous friction, DAC counts per rad/s of the motor (>= 0).

    Returns
    -------
    Params
        With ``act_p`` and ``act_K`` changed; the other fields as given.
    """
    num = params.act_num
    act_p = params.act_p + b * num
    return dataclasses.replace(params, act_p=act_p, act_K=num / abs(complex(act_p, 2.0 * math.pi)))


__all__ = ["MODELS_DIR", "SUBSTEPS", "LinearForm", "Model", "as_model", "builtin_models", "linear_form",
           "load_model", "with_viscous_friction"]
