"""A sessions diagnosis's logs (DESIGN.md "Sessions and drift"): which logs form a session, and
what of them the diagnosis uses (``station survey DIR... --diagnose``).

A session is the folder a log is in, or the ``session`` our log header names
(:func:`group_sessions`). Before any work each session's logs are read as diagnosis cases
(:func:`load_sessions`, through :func:`station.diagnosis.runs.cases.load_case`; the caller
leaves out files that are no logs); set aside, each with a note: logs the diagnosis cannot use
(the one-line reason), hub-held beam tests and a run whose data rows repeat another's. The cost
is bounded by ``max_samples`` (:data:`station.rig.SESSIONS_MAX_SAMPLES`): when the runs hold
more samples together, the longest are cut to their first samples, all to the same length
(:func:`cut_lengths`), and each cut is said. :func:`accel_drift` finds a run whose accelerometer
channel drifts (the diagnosis then uses its θ, not its a).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from station.diagnosis.runs.cases import NO_A_COLUMN, RunCase, load_case
from station.diagnosis.runs.admission import data_digest, set_aside_beam_tests, set_aside_copies
from station.errors import StationError
from station.inputs import open_regular, parse_json
from station.logged.audit import accel_drift as audit_accel_drift
from station.logged.simulate import simulate_log
from station.outputs import unique_names
from station.plant.model import builtin_models
from station.rig import SESSIONS_MAX_SAMPLES
from station.runlog.schema import MAGIC
from station.signals import check_stop

SESSION_KEY = "session"
"""Our log header's key naming a log's session (else: the folder it is in)."""

@dataclass(frozen=True)
class SessionLogs:
    """The logs of one session.

    Attributes
    ----------
    name : str
        The session's name (its folder's, or our header's ``session``).
    paths : tuple of Path
        Its files, in order.
    """

    name: str
    paths: tuple


def _header_session(path: Path) -> str | None:
    """Our log header's ``session`` (None for any other file, or without one), from the
    header's first three lines alone (:data:`station.runlog.schema.MAGIC` among them)."""
    try:
        with open_regular(path, "run log") as fh:
            lines = [fh.readline(1 << 20).decode("utf-8", "replace").rstrip("\r\n") for _ in range(3)]
    except (OSError, StationError):  # not a regular file, unreadable: its reading names it
        return None
    if MAGIC not in lines:
        return None
    meta = next((line[2:] for line in lines if line.startswith("# {")), None)
    try:
        meta = parse_json(meta, str(path)) if meta is not None else None
    except StationError:
        return None
    s = meta.get(SESSION_KEY) if isinstance(meta, dict) else None
    return s.strip() if isinstance(s, str) and s.strip() else None


SESSION_NAME_CHARS = 60
"""Longest session name: a header's ``session`` or a folder's path is cut to it (the end kept:
it tells folders apart), before any work; its model file is named after it."""

SESSION_SUFFIX = "-session"
"""Added to a session name that is a built-in model's (``rig``: the 2013-14 logs' folder), so
that ``--save-models DIR/rig-session.toml`` is not read as the built-in ``rig``."""


def session_name(raw: str) -> str:
    """A session's name as printed and as its model file's stem: control characters and runs of
    white space made one space, at most :data:`SESSION_NAME_CHARS` characters (the end kept),
    :data:`SESSION_SUFFIX` added to a built-in model's name.

    Parameters
    ----------
    raw : str
        A header's ``session`` or a folder's path (tail).

    Returns
    -------
    str
        Not empty ("session" when nothing printable is left).
    """
    name = " ".join(re.sub(r"[\x00-\x1f\x7f-\x9f]", " ", raw).split())
    if len(name) > SESSION_NAME_CHARS:
        name = name[-SESSION_NAME_CHARS:].strip(" /") or name[:SESSION_NAME_CHARS]
    name = name or "session"
    if name.lower() in builtin_models():
        name += SESSION_SUFFIX
    return name


def group_sessions(files: Iterable[str | Path]) -> list[SessionLogs]:
    """Group log files into sessions: our header's ``session``, else the folder a file is in
    (named by the folder's name; by its path where two folders share a name).

    Parameters
    ----------
    files : iterable of str or Path
        The files (e.g. :func:`station.survey.find_logs`).

    Returns
    -------
    list of SessionLogs
        Sorted by name; each session's files in the order given.
    """
    groups: dict[tuple, list[Path]] = {}
    for f in map(Path, files):
        s = _header_session(f)
        groups.setdefault(("header", s) if s else ("folder", str(f.parent.resolve())), []).append(f)
    folders = [Path(k[1]).parts for k in groups if k[0] == "folder"]
    out = []
    for (kind, what), paths in groups.items():
        name = what
        if kind == "folder":  # the shortest tail of its path no other folder shares: "2009", else "a/2009"
            parts = Path(what).parts
            k = next((k for k in range(1, len(parts)) if [f[-k:] for f in folders].count(parts[-k:]) == 1),
                     len(parts))
            name = "/".join(parts[-k:]).lstrip("/") or what
        out.append(SessionLogs(session_name(name), tuple(paths)))
    names = unique_names([s.name for s in out])
    out = [replace(s, name=n) for s, n in zip(out, names)]
    return sorted(out, key=lambda s: s.name)


def model_file_names(sessions: Sequence[SessionLogs]) -> list[str]:
    """The model file of each session in a ``--save-models`` folder: ``<session>.toml`` (its
    name, at most :data:`SESSION_NAME_CHARS` characters, made safe for a file name, unique).

    Parameters
    ----------
    sessions : sequence of SessionLogs

    Returns
    -------
    list of str
        One distinct file name per session, in their order, each ending in ".toml" (a name
        that is also a built-in model's gets :data:`SESSION_SUFFIX`).
    """
    stems = [re.sub(r"[^A-Za-z0-9_.-]+", "_", s.name).strip(".") or "session" for s in sessions]
    stems = [n + SESSION_SUFFIX if n.lower() in builtin_models() else n for n in stems]
    return [f"{n}.toml" for n in unique_names(stems)]


def accel_drift(case: RunCase) -> float:
    """The largest |mean of a| over any :data:`station.logged.audit.ACCEL_DRIFT_WINDOW_S`
    window of a run (its rest offset removed), counts; 0 for a shorter run
    (:func:`station.logged.audit.accel_drift`, the audit's one definition).

    Parameters
    ----------
    case : RunCase

    Returns
    -------
    float
    """
    return audit_accel_drift(case.a, case.log.dt)


def cut_lengths(lengths: Sequence[int], max_samples: int) -> list[int]:
    """Run lengths cut so that they hold at most ``max_samples`` together: the longest runs
    are cut to one common length, as long as the bound allows (water filling).

    Parameters
    ----------
    lengths : sequence of int
        Samples of each run.
    max_samples : int
        The bound.

    Returns
    -------
    list of int
        The samples used of each run (each at most its length).
    """
    if sum(lengths) <= max_samples:
        return list(lengths)
    lo, hi = 0, max(lengths)
    while lo < hi:  # the largest common cap that fits
        mid = (lo + hi + 1) // 2
        if sum(min(n, mid) for n in lengths) <= max_samples:
            lo = mid
        else:
            hi = mid - 1
    return [min(n, lo) for n in lengths]


def _cut(case: RunCase, n: int) -> RunCase:
    """The run's first n samples (simulated from rest as the whole run was)."""
    log = replace(case.log, data={k: v[:n] for k, v in case.log.data.items()})
    return replace(case, log=log, theta=case.theta[:n], a=case.a[:n], notes=list(case.notes))


def simulate_cut(case: RunCase, model) -> tuple[np.ndarray, np.ndarray]:
    """θ and a of a run, possibly cut (:func:`cut_lengths`), simulated on a model as the rig
    ran it (:func:`station.logged.simulate.simulate_log` on the case's own log, the model as
    the whole run had the rig: :meth:`station.logged.LoggedRun.model_for`).

    Parameters
    ----------
    case : RunCase
    model : Model

    Returns
    -------
    tuple of (ndarray, ndarray)
        Simulated θ (encoder counts) and a (accelerometer counts), each of shape (N,), N the
        case's (possibly cut) length.
    """
    model = case.run.model_for(model) if case.run is not None else model  # the accelerometer as the run had it
    pred = simulate_log(case.log, case.controller, case.alignment, model).prediction
    return pred["theta"], pred["a"]


@dataclass
class Loaded:
    """The runs a sessions diagnosis uses, and what was set aside.

    Attributes
    ----------
    cases : list of RunCase
        Session by session (possibly cut).
    groups : list of tuple of int
        Per session (same order as the names), its cases' indices.
    names : list of str
        The sessions kept (with at least one usable run).
    notes : list of str
        One line per file set aside, run cut or accelerometer not used.
    samples : tuple of int
        Samples used and samples the usable runs hold.
    """

    cases: list
    groups: list
    names: list
    notes: list = field(default_factory=list)
    samples: tuple = (0, 0)


def load_sessions(sessions: Sequence[SessionLogs], max_samples: int = SESSIONS_MAX_SAMPLES,
                  say: Callable[[str], None] = lambda msg: None) -> Loaded:
    """Read every session's logs as diagnosis cases; set aside what cannot be used, cut the
    longest runs to ``max_samples`` together (module docstring).

    Parameters
    ----------
    sessions : sequence of SessionLogs
    max_samples : int
        Most samples of all runs together.
    say : callable
        Called with one line per log read.

    Returns
    -------
    Loaded
        The cases session by session, their groups, the sessions kept, the notes and the
        samples used against those available.

    Raises
    ------
    StationError
        Fewer than two usable runs in all sessions (naming what was set aside and why).
    StopSignal
        SIGINT or SIGTERM arrived between two logs (:func:`station.signals.check_stop`).
    """
    notes: list[str] = []
    per_session: list[tuple[str, list[RunCase]]] = []
    seen: dict[str, str] = {}
    for s in sessions:
        cases = []
        for p in s.paths:
            check_stop()
            try:
                case = load_case(p)
            except StationError as exc:
                notes.append(f"{s.name}: {Path(p).name} not used: {str(exc).replace(str(p) + ': ', '', 1)}")
                continue
            digest = data_digest(case)
            if digest in seen:
                notes.append(f"{s.name}: {Path(p).name} not used: the same data rows as {seen[digest]}")
                continue
            seen[digest] = str(p)
            cases.append(case)
            say(f"read {s.name}: {Path(p).name} ({case.kind}, {case.n} samples)")
            notes += [] if case.a_logged else [f"{s.name}: {case.name}: {NO_A_COLUMN}"]
        kept, held = set_aside_beam_tests(cases)
        notes += [f"{s.name}: {n}" for n in held]
        if kept:
            per_session.append((s.name, [cases[i] for i in kept]))
        else:
            notes.append(f"{s.name}: no usable run; the session is left out")
    per_session, copies = set_aside_copies(per_session)
    notes += copies
    usable = [c.path for _, cs in per_session for c in cs]
    if len(usable) < 2:  # what was set aside and why, in the refusal itself (nothing is said before it)
        why = "; ".join(n for n in notes if "no usable run" not in n)
        if not usable:
            raise StationError("survey --diagnose: no usable run in " + ", ".join(s.name for s in sessions)
                               + (f" ({why})" if why else ""))
        raise StationError(f"survey --diagnose: one usable run ({usable[0]}); leave-one-run-out needs at least two"
                           + (f"; set aside: {why}" if why else ""))
    flat = [c for _, cs in per_session for c in cs]
    lengths = [c.n for c in flat]
    used = cut_lengths(lengths, max_samples)
    cases, groups, k = [], [], 0
    for name, cs in per_session:
        idx = []
        for c in cs:
            n = used[k]
            if n < c.n:
                notes.append(f"{name}: {c.name}: its first {n} of {c.n} samples used (--max-samples {max_samples} "
                             f"over all {len(flat)} runs)")
                c = _cut(c, n)
            idx.append(len(cases))
            cases.append(c)
            k += 1
        groups.append(tuple(idx))
    return Loaded(cases, groups, [name for name, _ in per_session], notes, (sum(used), sum(lengths)))
