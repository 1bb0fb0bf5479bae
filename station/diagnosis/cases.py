"""The measured runs a diagnosis works on: a log read and understood (controller, alignment,
open or closed loop, the accelerometer's at-rest offset removed), and its simulation on a
model as the rig ran it."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from station.analysis.residuals import ACCEL_NOISE_STD, THETA_QUANTIZATION_STD
from station.errors import StationError

Simulator = Callable[["RunCase", Any], tuple[np.ndarray, np.ndarray]]
"""``simulate(case, model) -> (theta, a)``: a run's simulated θ and a on a model."""


@dataclass
class RunCase:
    """One measured run, ready to be simulated as the rig ran it.

    Attributes
    ----------
    path : str
    log : station.runlog.RunLog
    controller : Compensator, OpenLoop or None
        The log's controller (None: driven by the logged v).
    alignment : int or None
        Detected computational delay d (None for open loop).
    closed : bool
        Closed-loop run.
    theta, a : ndarray, shape (N,)
        Measured θ (encoder counts; relative to its first sample in open loop) and a
        (accelerometer counts, its at-rest offset before the first command removed).
    sigma_theta, sigma_a : float
        Noise levels the errors are normalised by, counts.
    notes : list of str
    """

    path: str
    log: Any
    controller: Any
    alignment: int | None
    closed: bool
    theta: np.ndarray
    a: np.ndarray
    sigma_theta: float = THETA_QUANTIZATION_STD
    sigma_a: float = ACCEL_NOISE_STD
    notes: list = field(default_factory=list)

    @property
    def n(self) -> int:
        return int(self.theta.size)

    @property
    def name(self) -> str:
        return Path(self.path).name

    @property
    def kind(self) -> str:
        """The controller's name ("p", "lead", "lead-accel", "open-loop", ...)."""
        return getattr(self.controller, "name", None) or ("open-loop" if not self.closed else "unknown")


def load_case(path: str | Path) -> RunCase:
    """Read a log and find how the rig ran it (controller, alignment).

    Parameters
    ----------
    path : str or Path
        A run log (any format :func:`station.runlog.read_log` reads).

    Raises
    ------
    StationError
        Unreadable log (:class:`station.runlog.RunLogError`), a log without rows, or a
        malformed controller in its header.
    """
    from station.control import OpenLoop
    from station.replay import detect_alignment, log_controller
    from station.runlog import read_log

    log = read_log(path)
    if len(log) < 50:
        raise StationError(f"{path}: {len(log)} rows; a diagnosis needs a run of at least 50 samples")
    controller, notes = log_controller(log)
    data = log.data
    closed = controller is not None and not isinstance(controller, OpenLoop)
    alignment = None
    if closed:
        alignment, dv, _ = detect_alignment(controller, data["u"], data["theta"], data["a"], data["v"])
        if dv > 1e-3:
            notes.append(f"the log's controller does not reproduce its v (max |dv| = {dv:.3g} counts)")
    elif controller is None:
        notes.append("the log does not name its controller: the model is driven by the logged v")
    theta = np.asarray(data["theta"], float)
    if not closed:
        theta = theta - theta[0]
    a = np.asarray(data["a"], float)
    moving = np.flatnonzero(np.asarray(data["v"], float) != 0)
    rest = int(moving[0]) if moving.size else a.size
    offset = float(np.mean(a[:rest])) if rest >= 5 else 0.0
    if abs(offset) >= 0.5:
        notes.append(f"accelerometer offset {offset:.2f} counts at rest (before the first command) removed")
        a = a - offset
    return RunCase(str(path), log, controller, alignment, closed, theta, a, notes=notes)


def simulate_case(case: RunCase, model) -> tuple[np.ndarray, np.ndarray]:
    """θ and a of a run simulated on a model as the rig ran it (:func:`station.modelrun.simulate_log`).

    Parameters
    ----------
    case : RunCase
        The run (:func:`load_case`).
    model : Model
        The model to simulate it on.
    """
    from station.modelrun import simulate_log

    run = simulate_log(case.log, case.controller, case.alignment, model)
    return run.prediction["theta"], run.prediction["a"]
