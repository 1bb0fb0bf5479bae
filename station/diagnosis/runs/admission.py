"""Which runs a diagnosis may use, checked before any work starts: no run judged on itself
(the same data rows given twice, as a copy, cut or downsampled from another run
(:func:`station.logged.copies.copy_between`), or as both a RUN and a ``--validate`` run), and
hub-held beam tests set aside (the motor model cannot simulate a hand holding the hub)."""

from __future__ import annotations

import hashlib
from collections.abc import Sequence
from itertools import combinations

import numpy as np

from station.analysis.beam import HELD_COUNTS, HELD_MIN_S, HELD_MIN_V, hub_held
from station.diagnosis.runs.cases import RunCase
from station.errors import StationError
from station.logged.copies import copy_between

DIGEST_COLUMNS = ("t", "u", "v", "theta", "a")
"""The columns whose rows identify a run (its header and file name do not)."""


def data_digest(case: RunCase) -> str:
    """SHA-256 of a run's data rows (:data:`DIGEST_COLUMNS`, as read): equal for a copy of
    the file under another name or with another header.

    Parameters
    ----------
    case : RunCase
        The run as loaded (:func:`station.diagnosis.runs.cases.load_case`).

    Returns
    -------
    str
        The digest, 64 lowercase hex digits.
    """
    h = hashlib.sha256()
    for name in DIGEST_COLUMNS:
        col = case.log.data.get(name)
        h.update(name.encode())
        h.update(np.ascontiguousarray(np.asarray(col, dtype=np.float64)).tobytes() if col is not None else b"-")
    return h.hexdigest()


def refuse_repeated_runs(cases: Sequence[RunCase], n_fit: int) -> None:
    """Refuse the same data rows given twice: a run cannot validate itself (its twin would
    sit in the fit runs of the fold that judges it).

    Parameters
    ----------
    cases : sequence of RunCase
        The RUNs (the first ``n_fit``) then the ``--validate`` runs.
    n_fit : int
        How many of ``cases`` are RUNs.

    Raises
    ------
    StationError
        One line naming both files (and their roles when one is a ``--validate`` run).
    """
    role = lambda k: "--validate run" if k >= n_fit else "RUN"  # noqa: E731
    seen: dict[str, int] = {}
    for i, c in enumerate(cases):
        key = data_digest(c)
        j = seen.setdefault(key, i)
        if j == i:
            continue
        same = "the same file" if cases[j].path == c.path else "the same data rows"
        raise StationError(f"diagnose: {role(j)} {cases[j].path} and {role(i)} {c.path} are {same}: "
                           "a run cannot be judged on itself; give each run once")
    for (i, x), (j, y) in combinations(enumerate(cases), 2):
        found = copy_between(x.log, y.log)
        if found is not None:
            k, m = (i, j) if found[0] == 0 else (j, i)  # the copy, the run it was cut from
            raise StationError(f"diagnose: {role(k)} {cases[k].path} is a copy of {role(m)} {cases[m].path} "
                               f"({found[1].words()}): a run cannot be judged on itself; give each run once")


def set_aside_beam_tests(cases: Sequence[RunCase]) -> tuple[list[int], list[str]]:
    """Hub-held beam tests (:func:`station.analysis.beam.hub_held`) among the runs: the hand
    holds the hub while the motor is powered, which no motor model simulates; their beam
    modes are ``station replay``'s.

    Parameters
    ----------
    cases : sequence of RunCase

    Returns
    -------
    kept : list of int
        Indices of the runs the diagnosis uses.
    notes : list of str
        One sentence per run set aside, saying why and how it was treated.
    """
    kept, notes = [], []
    for i, c in enumerate(cases):
        d = c.log.data
        held = hub_held(d["theta"], d["v"], c.log.dt) if c.n else None
        if held is None:
            kept.append(i)
            continue
        notes.append(f"{c.name} is a hub-held beam test (θ within {held.theta_span:.0f} counts for "
                     f"{held.duration_s:.1f} s while |v| reached {held.v:.0f} DAC counts; a powered motor "
                     f"moves far with |v| >= {HELD_MIN_V:g} held for {HELD_MIN_S:g} s unless the hub is held "
                     f"within {HELD_COUNTS:g} counts): left out of the diagnosis, which simulates a free hub "
                     "(station replay analyses its beam modes)")
    return kept, notes


def set_aside_copies(sessions: Sequence[tuple[str, list[RunCase]]]) -> tuple[list[tuple[str, list[RunCase]]], list[str]]:
    """Runs that are cut or downsampled copies of another run of any session
    (:func:`station.logged.copies.copy_between`) set aside: the longer is kept.

    Parameters
    ----------
    sessions : sequence of (name, list of RunCase)

    Returns
    -------
    kept : list of (name, list of RunCase)
        The sessions with their copies left out (a session left with no run is dropped).
    notes : list of str
        One sentence per copy: "SESSION: FILE not used: a copy of PATH (its rows from row N on, ...)".
    """
    flat = [(name, c) for name, cs in sessions for c in cs]
    out: set[int] = set()
    notes = []
    for (i, (_, x)), (j, (_, y)) in combinations(enumerate(flat), 2):
        found = None if i in out or j in out else copy_between(x.log, y.log)
        if found is not None:
            k, m = (i, j) if found[0] == 0 else (j, i)
            out.add(k)
            notes.append(f"{flat[k][0]}: {flat[k][1].name} not used: a copy of {flat[m][1].path} ({found[1].words()})")
    kept = [(name, [c for c in cs if not any(c is flat[k][1] for k in out)]) for name, cs in sessions]
    return [(name, cs) for name, cs in kept if cs], notes
