"""Model vs rig for logged runs: step metrics and NRMSE fits next to the thesis's table
(``station compare``).

Each log is simulated as the rig ran it (:meth:`station.logged.LoggedRun.simulate`): the
log's controller (named by its header, with the rig's ±200 clamp, or inferred), the log's
reference and the log's own alignment d, detected from the data as replay does (the rig's
later logs and protocol v1 have d = 1, its 2009 logs d = 0); an open-loop log is driven by
its logged v. A hub-held beam test is not simulated: the logged v was not applied, so the
motor model cannot represent it (``station replay`` analyzes the beam's first mode). Step
metrics use the thesis's definitions (station.analysis.metrics), fits the NRMSE fit
(station.analysis.fit).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from station.analysis.metrics import FROM_START, SETTLE_HOLD_S, THESIS_BAND_PCT, StepMetrics, settling_label
from station.control.designs import make_controller
from station.control.rerun import detect_alignment
from station.errors import StationError
from station.logged import LoggedRun
from station.logged.audit import Audit
from station.logged.reference import held_words
from station.logged.reproduction import reproduction_lines
from station.logged.run import REPRODUCED_TOLERANCE
from station.runlog.timebase import restart_rows, run_start
from station.plots import source_label
from station.rig import THESIS_STEPS  # the thesis rows are shown for those step logs only

THESIS_TABLE = {
    # controller: (experiment (overshoot %, settling s), thesis FEM (overshoot %, settling s));
    # settling None = "> 2 s" / not settled. DESIGN.md "Step metrics as the thesis reports them".
    "p": ((24.00, 1.250), (38.20, None)),
    "lead": ((10.00, None), (18.85, 1.980)),
    "lead-accel": ((21.50, 0.608), (20.74, 0.708)),
}

@dataclass
class RunComparison:
    """Model vs rig for one log.

    Attributes
    ----------
    file : str
    controller : str or None
        The log's controller name ("p", "lead", "lead-accel", "open-loop", ...).
    step : float or None
        Final reference (the step size), encoder counts; None when not a step.
    rig, model : StepMetrics or None
        Metrics of the logged θ (whatever the log's source) and of the simulated θ
        (None when not a step).
    thesis_experiment, thesis_fem : StepMetrics or None
        The thesis's table, for the thesis's own logs only (a rig log of a thesis
        controller with the thesis's step height).
    source : str
        Where the log comes from: "rig", "simulated" or "station" (:func:`station.plots.source_label`).
    outcome : dict or None
        The log's end record (None: a rig log, or a run killed before its end).
    fit_pct : dict
        NRMSE fit of the model's ``theta`` and ``accel`` to the log, percent (None each
        for a hub-held beam test: not simulated).
    data, prediction : dict of ndarray
        The log's columns and the simulation's output (t, u, v, theta, a, theta_d_hat);
        ``prediction`` is None for a hub-held beam test.
    notes : list of str
    controller_source : str or None
        Where the controller came from (DESIGN.md "Log audit": "header", "inferred",
        "inferred (header contradicted)").
    audit : station.logged.audit.Audit or None
        The log's claims checked against its data.
    step_time_s : float or None
        When the step starts, s from the log's t = 0 (the thesis's settling (1 %) counts from
        t = 0); None when not a step.
    step_from : float
        The level the step starts from, encoder counts (0 but for a step from a held position,
        :attr:`station.logged.reference.Reference.initial`).
    """

    file: str
    controller: str | None
    step: float | None
    rig: StepMetrics | None
    model: StepMetrics | None
    thesis_experiment: StepMetrics | None
    thesis_fem: StepMetrics | None
    fit_pct: dict
    data: dict = field(repr=False)
    prediction: dict | None = field(repr=False)
    notes: list = field(default_factory=list)
    source: str = "rig"
    outcome: dict | None = None
    controller_source: str | None = None
    audit: Audit | None = field(default=None, repr=False)
    step_time_s: float | None = None
    step_from: float = 0.0

    def to_json(self) -> dict:
        """JSON-able summary (metrics as {overshoot_pct, settling_thesis_s} or null). ``rig``
        holds the log's own metrics whatever its ``source`` (rig / simulated / station)."""
        j = lambda m: None if m is None else m.to_json()  # noqa: E731
        return {"file": self.file, "source": self.source, "outcome": self.outcome,
                "controller": self.controller, "controller_source": self.controller_source,
                "audit": [] if self.audit is None else self.audit.to_json(), "step": self.step,
                **({"step_from": self.step_from} if self.step_from else {}),
                "step_time_s": self.step_time_s, "rig": j(self.rig),
                "model": j(self.model), "thesis_experiment": j(self.thesis_experiment),
                "thesis_fem": j(self.thesis_fem), "fit_pct": dict(self.fit_pct), "notes": list(self.notes)}


def compare_run(path, plant) -> RunComparison:
    """Simulate a logged run on the model as the rig ran it and compare.

    Parameters
    ----------
    path : str or Path
        A run log (ours or the rig's), read with station.runlog.read_log.
    plant : station.plant.model.Model or station.plant.DiscretePlant
        The model (a Model is simulated at the log's sample time with its effects; a
        DiscretePlant's dt should be the log's, 0.002 s for the rig).

    Returns
    -------
    RunComparison

    Raises
    ------
    StationError
        Unreadable log, a log without rows, or one that lacks a column the simulation needs
        (:meth:`station.logged.LoggedRun.check_columns`). A log whose controller is not known
        is driven by its logged v, as replay does.
    """
    run = LoggedRun.from_path(path)
    log, data = run.log, run.data
    source = source_label(log)
    log.require_rows("compare")  # the log's own notes say why: no controller to ask for
    controller, notes = run.controller, run.notes
    name = "none" if controller is None else controller.name  # none: the model is driven by the logged v
    if run.closed:
        clamp = "no clamp" if controller.limit is None else f"clamp ±{controller.limit:g}"
        said = reproduction_lines(run.max_abs_dv, run.alignment, run.audit, run.identified.judged_to)
        notes.append(f"{said[0]}; {clamp}")
        notes.extend(said[1:])
    step = run.reference.amplitude if run.closed else None  # station.logged.reference: the one definition of a step
    tick = run.reference.step_tick
    step_time = (None if step is None or tick is None else
                 float(data["t"][tick] - data["t"][0]) + run_start(data["t"], data["n"], log.dt))
    if run.held is not None:
        notes.append(f"{run.held_note}; `station replay` analyzes the beam's free vibration after the release")
        return RunComparison(str(path), name, step, run.step_metrics(), None, None, None,
                             {"theta": None, "accel": None}, data, None, notes, source=source, outcome=log.outcome,
                             controller_source=run.source, audit=run.audit, step_time_s=step_time,
                             step_from=run.reference.initial)
    sim = run.simulate(plant)
    pred, fits = sim.prediction, sim.fit_pct
    notes.append(f"model: driven by {sim.how}")
    if sim.parting is not None and sim.parting.t_follow is not None and not sim.parting.followed:
        notes.append(sim.parting.line())
    rig = model = exp = fem = None
    if step is not None:
        rig = run.step_metrics()
        model = run.step_metrics(pred["theta"], pred["t"])
        case = thesis_case(run, step) if source == "rig" and not run.reference.initial else None
        if case is not None:
            (eo, es), (fo, fs) = THESIS_TABLE[case]
            exp, fem = StepMetrics(eo, es), StepMetrics(fo, fs)
    return RunComparison(str(path), name, step, rig, model, exp, fem, fits, data, pred, notes,
                         source=source, outcome=log.outcome, controller_source=run.source, audit=run.audit_for(plant),
                         step_time_s=step_time, step_from=run.reference.initial)


def thesis_case(run: LoggedRun, step: float | None) -> str | None:
    """The thesis experiment a log is (a key of :data:`THESIS_TABLE`), decided from its data:
    a step of that experiment's height (:data:`station.rig.THESIS_STEPS`) whose logged v the
    thesis's law (P kp = 2, the lead, the lead with Ga on a or -a; ±200 clamp) reproduces at an
    alignment, whatever the header named (the thesis's lead step under a header that says
    open loop is still that experiment; a P step at another kp is not).

    Parameters
    ----------
    run : LoggedRun
        A closed-loop log.
    step : float or None
        Its step's height, encoder counts (:attr:`station.logged.LoggedRun.reference`).

    Returns
    -------
    str or None
        "p", "lead" or "lead-accel"; None for any other log.
    """
    kind = next((k for k, height in THESIS_STEPS.items() if height == step), None)
    if kind is None or run.controller is None or not len(run):
        return None
    d = run.data  # a column of NaN where the log has none: a law that reads it reproduces nothing
    # the thesis's Ga on -a is that experiment too: an a column with the other sign than the loop fed back
    for a in (d["a"], -d["a"]) if kind == "lead-accel" else (d["a"],):
        fit = detect_alignment(make_controller(kind), d["u"], d["theta"], a, d["v"], skipped=run.skipped,
                               restarts=restart_rows(d["n"]))
        if fit.max_abs_dv <= REPRODUCED_TOLERANCE:
            return kind
    return None


def format_comparison(c: RunComparison) -> str:
    """The table ``station compare`` prints for one log.

    Parameters
    ----------
    c : RunComparison

    Returns
    -------
    str
        First each claim of the log its data contradicted (``NAME: header: ...; data:
        ...``), then rows rig / thesis experiment / thesis FEM / model with overshoot %,
        settling (1 %) s ("not settled" for None) and the model's NRMSE fits.
    """
    def fmt(m: StepMetrics | None) -> str:
        if m is None:
            return f"{'-':>12} {'-':>14}"
        s = "not settled" if m.settling_time_s is None else f"{m.settling_time_s:.3f}"  # within the run
        return f"{m.overshoot_pct:12.2f} {s:>14}"

    def pct(x):
        return "-" if x is None else f"{x:.1f}"

    outcome = "" if c.outcome is None else f", outcome {c.outcome.get('reason')}"
    lines = [] if c.audit is None else [f"{Path(c.file).name}: {line}" for line in c.audit.lines()]
    lines += [f"{Path(c.file).name} ({c.source} log): controller {c.controller}"
             + ("" if c.step is None else f", step {c.step - c.step_from:g} counts"
                + held_words(c.step_from)) + outcome,
             f"  {'':<20} {'overshoot %':>12} {settling_label(THESIS_BAND_PCT) + ' s':>14} {'fit θ %':>8} "
             f"{'fit a %':>8}",
             f"  {c.source + ' (this log)':<20} {fmt(c.rig)}"]
    if c.thesis_experiment is not None:
        lines += [f"  {'thesis experiment':<20} {fmt(c.thesis_experiment)}",
                  f"  {'thesis FEM':<20} {fmt(c.thesis_fem)}"]
    lines += [f"  {'model':<20} {fmt(c.model)} {pct(c.fit_pct['theta']):>8} {pct(c.fit_pct['accel']):>8}"]
    if c.rig is not None and c.step is not None:
        start = "" if c.step_time_s is None else f"; this log's step at {c.step_time_s:.3f} s"
        lines.append(f"  {settling_label(THESIS_BAND_PCT)} s: {FROM_START} of the log (the thesis's definition{start})")
    if c.rig is not None and (c.rig.settling_time_s is None or (c.model and c.model.settling_time_s is None)):
        lines.append(f"  not settled = outside the 1 % band at the run's end, or inside it for less than "
                     f"{SETTLE_HOLD_S:g} s (not settled within the run)")
    lines += [f"  note: {n}" for n in c.notes]
    return "\n".join(lines)
