"""Simulate a logged run on a model exactly as the rig ran it.

The one place a logged run meets the model (:meth:`station.logged.LoggedRun.simulate`;
replay, compare and the diagnosis use it). Closed loop: the log's controller, reference,
clamp and alignment (DESIGN.md "Timing and log rows") and the device's command
quantization; open loop: the plant driven by what the device applied.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.analysis.fit import fit_pct
from station.control import OpenLoop
from station.control.rerun import is_closed_loop
from station.logged.device import command_quantization
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


@dataclass
class ModelRun:
    """A logged run simulated on the plant (:func:`simulate_log`).

    Attributes
    ----------
    prediction : dict of ndarray
        As :func:`station.plant.simulate` returns (t, u, v, theta, a, theta_d_hat), shape (N,) each.
    theta_measured : ndarray, shape (N,)
        The logged θ it is compared with, encoder counts (:func:`compared_theta`).
    fit_pct : dict
        NRMSE fit of θ and a, % (:func:`station.analysis.fit.fit_pct`: ``{"theta", "accel"}``,
        None where undefined).
    how : str
        One line saying how the model was driven.
    """

    prediction: dict
    theta_measured: np.ndarray
    fit_pct: dict
    how: str


def simulate_log(log: RunLog, controller, alignment: int | None, model) -> ModelRun:
    """Simulate a logged run on a model as the rig ran it, and fit it to the log.

    Closed loop: the log's controller, reference, clamp and alignment, the device's
    command quantization (:func:`station.logged.device.command_quantization`); a
    recursion on the stored integer runs compiled as the lab's software ran it. Open loop
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

    Returns
    -------
    ModelRun
    """
    # lazy: start-up time (the FEM and its compiled kernels, loaded when used)
    from station.plant import DiscretePlant, simulate

    data = log.data
    u = data["u"]
    kw = {}
    if isinstance(model, DiscretePlant):
        model.reset()
    else:  # a Model: simulated at the log's sample time
        kw["dt"] = log.dt
    command = command_quantization(log)
    closed = is_closed_loop(controller)
    if not closed:
        applied = data["v_applied"]
        if applied.size and np.all(np.isfinite(applied)):
            pred = simulate(model, OpenLoop(), u, alignment=0, v_open=applied, **kw)
            how = "the logged v_applied (open loop)"
        else:
            pred = simulate(model, OpenLoop(), u, alignment=0, v_open=data["v"], command=command, **kw)
            how = f"the logged v (open loop), quantized as the device did ({command})"
    else:
        d = 1 if alignment is None else alignment
        pred = simulate(model, controller, u, alignment=d, command=command, **kw)
        how = f"the log's controller and reference, alignment {d}, commands quantized as the device did ({command})"
    theta = compared_theta(data["theta"], closed)
    return ModelRun(pred, theta, fit_pct(theta, pred["theta"], data["a"], pred["a"]), how)
