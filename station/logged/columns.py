"""Which column holds what: the column line's names checked against the log's law.

A log's column line is a claim too (DESIGN.md "Log audit": the columns' units and signs, and
so their names): a lab script that wrote its columns in another order than it named them
gives a log whose header names the right law and whose "v" is not that law's output. When
the header's closed-loop law reproduces no logged v as the columns are named but every one
with two columns swapped (u and v, θ and a), or with θ negated (a script that wrote the
loop's angle with the other sign; a's sign is Ga's, :data:`TRIALS`), the data
say which column is which: the claim is contradicted, said first, and the log is read with
the columns swapped or negated. The law is the
header's own (as given, at its clamp or the log's, or completed from the data where it comes
within :data:`NEAR_COUNTS`); a log with no header, an open-loop one, or a header whose law
reproduces it on no rewrite either (a header that lies about the law as well: a P header's kp
over another gain, the columns swapped) is checked the same way against the law inferred from
its data, tried on the swaps only when none is found as the columns are named.

The command's unit is checked the same way: a v the header's law does not reproduce, whose
changes are all whole multiples of one size other than a DAC count (a script that wrote the
command in volts), is read in counts when its law (the data's, where the header lies about the
law as well) then reproduces it and the DAC's range says so too (:func:`check_command_unit`). A
P law's v scaled is also another kp, so only a v that can be no DAC command as written is read
so: under one count everywhere while the hub moved (the device would apply nothing), or past
the DAC's ±255 counts.

So is its zero (:func:`check_command_offset`): a v that reads one value other than 0 at rest
and that the header's law (or the data's, as for the unit) reproduces less that value was
written about another zero.
So is θ's (:func:`check_theta_zero`): a θ that rests on one count θ0 other than 0 before the
first command, whose law reproduces v from θ − θ0 and not from θ as written, was logged as the
encoder read it by a loop that took θ0 off (the lab's client reads θ0 at START); so is a's, under
a law feeding a back, and of both at once (:func:`station.logged.sensor_zeros.check_accel_zero`).

An open-loop run (v = u: no law feeds θ or a back) cannot say θ from a by a law: there the
sensors themselves say it (:mod:`station.logged.sensor_swap`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from station.analysis.glitches import most_glitches
from station.analysis.header_law import NEAR_COUNTS
from station.analysis.law_rows import TOLERANCE, no_dac_command, pins_a_law
from station.control.rerun import is_closed_loop
from station.errors import StationError
from station.logged.audit import AuditClaim
from station.logged.column_zeros import (ZEROED_TOO, Columns, check_command_offset, check_theta_zero, law_confirms,
                                         theta_from_zero)
from station.logged.command_scale import Scaled, law_line, law_scale
from station.logged.quantum import CONVERTER_VOLTS, count_step, in_counts, quantum_fits
from station.logged.controller import (NO_LAW, ControllerId, header_law_dv,
                                       header_reproduces, identify_controller)
from station.logged.reference_unit import check_reference_unit
from station.logged.sensor_zeros import check_accel_zero
from station.logged.rewrite_evidence import model_miss, tracking_error, tracks_better
from station.logged.units import whole_counts
from station.rig import DAC_LIMIT
from station.runlog import RunLog

SWAPS = (("u", "v"), ("theta", "a"), ("v", "theta"), ("u", "theta"))
"""Column pairs a swap is tried for: the reference and the command, the two sensors; the
command and the angle, the reference and the angle (a script that mapped one layout's columns
onto another's by place: the 2014 logs write v last)."""

TRIALS = SWAPS + (("theta",),)
"""What a law is tried on when it reproduces no v as the columns are named (the header's
closed-loop law, or the law inferred from the data): each swap, and θ negated (a script that
wrote the loop's angle with the other sign). An a written with the other sign than the loop fed
back is not a rewrite: it is Ga's sign (the law found on a as logged, Ga negated: the header's
claim contradicted, :func:`station.analysis.law_words.ga_text`), beside the accelerometer the
sensor audit reads reversed; so a session whose runs all read a reversed gets one sign, not a
column read back in the run that feeds it back and reversed again by the session's decision."""

PAIRS = tuple((pair, ("theta",)) for pair in SWAPS[:2])
"""Two column faults at once, tried when no one of :data:`TRIALS` makes the header's law
reproduce the log: a swap, then θ negated (a script that wrote its columns in another order and
the loop's angle with the other sign)."""

COMMAND_STEP_COUNTS = 10
"""Most DAC counts v's least change may span when it is written in another unit (a P law's v
steps by kp counts: :func:`check_command_unit` tries each)."""

UNKNOWN_UNIT = "v in another unit, its size not found"
"""The "columns" claim's data for a v that is no DAC command as written, in a size the data do
not give (:func:`check_command_unit`)."""

READ_AS_SAID = "the law the data give reproduces v, the columns read as the claims after this one say,"
"""How a rewrite's claim says that other columns were read back too (their claims follow it)."""

SHOWN = {"u": "u", "v": "v", "theta": "θ", "a": "a"}
"""How a column's name is printed."""


def swapped(log: RunLog, first: str, second: str) -> RunLog:
    """A copy of ``log`` with two of its columns exchanged.

    Parameters
    ----------
    log : RunLog
    first, second : str
        Standard column names (``station.runlog.COLUMNS``).
    """
    data = dict(log.data)
    data[first], data[second] = log.data[second], log.data[first]
    return dataclasses.replace(log, data=data)


def rewritten(log: RunLog, columns: tuple[str, ...]) -> RunLog:
    """A copy of ``log`` with a pair of :data:`TRIALS` swapped, or its one column negated.

    Parameters
    ----------
    log : RunLog
    columns : tuple of str
        Two standard column names to exchange, or one to negate.
    """
    if len(columns) == 2:
        return swapped(log, *columns)
    (name,) = columns
    return dataclasses.replace(log, data={**log.data, name: -np.asarray(log.data[name], dtype=float)})


def rewritten_all(log: RunLog, rewrites: tuple[tuple[str, ...], ...]) -> RunLog:
    """A copy of ``log`` with each of ``rewrites`` applied in turn.

    Parameters
    ----------
    log : RunLog
    rewrites : tuple of tuple of str
        Each :func:`rewritten`'s ``columns``: two names to exchange, or one to negate.
    """
    for columns in rewrites:
        log = rewritten(log, columns)
    return log


def check_columns(log: RunLog, skipped=None) -> Columns:
    """Check the column line against the header's closed-loop law (:func:`columns_as_named`),
    and where that law reproduces neither the log nor what the check made of it, also each
    rewrite of :data:`TRIALS` checked so, when the law lies on a line through v there
    (:func:`station.logged.command_scale.law_line`): three faults at once (θ negated, from its
    zero, and v in volts or about an unsigned DAC code's zero).

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    Columns
        As :func:`columns_as_named`; a rewrite's claim first, the claims of the check of the
        rewritten log after it, where only so the header's law reproduces v.
    """
    found = columns_as_named(log, skipped)
    if len(log) < 2 or named_by_header(found, skipped):
        return found
    for rewrites in tuple((c,) for c in TRIALS) + PAIRS:  # one rewrite, then a swap and θ negated
        trial = rewritten_all(log, rewrites)
        if not law_line(trial, skipped):
            continue
        inner = columns_as_named(trial, skipped)
        if inner.claims and named_by_header(inner, skipped):
            return _swapped_back(log, rewrites, inner.log, header_law_dv(log, skipped),
                                 "the header's law reproduces v, its columns read as the claims after this one say,",
                                 inner.identified, also=inner.claims)
    return found


def named_by_header(found: Columns, skipped=None) -> bool:
    """Whether the header's closed-loop law reproduces a column check's log (its own clamp where
    v pins no law), or the check's identification confirmed the header.

    Parameters
    ----------
    found : Columns
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    bool
        False where no closed-loop law named reproduces it (an open-loop header, or none) and no
        identification confirmed the header.
    """
    claim = found.identified.claim if found.identified is not None else None
    if claim is not None and claim.verdict == "confirmed":
        return True
    v = np.asarray(found.log.data["v"], dtype=float)
    dv = header_law_dv(found.log, skipped, own_clamp=not in_counts(v) and not pins_a_law(v))
    return dv is not None and dv <= TOLERANCE


def columns_as_named(log: RunLog, skipped=None) -> Columns:
    """Check the column line against the header's closed-loop law, or with no header (or an
    open-loop one no law replaces) against the law the data give (:data:`TRIALS`, :data:`PAIRS`;
    a single rewrite whose θ rests off 0 also from that zero, :func:`check_theta_zero`).

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    Columns
        The log as it is when its law (the header's closed-loop law; with no header, the law
        the data give) reproduces it as named, or when no swap or sign makes one reproduce it;
        else the rewritten copy and its claim; first, a command written in another unit read in
        counts (:func:`check_command_unit`).
    """
    if len(log) < 2:
        return Columns((), log)
    unit = check_command_unit(log, skipped)
    if unit is not None and unit.claims[0].data != UNKNOWN_UNIT:
        return unit
    v = np.asarray(log.data["v"], dtype=float)
    as_named = header_law_dv(log, skipped, own_clamp=not in_counts(v) and not pins_a_law(v))  # (its unit unread)
    if unit is None and as_named is not None and as_named <= TOLERANCE:
        return _rewritten_at_own_clamp(log, skipped) or Columns((), log)
    named = as_named > TOLERANCE if as_named is not None else header_reproduces(log, skipped) is not True
    held = check_command_unit(log, skipped, held=True) if named and unit is None else None
    if held is not None and held.claims[0].data != UNKNOWN_UNIT:
        return held  # a hub held still reads v in a unit as named, before a rewrite that would move it
    zeros = check_accel_zero(log, skipped) if named and unit is None else None  # (the header's law only: quick)
    if zeros is not None:
        return Columns(zeros.claims, zeros.log, zeros.identified)
    offset = (check_command_offset(log, skipped) or check_theta_zero(log, skipped)) if named else None
    if offset is not None:  # (past the DAC's range as written: about its zero, in counts)
        return offset
    ref = check_reference_unit(log, skipped, as_named) if as_named is not None and unit is None else None
    if ref is not None:
        return Columns((ref.claim,), ref.log, ref.identified)
    for columns in TRIALS:  # a swap or θ negated beside v in another unit (the swap's v is not in counts)
        trial = rewritten(log, columns)
        if in_counts(np.asarray(trial.data["v"], dtype=float)):
            continue
        sized = check_command_unit(trial, skipped, held=True)  # (a swap may leave the hub still)
        if sized is not None and sized.claims[0].data != UNKNOWN_UNIT:
            return _swapped_back(log, (columns,), sized.log, as_named, "the law reproduces v in counts",
                                 also=sized.claims)
    if unit is not None:
        return unit
    if as_named is None:
        return _inferred_swap(log, skipped)
    trials = []
    for tried in (tuple((c,) for c in TRIALS), PAIRS):  # one fault, else two at once
        exact, missed = [], []  # missed: single rewrites, asked from θ's zero after every one (tied as exact)
        for rewrites in tried:  # the header's law as given
            trial = rewritten_all(log, rewrites)
            pinned = pins_a_law(trial.data["v"])  # a step column for v: any law of high gain at its clamp gives it
            if not pinned and not np.any(trial.data["v"]):  # (every law gives a v of 0 where e is 0)
                continue
            if len(rewrites) > 1 and rewrites[0] == ("u", "v") and not tracks_better(trial, log):
                continue
            dv = header_law_dv(trial, skipped, own_clamp=not pinned)  # (unpinned: the header's law, its clamp)
            if dv is not None and dv <= TOLERANCE:
                exact.append((rewrites, trial, dv))
            elif dv is not None and dv <= NEAR_COUNTS < as_named and pinned:
                trials.append((rewrites, trial))
            elif len(rewrites) == 1:
                missed.append((rewrites, trial))
        if exact:  # a P law of gain 1 gives two: the nominal model's θ tells them apart
            rewrites, trial, dv = min(exact, key=lambda x: _law_miss(x[1], skipped) if len(exact) > 1 else 0.0)
            return _swapped_back(log, rewrites, trial, as_named, f"to {dv:.2g}")
        if trials:
            break
        if zeroed := [(r, z) for r, trial in missed if (z := check_theta_zero(trial, skipped)) is not None]:
            rewrites, zero = min(zeroed, key=lambda x: _law_miss(x[1].log, skipped, x[1].identified)
                                 if len(zeroed) > 1 else 0.0)
            return _swapped_back(log, rewrites, zero.log, as_named, ZEROED_TOO, zero.identified, also=zero.claims)
    if not trials and as_named <= NEAR_COUNTS:  # the header's law within a count as named: no lie about the law
        return Columns((), log)
    if not trials:  # a header that lies about the law too: the data's law, on the rewrites
        return _inferred_swap(log, skipped)
    # completed from the data (printed coefficients, a recursion the printing moves by a count)
    try:
        cid = identify_controller(log, skipped)
    except StationError:  # said where the controller is asked for (LoggedRun.identified)
        return Columns((), log)
    if cid.claim is None or cid.claim.verdict != "contradicted":
        return Columns((), log, cid)
    for rewrites, trial in trials:
        try:
            found = identify_controller(trial, skipped)
        except StationError:
            continue
        if found.claim is not None and found.claim.verdict == "confirmed":
            return _swapped_back(log, rewrites, trial, as_named, f"completed from the data ({found.claim.data})",
                                 found)
    return Columns((), log, cid)


def _inferred_swap(log: RunLog, skipped) -> Columns:
    """A log that names no controller, open loop, or a law that reproduces it on no rewrite (a
    header that lies about the law as well as the columns): when no law reproduces it as its
    columns are named and one does with two of them exchanged or θ negated, that rewrite (the
    law inferred on it; v also read about a DAC code's zero, and θ from its rest count, where that
    law then runs from rest: :func:`check_command_offset`, :func:`check_theta_zero`: three faults
    under an open-loop header). Of several rewrites of as many faults giving a law, the lowest order;
    of those (a P law of gain 1 at alignment 0, v = u − θ, reads the same with θ negated as with v
    and θ exchanged and the gain −1) the one whose θ the nominal model run in closed loop by its law
    gives most closely (:func:`station.logged.rewrite_evidence.model_miss`), then whose θ follows its
    u most closely (:func:`tracking_error`), the first on a tie."""
    try:
        cid = identify_controller(log, skipped)
    except StationError:  # said where the controller is asked for (LoggedRun.identified)
        return Columns((), log)
    # no header, an open-loop one (v = u), or a law the data contradict, and no law found in the data
    if cid.claim is None or not cid.claim.data.endswith(NO_LAW):
        return Columns((), log, cid)
    laws: list[tuple[tuple[tuple[str, ...], ...], RunLog, ControllerId]] = []
    for rewrites in tuple((c,) for c in TRIALS) + (None,) + PAIRS:  # one fault before two
        if laws and (rewrites is None or len(rewrites) > 1):
            break  # one fault gives a law: no two are tried
        if rewrites is None:  # u written in another unit (degrees, radians, milliradians): one fault
            ref = check_reference_unit(log, skipped)
            if ref is not None:
                return Columns((ref.claim,), ref.log, ref.identified)
            continue
        trial = rewritten_all(log, rewrites)
        if not pins_a_law(trial.data["v"]):  # a step as v (u swapped in): a law of the right gain gives any
            continue
        if len(rewrites) > 1 and rewrites[0] == ("u", "v") and not tracks_better(trial, log):
            continue
        # v about a DAC code's zero, or θ from its count, too: that law, from rest
        zero, how = _zero_read(trial, skipped) if len(rewrites) == 1 else (None, "")
        if zero is not None and zero.identified:
            laws.append((rewrites, zero.log, zero.identified, zero.claims, how))
            continue
        try:
            found = identify_controller(trial, skipped)
        except StationError:
            continue
        if found.controller is not None and found.fit is not None and (
                found.source in ("inferred", "inferred (header contradicted)")
                or (found.source == "header" and is_closed_loop(found.controller)  # its corrupted fields set aside
                    and found.claim is not None and found.claim.verdict == "confirmed")):
            laws.append((rewrites, trial, found, (), ""))
    if not laws:
        return Columns((), log, cid)
    low = min(_order(x[2].controller) for x in laws)
    laws = [x for x in laws if _order(x[2].controller) == low]
    rewrites, trial, found, also, how = min(laws, key=lambda x: (_law_miss(x[1], skipped, x[2]) if len(laws) > 1
                                                                 else 0.0, tracking_error(x[1])))
    return _swapped_back(log, rewrites, trial, None, how or f"{found.claim.data}", found, also=also)


def _zero_read(trial: RunLog, skipped) -> tuple[Columns | None, str]:
    """A rewrite's column zero and how its claim says so: v about a DAC code's zero (θ's with it
    where both are: :func:`check_command_offset`, whose claims then follow) else θ from its rest
    count (:func:`check_theta_zero`); (None, "") when neither."""
    if (zero := check_command_offset(trial, skipped)) is not None:
        return zero, READ_AS_SAID
    if (zero := check_theta_zero(trial, skipped)) is not None:
        return zero, ZEROED_TOO
    return None, ""


def _law_miss(trial: RunLog, skipped, found: ControllerId | None = None) -> float:
    """:func:`station.logged.rewrite_evidence.model_miss` of a rewrite, closed by its law."""
    if found is None:
        try:
            found = identify_controller(trial, skipped)
        except StationError:
            return np.inf
    alignment = found.fit.alignment if found.fit is not None else None
    return model_miss(trial, found.controller, alignment)


def _order(controller) -> int:
    """A law's order: its Gth's poles and, with accelerometer feedback, Ga's (0 for P)."""
    return sum(len(tf.den) - 1 for tf in (getattr(controller, "gth", None), getattr(controller, "ga", None))
               if tf is not None)


def named_by(log: RunLog) -> str:
    """What names the columns, as a swap's header says it.

    Parameters
    ----------
    log : RunLog

    Returns
    -------
    str
        The file's column line, or the rig's order assumed for rows saved without a header
        (:data:`station.runlog.rig_layouts.BARE_ORDER`).
    """
    return "in the rig's column order (no header names them)" if log.layout == "bare" else \
        "as the column line names them"


def _swapped_back(log: RunLog, rewrites: tuple[tuple[str, ...], ...], trial: RunLog, as_named: float | None,
                  how: str, identified: ControllerId | None = None, also: tuple[AuditClaim, ...] = ()) -> Columns:
    """The rewritten log (``trial``: ``log`` with ``rewrites`` applied, :func:`rewritten_all`)
    with one contradicted "columns" claim and note per rewrite, ``also``'s claims after them."""
    said = ("no law reproduces v as the columns are named" if as_named is None else
            f"the header's law replays v to max |dv| = {as_named:.3g} counts as the columns are named")
    done = " and ".join(f"the columns named {SHOWN[c[0]]} and {SHOWN[c[1]]} exchanged" if len(c) == 2 else
                        f"{SHOWN[c[0]]} negated" for c in rewrites)
    claims, notes = [], []
    for columns in rewrites:
        if len(columns) == 2:
            a, b = SHOWN[columns[0]], SHOWN[columns[1]]
            claims.append(AuditClaim("columns", f"{a} and {b} {named_by(log)}", f"{a} and {b} swapped",
                                     "contradicted", f"{said}, and {how} with {done}"))
            notes.append(f"the columns named {a} and {b} hold {b} and {a} (the audit): read swapped")
        else:
            a = SHOWN[columns[0]]
            claims.append(AuditClaim("columns", f"{a} with the sign the loop fed back", f"{a} written with the other sign",
                                     "contradicted", f"{said}, and {how} with {done}: the column holds -{a}"))
            notes.append(f"the column named {a} holds -{a} (the audit): read negated")
    return Columns(tuple(claims) + tuple(also), dataclasses.replace(trial, notes=list(trial.notes) + notes), identified)


def check_command_unit(log: RunLog, skipped=None, held: bool = False) -> Columns | None:
    """The command's unit (DAC counts) checked by the header's law and the DAC's range
    (module docstring).

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.
    held : bool, optional
        Also read a v under one count everywhere where the hub held still (the device applying 0
        would leave it so; asked where the law does not reproduce v as written, before a rewrite
        of the columns that would move it: :func:`check_columns`).

    Returns
    -------
    Columns or None
        When v as written is no DAC command (under one count everywhere while the hub moved,
        or past the DAC's ±255) and no law named reproduces it as written: the log with v (and
        u, where it steps by the same size: an open-loop run's command) in counts and a
        contradicted "columns" claim, when v steps by another size than a count and the
        header's law (with none named or an open-loop one, the law the data give) reproduces
        it in counts; else the log as it is with the claim that v is in a unit the data do
        not give (:func:`_unknown_unit`). None when v is in counts or could be a command.
    """
    v = np.asarray(log.data["v"], dtype=float)
    if in_counts(v) or not np.all(np.isfinite(v)):
        return None
    pinned = pins_a_law(v)  # else only 0 and ±peak: any law at a clamp of its peak gives it, in any unit
    dv = header_law_dv(log, skipped, own_clamp=not pinned)  # replayed once; None: open loop or none named
    stated = dv <= TOLERANCE if dv is not None else header_reproduces(log, skipped)
    if stated is True:
        return None
    peak = float(np.max(np.abs(v)))
    if 0 < np.count_nonzero(np.abs(v) > DAC_LIMIT) <= most_glitches(v.size):
        return None  # a field or two past the DAC's range is corrupted, not in a unit: the controller's audit says
    small = no_dac_command(v, log.data["theta"])
    if small:
        why = f"as written v stays under one DAC count (|v| ≤ {peak:.3g}: the device would apply 0) while the hub moved"
    elif held and peak < 1.0 and np.any(v != 0):
        small, why = True, f"as written v stays under one DAC count (|v| ≤ {peak:.3g}) where the hub held still"
    elif peak > DAC_LIMIT:
        why = f"as written v reaches {peak:.4g}, past the DAC's ±{DAC_LIMIT:g} counts"
    else:  # as written v could be a command too: another gain of the law as much as another unit
        return None
    least = count_step(v)
    scaled = _float_scale(log, skipped) if least is None else None
    if least is None and scaled is None:  # no size to read it in
        return _unknown_unit(log, why, "its changes are no whole multiples of one size (a float, or printed to few "
                                       "digits)", small)
    u = np.asarray(log.data["u"], dtype=float)
    u_least = None if in_counts(u) else count_step(u)
    steps = [scaled.ratio] if least is None else [least / k for k in range(1, COMMAND_STEP_COUNTS + 1)]  # kp·e
    commanded = np.isfinite(u) & (u != 0)
    if not pinned and dv is not None:  # a named law's gain and v's unit are one: a converter's count only
        steps = [q for q in CONVERTER_VOLTS if quantum_fits(v, q)]
    elif least is not None and u_least is None and np.any(commanded):  # open loop: u in counts, v in another unit
        steps.append(float(np.median(v[commanded] / u[commanded])))
    found = None  # the header's closed-loop law at any step, else the data's at the largest
    for step in filter(lambda x: x > 0, steps):
        data = dict(log.data)
        data["v"] = scaled.v if least is None else whole_counts(v / step)
        also = u_least is not None and quantum_fits(np.array([u_least / step]), 1.0)
        if also:
            data["u"] = whole_counts(u / step)
        trial, zero = dataclasses.replace(log, data=data), None
        whose = law_confirms(trial, skipped)
        if whose != "header" and (zero := check_theta_zero(trial, skipped)) is not None:  # θ from its zero too
            whose, trial = "data" if zero.identified is not None else "header", zero.log
        if not pinned and dv is not None and not (whose == "header" and _at_own_clamp(trial, skipped)):
            continue  # an unpinned v is read only by a named law at its own clamp
        if whose is not None and (found is None or whose == "header"):
            found = step, trial, also, whose, zero
        if found is not None and (dv is None or found[3] == "header"):
            break
    if found is not None:
        step, trial, also, whose, zero = found
        both = "v and u" if also else "v"
        header = ("the log names no law" if stated is None else
                  "the header's open loop (v = u) reproduces neither" if dv is None else "the header's law reproduces neither")
        law = (f"the header's law does not reproduce v as written and reproduces it in counts (÷ {step:.6g})"
               if dv is not None and whose == "header" else
               f"{header}, and the law the data give reproduces v in counts (÷ {step:.6g}; with no law named, its "
               f"gain and v's unit are one: gain k·g on steps of {step:.6g}/k gives the same v, and the largest step "
               f"is taken)") + (f", {ZEROED_TOO}" if zero is not None else "")
        sized = (f"every change of v is a whole multiple of {step:.6g}, not of one count" if least is not None else
                 f"v is a float, {step:.6g} times the header's law replayed on its own commands to its printing")
        sizes = "units" if least is None else "steps"
        claim = AuditClaim("columns", "v in DAC counts", f"{both} in {sizes} of {step:.6g}", "contradicted",
                           f"{sized}; {law}, and {why}: a command written in another unit")
        note = f"{both} in {sizes} of {step:.6g} a DAC count (the audit): divided by it"
        zeroed = zero.claims if zero is not None else ()
        return Columns((claim, *zeroed), dataclasses.replace(trial, notes=list(trial.notes) + [note]),
                       zero.identified if zero is not None else None)
    said = (f"its changes are whole multiples of {least:.6g}, but no law reproduces it in counts of that size or "
            f"of its fractions" if least is not None else f"it is {scaled.ratio:.6g} times the header's law replayed "
            f"on its own commands, but no law reproduces it so read in counts")
    return _unknown_unit(log, why, said, small)


def _at_own_clamp(trial: RunLog, skipped) -> bool:
    """Whether the header's law reproduces a rewrite at its own clamp (not at v's peak)."""
    dv = header_law_dv(trial, skipped, own_clamp=True)
    return dv is not None and dv <= TOLERANCE


def _rewritten_at_own_clamp(log: RunLog, skipped) -> Columns | None:
    """A v of 0 and one level that the header's law gives as named only at a clamp of its peak
    (as any law of high gain does) and at its own clamp on one rewrite (:data:`TRIALS`): that
    rewrite (u and v swapped on a P step the hub never followed: v is then the step, u is kp·u).
    None where v pins a law or the law reproduces it at its own clamp as named."""
    own = None if pins_a_law(log.data["v"]) else header_law_dv(log, skipped, own_clamp=True)
    if own is None or own <= TOLERANCE:
        return None
    for columns in TRIALS:
        trial = rewritten(log, columns)
        if np.any(trial.data["v"]) and _at_own_clamp(trial, skipped):  # (a v of 0: any law where e is 0)
            return _swapped_back(log, (columns,), trial, own, "to 0 counts at its own clamp (not only at v's peak)")
    return None


def _float_scale(log: RunLog, skipped) -> Scaled | None:
    """A float command's size by the header's law replayed (:func:`law_scale`), from θ's zero
    too (:func:`theta_from_zero`): θ's zero is asked of the command in counts after."""
    found = law_scale(log, skipped)
    zeroed = theta_from_zero(log) if found is None else None
    return law_scale(zeroed, skipped) if zeroed is not None else found


def _unknown_unit(log: RunLog, why: str, detail: str, small: bool) -> Columns:
    """A v that is no DAC command as written, in a unit the data do not give: said, and the log
    as it is (a v under one count gets no law inferred on it:
    :func:`station.analysis.law_rows.no_dac_command`)."""
    then = ("no law is inferred on it, and the model is driven by v as written" if small else
            "it is read as written")
    claim = AuditClaim("columns", "v in DAC counts", UNKNOWN_UNIT, "contradicted",
                       f"{why}: a command written in another unit; {detail}; {then}")
    note = f"v is in another unit than DAC counts, its size not found (the audit): {then}"
    return Columns((claim,), dataclasses.replace(log, notes=list(log.notes) + [note]))


