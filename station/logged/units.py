"""The log audit's sample time and column units: the claims a log's numbers make by their
form (DESIGN.md "Log audit": the sample time, the columns' units).

A log claims its sample time (our header's dt, else the rig's 0.002 s with t in s) and that
its columns hold counts: θ whole encoder counts, u, v, a and θ̂d signed counts. The data
contradict the first when t steps by another time (or by ms), θ's unit when its values are
whole multiples of a radian's or a degree's share of one count, a's unit when it steps by whole
multiples of another size than one count (a's reading scaled into g, m/s² or volts), and a
column's sign when it holds the rig's 16-bit two's-complement words (the legacy protocol's,
``../shared/spec/protocol.md``) read as unsigned: a negative x written as 65536 + x. Each
contradiction is converted, and said. (The command's unit needs its law: a float P law's v
steps by kp; :mod:`station.logged.columns` decides it.)
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from station.analysis.glitches import most_glitches
from station.logged.audit import AuditClaim
from station.logged.quantum import QUANTUM_TOLERANCE, count_step, in_counts, quantum_fits, quantum_fits_each
from station.rig import COUNTS_PER_REV, DT
from station.runlog import RunLog
from station.runlog.timebase import WORD

THETA_UNITS = {"milliradians": 2000.0 * math.pi / COUNTS_PER_REV, "degrees": 360.0 / COUNTS_PER_REV,
               "radians": 2.0 * math.pi / COUNTS_PER_REV}
"""θ columns in another unit than counts, by one encoder count in that unit, the coarsest first
(a θ in milliradians is whole multiples of a radian's count too)."""

PRINTED_COUNTS = 0.01
"""A column within this of whole counts in every row, once in counts, is whole counts printed in
another unit (17.5781 degrees: 49.99994 counts), read back as those counts."""


def counts_of(x, quantum: float) -> np.ndarray:
    """A column written in another unit, in counts: ``x / quantum``, rounded where every row is
    within :data:`PRINTED_COUNTS` of whole counts (a step's 50 counts printed in milliradians).

    Parameters
    ----------
    x : array_like, shape (N,)
        The column as written.
    quantum : float
        One count in its unit (:data:`THETA_UNITS`).

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    counts = np.asarray(x, dtype=float) / quantum
    whole = np.round(counts)
    return whole if counts.size and np.max(np.abs(counts - whole)) <= PRINTED_COUNTS else counts


@dataclass(frozen=True)
class TimeBase:
    """The sample-time and column-unit claims of a log and the log its data say it is
    (:func:`time_base`).

    Attributes
    ----------
    claims : tuple of AuditClaim
    log : RunLog
        The log itself when every claim holds or is unchecked; else a copy with the data's
        answer (t in s, θ and u in encoder counts, signed counts, the header's dt replaced)
        and a note.
    """

    claims: tuple[AuditClaim, ...]
    log: RunLog


def _whole(x: np.ndarray) -> bool:
    return bool(np.all(x == np.round(x)))


WORD_COLUMNS = {"u": "u", "v": "v", "theta": "θ", "a": "a", "theta_d_hat": "θ̂d"}
"""Columns of signed counts that a client may have read as unsigned words, by their printed name."""


def unsigned_words(x) -> bool:
    """Whether a column of signed counts holds 16-bit two's-complement words read as unsigned.

    Decided from the numbers alone: every value a whole count in [0, 65536), some at or above
    32768, and read as two's complement (x − 65536 for x ≥ 32768) the column is at most half
    as large and no less continuous (its largest step between rows no larger). A signal near
    zero that goes negative comes back (64, 65472 → 64, −64); an unsigned channel centred on
    32768 does not (its signed reading jumps by 65535 where it crosses the middle).

    Parameters
    ----------
    x : array_like, shape (N,)
        One column, counts.

    Returns
    -------
    bool
    """
    x = np.asarray(x, dtype=float)
    if x.size == 0 or not np.all(np.isfinite(x)) or not _whole(x):
        return False
    high = x >= WORD // 2
    if not np.any(high) or np.min(x) < 0 or np.max(x) >= WORD:
        return False
    signed = np.where(high, x - WORD, x)
    if np.max(np.abs(signed)) > 0.5 * np.max(np.abs(x)):
        return False
    return x.size < 2 or np.max(np.abs(np.diff(signed))) <= np.max(np.abs(np.diff(x)))


def word_claims(data: dict[str, np.ndarray]) -> tuple[list[AuditClaim], dict[str, np.ndarray]]:
    """The columns of ``data`` that hold 16-bit words read as unsigned (:func:`unsigned_words`),
    each a contradicted "columns" claim, and the columns read as two's complement.

    Parameters
    ----------
    data : dict of str to ndarray
        A log's columns (:attr:`station.runlog.RunLog.data`).

    Returns
    -------
    claims : list of AuditClaim
    signed : dict of str to ndarray
        The converted columns, by name.
    """
    claims: list[AuditClaim] = []
    signed: dict[str, np.ndarray] = {}
    for name, shown in WORD_COLUMNS.items():
        if name not in data or not unsigned_words(data[name]):
            continue
        x = np.asarray(data[name], dtype=float)
        high = x >= WORD // 2
        signed[name] = np.where(high, x - WORD, x)
        claims.append(AuditClaim(
            "columns", f"{shown} in signed counts", f"{shown} as unsigned 16-bit words", "contradicted",
            f"{int(np.count_nonzero(high))} of its {x.size} values are {int(np.min(x[high]))}..{int(np.max(x[high]))}; "
            f"read as two's complement (x - {WORD}) the column is {int(np.min(signed[name]))}.."
            f"{int(np.max(signed[name]))} counts, no less continuous"))
    return claims, signed


ACCEL_UNIT_CLAIM = "a in accelerometer counts"
"""What every log's a column claims about its unit (the header of :func:`accel_unit`'s claim)."""


class AccelUnit(NamedTuple):
    """a's unit as its data give it (:func:`accel_unit`).

    Attributes
    ----------
    claim : AuditClaim
    counts : ndarray or None
        a in counts, shape (N,), when a count's size was found; else None.
    step : float or None
        That size, in a's unit.
    """

    claim: AuditClaim
    counts: np.ndarray | None
    step: float | None


def accel_unit(a) -> AccelUnit | None:
    """a's claim to be in accelerometer counts (the rig's 16-bit readings, steps of whole
    counts), checked by the size of its steps (:func:`count_step`).

    Parameters
    ----------
    a : array_like, shape (N,)

    Returns
    -------
    AccelUnit or None
        None when a steps by whole counts (or never changes). Otherwise a contradicted claim
        and a in counts (a divided by its step) when a steps by another size, or an unchecked
        claim when its steps have no common size: its scale is then the accelerometer's gain,
        decided against the model (:mod:`station.logged.sensors`).
    """
    a = np.asarray(a, dtype=float)
    if in_counts(a):
        return None
    step = count_step(a, 2 * most_glitches(a.size))  # a corrupted field or two: the law finds them
    if step is None:
        changes = np.abs(np.diff(a))
        return AccelUnit(AuditClaim(
            "columns", ACCEL_UNIT_CLAIM, "a not in whole counts", "unchecked",
            f"a changes by amounts with no common size (e.g. {changes[changes > 0][0]:.6g}): a count's size is "
            f"not decided; its scale is the accelerometer's gain"), None, None)
    return AccelUnit(AuditClaim(
        "columns", ACCEL_UNIT_CLAIM, f"a in steps of {step:.6g}", "contradicted",
        f"every change of a is a whole multiple of {step:.6g}, not of one count: a count read in another unit "
        f"({1.0 / step:.6g} counts per unit)"), whole_counts(a / step), step)


def whole_counts(x: np.ndarray) -> np.ndarray:
    """``x`` (counts read back from another unit, off whole by the printing's last digits) on
    whole counts about its common offset (the thesis's lead + accelerometer log's a: 0.04).

    Parameters
    ----------
    x : ndarray, shape (N,)

    Returns
    -------
    ndarray, shape (N,)
    """
    offset = float(np.median(x - np.round(x)))
    if abs(offset) <= QUANTUM_TOLERANCE:  # the printing's last digits, not an offset
        offset = 0.0
    return np.round(x - offset) + offset


def replayable_rate(log: RunLog) -> bool:
    """Whether a log's commands can be replayed at its own sample time: ours (the header's dt),
    a rig log at the rig's 0.002 s, or a rig log at another rate whose n column counts every
    tick (a loop run at that rate: its law replayed there); not a rig log at another rate with
    n jumping or derived from t (rows kept from a 500 Hz loop: a law with memory ran on rows
    the log lacks).

    Parameters
    ----------
    log : RunLog
    """
    if log.format != "rig" or abs(log.dt - DT) <= 1e-9:
        return True
    n = np.asarray(log.data["n"], dtype=float)
    own_n = not any("no sample column" in note for note in log.notes)
    return own_n and n.size > 1 and bool(np.all(np.isfinite(n))) and bool(np.all(np.diff(n) == 1))


HOST_STAMP_TOLERANCE = 0.005
"""How near a log's t must come, over the whole run, to one claimed sample time a row for its
jittered steps to be a host's time stamps of the rig's ticks (0.5 %: a 4 s run ends within
20 ms of 2000 ticks)."""


def _host_stamps(t: np.ndarray, claimed: float) -> float | None:
    """t's mean step over the run when t is a host's time stamps of ticks ``claimed`` s apart:
    its steps jitter (by more than 1 % of a tick; each within half a tick of ``claimed``: no
    row missing or repeated) and its mean is ``claimed`` to :data:`HOST_STAMP_TOLERANCE`;
    else None (an even clock at another rate is that rate)."""
    steps = np.diff(t)
    mean = (t[-1] - t[0]) / (t.size - 1)
    jitter = np.max(np.abs(steps - np.median(steps))) > 0.01 * claimed  # an even clock at another rate is that rate
    whole = np.all(np.abs(steps - claimed) < 0.5 * claimed)
    return float(mean) if jitter and whole and abs(mean / claimed - 1.0) <= HOST_STAMP_TOLERANCE else None


def _in_unit(u: np.ndarray, theta_counts: np.ndarray, q: float) -> bool:
    """Whether a reference u that is not whole counts is in θ's unit ``q`` rather than in
    counts: its span so converted is nearer θ's in counts (θ follows u in a closed loop; a
    command written in u's place, such as a lead's float v, is in counts already)."""
    su, st = float(np.ptp(u)), float(np.ptp(theta_counts))
    if su == 0.0 or st == 0.0:
        return True
    return abs(math.log(su / q / st)) < abs(math.log(su / st))


MIN_RUN_ROWS = 10
"""Fewest rows after n starts again for them to be taken as another run written after the first."""


def run_starts(log: RunLog) -> tuple[int, ...]:
    """The rows where a file's n (and t) start again at its first row's: runs written one
    after another into one file (a logger that appended), each at least :data:`MIN_RUN_ROWS`
    long and going over ticks before it for at least half its rows; () for one run (a block of
    rows written again goes back less far, or, at the start, goes on to new ticks after it).

    Parameters
    ----------
    log : RunLog
    """
    n, t = (np.asarray(log.data[c], dtype=float) for c in ("n", "t"))
    if n.size < 2 * MIN_RUN_ROWS or not np.all(np.isfinite(n)):
        return ()
    back = np.flatnonzero((np.diff(n) < 0) & (n[1:] <= n[0]))
    if np.all(np.isfinite(t)):
        back = back[t[back + 1] <= t[0] + 0.5 * (log.dt or DT)]
    starts = [int(k) + 1 for k in back]
    # another run goes over the ticks before it again for most of its length; a block written
    # again at the start goes over a few, then on to new ticks
    return tuple(k for k, end in zip(starts, starts[1:] + [n.size])
                 if end - k >= MIN_RUN_ROWS and np.count_nonzero(n[k:end] <= np.max(n[:k])) >= 0.5 * (end - k))


def first_run(log: RunLog) -> tuple[AuditClaim | None, RunLog]:
    """A file of runs written one after another (:func:`run_starts`) read as its first, and the
    contradicted claim that says so; the log itself and None for one run.

    Parameters
    ----------
    log : RunLog
    """
    starts = run_starts(log)
    if not starts:
        return None, log
    k = starts[0]
    claim = AuditClaim("sample_time", "one run", f"{len(starts) + 1} runs (n starts again at row "
                       f"{', '.join(str(r) for r in starts)})", "contradicted",
                       f"n and t go back to the first row's: runs written one after another into one file; the first "
                       f"(rows 0-{k - 1}) is used, the others are not (split the file to use them)")
    notes = [x for x in log.notes if not x.startswith("t is not evenly spaced")]
    notes.append(f"the file holds {len(starts) + 1} runs (the audit): the first, rows 0-{k - 1}, used")
    return claim, dataclasses.replace(log, data={c: x[:k] for c, x in log.data.items()}, notes=notes)


SAMPLE_TIMES = (1e-5, 0.1)
"""Sample times a log's t may step by, s: from a 100 kHz loop to 10 Hz (the beam's first mode,
2.5 Hz, needs faster). Outside, t is no time base and the claimed one is used."""


def _ticks_times(log: RunLog, dt: float) -> dict[str, np.ndarray]:
    """n (the sample column, or the rows' index where the log has none) and t = dt·(n − n[0])."""
    n = np.asarray(log.data["n"], dtype=float)
    if any("no sample column" in x for x in log.notes) or not (n.size and np.all(np.isfinite(n))):
        n = np.arange(len(log), dtype=float)
    return {"n": n, "t": (n - n[0]) * dt}


def time_base(log: RunLog) -> TimeBase:
    """Check a log's sample time (our header's ``dt``, else the rig's 0.002 s with t in s)
    against its t column, its θ column's unit (encoder counts) against θ's quantization, and
    every column of signed counts against 16-bit words read as unsigned (:func:`word_claims`).

    Parameters
    ----------
    log : RunLog

    Returns
    -------
    TimeBase
        A t column in ms (steps 1000 times the claimed sample time) and a θ column in
        milliradians, degrees or radians (multiples of one encoder count in that unit, not whole) and a
        column of unsigned 16-bit words (:func:`unsigned_words`) are contradicted and
        converted; a header dt the t column contradicts is replaced by t's.
    """
    claims: list[AuditClaim] = []
    runs, log = first_run(log)
    claims += [runs] if runs is not None else []
    data = log.data
    changes: dict[str, np.ndarray] = {}
    meta = log.meta
    notes: list[str] = []
    sample_time = log.sample_time
    header_dt = meta.get("dt") if log.format == "station" else None
    stated = header_dt if isinstance(header_dt, (int, float)) and not isinstance(header_dt, bool) else None
    claimed = float(stated) if stated is not None else DT
    where = f"dt = {claimed:g} s" if stated is not None else f"not stated (the rig's {claimed:g} s assumed, t in s)"
    t = np.asarray(data["t"], dtype=float)
    no_t = any("no time column" in n for n in log.notes)
    has_t = sample_time is not None and not no_t
    new_meta = None
    if not has_t and not no_t and t.size > 1 and np.all(np.isfinite(t)):  # a t that does not increase
        back = int(np.flatnonzero(np.diff(t) <= 0)[0]) + 1
        claims.append(AuditClaim("sample_time", where, "t does not increase", "contradicted",
                                 f"t goes from {t[back - 1]:.6g} to {t[back]:.6g} s at row {back} and increases on "
                                 f"{np.count_nonzero(np.diff(t) > 0)} of {t.size - 1} rows: no time base; "
                                 f"{claimed:g} s a tick is used"))
        changes.update(_ticks_times(log, claimed))
        sample_time = claimed
        notes.append(f"t does not increase (the audit): {claimed:g} s a tick used, t = {claimed:g}·(n - n[0])")
    if has_t:
        steps = np.diff(t)
        spread = f"steps {np.min(steps):.6g} .. {np.max(steps):.6g} s, median {sample_time:.6g} s"
        if math.isclose(sample_time, claimed, rel_tol=1e-6):
            claims.append(AuditClaim("sample_time", where, f"{sample_time:g} s", "confirmed", f"t {spread}"))
        elif math.isclose(sample_time, 1000.0 * claimed, rel_tol=1e-6):
            claims.append(AuditClaim("columns", "t in s", "t in ms", "contradicted",
                                     f"t steps by {sample_time:g} per row, {claimed:g} s in ms"))
            changes["t"] = t / 1000.0
            sample_time = round(sample_time / 1000.0, 9)
            notes.append("the t column is in ms (the audit): divided by 1000")
        elif (host := _host_stamps(t, claimed)) is not None:
            claims.append(AuditClaim("sample_time", where, f"{claimed:g} s (t a host's time stamps)", "confirmed",
                                     f"t {spread}; over the run {host:.7g} s a row, {claimed:g} s to "
                                     f"{abs(host / claimed - 1):.2%}: the rows are the rig's ticks, t the time "
                                     f"each reached the computer"))
            changes.update(_ticks_times(log, claimed))
            sample_time = claimed
            notes.append(f"t holds a host's time stamps (from {t[0]:.10g} s, steps {np.min(steps):.6g} .. "
                         f"{np.max(steps):.6g} s; the audit): the rig's {claimed:g} s a tick used, "
                         f"t = {claimed:g}·(n - n[0])")
        elif not SAMPLE_TIMES[0] <= sample_time <= SAMPLE_TIMES[1]:  # no loop's, no beam's
            claims.append(AuditClaim("sample_time", where, f"t steps by {sample_time:g} s: not a sample time",
                                     "contradicted", f"t {spread}: no rig or simulation samples at that rate "
                                     f"({SAMPLE_TIMES[0]:g} .. {SAMPLE_TIMES[1]:g} s: the beam's 2.5 Hz mode needs "
                                     f"under {SAMPLE_TIMES[1]:g} s); t is not used, {claimed:g} s a tick is"))
            notes.append(f"t steps by {sample_time:g} s, no sample time (the audit): {claimed:g} s a tick used, "
                         f"t = {claimed:g}·(n - n[0])")
            changes.update(_ticks_times(log, claimed))
            sample_time = claimed
        else:
            claims.append(AuditClaim("sample_time", where, f"{sample_time:g} s", "contradicted",
                                     f"t {spread}; the data's {sample_time:g} s is used"))
            if stated is not None:
                new_meta = {**meta, "dt": sample_time}
        n = np.asarray(data["n"], dtype=float)
        if n.size > 1 and np.all(np.isfinite(n)) and not np.all(np.diff(n) == 1):
            dn = np.diff(n)
            skips, back = int(np.count_nonzero(dn > 1)), int(np.count_nonzero(dn < 1))
            gaps = skips + back
            what = ", ".join(f"{w} at {k} row{'s' * (k > 1)}" for k, w in
                             ((skips, "ticks missing"), (back, "a tick repeated or gone back")) if k)
            claims.append(AuditClaim("sample_time", "one row per tick", f"n jumps at {gaps} row{'s' * (gaps > 1)}",
                                     "contradicted", f"n steps {np.min(dn):g} .. {np.max(dn):g}: {what}"))
    words, signed = word_claims(data)
    claims += words
    changes.update(signed)
    notes += [f"{WORD_COLUMNS[name]} holds 16-bit two's-complement words read as unsigned (the audit): "
              f"values of {WORD // 2} and more taken as x - {WORD}" for name in signed]
    theta = np.asarray(changes.get("theta", data["theta"]), dtype=float)
    if theta.size and np.all(np.isfinite(theta)) and np.any(theta):
        if _whole(theta):
            claims.append(AuditClaim("columns", "θ in encoder counts", "θ in encoder counts", "confirmed",
                                     "every θ is a whole count"))
        else:
            unit = next((name for name, q in THETA_UNITS.items()
                         if quantum_fits(theta, q, most_glitches(theta.size))), None)  # a corrupted field too
            if unit is None:
                claims.append(AuditClaim("columns", "θ in encoder counts", "θ not quantized", "unchecked",
                                         f"θ is not whole counts (e.g. {theta[np.flatnonzero(theta != np.round(theta))[0]]:.6g})"
                                         f" nor whole counts of {', '.join(THETA_UNITS)}: its unit is not decided"))
            else:
                q = THETA_UNITS[unit]
                changes["theta"] = np.round(theta / q)
                u = np.asarray(changes.get("u", data["u"]), dtype=float)
                also = ""
                if u.size and np.all(np.isfinite(u)) and not _whole(u) and _in_unit(u, changes["theta"], q):
                    changes["u"] = counts_of(u, q)
                    also = "; u, not whole counts, taken in the same unit"
                off = np.flatnonzero(~quantum_fits_each(theta, q))
                but = f" but row{'s' * (off.size > 1)} {', '.join(map(str, off))} (corrupted)" if off.size else ""
                claims.append(AuditClaim("columns", "θ in encoder counts", f"θ in {unit}", "contradicted",
                                         f"every θ{but} is a multiple of {q:.6g} ({unit} per encoder count of "
                                         f"{COUNTS_PER_REV}/rev), none of 1{also}"))
                notes.append(f"θ is in {unit} (the audit): converted to encoder counts{also}")
    accel = accel_unit(np.asarray(changes.get("a", data["a"]), dtype=float))
    if accel is not None:
        claims.append(accel.claim)
        if accel.counts is not None:
            changes["a"] = accel.counts
            notes.append(f"a is in steps of {accel.step:.6g} a count (the audit): divided by it")
    if not changes and new_meta is None:
        return TimeBase(tuple(claims), log)
    fixed = dict(data)
    fixed.update(changes)
    corrected = dataclasses.replace(log, data=fixed, sample_time=sample_time, meta=new_meta or meta,
                                    notes=list(log.notes) + notes)
    return TimeBase(tuple(claims), corrected)
