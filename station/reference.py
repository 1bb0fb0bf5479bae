"""What a logged reference is: the one definition of a step, used by replay, compare and diagnosis.

A step is u = 0 up to one tick and a non-zero constant from it to the end; a non-zero
constant throughout is a step at tick 0 (the rig was at rest before the run, as
``station step --step-time 0`` runs it). Anything else (a pulse, a sweep, two levels in
any other order) is not a step, so step metrics are never computed for it.
"""

from __future__ import annotations

from typing import Any

import numpy as np


def classify_reference(u) -> dict[str, Any]:
    """What a logged reference is: a step from 0, all zeros, or something else.

    Parameters
    ----------
    u : array_like, shape (N,)
        Logged reference, encoder counts (DAC counts in open loop).

    Returns
    -------
    dict
        ``{"kind": "step", "amplitude": float, "tick": int}`` when u is 0 up to one tick
        and a non-zero constant from it to the end (tick 0: constant throughout);
        ``{"kind": "zero"}``; ``{"kind": "missing"}`` when u is not logged (NaN); else
        ``{"kind": "other"}``.
    """
    u = np.asarray(u, dtype=float)
    if u.size and not np.all(np.isfinite(u)):
        return {"kind": "missing"}
    if u.size == 0 or np.all(u == 0):
        return {"kind": "zero"}
    change = np.flatnonzero(np.diff(u) != 0)
    if change.size == 1 and u[0] == 0 and u[-1] != 0:
        return {"kind": "step", "amplitude": float(u[-1]), "tick": int(change[0] + 1)}
    if change.size == 0:  # non-zero constant: a step at tick 0
        return {"kind": "step", "amplitude": float(u[-1]), "tick": 0}
    return {"kind": "other"}


def step_amplitude(u) -> float | None:
    """The step's final value when ``u`` is a step (:func:`classify_reference`), else None.

    Parameters
    ----------
    u : array_like, shape (N,)
        Logged reference, encoder counts.

    Returns
    -------
    float or None
        The step height, encoder counts.
    """
    ref = classify_reference(u)
    return ref["amplitude"] if ref["kind"] == "step" else None
