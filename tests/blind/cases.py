"""Hidden-effect cases for the blind diagnosis tests and scripts/validate_diagnosis.py.

Magnitudes from issue 8: Coulomb friction and dead-zone 3-30 DAC counts, saturation
80-190, delay 1-4 samples, backlash 2-20 encoder counts, beam_damping 0.01-0.1,
accel_gain 0.5-2, param ratios 0.4-2.5. Ratios (accel_gain, param:NAME) are drawn
log-uniformly at least 1.3x away from 1 on either side (a parameter "off" by 5 % is no
cause to name); beam_damping log-uniformly. A case's value depends only on (effect, seed).

The effects added to the vocabulary later (:data:`NEW_MAGNITUDES`; kept apart from
:data:`MAGNITUDES`, which the blind diagnosis tests walk, until the station models them):

- static_friction v_s 5-30 DAC counts, always hidden with coulomb_friction
  v_c = (0.3-0.7) * v_s (:data:`STATIC_TO_COULOMB`) and the default Stribeck speed 0.05 rad/s
  unless the case also names "stribeck_speed" (0.02-0.2 rad/s, log-uniform);
- viscous_friction 1-5 DAC counts per rad/s: the motor's own damping is 14.8 DAC counts per
  rad/s (act_p / (act_K |2 pi j + act_p|)) and the +-100 pulses drive it at up to 6.7 rad/s,
  so b = 1 shortens the open-loop travel by 6 % (7 counts) and b = 5 by 25 %;
- amp_offset 1-8 DAC counts in size, either sign (an open-loop drift of 11 encoder counts/s
  per DAC count of offset; a P loop settles o/kp counts past its target).

Combinations ("A+B", "A+B+C": each effect drawn as it is alone, so the values of a
combination equal its single cases' for the same seed): :data:`PAIRS`, :data:`TRIPLES`.

Sensor and wiring faults (:data:`SENSOR_CASES`: a case part -> the effect it hides, drawn
by :func:`draw_sensor`; :data:`SENSOR_PAIRS` beside a physical effect):

- accel_reversed: accel_gain -(0.5-2), log-uniform magnitude (the real session's
  accelerometer read about -1.2x the model's a);
- accel_offset: 1.5-10 accelerometer counts in size, either sign (beyond the zeroing; the
  rig's a spans about +-50 counts in these runs, its noise is 0.3 counts);
- accel_drift: 1-8 accelerometer counts per s in size, either sign (2-16 counts over a run);
- accel_unzeroed: accel_offset 15-500 accelerometer counts in size, either sign (a channel
  stored without the rig's zeroing: past the fit's search of ±30; where a feeds back, Ga's DC
  gain of 18 turns it into a reference offset and the lead + accelerometer step runs to the clamp,
  as the rig's loop would);
- accel_sensitivity: accel_gain of 0.1-0.25 or 4-10 in size (log-uniform, either band), either
  sign (another accelerometer or its amplifier's gain: past the fit's search of 0.3-3);
- encoder_4096: encoder_scale 4 (a 4096-count encoder against the model's 1024);
- encoder_reversed: encoder_scale -1; motor_reversed: motor_polarity -1 (each alone runs the
  closed loops away to the clamp: positive feedback, as the rig would).

Breakaway with a sliding level judged on both levels (:data:`SLIDING_CASES`, issue 26): the
case part "breakaway_sliding" hides static_friction v_s 8-30 DAC counts over coulomb_friction
v_c = (0.3-0.7) * v_s, drawn apart from "static_friction"'s (whose v_s alone is judged); a
case's "@d0" suffix runs its closed loops at alignment 0, as the rig's 2009 logs
(:func:`case_alignment`). The part "held_offset" (after a friction part) hides an amp_offset of
(0.2-0.8) * v_c in size, either sign: below the sliding level, so friction holds a still motor
against it, as in issue 26's case (breakaway 14 over 9 with an offset of 2.5); an offset of
1-8 counts drawn alone may exceed v_c, and then the motor creeps on after every move.

The accelerometer's configuration (:data:`ACCEL_SETUPS`, :data:`ACCEL_SETUP_CASES`): beside the
case's four runs (with their accelerometer), a fifth, the rig's 2014 swept sine
(:func:`tests.blind.generator.write_sweep`), with the accelerometer taken off the beam
(accel_off: no tip mass, a reads a constant of :data:`DEAD_LEVEL` counts, either sign, and its
noise) or left on the tip unplugged (accel_unplugged: the mass there, a the same dead
channel), alone or beside a physical effect (in all five runs): :func:`sweep_setup`.

Out-of-vocabulary cases (:data:`OOV_CASES`, :data:`OOV_MAGNITUDES`; semantics in
``tests.blind.rig.OOV``), which no vocabulary effect explains, for the diagnosis's
"unexplained" flag:

- oov:encoder_cyclic: a cyclic encoder error of 2-4 counts amplitude and a period of 64-256
  counts (log-uniform): the measured theta (which the controller also sees) ripples by up to
  +-4 counts with the base angle, 0.4-1.7 periods over the open-loop pulse's ~110 counts;
- oov:cogging: a detent torque of 5-15 DAC counts, 8-24 cycles per motor revolution: the
  open-loop pulse's motor rests in a detent (every 43-128 counts) and the closed loops
  settle off target by up to c/kp;
- oov:position_spring: a spring from the hub to the ground of 0.03-0.1 DAC counts per encoder
  count (a cable): the open-loop hub creeps back towards where it started (1.3 s after the
  +100 pulse the base is at 0.68 (s = 0.03) to 0.29 (s = 0.1) of the motor's angle, against
  1.02 without it) and a P loop settles at kp*u/(kp + s), 0.7-2.4 counts short of its
  50-count target.
"""

from __future__ import annotations

import math
import zlib

import numpy as np

MAGNITUDES: dict[str, tuple[float, float]] = {
    "coulomb_friction": (3.0, 30.0),
    "deadzone": (3.0, 30.0),
    "saturation": (80.0, 190.0),
    "delay": (1, 4),
    "backlash": (2.0, 20.0),
    "beam_damping": (0.01, 0.1),
    "accel_gain": (0.5, 2.0),
    "param:drive_c": (0.4, 2.5),
    "param:drive_k": (0.4, 2.5),
    "param:J_base": (0.4, 2.5),
    "param:act_K": (0.4, 2.5),
}
"""Effect -> (lowest, highest) hidden value: issue 8's effects, one at a time."""

NEW_MAGNITUDES: dict[str, tuple[float, float]] = {
    "static_friction": (5.0, 30.0),
    "viscous_friction": (1.0, 5.0),
    "amp_offset": (1.0, 8.0),
}
"""The vocabulary's later effects -> (lowest, highest); amp_offset's range is its size
(either sign)."""

STATIC_TO_COULOMB = (0.3, 0.7)
"""v_c / v_s of a static_friction case (drawn uniformly)."""

SETTING_MAGNITUDES: dict[str, tuple[float, float]] = {"stribeck_speed": (0.02, 0.2)}
"""Shape settings a case may also name (log-uniform)."""

OOV_MAGNITUDES: dict[str, tuple[float, float]] = {
    "oov:encoder_cyclic": (2.0, 4.0),
    "oov:encoder_cyclic_period": (64.0, 256.0),
    "oov:cogging": (5.0, 15.0),
    "oov:cogging_cycles": (8, 24),
    "oov:position_spring": (0.03, 0.1),
}
"""Out-of-vocabulary effects and their settings -> (lowest, highest)."""

OOV_CASES: dict[str, tuple[str, ...]] = {
    "oov:encoder_cyclic": ("oov:encoder_cyclic", "oov:encoder_cyclic_period"),
    "oov:cogging": ("oov:cogging", "oov:cogging_cycles"),
    "oov:position_spring": ("oov:position_spring",),
}
"""Out-of-vocabulary case -> the keys it hides."""

MIN_RATIO = 1.3
"""Ratios are drawn at least this far from 1 (either way)."""

TWO_EFFECTS = ("coulomb_friction", "beam_damping")
"""The pair the two-effect case hides."""

PAIRS = (
    "coulomb_friction+amp_offset",
    "static_friction+param:drive_c",
    "viscous_friction+backlash",
    "amp_offset+deadzone",
    "static_friction+stribeck_speed",
)
"""Two-effect cases (the last: static friction with a Stribeck speed away from the default)."""

TRIPLES = (
    "amp_offset+coulomb_friction+param:drive_c",
    "static_friction+amp_offset+delay",
)
"""Three-effect cases; the first is the real rig's suspected structure."""

CASES = ("clean", *MAGNITUDES, "two", *NEW_MAGNITUDES, *PAIRS, *TRIPLES, *OOV_CASES)
"""Every case :func:`case_effects` knows."""

TOLERANCE = 0.25
"""A named cause's value must be within this fraction of the hidden one."""

SENSOR_CASES: dict[str, str] = {
    "accel_reversed": "accel_gain",
    "accel_offset": "accel_offset",
    "accel_drift": "accel_drift",
    "accel_unzeroed": "accel_offset",
    "accel_sensitivity": "accel_gain",
    "encoder_4096": "encoder_scale",
    "encoder_reversed": "encoder_scale",
    "motor_reversed": "motor_polarity",
}
"""Sensor and wiring fault cases: case part -> the effect it hides (module docstring)."""

SENSOR_MAGNITUDES: dict[str, tuple[float, float]] = {
    "accel_reversed": (-2.0, -0.5),
    "accel_offset": (1.5, 10.0),
    "accel_drift": (1.0, 8.0),
    "accel_unzeroed": (15.0, 500.0),
    "accel_sensitivity": (0.1, 10.0),
    "encoder_4096": (4.0, 4.0),
    "encoder_reversed": (-1.0, -1.0),
    "motor_reversed": (-1.0, -1.0),
}
"""Sensor fault case part -> (lowest, highest) hidden value; accel_offset's, accel_drift's and
accel_unzeroed's ranges are their sizes (either sign); accel_sensitivity's is its size's outer
bounds (drawn in :data:`SENSITIVITY_BANDS`, either sign)."""

SENSITIVITY_BANDS = ((0.1, 0.25), (4.0, 10.0))
"""The sizes an accel_sensitivity case part draws its gain in (log-uniform, one band at random)."""

SENSOR_PAIRS = (
    "accel_reversed+coulomb_friction",
    "accel_reversed+param:drive_c",
    "accel_offset+coulomb_friction",
    "accel_drift+param:drive_c",
    "accel_unzeroed+coulomb_friction",
    "accel_sensitivity+param:drive_c",
    "encoder_4096+coulomb_friction",
    "encoder_reversed+param:drive_c",
    "motor_reversed+coulomb_friction",
    "motor_reversed+amp_offset",
)
"""Each sensor or wiring fault beside a physical effect."""

CASES += (*SENSOR_CASES, *SENSOR_PAIRS)

SLIDING_MAGNITUDES: dict[str, tuple[float, float]] = {"breakaway_sliding": (8.0, 30.0)}
"""The breakaway level v_s of a "breakaway_sliding" case part, DAC counts (its sliding level is
:data:`STATIC_TO_COULOMB` of it)."""

HELD_OFFSET = (0.2, 0.8)
"""|amp_offset| / v_c of a "held_offset" case part (drawn uniformly, either sign)."""

SLIDING_CASES = ("breakaway_sliding", "breakaway_sliding+held_offset@d0", "breakaway_sliding+amp_offset@d0")
"""Breakaway over a sliding level, both judged: alone, beside an amplifier offset the friction
holds at the 2009 alignment (d = 0; issue 26's case: breakaway 14 over 9 with an offset of
2.5), and beside an offset of issue 17's range (1-8 counts, at times above the sliding level)."""

ALIGNMENTS = {"@d0": 0}
"""A case's suffix -> the alignment of its closed loops (none: 1)."""

CASES += SLIDING_CASES


def case_alignment(case: str) -> tuple[str, int]:
    """A case without its alignment suffix, and the alignment of its closed loops.

    Parameters
    ----------
    case : str
        A case, e.g. "breakaway_sliding+amp_offset@d0".

    Returns
    -------
    (str, int)
        The case's effects part and the alignment (1 without a suffix).
    """
    for suffix, d in ALIGNMENTS.items():
        if case.endswith(suffix):
            return case[:-len(suffix)], d
    return case, 1


ACCEL_SETUPS: dict[str, str] = {"accel_off": "accel_mounted", "accel_unplugged": "accel_connected"}
"""The accelerometer's configuration case parts -> the generator's key that is 0 in the fifth run
(:data:`tests.blind.rig.CONFIGURATIONS`)."""

ACCEL_SETUP_CASES = ("accel_off", "accel_off+coulomb_friction", "accel_off+param:drive_c", "accel_unplugged")
"""The configuration cases: off the beam alone and beside a physical effect, unplugged on it."""

DEAD_LEVEL = (2.0, 40.0)
"""What a dead accelerometer channel reads, counts in size (either sign), besides its noise."""

CASES += ACCEL_SETUP_CASES


def sweep_setup(case: str, seed: int) -> dict[str, float] | None:
    """The fifth run's accelerometer of a configuration case (its key 0 and the dead channel's
    level as ``accel_offset``), None for a case without a fifth run (deterministic).

    Parameters
    ----------
    case : str
        A case (e.g. "accel_off+coulomb_friction").
    seed : int
    """
    parts = [p for p in case.split("+") if p in ACCEL_SETUPS]
    if not parts:
        return None
    rng = _rng("dead level", seed)
    level = float(rng.uniform(*DEAD_LEVEL))
    return {ACCEL_SETUPS[parts[0]]: 0.0, "accel_offset": level if rng.random() < 0.5 else -level}


def draw_sensor(part: str, seed: int) -> float:
    """The hidden value of a sensor fault case part for ``seed`` (deterministic).

    Parameters
    ----------
    part : str
        A key of :data:`SENSOR_CASES`.
    seed : int
    """
    lo, hi = SENSOR_MAGNITUDES[part]
    rng = _rng(part, seed)
    if lo == hi:
        return float(lo)
    if part == "accel_reversed":
        return -float(math.exp(rng.uniform(math.log(-hi), math.log(-lo))))
    if part == "accel_sensitivity":
        lo, hi = SENSITIVITY_BANDS[int(rng.integers(len(SENSITIVITY_BANDS)))]
        size = float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
        return size if rng.random() < 0.5 else -size
    value = float(rng.uniform(lo, hi))
    return value if rng.random() < 0.5 else -value


def _rng(name: str, seed: int) -> np.random.Generator:
    return np.random.default_rng([zlib.crc32(name.encode()), seed])


def draw(name: str, seed: int) -> float:
    """The hidden value of ``name`` for ``seed`` (deterministic).

    Parameters
    ----------
    name : str
        A key of :data:`MAGNITUDES`, :data:`NEW_MAGNITUDES`, :data:`SETTING_MAGNITUDES` or
        :data:`OOV_MAGNITUDES`.
    seed : int
    """
    lo, hi = {**MAGNITUDES, **NEW_MAGNITUDES, **SETTING_MAGNITUDES, **OOV_MAGNITUDES}[name]
    rng = _rng(name, seed)
    if name in ("delay", "oov:cogging_cycles"):
        return int(rng.integers(lo, hi + 1))
    if name == "accel_gain" or name.startswith("param:"):
        top = math.log(max(hi, 1.0 / lo))
        mag = math.exp(rng.uniform(math.log(MIN_RATIO), top))
        ratio = mag if rng.random() < 0.5 else 1.0 / mag
        return float(min(max(ratio, lo), hi))
    if name in ("beam_damping", "stribeck_speed", "oov:encoder_cyclic_period"):
        return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
    value = float(rng.uniform(lo, hi))
    if name == "amp_offset":
        return value if rng.random() < 0.5 else -value
    return value


def _single(name: str, seed: int) -> dict[str, float]:
    if name in SLIDING_MAGNITUDES:
        v_s = float(_rng(name, seed).uniform(*SLIDING_MAGNITUDES[name]))
        ratio = float(_rng(f"{name}/coulomb_friction", seed).uniform(*STATIC_TO_COULOMB))
        return {"static_friction": v_s, "coulomb_friction": ratio * v_s}
    if name == "static_friction":
        v_s = draw(name, seed)
        ratio = float(_rng("static_friction/coulomb_friction", seed).uniform(*STATIC_TO_COULOMB))
        return {"static_friction": v_s, "coulomb_friction": ratio * v_s}
    if name in OOV_CASES:
        return {key: draw(key, seed) for key in OOV_CASES[name]}
    if name in MAGNITUDES or name in NEW_MAGNITUDES or name in SETTING_MAGNITUDES:
        return {name: draw(name, seed)}
    if name in SENSOR_CASES:
        return {SENSOR_CASES[name]: draw_sensor(name, seed)}
    if name in ACCEL_SETUPS:  # the fifth run's configuration only (sweep_setup)
        return {}
    raise ValueError(f"unknown case {name!r}; known: {', '.join(CASES)} (or effects joined by '+')")


def case_effects(case: str, seed: int) -> dict[str, float]:
    """The hidden effects of a case (deterministic per (effect, seed)).

    Parameters
    ----------
    case : str
        "clean" ({}), "two" (:data:`TWO_EFFECTS`), an effect of :data:`MAGNITUDES` or
        :data:`NEW_MAGNITUDES` (static_friction brings its coulomb_friction), an
        out-of-vocabulary case of :data:`OOV_CASES`, or such names joined by "+"
        (:data:`PAIRS`, :data:`TRIPLES`; "stribeck_speed" may join static_friction).
    seed : int

    Returns
    -------
    dict
        Effect name -> value, as :func:`tests.blind.generator.write_case` takes them.

    Raises
    ------
    ValueError
        An unknown name, or two parts that hide the same effect (e.g. static_friction
        with coulomb_friction).
    """
    case = case_alignment(case)[0]
    if case == "clean":
        return {}
    if case == "two":
        return {name: draw(name, seed) for name in TWO_EFFECTS}
    effects: dict[str, float] = {}
    for part in case.split("+"):
        if part == "held_offset":
            if "coulomb_friction" not in effects:
                raise ValueError(f"case {case!r}: held_offset needs a friction part before it")
            rng = _rng(part, seed)
            size = float(rng.uniform(*HELD_OFFSET)) * effects["coulomb_friction"]
            effects["amp_offset"] = size if rng.random() < 0.5 else -size
            continue
        hidden = _single(part, seed)
        if set(hidden) & set(effects):
            raise ValueError(f"case {case!r} hides {sorted(set(hidden) & set(effects))} twice")
        effects.update(hidden)
    if "stribeck_speed" in effects and "static_friction" not in effects:
        raise ValueError(f"case {case!r}: stribeck_speed without static_friction")
    return effects


def value_error(hidden: float, found: float) -> float:
    """|found - hidden| / |hidden|."""
    return abs(found - hidden) / abs(hidden)
