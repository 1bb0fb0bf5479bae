"""Values per session: the keys, the layout of runs in sessions, and the effects each run is
simulated with (DESIGN.md "Sessions and drift").

Every effect of a sessions diagnosis's structure is either *shared* (one value for all
sessions, its plain name) or *drifting* (one value per session: the key ``NAME@k`` for session
k, :func:`key`). :class:`Layout` says which runs belong to which session, and
:class:`PerSession` gives each run the shared values and its own session's (the
:class:`~station.diagnosis.runs.cost.Evaluator`'s ``run_effects``), so a session's value never
costs another session's runs a simulation. The search over them is :mod:`station.diagnosis.sessions.drift`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from station.plant.effects import EFFECTS

SEP = "@"
"""Between an effect's name and its session's index in a per-session key (no effect name
holds it)."""


def key(name: str, session: int) -> str:
    """The key of an effect's value in one session, e.g. ``coulomb_friction@1``.

    Parameters
    ----------
    name : str
        An effect (:data:`station.plant.effects.EFFECTS`).
    session : int
        The session's index.

    Returns
    -------
    str
        ``name`` + :data:`SEP` + the session's index.
    """
    return f"{name}{SEP}{session}"


def split_key(k: str) -> tuple[str, int | None]:
    """``(name, session)`` of a per-session key, ``(name, None)`` of a shared one.

    Parameters
    ----------
    k : str
        A key of an effects mapping.

    Returns
    -------
    tuple of (str, int or None)
        The effect's name and the session's index (None for a shared key).

    Raises
    ------
    ValueError
        A key whose part after :data:`SEP` is not a whole number.
    """
    name, sep, s = k.rpartition(SEP)
    return (name, int(s)) if sep else (k, None)


def sensor_sign(name: str, fixed: Mapping[str, float]) -> int:
    """The sign a session's decided sensor faults give a signed effect searched as a size: −1
    where it holds the effect negative (its accelerometer reads the other way), else 1.

    Parameters
    ----------
    name : str
        An effect name (plain).
    fixed : mapping of str to float
        The session's sensor and wiring faults (:func:`station.logged.sensors.decide_faults`).

    Returns
    -------
    int
    """
    spec = EFFECTS.get(name)
    return -1 if spec is not None and spec.signed and fixed.get(name, 1.0) < 0 else 1


def as_held(name: str, value: float, fixed: Mapping[str, float]) -> float:
    """A size searched beside a session's sensor faults as the session's model holds it
    (:func:`sensor_sign`; values at or below 0 as they are).

    Parameters
    ----------
    name : str
    value : float
        The value as searched.
    fixed : mapping of str to float
        The session's sensor and wiring faults.

    Returns
    -------
    float
    """
    return -value if sensor_sign(name, fixed) < 0 < value else value


class PerSession:
    """The effects each run is simulated with: the shared values, and its own session's
    values of the per-session keys (:class:`station.diagnosis.runs.cost.Evaluator`'s
    ``run_effects``).

    Parameters
    ----------
    session_of : sequence of int
        Per run index, its session's index.
    fixed : sequence of mapping, optional
        Per session index, the sensor and wiring faults decided from its data
        (:func:`station.logged.sensors.decide_faults`): under every effect asked for; a signed
        effect asked for as a size takes its session's sign.
    """

    def __init__(self, session_of: Sequence[int], fixed: Sequence[Mapping[str, float]] = ()):
        self.session_of = tuple(session_of)
        self.fixed = tuple(dict(f) for f in fixed)

    def __call__(self, effects: Mapping[str, float], i: int) -> dict[str, float]:
        """Run i's effects (plain names only).

        Parameters
        ----------
        effects : mapping of str to float
            Shared names and per-session keys (:func:`key`).
        i : int
            The run's index.
        """
        s = self.session_of[i]
        fixed = self.fixed[s] if s < len(self.fixed) else {}
        out, own = dict(fixed), {}
        for k, v in effects.items():
            name, ks = split_key(k)
            v = as_held(name, v, fixed)  # searched as a size; this session's sensor may read the other way
            if ks is None:
                out[name] = v
            elif ks == s:
                own[name] = v
        out.update(own)
        return out


@dataclass(frozen=True)
class Layout:
    """Which runs belong to which session.

    Attributes
    ----------
    groups : tuple of tuple of int
        Per session, its runs' indices.
    """

    groups: tuple

    @property
    def sessions(self) -> int:
        """How many sessions."""
        return len(self.groups)

    def session_of(self) -> list[int]:
        """Per run index, its session's index.

        Returns
        -------
        list of int
            Indexed by run, each run's session index.
        """
        out = [0] * sum(len(g) for g in self.groups)
        for s, g in enumerate(self.groups):
            for i in g:
                out[i] = s
        return out
