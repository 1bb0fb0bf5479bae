"""A log's time base: the sample time found in t or given by the header, and t or n
derived when a layout lacks one of them (:attr:`station.runlog.RunLog.dt` combines them).

Imports :mod:`station.runlog.schema`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from station.rig import DT


def _step_of(steps: np.ndarray) -> float | None:
    """The median of t's steps rounded to 1 ns, None when it is not positive."""
    dt = float(round(float(np.median(steps)), 9))
    return dt if dt > 0 else None


def header_dt(meta: dict[str, Any]) -> float | None:
    """The sample time a log's header gives.

    Parameters
    ----------
    meta : dict
        The header (:attr:`station.runlog.RunLog.meta`).

    Returns
    -------
    float or None
        ``meta["dt"]`` in s when it is a finite positive number (not a bool), else None.
    """
    dt = meta.get("dt")
    if isinstance(dt, (int, float)) and not isinstance(dt, bool) and math.isfinite(dt) and dt > 0:
        return float(dt)
    return None


def complete_time_base(data: dict[str, np.ndarray], names: list[str], notes: list[str]) -> float | None:
    """Fill t from n (at the rig's 0.002 s) or n from t, in place, and say so in ``notes``.

    Parameters
    ----------
    data : dict of numpy.ndarray
        The log's columns by standard name, shape (rows,) each; t and n may be all NaN.
    names : list of str
        The columns the file has (the others are NaN).
    notes : list of str
        The reader's notes; appended to.

    Returns
    -------
    float or None
        The sample time found in t, s: the median step rounded to 1 ns; None with fewer
        than two rows, a non-finite t, or a median step that is not positive.
    """
    if "n" in names:
        unwrap_counter(data, "t" in names, notes)
    t, n = data["t"], data["n"]
    if "t" not in names and "n" in names:
        data["t"] = t = n * DT
        notes.append(f"no time column: t = n * {DT} s (the rig's sample time)")
    if t.size < 2 or not np.all(np.isfinite(t)):
        return None
    steps = np.diff(t)
    dt = _step_of(steps)
    if dt is None:
        return None
    if "n" not in names:
        data["n"] = np.round((t - t[0]) / dt)
        notes.append(f"no sample column: n derived from t (sample time {dt:g} s)")
    if np.max(np.abs(steps - dt)) > 0.01 * dt:
        notes.append(f"t is not evenly spaced (steps {np.min(steps):g} .. {np.max(steps):g} s; "
                     f"median {dt:g} s used)")
    return dt


WORD = 65536
"""One more than the largest unsigned 16-bit word, the legacy protocol's (``../shared/spec/protocol.md``):
a two's-complement word x < 0 read as unsigned is ``WORD + x``; the lab's PSoC sends n as one, so
after 32767 (65.5 s at 500 Hz) n reads −32768 (read unsigned, 65535 then 0)."""


def unwrap_counter(data: dict[str, np.ndarray], has_t: bool, notes: list[str]) -> None:
    """Unwrap a 16-bit tick counter, in place, and say so in ``notes``: rows where n steps by
    1 − :data:`WORD` (32767 to −32768, or 65535 to 0) are the next tick. The lab's
    software computed t as n·dt, so a t that steps back by as much there is unwrapped with it
    (otherwise a run longer than 65.5 s reads as two runs).

    Parameters
    ----------
    data : dict of numpy.ndarray
        The log's columns by standard name (n, and t when ``has_t``), shape (rows,) each.
    has_t : bool
        The file has a t column.
    notes : list of str
        The reader's notes; appended to.
    """
    n = data["n"]
    if n.size < 2 or not np.all(np.isfinite(n)):
        return
    steps = np.diff(n)
    wraps = np.flatnonzero(steps == 1 - WORD) + 1
    if not wraps.size:
        return
    offset = np.zeros(n.size)
    offset[wraps] = WORD
    offset = np.cumsum(offset)  # each wrap adds a word to every row after it
    said = ", ".join(f"{int(k)} ({n[k - 1]:g} to {n[k]:g})" for k in wraps[:3]) + (" ..." if wraps.size > 3 else "")
    data["n"] = n + offset
    words = f"n wraps at 16 bits at row {said}: the device's tick counter, unwrapped"
    t = data["t"]
    if has_t and np.all(np.isfinite(t)):
        ticks = steps == 1
        dt = float(np.median(np.diff(t)[ticks])) if np.any(ticks) else 0.0
        back = np.diff(t)[wraps - 1]
        if dt > 0 and np.all(np.abs(back + (WORD - 1) * dt) < 0.5 * dt):
            data["t"] = t + offset * dt
            words += f"; t with it (t = n·{dt:g} s)"
    notes.append(words)


MISSING_SHARE = 9.0
"""At most this many missing ticks per row for a log to be simulated on its ticks
(:func:`row_ticks`): a copy of every 10th tick of a 500 Hz loop (a 50 Hz logger) is placed, and
its model runs 10 ticks a row; beyond it (an n that counts something else, such as a host's
microseconds) the rows are taken as consecutive ticks (the audit says n jumps)."""


def row_ticks(n) -> np.ndarray | None:
    """Each row's tick counted from the first row's, when rows are missing or repeated.

    A log's n is the device's tick counter (or derived from t: :mod:`station.runlog.timebase`).
    Rows the logger lost leave n jumping by more than one; rows written again repeat
    earlier n.

    Parameters
    ----------
    n : array_like, shape (N,)
        The log's n column.

    Returns
    -------
    numpy.ndarray of int64, shape (N,), or None
        ``n - n[0]``, when n is whole, no row is before the first's tick, n steps by other
        than 1 somewhere and at most :data:`MISSING_SHARE` ticks per row are missing; None
        otherwise (rows that are consecutive ticks, or whose ticks cannot be placed, such as a
        counter that wraps: taken as consecutive).
    """
    n = np.asarray(n, dtype=float)
    if n.size < 2 or not np.all(np.isfinite(n)) or np.any(n != np.round(n)):
        return None
    ticks = (n - n[0]).astype(np.int64)
    if np.all(np.diff(ticks) == 1) or np.any(ticks < 0):
        return None
    if ticks.max() + 1 - np.unique(ticks).size > MISSING_SHARE * n.size:
        return None
    return ticks


def on_ticks(ticks: np.ndarray, *columns) -> tuple[np.ndarray, ...]:
    """Columns on every tick from the first row's to the last: a tick's value is its first
    row's; a missing tick holds the tick before's (the device holds its command, a reference is
    held).

    Parameters
    ----------
    ticks : numpy.ndarray of int, shape (N,)
        Each row's tick from the first row's (:func:`row_ticks`).
    *columns : array_like, shape (N,)

    Returns
    -------
    tuple of numpy.ndarray, shape (ticks.max() + 1,) each
    """
    order = np.argsort(ticks, kind="stable")
    ordered = ticks[order]
    first = order[np.r_[True, ordered[1:] != ordered[:-1]]]  # each tick's first row, by tick
    grid = np.arange(int(ticks.max()) + 1)
    src = first[np.searchsorted(ticks[first], grid, side="right") - 1]
    return tuple(np.asarray(c, float)[src] for c in columns)


def tick_time(t, n, dt: float) -> float:
    """Seconds per tick of a log whose rows skip ticks: the median of t's steps over n's, to 1 ns.

    Parameters
    ----------
    t, n : array_like, shape (N,)
        The log's t (s) and n columns.
    dt : float
        The log's sample time (:attr:`station.runlog.RunLog.dt`): the answer when t and n
        cannot give one.

    Returns
    -------
    float
        0.002 on a copy of the rig's run that keeps every other row (t steps 0.004, n 2).
    """
    t, n = np.asarray(t, float), np.asarray(n, float)
    steps = np.diff(n)
    ok = (steps > 0) & np.isfinite(steps) & np.isfinite(np.diff(t))
    if not ok.any():
        return dt
    per = float(round(float(np.median(np.diff(t)[ok] / steps[ok])), 9))
    return per if per > 0 else dt


def restart_rows(n) -> tuple[int, ...]:
    """The rows where a log's ticks jump (the row before is not the tick before), where a
    replay of its controller starts again (:func:`station.control.rerun.replay_commands`).

    Parameters
    ----------
    n : array_like, shape (N,)
        The log's n column.

    Returns
    -------
    tuple of int
        Empty when :func:`row_ticks` cannot place the rows or they are consecutive.
    """
    ticks = row_ticks(n)
    return () if ticks is None else tuple(int(r) for r in np.flatnonzero(np.diff(ticks) != 1) + 1)


def run_start(t, n, dt: float) -> float:
    """How long before a log's first row its run started, s: n[0] ticks where the log's t and
    its own n agree that the first row is tick n[0] of a clock started at 0 (a copy cut from a
    longer run, t and n as the loop counted them: the P step from row 30 has t = 0.06 s at
    n = 30); else 0 (the run starts at the first row, whatever its clock read: a host's time
    stamps, a clock since boot, an n derived from t).

    Parameters
    ----------
    t, n : array_like, shape (N,)
        The log's t (s) and n columns.
    dt : float
        The log's sample time (:attr:`station.runlog.RunLog.dt`).

    Returns
    -------
    float
        >= 0.
    """
    t, n = np.asarray(t, float), np.asarray(n, float)
    if not t.size or not (np.isfinite(n[0]) and np.isfinite(t[0]) and n[0] > 0 and n[0] == round(n[0])):
        return 0.0
    tick = tick_time(t, n, dt) if t.size > 1 else dt
    start = float(n[0]) * tick
    return start if abs(float(t[0]) - start) <= 0.5 * tick else 0.0
