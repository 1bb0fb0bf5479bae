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
from dataclasses import dataclass
from pathlib import Path


from station import DT, __version__
from station.analysis.metrics import StepMetrics, step_metrics
from station.control import make_controller, step_reference
from station.errors import StationError
from station.link import open_session
from station.loop import RunResult, run_loop
from station.runlog import RunLogWriter, read_log

DEFAULT_PORT = "sim://"
DEFAULT_CONTROLLER = "lead"
DEFAULT_AMPLITUDE = 100.0
DEFAULT_STEP_TICK = 10
DEFAULT_DURATION = 2.0
DEFAULT_SOFT_LIMIT = 2048.0
DEFAULT_TIMEOUT = 0.1


@dataclass
class StepReport:
    """Outcome of one step test.

    log_path: the run log; result: how the loop ended, with timing; metrics: overshoot
    and settling time of the logged θ (None when no sample was logged).
    """

    log_path: Path
    result: RunResult
    metrics: StepMetrics | None

    def to_json(self) -> dict:
        """``{"log", "ok", "reason", "message", "metrics": {...}, "timing": {...}}`` (``station step --json``)."""
        m = self.metrics
        return {
            "log": str(self.log_path),
            "ok": self.result.ok,
            "reason": self.result.reason,
            "message": self.result.message,
            "metrics": {"overshoot_pct": None if m is None else m.overshoot_pct,
                        "settling_time_s": None if m is None else m.settling_time_s},
            "timing": self.result.timing().to_json(),
        }


def default_log_path(tag: str, when: _dt.datetime | None = None) -> Path:
    """``runs/step-<tag>-<UTC time>.tsv`` under the current directory (tag: controller name)."""
    when = when or _dt.datetime.now(_dt.timezone.utc)
    return Path("runs") / f"step-{tag}-{when:%Y%m%d-%H%M%S}.tsv"


def _plant_meta(port) -> dict | None:
    return getattr(port, "plant_meta", None)


def run_step(port: str = DEFAULT_PORT, protocol: str = "v1", controller: str = DEFAULT_CONTROLLER,
             amplitude: float = DEFAULT_AMPLITUDE, duration: float = DEFAULT_DURATION,
             step_tick: int = DEFAULT_STEP_TICK, out: str | Path | None = None, sinks=(),
             kp: float = 2.0, limit: float = 200.0, soft_limit: float = DEFAULT_SOFT_LIMIT,
             timeout: float = DEFAULT_TIMEOUT, baudrate: int | None = None, dt: float = DT,
             lean: bool = True) -> StepReport:
    """Run a step test on a device and log it.

    Parameters
    ----------
    port : str
        Port path or pyserial URL; ``sim://`` is the built-in simulated rig (lockstep).
    protocol : {"v1", "legacy"}
    controller : str or controller object
        "p", "lead", "lead-accel", "open-loop", a compensator TOML file, or any object
        with ``step(u, theta, a) -> (v, theta_d_hat)``, ``reset()`` and a JSON-able
        ``spec`` dict (e.g. a :class:`station.control.Compensator` built in Python).
    amplitude : float
        Step height, encoder counts (open loop: DAC counts).
    duration : float
        Run length, s; the run has round(duration/dt) ticks.
    step_tick : int
        Tick at which the step starts (default 10, t = 0.02 s).
    out : path, optional
        Log file; default :func:`default_log_path`.
    sinks : sequence
        Extra row sinks (e.g. :class:`station.viz.RerunSink`), fed off the hot path.
    kp, limit : float
        P gain and the controller's clamp (±DAC counts).
    soft_limit : float
        Encoder soft limit, counts: passing it stops the run safely.
    timeout : float
        Longest wait for one sample, s.
    lean : bool
        The loop's real-time settings (see :func:`station.loop.run_loop`).

    Returns
    -------
    StepReport
        Also when the run was stopped by a fault; ``report.result.reason`` says why.

    Raises
    ------
    StationError
        Bad arguments, a port that cannot be opened or a device that does not answer
        (nothing was started then).
    """
    n_ticks = int(round(duration / dt))
    if n_ticks < 2:
        raise StationError(f"--duration {duration} s is shorter than two samples of {dt} s")
    if not 0 <= step_tick < n_ticks:
        raise StationError(f"step tick {step_tick} is outside the run's {n_ticks} ticks")
    if isinstance(controller, (str, Path)):
        ctrl = make_controller(str(controller), dt=dt, kp=kp, limit=limit)
        tag = Path(controller).stem if str(controller).endswith(".toml") else str(controller)
    else:
        ctrl = controller
        ctrl.reset()
        tag = str(ctrl.spec.get("kind", "custom"))
    u = step_reference(amplitude, n_ticks, at_tick=step_tick)
    log_path = Path(out) if out is not None else default_log_path(tag)
    log_path.parent.mkdir(parents=True, exist_ok=True)
    with open_session(port, protocol, timeout=timeout, baudrate=baudrate) as session:
        info = session.hello()
        meta = {
            "station_version": __version__,
            "kind": "step",
            "controller": ctrl.spec,
            "reference": {"kind": "step", "amplitude": amplitude, "step_tick": step_tick, "n_ticks": n_ticks},
            "protocol": protocol,
            "port": session.url,
            "device": info,
            "plant": _plant_meta(session.port),
            "alignment": session.alignment,
            "dt": dt,
            "soft_limit": soft_limit,
            "start_time": _dt.datetime.now(_dt.timezone.utc).isoformat(),
            "start_unix": time.time(),
        }
        writer = RunLogWriter(log_path, meta, sinks=sinks)
        try:
            result = run_loop(session, ctrl, u, writer, soft_limit=soft_limit, dt=dt, lean=lean)
        finally:
            writer.close()  # after the loop has sent command 0 and stop
    return StepReport(log_path, result, _metrics_of(log_path, amplitude))


def _metrics_of(log_path: Path, amplitude: float) -> StepMetrics | None:
    log = read_log(log_path)
    t, theta = log.data["t"], log.data["theta"]
    if t.size == 0 or amplitude == 0:
        return None
    return step_metrics(t, theta, amplitude)


def format_report(report: StepReport) -> str:
    """Human-readable summary: outcome, overshoot, settling time, timing, log path."""
    r, m, tm = report.result, report.metrics, report.result.timing()
    lines = [("run completed" if r.ok else f"run STOPPED SAFELY ({r.reason}): {r.message}; command 0 sent")
             + f", {r.ticks} samples"]
    if m is not None:
        settle = "not settled" if m.settling_time_s is None else f"{m.settling_time_s:.3f} s"
        lines.append(f"overshoot {m.overshoot_pct:.2f} %   settling time {settle}")
    lines.append(f"latency p50 {tm.p50_us:.0f} us  p99 {tm.p99_us:.0f} us  max {tm.max_us:.0f} us   "
                 f"late {tm.late}  dropped {tm.dropped}")
    lines.append(f"log: {report.log_path}")
    return "\n".join(lines)
