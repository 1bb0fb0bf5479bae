"""Sessions and drift (DESIGN.md "Sessions and drift"): one model structure fitted on the runs of
several sessions, and the effects that drift between sessions with a value per session
(``station survey DIR... --diagnose``). The logs and what of them is used are
:mod:`station.diagnosis.sessions.logs`'s; the search is :mod:`station.diagnosis.sessions.drift`'s.
The accelerometer of a run whose a channel drifts (:func:`~station.diagnosis.sessions.logs.accel_drift`)
is not used: its θ is, its a weighs nothing.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from station.diagnosis.runs.cases import Simulator, keep_bias
from station.diagnosis.runs.cases import shown_effects
from station.diagnosis.runs.cost import IGNORED_SIGMA, Evaluator, calibrate_noise, pooled, rms_gain
from station.diagnosis.runs.folds import LEAVE_ONE_OUT, make_folds
from station.diagnosis.search.workbench import Bench, nominal_trial, workbench
from station.diagnosis.sessions.drift import DriftResult, decide_drift, finite, select_structure, session_axes
from station.diagnosis.sessions.layout import Layout, PerSession, key, sensor_sign
from station.diagnosis.sessions.logs import SessionLogs, accel_drift, load_sessions, simulate_cut
from station.logged.audit import ACCEL_DRIFT_COUNTS, ACCEL_DRIFT_WINDOW_S, said_once
from station.logged.sensor_evidence import sensor_evidence
from station.logged.sensors import SESSION_HEADERS, decide_faults
from station.plant.model import as_model
from station.rig import SESSIONS_MAX_SAMPLES


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
    said : list of str
        What its runs' data contradicted, said first (:func:`audit_said`): each contradicted
        claim of the logs with how many runs it holds for, then its sensor faults.
    """

    name: str
    runs: list
    effects: dict
    fit_nominal: object
    fit_final: object
    separate: dict = field(default_factory=dict)
    refits: dict = field(default_factory=dict)
    faults: dict = field(default_factory=dict)
    said: list = field(default_factory=list)

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

    def held(self, name: str, value: float) -> float:
        """A shared value as the sessions' models hold it: a signed effect is searched as a size
        beside a sensor that reads the other way (:class:`station.diagnosis.sessions.layout.PerSession`),
        and takes the sign every session's data decided; where the sessions' signs differ it
        stays a size (:meth:`sign_differs`).

        Parameters
        ----------
        name : str
            An effect of the structure.
        value : float
            Its shared value as searched.

        Returns
        -------
        float
        """
        signs = self._signs(name)
        return -value if signs == {-1} and value > 0 else value

    def sign_differs(self, name: str) -> bool:
        """Whether a signed effect's sign differs between sessions (its shared value a size).

        Parameters
        ----------
        name : str

        Returns
        -------
        bool
        """
        return len(self._signs(name)) > 1

    def _signs(self, name: str) -> set:
        return {sensor_sign(name, s.faults) for s in self.sessions}

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
                "shared": {k: fin(self.held(k, v)) for k, v in self.shared.items()},
                "drifting": list(self.drifting)}


def audit_said(cases, faults) -> list[str]:
    """What a session's runs' data contradicted, in the words of the log audit, said once per
    claim (:func:`station.logged.audit.said_once`: ``"audit: 16 of 16 runs: header: open loop;
    data: ..."``), then ``"sensor fault, decided from the data: ..."`` per sensor fault.

    Parameters
    ----------
    cases : sequence of station.diagnosis.runs.cases.RunCase
        The session's runs.
    faults : station.logged.sensors.SensorFaults
        Decided over them.

    Returns
    -------
    list of str
        In the order the claims were first met; empty when nothing was contradicted.
    """
    return said_once([(c.name, c.run.audit.lines(skip=SESSION_HEADERS)) for c in cases]) + faults.said()


def diagnose_sessions(sessions: Sequence[SessionLogs], model=None, progress: Callable[[str], None] | None = None,
                      candidates: Sequence[str] | None = None, max_samples: int = SESSIONS_MAX_SAMPLES,
                      simulate: Simulator | None = None) -> SessionsDiagnosis:
    """One structure on all sessions' runs, the effects that drift, and each session's values.

    Parameters
    ----------
    sessions : sequence of SessionLogs
        The sessions (:func:`station.diagnosis.sessions.logs.group_sessions`).
    model : Model, str, Path or None
        The nominal model (:func:`station.plant.model.as_model`; None: "tmm-fit").
    progress : callable, optional
        Called with one line of text per step.
    candidates : sequence of str, optional
        Effects to try (default :data:`station.plant.effects.CANDIDATES`).
    max_samples : int
        Most samples of all runs together (:func:`station.diagnosis.sessions.logs.load_sessions`).
    simulate : callable, optional
        ``simulate(case, model) -> (theta, a)`` (default :func:`station.diagnosis.sessions.logs.simulate_cut`).

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
    base = as_model(model)
    loaded = load_sessions(sessions, max_samples, say)
    cases = loaded.cases
    names = shown_effects(bench.names, cases)
    for note in loaded.notes:
        say(note)
    layout = Layout(tuple(loaded.groups))
    # each session's sensors decided from its own runs' data first (its accelerometer may be
    # mounted the other way in one session only)
    faults = [decide_faults([sensor_evidence(cases[i].run, base) for i in g]) for g in layout.groups]
    for name, f, g in zip(loaded.names, faults, layout.groups):
        for line in f.said():
            say(f"{name}: {line}")
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
                             f"{ACCEL_DRIFT_WINDOW_S:g} s moves {drift:.0f} counts from rest in the {cases[i].n} "
                             f"samples used: no tip acceleration does that); its θ is still used")
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
                                     separate, refits, dict(faults[s].effects),
                                     audit_said([cases[i] for i in g], faults[s].refined({**faults[s].effects, **effects}))))
    gain = rms_gain(pooled(ev, drift.final.val_sse).rms_theta, pooled(ev, nominal.val_sse).rms_theta) \
        if drift.accepted else 0.0
    shared = {n: drift.values[n] for n in drift.shared}
    return SessionsDiagnosis(results, shared, list(drift.drifting), list(drift.accepted), list(drift.decisions), base,
                             float(gain), notes, loaded.samples, ev.simulations, time.perf_counter() - t0, how)
