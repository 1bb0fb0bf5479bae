"""Corrupted fields in a column no law reads: told by what the column itself can hold.

A corrupted field in a column the log's law reads (v, θ and u under a closed loop, a under
accelerometer feedback) is found by the law (:mod:`station.analysis.glitches`). The same
serial glitch in a column no law reads (a under P or the lead alone, θ in open loop) left the
law reproducing every row and was read as the run's: the rig's P step with a of row 500 off by
512 counts compared with its model at an accelerometer fit of 4.3 % (the log's own 38.5 %),
without a word. Such a field is told by the column: θ past both neighbouring rows by more
than the hub can move in a tick (:data:`station.rig.MAX_ENCODER_STEP`), a past both its
neighbours :data:`SPIKE_FACTOR` times as far as any other row of the run lies past its own
(the rig's eleven logs: at most 1.7 times, the 2009 P step's jolt; two rows alike are no lone field).
Each is set aside, said, and put right from its neighbours.
"""

from __future__ import annotations

import dataclasses
from typing import NamedTuple

import numpy as np

from station.analysis.glitches import Glitches, most_glitches, neighbours_words
from station.analysis.law_rows import TOLERANCE
from station.control.rerun import is_closed_loop
from station.logged.controller import ControllerId
from station.rig import MAX_ENCODER_STEP
from station.runlog import RunLog

SPIKE_FACTOR = 4.0
"""How many times further past both its neighbours than any other row of the run an a field
must lie to be a corrupted one (the rig's logs: at most 1.7)."""

SPIKE_WORDS = "no law reads it; as a corrupted field has it, set aside"
"""Why such a field is set aside, said after it."""


class Spikes(NamedTuple):
    """Corrupted fields in the columns no law of a log reads (:func:`unread_spikes`).

    Attributes
    ----------
    theta_rows, a_rows : tuple of int
        The rows (0-based) whose θ or a is set aside.
    theta, a : numpy.ndarray, shape (N,)
        The columns with those rows put right (the mean of the neighbouring rows, rounded
        where the column is in whole counts).
    note : str
        Each field in words, and why.
    """

    theta_rows: tuple[int, ...]
    a_rows: tuple[int, ...]
    theta: np.ndarray
    a: np.ndarray
    note: str


def unread_spikes(t, theta, a, controller, found: Glitches | None = None) -> Spikes | None:
    """The corrupted fields of the columns ``controller`` does not read, told by the columns.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s.
    theta, a : array_like, shape (N,)
        Hub angle (encoder counts, the rig's) and accelerometer (counts), as the audit read
        them (a corrupted field the law found already put right: ``found``).
    controller : Compensator, OpenLoop or None
        The log's law: a closed loop reads θ, accelerometer feedback (``ga``) reads a; with no law,
        neither is read.
    found : Glitches, optional
        The fields the law set aside (:func:`station.analysis.glitches.isolated_misses`): at
        most :func:`station.analysis.glitches.most_glitches` in all.

    Returns
    -------
    Spikes or None
        None when no such field is found.
    """
    t = np.asarray(t, dtype=float)
    budget = most_glitches(t.size) - (0 if found is None else
                                      len(found.rows) + len(found.theta_rows) + len(found.a_rows) + len(found.u_rows))
    theta, a = np.array(theta, dtype=float), np.array(a, dtype=float)
    words: list[str] = []
    theta_rows: list[int] = []
    a_rows: list[int] = []
    if not is_closed_loop(controller):
        for k in _theta_spikes(theta, budget):
            words.append(_words("θ", t, theta, k, f"no hub moves {abs(theta[k] - _mean(theta, k)):.0f} counts in a "
                                f"tick and back (at most {MAX_ENCODER_STEP:g})"))
            theta[k] = _put_right(theta, k)
            theta_rows.append(k)
    if getattr(controller, "ga", None) is None:
        for k, rest in _a_spikes(a, budget - len(theta_rows)):
            past = min(abs(a[k] - a[k - 1]), abs(a[k] - a[k + 1]))
            words.append(_words("a", t, a, k, f"past both its neighbours {past / rest:.0f}× as far as any other row "
                                f"of the run ({rest:g} counts)"))
            a[k] = _put_right(a, k)
            a_rows.append(k)
    if not words:
        return None
    return Spikes(tuple(theta_rows), tuple(a_rows), theta, a, f"{', '.join(words)}: {SPIKE_WORDS}")


def with_spikes(log: RunLog, cid: ControllerId) -> ControllerId:
    """The controller's audit with the corrupted fields of the columns its law does not read
    (:func:`unread_spikes`) set aside too: said in its claim's evidence after the fields the law
    set aside (or in a note where no reproducing law says them), and put right in
    ``cid.corrupted`` (so :attr:`station.logged.LoggedRun.log` reads them put right).

    Parameters
    ----------
    log : RunLog
        The log as the audit read it (units and columns checked).
    cid : ControllerId
        Its controller's audit (:func:`station.logged.controller.identify_controller`).

    Returns
    -------
    ControllerId
        ``cid`` itself when no such field is found.
    """
    found = cid.corrupted
    data = log.data
    if len(data["t"]) < 3:  # no row has two neighbours to tell a field by
        return cid
    spikes = unread_spikes(data["t"], data["theta"] if found is None else found.theta,
                           data["a"] if found is None else found.a, cid.controller, found)
    if spikes is None:
        return cid
    if found is None:
        found = Glitches(cid.controller, cid.fit, (), (), (), (), np.asarray(data["u"], dtype=float),
                         spikes.theta, spikes.a)
    found = found._replace(theta_rows=found.theta_rows + spikes.theta_rows, a_rows=found.a_rows + spikes.a_rows,
                           theta=spikes.theta, a=spikes.a)
    claim, notes = cid.claim, list(cid.notes)
    if claim is not None:  # said as a field the law set aside is ("; but ...": replay's and survey's line)
        claim = dataclasses.replace(claim, evidence=claim.evidence + ("; and " if "; but " in claim.evidence
                                                                      else "; but ") + spikes.note)
    if claim is None or cid.fit is None or cid.fit.max_abs_dv > TOLERANCE:  # no such line: a note says it
        notes.append(spikes.note)
    return cid._replace(notes=notes, claim=claim, corrupted=found)


def _mean(x: np.ndarray, k: int) -> float:
    return float((x[k - 1] + x[k + 1]) / 2)


def _put_right(x: np.ndarray, k: int) -> float:
    """The neighbours' mean, a whole count where the column is in whole counts."""
    finite = x[np.isfinite(x)]
    whole = bool(np.all(finite == np.round(finite)))
    return float(np.round(_mean(x, k))) if whole else _mean(x, k)


def _words(name: str, t, x, k: int, why: str) -> str:
    return f"{name} of row {k} at t = {t[k]:g} s (logged {x[k]:g}, its {neighbours_words(x, k)}): {why}"


def _off(x: np.ndarray) -> np.ndarray:
    """|x[k] − the mean of its neighbours| for each interior row k (0 at the ends and where not finite)."""
    off = np.zeros(x.size)
    if x.size >= 3:
        off[1:-1] = np.abs(x[1:-1] - (x[:-2] + x[2:]) / 2)
    return np.where(np.isfinite(off), off, 0.0)


def _past_both(x: np.ndarray) -> np.ndarray:
    """How far x[k] lies past both its neighbours, on one side of them (0 where it lies between
    them or level with one: two rows alike are no lone field), for each interior row k."""
    past = np.zeros(x.size)
    if x.size >= 3:
        before, after = x[1:-1] - x[:-2], x[1:-1] - x[2:]
        past[1:-1] = np.where(np.sign(before) * np.sign(after) > 0, np.minimum(np.abs(before), np.abs(after)), 0.0)
    return np.where(np.isfinite(past), past, 0.0)


def _theta_spikes(theta: np.ndarray, budget: int) -> list[int]:
    """Rows whose θ lies past both neighbours by more than a tick's motion, the neighbours
    within a tick's motion of each other (a hub cannot jump there and back)."""
    off = _off(theta)
    agree = np.zeros(theta.size, bool)
    agree[1:-1] = np.abs(theta[2:] - theta[:-2]) <= MAX_ENCODER_STEP
    rows = np.flatnonzero((off > MAX_ENCODER_STEP) & agree)
    return [int(k) for k in rows] if 0 < rows.size <= budget else []


def _a_spikes(a: np.ndarray, budget: int) -> list[tuple[int, float]]:
    """Rows whose a lies past both its neighbours :data:`SPIKE_FACTOR` times as far as any other
    row lies past its own (the rows beside it left out), largest first, with that other row's."""
    past = _past_both(a)
    found: list[tuple[int, float]] = []
    while len(found) < budget:
        k = int(np.argmax(past))
        rest = past.copy()
        for j, _ in found + [(k, 0.0)]:
            rest[max(j - 2, 0):j + 3] = 0.0
        other = max(float(np.max(rest, initial=0.0)), 1.0)  # at least a count: a quiet channel's noise
        if past[k] <= SPIKE_FACTOR * other:
            break
        found.append((k, other))
        past[max(k - 2, 0):k + 3] = 0.0
    return found
