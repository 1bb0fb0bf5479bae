"""Where a column's zero is, and whose law says so: the results every column check returns.

A command written about another zero (an unsigned DAC code about its midpoint) reads one value
other than 0 at rest, and the log's law reproduces every v less it (:func:`check_command_offset`);
an angle logged as the encoder read it, by a loop that took its count at START off (the lab's
client reads θ0 at ``q``), rests on θ0 and its law reproduces v from θ − θ0
(:func:`check_theta_zero`). The law is the header's where it holds, else the one the data give
(:func:`law_confirms`). :mod:`station.logged.columns` asks these of a log as written and of each
rewrite of its columns or its command's unit, so that two faults at once are read too.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from station.analysis.law_rows import TOLERANCE, pins_a_law
from station.errors import StationError
from station.logged.audit import AuditClaim
from station.logged.controller import (ControllerId, describe_controller, header_law_dv, header_reproduces,
                                       identify_controller)
from station.logged.missing_ticks import GAP_LAW_ROWS
from station.logged.reference_unit import exact_from_rest
from station.logged.sensor_zeros import theta_zero_claim
from station.logged.start import REST_ROWS, rest_rows
from station.runlog import RunLog


ZEROED_TOO = "with θ's zero taken off as well (the next claim)"
"""How a rewrite's claim says that θ was also logged before its zero was taken off (:func:`check_theta_zero`)."""


class Columns(NamedTuple):
    """The column claim of a log and the log its data say it is
    (:func:`station.logged.columns.check_columns`).

    Attributes
    ----------
    claims : tuple of AuditClaim
        One contradicted "columns" claim when two columns were found swapped, else empty.
    log : RunLog
        The log itself, or a copy with the two columns swapped back and a note.
    identified : ControllerId or None
        The log's controller (:func:`station.logged.controller.identify_controller`) when
        deciding needed it, else None.
    """

    claims: tuple[AuditClaim, ...]
    log: RunLog
    identified: ControllerId | None = None


def check_command_offset(log: RunLog, skipped=None) -> Columns | None:
    """The command's zero checked by its rest and the log's law: a v that reads one value c
    other than 0 before the first command (u and θ unchanged: no law commands anything there but
    an accelerometer feedback on a's noise; c is v's first row or its median there, whole) and
    whose every row less c the header's law reproduces (a closed loop's, or an open loop's
    v = u; with no law named, or an open loop the data contradict, the law the data give, from
    rest, where v as written has none or one only with its first rows of memory as logged) was
    written about another zero (an unsigned DAC code about its midpoint, 128 of 8 bits). Where
    that law reproduces v less c only from θ's zero too (:func:`check_theta_zero`: a script that
    wrote the device's raw words), both are read.

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    Columns or None
        The log with c taken off v and a contradicted "columns" claim; None otherwise (fewer
        than :data:`REST_ROWS` rows at rest, v 0 there, or no law reproduces v less c).
    """
    u, theta, v = (np.asarray(log.data[c], dtype=float) for c in ("u", "theta", "v"))
    rest = rest_rows(u, theta)
    if rest < REST_ROWS or u[0] != 0 or not np.all(np.isfinite(v[:rest])):
        return None
    # one whole value at rest (a DAC code); a law feeding a back moves v about it by a's noise there (Ga)
    zeros = {float(z) for z in (v[0], np.round(np.median(v[:rest]))) if z == np.round(z)} - {0.0}
    for c in sorted(zeros, key=lambda z: abs(z - v[0])):
        found = _offset_taken_off(log, skipped, v, c, rest)
        if found is not None:
            return found
    return None


def _law_dv(trial: RunLog, skipped) -> float | None:
    """The header's law's max |dv| on a zero's trial (None: an open-loop header's v = u, or none
    named); a v of 0 and one level only at the law's own clamp (any law gives it at its peak)."""
    return header_law_dv(trial, skipped, own_clamp=not pins_a_law(trial.data["v"]))


def _offset_taken_off(log: RunLog, skipped, v: np.ndarray, c: float, rest: int) -> Columns | None:
    """:func:`check_command_offset` for one zero c."""
    trial = dataclasses.replace(log, data={**log.data, "v": v - c})
    dv = _law_dv(trial, skipped)
    whose, found, zero = "the header's law", None, None
    named = header_holds(trial, dv, skipped)
    if not named and dv is not None and law_confirms(trial, skipped) == "header":  # printed coefficients completed
        whose, dv = "the header's law (its printed coefficients completed from the data)", None
    elif not named:  # none named, an open loop's v = u contradicted, or a header lying about the law too
        zeroed = theta_from_zero(trial) if dv is not None else None  # the header's law from θ's zero, first
        header_zero = zeroed is not None and header_holds(zeroed, _law_dv(zeroed, skipped), skipped)
        found = None if header_zero else _data_law_from_rest(log, trial, skipped)
        zero = (check_theta_zero(trial, skipped) if header_zero else
                None if found is not None or _law_as_written(log, skipped) else check_theta_zero(trial, skipped))
        if found is None and zero is None:
            return None
        if zero is not None:  # θ from its zero as well: two faults of a script that wrote the device's raw words
            found, trial, dv = zero.identified, zero.log, None
            law = ("the header's law" if found is None else
                   f"the law the data give ({describe_controller(found.controller)})")
            whose = f"{law}, {ZEROED_TOO},"
        else:
            whose, dv = f"the law the data give ({describe_controller(found.controller)})", float(found.fit.max_abs_dv)
    within = "" if dv is None else f" (to {dv:.2g} counts)"
    claim = AuditClaim(
        "columns", "v in DAC counts about 0", f"v about {c:g} counts", "contradicted",
        f"v reads {c:g} on the {rest} rows at rest before the first command (u and θ unchanged: no law commands "
        f"anything there but a's noise), and {whose} reproduces every logged v less {c:g}{within}: a "
        f"command written about another zero (an unsigned DAC code about its midpoint)")
    note = f"v about {c:g} counts (the audit): {c:g} taken off"
    zeroed = zero.claims if zero is not None else ()
    return Columns((claim, *zeroed), dataclasses.replace(trial, notes=list(trial.notes) + [note]), found)


def check_theta_zero(log: RunLog, skipped=None) -> Columns | None:
    """θ's zero checked by its rest and the log's law: a θ that rests on one count θ0 other
    than 0 before the first command, where the law (the header's closed-loop law, else the data's
    from rest, as :func:`check_command_offset` asks it, a header that lies about the law too)
    reproduces every logged v from θ − θ0 and not from θ as written, was logged before the
    script took its zero off (the lab's client reads θ0 at START, ``q``, and the loop's error is
    u − (θ − θ0)); read from θ0. A law that reproduces θ as written is the encoder not zeroed
    (:func:`station.logged.start.start_claims`).

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    Columns or None
        The log with θ0 taken off θ and a contradicted "columns" claim; None otherwise (θ not
        in whole counts, fewer than :data:`REST_ROWS` rows at rest, or no law from θ − θ0).
    """
    trial = theta_from_zero(log)
    if trial is None:
        return None
    th0, rest = float(log.data["theta"][0]), rest_rows(log.data["u"], log.data["theta"])
    dv = _law_dv(trial, skipped)
    whose, found = "the header's law", None
    if dv is None or dv > TOLERANCE:  # none named, an open loop's v = u, or a header lying about the law too
        found = _data_law_from_rest(log, trial, skipped)
        if found is None:
            return None
        whose, dv = f"the law the data give ({describe_controller(found.controller)})", float(found.fit.max_abs_dv)
    claim, note = theta_zero_claim(th0, rest, whose, dv)
    return Columns((claim,), dataclasses.replace(trial, notes=list(log.notes) + [note]), found)


def theta_from_zero(log: RunLog) -> RunLog | None:
    """``log`` with θ's first count θ0 taken off, where θ rests on θ0 other than 0 before the first command.

    Parameters
    ----------
    log : RunLog

    Returns
    -------
    RunLog or None
        A copy with θ − θ0; None when θ starts at 0, is not in whole counts (a law on the
        truncated integer may fit θ's fractions from any zero), or rests on fewer than
        :data:`station.logged.start.REST_ROWS` rows with u at 0 (:func:`check_theta_zero` asks
        whether the log's law holds so).
    """
    u, theta = (np.asarray(log.data[c], dtype=float) for c in ("u", "theta"))
    th0 = float(theta[0])
    if th0 == 0 or not np.isfinite(th0) or u[0] != 0 or rest_rows(u, theta) < REST_ROWS:
        return None
    if not np.all(theta == np.round(theta)):
        return None
    return dataclasses.replace(log, data={**log.data, "theta": theta - th0})


def _data_law_from_rest(log: RunLog, trial: RunLog, skipped) -> ControllerId | None:
    """With no law named (or an open loop's v = u the data contradict, less c as well): the law
    the data give reproducing ``trial`` (v less its rest value, or θ less its first count)
    from rest, where on ``log`` as written none does, or one does only with its first rows of
    memory taken as logged (an integrator carrying the rest value: a copy "cut from a longer
    run" whose hub rested under a command of many counts); that law (kept: the log's controller,
    not identified twice), or None.
    A law from rest on u and θ of 0 gives 0 there, so v as written, c there, needs no search."""
    try:
        found = identify_controller(trial, skipped)
        if not exact_from_rest(found):
            return None
        if log.data["theta"][0] != 0 and _law_as_written(log, skipped):  # a P law's -kp·θ at rest is one value too
            return None
    except StationError:
        return None
    return found


def _law_as_written(log: RunLog, skipped) -> bool:
    """Whether the law the data give reproduces ``log`` as written, its memory from rest."""
    try:
        found = identify_controller(log, skipped)
    except StationError:
        return False
    return found.fit is not None and found.fit.max_abs_dv <= TOLERANCE and not found.cut


def header_holds(log: RunLog, dv: float | None, skipped) -> bool:
    """Whether the header's law holds as given.

    Parameters
    ----------
    log : RunLog
    dv : float or None
        The header's law replayed once (:func:`station.logged.controller.header_law_dv`), max
        |dv| in DAC counts; None for an open-loop header (v = u) or none named.
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.
    """
    return dv <= TOLERANCE if dv is not None else header_reproduces(log, skipped) is True


def law_confirms(log: RunLog, skipped) -> str | None:
    """Whose law reproduces every logged v.

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    str or None
        "header" where the header's law does (as given, v = u in open loop, past a few
        corrupted fields, or within :data:`station.analysis.header_law.NEAR_COUNTS` with its
        printed coefficients completed from the data); "data" where a law the data give does
        (none named, an open-loop header's v = u contradicted, or a closed-loop header lying
        about the law too); else None.
    """
    dv = header_law_dv(log, skipped)  # replayed once; None for an open-loop header (v = u) or none
    if header_holds(log, dv, skipped):
        return "header"
    try:
        found = identify_controller(log, skipped)
    except StationError:
        return None
    if found.fit is None or found.fit.max_abs_dv > TOLERANCE or found.judged_to is not None and (
            found.judged_to == 0 or found.source != "header" and found.judged_to < GAP_LAW_ROWS):
        return None  # judged on the rows before n jumps: a law the data give, on enough of them
    return "header" if found.source == "header" and dv is not None else "data"
