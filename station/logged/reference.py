"""What a logged reference is: the one definition of a step, used by replay, compare and diagnosis.

A step is u = 0 up to one tick and a non-zero constant from it to the end; a non-zero
constant throughout is a step at tick 0 (the rig was at rest before the run, as
``station step --step-time 0`` runs it). Anything else (a pulse, a sweep, two levels in
any other order) is not a step, so step metrics are never computed for it.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True, eq=False)
class Reference(Mapping):
    """What a logged reference is (:func:`classify_reference`).

    It also reads as its JSON dict (``ref["kind"]``, ``ref == {"kind": "zero"}``), the form
    older callers and the reports use.

    Attributes
    ----------
    kind : {"step", "zero", "missing", "other"}
        "step": 0 up to ``step_tick`` and a non-zero constant from it to the end; "zero":
        all zeros (or no rows); "missing": u is not logged (NaN); "other": anything else.
    amplitude : float or None
        The step's height, encoder counts (DAC counts in open loop); None unless a step.
    step_tick : int or None
        The first tick at the step's level (0: constant throughout), the log header's
        ``step_tick``; None unless a step.
    """

    kind: str
    amplitude: float | None = None
    step_tick: int | None = None

    @property
    def is_step(self) -> bool:
        """True for a step."""
        return self.kind == "step"

    def to_json(self) -> dict[str, Any]:
        """``{"kind": "step", "amplitude": F, "tick": N}`` for a step, else ``{"kind": K}``."""
        if self.is_step:
            return {"kind": self.kind, "amplitude": self.amplitude, "tick": self.step_tick}
        return {"kind": self.kind}

    def __getitem__(self, key: str) -> Any:
        return self.to_json()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.to_json())

    def __len__(self) -> int:
        return len(self.to_json())

    def __repr__(self) -> str:
        return f"Reference({self.to_json()!r})"


def classify_reference(u) -> Reference:
    """What a logged reference is: a step from 0, all zeros, or something else.

    Parameters
    ----------
    u : array_like, shape (N,)
        Logged reference, encoder counts (DAC counts in open loop).

    Returns
    -------
    Reference
        kind "step" with its amplitude and step tick when u is 0 up to one tick and a
        non-zero constant from it to the end (tick 0: constant throughout); "zero";
        "missing" when u is not logged (NaN); else "other".
    """
    u = np.asarray(u, dtype=float)
    if u.size and not np.all(np.isfinite(u)):
        return Reference("missing")
    if u.size == 0 or np.all(u == 0):
        return Reference("zero")
    change = np.flatnonzero(np.diff(u) != 0)
    if change.size == 1 and u[0] == 0 and u[-1] != 0:
        return Reference("step", float(u[-1]), int(change[0] + 1))
    if change.size == 0:  # non-zero constant: a step at tick 0
        return Reference("step", float(u[-1]), 0)
    return Reference("other")


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
    return classify_reference(u).amplitude
