"""A PID header's law matched against the standard discretizations (integral by backward
Euler, forward Euler or Tustin; derivative by backward difference; Franklin, Powell &
Workman, Digital Control of Dynamic Systems, ch. 6): a header with ki or kd != 0 does not say
how the rig discretized it, the data do (:func:`match_pid`).
"""

from __future__ import annotations

import numpy as np

from station.analysis.controller_id import TOLERANCE, IdentifiedController, check_law, law_compensator
from station.control import Compensator
from station.rig import CLAMP, DT


PID_INTEGRALS = {
    "backward Euler": lambda ki, dt: ([ki * dt, 0.0], [1.0, -1.0]),
    "forward Euler": lambda ki, dt: ([0.0, ki * dt], [1.0, -1.0]),
    "Tustin": lambda ki, dt: ([ki * dt / 2, ki * dt / 2], [1.0, -1.0]),
}
"""Integral term ki/s discretized three standard ways: (num, den) in z^-1."""


def pid_controllers(kp: float, ki: float, kd: float, dt: float = DT,
                    limit: float | None = CLAMP) -> list[tuple[str, Compensator]]:
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
        says which. A rule whose coefficients overflow (gains near the float's limit) is
        left out: it runs no law.
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
        if not (np.all(np.isfinite(num)) and np.all(np.isfinite(den))):
            continue  # finite gains whose discretization overflows (kd = 1.8e308 over dt) run no law
        extra = {"kp": kp, "ki": ki, "kd": kd, "discretization": what}
        ctl = law_compensator(num, den, limit, dt, "pid", extra)
        ctl.spec["source"] = "rig header"
        out.append((what, ctl))
    return out


def match_pid(kp: float, ki: float, kd: float, u, theta, v, a=None, dt: float = DT,
              limit: float | None = CLAMP, alignments=(0, 1)) -> tuple[IdentifiedController | None, float]:
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
        hit = check_law(ctl, u, theta, a, v, what, alignments)
        if hit is None:
            continue
        best_err = min(best_err, hit.max_abs_dv)
        if hit.max_abs_dv <= TOLERANCE:
            return hit, best_err
    return None, best_err
