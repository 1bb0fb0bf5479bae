"""Hidden-effect cases for the blind diagnosis tests and scripts/validate_diagnosis.py.

Magnitudes from issue 8: Coulomb friction and dead-zone 3-30 DAC counts, saturation
80-190, delay 1-4 samples, backlash 2-20 encoder counts, beam_damping 0.01-0.1,
accel_gain 0.5-2, param ratios 0.4-2.5. Ratios (accel_gain, param:NAME) are drawn
log-uniformly at least 1.3x away from 1 on either side (a parameter "off" by 5 % is no
cause to name); beam_damping log-uniformly. A case's value depends only on (effect, seed).
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
"""Effect -> (lowest, highest) hidden value; every effect the blind tests hide."""

MIN_RATIO = 1.3
"""Ratios are drawn at least this far from 1 (either way)."""

TWO_EFFECTS = ("coulomb_friction", "beam_damping")
"""The pair the two-effect case hides."""

TOLERANCE = 0.25
"""A named cause's value must be within this fraction of the hidden one."""


def draw(name: str, seed: int) -> float:
    """The hidden value of ``name`` for ``seed`` (deterministic)."""
    lo, hi = MAGNITUDES[name]
    rng = np.random.default_rng([zlib.crc32(name.encode()), seed])
    if name == "delay":
        return int(rng.integers(lo, hi + 1))
    if name == "accel_gain" or name.startswith("param:"):
        top = math.log(max(hi, 1.0 / lo))
        mag = math.exp(rng.uniform(math.log(MIN_RATIO), top))
        ratio = mag if rng.random() < 0.5 else 1.0 / mag
        return float(min(max(ratio, lo), hi))
    if name == "beam_damping":
        return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))
    return float(rng.uniform(lo, hi))


def case_effects(case: str, seed: int) -> dict[str, float]:
    """The hidden effects of a case: an effect name, "clean" ({}) or "two" (:data:`TWO_EFFECTS`)."""
    if case == "clean":
        return {}
    if case == "two":
        return {name: draw(name, seed) for name in TWO_EFFECTS}
    return {case: draw(case, seed)}


def value_error(hidden: float, found: float) -> float:
    """|found - hidden| / |hidden|."""
    return abs(found - hidden) / abs(hidden)
