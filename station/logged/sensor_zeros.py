"""A sensor's zero the loop took off before the log was written: θ's and a's.

The lab's client reads the encoder's count θ0 at START (``q``) and runs its loop on θ − θ0, and
it zeroes the accelerometer before a test (the rig's logs read a about 0.04 at rest: a reading
less a calibrated zero a0) and feeds the accelerometer feedback Ga the reading less a0. A script
that logs the readings as read writes θ from θ0 and a from a0, and the header's law then
reproduces no logged v. θ0 is the count θ rests on (:func:`station.logged.columns.check_theta_zero`
reads it alone; :func:`theta_zero_claim` says it). The law is linear in a between its clamps, so
the a0 that makes it reproduce the log is a least-squares fit (Gauss–Newton on the replayed
commands, :func:`fitted_zeros`; on a whole-count command, bisected on the first row the replay
misses); where the header's law reproduces every logged v from a − a0
(and θ − θ0, when θ rests on θ0 too), the column claims are contradicted and a (and θ) read
from their zeros (:func:`check_accel_zero`). With no header, or an open-loop one, the law the
data give is asked instead: Gth and Ga fitted from the data with a0 beside them
(:func:`data_accel_zero`).

A law that reproduces a as written, a bias and all, is an accelerometer offset the loop fed
back: a sensor fault (``accel_offset``, :mod:`station.logged.sensors`), not this; so is θ's
encoder not zeroed (:func:`station.logged.start.start_claims`).
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import NamedTuple

import numpy as np

from station.analysis.accel_law import GIVE_UP_COUNTS, AccelFeedback, accel_feedback
from station.analysis.controller_id import (ALIGNMENTS, MAX_ORDER, aligned_error, at_clamps, clamps_to_try,
                                            law_variants, whole_counts)
from station.analysis.law_rows import TOLERANCE, LawRows
from station.control.rerun import is_closed_loop, replay_commands
from station.logged.audit import AuditClaim
from station.errors import StationError
from station.logged.controller import ControllerId, header_law_dv, identify_controller, named_law
from station.logged.start import REST_ROWS, rest_rows
from station.runlog import RunLog
from station.rig import CLAMP
from station.runlog.timebase import restart_rows

ITERATIONS = 4
"""Gauss–Newton steps per law variant and alignment (the rig's lead + accelerometer step, a
written 37 counts over the loop's: 37.2 after the first, 37.000000 after the second)."""

REFINED = 4
"""Fits bisected and judged, by least residual (the law's variant, clamp and alignment)."""

BRACKET = 1.0
BISECTIONS = 48
"""A law on a whole-count command pins a0 to about 1e-4 counts (its rows' distance from a count
over a's effect on them), finer than Gauss–Newton on the quantized replay gets: bisected within
±:data:`BRACKET` counts of the fit, to 2e-14 counts at most."""

A0_STEP = 0.01
A0_ITERATIONS = 60
A0_CANDIDATES = 3
"""The a0 search where no law fitted with a0 beside it reproduced v (:func:`_a0_searched`):
Brent's bracket from the joint fit's a0, counts, its most iterations (three blind logs took
25–27 fits, a0 found within 6e-9 counts), and how many of the fits nearest v are searched."""

ZERO_FLOOR = 0.25
"""Least |a| at rest, counts, that :func:`data_accel_zero` reads as a zero not taken off (the
rig's zeroed logs rest at about 0.04)."""


THETA_ZERO_CLAIM = "θ as the loop's error used it"
ACCEL_ZERO_CLAIM = "a as the loop's accelerometer feedback used it"
"""The "columns" claims' headers: θ's zero and a's, as the loop took them off."""


class SensorZeros(NamedTuple):
    """Sensor zeros the loop took off before the log was written (:func:`check_accel_zero`).

    Attributes
    ----------
    claims : tuple of AuditClaim
        The contradicted "columns" claims: θ's zero (when θ rests on θ0 ≠ 0), then a's.
    log : RunLog
        The log with the zeros taken off θ and a, and a note each.
    a0 : float
        The accelerometer's zero the loop took off, counts.
    theta0 : float
        The encoder's count the loop took off, counts (0: none).
    identified : ControllerId or None
        The law the data give on the log read from its zeros, where the header names none
        (:func:`data_accel_zero`); None where the header's law is the one.
    """

    claims: tuple[AuditClaim, ...]
    log: RunLog
    a0: float
    theta0: float = 0.0
    identified: ControllerId | None = None


def theta_zero_claim(th0: float, rest: int, whose: str, dv: float) -> tuple[AuditClaim, str]:
    """θ logged before its zero θ0 was taken off, said: the contradicted "columns" claim and
    the log's note.

    Parameters
    ----------
    th0 : float
        The count θ rests on before the first command, encoder counts.
    rest : int
        Rows at rest (:func:`station.logged.start.rest_rows`).
    whose : str
        The law that reproduces v from θ − θ0, in words ("the header's law").
    dv : float
        Its max |dv|, DAC counts.

    Returns
    -------
    (AuditClaim, str)
    """
    claim = AuditClaim(
        "columns", THETA_ZERO_CLAIM, f"θ logged before its zero was taken off (θ0 = {th0:g} counts)",
        "contradicted",
        f"θ rests at {th0:g} counts on the {rest} rows before the first command, and {whose} reproduces every logged "
        f"v from θ − θ0 (to {dv:.2g} counts) where it does not from θ as written: the loop's error was "
        f"u − (θ − θ0), its zero taken at the start; read from θ0")
    return claim, f"θ logged before its zero was taken off (the audit): {th0:g} taken off"


def fitted_zeros(controller, log: RunLog, skipped=None) -> list[float]:
    """The zeros a0 of a that best make ``controller`` reproduce the logged v from a − a0,
    one per law variant (:func:`station.analysis.controller_id.law_variants`) and alignment,
    by Gauss–Newton least squares over the rows no clamp holds (the replay is linear in a
    there: its sensitivity to a is the replay's change under a − 1).

    Parameters
    ----------
    controller : Compensator
        A closed-loop law.
    log : RunLog
        u, θ, a and v finite.
    skipped : array_like of bool, optional
        As :func:`station.control.rerun.replay_commands`.

    Returns
    -------
    list of float
        Candidate zeros, accelerometer counts, by least residual first; empty when the law
        does not feed a back (the replay does not change with a).
    """
    d = log.data
    u, theta, a, v = (np.asarray(d[c], dtype=float) for c in ("u", "theta", "a", "v"))
    restarts = restart_rows(d["n"])
    found = []
    for clamped in at_clamps(controller, v):
        for law in law_variants(clamped, v):
            for alignment in ALIGNMENTS:
                fit = _gauss_newton(law, u, theta, a, v, alignment, skipped, restarts)
                if fit is None:
                    return []
                found.append((*fit, law, alignment))
    found.sort(key=lambda f: f[0])
    zeros = []
    for dv, a0, law, alignment in found[:REFINED]:
        if dv > TOLERANCE and law.recursion != "none":  # a whole count stored or sent: a0 pinned finer
            a0 = _bisected(law, u, theta, a, v, alignment, skipped, restarts, a0)
        zeros.append(a0)
    return zeros


def _gauss_newton(law, u, theta, a, v, alignment: int, skipped, restarts) -> tuple[float, float] | None:
    """(max |dv|, a0) of one law variant at one alignment (:func:`fitted_zeros`); None when the
    replay does not change with a."""
    limit = law.limit or np.inf
    a0 = 0.0
    for step_number in range(ITERATIONS):
        r0, _ = replay_commands(law, u, theta, a - a0, alignment, skipped, v, restarts=restarts)
        r1, _ = replay_commands(law, u, theta, a - a0 - 1.0, alignment, skipped, v, restarts=restarts)
        h = r0 - r1
        if not np.any(h):  # from a as written: the law does not feed a back; later, every row clamped
            return None if step_number == 0 else (np.inf, a0)
        free = (np.abs(r0) < limit) & (np.abs(r1) < limit) & (np.abs(v) < limit) & (h != 0)
        free[:alignment] = False  # the rows before the law's first sample
        if not free.any():
            break
        step = float(np.dot(h[free], (r0 - v)[free]) / np.dot(h[free], h[free]))
        a0 += step
        if abs(step) <= 1e-9 * max(1.0, abs(a0)):
            break
    r0, _ = replay_commands(law, u, theta, a - a0, alignment, skipped, v, restarts=restarts)
    return float(np.max(np.abs(r0 - v)[alignment:], initial=0.0)), a0


def _bisected(law, u, theta, a, v, alignment: int, skipped, restarts, a0: float) -> float:
    """a0 within :data:`BRACKET` counts of a fit, bisected on the first row the replay misses:
    every row before it reproduced, the law's memory there is the log's, and that row's
    command moves with a0 only through the error's a-part (θ̂_d = u − Ga(a − a0), linear:
    Gth's numerator over its change). The fit itself where no bisection reproduces every row."""
    _, hat0 = replay_commands(law, u, theta, a - a0, alignment, skipped, v, restarts=restarts)
    _, hat1 = replay_commands(law, u, theta, a - a0 - 1.0, alignment, skipped, v, restarts=restarts)
    falls = np.convolve(hat0 - hat1, law.gth.num)[:v.size]  # −∂(the row's command before its count)/∂a0
    lo, hi = a0 - BRACKET, a0 + BRACKET
    for _ in range(BISECTIONS):
        mid = 0.5 * (lo + hi)
        r0, _ = replay_commands(law, u, theta, a - mid, alignment, skipped, v, restarts=restarts)
        missed = np.flatnonzero(np.abs(r0 - v)[alignment:] > TOLERANCE)
        if not missed.size:
            return mid
        k = int(missed[0]) + alignment
        if falls[k] == 0:  # a row a0 does not move: no side to take
            return a0
        if (r0[k] - v[k]) * falls[k] > 0:  # too high, falling as a0 grows: a0 is above mid
            lo = mid
        else:
            hi = mid
    return a0


def check_accel_zero(log: RunLog, skipped=None) -> SensorZeros | None:
    """a's zero checked by the header's law: where the header names a closed-loop law that
    feeds a back, the run rests (u and θ unchanged) for :data:`REST_ROWS` rows before the first
    command, and the law reproduces every logged v from a − a0 (to the device's quantization)
    where it does not from a as written, a was logged before the loop took its zero a0 off;
    read from a0. Where θ rests on a whole count θ0 ≠ 0 there too, the law is asked of θ − θ0
    as well (both zeros taken off by the lab's client). Where the header names no closed-loop
    law (none, or open loop), :func:`data_accel_zero` asks the law the data give.

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    SensorZeros or None
        None otherwise: a closed-loop law named that feeds no a back, the law reproduces a as
        written (from θ or θ − θ0), a column not finite, too short a rest, or no a0 makes the
        law reproduce the log.
    """
    controller = named_law(log)
    if controller is None or not is_closed_loop(controller):
        return data_accel_zero(log, skipped)
    if getattr(controller, "ga", None) is None:
        return None
    if not all(np.all(np.isfinite(log.data[c])) for c in ("u", "theta", "a", "v")):
        return None
    u, theta, a = (np.asarray(log.data[c], dtype=float) for c in ("u", "theta", "a"))
    rest = rest_rows(u, theta)
    if rest < REST_ROWS or u[0] != 0:
        return None
    for zero in _theta_zeros(theta):
        from_zero = dataclasses.replace(log, data={**log.data, "theta": theta - zero})
        as_written = header_law_dv(from_zero, skipped)
        if as_written is None or as_written <= TOLERANCE:  # a as written (θ0 alone is columns.check_theta_zero's)
            return None
        for a0 in fitted_zeros(controller, from_zero, skipped):
            trial = dataclasses.replace(from_zero, data={**from_zero.data, "a": a - a0})
            dv = header_law_dv(trial, skipped)
            if dv is not None and dv <= TOLERANCE:
                return _said(log, trial, rest, a0, zero, dv, as_written)
    return None


def data_accel_zero(log: RunLog, skipped=None) -> SensorZeros | None:
    """a's zero checked by the law the data give, where the header names no closed-loop law
    (none, or open loop): where a rests off 0 (by :data:`ZERO_FLOOR` counts or more) on the
    :data:`REST_ROWS` or more rows before the first command, and a law with accelerometer
    feedback reproduces every logged v from a − a0 (Gth and Ga fitted with a0 beside them,
    :func:`station.analysis.accel_law.accel_feedback`'s ``zero``; a0 within the rest's spread)
    where it does not from a as written, a was logged before the loop took its zero a0 off.
    Where no such fit reproduces v, a0 is searched alone on the fits nearest it
    (:func:`_a0_searched`).

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    SensorZeros or None
        With the law identified on a − a0; None otherwise, and on a whole-count command (its
        recursion beside Ga is not fitted: :mod:`station.analysis.accel_law`).
    """
    if not all(np.all(np.isfinite(log.data[c])) for c in ("u", "theta", "a", "v")):
        return None
    u, theta, a, v = (np.asarray(log.data[c], dtype=float) for c in ("u", "theta", "a", "v"))
    rest = rest_rows(u, theta)
    if rest < REST_ROWS or u[0] != 0 or whole_counts(v) or abs(np.mean(a[:rest])) < ZERO_FLOOR:
        return None
    resting, spread = float(np.mean(a[:rest])), 1.0 + 4.0 * float(np.std(a[:rest]))
    orders = [(m, total - m) for total in range(1, 2 * MAX_ORDER + 1)  # the simplest law first
              for m in range(max(0, total - MAX_ORDER), min(total - 1, MAX_ORDER) + 1)]
    near = []  # (miss, zero, m, p, d, limit, a0): fits within a count of v that do not reproduce it
    for zero, (m, p), d, limit in itertools.product(_theta_zeros(theta), orders, ALIGNMENTS, clamps_to_try(v, CLAMP)):
        ga = accel_feedback(u, theta - zero, a, v, d, m, p, limit, log.dt, zero=True)
        if ga is None or abs(ga.a0 - resting) > spread:
            continue
        if (miss := _gth_miss(u, theta - zero, v, d, m, limit, ga)) > TOLERANCE:
            if miss <= GIVE_UP_COUNTS:
                near.append((miss, zero, m, p, d, limit, ga.a0))
            continue
        if (said := _law_said(log, theta - zero, a, ga.a0, zero, rest, skipped)) is not None:
            return said
    for _, zero, m, p, d, limit, a0 in sorted(near, key=lambda x: x[0])[:A0_CANDIDATES]:  # the nearest first
        ga = _a0_searched(u, theta - zero, a, v, d, m, p, limit, log.dt, a0, (resting - spread, resting + spread))
        if ga is not None and \
                (said := _law_said(log, theta - zero, a, ga.a0, zero, rest, skipped)) is not None:
            return said
    return None


def _law_said(log: RunLog, theta, a, a0: float, zero: float, rest: int, skipped) -> SensorZeros | None:
    """:func:`data_accel_zero`'s answer where the data's law on a − a0 (and θ − θ0) reproduces v."""
    found = _data_law(log, theta, a - a0, skipped)
    if found is None:
        return None
    trial, cid, as_written = found
    return _said(log, trial, rest, a0, zero, cid.fit.max_abs_dv, as_written, cid)


def _gth_miss(u, theta, v, d: int, m: int, limit: float, ga: AccelFeedback) -> float:
    """Largest |v − Gth's| (DAC counts) of Gth of order ``m`` fitted beside ``ga`` (quick, to
    the float's last digits); inf where none fits."""
    rows = LawRows(aligned_error(u, theta, d) - ga.x, v, d, m, limit)
    c = rows.least_squares("none")
    return np.inf if c is None else float(np.max(np.abs(rows.predict(c, "none") - rows.v)))


def _a0_searched(u, theta, a, v, d: int, m: int, p: int, limit: float, dt: float,
                 a0: float, bounds: tuple[float, float]) -> AccelFeedback | None:
    """a's zero searched alone, Ga fitted anew at each (Brent's method on log10 of
    :func:`_gth_miss`, bracketed from the joint fit's ``a0``), where the joint fit came within
    a count of v but did not reproduce it: a0 and a slow pole of Ga trade against each other
    there (the joint fit ended 7e-5 counts off a0 on a blind log and missed v by 4e-4 counts),
    where a fixed a0 is well conditioned. The search stays within ``bounds`` (counts, where a
    rests): outside them the miss is raised by the distance, so a miss that falls on and on
    ends the bracket there, not at the float's overflow. The Ga with a0 that reproduces every
    v, else None (also where scipy finds no bracket)."""
    from scipy.optimize import minimize_scalar  # lazy: start-up time

    low, high = bounds
    fits: dict[float, tuple[AccelFeedback | None, float]] = {}

    def fitted(x: float) -> tuple[AccelFeedback | None, float]:
        if x not in fits:
            ga = accel_feedback(u, theta, a - x, v, d, m, p, limit, dt)
            ga = None if ga is None else AccelFeedback(ga.num, ga.den, ga.x, float(x))
            fits[x] = (ga, np.inf if ga is None else _gth_miss(u, theta, v, d, m, limit, ga))
        return fits[x]

    def log_miss(x: float) -> float:
        if not low <= x <= high:
            return 3.0 + max(low - x, x - high)  # above any miss within: the bracket ends here
        return float(np.log10(min(fitted(x)[1], 1e3) + 1e-12))

    try:
        best = minimize_scalar(log_miss, bracket=(a0 - A0_STEP, a0),
                               options={"xtol": 1e-10, "maxiter": A0_ITERATIONS})
    except (RuntimeError, ValueError):  # scipy's BracketError: no bracket within the bounds
        return None
    if not low <= best.x <= high:
        return None
    ga, miss = fitted(float(best.x))
    return ga if miss <= TOLERANCE else None


def _theta_zeros(theta: np.ndarray) -> list[float]:
    """The zeros of θ a law is asked from: none, and the whole count θ0 ≠ 0 it rests on."""
    th0 = float(theta[0])
    return [0.0] + ([th0] if th0 != 0 and np.all(theta == np.round(theta)) else [])


def _data_law(log: RunLog, theta, a, skipped) -> tuple[RunLog, ControllerId, float] | None:
    """(the log read from its zeros, its law, max |dv| from a as written) where the data's law
    on θ and a feeds a back and reproduces every logged v, and not from a as written."""
    trial = dataclasses.replace(log, data={**log.data, "theta": theta, "a": a})
    try:
        cid = identify_controller(trial, skipped)
    except StationError:
        return None
    if cid.fit is None or cid.fit.max_abs_dv > TOLERANCE or getattr(cid.controller, "ga", None) is None:
        return None
    written = np.asarray(log.data["a"], dtype=float)
    replayed, _ = replay_commands(cid.controller, trial.data["u"], theta, written, cid.fit.alignment, skipped,
                                  trial.data["v"], restarts=restart_rows(log.data["n"]))
    as_written = float(np.max(np.abs(replayed - trial.data["v"])[cid.fit.alignment:], initial=0.0))
    return (trial, cid, as_written) if as_written > TOLERANCE else None


def _said(log: RunLog, trial: RunLog, rest: int, a0: float, th0: float, dv: float, as_written: float,
          identified: ControllerId | None = None) -> SensorZeros:
    """:func:`check_accel_zero`'s claims and the log read from the zeros."""
    a = np.asarray(log.data["a"], dtype=float)
    also = " and θ − θ0" if th0 else ""
    whose = "the header's law" if identified is None else "the law the data give"
    claim = AuditClaim(
        "columns", ACCEL_ZERO_CLAIM, f"a logged before its zero was taken off (a0 = {a0:.4g} counts)", "contradicted",
        f"a reads {np.mean(a[:rest]):.4g} counts on average on the {rest} rows at rest before the first command, "
        f"and {whose}, which feeds a back, reproduces every logged v from a − a0{also} (to {dv:.2g} "
        f"counts) where it does not from a as written (max |dv| = {as_written:.3g} counts): the loop fed back the "
        f"reading less its zero a0; read from a0")
    claims, notes = [claim], [f"a logged before its zero was taken off (the audit): {a0:.6g} taken off"]
    if th0:
        theta_claim, note = theta_zero_claim(th0, rest, f"{whose} (from a − a0)", dv)
        claims.insert(0, theta_claim)
        notes.insert(0, note)
    return SensorZeros(tuple(claims), dataclasses.replace(trial, notes=list(log.notes) + notes), a0, th0, identified)
