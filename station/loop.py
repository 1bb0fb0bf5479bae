"""The real-time loop: sample in, command out, one command per sample.

The device paces the loop: each sample it sends is answered at once with the command
for the next tick (alignment d = 1, DESIGN.md "Timing and log rows"): on sample k the
loop computes v[k+1] = C(u[k+1], θ[k], a[k]). Row k of the log holds θ[k], a[k], the
reference u[k], the command v[k] acting during tick k (computed on sample k−1, with its
θ̂_d and compute latency) and what the device reports it applied.

Catch up, don't give up: when the station was held up and several samples are waiting,
each one is logged, all but the newest marked :data:`~station.runlog.SKIPPED` (no command
computed from them, the controller not stepped on them: the device holds its last
output), and the command is computed from the newest only (:meth:`station.link.Session.poll_sample`);
the link stops the run (reason "lag") when the station cannot catch up.

The hot path does only: blocking read, a non-blocking look for a newer sample, controller
step, write, and an O(1) append of the row to the log writer's queue; formatting, disk and rerun happen on the writer's
thread. Garbage collection is off during the run, the GIL switch interval is short so
the writer thread cannot hold the loop up, and the scheduling priority is raised where
the OS allows it.

Fail safe: on any stop - a link fault (timeout, lag, sequence, rate, a failed port:
:mod:`station.link`), SIGINT / SIGTERM (recorded by :mod:`station.signals`, acted on at
the next sample), an exception or NaN from the controller, or the encoder passing the soft
limit - the loop sends command 0 and stop *first*, then logs the sample in hand and every
sample that had already arrived (skipped), then the caller closes the log, then the outcome is reported (:class:`RunResult`,
:class:`station.outcome.Outcome`). Every command is clamped to ±limit before the wire.
"""

from __future__ import annotations

import gc
import logging
import math
import sys
import time
from dataclasses import dataclass, field

import numpy as np

from station.rig import CLAMP, DEFAULT_SOFT_LIMIT, DT
from station.control.contract import ControllerFault, guard_command
from station.link import DeviceStopped, LinkFault, Session
from station.outcome import Outcome
from station.realtime import RealtimePriority, process_age
from station.runlog import SKIPPED, LogRow
from station.signals import StopSignals

NAN = math.nan

logger = logging.getLogger("station.loop")
"""INFO: each run's start and outcome; WARNING: runs that did not complete."""


@dataclass
class TimingSummary:
    """Compute latency (sample received → command written) and link health of a run.

    Attributes
    ----------
    p50_us, p99_us, max_us : float
        Latency percentiles and maximum, µs (NaN when no command was sent).
    late : int
        Commands the device reports as late (v1 LATE status).
    dropped : int
        Samples missing from the sequence numbers.
    skipped : int
        Samples not answered: a newer one was already waiting.
    max_lag_ms : float
        The most the station fell behind the device when a command went out, ms
        (:meth:`station.link.Session._command`; NaN when unknown).
    first_tick_s : float
        Start-up: from the process's start to the first sample, s (NaN when unknown).
    first_tick_cpu_s : float
        The CPU time the process had used when the first sample came, s (what the start-up
        costs, whatever else the machine runs).
    setup_s : float
        From the run's call (:func:`station.experiment.run_step`) to the first sample, s.
    """

    p50_us: float
    p99_us: float
    max_us: float
    late: int
    dropped: int
    skipped: int = 0
    max_lag_ms: float = NAN
    first_tick_s: float = NAN
    first_tick_cpu_s: float = NAN
    setup_s: float = NAN

    def to_json(self) -> dict:
        """The ``timing`` object of ``station step --json``."""
        def num(x, digits=1):
            return None if math.isnan(x) else round(float(x), digits)
        return {"p50_us": num(self.p50_us), "p99_us": num(self.p99_us), "max_us": num(self.max_us),
                "late": int(self.late), "dropped": int(self.dropped), "skipped": int(self.skipped),
                "max_lag_ms": num(self.max_lag_ms, 2), "first_tick_s": num(self.first_tick_s, 3),
                "first_tick_cpu_s": num(self.first_tick_cpu_s, 3), "setup_s": num(self.setup_s, 3)}


@dataclass
class RunResult:
    """How a run ended.

    Attributes
    ----------
    outcome : station.outcome.Outcome
        Reason (DESIGN.md "Run outcome") and counters.
    latency_us : ndarray, shape (n_ticks,)
        Compute latency of each command (sample received → command written), µs;
        NaN where no command was sent.
    stopped : dict or None
        The device's STOPPED counters (v1) or None.
    extra : dict
        ``priority`` (the scheduling level reached), ``max_lag_ms`` (the most the station
        fell behind, ms), ``first_sample_at`` (``time.perf_counter()`` when the first sample
        came, NaN when none), ``first_tick_s`` (from the process's start to it, s),
        ``first_tick_cpu_s`` (the CPU time the process had used by then, s: the start-up's
        cost on a busy machine), and what the caller adds (``setup_s``).
    """

    outcome: Outcome
    latency_us: np.ndarray
    stopped: dict | None = None
    extra: dict = field(default_factory=dict)

    reason = property(lambda self: self.outcome.reason, doc="Outcome reason (DESIGN.md vocabulary).")
    message = property(lambda self: self.outcome.message, doc="One line for the user.")
    ticks = property(lambda self: self.outcome.ticks, doc="Samples received and logged.")
    late = property(lambda self: self.outcome.late, doc="Late commands.")
    dropped = property(lambda self: self.outcome.dropped, doc="Samples missing from the sequence.")

    @property
    def ok(self) -> bool:
        """True when the run completed as planned."""
        return self.outcome.ok

    def timing(self) -> TimingSummary:
        """Latency percentiles and link counters of the run."""
        lat = self.latency_us[np.isfinite(self.latency_us)]
        if lat.size:
            p50, p99, mx = np.percentile(lat, 50), np.percentile(lat, 99), lat.max()
        else:
            p50 = p99 = mx = NAN
        x = self.extra
        return TimingSummary(p50, p99, mx, self.late, self.dropped, self.outcome.skipped,
                             x.get("max_lag_ms", NAN), x.get("first_tick_s", NAN), x.get("first_tick_cpu_s", NAN),
                             x.get("setup_s", NAN))


class SoftLimitError(Exception):
    """The encoder passed the soft limit."""


class _Signalled(Exception):
    pass


def run_loop(session: Session, controller, reference: np.ndarray, writer, soft_limit: float = DEFAULT_SOFT_LIMIT,
             dt: float = DT, lean: bool = True, limit: float = CLAMP, signals: StopSignals | None = None) -> RunResult:
    """Run one test: start the device, answer every sample, stop it safely.

    Parameters
    ----------
    session : station.link.Session
        An open session (``hello()`` already done); its :class:`~station.link.LinkLimits`
        bound the timeout, lag, misses, encoder steps and rate.
    controller : object
        ``step(u, theta, a) -> (v, theta_d_hat)``; reset before the run.
    reference : ndarray, shape (n_ticks,)
        u[k] for every tick, counts; its length is the run's length in ticks.
    writer : station.runlog.RunLogWriter
        Receives one row per sample (``append(row)``, O(1)); the caller closes it
        after this returns (the stop command goes out before the log is flushed).
    soft_limit : float
        |θ| above this many encoder counts stops the run (finite, > 0).
    dt : float
        Sample time, s (for the t column).
    lean : bool
        Garbage collection off, a short GIL switch interval and a raised scheduling
        priority (SCHED_FIFO / nice, where the OS allows) during the run. False runs a
        plain loop (the benchmark's baseline).
    limit : float
        Every command is clamped to ±limit DAC counts before it reaches the wire,
        whatever the controller returns (±inf, 1e300); NaN stops the run
        ("controller-fault"): :func:`station.control.contract.guard_command`.
    signals : station.signals.StopSignals, optional
        The caller's signal guard (it stays installed while the caller closes the log);
        default: one installed for the loop's duration. SIGINT / SIGTERM end the run
        with reason "sigint" / "sigterm" at the next sample (or while waiting for one).

    Returns
    -------
    RunResult
        Never raises for device, controller, user faults or signals: they end the run,
        with command 0 and stop already sent (``outcome.command_zero_sent`` says whether
        the port took them), and are described in the result.

    Raises
    ------
    ValueError
        ``soft_limit`` or ``limit`` not finite and positive (nothing started).
    """
    for name, value in (("soft_limit", soft_limit), ("limit", limit)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    own_signals = signals is None
    if own_signals:
        signals = StopSignals().__enter__()
    signals.defer()
    session.stop_requested = lambda: signals.reason
    u = np.asarray(reference, dtype=float).tolist()
    n_ticks = len(u)
    latencies = np.full(n_ticks, NAN)
    ticks = skipped = 0
    reason, message = "completed", f"completed {n_ticks} ticks"
    stopped = None
    old_switch = sys.getswitchinterval()
    gc_was_enabled = gc.isenabled()
    priority = RealtimePriority()
    level = priority.level
    perf_ns = time.perf_counter_ns
    pending = None  # the row of a sample received but not yet logged
    read_sample, poll_sample, send_command = session.read_sample, session.poll_sample, session.send_command
    step, append = controller.step, writer.append
    new_row = tuple.__new__  # a LogRow without its Python-level __new__: 0.2 µs less inside the compute latency
    lim, neg = float(limit), -float(limit)
    stop_ok = True
    first_at = first_cpu = NAN
    v_k, dhat_k, lat_k = 0.0, u[0], NAN  # the command acting in the next tick to log (tick 0 outputs 0)
    logger.info("run: %d ticks, clamp ±%g, soft limit ±%g, lean %s", n_ticks, lim, soft_limit, lean)
    try:
        try:
            if lean:  # before START: once the device ticks, every ms counts
                level = priority.raise_()
                gc.collect()
                gc.disable()
                sys.setswitchinterval(5e-5)  # the writer thread must not hold the GIL for ms
            session.start(n_ticks)
            last = n_ticks - 1
            sample = read_sample()
            first_at, first_cpu = time.perf_counter(), time.process_time()
            while True:
                # catch up: every sample is logged; a command only from the newest one waiting
                while True:
                    n, theta, accel, v_applied, status = sample
                    t_recv = perf_ns()
                    if n > last:
                        break
                    # sample n is in: its row is complete (v[n] was sent on sample n-1) and must be
                    # logged whatever happens next (a signal, a controller fault, a failed write)
                    pending = new_row(LogRow, (n * dt, n, u[n], v_k, theta, accel, dhat_k,
                                               NAN if v_applied is None else v_applied, status, lat_k))
                    if signals.signum is not None:
                        raise _Signalled()
                    if abs(theta) > soft_limit:
                        raise SoftLimitError(f"encoder at {theta} counts passed the soft limit ±{soft_limit:g} "
                                             f"at tick {n}")
                    if n == last:
                        break
                    newer = poll_sample()  # None on a healthy link (the read that brought this sample was the look)
                    if newer is None:
                        break
                    append(pending._replace(status=status | SKIPPED))  # not answered: v held
                    pending = None
                    ticks += 1
                    skipped += 1
                    lat_k = NAN
                    sample = newer
                if n > last:
                    break
                if n < last:
                    try:
                        v_next, dhat_next = step(u[n + 1], theta, accel)
                    except BaseException as exc:  # noqa: BLE001 - any controller fault (SystemExit too) stops the motor
                        raise ControllerFault(f"controller raised {type(exc).__name__}: {exc} at tick {n}") from exc
                    if not neg <= v_next <= lim:  # also for NaN; inside ±limit the guard is the identity
                        v_next = guard_command(v_next, lim, n)  # ±inf, 1e300 clamped; NaN a ControllerFault
                    send_command(n, v_next)
                    lat_next = (perf_ns() - t_recv) / 1000.0
                    latencies[n + 1] = lat_next
                append(pending)
                pending = None
                ticks += 1
                if n == last:
                    break
                v_k, dhat_k, lat_k = v_next, dhat_next, lat_next
                sample = read_sample()
        finally:
            # first: command 0 and stop, before anything else; signals are only recorded now
            signals.defer()
            stop_info, stop_ok, stop_error = _safe_stop(session)
    except DeviceStopped as exc:
        stopped = exc.stopped
        if ticks < n_ticks:
            reason, message = "link", f"{exc} before the planned {n_ticks}"
    except LinkFault as exc:
        reason, message = exc.reason, str(exc)
    except _Signalled:
        reason, message = signals.reason, f"{signals.name} at tick {ticks}"
    except KeyboardInterrupt:  # raised by other code than our handler (e.g. not the main thread)
        reason, message = "sigint", f"KeyboardInterrupt at tick {ticks}"
    except SoftLimitError as exc:
        reason, message = "soft-limit", str(exc)
    except ControllerFault as exc:
        reason, message = "controller-fault", str(exc)
    except Exception as exc:  # noqa: BLE001 - whatever broke, the motor went to 0 first
        reason, message = "link", f"{type(exc).__name__}: {exc}"
    finally:
        sys.setswitchinterval(old_switch)
        if gc_was_enabled:
            gc.enable()
        _quietly(priority.restore)
        session.stop_requested = None
        if own_signals:
            signals.__exit__(None, None, None)
    # after the stop, before the caller closes the log: the sample in hand, and every sample that
    # had already arrived (nothing measured is lost), all unanswered (skipped when a newer followed)
    unread = [s for s in (_quietly(session.unread_samples) or ()) if 0 <= s.n < n_ticks]
    if pending is not None:
        if unread:
            pending = pending._replace(status=pending.status | SKIPPED)
            skipped += 1
        _quietly(lambda: append(pending))
        ticks += 1
        lat_k = NAN
    for i, s in enumerate(unread):
        row = LogRow(s.n * dt, s.n, u[s.n], v_k, s.theta, s.accel, dhat_k,
                     NAN if s.v_applied is None else s.v_applied, s.status | SKIPPED * (i + 1 < len(unread)), lat_k)
        if _quietly(lambda row=row: append(row)):
            ticks += 1
            skipped += i + 1 < len(unread)
            lat_k = NAN
    if signals.signum is not None and reason not in ("sigint", "sigterm") and ticks < n_ticks:
        reason, message = signals.reason, f"{signals.name} at tick {ticks} ({message})"
    if not stop_ok and reason not in ("sigint", "sigterm"):
        reason = "link"
    if not stop_ok:
        message += f"; command 0 and stop could NOT be sent ({stop_error})"
    if stop_info is not None:
        stopped = stop_info
    counters = session.counters()
    counters["skipped"] = skipped  # the rows marked SKIPPED
    if stopped is not None and session.protocol == "v1":
        counters["late"] = max(counters["late"], stopped.get("late", 0))
        counters["watchdog_trips"] = max(counters["watchdog_trips"], stopped.get("watchdog_trips", 0))
    outcome = Outcome(reason, message, ticks=ticks, command_zero_sent=stop_ok, **counters)
    logger.info("run ended: %s (%s), %d ticks", outcome.reason, outcome.message, outcome.ticks)  # the caller reports it
    age = process_age()  # the start-up: from the process's start to the first sample
    first_tick = NAN if age is None else age - (time.perf_counter() - first_at)
    return RunResult(outcome, latencies, stopped, {"priority": level, "max_lag_ms": 1000.0 * session.max_lag_seen,
                                                    "first_sample_at": first_at, "first_tick_s": first_tick,
                                                    "first_tick_cpu_s": first_cpu})


def _quietly(fn):
    """Call ``fn`` and return what it returns (True when that is None); whatever it raises (a
    late signal included) is dropped and gives None: the run is ending."""
    for _ in range(2):
        try:
            out = fn()
            return True if out is None else out
        except BaseException:  # noqa: BLE001
            continue
    return None


def _safe_stop(session: Session) -> tuple[dict | None, bool, str]:
    """Command 0 and stop; never raises (the port may already be gone).

    ``session.stop`` sends command 0 and stop (v1: COMMAND for the last sample, then
    STOP; legacy: v = 0 then 's'). Anything raised, BaseException included, gets one
    more attempt. Returns (the device's STOPPED counters or None, whether the writes
    went out, the error if they did not).
    """
    error = ""
    for _ in range(2):
        try:
            return session.stop(), True, ""
        except BaseException as exc:  # noqa: BLE001 - the motor must get its 0 whatever happened
            error = str(exc) or type(exc).__name__
            continue
    return None, False, error
