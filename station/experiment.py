"""Step tests as a Python function: what ``station step`` runs, callable from a notebook.

A step test is planned once (:func:`station.plan.plan_step`: every setting settled and
checked before anything starts) and run by :func:`run_step`; ``station step`` builds the
same plan from its options. Example (in a notebook)::

    from station.experiment import run_step
    report = run_step(controller="p", amplitude=50)          # the built-in simulated rig
    report.metrics.overshoot_pct, report.log_path
"""

from __future__ import annotations

import datetime as _dt
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from station import __version__
from station.analysis.metrics import (FROM_START, NOT_SETTLED, THESIS_BAND_PCT, StepInfo, StepMetrics, settling_label,
                                      step_info, step_metrics)
from station.control.rerun import is_closed_loop
from station.errors import StationError
from station.link import open_session
from station.logged.reference import classify_reference
from station.loop import RunResult, run_loop
from station.outputs import is_device
from station.plots import plot_runs, run_title, save_figure
from station.progress import ProgressSink
from station.plan import (DEFAULT_CONTROLLER, DEFAULT_PORT, StepPlan, default_log_path, figure_path,  # noqa: F401
                          plan_step)
from station.rig import DEFAULT_AMPLITUDE, DEFAULT_SOFT_LIMIT, DEFAULT_STEP_TICK, DEFAULT_TIMEOUT  # noqa: F401
from station.runlog import RunLog, RunLogError, RunLogWriter, read_log
from station.runsetup import log_tag
from station.signals import StopSignals

WHOLE_COLUMNS = ("n", "status", "v_applied")
"""Columns :meth:`StepReport.to_pandas` gives as integers when every value is whole: the tick
and the status bits (integers in :class:`station.runlog.LogRow`) and the DAC counts the device
reports (NaN where it reports none, as on the legacy protocol: then they stay floats)."""

NOT_SETTLED_EITHER = "not settled either"
"""What the 2 % settling time says when the 1 % one has already said :data:`NOT_SETTLED`."""


@dataclass(repr=False)
class StepReport:
    """Outcome of one step test.

    Attributes
    ----------
    log_path : Path
        The run log.
    result : RunResult
        How the loop ended (``result.outcome``), with timing.
    metrics : StepMetrics or None
        Overshoot and settling time of the logged θ (None unless a closed-loop step run
        completed: a run cut short has no meaningful step metrics).
    info : StepInfo or None
        Rise, peak and 2 % settling times, steady-state error and time at the clamp
        (None when ``metrics`` is).
    figure_path : Path or None
        The run's figure (None when none was drawn).
    """

    log_path: Path
    result: RunResult
    metrics: StepMetrics | None
    info: StepInfo | None = None
    figure_path: Path | None = None

    def __repr__(self) -> str:
        """Paths, outcome, metrics and the latency summary (not the per-tick latencies)."""
        m, i, tm = self.metrics, self.info, self.result.timing()
        parts = [f"log_path={str(self.log_path)!r}", f"figure_path={None if self.figure_path is None else str(self.figure_path)!r}",
                 f"reason={self.result.reason!r}", f"ticks={self.result.ticks}"]
        if m is not None:
            parts += [f"overshoot_pct={m.overshoot_pct:.2f}", f"settling_time_s={m.settling_time_s}"]
        if i is not None:
            parts.append(f"settling_time_2pct_s={i.settling_time_2pct_s}")
        parts.append(f"latency_us=(p50 {tm.p50_us:.0f}, p99 {tm.p99_us:.0f}, max {tm.max_us:.0f})")
        return f"StepReport({', '.join(parts)})"

    def to_pandas(self):
        """The logged run as a :class:`pandas.DataFrame` (pandas is imported here, not with the
        package).

        Returns
        -------
        pandas.DataFrame
            One row per tick, the log's columns: floats, but ``n``, ``status`` and
            ``v_applied`` as int64 when every value is whole (:data:`WHOLE_COLUMNS`).
        """
        import pandas as pd  # lazy: start-up time (pandas)

        data = read_log(self.log_path).data
        return pd.DataFrame({name: _whole(col) if name in WHOLE_COLUMNS else col for name, col in data.items()})

    def plot(self):
        """The run's figure (θ and u, v and v_applied, a; outcome and metrics in the title).

        Returns
        -------
        matplotlib.figure.Figure
            No pyplot state: display it in a notebook or save it.
        """
        return _run_figure(read_log(self.log_path), self.metrics)

    def to_json(self) -> dict:
        """``{"log", "ok", "reason", "message", "outcome": {...}, "metrics": {...}, "timing": {...}}``
        (``station step --json``; ``outcome`` as DESIGN.md "Run outcome").

        Returns
        -------
        dict
            JSON-able; ``metrics`` holds ``overshoot_pct`` and ``settling_thesis_s`` (the 1 %
            band's, from t = 0), and :meth:`StepInfo.to_json`'s keys (``settling_2pct_s``
            after the step...), None where undefined: DESIGN.md's names, as ``station tune
            --json``'s.
        """
        m = self.metrics
        return {
            "log": str(self.log_path),
            "ok": self.result.ok,
            "reason": self.result.reason,
            "message": self.result.message,
            "outcome": self.result.outcome.to_json(),
            "metrics": {**({"overshoot_pct": None, "settling_thesis_s": None} if m is None else m.to_json()),
                        **(self.info.to_json() if self.info is not None else {})},
            "timing": self.result.timing().to_json(),
        }


def _whole(col: np.ndarray) -> np.ndarray:
    """``col`` as int64 when every value is a finite whole number, else as it is."""
    if np.all(np.isfinite(col)) and np.all(col == np.round(col)) and np.all(np.abs(col) < 2**53):
        return col.astype(np.int64)
    return col


def _plant_meta(port) -> dict | None:
    return getattr(port, "plant_meta", None)


def run_step(plan: StepPlan | None = None, *, sinks=(), progress: bool = False, announce=None,
             **settings) -> StepReport:
    """Run a step test on a device and log it: a :class:`~station.plan.StepPlan`, or the
    settings of one.

    Parameters
    ----------
    plan : StepPlan, optional
        What to run (:func:`station.plan.plan_step`). A plan is checked again against its
        outputs as the run starts: a log that exists by then (the plan already ran) needs
        the plan's ``force``.
    sinks : sequence
        Extra row sinks (e.g. :class:`station.viz.RerunSink`), fed off the hot path.
    progress : bool
        Show a live progress line on stderr (:class:`station.progress.ProgressSink`, fed off
        the hot path by the log's sink thread).
    announce : callable, optional
        Gets the run's start line once the device answered, before the run (the port, its
        adapter and latency timer, the protocol, ticks and controller: :func:`start_line`);
        ``station step`` prints it.
    **settings
        Without ``plan``: :func:`station.plan.plan_step`'s keywords (``port``, ``protocol``,
        ``controller``, ``amplitude``, ``duration``, ``step_time``, ``reference``, ``out``,
        ``model``, ``force``, ``figure``...), planned and checked exactly as ``station step``
        plans its options; a note (which clamp won) is a :class:`UserWarning`.

    Returns
    -------
    StepReport
        Also when the run was stopped by a fault or a signal; ``report.result.outcome``
        says why. The log ends with the outcome's end record. Its timing's ``setup_s``
        is the planning plus the time from this call to the first sample.

    Raises
    ------
    StationError
        Bad settings (:func:`station.plan.plan_step`), a port that cannot be opened or a
        device that does not answer (nothing was started then).
    station.signals.StopSignal
        SIGINT / SIGTERM before the run started (nothing was started then).

    Examples
    --------
    >>> import tempfile
    >>> from pathlib import Path
    >>> from station.experiment import run_step
    >>> folder = Path(tempfile.mkdtemp())
    >>> report = run_step(controller="p", amplitude=50, duration=0.6, out=folder / "p.tsv", figure=False)
    >>> report.result.reason, report.result.ticks
    ('completed', 300)
    >>> 35 < report.metrics.overshoot_pct < 45           # thesis FEM 38.2 %, plus one sample of delay
    True
    >>> df = report.to_pandas()
    >>> len(df), str(df["n"].dtype)
    (300, 'int64')
    """
    if plan is None:
        plan = plan_step(**settings)
    elif settings:
        raise StationError(f"run_step: a plan or its settings, not both (got {', '.join(sorted(settings))})")
    planned_at = time.perf_counter()
    plan.check_outputs()
    log_path = plan.log_path
    try:
        log_path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StationError(f"{log_path}: cannot create the run log's folder: {exc.strerror or exc}") from None
    ctrl, dt = plan.controller, plan.dt
    ctrl.reset()  # at rest, also when a plan runs again
    with StopSignals() as signals, open_session(plan.url, plan.protocol, baudrate=plan.baudrate,
                                                limits=plan.limits) as session:
        info = session.hello()
        accel_zero = session.zero_accel()
        link = getattr(session.port, "station_info", None)
        limits = plan.limits
        meta = {
            "station_version": __version__,
            "kind": "step",
            "controller": ctrl.spec,
            "reference": plan.reference_meta,
            "protocol": plan.protocol,
            "port": session.url,
            "device": info,
            "plant": _plant_meta(session.port),
            "alignment": session.alignment,
            "accel_zero": accel_zero,
            "dt": dt,
            "soft_limit": plan.soft_limit,
            "limit": plan.limit,
            "limits": {"timeout": limits.timeout, "max_lag_s": limits.max_lag, "max_miss": limits.max_miss,
                       "max_step": limits.max_step},
            "link": None if link is None else link.to_json(),  # the adapter and its latency timer
            "start_time": _dt.datetime.now(_dt.UTC).isoformat(),
            "start_unix": time.time(),
        }
        sinks = list(sinks)
        bar = None
        if progress:
            bar = ProgressSink(plan.duration)
            sinks.append(bar)
        try:
            writer = RunLogWriter(log_path, meta, sinks=sinks)
        except RunLogError:  # not even the header fits (a full disk): leave no part of a log
            if log_path.is_file():
                log_path.unlink()
            raise
        if announce is not None:
            announce(start_line(session, plan.n_ticks, dt, ctrl))
        result = None
        try:
            result = run_loop(session, ctrl, plan.u, writer, soft_limit=plan.soft_limit, dt=dt, lean=plan.lean,
                              limit=plan.limit, signals=signals)
        finally:
            # after the loop has sent command 0 and stop; signals are only recorded here
            writer.close(None if result is None else result.outcome.to_json())
            if bar is not None:
                bar.close()
    result.extra["setup_s"] = plan.planning_s + (result.extra["first_sample_at"] - planned_at)
    # step metrics compare θ with the step in encoder counts: closed-loop completed steps only
    # (a reference taken from a log is one when it is a step: station.logged.reference's definition)
    from_file = plan.amplitude is None  # a file's reference has no amplitude of ours
    wants_metrics = result.ok and is_closed_loop(plan.controller) and (plan.closed_step or from_file)
    log = _read_back(log_path) if (wants_metrics or plan.figure_path is not None) and not is_device(log_path) else None
    metrics, info = _metrics_of(log, plan) if wants_metrics and log is not None else (None, None)
    report = StepReport(log_path, result, metrics, info=info)
    if plan.figure_path is not None and log is not None:  # after command 0, STOP and the log's close
        report.figure_path = _write_figure(log, metrics, plan.figure_path)
    return report


def start_line(session, n_ticks: int, dt: float, controller) -> str:
    """The run's first line: what runs on which port, through which adapter and latency timer.

    Parameters
    ----------
    session : station.link.Session
        The open session (its port's ``station_info``, :class:`station.link.PortInfo`).
    n_ticks : int
        Ticks of the run.
    dt : float
        Sample time, s.
    controller : controller object
        Its ``spec`` names the kind.

    Returns
    -------
    str
        E.g. ``run: 1000 ticks (2 s), lead, protocol v1 on /dev/ttyUSB0 (FT232R USB UART,
        latency timer 1 ms)``.
    """
    info = getattr(session.port, "station_info", None)
    where = info.summary() if info is not None else session.url
    return (f"run: {n_ticks} ticks ({n_ticks * dt:g} s), {log_tag(controller)}, protocol {session.protocol} "
            f"on {where}")


def _read_back(log_path: Path) -> RunLog | None:
    """The run's log, read once after the run for the metrics and the figure; a warning (the
    log stays as it is) and None when it cannot be read."""
    try:
        return read_log(log_path)
    except RunLogError as exc:
        warnings.warn(f"{log_path}: the run log could not be read back ({exc}); no metrics, no figure",
                      RuntimeWarning, stacklevel=3)
        return None


def _run_figure(log: RunLog, metrics: StepMetrics | None):
    """The run's figure: :func:`station.plots.plot_runs` with the outcome and metrics in the title."""
    return plot_runs([log], title=run_title(log, "" if metrics is None else metrics.summary()))


def _write_figure(log: RunLog, metrics: StepMetrics | None, png: Path) -> Path | None:
    """``<log stem>.png`` beside the log; a warning (not an error) when it cannot be drawn."""
    try:
        save_figure(_run_figure(log, metrics), png)
    except Exception as exc:  # noqa: BLE001 - a figure must never cost the run's report
        warnings.warn(f"{png}: the run's figure was not written ({exc}); the log is complete",
                      RuntimeWarning, stacklevel=3)
        return None
    return png


def _metrics_of(log: RunLog, plan: StepPlan) -> tuple[StepMetrics | None, StepInfo | None]:
    """The run's step metrics: the planned step's, or, for a reference taken from a log, the step
    the run's u is (:func:`station.logged.reference.classify_reference`); None otherwise."""
    t, theta = log.data["t"], log.data["theta"]
    if t.size == 0:
        return None, None
    amplitude, step_time, initial = plan.amplitude, plan.step_time, 0.0
    if not plan.closed_step:
        ref = classify_reference(log.data["u"], float(theta[0]))
        if not ref.is_step or ref.step_tick >= t.size:
            return None, None
        amplitude, step_time, initial = ref.amplitude, float(t[ref.step_tick]), ref.initial
    return (step_metrics(t, theta, amplitude, initial),
            step_info(t, theta, amplitude, step_time, v=log.data["v"], limit=plan.limit, u_initial=initial))


def format_report(report: StepReport) -> str:
    """Human-readable summary: outcome, overshoot, settling times, timing, log path.

    Each settling time names its band (:func:`station.analysis.metrics.settling_label`); a
    run that settles in neither band says "not settled within the run" once.

    Parameters
    ----------
    report : StepReport
        What :func:`run_step` returned.

    Returns
    -------
    str
        Lines without a trailing newline.
    """
    r, m, tm = report.result, report.metrics, report.result.timing()
    o = r.outcome
    if r.ok:
        head = "run completed"
    elif o.command_zero_sent:
        head = f"run STOPPED SAFELY ({r.reason}): {r.message}; command 0 sent"
    else:
        head = f"run STOPPED ({r.reason}): {r.message}"
    lines = [head + f", {r.ticks} samples"]
    if not r.ok:
        lines.append("no step metrics: the run was cut short")
    if m is not None:
        settle = NOT_SETTLED if m.settling_time_s is None else f"{m.settling_time_s:.3f} s {FROM_START}"
        lines.append(f"{m.overshoot_words()}   {settling_label(THESIS_BAND_PCT)} {settle}   "
                     f"(thesis definitions)")
    if report.info is not None:
        lines.append(report.info.summary(
            unsettled=NOT_SETTLED_EITHER if m is not None and m.settling_time_s is None else NOT_SETTLED))
    lines.append(f"latency p50 {tm.p50_us:.0f} us  p99 {tm.p99_us:.0f} us  max {tm.max_us:.0f} us   "
                 f"late {tm.late}  skipped {o.skipped}  dropped {tm.dropped}  stale {o.stale}  "
                 f"duplicates {o.duplicates}  rx errors {o.rx_errors}")
    if o.skipped:
        lines.append(f"the station was held up: {o.skipped} sample(s) logged but not answered (skipped; the device "
                     f"held its output), at most {tm.max_lag_ms:.1f} ms behind")
    if o.watchdog_trips:
        lines.append(f"the device's watchdog tripped {o.watchdog_trips} time(s): commands were missing")
    lines.append(f"log: {report.log_path}")
    return "\n".join(lines)
