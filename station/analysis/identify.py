"""Which controller made a log: identified from the data when the header does not say.

A log whose header names no controller (the rig's 2014 logs, cut-down copies, ours
without a spec) still holds u, θ and the command v it produced. Candidate laws, simplest
first, each for both alignments d (DESIGN.md "Timing and log rows":
v[k] = C(u[k], θ[k-d])):

- open loop, v = u;
- proportional, v = sat(kp·(u[k] - θ[k-d]));
- linear compensators e -> v of order 1 to 3 (a direct-form recursion in z^-1).

Their coefficients come from linear least squares on the logged e and v over the rows
where v is not clamped (the recursion runs on the clamped v, so the regression is exact
there). A law is accepted only when, run as the rig runs it
(:func:`station.control.rerun.replay_commands`), it reproduces every logged v to ``tolerance``
(1e-6 DAC counts): the identification claims nothing the data do not prove.

A PID header with ki or kd != 0 does not say how the rig discretized it;
:func:`pid_controllers` gives the standard choices (integral by backward Euler, forward
Euler or Tustin; derivative by backward difference; Franklin, Powell & Workman, Digital
Control of Dynamic Systems, ch. 6) to try against the data.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.control import DAC_LIMIT, Compensator, DiscreteTF, OpenLoop  # DAC_LIMIT: the clamp assumed when v exceeds the rig's ±200
from station.control.rerun import detect_alignment

TOLERANCE = 1e-6
"""max |v_replayed - v_logged| (DAC counts) a law must meet to be accepted."""

MAX_ORDER = 3
"""Highest order of the linear compensators tried."""



@dataclass(frozen=True)
class IdentifiedController:
    """A control law that reproduces a log's commands (:func:`infer_controller`,
    :func:`match_pid`).

    Attributes
    ----------
    controller : Compensator or OpenLoop
    alignment : int
        The computational delay d it needs, samples.
    max_abs_dv : float
        max |v_replayed - v_logged| with it, DAC counts.
    v_replayed : numpy.ndarray, shape (N,)
    law : str
        One line for reports, e.g. "P, kp = 1" or "integral by Tustin, derivative by
        backward difference".
    """

    controller: Compensator | OpenLoop
    alignment: int
    max_abs_dv: float
    v_replayed: np.ndarray
    law: str


def _limit_for(v: np.ndarray, rig_limit: float) -> float:
    vmax = float(np.max(np.abs(v))) if v.size else 0.0
    return rig_limit if vmax <= rig_limit else max(DAC_LIMIT, vmax)


def _nice(x: float) -> float:
    """x rounded to 9 significant digits (a gain typed by a person), when that is what it is."""
    return float(f"{x:.9g}")


def _compensator(num, den, limit: float, dt: float, kind: str, extra: dict | None = None) -> Compensator:
    tf = DiscreteTF(num, den)
    spec = {"kind": kind, "name": kind, "dt": dt, "limit": limit, "source": "inferred from the data",
            "gth": {"num_z": tf.num.tolist(), "den_z": tf.den.tolist()}, "ga": None, **(extra or {})}
    return Compensator(tf, None, limit=limit, name=kind, spec=spec)


def _check(controller, u, theta, a, v, law: str, alignments) -> IdentifiedController | None:
    """``controller`` at its best alignment (:func:`station.control.rerun.detect_alignment`)."""
    fit = detect_alignment(controller, u, theta, a, v, alignments)
    return None if fit is None else IdentifiedController(controller, *fit, law)  # None: no alignment tried


def _regression(u, theta, v, d: int, order: int, limit: float):
    """Least-squares coefficients (num, den) of v[k] = sum b_i e[k-i] - sum a_j v[k-j]."""
    n = v.size
    e = np.zeros(n)
    e[d:] = u[d:] - theta[:n - d]
    start = d + order
    rows = np.arange(start, n)
    rows = rows[np.abs(v[rows]) < limit - 1e-9]
    if rows.size < 4 * (2 * order + 1):
        return None
    cols = [e[rows - i] for i in range(order + 1)] + [-v[rows - j] for j in range(1, order + 1)]
    X = np.column_stack(cols)
    if not np.any(X):
        return None
    coef, *_ = np.linalg.lstsq(X, v[rows], rcond=None)
    return coef[:order + 1], np.concatenate(([1.0], coef[order + 1:]))


def infer_controller(u, theta, v, a=None, dt: float = 0.002, rig_limit: float = 200.0,
                     alignments=(0, 1)) -> IdentifiedController | None:
    """Identify the controller that produced a log's commands from u, θ and v.

    Parameters
    ----------
    u, theta, v : array_like, shape (N,)
        Logged reference (encoder counts), encoder counts and command (DAC counts).
    a : array_like, shape (N,), optional
        Accelerometer counts (unused by the laws tried; passed to the replay).
    dt : float
        Sample time, s (recorded in the controller's spec).
    rig_limit : float
        The clamp assumed when |v| never exceeds it (the rig's 200 DAC counts); else
        the DAC's 255 (or max |v|).
    alignments : sequence of int
        Computational delays tried, samples.

    Returns
    -------
    IdentifiedController or None
        The simplest law (open loop, P, then linear of order 1..3) that reproduces every
        logged v to :data:`TOLERANCE`; None when none does, or the log lacks u, θ or v
        (NaN) or never commands anything.
    """
    u = np.asarray(u, dtype=float)
    theta = np.asarray(theta, dtype=float)
    v = np.asarray(v, dtype=float)
    a = np.zeros_like(v) if a is None else np.asarray(a, dtype=float)
    if v.size < 8 or not all(np.all(np.isfinite(x)) for x in (u, theta, v)) or not np.any(v):
        return None
    a = np.where(np.isfinite(a), a, 0.0)
    limit = _limit_for(v, rig_limit)

    if np.array_equal(v, u) or np.array_equal(v[1:], u[1:]) and v[0] == 0:
        ol = OpenLoop(limit=None)
        return _check(ol, u, theta, a, v, "open loop, v = u", alignments)

    tried = []
    for d in alignments:  # P: v = kp e on the unclamped rows
        reg = _regression(u, theta, v, d, 0, limit)
        if reg is not None:
            tried.append(_nice(float(reg[0][0])))
    for kp in dict.fromkeys(tried):
        if kp == 0 or not np.isfinite(kp):
            continue
        ctl = _compensator([kp], [1.0], limit, dt, "p", {"kp": kp})
        hit = _check(ctl, u, theta, a, v, f"P, kp = {kp:g}", alignments)
        if hit is not None and hit.max_abs_dv <= TOLERANCE:
            return hit
    for order in range(1, MAX_ORDER + 1):
        best = None
        for d in alignments:
            reg = _regression(u, theta, v, d, order, limit)
            if reg is None or not np.all(np.isfinite(reg[0])) or not np.all(np.isfinite(reg[1])):
                continue
            num, den = reg
            try:
                ctl = _compensator(num, den, limit, dt, f"linear-{order}")
            except ValueError:
                continue
            hit = _check(ctl, u, theta, a, v, _law(order, num, den), (d,))
            if hit is not None and (best is None or hit.max_abs_dv < best.max_abs_dv):
                best = hit
        if best is not None and best.max_abs_dv <= TOLERANCE:
            return best
    return None


def _law(order: int, num, den) -> str:
    fmt = lambda c: "[" + ", ".join(f"{x:.8g}" for x in c) + "]"  # noqa: E731
    return f"linear compensator e -> v of order {order}, num {fmt(num)}, den {fmt(den)} (z^-1)"


PID_INTEGRALS = {
    "backward Euler": lambda ki, dt: ([ki * dt, 0.0], [1.0, -1.0]),
    "forward Euler": lambda ki, dt: ([0.0, ki * dt], [1.0, -1.0]),
    "Tustin": lambda ki, dt: ([ki * dt / 2, ki * dt / 2], [1.0, -1.0]),
}
"""Integral term ki/s discretized three standard ways: (num, den) in z^-1."""


def pid_controllers(kp: float, ki: float, kd: float, dt: float = 0.002,
                    limit: float | None = 200.0) -> list[tuple[str, Compensator]]:
    """The standard discretizations of a PID law v = kp e + ki ∫e + kd de/dt.

    Parameters
    ----------
    kp, ki, kd : float
        Gains (DAC counts per encoder count, per count·s, per count/s).
    dt : float
        Sample time, s.
    limit : float or None
        Clamp of v, DAC counts.

    Returns
    -------
    list of (str, Compensator)
        One per integral rule (backward Euler, forward Euler, Tustin; one entry when
        ki = 0), the derivative always by backward difference kd (1 - z^-1)/dt; the name
        says which.
    """
    deriv = np.array([kd / dt, -kd / dt])
    out = []
    rules = PID_INTEGRALS.items() if ki != 0 else [("none", None)]
    for rule, make in rules:
        if make is None:
            num = np.array([kp, 0.0]) + deriv
            den = np.array([1.0])
        else:
            inum, den = make(ki, dt)
            # common denominator (1 - z^-1): kp (1 - z^-1) + I + kd/dt (1 - z^-1)^2
            num = np.zeros(3)
            num[:2] += kp * np.array([1.0, -1.0]) + np.asarray(inum)
            num += (kd / dt) * np.array([1.0, -2.0, 1.0])
            den = np.asarray(den)
        what = ("derivative by backward difference" if make is None
                else f"integral by {rule}" + (", derivative by backward difference" if kd else ""))
        extra = {"kp": kp, "ki": ki, "kd": kd, "discretization": what}
        ctl = _compensator(num, den, limit, dt, "pid", extra)
        ctl.spec["source"] = "rig header"
        out.append((what, ctl))
    return out


def match_pid(kp: float, ki: float, kd: float, u, theta, v, a=None, dt: float = 0.002,
              limit: float | None = 200.0, alignments=(0, 1)) -> tuple[IdentifiedController | None, float]:
    """The standard PID discretization that reproduces the logged v, if one does.

    Parameters
    ----------
    kp, ki, kd : float
        The header's gains.
    u, theta, v, a : array_like, shape (N,)
    dt, limit, alignments
        As :func:`infer_controller`.

    Returns
    -------
    (IdentifiedController or None, float)
        The first of :func:`pid_controllers` that reproduces v to :data:`TOLERANCE`
        (None if none does) and the smallest max |dv| seen, DAC counts.
    """
    u, theta, v = (np.asarray(x, dtype=float) for x in (u, theta, v))
    a = np.zeros_like(v) if a is None else np.where(np.isfinite(a), np.asarray(a, dtype=float), 0.0)
    best_err = float("inf")
    for what, ctl in pid_controllers(kp, ki, kd, dt, limit):
        hit = _check(ctl, u, theta, a, v, what, alignments)
        if hit is None:
            continue
        best_err = min(best_err, hit.max_abs_dv)
        if hit.max_abs_dv <= TOLERANCE:
            return hit, best_err
    return None, best_err
