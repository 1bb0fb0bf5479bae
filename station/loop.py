"""The real-time loop: sample in, command out, one command per sample.

The device paces the loop: each sample it sends is answered at once with the command
for the next tick (alignment d = 1, DESIGN.md "Timing and log rows"): on sample k the
loop computes v[k+1] = C(u[k+1], θ[k], a[k]). Row k of the log holds θ[k], a[k], the
reference u[k], the command v[k] acting during tick k (computed on sample k−1, with its
θ̂_d and compute latency) and what the device reports it applied.

The hot path does only: blocking read, controller step, write, and an O(1) append of
the row to the log writer's queue; formatting, disk and rerun happen on the writer's
thread. Garbage collection is off during the run, the GIL switch interval is short so
the writer thread cannot hold the loop up, and the scheduling priority is raised where
the OS allows it.

Fail safe: on a timeout (device silent), Ctrl-C / SIGTERM, a legacy sequence gap, an
exception in the controller or anywhere in the loop, or the encoder passing the soft
limit, the loop sends command 0 and stop *first*, then the caller flushes the log, then
the reason is reported (:class:`RunResult`).
"""

from __future__ import annotations

import gc
import math
import sys
import threading
import time
from dataclasses import dataclass, field

import numpy as np

from station import DT
from station.link import DeviceStopped, LinkTimeout, SequenceError, Session
from station.realtime import RealtimePriority

NAN = math.nan


@dataclass
class TimingSummary:
    """Compute latency (sample received → command written) and link health of a run.

    p50_us, p99_us, max_us: latency percentiles in µs (NaN when no command was sent);
    late: commands the device reports as late (v1 LATE status); dropped: samples
    missing from the sequence numbers.
    """

    p50_us: float
    p99_us: float
    max_us: float
    late: int
    dropped: int

    def to_json(self) -> dict:
        """The ``timing`` object of ``station step --json``."""
        def num(x):
            return None if math.isnan(x) else round(float(x), 1)
        return {"p50_us": num(self.p50_us), "p99_us": num(self.p99_us), "max_us": num(self.max_us),
                "late": int(self.late), "dropped": int(self.dropped)}


@dataclass
class RunResult:
    """How a run ended.

    reason: "completed", "timeout", "interrupted", "sequence", "controller", "soft-limit"
    or "error"; message: one line for the user; ticks: samples received; latency_us:
    per-command compute latency, µs, shape (commands,); stopped: the device's STOPPED
    counters (v1) or None.
    """

    reason: str
    message: str
    ticks: int
    latency_us: np.ndarray
    late: int
    dropped: int
    stopped: dict | None = None
    extra: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """True when the run completed as planned."""
        return self.reason == "completed"

    def timing(self) -> TimingSummary:
        """Latency percentiles and link counters of the run."""
        lat = self.latency_us[np.isfinite(self.latency_us)]
        if lat.size:
            p50, p99, mx = np.percentile(lat, 50), np.percentile(lat, 99), lat.max()
        else:
            p50 = p99 = mx = NAN
        return TimingSummary(p50, p99, mx, self.late, self.dropped)


class SoftLimitError(Exception):
    """The encoder passed the soft limit."""


class _Terminate(BaseException):
    """SIGTERM turned into an exception so the fail-safe path runs."""


def run_loop(session: Session, controller, reference: np.ndarray, writer, soft_limit: float = 2048.0,
             dt: float = DT, lean: bool = True) -> RunResult:
    """Run one test: start the device, answer every sample, stop it safely.

    Parameters
    ----------
    session : station.link.Session
        An open session (``hello()`` already done).
    controller : station.control.Compensator or OpenLoop
        ``step(u, theta, a) -> (v, theta_d_hat)``; reset before the run.
    reference : ndarray, shape (n_ticks,)
        u[k] for every tick, counts; its length is the run's length in ticks.
    writer : station.runlog.RunLogWriter
        Receives one row per sample (``append(row)``, O(1)); the caller closes it
        after this returns (the stop command goes out before the log is flushed).
    soft_limit : float
        |θ| above this many encoder counts stops the run.
    dt : float
        Sample time, s (for the t column).
    lean : bool
        Garbage collection off, a short GIL switch interval and a raised scheduling
        priority (SCHED_FIFO / nice, where the OS allows) during the run. False runs a
        plain loop (the benchmark's baseline).

    Returns
    -------
    RunResult
        Never raises for device, controller or user faults: they end the run, with
        command 0 and stop already sent, and are described in the result.
    """
    u = np.asarray(reference, dtype=float).tolist()
    n_ticks = len(u)
    latencies = np.full(n_ticks, NAN)
    ticks = 0
    reason, message = "completed", f"completed {n_ticks} ticks"
    stopped = None
    old_switch = sys.getswitchinterval()
    old_term = _install_sigterm()
    gc_was_enabled = gc.isenabled()
    priority = RealtimePriority()
    level = priority.raise_() if lean else priority.level
    perf_ns = time.perf_counter_ns
    pending = None  # the row of a sample received but not yet logged
    read_sample, send_command, step, append = session.read_sample, session.send_command, controller.step, writer.append
    try:
        if lean:  # before START: once the device ticks, every ms counts
            gc.collect()
            gc.disable()
            sys.setswitchinterval(5e-5)  # the writer thread must not hold the GIL for ms
        session.start(n_ticks)
        v_k, dhat_k, lat_k = 0.0, u[0], NAN  # tick 0 outputs 0
        last = n_ticks - 1
        while True:
            n, theta, accel, v_applied, status = read_sample()
            t_recv = perf_ns()
            if n > last:
                break
            if abs(theta) > soft_limit:
                append((n * dt, n, u[n], v_k, theta, accel, dhat_k,
                        NAN if v_applied is None else v_applied, status, lat_k))
                raise SoftLimitError(f"encoder at {theta} counts passed the soft limit ±{soft_limit:g} at tick {n}")
            # sample n is in: its row is complete (v[n] was sent on sample n-1) and must be
            # logged whatever happens next (a controller fault, a failed write)
            pending = (n * dt, n, u[n], v_k, theta, accel, dhat_k,
                       NAN if v_applied is None else v_applied, status, lat_k)
            if n < last:
                try:
                    v_next, dhat_next = step(u[n + 1], theta, accel)
                except Exception as exc:  # noqa: BLE001 - any controller fault must stop the motor
                    raise _ControllerFault(f"controller raised {type(exc).__name__}: {exc} at tick {n}") from exc
                send_command(n, v_next)
                lat_next = (perf_ns() - t_recv) / 1000.0
                latencies[n + 1] = lat_next
            append(pending)
            pending = None
            ticks += 1
            if n == last:
                break
            v_k, dhat_k, lat_k = v_next, dhat_next, lat_next
    except DeviceStopped as exc:
        stopped = exc.stopped
        if ticks < n_ticks:
            reason, message = "error", f"{exc} before the planned {n_ticks}"
    except LinkTimeout as exc:
        reason, message = "timeout", str(exc)
    except SequenceError as exc:
        reason, message = "sequence", str(exc)
    except SoftLimitError as exc:
        reason, message = "soft-limit", str(exc)
    except _ControllerFault as exc:
        reason, message = "controller", str(exc)
    except (KeyboardInterrupt, _Terminate):
        reason, message = "interrupted", f"interrupted by the user at tick {ticks}"
    except Exception as exc:  # noqa: BLE001 - whatever broke, the motor goes to 0 first
        reason, message = "error", f"{type(exc).__name__}: {exc}"
    finally:
        stop_info = _safe_stop(session)  # first: command 0 and stop, before anything else
        sys.setswitchinterval(old_switch)
        if gc_was_enabled:
            gc.enable()
        priority.restore()
        _restore_sigterm(old_term)
    if pending is not None:  # after the stop, before the caller closes the log
        try:
            append(pending)
        except Exception:  # noqa: BLE001 - never raises; the writer reports its own failures
            pass
    if stop_info is not None:
        stopped = stop_info
    late = session.late if stopped is None else max(session.late, stopped.get("late", 0))
    return RunResult(reason, message, ticks, latencies, late, session.dropped, stopped,
                     {"priority": level, "rx_errors": session.rx_errors})


class _ControllerFault(Exception):
    pass


def _safe_stop(session: Session) -> dict | None:
    """Command 0 and stop; never raises (the port may already be gone).

    A second Ctrl-C / SIGTERM while stopping must not skip the stop: anything raised,
    BaseException included, gets one more attempt, then is given up quietly (the run is
    ending anyway and its reason is already recorded). ``session.stop`` itself sends
    command 0 and stop (v1: COMMAND for the last sample, then STOP).
    """
    for _ in range(2):
        try:
            return session.stop()
        except BaseException:  # noqa: BLE001 - the motor must get its 0 whatever happened
            continue
    return None


def _install_sigterm():
    import signal

    if threading.current_thread() is not threading.main_thread():
        return None

    def handler(signum, frame):
        raise _Terminate()

    try:
        return signal.signal(signal.SIGTERM, handler)
    except (ValueError, OSError):
        return None


def _restore_sigterm(old) -> None:
    import signal

    if old is not None:
        try:
            signal.signal(signal.SIGTERM, old)
        except (ValueError, OSError):
            pass
