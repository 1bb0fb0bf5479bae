"""A header's law against the data's: the same law (:func:`same_law`), its continuous
design (:func:`named_design`), and the law its printed coefficients round
(:func:`completed_law`).

A rig header prints its compensator's z-coefficients; the data's law is found to more
digits (:mod:`station.analysis.controller_id`). These say when the two are one law and name
a header's law by the design a person wrote, so the audit says "2.5(s+17)/(s+44)" where the
header printed [2.43534483, -2.3539272].
"""

from __future__ import annotations

import numpy as np

from station.analysis.continuous_design import recognize
from station.analysis.controller_id import (MAX_ORDER, IdentifiedController, aligned_error, law_compensator,
                                            replayed_or_tied)
from station.analysis.law_words import law_text
from station.analysis.law_rows import BOUNDARY, LawRows, nudged_inside, pinned_law
from station.control import Compensator, DiscreteTF
from station.control.compensator import RECURSIONS, STORED
from station.control.rerun import ALIGNMENTS, is_closed_loop
from station.rig import DT

PRINTED_TOLERANCE = 5.0001e-9
"""Largest difference between a coefficient and its 8-decimal print (half a unit in the 8th place)."""

NEAR_COUNTS = 2.0
"""A header's law that replays a log this near, DAC counts, and no nearer than a count off, is
completed from the data (printed coefficients, a recursion the printing moves by a count:
:func:`completed_law`); so is one that does with two columns swapped
(:func:`station.logged.columns.check_columns`)."""

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
    return a is not None and b is not None and len(a) == len(b) and _same(a, b)


def _same(a: list[np.ndarray], b: list[np.ndarray]) -> bool:
    return all(x.shape == y.shape and np.allclose(x, y, rtol=SAME_LAW_RTOL, atol=PRINTED_TOLERANCE)
               for x, y in zip(a, b))


def gain_words(stated, found, lab_b_lines: bool = False) -> str:
    """Where the data's law is the header's times a gain: "; the header's law times 1.5".

    ryanGT's Motor_Comp scripts ran v[i] = (b0·e[i] + b1·e[i−1])·gain − a1·v[i−1] and printed
    ``#b0=``, ``#b1=``, ``#a1=`` but not the gain: a run with gain ≠ 1 contradicts its header by
    exactly that factor on Gth's numerator.

    Parameters
    ----------
    stated, found : Compensator, OpenLoop or None
        The header's controller and the data's law.
    lab_b_lines : bool
        The header printed Gth as Motor_Comp's ``#b0=`` lines (the words then name its gain).

    Returns
    -------
    str
        The words (with their leading "; "), or "" where the data's law is not the header's
        Gth numerator times one gain ≠ 1 with the same denominator and Ga, or the header's law
        is a P (its gain is said as kp).
    """
    if not (is_closed_loop(stated) and is_closed_loop(found)):
        return ""
    a, b = _coefficients(stated), _coefficients(found)
    if (a is None or b is None or len(a) != len(b) or a[0].shape != b[0].shape or not np.any(a[0])
            or a[1].size < 2):  # a P law's gain is said as its kp
        return ""
    i = int(np.argmax(np.abs(a[0])))
    g = float(b[0][i] / a[0][i])
    if not np.isfinite(g) or abs(g - 1.0) <= SAME_LAW_RTOL or not _same([a[0] * g] + a[1:], b):
        return ""
    lab = " (Motor_Comp's gain, which its #b0= lines do not print)" if lab_b_lines else ""
    return f"; the header's law times {g:.6g}{lab}"


def idle_ga(stated, found, a, d: int) -> str | None:
    """Why a header's Ga is not in the data's law, where its whole-count output is 0 on every row.

    The lab's 2009 software (ryanGT's SLFR_RTP, ``Motor_Comp_w_accel_fb``) kept Ga's output,
    θ̂_d and v in int32 arrays: Ga's recursion stored its output as a whole count, truncated,
    and remembered that. The thesis's Ga (DESIGN.md) adds less than a count per tick, so the
    stored output stays 0 and the loop runs Gth alone; the header, which names Ga, is true of
    the software and the data's law is the lead alone.

    Parameters
    ----------
    stated : Compensator
        The header's controller (Gth and Ga).
    found : Compensator or OpenLoop
        The data's law.
    a : ndarray, shape (N,)
        The logged accelerometer counts.
    d : int
        The alignment the data's law reproduces the log at: Ga reads a[k - d] from tick d on.

    Returns
    -------
    str or None
        The words, when ``found`` is the header's Gth alone with its recursion on the stored
        integer and the header's Ga, its output stored as that integer (truncated or rounded
        as ``found``'s), is 0 on every row; else None.
    """
    ga, recursion = getattr(stated, "ga", None), getattr(found, "recursion", "none")
    if ga is None or not is_closed_loop(found) or found.ga is not None or recursion not in STORED:
        return None
    if not _same(_coefficients(stated)[:2], _coefficients(found)):
        return None
    x = np.asarray(a, dtype=float)[:max(len(a) - d, 0)]
    den = np.asarray(ga.den, dtype=float)
    out = np.convolve(np.asarray(ga.num, dtype=float) / den[0], x)[:x.size]  # every stored output 0: no feedback term
    quantize = RECURSIONS[recursion]
    if not (np.all(np.isfinite(out)) and all(quantize(float(y)) == 0.0 for y in out)):
        return None
    lab = " (as the lab's int32 arrays stored it)" if recursion == "trunc" else ""
    peak = float(np.max(np.abs(out), initial=0.0))
    return (f"the header's Ga, its output stored as a {STORED[recursion]} whole count{lab}, is 0 on every row "
            f"(its largest sum {peak:.2g}): the accelerometer feedback it names did nothing")


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


def completed_law(controller, u, theta, a, v, d: int, dt: float = DT, rig_limit: float | None = None,
                  prefer: int | None = None, restarts=()) -> IdentifiedController | None:
    """The continuous design a header's printed Gth rounds, where its exact discretization
    reproduces the log that the printed coefficients miss by a count.

    A lab script prints a design's z-coefficients to 8 digits; a recursion on the stored integer
    whose exact value falls on a whole count (round numbers give rational coefficients) then
    replays a count off where the print's last digit moves it across. The data's law found on its
    own may be another design of fewer digits that the log does not tell from the header's (a
    sine of 25 counts leaves a band of laws): the header's claim is judged by the simplest design
    within its print (:data:`SAME_LAW_RTOL`, :data:`PRINTED_TOLERANCE`) that reproduces the rows
    (:func:`station.analysis.continuous_design.recognize`), run as the rig ran it.

    Parameters
    ----------
    controller : Compensator
        The rig header's controller as replayed (its recursion the one that came nearest).
    u, theta, a, v : array_like, shape (N,)
        The log's reference, hub angle, accelerometer and commands (counts).
    d : int
        The alignment the header's law came nearest at (tried first; then the other: a print a
        count off may come nearest at the wrong one).
    dt : float
        Sample time, s.
    rig_limit : float, optional
        The clamp a law's words leave unsaid (default: the controller's).
    prefer : int or None
        As :func:`station.analysis.controller_id.fit_alignments`.
    restarts : sequence of int
        Rows where the log's ticks jump.

    Returns
    -------
    IdentifiedController or None
        The design's law, named by its text and holding it in its spec, when it reproduces every
        logged v (to :data:`station.analysis.law_rows.TOLERANCE`, or but on rows whose exact value
        is a quantization boundary: :func:`station.analysis.controller_id.replayed_or_tied`); None for open loop, a P
        law, a law with Ga, a station log's (its compensator file's coefficients are whole), or
        no design within the print that does.
    """
    if (not isinstance(controller, Compensator) or controller.spec.get("source") != "rig header"
            or controller.ga is not None or controller.recursion not in ("none", *STORED)):
        return None
    num = np.asarray(controller.gth.num, float) / controller.gth.den[0]
    den = np.asarray(controller.gth.den, float) / controller.gth.den[0]
    order = den.size - 1
    if not 1 <= order <= MAX_ORDER or num.size != den.size:
        return None
    for at in (d, *(x for x in ALIGNMENTS if x != d)):  # the print's miss may have chosen the other alignment
        hit = _completed_at(controller, num, den, order, u, theta, a, v, at, dt, rig_limit, prefer, restarts)
        if hit is not None:
            return hit
    return None


def _completed_at(controller, num, den, order: int, u, theta, a, v, d: int, dt: float, rig_limit, prefer,
                  restarts) -> IdentifiedController | None:
    """:func:`completed_law` at one alignment."""
    rows = LawRows(aligned_error(np.asarray(u, float), np.asarray(theta, float), d), np.asarray(v, float), d, order,
                   controller.limit)
    tol_num = PRINTED_TOLERANCE + SAME_LAW_RTOL * np.abs(num)
    tol_den = PRINTED_TOLERANCE + SAME_LAW_RTOL * np.abs(den)

    def within_print(n_unit: np.ndarray, d_unit: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        lo, hi = rows.gain_interval(n_unit, d_unit, controller.recursion, BOUNDARY)
        same_den = np.all(np.abs(d_unit - den) <= tol_den, axis=1)
        with np.errstate(divide="ignore", invalid="ignore"):  # the gains K with K·n_unit within the print
            k1, k2 = (num - tol_num) / n_unit, (num + tol_num) / n_unit
        k_lo = np.where(n_unit > 0, k1, np.where(n_unit < 0, k2, -np.inf))
        k_hi = np.where(n_unit > 0, k2, np.where(n_unit < 0, k1, np.inf))
        dead = np.any((n_unit == 0) & (np.abs(num) > tol_num), axis=1)
        lo = np.where(same_den & ~dead, np.maximum(lo, np.max(k_lo, axis=1)), np.inf)
        hi = np.where(same_den & ~dead, np.minimum(hi, np.min(k_hi, axis=1)), -np.inf)
        return lo, hi

    design = recognize(num, den, dt, within_print)
    if design is None:
        return None
    num_z, den_z = design.discretize(dt, order)
    deep = rows.least_squares("none") if controller.recursion == "none" else rows.deepest_fit(controller.recursion)
    c = None if deep is None else nudged_inside(rows, np.concatenate([num_z, den_z[1:]]), deep, controller.recursion)
    if c is None:
        return None
    num_z, den_z = c[:order + 1], np.concatenate(([1.0], c[order + 1:]))
    law = Compensator(DiscreteTF(num_z, den_z), None, limit=controller.limit, name=design.text,
                      spec={**controller.spec, "name": design.text, "design": design.to_json()},
                      shaper=controller.shaper, recursion=controller.recursion)
    limit = controller.limit if rig_limit is None else rig_limit
    words = law_text(order, np.concatenate([num_z, den_z[1:]]), design, dt, controller.recursion, law.limit, limit)
    return replayed_or_tied(law, (u, theta, a, v), words, (d, *(x for x in ALIGNMENTS if x != d)), design, prefer,
                            0, restarts, rows, c, controller.recursion, d)
