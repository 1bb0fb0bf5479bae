"""The vocabulary of model effects: names, units, neutral values and fit ranges.

DESIGN.md "Model diagnosis contract": every effect is named and valued in device units
that do not depend on a model's internals (DAC counts, samples, encoder counts, ratios).
Where each acts:

- "amplifier" (on the command, in this order after the device's command quantization):
  amp_offset, saturation, deadzone, delay;
- "plant" (inside the plant, integrated on a sub-step grid): coulomb_friction,
  static_friction, backlash;
- "linear" (rebuild the linear FEM part): viscous_friction, beam_damping, param:NAME, and
  accel_mounted (:data:`CONFIGURATIONS`: 0 takes the accelerometer's mass m_accel and rotary
  inertia J_accel off the beam's tip, whatever param:m_accel and param:J_accel say);
- "output": the sensors' faults, on the noise-free outputs before their quantization:
  encoder_scale multiplies θ; a becomes accel_gain·a + accel_offset + accel_drift·t, t = k·dt
  from the run's first sample (k = 0);
- "wiring": motor_polarity, at the amplifier's output (after its offset, saturation,
  dead-zone and delay): −1 turns the whole torque around (the amplifier's offset too; dry
  friction is the motor's and still opposes its motion);
- "setting": the shape of another effect, no effect alone: stribeck_speed (of
  static_friction). It is a key of a model file's ``[effects]`` like the others, but never a
  candidate cause; a diagnosis fits it only beside static_friction.

Signed effects (accel_gain, encoder_scale, motor_polarity; :attr:`EffectSpec.signed`): the
range is of the magnitude and either sign is allowed, a negative value meaning a sensor or
motor wired the other way: accel_gain 0.3..3 either sign (a diagnosis never fits through
0; a model may hold 0.01..100, :attr:`EffectSpec.held`, where the data decide a gain beyond the
search's reach), encoder_scale 0.25..16 either sign (256- to 16384-count encoders against the model's
1024), motor_polarity ±1 only (never between). A search over such an effect's range
(``lower``..``upper``) covers the positive side; its sign is decided from the data.

Dry friction: ``coulomb_friction`` v_c is the sliding level and, alone, also the static
level; ``static_friction`` v_s >= v_c is the breakaway level, and the sliding friction falls
from v_s to v_c as exp(-(ω/ω_s)²) of the motor speed ω, ω_s = ``stribeck_speed`` (rad/s of
the motor, default :data:`STRIBECK_SPEED`). A static_friction without coulomb_friction has
v_c = 0. :func:`friction_levels` gives (v_c, v_s, ω_s) of a set of effects.
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
from station.rig import DAC_LIMIT


class EffectSpec(NamedTuple):
    """One effect of the vocabulary.

    Attributes
    ----------
    name : str
        As in DESIGN.md ("coulomb_friction", ..., "param:drive_c").
    unit : str
        "DAC counts", "samples", "encoder counts", "accelerometer counts", "1", ... (DESIGN.md).
    neutral : float
        The value that means "no effect".
    lower, upper : float
        The range a fit may search (and a model file may hold, besides ``neutral``, unless
        ``held`` is wider); of the magnitude when ``signed``.
    kind : {"amplifier", "plant", "linear", "output", "wiring", "setting"}
        Where it acts (module docstring).
    signed : bool, default False
        Either sign is allowed, ``lower <= |value| <= upper`` (a reversed sensor or motor).
    held : (float, float) or None, default None
        The range a model may hold and the data may decide, where it is wider than the fit's
        search (a sensor fault: an accelerometer of another sensitivity, a channel stored
        without its zeroing); of the magnitude when ``signed``. None: ``lower``, ``upper``.
    """

    name: str
    unit: str
    neutral: float
    lower: float
    upper: float
    kind: str
    signed: bool = False
    held: tuple[float, float] | None = None

    @property
    def bounds(self) -> tuple[float, float]:
        """The range a model may hold (``held``, else ``lower``, ``upper``); of the magnitude
        when ``signed``."""
        return self.held if self.held is not None else (self.lower, self.upper)

    def admits(self, value: float) -> bool:
        """True when ``value`` (a float, not NaN) is the neutral value or within :attr:`bounds`.

        Parameters
        ----------
        value : float
            In the effect's unit.
        """
        size = abs(value) if self.signed else value
        lo, hi = self.bounds
        return value == self.neutral or lo <= size <= hi

    def searched(self, value: float, about: float | None = None) -> bool:
        """True when ``value`` lies within the fit's search range (``lower``..``upper``, of the
        magnitude when ``signed``): a decided value outside it is out of the search's reach.

        Parameters
        ----------
        value : float
            In the effect's unit.
        about : float, optional
            The value a model holds: the range is then the one searched beside it
            (:meth:`search_about`).
        """
        size = abs(value) if self.signed else value
        lo, hi = (self.lower, self.upper) if about is None else self.search_about(about)
        return lo <= size <= hi

    def search_about(self, value: float) -> tuple[float, float]:
        """The range a fit searches beside a model that holds ``value``: ``lower``, ``upper``
        when the search reaches it (:meth:`searched`), else the search's span (the factor
        upper/lower) centred on it, geometrically, within :attr:`bounds`. Of the magnitude when
        ``signed`` (the sign is the held value's).

        Parameters
        ----------
        value : float
            The value the model holds (a sensor fault decided from the data), in the effect's unit.

        Returns
        -------
        (float, float)

        Raises
        ------
        ValueError
            Off the search's reach for an effect whose search range is not of one sign.
        """
        size = abs(value) if self.signed else value
        if self.lower <= size <= self.upper or value == self.neutral:
            return self.lower, self.upper
        if not self.lower > 0:
            raise ValueError(f"effect '{self.name}': no search about {value:g}")
        half = math.sqrt(self.upper / self.lower)
        lo, hi = self.bounds
        return max(size / half, lo), min(size * half, hi)

    def range_text(self) -> str:
        """The range a model may hold as an error message says it ("0..40", "±0.01..100",
        "±1", "0 or 1")."""
        lo, hi = self.bounds
        if not self.signed and lo == hi:
            return f"{lo:g} or {self.neutral:g}"
        if not self.signed:
            return f"{lo:g}..{hi:g}"
        return f"±{lo:g}" if lo == hi else f"±{lo:g}..{hi:g}"


PARAM_NAMES = ("mu", "EI", "drive_k", "drive_c", "clamp_k", "clamp_c", "J_base", "m_accel", "J_accel",
               "act_K", "act_p")
"""Parameters a param:NAME ratio may scale (all of the table but beam_beta, L, k_tau, a_gain)."""

AMPLIFIER_ORDER = ("amp_offset", "saturation", "deadzone", "delay")
"""DESIGN.md: after the device's command quantization, in this order (then motor_polarity
at the amplifier's output)."""

CONFIGURATIONS = ("accel_mounted",)
"""How the rig was set up for a run, not a fault of it: accel_mounted 1 (the nominal, the
accelerometer on the tip) or 0 (taken off the beam). Never a candidate cause: the log audit
decides it per run from the data (:mod:`station.logged.mounting`), and a run is simulated in
its own configuration (:meth:`station.logged.LoggedRun.model_for`); a model file may hold it for
a rig that has no accelerometer at all."""

SENSOR_FAULTS = ("accel_gain", "accel_offset", "accel_drift", "encoder_scale", "motor_polarity")
"""DESIGN.md's sensor and wiring faults: decided from the data where the data decide them
(a sign from a correlation, a scale from a ratio), fitted like the others otherwise."""

STRIBECK_SPEED = 0.05
"""Default Stribeck speed ω_s of static_friction, rad/s of the motor (DESIGN.md)."""


def _nominal_beam_damping() -> float:
    # tmm-fit's own first hub-held mode damping ratio (from the clamp damper alone); cached
    # on disk: an eigenvalue problem at import would cost every command scipy's start-up
    params = load_params("tmm-fit")
    return float(cached_arrays("beam-damping", tuple(vars(params).values()), lambda: {
        "zeta": np.asarray(modal_summary(params, 4).antiresonance_damping[0])})["zeta"])


ACCEL_GAIN_HELD = (0.01, 100.0)
"""The accelerometer gain's magnitude a model may hold (decided from the data): two decades
either way of the thesis's sensitivity, where the fit searches 0.3..3."""

ACCEL_I16 = (-32768.0, 32767.0)
"""The accelerometer's bias (counts) and drift (counts per s) a model may hold: the protocol's
SAMPLE accel field is an i16 (spec/protocol.md), where the fit's search spans ±30 and ±20."""

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
        # v_s: the sliding level's 0..40 plus a breakaway excess of up to 30 (a diagnosis
        # fits static_friction as coulomb_friction + excess, station.diagnosis.search.selection)
        EffectSpec("static_friction", "DAC counts", 0.0, 0.0, 70.0, "plant"),
        EffectSpec("stribeck_speed", "rad/s", STRIBECK_SPEED, 0.01, 1.0, "setting"),
        # the motor's own damping c_m/k_tau is 14.8 counts per rad/s (tmm-fit): up to 2.4x
        EffectSpec("viscous_friction", "DAC counts per rad/s", 0.0, 0.0, 20.0, "linear"),
        # 20 counts (0.2 V) would drive the free motor at 220 encoder counts/s open loop
        EffectSpec("amp_offset", "DAC counts", 0.0, -20.0, 20.0, "amplifier"),
        EffectSpec("deadzone", "DAC counts", 0.0, 0.0, 40.0, "amplifier"),
        EffectSpec("saturation", "DAC counts", math.inf, 50.0, DAC_LIMIT, "amplifier"),
        EffectSpec("delay", "samples", 0.0, 0.0, 6.0, "amplifier"),
        EffectSpec("backlash", "encoder counts", 0.0, 0.0, 30.0, "plant"),
        EffectSpec("beam_damping", "1", BEAM_DAMPING_NOMINAL, BEAM_DAMPING_NOMINAL, 0.2, "linear"),
        # held: another accelerometer's sensitivity, or its amplifier's (decided from the data)
        EffectSpec("accel_gain", "1", 1.0, 0.3, 3.0, "output", signed=True, held=ACCEL_GAIN_HELD),
        # beyond the rig's pre-test zeroing; the rig's a spans about ±125 counts; held: a channel
        # stored without its zeroing reads anywhere in the sample's i16 field
        EffectSpec("accel_offset", "accelerometer counts", 0.0, -30.0, 30.0, "output", held=ACCEL_I16),
        # a linear bias from the run's first sample: ±20 counts/s is ±40 counts over a 2 s run
        EffectSpec("accel_drift", "accelerometer counts per s", 0.0, -20.0, 20.0, "output", held=ACCEL_I16),
        EffectSpec("encoder_scale", "1", 1.0, 0.25, 16.0, "output", signed=True),
        EffectSpec("motor_polarity", "1", 1.0, 1.0, 1.0, "wiring", signed=True),
        EffectSpec("accel_mounted", "1", 1.0, 0.0, 0.0, "linear"),  # 1 or 0 only (CONFIGURATIONS)
        *(EffectSpec(f"param:{name}", "1", 1.0, PARAM_RATIO_RANGE[0], PARAM_RATIO_RANGE[1], "linear")
          for name in PARAM_NAMES),
    )
}
"""Every effect of the vocabulary by name (DESIGN.md table)."""

CANDIDATES: tuple[str, ...] = (
    "coulomb_friction", "deadzone", "saturation", "delay", "backlash", "beam_damping", "accel_gain",
    "static_friction", "viscous_friction", "amp_offset",
    *(f"param:{name}" for name in ("drive_k", "drive_c", "clamp_k", "clamp_c", "J_base", "act_K", "act_p",
                                   "EI", "mu", "m_accel", "J_accel")),
)
"""The effects a diagnosis tries (DESIGN.md "Candidates"); never a "setting"."""


SENSOR_SIGNS = tuple(n for n in SENSOR_FAULTS if EFFECTS[n].signed)
"""The sensor and wiring faults that turn a signal around or rescale it (:attr:`EffectSpec.signed`):
the ones a single run's data decide (:attr:`station.logged.LoggedRun.sensors`)."""


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
        Unknown name, a value that is not a number, out of ``[lower, upper]`` (of its
        magnitude for a signed effect; the neutral value is always allowed), a delay that is not a whole number of samples, or a
        static_friction below the coulomb_friction beside it. One line naming ``where``
        and the effect.
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
        if not spec.admits(value):
            raise StationError(f"{prefix}effect '{name}' = {value:g} out of range {spec.range_text()} {spec.unit}")
        if name == "delay" and value != int(value):
            raise StationError(f"{prefix}effect 'delay' must be a whole number of samples, got {value:g}")
        out[name] = value
    v_s, v_c = out.get("static_friction", 0.0), out.get("coulomb_friction", 0.0)
    if "static_friction" in out and v_s != 0.0 and v_s < v_c:
        raise StationError(f"{prefix}effect 'static_friction' = {v_s:g} below coulomb_friction = {v_c:g} "
                           "(the breakaway level must be at least the sliding level)")
    return out


class FrictionLevels(NamedTuple):
    """The motor's dry friction of a set of effects.

    Attributes
    ----------
    v_c : float
        Sliding (Coulomb) level, DAC counts.
    v_s : float
        Breakaway (static) level, DAC counts: static_friction, else v_c (0: no dry friction).
    w_s : float
        Stribeck speed, rad/s of the motor.
    """

    v_c: float
    v_s: float
    w_s: float


def friction_levels(effects: Mapping[str, float]) -> FrictionLevels:
    """(v_c, v_s, ω_s) of checked effects (module docstring, "Dry friction").

    Parameters
    ----------
    effects : mapping of str to float
        Effect name -> value (:func:`check_effects` holds v_s >= v_c).
    """
    v_c = float(effects.get("coulomb_friction", 0.0))
    v_s = max(float(effects.get("static_friction", 0.0)), v_c)
    return FrictionLevels(v_c, v_s, float(effects.get("stribeck_speed", STRIBECK_SPEED)))
