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
from station.logged import LoggedRun

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
    run : station.logged.LoggedRun
        The log understood (controller, alignment, reference, model glue).
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
    run: Any = field(default=None, repr=False)

    @property
    def n(self) -> int:
        return int(self.theta.size)

    @property
    def name(self) -> str:
        return Path(self.path).name

    @property
    def a_logged(self) -> bool:
        """Whether its log has an a column (without one, ``a`` is zeros: :data:`NO_A_COLUMN`)."""
        return self.run is None or self.run.has_column("a")

    @property
    def fits_a(self) -> bool:
        """Whether its a is a tip acceleration a fit uses: the log has an a column and its audit
        finds a tip acceleration there (:attr:`station.logged.audit.Audit.accel_is_tip`)."""
        return self.a_logged and (self.run is None or self.run.audit.accel_is_tip)

    @property
    def kind(self) -> str:
        """The controller's name ("p", "lead", "lead-accel", "open-loop", ...)."""
        return getattr(self.controller, "name", None) or ("open-loop" if not self.closed else "unknown")


def load_case(path: str | Path) -> RunCase:
    """Read a log and find how the rig ran it (:class:`station.logged.LoggedRun`: controller,
    alignment, open or closed loop), with θ relative to its first sample in open loop and
    the accelerometer's at-rest offset removed.

    Parameters
    ----------
    path : str or Path
        A run log (any format :func:`station.runlog.read_log` reads).

    Returns
    -------
    RunCase
        The run: its log, controller, alignment, whether closed, θ (encoder counts) and a
        (accelerometer counts) as above, shape (N,), N ≥ 50 (a zeros where the log has no a
        column: :data:`NO_A_COLUMN`), and notes on what was adjusted.

    Raises
    ------
    StationError
        Unreadable log (:class:`station.runlog.RunLogError`), a log of fewer than 50 rows,
        a log without a column the simulation needs (:attr:`station.logged.LoggedRun.simulated_columns`)
        or its controller replays (:attr:`station.logged.LoggedRun.replay_columns`: a where it feeds a back),
        or a malformed controller in its header.
    """
    run = LoggedRun.from_path(path)
    if len(run) < 50:
        raise StationError(f"{path}: {len(run)} rows; a diagnosis needs a run of at least 50 samples")
    # a is fitted where the log has it (θ alone otherwise) and needed where the law feeds it back
    run.check_columns(dict.fromkeys(run.simulated_columns + run.replay_columns),
                      "a diagnosis (the run simulated on a model and fitted)")
    notes = list(run.notes)
    if run.closed:
        if run.max_abs_dv > REPRODUCED_DV:
            notes.append(f"the log's controller does not reproduce its v (max |dv| = {run.max_abs_dv:.3g} counts)")
    elif run.controller is None:
        notes.append("the log does not name its controller: the model is driven by the logged v")
    if not run.has_column("a"):
        notes.append(NO_A_COLUMN)
        return RunCase(str(path), run.log, run.controller, run.alignment, run.closed, np.asarray(run.theta, float),
                       np.zeros(len(run)), notes=notes, run=run)
    a = np.asarray(run.data["a"], float)
    offset = run.accel_rest_offset
    if abs(offset) >= 0.5:
        notes.append(f"accelerometer offset {offset:.2f} counts at rest (before the first command) removed")
        a = a - offset
    return RunCase(str(path), run.log, run.controller, run.alignment, run.closed, np.asarray(run.theta, float), a,
                   notes=notes, run=run)


def keep_bias(case: RunCase) -> None:
    """Give a run its accelerometer's a as logged, bias and all, where a bias decided over
    the runs is in the model (:func:`station.logged.sensors.decide_faults`): the model then
    adds the bias itself, and where a feeds back (Ga) the loop sees it as the rig's did.

    Parameters
    ----------
    case : RunCase
        Changed in place (its ``a``: the logged a, as many samples as it had).
    """
    if case.run is not None and case.run.has_column("a"):  # (no a column: nothing to keep)
        raw = np.asarray(case.run.data["a"], float)[:case.a.size]
        if not np.array_equal(raw, case.a):
            case.a = raw
            case.notes.append("accelerometer bias kept in its a: the model holds the bias decided over the runs")


NO_A_COLUMN = "the log has no a column: its θ alone is fitted"
"""A run's note where its log has no accelerometer column (its a is zeros, weighing nothing:
:func:`station.diagnosis.runs.cost.calibrate_noise`)."""

REPRODUCED_DV = 1e-3
"""max |dv| (DAC counts) above which a diagnosis notes that the log's controller does not
reproduce its commands (looser than replay's 1e-6: the model, not the replay, is judged)."""


def simulate_case(case: RunCase, model) -> tuple[np.ndarray, np.ndarray]:
    """θ and a of a run simulated on a model as the rig ran it (:meth:`station.logged.LoggedRun.simulate`).

    Parameters
    ----------
    case : RunCase
        The run (:func:`load_case`).
    model : Model
        The model to simulate it on.

    Returns
    -------
    tuple of (ndarray, ndarray)
        Simulated θ (encoder counts) and a (accelerometer counts), each of shape (N,), on the
        run's own scale (θ relative in open loop, as :func:`load_case`).
    """
    pred = case.run.simulate(model, sensors=False).prediction  # the sensors: decided over the runs, in the model
    return pred["theta"], pred["a"]


def feeds_back_a(case: RunCase) -> bool:
    """Whether the run's controller feeds the accelerometer back (Ga): its a then shapes the
    loop, and no scale of the simulated a stands for another gain.

    Parameters
    ----------
    case : RunCase

    Returns
    -------
    bool
    """
    return getattr(case.controller, "ga", None) is not None


def shown_effects(names, cases) -> list[str]:
    """The effects the runs can show: an accelerometer's (``accel_*``) only where a run's a is
    fitted (:attr:`station.diagnosis.runs.cases.RunCase.fits_a`) or fed back (:func:`feeds_back_a`).

    Parameters
    ----------
    names : iterable of str
        Effect names (DESIGN.md's vocabulary).
    cases : sequence of RunCase

    Returns
    -------
    list of str
        ``names`` in their order, less those no run shows.
    """
    seen = any(c.fits_a or feeds_back_a(c) for c in cases)
    return [n for n in names if seen or not n.startswith("accel_")]
