"""The reference's unit: a closed loop's u in encoder counts, checked against its law.

A log claims u in encoder counts, the unit the loop's error u - θ is taken in (DESIGN.md "Log
audit": the columns' units). A lab script that wrote the reference in degrees, radians or milliradians
while θ stayed in counts leaves a log whose law reproduces no logged v as written (a P step of
50 counts written 17.578125: the header's kp = 2 misses by 65 counts) and every v with u read
back in counts. θ in degrees too is :mod:`station.logged.units`' (u goes with it); this is a
reference alone in another unit, decided by the law: a step is a multiple of the unit's
share of a count, but a sine is not, and only the law tells.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from station.analysis.controller_id import check_law
from station.analysis.law_rows import TOLERANCE, pins_a_law
from station.control.rerun import pole_radius
from station.errors import StationError
from station.logged.audit import AuditClaim
from station.logged.controller import ControllerId, describe_controller, header_law_dv, identify_controller
from station.logged.units import THETA_UNITS, counts_of
from station.rig import COUNTS_PER_REV
from station.runlog import RunLog


class ReferenceUnit(NamedTuple):
    """A reference found in another unit (:func:`check_reference_unit`).

    Attributes
    ----------
    claim : AuditClaim
        The contradicted "columns" claim.
    log : RunLog
        The log with u in encoder counts and a note.
    identified : ControllerId or None
        The law the data give on it, when no header named one.
    """

    claim: AuditClaim
    log: RunLog
    identified: ControllerId | None


LAGS = 3
"""Lags of the regression that finds u's share of the loop's error (:func:`reference_ratio`):
the rig's laws are of order 3 at most."""

RATIO_TOLERANCE = 0.2
"""How near 1 u's share (:func:`reference_ratio`) says u is in counts and no other unit is
tried (in degrees it is 2.84, in radians 163, where a step pins it; a 5 Hz sine, or a
recursion on the stored integer, may leave it anywhere, and then the law decides)."""


def reference_ratio(log: RunLog) -> float | None:
    """How many counts of θ one unit of u is worth to the loop's law: -Σb_u / Σb_θ of the
    least-squares fit v[k] = Σ b_u,i u[k-i] + Σ b_θ,i θ[k-i] + Σ b_a,i a[k-i] + Σ c_i v[k-i]
    (i ≤ :data:`LAGS`). A law on the error u - θ (any order, beside an accelerometer feedback)
    weighs u and θ alike at DC: 1 with u in counts, 1/q with u in a unit of q counts' share.

    Parameters
    ----------
    log : RunLog

    Returns
    -------
    float or None
        None when the fit is singular or θ carries no weight.
    """
    u, theta, v, a = (np.asarray(log.data[c], dtype=float) for c in ("u", "theta", "v", "a"))
    n = u.size
    if n <= 4 * LAGS or not np.all(np.isfinite(v)):
        return None
    rows = slice(LAGS, n)
    cols = [x[LAGS - i:n - i] for x in (u, theta) for i in range(LAGS + 1)]
    if np.all(np.isfinite(a)) and np.any(a != a[0]):
        cols += [a[LAGS - i:n - i] for i in range(LAGS + 1)]
    cols += [v[LAGS - i:n - i] for i in range(1, LAGS + 1)]
    coef, *_ = np.linalg.lstsq(np.column_stack(cols), v[rows], rcond=None)
    b_u, b_theta = float(np.sum(coef[:LAGS + 1])), float(np.sum(coef[LAGS + 1:2 * LAGS + 2]))
    if not np.isfinite(b_u) or abs(b_theta) < 1e-9:
        return None
    return -b_u / b_theta


def exact_from_rest(found: ControllerId) -> bool:
    """Whether an identified law reproduces every logged v (to :data:`TOLERANCE`) from rest: not
    with its first rows of memory taken as logged (a "cut" copy), not only up to a jump of n.

    Parameters
    ----------
    found : ControllerId
        As :func:`station.logged.controller.identify_controller` gives it.
    """
    return (found.fit is not None and not found.cut and found.judged_to is None
            and found.fit.max_abs_dv <= TOLERANCE)


def check_reference_unit(log: RunLog, skipped=None, as_named: float | None = None) -> ReferenceUnit | None:
    """Whether a closed loop's u is in degrees, radians or milliradians of the hub (θ in counts): the
    header's law (else the law the data give) reproduces every logged v with u divided by one
    encoder count in that unit (:data:`station.logged.units.THETA_UNITS`). Not asked where a
    least-squares fit already weighs u as counts (:func:`reference_ratio` within
    :data:`RATIO_TOLERANCE` of 1); the unit it points at is tried first.

    A header's law is replayed on u in counts (cheap); a law is searched for (costly: every
    recursion, order and alignment) with none named or an open-loop one, where the caller found
    none as written, or where the fit's weight points at the unit (a header lying about the law
    as well).

    Parameters
    ----------
    log : RunLog
        A log whose law, as its columns are written, does not reproduce it.
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.
    as_named : float or None
        The header's law's max |dv| as written (:func:`header_law_dv`), None when no header
        names a closed-loop law.

    Returns
    -------
    ReferenceUnit or None
        None when u is not finite or 0 throughout, θ not finite, v pins no law
        (:func:`station.analysis.law_rows.pins_a_law`) and no header names one, or no unit makes
        a law reproduce v. A v that pins no law (0 and one level: a hub held still) is read only
        by the header's law at its own clamp.
    """
    u, theta = (np.asarray(log.data[c], dtype=float) for c in ("u", "theta"))
    pinned = pins_a_law(log.data["v"])
    usable = np.all(np.isfinite(u)) and np.all(np.isfinite(theta)) and np.any(u)
    if not usable or not (pinned or as_named is not None):
        return None  # a v that pins no law (a step at a clamp, u swapped in: any law of high gain gives it)
    ratio = reference_ratio(log) if pinned else None  # (0 and one level weigh nothing)
    if ratio is not None and abs(ratio - 1.0) <= RATIO_TOLERANCE:  # the law weighs u as counts
        return None
    # a step pins the ratio; a sine, or a recursion on the stored integer, may not: then the law decides
    def off(item):  # how far the fit's weight is from the unit's (its log ratio)
        return 0.0 if ratio is None else abs(np.log(abs(ratio * item[1]) + 1e-12))

    units = sorted(THETA_UNITS.items(), key=off)
    for unit, q in units:
        counts = counts_of(u, q)  # a step's counts, printed in the unit: whole again
        trial = dataclasses.replace(log, data={**log.data, "u": counts})
        found, dv = None, None if as_named is None else header_law_dv(trial, skipped, own_clamp=not pinned)
        if dv is not None and dv <= TOLERANCE:
            whose = "the header's law" if pinned else "the header's law at its own clamp"
        elif not pinned:
            continue  # a v of 0 and one level (a hub held still): only the header's law at its own clamp reads it
        elif as_named is not None and (ratio is None or abs(ratio * q - 1.0) > RATIO_TOLERANCE):
            continue  # a header that lies about the law as well: searched only where the fit points at the unit
        else:  # none named, an open loop's v = u, or a lying header the fit's weight of u points past
            try:
                found = identify_controller(trial, skipped)
            except StationError:
                continue
            # a recursion that grows is no lab's law (an order-3 fit with a pole at z = 1062 on the
            # truncated integer at a ±100 clamp "reproduced" the P step with θ negated, u 163x)
            if not exact_from_rest(found) or pole_radius(found.controller) > 1.0 + 1e-6:
                continue
            # nor is a law that gives v from u of twice the size too (an integrator whose first row
            # the clamp took: the P step with θ written 4x read as "u in radians"): u's unit undecided
            twice = check_law(found.controller, 2.0 * counts, theta, np.nan_to_num(np.asarray(log.data["a"], float)),
                              np.asarray(log.data["v"], float), "", (found.fit.alignment,))
            if twice is not None and twice.max_abs_dv <= TOLERANCE:
                continue
            whose, dv = f"the law the data give ({describe_controller(found.controller)})", float(found.fit.max_abs_dv)
        before = "" if as_named is None else f" (as written: max |dv| = {as_named:.3g} counts)"
        claim = AuditClaim("columns", "u in encoder counts", f"u in {unit}", "contradicted",
                           f"{whose} reproduces every logged v to {dv:.2g} counts with u read in encoder counts "
                           f"(u / {q:.6g}, {unit} per count of {COUNTS_PER_REV}/rev){before}: a reference "
                           f"written in {unit}")
        note = f"u is in {unit} (the audit): converted to encoder counts"
        return ReferenceUnit(claim, dataclasses.replace(trial, notes=list(log.notes) + [note]), found)
    return None
