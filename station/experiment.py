"""Step tests as a Python function: what ``station step`` runs, callable from a notebook.

Example
-------
>>> from station.experiment import run_step
>>> report = run_step(controller="p", amplitude=50)          # the built-in simulated rig
>>> report.metrics.overshoot_pct, report.log_path
"""

from __future__ import annotations

import datetime as _dt
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

from station import DT, __version__
from station.analysis.metrics import NOT_SETTLED, StepInfo, StepMetrics, step_info, step_metrics
from station.control.contract import wire_limit
from station.control.rerun import is_closed_loop
from station.errors import StationError
from station.link import LinkLimits, open_session
from station.protocol import check_ticks
from station.loop import RunResult, run_loop
from station.outputs import Input, Output, check_outputs, is_device
from station.plots import plot_runs, run_title, save_figure
from station.progress import ProgressSink
from station.runlog import RunLogError, RunLogWriter, read_log
from station.runsetup import DEFAULT_LIMIT, choose_controller, log_tag, make_reference, reference_path, run_url
from station.signals import StopSignals

DEFAULT_PORT = "sim://"
DEFAULT_CONTROLLER = "lead"
DEFAULT_AMPLITUDE = 100.0
DEFAULT_STEP_TICK = 10
DEFAULT_SOFT_LIMIT = 2048.0
DEFAULT_TIMEOUT = 0.1


def figure_path(log_path: str | Path) -> Path:
    """The figure :func:`run_step` draws beside a run log: ``<log stem>.png``.

    Parameters
    ----------
    log_path : str or Path
        The run log.
    """
    return Path(log_path).with_suffix(".png")


@dataclass
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

    def to_pandas(self):
        """The logged run as a :class:`pandas.DataFrame` (one row per tick, the log's columns;
        pandas is imported here, not with the package)."""
        import pandas as pd  # lazy: start-up time (pandas)

        log = read_log(self.log_path)
        return pd.DataFrame({name: col for name, col in log.data.items()})

    def plot(self):
        """The run's figure (θ and u, v and v_applied, a; outcome and metrics in the title),
        a :class:`matplotlib.figure.Figure` (no pyplot state: display it in a notebook or save it)."""
        log = read_log(self.log_path)
        return plot_runs([log], title=run_title(log, "" if self.metrics is None else self.metrics.summary()))

    def to_json(self) -> dict:
        """``{"log", "ok", "reason", "message", "outcome": {...}, "metrics": {...}, "timing": {...}}``
        (``station step --json``; ``outcome`` as DESIGN.md "Run outcome")."""
        m = self.metrics
        return {
            "log": str(self.log_path),
            "ok": self.result.ok,
            "reason": self.result.reason,
            "message": self.result.message,
            "outcome": self.result.outcome.to_json(),
            "metrics": {"overshoot_pct": None if m is None else m.overshoot_pct,
                        "settling_time_s": None if m is None else m.settling_time_s,
                        **(self.info.to_json() if self.info is not None else {})},
            "timing": self.result.timing().to_json(),
        }


def default_log_path(tag: str, when: _dt.datetime | None = None, folder: str | Path = "runs") -> Path:
    """``runs/step-<tag>-<UTC time, ms>.tsv`` under the current directory (tag: controller
    name), with ``-2``, ``-3``... added when that name exists: names never collide.

    Parameters
    ----------
    tag : str
        The controller's name.
    when : datetime, optional
        The time in the name (default now, UTC).
    folder : str or Path, default "runs"
        Folder of the log.

    Returns
    -------
    Path
        A name that neither a log nor its figure uses yet.
    """
    when = when or _dt.datetime.now(_dt.UTC)
    stem = f"step-{tag}-{when:%Y%m%d-%H%M%S}-{when.microsecond // 1000:03d}"
    path = Path(folder) / f"{stem}.tsv"
    counter = 1
    while path.exists() or figure_path(path).exists():
        counter += 1
        path = Path(folder) / f"{stem}-{counter}.tsv"
    return path


def _plant_meta(port) -> dict | None:
    return getattr(port, "plant_meta", None)


def run_step(port: str = DEFAULT_PORT, protocol: str = "v1", controller: str = DEFAULT_CONTROLLER,
             amplitude: float = DEFAULT_AMPLITUDE, duration: float | None = None,
             step_time: float | None = None, reference: str = "step",
             out: str | Path | None = None, sinks=(),
             kp: float | None = None, limit: float | None = None, soft_limit: float = DEFAULT_SOFT_LIMIT,
             timeout: float = DEFAULT_TIMEOUT, baudrate: int | None = None, dt: float = DT,
             lean: bool = True, limits: LinkLimits | None = None, force: bool = False,
             figure: bool = True, progress: bool = False, out_dir: str | Path = "runs",
             model=None, n_elements: int | None = None, seed: int | None = None,
             step_tick: int | None = None, announce=None) -> StepReport:
    """Run a step test on a device and log it.

    Parameters
    ----------
    port : str
        Port path or pyserial URL; ``sim://`` is the built-in simulated rig (lockstep).
    protocol : {"v1", "legacy"}
        The device's wire protocol (``shared/spec/protocol.md``).
    controller : str or controller object
        "p", "lead", "lead-accel", "open-loop", a compensator TOML file, or any object
        with ``step(u, theta, a) -> (v, theta_d_hat)``, ``reset()`` and a JSON-able
        ``spec`` dict (e.g. a :class:`station.control.Compensator` built in Python);
        see :func:`choose_controller`.
    amplitude : float
        Step height, encoder counts (open loop: DAC counts).
    duration : float or None
        Run length, s; the run has round(duration/dt) ticks. None: the reference's
        default (:func:`make_reference`; 2 s for a step).
    step_time : float, optional
        When the step (or pulse) starts, s, on the tick grid: tick round(step_time/dt)
        (default 0.02 s, tick 10). As ``station step --step-time``.
    reference : str
        "step" (default), "pulse", "swept-sine" or ``FILE[:COLUMN]``
        (:func:`make_reference`). Step metrics are computed for steps only.
    out : path, optional
        Log file; default :func:`default_log_path` in ``out_dir``. An existing file (or
        an existing figure beside it) is an error unless ``force``; an input (the
        reference's or controller's file) always is (:func:`station.outputs.check_outputs`).
        The log is streamed during the run; with ``force`` an existing one is replaced
        from the run's first row.
    sinks : sequence
        Extra row sinks (e.g. :class:`station.viz.RerunSink`), fed off the hot path.
    kp : float, optional
        P gain of kind "p", DAC counts per encoder count (default 2).
    limit : float, optional
        The controller's clamp, ±DAC counts (default 200); a compensator file's own
        ``limit`` wins, with a warning when ``limit`` was given (:func:`choose_controller`).
        Every command is clamped to :func:`wire_limit` before the wire.
    soft_limit : float
        Encoder soft limit, counts: passing it stops the run safely.
    timeout : float
        Longest wait for one sample, s.
    baudrate : int, optional
        Serial baud rate (default: the protocol's, :func:`station.link.open_port`).
    dt : float
        Sample time, s (0.002: the rig's 500 Hz); sizes the reference and the controller's
        discretization.
    lean : bool
        The loop's real-time settings (see :func:`station.loop.run_loop`).
    limits : station.link.LinkLimits, optional
        The link's fail-safe bounds (max lag, misses, encoder step, rate check);
        default ``LinkLimits(timeout)``. Its timeout wins over ``timeout``.
    force : bool
        Replace an existing ``out`` and its figure.
    figure : bool
        Write ``<log stem>.png`` beside the log (:func:`figure_path`; none beside a device
        such as /dev/null) once the run has ended and the log is closed
        (:mod:`station.plots`, whole or not at all); a figure that fails is a warning,
        never a lost run.
    progress : bool
        Show a live progress line on stderr (:class:`station.progress.ProgressSink`,
        fed off the hot path by the log's sink thread).
    out_dir : path
        Folder of the default log name.
    model : Model, str or Path, optional
        The simulated rig's model (``sim://`` ports only): a :class:`station.plant.model.Model`,
        a built-in model's name or a model file (default: the port's, tmm-fit). A name or
        file goes into the URL (``sim://?model=``, as ``station step --model``); a Model is
        handed over as a model file in a temporary folder. The log header's
        ``plant.model`` records it either way.
    n_elements, seed : int, optional
        The simulated rig's element count and sensor noise seed (``sim://?elements=``,
        ``sim://?seed=``; ``station step --elements``, ``--seed``).
    step_tick : int, optional
        The step's tick instead of ``step_time`` (older scripts; not both).
    announce : callable, optional
        Gets the run's start line once the device answered, before the run (the port, its
        adapter and latency timer, the protocol, ticks and controller: :func:`start_line`);
        ``station step`` prints it.

    Returns
    -------
    StepReport
        Also when the run was stopped by a fault or a signal; ``report.result.outcome``
        says why. The log ends with the outcome's end record.

    Raises
    ------
    StationError
        Bad arguments, a port that cannot be opened or a device that does not answer
        (nothing was started then).
    station.signals.StopSignal
        SIGINT / SIGTERM before the run started (nothing was started then).
    """
    called_at = time.perf_counter()
    amplitude = DEFAULT_AMPLITUDE if amplitude is None else amplitude
    if step_tick is not None and step_time is not None:
        raise StationError("step_time and step_tick: give one of them")
    if step_tick is None:
        step_tick = DEFAULT_STEP_TICK if step_time is None else int(round(step_time / dt))
    url, model_folder = run_url(port, model, n_elements, seed)  # a real port refuses the rig's options
    ctrl, note = choose_controller(controller, kp, limit, dt)
    if note is not None:
        warnings.warn(note, UserWarning, stacklevel=2)
    limit = DEFAULT_LIMIT if limit is None else limit
    u, reference_meta = make_reference(reference, amplitude, duration, step_tick, dt)
    check_ticks(protocol, u.size, dt)  # a user error: nothing started, no log
    log_path = Path(out) if out is not None else default_log_path(log_tag(ctrl), folder=out_dir)
    figure = figure and not is_device(log_path)  # (no figure beside /dev/null)
    check_outputs([Output("out", log_path), Output("out's figure", figure_path(log_path) if figure else None)],
                  [Input("reference", reference_path(reference)),
                   Input("controller", controller if isinstance(controller, (str, Path)) else None)], force=force)
    try:
        log_path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StationError(f"{log_path}: cannot create the run log's folder: {exc.strerror or exc}") from None
    limits = limits or LinkLimits(timeout=timeout)
    with StopSignals() as signals, open_session(url, protocol, baudrate=baudrate, limits=limits) as session:
        if model_folder is not None:
            model_folder.cleanup()
        info = session.hello()
        accel_zero = session.zero_accel()
        link = getattr(session.port, "station_info", None)
        meta = {
            "station_version": __version__,
            "kind": "step",
            "controller": ctrl.spec,
            "reference": reference_meta,
            "protocol": protocol,
            "port": session.url,
            "device": info,
            "plant": _plant_meta(session.port),
            "alignment": session.alignment,
            "accel_zero": accel_zero,
            "dt": dt,
            "soft_limit": soft_limit,
            "limit": limit,
            "limits": {"timeout": limits.timeout, "max_lag_s": limits.max_lag, "max_miss": limits.max_miss,
                       "max_step": limits.max_step},
            "link": None if link is None else link.to_json(),  # the adapter and its latency timer
            "start_time": _dt.datetime.now(_dt.UTC).isoformat(),
            "start_unix": time.time(),
        }
        sinks = list(sinks)
        bar = None
        if progress:
            bar = ProgressSink(u.size * dt)
            sinks.append(bar)
        try:
            writer = RunLogWriter(log_path, meta, sinks=sinks)
        except RunLogError:  # not even the header fits (a full disk): leave no part of a log
            if log_path.is_file():
                log_path.unlink()
            raise
        if announce is not None:
            announce(start_line(session, u.size, dt, ctrl))
        result = None
        try:
            result = run_loop(session, ctrl, u, writer, soft_limit=soft_limit, dt=dt, lean=lean,
                              limit=wire_limit(ctrl, limit),
                              signals=signals)
        finally:
            # after the loop has sent command 0 and stop; signals are only recorded here
            writer.close(None if result is None else result.outcome.to_json())
            if bar is not None:
                bar.close()
    if result is not None:
        result.extra["setup_s"] = result.extra["first_sample_at"] - called_at
    # step metrics compare θ with the step in encoder counts: closed-loop steps only
    closed_step = reference == "step" and is_closed_loop(ctrl) and result.ok
    metrics, info = _metrics_of(log_path, amplitude, limit, step_tick * dt) if closed_step else (None, None)
    report = StepReport(log_path, result, metrics, info=info)
    if figure:  # after command 0, STOP and the log's close: a figure never delays a stop
        report.figure_path = _write_figure(report)
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


def _write_figure(report: StepReport) -> Path | None:
    """``<log stem>.png`` beside the log; a warning (not an error) when it cannot be drawn."""
    png = figure_path(report.log_path)
    try:
        save_figure(report.plot(), png)
    except Exception as exc:  # noqa: BLE001 - a figure must never cost the run's report
        warnings.warn(f"{png}: the run's figure was not written ({exc}); the log is complete",
                      RuntimeWarning, stacklevel=3)
        return None
    return png


def _metrics_of(log_path: Path, amplitude: float, limit: float | None,
                step_time: float) -> tuple[StepMetrics | None, StepInfo | None]:
    log = read_log(log_path)
    t, theta = log.data["t"], log.data["theta"]
    if t.size == 0 or amplitude == 0:
        return None, None
    return (step_metrics(t, theta, amplitude),
            step_info(t, theta, amplitude, step_time, v=log.data["v"], limit=limit))


def format_report(report: StepReport) -> str:
    """Human-readable summary: outcome, overshoot, settling time, timing, log path.

    Parameters
    ----------
    report : StepReport
        What :func:`run_step` returned.
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
        settle = NOT_SETTLED if m.settling_time_s is None else f"{m.settling_time_s:.3f} s"
        lines.append(f"overshoot {m.overshoot_pct:.2f} %   settling time {settle}   (thesis definitions)")
    if report.info is not None:
        lines.append(report.info.summary())
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
