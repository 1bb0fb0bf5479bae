"""Simulate a logged run on a model exactly as the rig ran it.

The one place a logged run meets the model: replay, compare and the diagnosis all call
:func:`simulate_log`. Closed loop: the log's controller, reference, clamp and alignment
(DESIGN.md "Timing and log rows") and the device's command quantization; open loop: the
plant driven by what the device applied.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from station.analysis.fit import nrmse_fit
from station.control import OpenLoop
from station.runlog import RunLog


def command_quantization(log: RunLog) -> str:
    """How the log's device turned v into DAC counts (for :func:`station.plant.simulate`).

    Our logs name their protocol: v1 rounds (halves away from zero), legacy truncates;
    a log of ours without a protocol did not come from a device (e.g. written from a
    simulation): "none". The rig's logs were recorded with its legacy firmware:
    truncation toward zero.

    Parameters
    ----------
    log : RunLog
        The log (its header's protocol and format decide).
    """
    if log.format != "station":
        return "trunc"
    return {"v1": "round", "legacy": "trunc"}.get(log.meta.get("protocol"), "none")


@dataclass
class ModelRun:
    """A logged run simulated on the plant (:func:`simulate_log`).

    Attributes
    ----------
    prediction : dict of ndarray
        As :func:`station.plant.simulate` returns (t, u, v, theta, a, theta_d_hat), shape (N,) each.
    theta_measured : ndarray, shape (N,)
        The logged θ it is compared with, encoder counts (relative to its first sample in
        open loop: the rig's encoder is not reset before an open-loop test).
    fit_pct : dict
        NRMSE fit of θ and a, % (``{"theta", "accel"}``, None where undefined).
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
    command quantization (:func:`command_quantization`). Open loop (or no controller):
    the plant driven by what was applied: ``v_applied`` where the log has it (our
    logs), else the logged v quantized as the device did.

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
    from station.plant import DiscretePlant, simulate

    data = log.data
    u, theta = data["u"], data["theta"]
    kw = {}
    if isinstance(model, DiscretePlant):
        model.reset()
    else:  # a Model: simulated at the log's sample time
        kw["dt"] = log.dt
    command = command_quantization(log)
    if controller is None or isinstance(controller, OpenLoop):
        applied = data["v_applied"]
        if applied.size and np.all(np.isfinite(applied)):
            pred = simulate(model, OpenLoop(), u, alignment=0, v_open=applied, **kw)
            how = "the logged v_applied (open loop)"
        else:
            pred = simulate(model, OpenLoop(), u, alignment=0, v_open=data["v"], command=command, **kw)
            how = f"the logged v (open loop), quantized as the device did ({command})"
        theta = theta - theta[0] if theta.size else theta
    else:
        d = 1 if alignment is None else alignment
        pred = simulate(model, controller, u, alignment=d, command=command, **kw)
        how = f"the log's controller and reference, alignment {d}, commands quantized as the device did ({command})"
    fits = {}
    for key, meas, sim in (("theta", theta, pred["theta"]), ("accel", data["a"], pred["a"])):
        fit = nrmse_fit(meas, sim)
        fits[key] = None if np.isnan(fit) else fit
    return ModelRun(pred, theta, fits, how)
