"""Whether one log is a copy of another: the same rows cut from a later row, every k-th kept,
in another layout (the lab's ``_trunc``, ``_trunc_trunc`` and ``_downsampled`` copies of one
run). Two logs of one run are one experiment: a diagnosis that fits one and judges the other
judges a run on itself.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.runlog import RunLog

COMPARED = ("theta", "v", "a", "u")
"""The columns a copy keeps as they were (t is re-zeroed, n renumbered, u may be dropped)."""

MIN_ROWS = 50
"""Fewest rows a copy must have (fewer prove nothing: a run's rest looks like any other's)."""


@dataclass(frozen=True)
class Copy:
    """Where a shorter log's rows sit in a longer one (:func:`copy_in`).

    Attributes
    ----------
    start : int
        The longer log's row the copy's first row is.
    every : int
        Rows of the longer log per row of the copy (2: every second row kept).
    """

    start: int
    every: int

    def words(self) -> str:
        """E.g. "its rows from row 37 on, every 2nd"."""
        every = "" if self.every == 1 else f", every {self.every}{'nd' if self.every == 2 else 'th'}"
        return f"its rows from row {self.start} on{every}"


def _columns(log: RunLog) -> dict[str, np.ndarray]:
    return {k: np.asarray(log.data[k], float) for k in COMPARED
            if k in log.data and log.data[k].size and np.all(np.isfinite(log.data[k]))}


def copy_in(longer: RunLog, shorter: RunLog) -> Copy | None:
    """Whether ``shorter``'s rows are ``longer``'s from some row on, every k-th (k the ratio of
    their sample times), equal in every column both hold of θ, v, a and u.

    Parameters
    ----------
    longer, shorter : RunLog
        Two logs (the sample times' ratio must be a whole number, the shorter's the larger).

    Returns
    -------
    Copy or None
        None when ``shorter`` has fewer than :data:`MIN_ROWS` rows, θ and v constant (a rest
        matches any rest), no column in common, or its rows are not ``longer``'s.
    """
    a, b = _columns(longer), _columns(shorter)
    common = [k for k in COMPARED if k in a and k in b]
    n = len(shorter)
    if n < MIN_ROWS or "theta" not in common or not any(np.ptp(b[k]) > 0 for k in ("theta", "v") if k in common):
        return None
    ratio = shorter.dt / longer.dt
    every = int(round(ratio))
    if every < 1 or abs(ratio - every) > 1e-6:
        return None
    last = len(longer) - (n - 1) * every  # the copy's first row is before this
    if last <= 0:
        return None
    first = np.ones(last, dtype=bool)
    for k in common:
        first &= a[k][:last] == b[k][0]
    for start in np.flatnonzero(first):
        rows = slice(int(start), int(start) + (n - 1) * every + 1, every)
        if all(np.array_equal(a[k][rows], b[k]) for k in common):
            return Copy(int(start), every)
    return None


def copy_between(x: RunLog, y: RunLog) -> tuple[int, Copy] | None:
    """Whether one of two logs is a copy of the other (:func:`copy_in` both ways).

    Parameters
    ----------
    x, y : RunLog

    Returns
    -------
    (int, Copy) or None
        The copy's index (0: ``x`` is the copy of ``y``; 1: ``y`` of ``x``) and where it sits.
    """
    for i, (longer, shorter) in enumerate(((x, y), (y, x))):
        if len(shorter) <= len(longer):
            found = copy_in(longer, shorter)
            if found is not None:
                return 1 - i, found
    return None
