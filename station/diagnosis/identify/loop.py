"""Identifying a rig on the device itself (DESIGN.md "Identifying a rig"): run the thesis's four
experiments, diagnose, and while the diagnosis leaves rivals (alternatives, wide intervals)
design the experiment that best separates them, run it and diagnose again, up to a budget
(:func:`identify`; ``station identify`` is its CLI).

Every experiment is a normal ``station step`` run (:func:`station.experiment.run_step`:
fail-safe, logged; the reference of a designed experiment is written beside its log as
``<log stem>.u.tsv`` and given as ``FILE:u``). A run that does not complete (any stop, or a
watchdog trip) is reported and not used; a SIGINT or SIGTERM ends the identification, and
no experiment starts after one (a signal during a diagnosis or a design stops the work there,
saying which experiments ran and where their logs are). A device that cannot be opened for a
later experiment (unplugged, powered off) ends the identification with what ran (exit code 1),
not as bad input.

The first diagnosis tries the whole vocabulary (or the ``candidates`` given); each later one
only the effects the first found worth a look (:func:`recheck_candidates`), which keeps a
re-diagnosis of up to twelve runs by leave-one-run-out affordable. A re-diagnosis that fits
every run worse than the earlier explanation is set aside
(:func:`station.diagnosis.identify.prefer.prefer`); the next design then separates the kept
explanation's rivals on all the runs (its intervals there, and the set-aside one unless the
kept one pays over it), not the earlier diagnosis's of fewer runs, so a settled answer stops
the loop. Every explanation met on the way (earlier answers, their alternatives) stays in
``alternatives`` until the answer pays over it on all the runs as forward selection demands
of an effect (:func:`station.diagnosis.identify.prefer.contest`), so the loop designs
experiments against it and never ends with ``alternatives: []`` while such a rival remains.
"""

from __future__ import annotations

import datetime as _dt
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, NamedTuple

from station.diagnosis.identify.design import Design, choose_experiment
from station.diagnosis.identify.experiments import THESIS_EXPERIMENTS, Experiment, candidate_experiments, write_reference
from station.diagnosis.identify.prefer import Explanation, contest, kept_diagnosis, prefer
from station.diagnosis.pipeline import diagnose
from station.diagnosis.honesty.rivals import describe, rivals
from station.diagnosis.search.fitting import SHAPE
from station.errors import StationError
from station.experiment import run_step
from station.link import LinkLimits
from station.logged.device import command_quantization
from station.plant.effects import CANDIDATES
from station.plant.model import as_model
from station.rig import CLAMP, DEFAULT_SOFT_LIMIT, DEFAULT_TIMEOUT
from station.runlog import read_log
from station.signals import StopSignal, StopSignals, noting

DEFAULT_BUDGET = 8
"""Designed experiments after the thesis's four, at most (``station identify --budget``)."""

SURVIVALS = 2
"""An alternative that still fits every run as well as the answer after this many experiments
designed against it (its refit matches each one) is not aimed at again: the loop ends when only
such remain, and they stay listed (an actuator pole with viscous friction is an actuator gain
to the model)."""

RECHECK_CANDIDATES = 8
"""Re-diagnoses try at most this many effects: the first diagnosis's accepted ones, its rivals'
and the best of the others alone."""

THESIS_WHY = ("the thesis's P step", "the thesis's lead step", "the thesis's lead + accelerometer step",
              "the thesis's open-loop pulses")
"""Why each of :data:`~station.diagnosis.identify.experiments.THESIS_EXPERIMENTS` is run."""


class ExperimentRun(NamedTuple):
    """What running one experiment gave.

    Attributes
    ----------
    log : Path
        Its run log.
    reason : str
        The outcome's reason (DESIGN.md "Run outcome"; "completed" when it ran to the end).
    exit_code : int
        As ``station step``'s: 0 completed without a watchdog trip, 130 / 143 stopped by a signal.
    """

    log: Path
    reason: str
    exit_code: int


Runner = Callable[[Experiment, Path], ExperimentRun]
"""``runner(experiment, log_path) -> ExperimentRun``: runs an experiment on the device."""


def step_runner(port: str, protocol: str = "v1", soft_limit: float = DEFAULT_SOFT_LIMIT, limit: float = CLAMP,
                timeout: float = DEFAULT_TIMEOUT, force: bool = False, limits: LinkLimits | None = None,
                baudrate: int | None = None) -> Runner:
    """A runner that runs each experiment as ``station step`` does (:func:`station.experiment.run_step`).

    Parameters
    ----------
    port : str
        Port path or pyserial URL (``sim://`` is the simulated rig).
    protocol : {"v1", "legacy"}
        The device's wire protocol.
    soft_limit : float
        Encoder soft limit, counts.
    limit : float
        The controller's clamp, ±DAC counts.
    timeout : float
        Longest wait for one sample, s.
    force : bool
        Overwrite an existing log (and reference file) of the same name.
    limits : LinkLimits, optional
        The link's fail-safe bounds (default: ``LinkLimits(timeout=timeout)``), as ``station
        step`` takes them from its options and ``station.toml``.
    baudrate : int, optional
        The port's baud rate (default: the protocol's).

    Returns
    -------
    Runner
        ``run(experiment, log) -> ExperimentRun``.
    """
    def run(experiment: Experiment, log: Path) -> ExperimentRun:
        if experiment.reference == "step":
            ref = {"reference": "step", "amplitude": experiment.amplitude, "step_time": experiment.step_time}
        else:
            path = log.with_name(log.stem + ".u.tsv")
            if path.exists() and not force:
                raise StationError(f"{path}: exists; use --force to overwrite it, or another --out-dir")
            ref = {"reference": f"{write_reference(experiment, path)}:u"}
        try:
            report = run_step(port=port, protocol=protocol, controller=experiment.controller, kp=experiment.kp,
                              limit=limit, soft_limit=soft_limit, timeout=timeout, out=log, force=force,
                              duration=experiment.duration, limits=limits, baudrate=baudrate, **ref)
        except (StationError, StopSignal):  # the run never started: its reference file goes too
            if experiment.reference != "step":
                log.with_name(log.stem + ".u.tsv").unlink(missing_ok=True)
            raise
        o = report.result.outcome
        return ExperimentRun(report.log_path, o.reason, o.exit_code)

    return run


@dataclass
class ExperimentRecord:
    """One experiment of an identification.

    Attributes
    ----------
    experiment : Experiment
    log : Path
    why : str
        Why it was run (the thesis's, or the design's reason in words).
    reason : str
        Its outcome's reason.
    used : bool
        Completed (without a watchdog trip): the diagnoses use it.
    design : Design or None
        The design that chose it (None for the thesis's four).
    """

    experiment: Experiment
    log: Path
    why: str
    reason: str
    used: bool
    design: Design | None = field(default=None, repr=False)

    def to_json(self) -> dict:
        """``{"log", "controller", "kp", "reference", "label", "why", "outcome", "used"}``.

        Returns
        -------
        dict
            ``log`` (str), the experiment's :meth:`~station.diagnosis.identify.experiments.Experiment.to_json`
            keys, ``why``, ``outcome`` (the reason) and ``used`` (bool).
        """
        return {"log": str(self.log), **self.experiment.to_json(), "why": self.why, "outcome": self.reason,
                "used": self.used}


@dataclass
class Identification:
    """The result of :func:`identify`.

    Attributes
    ----------
    diagnosis : Diagnosis or None
        The last diagnosis (None when fewer than two experiments completed).
    experiments : list of ExperimentRecord
        In the order they ran.
    stopped : str
        Why the loop ended, in words.
    budget : int
        Designed experiments allowed.
    diagnoses : int
        Diagnoses made.
    timings : dict of str to float
        Seconds spent running experiments, diagnosing, designing, and in total.
    exit_code : int
        0, or 130 / 143 when a signal ended it, 1 when nothing could be diagnosed.
    kept : list of str
        Each time a re-diagnosis was set aside for the earlier explanation, why (:func:`prefer`).
    model : station.plant.model.Model or None
        The identified model: the diagnosis's extended model, or, when the last re-diagnosis was
        set aside, the kept explanation refitted on every completed run.
    """

    diagnosis: Any
    experiments: list
    stopped: str
    budget: int
    diagnoses: int = 0
    timings: dict = field(default_factory=dict)
    exit_code: int = 0
    kept: list = field(default_factory=list)
    model: Any = None

    def to_json(self) -> dict:
        """The diagnosis's JSON (DESIGN.md) plus ``"experiments"`` and ``"identify"`` (how it
        ended, the budget, the diagnoses made, the timings).

        Returns
        -------
        dict
            :meth:`Diagnosis.to_json` (``{"cause": None, "causes": []}`` without a diagnosis) with
            ``experiments`` (one :meth:`ExperimentRecord.to_json` each) and ``identify``
            (``stopped``, ``budget``, ``diagnoses``, ``kept_earlier``, ``model``, the experiments
            run and used, ``timings_s`` in s to 3 decimals).
        """
        doc = self.diagnosis.to_json() if self.diagnosis is not None else {"cause": None, "causes": []}
        doc["experiments"] = [e.to_json() for e in self.experiments]
        doc["identify"] = {"stopped": self.stopped, "budget": self.budget, "diagnoses": self.diagnoses,
                           "kept_earlier": list(self.kept),
                           "model": None if self.model is None else self.model.to_json(),
                           "experiments_run": len(self.experiments),
                           "experiments_used": sum(e.used for e in self.experiments),
                           "timings_s": {k: round(v, 3) for k, v in self.timings.items()}}
        return doc


def default_out_dir(when: _dt.datetime | None = None, folder: str | Path = "runs") -> Path:
    """``runs/identify-<UTC time, ms>``, with ``-2``, ``-3``... when taken.

    Parameters
    ----------
    when : datetime, optional
        The time in the name (default now, UTC).
    folder : str or Path
        Where the folder goes.

    Returns
    -------
    Path
        ``folder/identify-YYYYmmdd-HHMMSS-mmm`` (a suffix when taken); not created.
    """
    when = when or _dt.datetime.now(_dt.UTC)
    stem = f"identify-{when:%Y%m%d-%H%M%S}-{when.microsecond // 1000:03d}"
    path, k = Path(folder) / stem, 1
    while path.exists():
        k += 1
        path = Path(folder) / f"{stem}-{k}"
    return path


def recheck_candidates(diag, rival_effects: Sequence[str], allowed: Sequence[str]) -> list[str]:
    """The effects later diagnoses try: the accepted ones, the rivals', then the best of the rest
    by their cost gain alone (positive only), at most :data:`RECHECK_CANDIDATES`.

    Parameters
    ----------
    diag : Diagnosis
        The first diagnosis.
    rival_effects : sequence of str
        Effects named by its rivals.
    allowed : sequence of str
        The candidates of the first diagnosis.

    Returns
    -------
    list of str
        Distinct effect names from ``allowed`` in that order, at most
        :data:`RECHECK_CANDIDATES` (or as many as the causes); ``allowed`` itself when none.
    """
    order = list(diag.accepted) + list(rival_effects)
    order += [e.name for e in sorted(diag.effects, key=lambda e: -e.cost_gain_pct) if e.cost_gain_pct > 0]
    out: list[str] = []
    for n in order:
        if n in allowed and n not in out:
            out.append(n)
    return out[:max(RECHECK_CANDIDATES, len(diag.accepted))] or list(allowed)


def identify(port: str = "sim://", model=None, budget: int = DEFAULT_BUDGET, out_dir: str | Path | None = None,
             protocol: str = "v1", candidates: Sequence[str] | None = None, soft_limit: float = DEFAULT_SOFT_LIMIT,
             limit: float = CLAMP, timeout: float = DEFAULT_TIMEOUT, force: bool = False,
             progress: Callable[[str], None] | None = None, runner: Runner | None = None,
             limits: LinkLimits | None = None, baudrate: int | None = None) -> Identification:
    """Identify a rig by experiments on the device (module docstring).

    Parameters
    ----------
    port : str
        The device (a port path or pyserial URL; ``sim://?model=FILE`` a simulated rig).
    model : Model, str, Path or None
        The nominal model the diagnoses extend (default tmm-fit).
    budget : int
        Designed experiments after the thesis's four, at most (0: the four only).
    out_dir : str or Path, optional
        Folder of the experiments' logs (default :func:`default_out_dir`); created.
    protocol : {"v1", "legacy"}
        The device's wire protocol.
    candidates : sequence of str, optional
        Effects the first diagnosis tries (default the whole vocabulary).
    soft_limit : float
        Encoder soft limit of every run, counts.
    limit : float
        The controllers' clamp, ±DAC counts.
    timeout : float
        Longest wait for one sample, s.
    force : bool
        Overwrite logs of the same name in ``out_dir``.
    progress : callable, optional
        Called with one line per experiment, design and diagnosis step.
    runner : callable, optional
        ``runner(experiment, log_path) -> ExperimentRun`` (default :func:`step_runner` on
        ``port``); tests plug in their own.
    limits : LinkLimits, optional
        The link's fail-safe bounds for every experiment (``station.toml`` and the options,
        as ``station step``'s; default ``LinkLimits(timeout=timeout)``).
    baudrate : int, optional
        The port's baud rate (default: the protocol's).

    Returns
    -------
    Identification

    Raises
    ------
    StationError
        A negative budget, a bad model or candidate, a port that cannot be opened (before
        any run), an unwritable folder.
    """
    if isinstance(budget, bool) or int(budget) != budget or budget < 0:
        raise StationError(f"identify: the budget must be a whole number of experiments >= 0, got {budget!r}")
    base = as_model(model)
    names = list(CANDIDATES if candidates is None else candidates)
    say = progress or (lambda msg: None)
    run = runner or step_runner(port, protocol, soft_limit, limit, timeout, force, limits, baudrate)
    folder = Path(out_dir) if out_dir is not None else default_out_dir()
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StationError(f"{folder}: cannot create the experiments' folder: {exc.strerror or exc}") from None
    loop = _Loop(base, folder, run, say, soft_limit, limit)
    with noting(loop.kept_note):  # a signal in a diagnosis or a design: what ran and where its logs are
        return _identify(loop, names, budget)


def _identify(loop: _Loop, names: list[str], budget: int) -> Identification:
    """:func:`identify`'s loop: the thesis's four, then diagnose and design while rivals remain."""
    for exp, why in zip(THESIS_EXPERIMENTS, THESIS_WHY):
        code = loop.run(exp, why)
        if code is not None:
            return loop.result(None, f"stopped by {loop.stopped_by}", budget, code)
    diag = loop.diagnose(names)
    if diag is None:
        return loop.result(None, "fewer than two of the thesis's experiments completed: nothing to diagnose", budget, 1)
    recheck = None
    tried = set(THESIS_EXPERIMENTS)
    designed = 0
    survived: dict[frozenset, int] = {}  # an alternative -> designed experiments it fitted as well as the answer
    while True:
        rv = rivals(diag)  # the record identify prints and writes: the verdict reads what the table shows
        if not rv.rivals:
            stopped = settled(diag, rv)
            break
        if designed >= budget:
            stopped = f"budget of {budget} designed experiment(s) spent; {len(rv.rivals)} rival(s) remain: {named(rv)}"
            break
        aimed = [r for r in rv.rivals if survived.get(_structure(r), 0) < SURVIVALS]
        if not aimed:
            stopped = (f"{len(rv.rivals)} alternative(s) fitted every run as well as the answer after "
                       f"{SURVIVALS} experiments designed against each: the data cannot tell them apart "
                       f"({named(rv)})")
            break
        design = loop.design(rv._replace(rivals=aimed), [c for c in candidate_experiments() if c not in tried])
        if design.experiment is None:
            stopped = design.why
            break
        tried.add(design.experiment)
        designed += 1
        code = loop.run(design.experiment, design.why, design)
        if code is not None:
            return loop.result(diag, f"stopped by {loop.stopped_by}", budget, code)
        if not loop.records[-1].used:
            continue
        if recheck is None:
            recheck = recheck_candidates(diag, [n for r in rv.rivals for n in r.effects], names)
        new = loop.diagnose(recheck)
        if new is not None:
            diag = loop.contest(loop.prefer(diag, new), Explanation.of(diag) + Explanation.of(new))
        still = {_structure(r) for r in rivals(diag).rivals}
        for key in {_structure(r) for r in aimed if r.kind == "alternative"} & still:
            survived[key] = survived.get(key, 0) + 1
    return loop.result(diag, stopped, budget, 0)


NAMED_RIVALS = 4
"""Most rivals an ending names (the rest counted)."""


def named(rv) -> str:
    """The rivals left open, in words: each alternative, and each wide interval's ends.

    Parameters
    ----------
    rv : Rivals
        :func:`station.diagnosis.honesty.rivals.rivals`'s record.

    Returns
    -------
    str
        Their labels joined by "; ", the first :data:`NAMED_RIVALS` of them and how many more.
    """
    labels = [r.label for r in rv.rivals]
    more = len(labels) - NAMED_RIVALS
    return "; ".join(labels[:NAMED_RIVALS]) + (f"; and {more} more" if more > 0 else "")


def _structure(rival) -> frozenset:
    """An alternative rival's effects (its refits move its values, not its structure); an
    interval's end is its own."""
    return frozenset(n for n in rival.effects if n != SHAPE) if rival.kind == "alternative" else frozenset([rival.label])


def settled(diag, rv) -> str:
    """How the loop ends when a diagnosis leaves no rivals, in words read from that diagnosis
    (:func:`station.diagnosis.honesty.rivals.rivals` of it): an interval is called narrow only
    when it is (half-width within :data:`~station.diagnosis.honesty.rivals.WIDE_INTERVAL` of
    the value); a wide one whose ends no experiment can move (at its search range) is said.

    Parameters
    ----------
    diag : Diagnosis
        The record identify prints.
    rv : Rivals
        Its rivals (none).

    Returns
    -------
    str
        One sentence without a final period.
    """
    if not diag.accepted:
        return "the diagnosis accepted no effect: nothing to tell apart"
    if not rv.wide:
        return f"settled: {describe(rv.chosen)}, no alternatives and every interval narrow"
    return (f"settled: {describe(rv.chosen)}, no alternatives; the 95 % interval of {', '.join(rv.wide)} is wide "
            "but reaches only past its search range, where no experiment can look")


class _Loop:
    """The identification's state: the records, the timings, and its three steps."""

    def __init__(self, base, folder: Path, runner: Runner, say, soft_limit: float, limit: float):
        self.base, self.folder, self.runner, self.say = base, folder, runner, say
        self.soft_limit, self.limit = soft_limit, limit
        self.records: list[ExperimentRecord] = []
        self.timings = {"experiments": 0.0, "diagnosis": 0.0, "design": 0.0}
        self.diagnoses = 0
        self.kept: list[str] = []
        self.open: list[Explanation] = []  # explanations met earlier that the runs have not settled
        self.command = "round"
        self.t0 = time.perf_counter()
        self.stopped_by = ""  # what stopped the last experiment (or kept the next from starting)

    def kept_note(self) -> str:
        """What the identification leaves on disk when a signal stops it outside a run."""
        if not self.records:
            return f"no experiment ran; nothing written (the experiments' folder {self.folder} is empty)"
        logs = ", ".join(r.log.name for r in self.records)
        return (f"{len(self.records)} experiment(s) ran; their logs and figures are in {self.folder} ({logs}); "
                f"no JSON, report or model written")

    def run(self, exp: Experiment, why: str, design: Design | None = None) -> int | None:
        """Run one experiment and record it; the exit code to end with when it ends the
        identification (130 / 143 a signal, 1 a device that could not be opened for a later
        experiment), else None.

        Raises
        ------
        StationError
            The first experiment could not start (a port that cannot be opened: nothing ran).
        """
        k = len(self.records) + 1
        log = self.folder / f"{k:02d}-{exp.slug}.tsv"
        active = StopSignals._active
        if active is not None and active.signum is not None:
            # a signal came while the diagnosis or the design worked: no experiment starts
            self.stopped_by = f"{active.reason} before experiment {k} started"
            return StopSignal(active.signum).exit_code
        t = time.perf_counter()
        try:
            done = self.runner(exp, log)
        except StationError as exc:
            if not self.records:
                raise  # nothing ran: bad input, as station step says it
            ran = ", ".join(r.log.name for r in self.records)
            self.stopped_by = (f"the device: experiment {k} ({exp.label}) could not start ({exc}); "
                               f"{len(self.records)} experiment(s) ran before, their logs in {self.folder} ({ran})")
            return 1
        self.stopped_by = done.reason
        self.timings["experiments"] += time.perf_counter() - t
        used = done.exit_code == 0
        self.records.append(ExperimentRecord(exp, done.log, why, done.reason, used, design))
        self.say(f"experiment {k}: {exp.label}: {done.reason} in {time.perf_counter() - t:.1f} s"
                 + ("" if used else ", NOT USED (stopped early)") + f"; log {done.log}")
        if used and not any(r.used for r in self.records[:-1]):
            self.command = command_quantization(read_log(done.log))  # how this device turns v into counts
        return done.exit_code if done.exit_code in (130, 143) else None

    def diagnose(self, names: Sequence[str]):
        """Diagnose every completed run (None when fewer than two)."""
        runs = [str(r.log) for r in self.records if r.used]
        if len(runs) < 2:
            return None
        self.diagnoses += 1
        n = self.diagnoses
        self.say(f"diagnosis {n}: {len(runs)} runs, {len(names)} candidate effects")
        t = time.perf_counter()
        diag = diagnose(runs, model=self.base, candidates=names, likelihood_values=False,
                        progress=lambda msg: self.say(f"diagnosis {n}: {msg}"))
        self.timings["diagnosis"] += time.perf_counter() - t
        return diag

    def design(self, rv, candidates: Sequence[Experiment]) -> Design:
        """The next experiment (:func:`station.diagnosis.identify.design.choose_experiment`)."""
        t = time.perf_counter()
        self.say(f"design: {len(rv.rivals)} rival(s) of {rv.label} ({'; '.join(rv.sources)}): "
                 + ", ".join(r.label for r in rv.rivals))
        design = choose_experiment(self.base, rv, candidates, self.command, self.soft_limit, self.limit)
        self.timings["design"] += time.perf_counter() - t
        self.say(f"design ({len(design.candidates)} candidates in {time.perf_counter() - t:.1f} s): {design.why}")
        return design

    def prefer(self, old, new):
        """The better supported of the current answer and a re-diagnosis (:func:`prefer`)."""
        t = time.perf_counter()
        runs = [str(r.log) for r in self.records if r.used]
        pref = prefer(old, new, runs, self.base)
        self.timings["diagnosis"] += time.perf_counter() - t
        if pref.note:
            self.say(f"diagnosis {self.diagnoses}: {pref.note}" + ("; kept the earlier diagnosis" if pref.keep_old else ""))
        if not pref.keep_old:
            return new
        self.kept.append(pref.note)
        model = self.base.with_effects(pref.values, name=f"{self.base.name} + {' + '.join(pref.values)}")
        kept = kept_diagnosis(old, new, pref, model, len(runs))
        self.say(f"diagnosis {self.diagnoses}: the kept explanation's 95 % intervals on all {len(runs)} runs: "
                 + (", ".join(f"{n} {iv.lo:.4g} .. {iv.hi:.4g}" for n, iv in pref.intervals.items()) or "none"))
        u = kept.unexplained
        self.say(f"diagnosis {self.diagnoses}: the kept explanation on all {len(runs)} runs, unexplained: "
                 + ("no" if u is None or not u.flag else u.evidence))
        return kept

    def contest(self, diag, met: Sequence[Explanation]):
        """The answer with every explanation met so far that the answer does not pay over among
        its alternatives (:func:`station.diagnosis.identify.prefer.contest`); the rest forgotten."""
        t = time.perf_counter()
        runs = [str(r.log) for r in self.records if r.used]
        found = contest(diag, [*self.open, *met], runs, self.base)
        self.timings["diagnosis"] += time.perf_counter() - t
        self.open = found.open
        for line in found.settled:
            self.say(f"diagnosis {self.diagnoses}: settled by the runs: {line}")
        if not found.alternatives:
            return diag
        self.say(f"diagnosis {self.diagnoses}: still fitting all {len(runs)} runs as well (kept as alternatives): "
                 + "; ".join(f"{describe(a.values)} (cost ×{a.cost_ratio:.3f})" for a in found.alternatives))
        return replace(diag, alternatives=list(diag.alternatives) + found.alternatives)

    def result(self, diag, stopped: str, budget: int, code: int) -> Identification:
        self.timings["total"] = time.perf_counter() - self.t0
        self.say(f"done: {stopped}")
        model = diag.extended_model if diag is not None else None  # the record the table prints
        return Identification(diag, self.records, stopped, budget, self.diagnoses, dict(self.timings), code,
                              list(self.kept), model)
