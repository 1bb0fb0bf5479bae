"""What a logged reference is: the one definition of a step, used by replay, compare and diagnosis.

A step is u = 0 up to one tick and a non-zero constant from it to the end; a non-zero
constant throughout is a step at tick 0 (the rig was at rest before the run, as
``station step --step-time 0`` runs it). Two levels, the first not 0, are a step from the
first when the hub was held there at the log's first row (θ nearer that level than 0: a step
from a held position, or back to 0); with θ at 0 they are a pulse from rest. Anything else (a
pulse, a sweep, three levels) is not a step, so step metrics are never computed for it.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np


def held_words(initial: float) -> str:
    """How a step from a held position is said after its height.

    Parameters
    ----------
    initial : float
        The level u held before the step, encoder counts.

    Returns
    -------
    str
        `` from u = 20``, or "" for a step from 0.
    """
    return f" from u = {initial:g}" if initial else ""


@dataclass(frozen=True, eq=False)
class Reference(Mapping):
    """What a logged reference is (:func:`classify_reference`).

    It also reads as its JSON dict (``ref["kind"]``, ``ref == {"kind": "zero"}``), the form
    older callers and the reports use.

    Attributes
    ----------
    kind : {"step", "zero", "missing", "other"}
        "step": ``initial`` up to ``step_tick`` and another constant from it to the end;
        "zero": all zeros (or no rows); "missing": u is not logged (NaN); "other": anything else.
    amplitude : float or None
        The level u steps to, encoder counts (DAC counts in open loop): the step's height for
        a step from 0; None unless a step.
    step_tick : int or None
        The first tick at the step's level (0: constant throughout), the log header's
        ``step_tick``; None unless a step.
    initial : float
        The level u held before the step (0 but for a step from a held position).
    """

    kind: str
    amplitude: float | None = None
    step_tick: int | None = None
    initial: float = 0.0

    @property
    def height(self) -> float | None:
        """The step's height, ``amplitude - initial`` (None unless a step)."""
        return None if self.amplitude is None else self.amplitude - self.initial

    @property
    def held_words(self) -> str:
        """:func:`held_words` of its ``initial``."""
        return held_words(self.initial)

    @property
    def is_step(self) -> bool:
        """True for a step."""
        return self.kind == "step"

    def to_json(self) -> dict[str, Any]:
        """``{"kind": "step", "amplitude": F, "tick": N}`` for a step (with ``"from": F`` for a
        step from a held position), else ``{"kind": K}``."""
        if self.is_step:
            held = {"from": self.initial} if self.initial else {}
            return {"kind": self.kind, "amplitude": self.amplitude, "tick": self.step_tick, **held}
        return {"kind": self.kind}

    def __getitem__(self, key: str) -> Any:
        return self.to_json()[key]

    def __iter__(self) -> Iterator[str]:
        return iter(self.to_json())

    def __len__(self) -> int:
        return len(self.to_json())

    def __repr__(self) -> str:
        return f"Reference({self.to_json()!r})"


def classify_reference(u, theta0: float | None = None) -> Reference:
    """What a logged reference is: a step, all zeros, or something else.

    Parameters
    ----------
    u : array_like, shape (N,)
        Logged reference, encoder counts (DAC counts in open loop).
    theta0 : float, optional
        The hub angle at the first row, encoder counts: two levels whose first is not 0 are a
        step from it only where the hub was held there (θ0 nearer that level than 0); without
        it, never.

    Returns
    -------
    Reference
        kind "step" with its level, step tick and the level before when u is 0 up to one tick
        and a non-zero constant from it to the end (tick 0: constant throughout), or held at a
        level θ0 shows the hub at and then another; "zero"; "missing" when u is not logged
        (NaN); else "other".
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
    if change.size == 1 and theta0 is not None and held_at(u[0], theta0):
        return Reference("step", float(u[-1]), int(change[0] + 1), float(u[0]))
    return Reference("other")


def held_at(level: float, theta0: float) -> bool:
    """Whether a run starts with its hub held at a reference ``level`` other than 0: θ at its
    first row nearer that level than 0 (a P loop holds the hub within friction / kp counts of
    it; a run from rest starts at 0).

    Parameters
    ----------
    level : float
        u at the first row, encoder counts.
    theta0 : float
        θ at the first row, encoder counts.

    Returns
    -------
    bool
    """
    return bool(np.isfinite(level) and level != 0 and abs(theta0 - level) < abs(theta0))


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
