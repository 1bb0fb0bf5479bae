"""A header's law against the data's: the same law (:func:`same_law`), and its continuous
design (:func:`named_design`).

A rig header prints its compensator's z-coefficients; the data's law is found to more
digits (:mod:`station.analysis.controller_id`). These say when the two are one law and name
a header's law by the design a person wrote, so the audit says "2.5(s+17)/(s+44)" where the
header printed [2.43534483, -2.3539272].
"""

from __future__ import annotations

import numpy as np

from station.analysis.controller_id import MAX_ORDER, aligned_error, law_compensator
from station.analysis.law_rows import LawRows, pinned_law
from station.control import Compensator, DiscreteTF
from station.control.compensator import STORED
from station.control.rerun import is_closed_loop
from station.rig import DT

PRINTED_TOLERANCE = 5.0001e-9
"""Largest difference between a coefficient and its 8-decimal print (half a unit in the 8th place)."""

SAME_LAW_RTOL = 1e-6
"""Relative agreement of a header's coefficients with the data's law under which the header
states that law (printed to 8 significant digits; a lying header is off by percent)."""


def _coefficients(controller) -> list[np.ndarray] | None:
    gth = getattr(controller, "gth", None)
    if gth is None:
        return None
    out = []
    for tf in (gth, getattr(controller, "ga", None)):
        if tf is not None:
            num, den = np.asarray(tf.num, float), np.asarray(tf.den, float)
            out += [num / den[0], den / den[0]]
    return out


def same_law(stated, found) -> bool:
    """Whether two closed-loop controllers run the same linear law (Gth and Ga coefficients
    within :data:`SAME_LAW_RTOL`), whatever their clamps and integer recursions.

    Parameters
    ----------
    stated, found : Compensator, OpenLoop or None
        The header's controller and the data's.

    Returns
    -------
    bool
    """
    if not (is_closed_loop(stated) and is_closed_loop(found)):
        return False
    a, b = _coefficients(stated), _coefficients(found)
    if a is None or b is None or len(a) != len(b):
        return False
    return all(x.shape == y.shape and np.allclose(x, y, rtol=SAME_LAW_RTOL, atol=PRINTED_TOLERANCE)
               for x, y in zip(a, b))


def named_design(controller, u, theta, v, d: int, dt: float = DT):
    """A header's Gth that reproduces its log, named by the continuous design it discretizes.

    A lab script prints its compensator's z-coefficients (ryanGT's Motor_Comp ``#b0=``
    lines, or Motor_Comp_w_accel_fb's ``#Gth num=``); the design a person wrote,
    "2.5(s+17)/(s+44)", is found the way an inferred law's is
    (:func:`station.analysis.law_rows.pinned_law` on the log's rows at the alignment the
    header's law reproduces them at) and kept only where its discretization is the header's
    law (:func:`same_law`): the name changes, the coefficients replayed do not.

    Parameters
    ----------
    controller : Compensator, OpenLoop or None
        The header's controller, confirmed on the log.
    u, theta, v : array_like, shape (N,)
        The log's reference, hub angle and commands.
    d : int
        The alignment it reproduces the log at.
    dt : float
        Sample time, s.

    Returns
    -------
    Compensator, OpenLoop or None
        ``controller`` itself (open loop, a P law, a known design, one with Ga or with its
        whole count sent, no design recognised, or a station log's controller, which keeps
        the name its compensator file gave it), else a copy named by the design's text whose
        spec holds the design.
    """
    if (not isinstance(controller, Compensator) or controller.spec.get("source") != "rig header"
            or controller.ga is not None or controller.spec.get("design") or controller.name in ("lead", "lead-accel")
            or controller.recursion not in ("none", *STORED)):
        return controller
    den = np.asarray(controller.gth.den, float)
    order = den.size - 1
    if not 1 <= order <= MAX_ORDER or np.asarray(controller.gth.num).size != den.size:
        return controller
    e = aligned_error(np.asarray(u, float), np.asarray(theta, float), d)
    rows = LawRows(e, np.asarray(v, float), d, order, controller.limit)
    pinned = pinned_law(rows, controller.recursion, dt)
    if pinned is None or pinned[1] is None:
        return controller
    named = law_compensator(*pinned[1].discretize(dt), controller.limit, dt, controller.spec.get("kind", "linear"))
    if not same_law(controller, named):
        return controller
    text = pinned[1].text  # named as an inferred law is (controller_id.infer_controller)
    return Compensator(DiscreteTF(controller.gth.num, controller.gth.den), None, limit=controller.limit, name=text,
                       spec={**controller.spec, "name": text, "design": pinned[1].to_json()},
                       shaper=controller.shaper, recursion=controller.recursion)
