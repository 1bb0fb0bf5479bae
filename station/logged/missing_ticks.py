"""A named law on a copy that lacks ticks between its rows (a rig log kept every other tick,
n jumping by 2 and t by 0.004 s, or every k-th up to :data:`station.runlog.timebase.MISSING_SHARE`
+ 1): what its rows can say of the law, and how the model runs it.

The rig's laws ran at every 0.002 s tick; the rows in between are not in the log, so a law
with memory cannot be replayed on its rows (:func:`station.control.rerun.replay_commands`
starts again at each jump of n, and a copy where every row follows a jump leaves nothing to
judge). A law without memory (P: v[k] = kp·(u[k] − θ[k−d])) needs only θ at tick k − d: where
the log lacks that tick, θ there lay between the rows around it (the hub moves a few counts a
tick; a count either side for a turn between rows), so the logged v must lie in the law's range
over that bracket. At d = 0 that test is exact (θ of the row's own tick), so where a law holds at
both alignments d = 0 is used. A log that names no closed-loop law (none, or an open loop its v
contradicts) gets a P law found so (:func:`p_on_kept_rows`). A law with memory is run on θ
interpolated at the missing ticks, a number said beside it, never a verdict. Either way the
model then runs the law at every tick, the reference held between rows
(:func:`station.logged.simulate.simulate_log`).
"""

from __future__ import annotations

from dataclasses import replace
from typing import NamedTuple

import numpy as np

from station.analysis.controller_id import (TOLERANCE, IdentifiedController, clamps_to_try, infer_controller,
                                           law_variants)
from station.analysis.law_rows import pins_a_law
from station.control import p_controller
from station.control.rerun import (ALIGNMENTS, AlignmentFit, command_error, detect_alignment, is_closed_loop, memory,
                                   replay_commands)
from station.logged.audit import AuditClaim
from station.rig import CLAMP  # the rig's clamp: its laws ran at it
from station.runlog.timebase import on_ticks, restart_rows

GAP_LAW_ROWS = 100
"""Rows before a log's first jump of n that a law is inferred on, at least (0.2 s at the rig's
rate): many times the 14 coefficients of the largest law tried, Gth and Ga of order 3 each."""

TURN_COUNTS = 1.0
"""How far θ at a missing tick may lie outside the rows around it, encoder counts (one count:
the hub turning between two rows)."""


class KeptRowsLaw(NamedTuple):
    """A header's law judged on a copy that lacks ticks between its rows (:func:`law_on_kept_rows`).

    Attributes
    ----------
    law : Compensator
        The law as it reproduces the rows best (its recursion on the stored integer when that
        fits better).
    fit : AlignmentFit
        Its fit over the judged rows (a law with memory: replayed on interpolated θ).
    claim : AuditClaim
        The controller's audit row.
    alignments : tuple of int
        The alignments at which it holds.
    note : str
        One line on how the rows judged it and how the model runs it.
    judged : bool
        Whether the rows judged it (False: a law with memory, its fit a number only).
    """

    law: object
    fit: AlignmentFit
    claim: AuditClaim
    alignments: tuple
    note: str
    judged: bool


def _kept(ticks: np.ndarray, tick_s: float) -> str:
    """The copy's rows against its ticks, in words."""
    span = int(ticks.max()) + 1
    missing = span - np.unique(ticks).size
    return f"the log keeps {ticks.size} rows of {span} ticks ({missing} missing, {tick_s:g} s a tick)"


def _bracket(ticks: np.ndarray, theta: np.ndarray, d: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """θ at each row's tick − d: (lowest, highest, judged). Exact where the log has that tick;
    between the rows around it (± :data:`TURN_COUNTS`) where it does not; not judged before the
    log's first tick."""
    want = ticks - d
    order = np.argsort(ticks, kind="stable")
    placed = ticks[order]
    at = np.searchsorted(placed, want, side="left")
    exact = (at < placed.size) & (placed[np.minimum(at, placed.size - 1)] == want)
    before = order[np.clip(at - 1, 0, placed.size - 1)]
    after = order[np.clip(at, 0, placed.size - 1)]
    lo = np.minimum(theta[before], theta[after]) - TURN_COUNTS
    hi = np.maximum(theta[before], theta[after]) + TURN_COUNTS
    lo, hi = np.where(exact, theta[after], lo), np.where(exact, theta[after], hi)  # exact: `after` is that tick
    return lo, hi, want >= placed[0]


def _miss(law, u, lo, hi, a, v, judged) -> tuple[float, np.ndarray]:
    """How far each logged v lies outside a law's range over θ in [lo, hi] (a law without
    memory is monotone in θ): the largest miss over judged rows, and the range's nearest v."""
    at_hi, _ = replay_commands(law, u, hi, a, 0)  # the law at each end of the bracket, whatever kp's sign
    at_lo, _ = replay_commands(law, u, lo, a, 0)
    low, high = np.minimum(at_lo, at_hi), np.maximum(at_lo, at_hi)
    nearest = np.clip(v, low, high)
    miss = np.abs(v - nearest)[judged]
    return float(np.max(miss, initial=0.0)), nearest


def _interpolated(law, u, theta, a, v, ticks, d: int) -> AlignmentFit:
    """A law with memory run on every tick, θ and a interpolated at the missing ones and u held;
    its commands at the log's rows against the logged v."""
    grid = np.arange(int(ticks.max()) + 1)
    order = np.argsort(ticks, kind="stable")
    at = [np.interp(grid, ticks[order], np.asarray(x, float)[order]) for x in (theta, a)]
    out, _ = replay_commands(law, on_ticks(ticks, u)[0], at[0], at[1], d)
    replayed = out[ticks]
    return AlignmentFit(d, float(np.max(np.abs(replayed - v), initial=0.0)), replayed)


def law_on_kept_rows(controller, u, theta, a, v, ticks: np.ndarray, said: str, tick_s: float) -> KeptRowsLaw:
    """Judge a closed-loop law a log's header names on a copy that lacks ticks between its
    rows, and keep it to run the model at every tick.

    Parameters
    ----------
    controller : Compensator
        The header's law (closed loop).
    u, theta, a, v : numpy.ndarray, shape (N,)
        The log's columns (a with 0 where not finite).
    ticks : numpy.ndarray of int, shape (N,)
        Each row's tick from the first row's (:func:`station.runlog.timebase.row_ticks`).
    said : str
        The header's claim in words (:func:`station.logged.controller.describe_controller`).
    tick_s : float
        Seconds per tick (:func:`station.runlog.timebase.tick_time`), for the words.

    Returns
    -------
    KeptRowsLaw
    """
    u, theta, a, v = (np.asarray(x, dtype=float) for x in (u, theta, a, v))
    gap = _kept(ticks, tick_s)
    if memory(controller) == 0:  # P: θ at the tick it used, bracketed by the rows around it
        best, holds = None, []
        for d in sorted(ALIGNMENTS):
            lo, hi, judged = _bracket(ticks, theta, d)
            for law in law_variants(controller, v):
                dv, nearest = _miss(law, u, lo, hi, a, v, judged)
                if dv <= TOLERANCE and d not in holds:
                    holds.append(d)
                if best is None or dv < best[1].max_abs_dv - TOLERANCE:  # d = 0 first: its test is exact
                    best = (law, AlignmentFit(d, dv, nearest))
        law, fit = best
        ok = fit.max_abs_dv <= TOLERANCE
        words = (f"every logged v within the law's range over θ at the tick it used (the rows around a missing "
                 f"tick, ±{TURN_COUNTS:g} count): {gap}")
        claim = AuditClaim("controller", said, f"{said} at alignment {fit.alignment}" if ok else
                           f"not this law (max |dv| = {fit.max_abs_dv:.3g} counts)",
                           "confirmed" if ok else "contradicted" if fit.max_abs_dv >= 1.0 else "unchecked",
                           words if ok else f"a logged v lies {fit.max_abs_dv:.3g} counts outside the law's range "
                                            f"over θ at the tick it used: {gap}")
        note = (f"{gap}: the header's law is judged on θ bracketed at the missing ticks "
                f"(max |dv| = {fit.max_abs_dv:.3g} counts) and the model runs it at every tick, u held between rows")
        return KeptRowsLaw(law, fit, claim, tuple(sorted(holds)), note, True)
    best = None
    for law in law_variants(controller, v):
        for d in ALIGNMENTS:
            fit = _interpolated(law, u, theta, a, v, ticks, d)
            rms = float(np.sqrt(np.mean((fit.v_replayed - v) ** 2)))
            if best is None or rms < best[2]:
                best = (law, fit, rms)
    law, fit, rms = best
    words = (f"a law with memory ran on the ticks between the rows, which the log lacks: not judged ({gap}); "
             f"replayed on θ interpolated there it comes within {rms:.3g} counts RMS of the logged v "
             f"(max {fit.max_abs_dv:.3g})")
    claim = AuditClaim("controller", said, "not judged (ticks missing between rows)", "unchecked", words)
    note = f"{words}; the model runs the header's law at every tick, u held between rows"
    return KeptRowsLaw(law, fit, claim, (fit.alignment,), note, False)


def p_on_kept_rows(u, theta, a, v, ticks: np.ndarray, said: str, tick_s: float, stated: bool) -> KeptRowsLaw | None:
    """A P law v = kp·(u[k] − θ[k−d]) found on a copy that lacks ticks between its rows, where
    the log names no closed-loop law (none, or an open loop its v contradicts): kp by least
    squares on θ at the middle of each row's bracket, then the fewest digits of it (1 to 4, or
    as found) whose law every logged v lies within (:func:`law_on_kept_rows`'s test), at the
    rig's clamp or the log's own.

    Parameters
    ----------
    u, theta, a, v : numpy.ndarray, shape (N,)
        The log's columns.
    ticks : numpy.ndarray of int, shape (N,)
        Each row's tick from the first row's.
    said : str
        The header's claim in words ("not stated", "open loop", a PID's gains).
    tick_s : float
        Seconds per tick.
    stated : bool
        Whether the header named a law (an open loop, or a PID no standard discretization
        matched): its claim is then contradicted.

    Returns
    -------
    KeptRowsLaw or None
        None when v pins no law (:func:`station.analysis.law_rows.pins_a_law`) or no kp
        holds at either alignment.
    """
    u, theta, a, v = (np.asarray(x, dtype=float) for x in (u, theta, a, v))
    if not pins_a_law(v):
        return None
    brackets = {d: _bracket(ticks, theta, d) for d in sorted(ALIGNMENTS)}  # d = 0 first: its test is exact
    for d, (lo, hi, judged) in brackets.items():
        e = u - 0.5 * (lo + hi)
        for limit in clamps_to_try(v, CLAMP):
            rows = judged & (np.abs(v) < limit)
            if not np.any(e[rows] != 0):
                continue
            kp = float(np.dot(e[rows], v[rows]) / np.dot(e[rows], e[rows]))
            for gain in dict.fromkeys([float(f"{kp:.{k}g}") for k in (1, 2, 3, 4)] + [kp]):
                for law in law_variants(p_controller(gain, limit, tick_s), v):
                    dv, nearest = _miss(law, u, lo, hi, a, v, judged)
                    if dv <= TOLERANCE:  # and every other alignment at which it holds alike
                        holds = tuple(x for x, b in brackets.items() if x == d or _miss(law, u, b[0], b[1], a, v,
                                                                                      b[2])[0] <= TOLERANCE)
                        return _inferred(law, AlignmentFit(d, dv, nearest), holds, said, tick_s, ticks, stated)
    return None


def _inferred(law, fit: AlignmentFit, holds: tuple, said: str, tick_s: float, ticks: np.ndarray,
              stated: bool) -> KeptRowsLaw:
    """:func:`p_on_kept_rows`'s answer, in the audit's words."""
    gap = _kept(ticks, tick_s)
    data = f"P, kp = {law.spec['kp']:g} at alignment {fit.alignment}"
    header = f"the header's {said} does not give the logged v; " if stated else ""
    evidence = (f"{header}every logged v within the P law's range over θ at the tick it used (the rows around a "
                f"missing tick, ±{TURN_COUNTS:g} count): {gap}")
    claim = AuditClaim("controller", said, data, "contradicted" if stated else "unchecked", evidence)
    note = f"controller inferred from the data: {data} ({gap}); the model runs it at every tick, u held between rows"
    return KeptRowsLaw(law, fit, claim, holds, note, True)


def miss_at_gap(controller, u, theta, a, v, n, skipped) -> tuple[int, AlignmentFit] | None:
    """The row where n jumps (a tick missing or repeated) at which, or within its alignment
    after which, the controller replayed straight through at some alignment first misses the
    logged v, and that alignment's fit: a law judged on rows it never saw together, not
    contradicted.

    Parameters
    ----------
    controller : Compensator or OpenLoop
    u, theta, a, v, n : array_like, shape (N,)
        The log's columns.
    skipped : array_like of bool or None
        As :func:`station.control.rerun.replay_commands`.

    Returns
    -------
    (int, AlignmentFit) or None
        The fit's ``max_abs_dv`` is over the rows before that one (from the alignment's, to v's
        printing: :func:`station.control.rerun.command_error`), its ``v_replayed`` over every
        row. None when at every alignment it first misses elsewhere, or n does not jump.
    """
    n = np.asarray(n, dtype=float)
    if n.size < 2 or not np.all(np.isfinite(n)):
        return None
    gaps = np.flatnonzero(np.diff(n) != 1) + 1
    rows_back = memory(controller)
    for d in ALIGNMENTS if gaps.size else ():
        fit = detect_alignment(controller, u, theta, a, v, (d,), skipped)
        miss = np.flatnonzero(command_error(fit.v_replayed, v) > TOLERANCE)
        # the rows a jump reaches: d + the law's memory after it; every later row for Ga's, whose
        # state is in no column (the clamp can hide it for a while); none for an open loop (v = u
        # of its own row, whatever d)
        reach = 0 if not is_closed_loop(controller) else n.size if rows_back is None else d + rows_back
        near = gaps[(miss[0] >= gaps) & (miss[0] < gaps + reach)] if miss.size else gaps[:0]
        if near.size:
            gap = int(near[0])
            before = command_error(fit.v_replayed, v)[fit.alignment:gap]
            return gap, fit._replace(max_abs_dv=float(np.max(before, initial=0.0)))
    return None


def law_before_gap(u, theta, a, v, n, skipped, dt: float,
                   prefer: int | None) -> tuple[IdentifiedController, int] | None:
    """A law whose memory is in no column (Ga's state, a's whole past) inferred on the rows
    before a log's first jump of n, where the replay cannot start again: the law it finds, and
    the row where n jumps, past which it is not judged (as a header's law is, :func:`miss_at_gap`).

    Parameters
    ----------
    u, theta, a, v, n : array_like, shape (N,)
        The log's columns (u, θ in encoder counts, a in accelerometer counts, v in DAC counts).
    skipped : array_like of bool or None
        As :func:`station.control.rerun.replay_commands`.
    dt : float
        Sample time, s.
    prefer : int or None
        The alignment chosen where the law holds at several.

    Returns
    -------
    (IdentifiedController, int) or None
        The law replayed over every row (``max_abs_dv`` over the rows before the jump) and that
        row. None when n does not jump, fewer than :data:`GAP_LAW_ROWS` rows come before it, no
        law reproduces them (:func:`station.analysis.controller_id.infer_controller`), or the
        law replayed straight through first misses elsewhere than at a jump (a law whose memory
        the rows hold is judged across the jumps already).
    """
    jumps = restart_rows(n)  # the replay's own rows where n jumps
    if not jumps or jumps[0] < GAP_LAW_ROWS:
        return None
    first = jumps[0]
    cols = [np.asarray(x, dtype=float) for x in (u, theta, v, a)]
    hit = infer_controller(*(x[:first] for x in cols), dt, CLAMP, prefer=prefer)
    if hit is None or memory(hit.controller) is not None:
        return None
    found = miss_at_gap(hit.controller, cols[0], cols[1], cols[3], cols[2], n, skipped)
    if found is None or found[0] != first or found[1].alignment not in (hit.alignments or (hit.alignment,)):
        return None
    fit = found[1]
    return replace(hit, alignment=fit.alignment, max_abs_dv=fit.max_abs_dv, v_replayed=fit.v_replayed,
                   alignments=(fit.alignment,)), first
