"""Replay a logged run: re-run its controller on the logged samples, prove it reproduces
the logged commands, and overlay the FEM model's prediction.

DESIGN.md "Compensators" and "Timing and log rows": v[k] = C(u[k], theta[k-d], a[k-d]) with
the alignment d in {0, 1} detected from the data (the rig's 2009 logs d = 0, its later
logs and protocol v1 d = 1). The rig's headers print the compensators' z coefficients to
8 decimals; when they equal the Tustin coefficients of the known continuous designs to
the printed digits, the unrounded designs are used (the printed Ga alone replays the
accelerometer run only to 0.03 counts).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from station.analysis.metrics import StepMetrics, step_metrics
from station.control import (
    Compensator,
    DiscreteTF,
    OpenLoop,
    controller_from_spec,
    lead_controller,
    p_controller,
)
from station.analysis.beam import (
    HELD_MIN_V,
    BeamTestReport,
    HubHeld,
    analyze_beam_test,
    hub_held,
    model_first_mode,
)
from station.errors import StationError
from station.modelrun import ModelRun, command_quantization, simulate_log  # noqa: F401 (moved; re-exported)
from station.reference import classify_reference  # one definition of a step (also for compare, diagnosis)
from station.runlog import RIG_DT, RunLog, read_log

ALIGNMENTS = (0, 1)
"""Computational delays replay tries, samples."""

RIG_LIMIT = 200.0
"""The rig software's clamp of v, DAC counts (DESIGN.md)."""

PRINTED_TOLERANCE = 5.0001e-9
"""Largest difference between a coefficient and its 8-decimal print (half a unit in the 8th place)."""

REPRODUCED_TOLERANCE = 1e-6
"""max |v_replayed - v_logged| (DAC counts) under which a replay counts as reproducing the log."""


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
        max |v_replayed - v_logged|, DAC counts.
    metrics : StepMetrics or None
        Of the logged theta with u_final = the last u, for closed-loop step logs.
    reference : dict
        What the logged u is: ``{"kind": "step", "amplitude", "tick"}``, ``{"kind": "zero"}``
        or ``{"kind": "other"}``.
    fit_pct : dict or None
        NRMSE fit (percent) of the model's theta and a to the logged ones (None when no
        model ran, or the model cannot represent the test, e.g. a hub-held beam test).
    n_elements : int or None
        FEM element count of the model that ran (None when none did).
    notes : list of str
        What was assumed or could not be done.
    controller_source : {"header", "inferred"} or None
        Where the replayed controller came from (:func:`identify_controller`).
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
    """

    file: str
    format: str
    controller: str | None
    controller_spec: dict[str, Any] | None
    alignment: int | None
    samples: int
    max_abs_dv: float | None
    metrics: StepMetrics | None
    reference: dict[str, Any]
    fit_pct: dict[str, float | None] | None = None
    n_elements: int | None = None
    notes: list[str] = field(default_factory=list)
    controller_source: str | None = None
    layout: str = ""
    sample_time: float | None = None
    beam_test: BeamTestReport | None = None
    outcome: dict[str, Any] | None = None
    v_replayed: np.ndarray | None = field(default=None, repr=False)
    prediction: dict[str, np.ndarray] | None = field(default=None, repr=False)
    log: RunLog | None = field(default=None, repr=False)

    @property
    def reproduced(self) -> bool:
        """True when the replay reproduces the logged v within ``REPRODUCED_TOLERANCE``."""
        return self.max_abs_dv is not None and self.max_abs_dv <= REPRODUCED_TOLERANCE

    def to_json(self) -> dict[str, Any]:
        """The report as JSON-able dict (``station replay --json``).

        Keys: file, format, layout, sample_time_s, controller, controller_source
        ("header" | "inferred" | null), controller_spec, alignment, samples, max_abs_dv,
        reproduced, reference, metrics {overshoot_pct, settling_time_s} (nulls when not a
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
            "controller_spec": self.controller_spec,
            "alignment": self.alignment,
            "samples": self.samples,
            "max_abs_dv": self.max_abs_dv,
            "reproduced": self.reproduced if self.max_abs_dv is not None else None,
            "reference": self.reference,
            "metrics": {"overshoot_pct": None if m is None else m.overshoot_pct,
                        "settling_time_s": None if m is None else m.settling_time_s},
            "model": None if self.fit_pct is None else {"fit_pct": dict(self.fit_pct),
                                                        "n_elements": self.n_elements},
            "beam_test": None if self.beam_test is None else self.beam_test.to_json(),
            "outcome": self.outcome,
            "notes": list(self.notes),
        }


# --- which controller ran ---------------------------------------------------------------

def _matches_printed(printed: list[float], exact: np.ndarray) -> bool:
    return len(printed) == exact.size and bool(np.all(np.abs(np.asarray(printed) - exact) <= PRINTED_TOLERANCE))


def _rig_stage(meta: dict, key: str, design: DiscreteTF, notes: list[str]) -> tuple[DiscreteTF | None, bool]:
    """The filter printed in a rig header: the exact design when it matches, else as printed."""
    coeffs = meta.get(key)
    if not coeffs or not coeffs.get("num"):
        return None, True
    num, den = coeffs.get("num", []), coeffs.get("den", [])
    if _matches_printed(num, design.num) and _matches_printed(den, design.den):
        return design, True
    notes.append(f"{key} coefficients as printed in the header (8 decimals; not a known design)")
    try:
        return DiscreteTF(num, den), False
    except ValueError as exc:
        raise StationError(f"header {key} num={num} den={den}: {exc}") from None


def _header_number(meta: dict[str, Any], key: str) -> float:
    """A gain of a rig header (0 when absent); StationError naming the field when not a number."""
    value = meta.get(key, 0.0)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise StationError(f"{key}: expected a number, got {value!r}", key=key)
    return float(value)


def rig_controller(meta: dict[str, Any], dt: float = 0.002) -> tuple[Compensator | OpenLoop | None, list[str]]:
    """The controller a rig log's header names.

    Parameters
    ----------
    meta : dict
        ``RunLog.meta`` of a rig log (see :func:`station.runlog.read_log`).
    dt : float
        Sample time, s.

    Returns
    -------
    controller : Compensator, OpenLoop or None
        P_control (kp) and PID_control with ki = kd = 0 -> P; Motor_Comp with Gth (and Ga)
        -> lead / lead-accel (exact designs when the printed coefficients match them);
        OL_Test -> open loop; None when the header does not say.
    notes : list of str
    """
    notes: list[str] = []
    test = str(meta.get("test", ""))
    if "Gth" in meta:
        ref = lead_controller(RIG_LIMIT, dt, accel=True)
        gth, gth_known = _rig_stage(meta, "Gth", ref.gth, notes)
        if gth is None:
            return None, [f"header has an empty Gth ({test}): controller unknown"]
        ga, ga_known = _rig_stage(meta, "Ga", ref.ga, notes)
        known = gth_known and ga_known
        name = ("lead-accel" if ga is not None else "lead") if known else "rig-printed"
        spec = {"kind": name, "name": name, "dt": dt, "limit": RIG_LIMIT, "source": "rig header",
                "gth": {"num_z": gth.num.tolist(), "den_z": gth.den.tolist()},
                "ga": None if ga is None else {"num_z": ga.num.tolist(), "den_z": ga.den.tolist()}}
        if known:
            notes.append("printed coefficients equal the Tustin designs to their 8 decimals: unrounded designs used")
        return Compensator(gth, ga, limit=RIG_LIMIT, name=name, spec=spec), notes
    if "kp" in meta:
        kp, ki, kd = (_header_number(meta, key) for key in ("kp", "ki", "kd"))
        if ki != 0.0 or kd != 0.0:  # how the rig discretized it: the data decide (identify_controller)
            return None, []
        if "ki" in meta or "kd" in meta:
            notes.append("PID_control with ki = kd = 0: P control")
        return p_controller(kp, RIG_LIMIT, dt), notes
    if "OL" in test.split("_") or test.startswith("OL"):
        return OpenLoop(limit=None), notes
    return None, notes


class ControllerId(NamedTuple):
    """Which controller ran a log and where that came from (:func:`identify_controller`).

    Attributes
    ----------
    controller : Compensator, OpenLoop or None
        None when no controller is known: commands not replayed, the model driven by the
        logged v.
    source : {"header", "inferred"} or None
        "header": named by the log (including a PID header matched to a standard
        discretization); "inferred": identified from the data.
    notes : list of str
        One line each on what was assumed or could not be done.
    """

    controller: Compensator | OpenLoop | None
    source: str | None
    notes: list[str]


def log_controller(log: RunLog) -> tuple[Compensator | OpenLoop | None, list[str]]:
    """The controller that ran a log: named by its header, else identified from the data.

    Parameters
    ----------
    log : RunLog
        Ours (the header's ``controller`` spec) or the rig's (see :func:`rig_controller`).

    Returns
    -------
    controller : Compensator, OpenLoop or None
        None when the header names none and none reproduces the logged v
        (:func:`identify_controller`).
    notes : list of str
        What was assumed.

    Raises
    ------
    StationError
        Our header's controller spec is malformed, or a rig header's gain is not a
        number (naming the file and line).
    """
    cid = identify_controller(log)
    return cid.controller, cid.notes


def identify_controller(log: RunLog) -> ControllerId:
    """The controller that ran a log, and whether the header named it or the data did.

    Order: the header's controller; a PID header with ki or kd != 0 matched against the
    standard discretizations (:func:`station.analysis.identify.match_pid`); else a law
    identified from u, θ and v (:func:`station.analysis.identify.infer_controller`:
    open loop, P, linear e -> v up to order 3), accepted only when it reproduces every
    logged v to 1e-6 DAC counts. A rig log sampled at another rate than the rig's
    0.002 s cannot be replayed with a closed-loop controller (the rows it ran on are
    missing): one note says so and the model is driven by the logged v.

    Parameters
    ----------
    log : RunLog

    Returns
    -------
    ControllerId

    Raises
    ------
    StationError
        As :func:`log_controller`.
    """
    from station.analysis.identify import infer_controller, match_pid

    custom = _custom_controller(log)
    if custom is not None:  # a Python controller of the user's: its law is not in the log
        return ControllerId(None, None, [f"the log's controller is a custom Python controller ({custom}): its "
                                         f"commands cannot be replayed; the model is driven by the logged v"])
    controller, notes = _named_controller(log)
    dt = log.dt
    data = log.data
    u, theta, v, a = data["u"], data["theta"], data["v"], data["a"]
    if log.format == "rig" and abs(dt - RIG_DT) > 1e-9 and not isinstance(controller, OpenLoop):
        notes.append(f"sampled at {dt:g} s, not the rig's {RIG_DT:g} s: closed-loop commands cannot be "
                     f"replayed or inferred (the rig's controllers ran at {RIG_DT:g} s, on rows this log "
                     f"lacks); the model is driven by the logged v at {dt:g} s")
        return ControllerId(None, None, notes)
    if controller is not None:
        return ControllerId(controller, "header", notes)
    missing = [name for name in ("u", "theta", "v") if not np.all(np.isfinite(data[name]))]
    pid = _header_pid(log)
    if pid is not None and not missing:
        hit, best = match_pid(*pid, u, theta, v, a, dt, RIG_LIMIT)
        gains = f"kp = {pid[0]:g}, ki = {pid[1]:g}, kd = {pid[2]:g}"
        if hit is not None:
            notes.append(f"PID header ({gains}) replayed with the {hit.law}")
            return ControllerId(hit.controller, "header", notes)
        notes.append(f"PID header ({gains}): no standard discretization (integral by backward Euler, "
                     f"forward Euler or Tustin; derivative by backward difference) reproduces the logged v "
                     f"(best max |dv| = {best:.3g} counts)")
    elif pid is not None:
        notes.append(f"PID header, but the log has no usable {', '.join(missing)}: commands not replayed")
    if missing:
        if pid is None:
            notes.append(f"the log names no controller and has no usable {', '.join(missing)} column to "
                         f"infer one from: commands not replayed, model driven by the logged v")
        return ControllerId(None, None, notes)
    hit = infer_controller(u, theta, v, a, dt, RIG_LIMIT)
    if hit is not None:
        notes.append(f"controller inferred from the data: {hit.law}, alignment {hit.alignment} "
                     f"(reproduces the logged v to {hit.max_abs_dv:.2g} counts)")
        return ControllerId(hit.controller, "inferred", notes)
    if pid is None:
        notes.append("the log names no controller and none could be inferred from the data (open loop, "
                     "P, linear e -> v up to order 3): commands not replayed, model driven by the logged v")
    return ControllerId(None, None, notes)


def _header_pid(log: RunLog) -> tuple[float, float, float] | None:
    """(kp, ki, kd) of a rig header whose PID has ki or kd != 0, else None."""
    meta = log.meta
    if log.format != "rig" or "kp" not in meta:
        return None
    try:
        kp, ki, kd = (_header_number(meta, key) for key in ("kp", "ki", "kd"))
    except StationError:
        return None
    return (kp, ki, kd) if (ki != 0.0 or kd != 0.0) else None


def _custom_controller(log: RunLog) -> str | None:
    """The name of a custom Python controller our log's header records (a spec with
    neither coefficients nor open loop, e.g. ``{"kind": "custom"}``), else None."""
    spec = log.meta.get("controller") if log.format == "station" else None
    if not isinstance(spec, dict) or spec.get("kind") == "open-loop" or "gth" in spec:
        return None
    return str(spec.get("name") or spec.get("kind") or "unnamed")


def _named_controller(log: RunLog) -> tuple[Compensator | OpenLoop | None, list[str]]:
    """The controller the log's header names (None when it names none)."""
    if log.format == "station":
        spec = log.meta.get("controller")
        if not isinstance(spec, dict):
            return None, []
        return controller_from_spec(spec), []
    dt = log.dt
    try:
        return rig_controller(log.meta, dt)
    except StationError as exc:  # a header field: name the file and its line
        key = exc.key
        line = None if key is None else next((i for i, text in enumerate(log.header, 1)
                                              if text[1:].strip().startswith(key) and "=" in text), None)
        where = f"{log.path}: line {line}" if line else str(log.path)
        raise StationError(f"{where}: {exc}", file=log.path, line=line, key=key) from None


# --- replaying the commands -------------------------------------------------------------

def replay_commands(controller: Compensator | OpenLoop, u, theta, a, alignment: int) -> tuple[np.ndarray, np.ndarray]:
    """Run a controller over logged samples: v[k] = C(u[k], theta[k-d], a[k-d]).

    Before the first sample (k < d) there is nothing to compute from: v[k] = 0 and
    theta_d_hat[k] = u[k], and the controller is not stepped (as :func:`station.loop.run_loop`
    and the device do: tick 0 outputs 0; the rig's logs start with v[0] = 0).

    Parameters
    ----------
    controller : Compensator or OpenLoop
        Reset before the run.
    u : array_like, shape (N,)
        Reference, encoder counts (DAC counts in open loop).
    theta, a : array_like, shape (N,)
        Logged encoder and accelerometer counts.
    alignment : int
        d >= 0, samples.

    Returns
    -------
    v, theta_d_hat : numpy.ndarray, shape (N,)
    """
    d = int(alignment)
    if d < 0:
        raise ValueError(f"alignment must be >= 0, got {alignment}")
    u = np.asarray(u, dtype=float)
    n = u.size
    theta = np.asarray(theta, dtype=float)
    a = np.asarray(a, dtype=float)
    v_out = np.zeros(n)
    hat_out = u.copy()  # k < d: theta_d_hat = u
    controller.reset()
    step = controller.step
    # in blocks: Python floats for speed, without a list per sample of a 100 MB log at once
    for lo in range(min(d, n), n, _BLOCK):
        hi = min(n, lo + _BLOCK)
        uu, th, ac = u[lo:hi].tolist(), theta[lo - d:hi - d].tolist(), a[lo - d:hi - d].tolist()
        out = [step(x, y, z) for x, y, z in zip(uu, th, ac)]
        block = np.array(out, dtype=float).reshape(hi - lo, 2)
        v_out[lo:hi], hat_out[lo:hi] = block[:, 0], block[:, 1]
    controller.reset()
    return v_out, hat_out


_BLOCK = 1 << 16
"""Samples per block of :func:`replay_commands`."""


def detect_alignment(controller: Compensator | OpenLoop, u, theta, a, v) -> tuple[int, float, np.ndarray]:
    """The computational delay d in :data:`ALIGNMENTS` with which ``controller`` best
    reproduces the logged commands ``v`` (DESIGN.md: headers do not say; the data do).

    Parameters
    ----------
    controller : Compensator or OpenLoop
    u, theta, a, v : array_like, shape (N,), N >= 1
        The log's reference, samples and commands.

    Returns
    -------
    d : int
        The best alignment (the smaller one on a tie).
    max_abs_dv : float
        max |v_replayed - v| with it, DAC counts.
    v_replayed : numpy.ndarray, shape (N,)
    """
    v = np.asarray(v, dtype=float)
    best = None
    for d in ALIGNMENTS:
        v_hat, _ = replay_commands(controller, u, theta, a, d)
        err = float(np.max(np.abs(v_hat - v)))
        if best is None or err < best[1]:
            best = (d, err, v_hat)
    return best


# --- the model --------------------------------------------------------------------------

def _model(report: ReplayReport, log: RunLog, controller, model) -> None:
    run = simulate_log(log, controller, report.alignment, model)
    if run.theta_measured is not log.data["theta"] and log.data["theta"][0] != 0:
        report.notes.append("open loop: logged theta compared relative to its first sample")
    report.prediction = run.prediction
    report.n_elements = n_elements = model.n_elements
    report.fit_pct = fits = run.fit_pct
    if fits["theta"] is not None and fits["theta"] < -100.0:
        report.notes.append(f"the model's theta diverges from the log (fit {fits['theta']:.3g} %): "
                            "was the logged v really applied (motor powered, no hold)?")
    effects = ", ".join(f"{k} = {v:g}" for k, v in model.effects) or "no effects"
    report.notes.append(f"model: {model.name} (FEM plant, {n_elements} elements, {effects}), driven by {run.how}")


# --- replay -----------------------------------------------------------------------------

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
        Our log's controller spec is malformed, the model cannot be read, or
        ``n_elements`` is out of the model's range.
    """
    log = read_log(path)
    data = log.data
    n = len(log)
    cid = identify_controller(log) if n else ControllerId(None, None, [])
    controller = cid.controller
    reference = classify_reference(data["u"])
    report = ReplayReport(file=str(path), format=log.format, controller=None, controller_spec=None,
                          alignment=None, samples=n, max_abs_dv=None, metrics=None, reference=reference,
                          notes=list(log.notes) + list(cid.notes), log=log, layout=log.layout,
                          sample_time=log.sample_time, outcome=log.outcome)
    held = hub_held(data["theta"], data["v"], log.dt) if n else None
    if controller is not None and n > 0:  # else identify_controller's notes say why
        report.controller = controller.name
        report.controller_spec = controller.spec
        report.controller_source = cid.source
        d, report.max_abs_dv, report.v_replayed = detect_alignment(controller, data["u"], data["theta"],
                                                                  data["a"], data["v"])
        if isinstance(controller, OpenLoop):
            # v = u: d only decides whether v[0] is u[0] (d = 0) or 0 (d = 1, no sample yet)
            report.notes.append("open loop: v = u")
        else:
            report.alignment = d
            logged_d = log.meta.get("alignment") if log.format == "station" else None
            if isinstance(logged_d, int) and logged_d != report.alignment:
                report.notes.append(f"header says alignment {logged_d}, the data say {report.alignment}")
            if not report.reproduced:
                report.notes.append(f"the replay does NOT reproduce the logged v (max |dv| = "
                                    f"{report.max_abs_dv:.3g} counts)")
            if reference["kind"] == "step":
                report.metrics = step_metrics(data["t"], data["theta"], data["u"][-1])
    if n == 0:
        report.notes.append("the log has no rows")
    want_model = model is not False and model is not None
    if want_model or held is not None:
        from station.plant.model import as_model

        the_model = as_model(None if model is True or not want_model else model, n_elements)
    if held is not None:
        _beam_test(report, log, held, the_model)
    elif want_model and n > 0:
        _model(report, log, controller, the_model)
    return report


def _beam_test(report: ReplayReport, log: RunLog, held: HubHeld, model) -> None:
    """A hub-held test: the beam's first mode instead of the motor model's fit."""
    data = log.data
    measured = analyze_beam_test(data["t"], data["a"], log.dt)
    try:
        f_model, z_model = model_first_mode(model)
    except (ValueError, StationError) as exc:
        f_model = z_model = None
        report.notes.append(f"the model's hub-held first mode could not be computed ({exc})")
    report.beam_test = BeamTestReport(measured, held, f_model, z_model)
    report.notes.append(f"hub-held beam test (theta within {held.theta_span:g} counts while |v| >= "
                        f"{HELD_MIN_V:g} for {held.duration_s:.1f} s): the logged v was not applied, so the "
                        f"motor model cannot represent this run and its fit is not computed; the beam's "
                        f"free vibration after the release is analyzed instead")
    report.notes.extend(f"beam test: {note}" for note in measured.notes)


def format_report(report: ReplayReport) -> str:
    """A readable summary of a replay (what ``station replay`` prints).

    Parameters
    ----------
    report : ReplayReport

    Returns
    -------
    str
        Several lines: file, format, sample time, controller and its source, replay
        verdict with max |dv| (DAC counts) and alignment, reference, overshoot / settling
        time, NRMSE fits or the beam test, outcome, notes.
    """
    layout = f" ({report.layout})" if report.layout and report.layout != report.format else ""
    dt = "" if report.sample_time is None else f", sample time {report.sample_time:g} s"
    lines = [f"{report.file}", f"  format {report.format}{layout}, {report.samples} samples{dt}"]
    if report.controller is None:
        lines.append("  controller: none replayed (see the notes)")
    else:
        source = {"header": "named by the log", "inferred": "inferred from the data"}.get(report.controller_source, "")
        lines.append(f"  controller: {report.controller}" + (f" ({source})" if source else ""))
    if report.max_abs_dv is not None:
        verdict = "reproduces" if report.reproduced else "does NOT reproduce"
        align = "" if report.alignment is None else f", alignment d = {report.alignment}"
        lines.append(f"  replay {verdict} the logged v: max |dv| = {report.max_abs_dv:.3g} counts{align}")
    ref = report.reference
    if ref["kind"] == "step":
        lines.append(f"  reference: step of {ref['amplitude']:g} at tick {ref['tick']}")
    if report.metrics is not None:
        m = report.metrics
        settle = "not settled" if m.settling_time_s is None else f"{m.settling_time_s:.3f} s"
        lines.append(f"  overshoot {m.overshoot_pct:.2f} %   settling time {settle}")
    if report.fit_pct is not None:
        f = report.fit_pct
        fmt = lambda x: "n/a" if x is None else f"{x:.1f} %"  # noqa: E731
        lines.append(f"  model fit (NRMSE): theta {fmt(f['theta'])}, accel {fmt(f['accel'])}")
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
