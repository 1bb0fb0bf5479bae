"""Simulate a logged run on a model exactly as the rig ran it.

The one place a logged run meets the model (:meth:`station.logged.LoggedRun.simulate`;
replay, compare and the diagnosis use it). Closed loop: the log's controller, reference,
clamp and alignment (DESIGN.md "Timing and log rows") and the device's command
quantization; open loop: the plant driven by what the device applied.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from station.analysis.fit import fit_pct
from station.control import OpenLoop
from station.control.rerun import is_closed_loop
from station.errors import StationError
from station.logged.device import command_quantization
from station.runlog.timebase import on_ticks, row_ticks, tick_time
from station.runlog import RunLog


def compared_theta(theta, closed: bool) -> np.ndarray:
    """θ as a model is compared with it: relative to its first sample in open loop (the
    rig's encoder is not reset before an open-loop test), as logged in closed loop.

    Parameters
    ----------
    theta : numpy.ndarray, shape (N,)
        Logged encoder counts.
    closed : bool
        Whether the run was closed loop (:func:`station.control.rerun.is_closed_loop`).

    Returns
    -------
    numpy.ndarray, shape (N,)
        ``theta`` itself in closed loop (or without rows), else a new array.
    """
    return theta if closed or not theta.size else theta - theta[0]


PART_COUNTS = 3.0
"""θ of the model and the log part where they differ by more than this, encoder counts
(a few counts: the encoder's quantization and a sticking hub's last count)."""

FOLLOW_COUNTS = 5.0
"""How far the model's hub moves before the log's is judged to follow it, encoder counts."""

FOLLOW_SHARE = 0.3
"""The log's hub follows the model's when it has moved at least this share of the model's
move by the time the model's has moved :data:`FOLLOW_COUNTS` (a held hub or an unpowered
motor: none)."""


@dataclass(frozen=True)
class Parting:
    """Where the model's θ parts from the log's, in an open-loop run (:func:`parting`).

    Attributes
    ----------
    followed : bool
        Whether the log's hub first moved with the model's (the logged v was applied).
    t_follow : float or None
        When the model's hub had moved :data:`FOLLOW_COUNTS`, s (None: it never did).
    t_part : float or None
        When the two first differ by more than :data:`PART_COUNTS`, s (None: never).
    end_measured, end_model : float
        θ at the end, encoder counts (as compared: relative to the first sample in open loop).
    """

    followed: bool
    t_follow: float | None
    t_part: float | None
    end_measured: float
    end_model: float

    def line(self) -> str:
        """One line: how long the model follows the log and how far they end apart."""
        if self.t_follow is None:
            return "the model's hub hardly moves"
        if not self.followed:
            return (f"the log's hub does not follow the model's (by t = {self.t_follow:.3g} s the model's moved "
                    f"{FOLLOW_COUNTS:g} counts, the log's under {FOLLOW_SHARE:.0%} of that): the logged v did not "
                    f"move the hub (an unpowered motor or a held hub)")
        part = "never part" if self.t_part is None else f"part at t = {self.t_part:.3g} s"
        return (f"the log's hub first moves with the model's (the logged v was applied); they {part} and end at "
                f"θ = {self.end_measured:g} (log) and {self.end_model:.0f} (model) counts: what the model lacks "
                f"acts after the start (friction, damping: `station diagnose`)")


def parting(t, theta_measured, theta_model) -> Parting:
    """How an open-loop run's model follows the log (its θ as compared, :func:`compared_theta`).

    Parameters
    ----------
    t, theta_measured, theta_model : array_like, shape (N,)
        Time (s), the logged and the modelled θ (encoder counts).

    Returns
    -------
    Parting
    """
    t = np.asarray(t, float)
    y = np.asarray(theta_measured, float)
    m = np.asarray(theta_model, float)
    moved = np.flatnonzero(np.abs(m) >= FOLLOW_COUNTS)
    apart = np.flatnonzero(np.abs(y - m) > PART_COUNTS)
    t_part = float(t[apart[0]]) if apart.size else None
    if not moved.size:
        return Parting(False, None, t_part, float(y[-1]), float(m[-1]))
    k = int(moved[0])
    followed = bool(y[k] * m[k] > 0 and abs(y[k]) >= FOLLOW_SHARE * abs(m[k]))
    return Parting(followed, float(t[k]), t_part, float(y[-1]), float(m[-1]))


@dataclass
class ModelRun:
    """A logged run simulated on the plant (:func:`simulate_log`).

    Attributes
    ----------
    prediction : dict of ndarray
        As :func:`station.plant.simulate` returns (t, u, v, theta, a, theta_d_hat), shape (N,) each.
    theta_measured : ndarray, shape (N,)
        The logged θ it is compared with, encoder counts (:func:`compared_theta`).
    accel_measured : ndarray, shape (N,)
        The logged a, accelerometer counts.
    how : str
        One line saying how the model was driven.
    parting : Parting or None
        Open loop: whether the log's hub first moved with the model's and where they part
        (:func:`parting`); None in closed loop.
    doubt : str
        What the run's data point at about its sensors but do not decide, said beside this
        simulation (:attr:`station.logged.sensors.SensorFaults.doubt`); "" when nothing.
    """

    prediction: dict
    theta_measured: np.ndarray
    accel_measured: np.ndarray = field(repr=False)
    how: str
    parting: Parting | None = None
    doubt: str = ""

    @cached_property
    def fit_pct(self) -> dict:
        """NRMSE fit of θ and a, % (:func:`station.analysis.fit.fit_pct`: ``{"theta", "accel"}``,
        None where undefined); computed when first asked (a diagnosis's thousands of
        simulations need only the prediction)."""
        p = self.prediction
        return fit_pct(self.theta_measured, p["theta"], self.accel_measured, p["a"])


FROM_N = "from n"
""":func:`simulate_log`'s ``ticks`` default: placed from the log's n (:func:`station.runlog.timebase.row_ticks`)."""


def simulate_log(log: RunLog, controller, alignment: int | None, model, ticks=FROM_N) -> ModelRun:
    """Simulate a logged run on a model as the rig ran it, and fit it to the log.

    Closed loop: the log's controller, reference, clamp and alignment, the device's
    command quantization (:func:`station.logged.device.command_quantization`); a
    recursion on the stored integer runs compiled as the lab's software ran it; the model
    starts at rest at the log's first θ (an encoder that was not zeroed). Open loop
    (or no controller): the plant driven by what was applied: ``v_applied`` where the log
    has it (our logs), else the logged v quantized as the device did.

    Parameters
    ----------
    log : RunLog
    controller : Compensator, OpenLoop, an object with step/reset, or None
    alignment : int or None
        The log's computational delay d (None: 1).
    model : station.plant.model.Model or station.plant.DiscretePlant
        A Model is simulated at the log's sample time with its effects; a DiscretePlant
        (reset here) should have the log's dt.
    ticks : numpy.ndarray, None or :data:`FROM_N`
        Each row's tick when rows are missing or repeated (the model then runs on every
        tick and is compared at the rows there are), None for consecutive rows; by default
        placed from n (:func:`station.runlog.timebase.row_ticks`; a caller that simulates one
        log thousands of times passes it once placed).

    Returns
    -------
    ModelRun
    """
    # lazy: start-up time (the FEM and its compiled kernels, loaded when used)
    from station.plant import DiscretePlant, simulate

    data = log.data
    if isinstance(ticks, str):
        ticks = row_ticks(data["n"])
    u, v, applied = data["u"], data["v"], data["v_applied"]
    if ticks is not None:  # rows missing or repeated: the model runs on every tick
        u, v, applied = on_ticks(ticks, u, v, applied)
    kw = {}
    if isinstance(model, DiscretePlant):
        model.reset()
    else:  # a Model: simulated at the log's sample time (a tick's, when rows skip ticks)
        kw["dt"] = log.dt if ticks is None else tick_time(data["t"], data["n"], log.dt)
    command = command_quantization(log)
    closed = is_closed_loop(controller)
    if not closed:
        if applied.size and np.all(np.isfinite(applied)):
            pred = simulate(model, OpenLoop(), u, alignment=0, v_open=applied, **kw)
            how = "the logged v_applied (open loop)"
        else:
            pred = simulate(model, OpenLoop(), u, alignment=0, v_open=v, command=command, **kw)
            how = f"the logged v (open loop), quantized as the device did ({command})"
    else:
        d = 1 if alignment is None else alignment
        # the loop's error is u - θ: a run whose encoder was not zeroed started at rest at its
        # first θ (every position shifted alike is a rest of the plant: nothing holds it to 0)
        theta0 = float(data["theta"][0]) if data["theta"].size and np.isfinite(data["theta"][0]) else 0.0
        pred = simulate(model, controller, u - theta0, alignment=d, command=command, **kw)
        how = f"the log's controller and reference, alignment {d}, commands quantized as the device did ({command})"
        if theta0 != 0.0:
            pred = pred._replace(u=np.asarray(u, float), theta=pred.theta + theta0, theta_d_hat=pred.theta_d_hat + theta0)
            how += (f", from rest at θ = {theta0:g} (the log's first θ: an encoder not zeroed, or where a copy cut "
                    f"from a longer run starts; the audit says which)")
    if ticks is not None:
        missing = int(ticks.max()) + 1 - np.unique(ticks).size
        repeated = int(ticks.size - np.unique(ticks).size)
        pred = type(pred)(*(np.asarray(x)[ticks] for x in pred))
        held = "u" if closed else "u and v"  # a closed loop computes its own v at every tick
        said = [f"{missing} tick(s) missing (the row before's {held} held there)"] if missing else []
        said += [f"{repeated} row(s) repeating a tick"] if repeated else []
        first = np.zeros(ticks.size, bool)
        first[np.unique(ticks, return_index=True)[1]] = True
        late = int(np.count_nonzero(first[1:] & (ticks[1:] < np.maximum.accumulate(ticks)[:-1])))
        said += [f"{late} row(s) out of order (each compared at its own tick)"] if late else []
        how += f"; on the log's ticks (n jumps: {', '.join(said)})"
    theta = compared_theta(data["theta"], closed)
    part = None if closed or not theta.size else parting(data["t"], theta, pred["theta"])
    return ModelRun(pred, theta, data["a"], how, part)


def nominal_theta(log: RunLog, controller=None, alignment: int | None = None) -> np.ndarray | None:
    """The nominal model's θ for a log driven by its logged command, or run in closed loop by
    its law: the evidence of :func:`station.logged.sensor_swap.check_sensor_swap` and of a column
    rewrite a law cannot decide (:func:`station.logged.rewrite_evidence.model_miss`).

    Parameters
    ----------
    log : RunLog
    controller : Compensator, OpenLoop or None
        The log's law (None: the model driven by the logged v, open loop).
    alignment : int or None
        As :func:`simulate_log`.

    Returns
    -------
    ndarray, shape (N,), or None
        Encoder counts; None when the log cannot be simulated.
    """
    from station.plant.model import load_model  # lazy: start-up time (asked only of a suspect log)

    try:
        return simulate_log(log, controller, alignment, load_model("tmm-fit")).prediction["theta"]
    except (StationError, ArithmeticError, ValueError, KeyError):  # a run the model cannot replay decides nothing
        return None
