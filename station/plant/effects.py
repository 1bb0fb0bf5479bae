"""The vocabulary of model effects: names, units, neutral values and fit ranges.

DESIGN.md "Model diagnosis contract": every effect is named and valued in device units
that do not depend on a model's internals (DAC counts, samples, encoder counts, ratios).
Where each acts:

- "amplifier" (on the command, in this order after the device's command quantization):
  saturation, deadzone, delay;
- "plant" (inside the plant, integrated on a sub-step grid): coulomb_friction, backlash;
- "linear" (rebuild the linear FEM part): beam_damping, param:NAME;
- "output": accel_gain (on the accelerometer output, before its quantization).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np

from station.errors import StationError
from station.plant.diskcache import cached_arrays
from station.plant.modes import modal_summary
from station.plant.parameters import load_params


class EffectSpec(NamedTuple):
    """One effect of the vocabulary.

    Attributes
    ----------
    name : str
        As in DESIGN.md ("coulomb_friction", ..., "param:drive_c").
    unit : str
        "DAC counts", "samples", "encoder counts" or "1".
    neutral : float
        The value that means "no effect".
    lower, upper : float
        The range a fit may search (and a model file may hold, besides ``neutral``).
    kind : {"amplifier", "plant", "linear", "output"}
        Where it acts (module docstring).
    """

    name: str
    unit: str
    neutral: float
    lower: float
    upper: float
    kind: str


PARAM_NAMES = ("mu", "EI", "drive_k", "drive_c", "clamp_k", "clamp_c", "J_base", "m_accel", "J_accel",
               "act_K", "act_p")
"""Parameters a param:NAME ratio may scale (all of the table but beam_beta, L, k_tau, a_gain)."""

AMPLIFIER_ORDER = ("saturation", "deadzone", "delay")
"""DESIGN.md: after the device's command quantization, in this order."""


def _nominal_beam_damping() -> float:
    # tmm-fit's own first hub-held mode damping ratio (from the clamp damper alone); cached
    # on disk: an eigenvalue problem at import would cost every command scipy's start-up
    params = load_params("tmm-fit")
    return float(cached_arrays("beam-damping", tuple(vars(params).values()), lambda: {
        "zeta": np.asarray(modal_summary(params, 4).antiresonance_damping[0])})["zeta"])


PARAM_RATIO_RANGE = (0.1, 10.0)
"""The range of a param:NAME ratio (fit search and model files). DESIGN.md fixes only its
meaning; on the rig's four thesis logs a 0.25..4 range stopped four of the eleven single
fits at its ends (drive_c 4, act_p 4, drive_k 0.25, J_base 0.25), so it spans a decade
either way."""

BEAM_DAMPING_NOMINAL = _nominal_beam_damping()
"""First-mode damping ratio of tmm-fit (4 elements, beam_beta = 0), about 0.0054."""

EFFECTS: dict[str, EffectSpec] = {
    spec.name: spec
    for spec in (
        EffectSpec("coulomb_friction", "DAC counts", 0.0, 0.0, 40.0, "plant"),
        EffectSpec("deadzone", "DAC counts", 0.0, 0.0, 40.0, "amplifier"),
        EffectSpec("saturation", "DAC counts", math.inf, 50.0, 255.0, "amplifier"),
        EffectSpec("delay", "samples", 0.0, 0.0, 6.0, "amplifier"),
        EffectSpec("backlash", "encoder counts", 0.0, 0.0, 30.0, "plant"),
        EffectSpec("beam_damping", "1", BEAM_DAMPING_NOMINAL, BEAM_DAMPING_NOMINAL, 0.2, "linear"),
        EffectSpec("accel_gain", "1", 1.0, 0.3, 3.0, "output"),
        *(EffectSpec(f"param:{name}", "1", 1.0, PARAM_RATIO_RANGE[0], PARAM_RATIO_RANGE[1], "linear")
          for name in PARAM_NAMES),
    )
}
"""Every effect of the vocabulary by name (DESIGN.md table)."""

CANDIDATES: tuple[str, ...] = (
    "coulomb_friction", "deadzone", "saturation", "delay", "backlash", "beam_damping", "accel_gain",
    *(f"param:{name}" for name in ("drive_k", "drive_c", "clamp_k", "clamp_c", "J_base", "act_K", "act_p",
                                   "EI", "mu", "m_accel", "J_accel")),
)
"""The effects a diagnosis tries (DESIGN.md "Candidates")."""


def is_neutral(name: str, value: float) -> bool:
    """True when ``value`` means "no effect" for the effect ``name`` (known name).

    Parameters
    ----------
    name : str
        An effect of :data:`EFFECTS`.
    value : float
        Its value, in the effect's unit.
    """
    return float(value) == EFFECTS[name].neutral


def check_effects(effects: Mapping[str, float], where: str = "") -> dict[str, float]:
    """Validate effect values against the vocabulary.

    Parameters
    ----------
    effects : mapping of str to float
        Effect name -> value in its unit (see :data:`EFFECTS`).
    where : str, optional
        Prefix of the error message (a file name, "[effects]" of a file, an option).

    Returns
    -------
    dict of str to float
        The same effects as floats (delay a whole number).

    Raises
    ------
    StationError
        Unknown name, a value that is not a number, out of ``[lower, upper]`` (and not
        the neutral value), or a delay that is not a whole number of samples. One line
        naming ``where`` and the effect.
    """
    prefix = f"{where}: " if where else ""
    out: dict[str, float] = {}
    for name, value in effects.items():
        spec = EFFECTS.get(name)
        if spec is None:
            raise StationError(f"{prefix}unknown effect '{name}' (known: {', '.join(EFFECTS)})")
        if isinstance(value, bool) or not isinstance(value, (int, float)) or math.isnan(value):
            raise StationError(f"{prefix}effect '{name}' must be a number ({spec.unit}), got {value!r}")
        value = float(value)
        if value != spec.neutral and not spec.lower <= value <= spec.upper:
            raise StationError(f"{prefix}effect '{name}' = {value:g} out of range "
                               f"{spec.lower:g}..{spec.upper:g} {spec.unit}")
        if name == "delay" and value != int(value):
            raise StationError(f"{prefix}effect 'delay' must be a whole number of samples, got {value:g}")
        out[name] = value
    return out
