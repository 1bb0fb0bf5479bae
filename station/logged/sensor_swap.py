"""θ and a of an open-loop run, told apart by the sensors themselves.

An open-loop run (v = u: no law feeds θ or a back) cannot say θ from a by a law
(:mod:`station.logged.columns`). At rest before the first command the encoder reads one count
and the accelerometer its noise, and the hub's angle follows the nominal model's driven by the
logged command where the tip's acceleration does not.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from station.logged.audit import AuditClaim
from station.logged.columns import Columns, named_by, swapped
from station.logged.sensor_evidence import cosine_ratio
from station.logged.simulate import nominal_theta
from station.logged.start import REST_ROWS
from station.runlog import RunLog

ModelTheta = Callable[[RunLog], "np.ndarray | None"]
"""``model_theta(log) -> θ``: the nominal model's θ for a log driven open loop by its v (encoder
counts, shape (N,)), None when the log cannot be simulated (:func:`nominal_theta`)."""

SWAP_COSINE = 0.9
"""An open-loop run's θ and a are read swapped when the column named a follows the nominal
model's θ this closely (the cosine of their changes from row 0; the rig's own open-loop pulses
as named: 0.98) and the column named θ does not (under :data:`UNLIKE_COSINE`)."""

UNLIKE_COSINE = 0.5
"""A column no closer than this to the model's θ is not the hub's angle."""


def _cosine(x: np.ndarray, y: np.ndarray) -> float:
    """|cosine| of two signals' changes from their row 0 (0 where either never changes)."""
    cos, _ = cosine_ratio(x - x[0], y - y[0])
    return 0.0 if cos is None else abs(cos)


def check_sensor_swap(columns: Columns, model_theta: ModelTheta | None = None) -> Columns:
    """θ and a of an open-loop run (v = u) checked by the sensors themselves (module docstring).

    Asked only where the rest before the first command says it may be (the column named θ moves
    there more than the column named a: an encoder at rest reads one count); decided by the
    nominal model's θ driven by the logged command (:data:`SWAP_COSINE`, :data:`UNLIKE_COSINE`).

    Parameters
    ----------
    columns : Columns
        What :func:`station.logged.columns.check_columns` found; returned as it is when it found a swap, the run is
        closed loop, or its rest is shorter than :data:`REST_ROWS`.
    model_theta : callable, optional
        ``model_theta(log) -> θ`` (encoder counts, shape (N,)): the nominal model's θ for the
        log driven open loop by its command; None when the log cannot be simulated (default
        :func:`nominal_theta`).

    Returns
    -------
    Columns
    """
    log = columns.log
    if columns.claims or len(log) < 2 * REST_ROWS:
        return columns
    d = log.data
    u, v, theta, a = (np.asarray(d[k], dtype=float) for k in ("u", "v", "theta", "a"))
    if not all(np.all(np.isfinite(x)) for x in (u, v, theta, a)) or not np.array_equal(u, v):
        return columns
    moved = np.flatnonzero(v != v[0])
    rest = int(moved[0]) if moved.size else 0
    if rest < REST_ROWS or np.ptp(theta[:rest]) <= np.ptp(a[:rest]):
        return columns
    expected = (model_theta or nominal_theta)(log)
    if expected is None:
        return columns
    named, crossed = _cosine(theta, expected), _cosine(a, expected)
    if crossed < SWAP_COSINE or named >= UNLIKE_COSINE:
        return columns
    claim = AuditClaim(
        "columns", f"θ and a {named_by(log)}", "θ and a swapped", "contradicted",
        f"open loop: at rest before the first command the column named θ moves {np.ptp(theta[:rest]):g} counts and "
        f"the one named a {np.ptp(a[:rest]):g}; the nominal model's θ driven by the logged command has a cosine "
        f"of {crossed:.2f} with the column named a and {named:.2f} with the one named θ")
    note = "the columns named θ and a hold a and θ (the audit): read swapped"
    trial = swapped(log, "theta", "a")
    return Columns((claim,), dataclasses.replace(trial, notes=list(log.notes) + [note]))  # its controller asked again


