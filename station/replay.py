"""Replay a logged run: re-run its controller on the logged samples, prove it reproduces
the logged commands, and overlay the FEM model's prediction (``station replay``).

What the log was (its controller, named or inferred; the alignment d of DESIGN.md "Timing
and log rows", detected from the data; closed or open loop; its reference; a hub-held beam
test) is :class:`station.logged.LoggedRun`'s to say. This module turns it into a
:class:`ReplayReport` (the model's fit, or the beam's first mode for a hub-held test) and
its text.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from station.analysis.beam import BeamTestReport, analyze_beam_test, model_first_mode
from station.analysis.metrics import StepMetrics
from station.analysis.design_doubt import alternatives_phrase, span_phrase
from station.control.compensator import STORED, on_integer
from station.errors import StationError
from station.logged import REPRODUCED_TOLERANCE, LoggedRun
from station.logged.audit import Audit
from station.logged.reference import Reference
from station.logged.reproduction import reproduction_lines
from station.runlog import RunLog



SOURCE_WORDS = {"header": "named by the log", "inferred": "inferred from the data",
                "inferred (header contradicted)": "inferred from the data: the log's header is contradicted"}
"""How a report words each ``controller_source``."""


@dataclass
class ReplayReport:
    """Outcome of :func:`replay`.

    Attributes
    ----------
    file : str
    format : {"station", "rig"}
    controller : str or None
        "p", "lead", "lead-accel", "open-loop", a compensator name, or None when the log
        does not name its controller (model only).
    controller_spec : dict or None
        The controller that was replayed (``Compensator.spec``).
    alignment : int or None
        Detected computational delay d, samples (None: open loop or not replayed).
    samples : int
    max_abs_dv : float or None
        max |v_replayed - v_logged|, DAC counts, over the rows judged.
    judged_to : int or None
        The row where n jumps past which the controller could not be judged (its memory is
        not in the log: :attr:`station.logged.controller.ControllerId.judged_to`);
        ``max_abs_dv`` is over the rows before it. None: every row judged.
    metrics : StepMetrics or None
        Of the logged theta against the step's amplitude, for closed-loop step logs.
    reference : station.logged.reference.Reference
        What the logged u is (reads as its JSON dict too: ``{"kind": "step", "amplitude",
        "tick"}``, ``{"kind": "zero"}``, ``{"kind": "missing"}`` or ``{"kind": "other"}``).
    fit_pct : dict or None
        NRMSE fit (percent) of the model's theta and a to the logged ones (None when no
        model ran, or the model cannot represent the test, e.g. a hub-held beam test).
    n_elements : int or None
        FEM element count of the model that ran (None when none did).
    notes : list of str
        What was assumed or could not be done.
    controller_source : {"header", "inferred", "inferred (header contradicted)"} or None
        Where the replayed controller came from
        (:func:`station.logged.controller.identify_controller`).
    audit : station.logged.audit.Audit or None
        Every claim of the log checked against its data (DESIGN.md "Log audit").
    layout : str
        The file's layout (:attr:`station.runlog.RunLog.layout`).
    sample_time : float or None
        Sample time found in the log, s.
    beam_test : station.analysis.beam.BeamTestReport or None
        First mode of a hub-held beam test (None for other runs).
    outcome : dict or None
        The log's end record (DESIGN.md "Run outcome"); None when it has none.
    v_replayed, prediction : numpy arrays (not in the JSON)
        The replayed commands, shape (N,); the model's ``simulate`` output (t, u, v,
        theta, a, theta_d_hat).
    log : RunLog (not in the JSON)
        The log that was replayed.
    run : station.logged.LoggedRun (not in the JSON)
        What the log was (controller, alignment, reference, hub held, ...).
    doubt : str (not in the JSON: its notes say it)
        What the data point at about the sensors but do not decide, beside the model's fit
        (:attr:`station.logged.simulate.ModelRun.doubt`); "" when nothing.
    """

    file: str
    format: str
    controller: str | None
    controller_spec: dict[str, Any] | None
    alignment: int | None
    samples: int
    max_abs_dv: float | None
    metrics: StepMetrics | None
    reference: Reference
    fit_pct: dict[str, float | None] | None = None
    n_elements: int | None = None
    notes: list[str] = field(default_factory=list)
    controller_source: str | None = None
    layout: str = ""
    sample_time: float | None = None
    beam_test: BeamTestReport | None = None
    outcome: dict[str, Any] | None = None
    audit: Audit | None = None
    judged_to: int | None = None
    v_replayed: np.ndarray | None = field(default=None, repr=False)
    prediction: dict[str, np.ndarray] | None = field(default=None, repr=False)
    log: RunLog | None = field(default=None, repr=False)
    run: LoggedRun | None = field(default=None, repr=False)
    doubt: str = ""

    @property
    def reproduced(self) -> bool | None:
        """True when the replay reproduces the logged v within ``REPRODUCED_TOLERANCE``; None
        when nothing was judged (no replay, or a law with memory on rows that skip ticks:
        :attr:`judged_to` 0)."""
        if self.max_abs_dv is None or self.judged_to == 0:
            return None
        return self.max_abs_dv <= REPRODUCED_TOLERANCE

    def to_json(self) -> dict[str, Any]:
        """The report as JSON-able dict (``station replay --json``).

        Keys: file, format, layout, sample_time_s, controller, controller_source
        ("header" | "inferred" | "inferred (header contradicted)" | null), audit (DESIGN.md
        "Log audit": [{claim, header, data, verdict, evidence}]), controller_spec, alignment, samples, max_abs_dv,
        judged_to_row, reproduced, reference, metrics {overshoot_pct, settling_thesis_s} (nulls when not a
        closed-loop step), model {fit_pct {theta, accel}, n_elements} or null, beam_test
        {f1_hz, f1_hz_std, zeta1, zeta1_std, f1_model_hz, zeta1_model, ...} or null,
        outcome, notes.
        """
        m = self.metrics
        return {
            "file": self.file,
            "format": self.format,
            "layout": self.layout,
            "sample_time_s": self.sample_time,
            "controller": self.controller,
            "controller_source": self.controller_source,
            "audit": [] if self.audit is None else self.audit.to_json(),
            "controller_spec": self.controller_spec,
            "alignment": self.alignment,
            "samples": self.samples,
            "max_abs_dv": self.max_abs_dv,
            "judged_to_row": self.judged_to,
            "reproduced": self.reproduced,
            "reference": self.reference.to_json(),
            "metrics": {"overshoot_pct": None, "settling_thesis_s": None} if m is None else m.to_json(),
            "model": None if self.fit_pct is None else {"fit_pct": dict(self.fit_pct),
                                                        "n_elements": self.n_elements},
            "beam_test": None if self.beam_test is None else self.beam_test.to_json(),
            "outcome": self.outcome,
            "notes": list(self.notes),
        }


def replay(path: str | Path, model=True, n_elements: int | None = None) -> ReplayReport:
    """Replay a run log.

    Parameters
    ----------
    path : str or Path
        A run log, ours or the rig's.
    model : bool, Model, str or Path
        Also run a model on the same reference (closed loop, with the log's controller
        and alignment) or the logged v (open loop) and report the NRMSE fit of theta and
        a: True for the nominal "tmm-fit", a :class:`station.plant.model.Model`, or a
        built-in model's name or model file; False: no model.
    n_elements : int, optional
        Beam elements of the model (default: the model's own, 4 for tmm-fit).

    Returns
    -------
    ReplayReport

    Raises
    ------
    station.runlog.RunLogError
        The log cannot be read.
    StationError
        Our log's controller spec is malformed, the model cannot be read,
        ``n_elements`` is out of the model's range, or the log lacks a column the replay
        or the model needs (:meth:`station.logged.LoggedRun.check_columns`).
    """
    run = LoggedRun.from_path(path)
    log = run.log
    report = ReplayReport(file=str(path), format=log.format, controller=None, controller_spec=None,
                          alignment=None, samples=len(run), max_abs_dv=None, metrics=None, reference=run.reference,
                          notes=list(log.notes) + run.notes, log=log, layout=log.layout,
                          sample_time=log.sample_time, outcome=log.outcome, run=run)
    if run.replayed is not None:  # else the identification's notes say why
        controller = run.controller
        report.controller, report.controller_spec = controller.name, controller.spec
        report.controller_source = run.source
        report.max_abs_dv, report.v_replayed = run.max_abs_dv, run.replayed.v_replayed
        report.judged_to = run.identified.judged_to
        report.alignment = run.alignment
        if not run.closed:
            report.notes.append("open loop: v = u")
        else:
            if run.header_alignment is not None and run.header_alignment != run.alignment:
                report.notes.append(f"header says alignment {run.header_alignment}, the data say {run.alignment}")
            if not run.reproduced and report.judged_to != 0:  # 0: not judged (reproduction_lines says)
                report.notes.append(f"the replay does NOT reproduce the logged v (max |dv| = "
                                    f"{report.max_abs_dv:.3g} counts)")
            report.metrics = run.step_metrics()
    if not len(run):
        report.notes.append("the log has no rows")
    report.audit = run.audit
    want_model = model is not False and model is not None
    if want_model and run.held is None and len(run):
        run.check_columns(run.simulated_columns, "simulating it on a model (--no-model: the commands only)")
    if want_model or run.held is not None:
        from station.plant.model import as_model  # lazy: start-up time (the FEM, loaded only when a model runs)

        the_model = as_model(None if model is True or not want_model else model, n_elements)
        report.audit = run.audit_for(the_model)  # the sensors' values the model simulates with
    if run.held is not None:
        _beam_test(report, run, the_model)
    elif want_model and len(run):
        _model(report, run, the_model)
    return report


def _tick_of_row(log: RunLog | None, row: int, row_said: bool = True) -> str:
    """"tick K" of a log's row: its n there, and the row beside it where rows skip ticks (a log
    of every other tick steps at row 25, the device's tick 50) unless not ``row_said``."""
    n = None if log is None or row >= len(log.data["n"]) else log.data["n"][row]
    if n is None or not np.isfinite(n) or n == row or n != round(n):
        return f"tick {row}"
    return f"tick {int(n)} (row {row})" if row_said else f"tick {int(n)}"


def _model(report: ReplayReport, run: LoggedRun, model) -> None:
    """The model run as the rig ran the log, and its fit."""
    sim = run.simulate(model)
    if not run.closed and run.data["theta"][0] != 0:
        report.notes.append("open loop: logged theta compared relative to its first sample")
    report.prediction, report.doubt = sim.prediction, sim.doubt
    report.n_elements = model.n_elements
    report.fit_pct = fits = sim.fit_pct
    if not run.has_column("a"):
        report.notes.append("the log has no a column: the model's θ alone is fitted (no sensor audit of a)")
    part = sim.parting
    if part is not None and part.t_follow is not None and not part.followed:
        report.notes.append(part.line())
    elif fits["theta"] is not None and fits["theta"] < -100.0:
        why = "" if part is None else f": {part.line()}"
        report.notes.append(f"the model's theta diverges from the log (fit {fits['theta']:.3g} %){why}")
    effects = ", ".join(f"{k} = {v:g}" for k, v in model.effects) or "no effects"
    report.notes.append(f"model: {model.name} (FEM plant, {model.n_elements} elements, {effects}), "
                        f"driven by {sim.how}")


def _beam_test(report: ReplayReport, run: LoggedRun, model) -> None:
    """A hub-held test: the beam's first mode instead of the motor model's fit."""
    measured = analyze_beam_test(run.data["t"], run.data["a"], run.dt)
    try:
        f_model, z_model = model_first_mode(model)
    except (ValueError, StationError) as exc:
        f_model = z_model = None
        report.notes.append(f"the model's hub-held first mode could not be computed ({exc})")
    report.beam_test = BeamTestReport(measured, run.held, f_model, z_model)
    report.notes.append(f"{run.held_note}; the beam's free vibration after the release is analyzed instead")
    if (departure := report.beam_test.departure()) is not None:
        report.notes.append(f"beam test: {departure}")
    report.notes.extend(f"beam test: {note}" for note in measured.notes)


NOT_TIP = "a is no tip acceleration: the audit"
"""Beside a's fit wherever it is printed (replay, survey) when the log audit found the a channel
no tip acceleration (a fit far below zero is then no model error)."""


def format_report(report: ReplayReport) -> str:
    """A readable summary of a replay (what ``station replay`` prints).

    Parameters
    ----------
    report : ReplayReport

    Returns
    -------
    str
        Several lines: first each claim of the log its data contradicted (``header: ...;
        data: ...``, DESIGN.md "Log audit"), then file, format, sample time, controller and
        its source, replay verdict with max |dv| (DAC counts) and alignment, reference,
        overshoot / settling time, NRMSE fits or the beam test, outcome, notes.
    """
    layout = f" ({report.layout})" if report.layout and report.layout != report.format else ""
    dt = "" if report.sample_time is None else f", sample time {report.sample_time:g} s"
    lines = [] if report.audit is None else report.audit.lines()
    lines += [f"{report.file}", f"  format {report.format}{layout}, {report.samples} samples{dt}"]
    if report.controller is None:
        lines.append("  controller: none replayed (see the notes)")
    else:
        source = SOURCE_WORDS.get(report.controller_source, "")
        design = (report.controller_spec or {}).get("design") or {}
        alts = [(d["text"], d["method"], d.get("recursion", "")) for d in design.get("alternatives", ())]
        own = (report.controller_spec or {}).get("recursion", "")
        if own in STORED and any(r for _, _, r in alts):  # beside laws on the other integer: its own said
            source = "; ".join(filter(None, (source, on_integer(own))))
        spec = report.controller_spec or {}
        name = f"P, kp = {spec['kp']:g}" if spec.get("kind") == "p" and "kp" in spec else report.controller
        lines.append(f"  controller: {name}" + (f" ({source})" if source else "")
                     + alternatives_phrase(alts, design.get("method", ""), design.get("more_alternatives", 0))
                     + span_phrase(design))
    if report.max_abs_dv is not None:
        lines += ["  " + line for line in reproduction_lines(report.max_abs_dv, report.alignment, report.audit,
                                                             report.judged_to)]
    ref = report.reference
    if ref.is_step:
        first = _tick_of_row(report.log, 0, row_said=False)  # u at its level from the first row: a cut copy
        lines.append(f"  reference: step of {ref.height:g}{ref.held_words} at {_tick_of_row(report.log, ref.step_tick)}"
                     if ref.step_tick else
                     f"  reference: u = {ref.amplitude:g} from the first row ({first}): the step is at or before it")
    if report.metrics is not None:
        lines.append(f"  {report.metrics.summary()}")
    if report.fit_pct is not None:
        f = report.fit_pct
        fmt = lambda x: "n/a" if x is None else f"{x:.1f} %"  # noqa: E731
        why = "" if report.audit is None or report.audit.accel_is_tip else f" ({NOT_TIP})"
        lines.append(f"  model fit (NRMSE): theta {fmt(f['theta'])}, accel {fmt(f['accel'])}{why}")
    if report.beam_test is not None:
        lines.extend("  " + line for line in format_beam_test(report.beam_test))
    if report.outcome is not None:
        lines.append(f"  outcome: {report.outcome.get('reason', '?')}")
    for note in report.notes:
        lines.append(f"  note: {note}")
    return "\n".join(lines)


def format_beam_test(bt: BeamTestReport) -> list[str]:
    """Lines for a hub-held beam test: measured first mode (fit and log decrement, ± one
    standard error) beside the model's.

    Parameters
    ----------
    bt : BeamTestReport
        :attr:`ReplayReport.beam_test`.
    """
    m = bt.measured
    pm = lambda x, sd, f: "n/a" if x is None else f"{x:{f}}" + ("" if sd is None else f" ± {sd:.2g}")  # noqa: E731
    out = [f"beam test (hub held): first mode {pm(m.f1_hz, m.f1_hz_std, '.3f')} Hz, "
           f"zeta {pm(m.zeta1, m.zeta1_std, '.4f')} (damped-sine fit, 1-5 Hz band)"]
    if m.f1_logdec_hz is not None:
        out.append(f"  log decrement: {pm(m.f1_logdec_hz, m.f1_logdec_hz_std, '.3f')} Hz, "
                   f"zeta {pm(m.zeta1_logdec, m.zeta1_logdec_std, '.4f')}")
    if bt.f1_model_hz is not None:
        out.append(f"  model (hub held): {bt.f1_model_hz:.3f} Hz, zeta {bt.zeta1_model:.4f}")
    return out
