"""A hub held off the target by dry friction: what the design reports about it.

The rig's structures (P, lead, lead + accelerometer) have no integral action. At rest the
command is the loop's DC gain times the error, and the motor does not move while that stays
below its dry friction: the loop holds the hub wherever it stopped, up to friction / DC gain
counts off the target. With the rig's friction (some 15 DAC counts) and the gains the margins
allow, that is several counts, and the 2 % band of a small step (1 count of a 50-count step)
is entered for good on some models only, as the hub happens to stop.
(:func:`station.design.evaluate.friction_held` tells such a run; the search ranks it by the
settling time into the band it holds, :func:`station.design.evaluate.cost`.)

This module words it, honestly and in encoder counts: :func:`design_model_warning` when the
design model itself holds the hub outside the band, :func:`held_summary` over a set of models.
"""

from __future__ import annotations

from station.design.evaluate import Figures, Requirements, friction_held, held_error
from station.plant.effects import EFFECTS
from station.design.linear import loop_model

HOLDING_EFFECTS = ("coulomb_friction", "static_friction", "deadzone")
"""Effects that hold a small command: the motor's dry (sliding, breakaway) friction and an
amplifier's dead zone, DAC counts (those the simulator knows)."""


def holding_level(model) -> float:
    """The command a model's motor needs to move from rest, DAC counts: the larger of its
    sliding and breakaway friction, plus its dead zone (0 when it has none).

    Parameters
    ----------
    model : station.plant.model.Model

    Returns
    -------
    float
        max(Coulomb friction, static friction) + dead zone, DAC counts (≥ 0).
    """
    def value(name):
        return float(model.effect(name)) if name in EFFECTS else 0.0

    return max(value("coulomb_friction"), value("static_friction")) + value("deadzone")


def dc_parameter(structure: str) -> str:
    """The design parameter that is the compensator's DC gain (kp for P, k0 for the leads).

    Parameters
    ----------
    structure : {"p", "lead", "lead-accel"}

    Returns
    -------
    str
        ``"kp"`` for ``"p"``, ``"k0"`` otherwise.
    """
    return "kp" if structure == "p" else "k0"


def design_model_warning(space, values: dict, model, figure: Figures, requirements: Requirements) -> str | None:
    """One line when the design model itself holds the hub outside the 2 % band (else None).

    Names the held error (encoder counts), the DC gain that would promise the band against
    the model's friction and whether the margins would allow it, and that integral action
    is not in the rig's structures.

    Parameters
    ----------
    space : station.design.space.DesignSpace
        The design's structure.
    values : dict
        The design's parameters.
    model : station.plant.model.Model
        The design model.
    figure : Figures
        The design on it.
    requirements : Requirements
        The margins a higher gain would have to keep.

    Returns
    -------
    str or None
        The warning, one line without a trailing newline; None when the design model does not
        hold the hub off the band (:func:`~station.design.evaluate.friction_held` is false).
    """
    if not friction_held(figure, requirements):
        return None
    error, band = held_error(figure), figure.band
    name = dc_parameter(space.structure)
    level = holding_level(model)
    text = (f"friction holds the hub {error} encoder counts off the target on the design model {model.name!r}, "
            f"outside the 2 % band (±{band:g} counts): ")
    if level <= 0:
        return text + "the model has no dry friction or dead zone to blame; integral action, which would remove the " \
                      "error, is not in the rig's structures"
    need = level / band
    comp = space.compensator_file(dict(values, **{name: need})).compensator()
    mg = loop_model(model).margins(comp)
    allowed = mg.gain_margin_db >= requirements.gain_margin_db and mg.phase_margin_deg >= requirements.phase_margin_deg
    return text + (f"at rest the motor does not move below {level:.3g} DAC counts, so promising the band takes a DC "
                   f"gain of {need:.3g} DAC counts per count ({name} {need:.3g}, this design's {values[name]:.3g}), "
                   f"where the loop's margins {'would still' if allowed else 'would not'} meet the requirements "
                   f"(gain {mg.gain_margin_db:.1f} dB, phase {mg.phase_margin_deg:.1f}°); integral action, which "
                   f"would remove the error, is not in the rig's structures")


def held_summary(figures, requirements) -> dict:
    """The models of a set on which friction holds the hub outside the 2 % band, and how
    their step was judged.

    Parameters
    ----------
    figures : sequence of Figures
        The design on each model.
    requirements : Requirements or sequence of Requirements
        The requirements, or each model's own (a tip bound is per model: one model's
        requirements would misjudge another's).

    Returns
    -------
    dict
        ``models`` (how many), ``of`` (the set's size), ``held_error_counts`` and
        ``band_counts`` ([min, max] over them, None when none) and ``note``: one sentence
        saying how those models were judged (None when none).
    """
    reqs = [requirements] * len(figures) if isinstance(requirements, Requirements) else list(requirements)
    held = [f for f, r in zip(figures, reqs) if friction_held(f, r)]
    out = {"models": len(held), "of": len(figures), "held_error_counts": None, "band_counts": None, "note": None}
    if not held:
        return out
    errors = [held_error(f) for f in held]
    bands = [f.rest_band for f in held]

    def span(lo, hi, unit):
        return f"{lo:g} {unit}" if lo == hi else f"{lo:g}-{hi:g} {unit}"

    out.update({"held_error_counts": [min(errors), max(errors)], "band_counts": [min(bands), max(bands)],
                "note": f"on {len(held)} of {len(figures)} models friction holds the hub "
                        f"{span(min(errors), max(errors), 'counts')} off the target, outside the 2 % band "
                        f"(±{held[0].band:g} counts): settling measured there to the band it holds "
                        f"(±{span(min(bands), max(bands), 'counts')}) and charged the held error's fraction of "
                        f"the step times the rest of the run; requirements counted as not met there"})
    return out
