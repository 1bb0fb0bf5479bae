"""A law found in a log in words: its continuous design or z-coefficients, its recursion, the
designs the log does not tell apart from it, and an accelerometer feedback Ga
(:attr:`station.analysis.controller_id.IdentifiedController.law`).
"""

from __future__ import annotations

import numpy as np

from station.analysis.continuous_design import ContinuousDesign, to_continuous
from station.analysis.design_doubt import alternatives_phrase, span_phrase
from station.control import DiscreteTF, lead_controller
from station.control.compensator import recursion_words
from station.rig import CLAMP


def _s_poly(c: np.ndarray) -> str:
    """A polynomial in s (descending powers) to 4 significant digits, negligible terms left out."""
    n, big = c.size - 1, float(np.max(np.abs(c)))
    terms = []
    for i, x in enumerate(c):
        if abs(x) <= 1e-9 * big:
            continue
        power = n - i
        s_part = "" if power == 0 else "s" if power == 1 else f"s^{power}"
        mag = "" if abs(abs(x) - 1.0) < 1e-12 and power else f"{abs(x):.4g}"
        terms.append(("-" if x < 0 else "+") + mag + s_part)
    text = "".join(terms).lstrip("+")
    return text or "0"


def thesis_ga_sign(ga: DiscreteTF, dt: float) -> int | None:
    """Whether an accelerometer feedback is the thesis's Ga (DESIGN.md), or it negated: the
    thesis's Ga on an a column written (or an accelerometer mounted) with the other sign.

    Parameters
    ----------
    ga : DiscreteTF
        Ascending powers of z⁻¹.
    dt : float
        Sample time, s.

    Returns
    -------
    int or None
        1: the thesis's Ga, -1: its negation (to 1e-6 relative), None: another law.
    """
    thesis = lead_controller(CLAMP, dt, accel=True).ga
    if (ga.num.size != thesis.num.size or ga.den.size != thesis.den.size
            or not np.allclose(ga.den, thesis.den, rtol=1e-6, atol=0.0)):
        return None
    return next((sign for sign in (1, -1) if np.allclose(ga.num, sign * thesis.num, rtol=1e-6, atol=0.0)), None)


def ga_text(ga: DiscreteTF, dt: float) -> str:
    """Accelerometer feedback in a few words: the thesis's Ga when it is that law, else its
    continuous form by the Tustin inverse (4 digits; the z-law itself is in the spec).

    Parameters
    ----------
    ga : DiscreteTF
    dt : float
        Sample time, s.
    """
    sign = thesis_ga_sign(ga, dt)
    if sign is not None:
        return "the thesis's accelerometer feedback Ga" + ("" if sign > 0 else " on -a (the a column has the "
                                                            "other sign than the loop fed back)")
    order = max(ga.num.size, ga.den.size) - 1
    back = to_continuous(ga.num, ga.den, dt, "Tustin") if order else None
    if back is None:
        fmt = lambda x: "[" + ", ".join(f"{y:.8g}" for y in x) + "]"  # noqa: E731
        return f"accelerometer feedback Ga num {fmt(ga.num)}, den {fmt(ga.den)} (z^-1)"
    return f"accelerometer feedback Ga ≈ ({_s_poly(back[0])})/({_s_poly(back[1])}) (Tustin, {dt:g} s)"


def law_text(order: int, c: np.ndarray, design: ContinuousDesign | None, dt: float, recursion: str,
             limit: float, rig_limit: float, ga: DiscreteTF | None = None) -> str:
    """A law found in a log in one line for reports
    (:attr:`station.analysis.controller_id.IdentifiedController.law`).

    Parameters
    ----------
    order : int
        The law's order (0: a P gain).
    c : numpy.ndarray, shape (2·order + 1,)
        [b_0..b_m, a_1..a_m].
    design : ContinuousDesign or None
        Its continuous design when recognised.
    dt : float
        Sample time, s.
    recursion : {"none", "trunc", "round", ...}
        What its recursion remembers (:func:`station.control.compensator.recursion_words`).
    limit, rig_limit : float
        Its clamp and the one left unsaid, DAC counts.
    ga : DiscreteTF, optional
        Its accelerometer feedback.

    Returns
    -------
    str
        The P gain, or the design and its discretization, or the z-coefficients; the recursion,
        the designs the log does not tell apart from it and how far it pins them, Ga, and a
        clamp other than ``rig_limit``.
    """
    if order == 0:
        text = f"P, kp = {c[0]:g}"
    elif design is not None:
        text = f"{design.text} ({design.method}, {dt:g} s)"
    else:
        fmt = lambda x: "[" + ", ".join(f"{y:.8g}" for y in x) + "]"  # noqa: E731
        text = (f"linear compensator e -> v of order {order}, num {fmt(c[:order + 1])}, "
                f"den {fmt(np.concatenate(([1.0], c[order + 1:])))} (z^-1)")
    if recursion != "none":  # before the alternatives: theirs is said where it differs
        text += f", {recursion_words(recursion)}"
    if design is not None and design.alternatives:  # the log does not tell them apart: said, never hidden
        text += alternatives_phrase([(d.text, d.method, d.recursion) for d in design.alternatives], design.method,
                                    design.more)
    if design is not None:  # how far the log pins a first-order design at all
        text += span_phrase(design.to_json())
    if ga is not None:
        text += f", with {ga_text(ga, dt)}"
    if limit != rig_limit:
        text += f", clamp ±{limit:g}"
    return text
