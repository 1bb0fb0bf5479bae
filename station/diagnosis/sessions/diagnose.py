"""Sessions and drift (DESIGN.md "Sessions and drift"): logs grouped into sessions, one model
structure fitted on all of them, and the effects that drift between sessions with a value
per session (``station survey DIR... --diagnose``; the search is :mod:`station.diagnosis.sessions.drift`).

A session is the folder a log is in, or the ``session`` our log header names. Before any
work each session's logs are read as diagnosis cases (:func:`station.diagnosis.runs.cases.load_case`;
the caller leaves out files that are no logs); set aside, each with a note: logs the diagnosis
cannot use (the one-line reason), hub-held beam tests, a run whose data rows repeat another's, and the
accelerometer of a run whose a channel drifts (:func:`accel_drift`: its θ is used, its a is
not). The cost is bounded by ``max_samples``: when the runs hold more samples together, the
longest are cut to their first samples, all to the same length (:func:`cut_lengths`), and
each cut is said.
"""

from __future__ import annotations

import re
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from station.diagnosis.runs.cases import RunCase, Simulator, load_case, keep_bias
from station.diagnosis.runs.cost import Evaluator, calibrate_noise, pooled, rms_gain
from station.diagnosis.sessions.drift import (
    DriftResult,
    Layout,
    PerSession,
    decide_drift,
    finite,
    key,
    select_structure,
    session_axes,
)
from station.diagnosis.runs.folds import LEAVE_ONE_OUT, make_folds
from station.diagnosis.runs.inputs import data_digest, set_aside_beam_tests
from station.diagnosis.search.workbench import Bench, nominal_trial, workbench
from station.errors import StationError
from station.inputs import open_regular, parse_json
from station.logged.audit import ACCEL_DRIFT_COUNTS, ACCEL_DRIFT_WINDOW_S
from station.logged.audit import accel_drift as audit_accel_drift
from station.logged.sensors import decide_faults, sensor_evidence
from station.logged.simulate import simulate_log
from station.outputs import unique_names
from station.signals import check_stop
from station.plant.model import as_model, builtin_models
from station.runlog.schema import MAGIC

SESSION_KEY = "session"
"""Our log header's key naming a log's session (else: the folder it is in)."""

MAX_SAMPLES = 20_000
"""Default bound of the samples of all runs together (40 s of the rig's data). The rig's
folder (ten usable runs, 66 000 samples) then uses the first 3000 samples (6 s) of its five
long runs."""

IGNORED_SIGMA = 1e6
"""σ_a (counts) of a run whose accelerometer is not used: its a error weighs nothing."""


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
    ran it (:func:`station.logged.simulate.simulate_log` on the case's own log).

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


def load_sessions(sessions: Sequence[SessionLogs], max_samples: int = MAX_SAMPLES,
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
        No usable run in any session.
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
        kept, held = set_aside_beam_tests(cases)
        notes += [f"{s.name}: {n}" for n in held]
        if kept:
            per_session.append((s.name, [cases[i] for i in kept]))
        else:
            notes.append(f"{s.name}: no usable run; the session is left out")
    if not per_session:
        why = "; ".join(n for n in notes if "no usable run" not in n)
        raise StationError("survey --diagnose: no usable run in " + ", ".join(s.name for s in sessions)
                           + (f" ({why})" if why else ""))
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


@dataclass
class SessionResult:
    """One session in a sessions diagnosis.

    Attributes
    ----------
    name : str
    runs : list of str
        The runs used (paths).
    effects : dict of str to float
        Its model's effects: the shared values and its own drifting ones.
    fit_nominal, fit_final : PooledFit
        Its runs' held-out θ RMS and fits on the nominal model and the final structure.
    separate : dict of str to float
        Every accepted effect's value when each is fitted per session (before the drift
        decisions).
    refits : dict of str to list of float
        Per accepted effect, its value in this session refitted leaving each run out, with
        every effect per session.
    faults : dict of str to float
        The sensor and wiring faults decided from its runs' data
        (:func:`station.logged.sensors.decide_faults`), in its model under ``effects``.
    """

    name: str
    runs: list
    effects: dict
    fit_nominal: object
    fit_final: object
    separate: dict = field(default_factory=dict)
    refits: dict = field(default_factory=dict)
    faults: dict = field(default_factory=dict)

    @property
    def gain_pct(self) -> float:
        """Held-out θ RMS gain of its runs, %."""
        return rms_gain(self.fit_final.rms_theta, self.fit_nominal.rms_theta)


@dataclass
class SessionsDiagnosis:
    """The result of :func:`diagnose_sessions`.

    Attributes
    ----------
    sessions : list of SessionResult
    shared : dict of str to float
        The structure's effects with one value for all sessions.
    drifting : list of str
        Its effects with a value per session.
    accepted : list of str
        The structure's effects in the order they were added.
    decisions : list of station.diagnosis.sessions.drift.Decision
        Per accepted effect, whether it drifts and by how much per-session values pay.
    nominal_model : Model
    gain_pct : float
        Held-out θ RMS gain of all runs pooled, final structure against the nominal model, %.
    notes : list of str
        What was set aside or cut, and why.
    samples : tuple of int
        Samples used and samples the usable runs held.
    simulations : int
    elapsed_s : float
    validation : str
        How the held-out runs were chosen.
    """

    sessions: list
    shared: dict
    drifting: list
    accepted: list
    decisions: list
    nominal_model: object
    gain_pct: float
    notes: list
    samples: tuple
    simulations: int
    elapsed_s: float
    validation: str = LEAVE_ONE_OUT

    def session_model(self, name: str):
        """A session's model: the nominal model with its effects (shared + its drifting values).

        Parameters
        ----------
        name : str
            The session's name.

        Returns
        -------
        station.plant.model.Model
            Named "<nominal> session <name>": its sensor faults and effects applied.

        Raises
        ------
        KeyError
            No such session.
        """
        s = next((s for s in self.sessions if s.name == name), None)
        if s is None:
            raise KeyError(name)
        base = self.nominal_model
        return base.with_effects({**s.faults, **s.effects}, name=f"{base.name} session {name}")

    def model_text(self, name: str) -> str:
        """A session's model file (``--save-models``): :meth:`session_model`'s TOML after comment
        lines saying where it comes from (the session, its runs, what drifts and what is shared).

        Parameters
        ----------
        name : str
            The session's name.

        Returns
        -------
        str
            Two comment lines and the model's TOML, ending with a newline.

        Raises
        ------
        KeyError
            No such session.
        """
        model = self.session_model(name)
        s = next(s for s in self.sessions if s.name == name)
        head = [f"# station survey --diagnose: session {name}, {len(s.runs)} runs: "
                + ", ".join(Path(r).name for r in s.runs),
                "# drifting (this session's values): " + (", ".join(self.drifting) or "none")
                + "; shared by all sessions: " + (", ".join(self.shared) or "none")]
        return "\n".join(line.replace("\n", " ") for line in head) + "\n" + model.to_toml()

    def to_json(self, models: Mapping[str, str] | None = None) -> dict:
        """The JSON of DESIGN.md "Sessions and drift" (a session's ``effects`` are its model's:
        its sensor faults decided from the data first, then the effects fitted).

        Parameters
        ----------
        models : mapping of str to str, optional
            Session name -> its saved model file (``--save-models``); null otherwise.

        Returns
        -------
        dict
            ``sessions`` (per session: ``name``, ``runs``, ``effects`` (effect to value, its unit;
            None where not finite) and ``model``), ``shared`` (effect to value) and ``drifting``
            (list of effect names).
        """
        models, fin = models or {}, finite
        return {"sessions": [{"name": s.name, "runs": list(s.runs),
                              "effects": {k: fin(v) for k, v in {**s.faults, **s.effects}.items()},
                              "model": models.get(s.name)} for s in self.sessions],
                "shared": {k: fin(v) for k, v in self.shared.items()},
                "drifting": list(self.drifting)}


def diagnose_sessions(sessions: Sequence[SessionLogs], model=None, progress: Callable[[str], None] | None = None,
                      candidates: Sequence[str] | None = None, max_samples: int = MAX_SAMPLES,
                      simulate: Simulator | None = None) -> SessionsDiagnosis:
    """One structure on all sessions' runs, the effects that drift, and each session's values.

    Parameters
    ----------
    sessions : sequence of SessionLogs
        The sessions (:func:`group_sessions`).
    model : Model, str, Path or None
        The nominal model (:func:`station.plant.model.as_model`; None: "tmm-fit").
    progress : callable, optional
        Called with one line of text per step.
    candidates : sequence of str, optional
        Effects to try (default :data:`station.plant.effects.CANDIDATES`).
    max_samples : int
        Most samples of all runs together (:func:`load_sessions`).
    simulate : callable, optional
        ``simulate(case, model) -> (theta, a)`` (default :func:`simulate_cut`).

    Returns
    -------
    SessionsDiagnosis

    Raises
    ------
    StationError
        An unknown candidate, a bad model, no usable run, or fewer than two usable runs.
    """
    with workbench("survey --diagnose", candidates) as bench:
        return _diagnose_sessions(sessions, model, progress or (lambda msg: None), bench, max_samples, simulate)


def _diagnose_sessions(sessions, model, say, bench: Bench, max_samples, simulate) -> SessionsDiagnosis:
    t0 = time.perf_counter()
    names = bench.names
    base = as_model(model)
    loaded = load_sessions(sessions, max_samples, say)
    cases = loaded.cases
    if len(cases) < 2:
        raise StationError(f"survey --diagnose: one usable run ({cases[0].path}); leave-one-run-out needs at least two")
    for note in loaded.notes:
        say(note)
    layout = Layout(tuple(loaded.groups))
    # each session's sensors decided from its own runs' data first (its accelerometer may be
    # mounted the other way in one session only)
    faults = [decide_faults([sensor_evidence(cases[i].run, base) for i in g]) for g in layout.groups]
    for name, f, g in zip(loaded.names, faults, layout.groups):
        for line in f.lines():
            say(f"{name}: sensor fault, decided from the data: {line}")
        for i in g if "accel_offset" in f.effects else ():
            keep_bias(cases[i])
    ev = Evaluator(cases, base, simulate or simulate_cut,
                   run_effects=PerSession(layout.session_of(), [f.effects for f in faults]))
    folds, how = make_folds(len(cases), 0)
    search = bench.search(ev, folds, range(len(cases)), say)
    session_axes(search, names, layout.sessions)
    calibrate_noise(ev)
    notes = list(loaded.notes)
    for s, g in zip(loaded.names, layout.groups):
        for i in g:
            drift = accel_drift(cases[i])
            if drift >= ACCEL_DRIFT_COUNTS:
                cases[i].sigma_a = IGNORED_SIGMA
                notes.append(f"{s}: {cases[i].name}: its accelerometer is not used (a's mean over "
                             f"{ACCEL_DRIFT_WINDOW_S:g} s moves {drift:.0f} counts from rest: no tip acceleration "
                             f"does that); its θ is still used")
                say(notes[-1])
    for s, g in zip(loaded.names, layout.groups):
        if len(g) == 1 and layout.sessions > 1:
            notes.append(f"{s}: one usable run: held out, it is predicted with the mean of the other sessions' "
                         "values, so its own values are never judged on a run they were not fitted to")
            say(notes[-1])
    if layout.sessions == 1:
        notes.append(f"one session ({loaded.names[0]}): its runs are diagnosed, but nothing can drift")
        say(notes[-1])
    say(f"{len(cases)} runs in {layout.sessions} session(s), {loaded.samples[0]} samples used of "
        f"{loaded.samples[1]}; judged by {how}")
    nominal = nominal_trial(ev, folds)
    structure = select_structure(search, layout, names, nominal, loaded.names)
    drift: DriftResult = decide_drift(search, layout, structure, nominal, loaded.names)
    results = []
    for s, (name, g) in enumerate(zip(loaded.names, layout.groups)):
        fit_nom = pooled(ev, {i: nominal.val_sse[i] for i in g})
        fit_fin = pooled(ev, {i: drift.final.val_sse[i] for i in g})
        separate = {n: drift.separate[key(n, s)] for n in drift.accepted}
        refits = {n: drift.refits(n, s) for n in drift.accepted}
        effects = drift.session_effects(s)
        effects = {n: effects[n] for n in drift.accepted}  # in the order they were accepted
        effects = ev.run_effects(effects, g[0])  # a size searched beside a reversed sensor takes its sign
        effects = {n: effects[n] for n in drift.accepted}
        results.append(SessionResult(name, [cases[i].path for i in g], effects, fit_nom, fit_fin,
                                     separate, refits, dict(faults[s].effects)))
    gain = rms_gain(pooled(ev, drift.final.val_sse).rms_theta, pooled(ev, nominal.val_sse).rms_theta) \
        if drift.accepted else 0.0
    shared = {n: drift.values[n] for n in drift.shared}
    return SessionsDiagnosis(results, shared, list(drift.drifting), list(drift.accepted), list(drift.decisions), base,
                             float(gain), notes, loaded.samples, ev.simulations, time.perf_counter() - t0, how)
