"""The rig's compensator structure and the open-loop pass-through.

DESIGN.md "Compensators": theta_d_hat = u - Ga(a) (u without Ga); e = theta_d_hat - theta;
v = sat(Gth(e)) at +-limit; the Gth recursion remembers the saturated v (anti-windup),
the Ga recursion its own output. With a reference shaper (:mod:`station.control.shaper`,
a compensator file's ``[shaper]``) the reference is shaped first: theta_d_hat = S(u) - Ga(a).
"""

from __future__ import annotations

from typing import Any

from station.control.shaper import ReferenceShaper
from station.control.tf import DiscreteTF
from station.rig import CLAMP
from station.rounding import half_away, toward_zero

RECURSIONS = {"none": None, "trunc": toward_zero, "round": half_away,
              "float-trunc": toward_zero, "float-round": half_away}
"""What a compensator's recursion remembers of its command: "none" the float; "trunc" or
"round" the whole DAC count the software stored (toward zero; halves away from zero), which
is then the command itself; "float-trunc" or "float-round" the float, the command sent (and
stored) being its whole count (:data:`SENT`)."""

SENT = ("float-trunc", "float-round")
"""Recursions on the float whose command is the whole count (lab software that logs what it
sends): the recursion remembers the clamped float, the command is Q(that)."""


STORED = {"trunc": "truncated", "round": "rounded"}
"""How a recursion's stored integer is named in reports."""


def on_integer(recursion: str) -> str:
    """The words for the stored integer a recursion runs on: ``"on the truncated integer"``.

    Parameters
    ----------
    recursion : str
        "trunc" or "round" (a key of :data:`STORED`).

    Returns
    -------
    str

    Raises
    ------
    KeyError
        Any other recursion ("none" has no integer).
    """
    return f"on the {STORED[recursion]} integer"


def recursion_words(recursion: str) -> str:
    """How a report says a quantized recursion, after a law's text:
    ``"its recursion on the truncated integer command"`` (the integer remembered) or
    ``"its recursion on the float, the command sent as its truncated integer"`` (the float
    remembered, :data:`SENT`).

    Parameters
    ----------
    recursion : str
        A key of :data:`STORED`, or "float-" and one.

    Raises
    ------
    KeyError
        Any other recursion ("none" has no integer).
    """
    if recursion.startswith("float-"):
        return f"its recursion on the float, the command sent as its {STORED[recursion[6:]]} integer"
    return f"its recursion {on_integer(recursion)} command"


def saturate(v: float, limit: float | None) -> float:
    """Clamp ``v`` to ±limit (DAC counts); None means no clamp.

    Parameters
    ----------
    v : float
        The command, DAC counts.
    limit : float or None
        The clamp, ±DAC counts; None: no clamp.
    """
    if limit is None:
        return v
    return limit if v > limit else -limit if v < -limit else v


class Compensator:
    """Lead/P compensator Gth with optional accelerometer feedback Ga.

    Parameters
    ----------
    gth : DiscreteTF
        Forward compensator from the error e (encoder counts) to v (DAC counts).
    ga : DiscreteTF or None
        Accelerometer feedback from a (accelerometer counts) to encoder counts.
    limit : float or None
        Saturation of v, DAC counts (the rig clamps at +-200); None for no clamp.
    name : str
        Short name for reports ("p", "lead", "lead-accel", a file name).
    spec : dict
        JSON-able description for log headers (kind, designs, z coefficients, limit, shaper).
    shaper : ReferenceShaper or None
        Shapes the reference before anything else (None: u as given).
    recursion : {"none", "trunc", "round", "float-trunc", "float-round"}
        The command the Gth recursion remembers (:data:`RECURSIONS`): the float, or the whole
        DAC count lab software stored (the command is then that integer); or the float with
        the whole count as the command (:data:`SENT`).

    Raises
    ------
    ValueError
        A limit that is not positive, an unknown ``recursion``.
    """

    def __init__(self, gth: DiscreteTF, ga: DiscreteTF | None = None, limit: float | None = CLAMP,
                 name: str = "", spec: dict[str, Any] | None = None, shaper: ReferenceShaper | None = None,
                 recursion: str = "none"):
        if limit is not None and not limit > 0:
            raise ValueError(f"limit must be positive or None, got {limit}")
        if recursion not in RECURSIONS:
            raise ValueError(f"recursion must be one of {', '.join(RECURSIONS)}, got {recursion!r}")
        self.recursion = recursion
        sent = recursion in SENT  # decided once: step() runs in the real-time loop
        self._store = None if sent else RECURSIONS[recursion]  # the whole count remembered
        self._send = RECURSIONS[recursion] if sent else None  # the float remembered, its whole count sent
        self.gth = gth
        self.ga = ga
        self.limit = None if limit is None else float(limit)
        self.name = name
        self.spec = dict(spec) if spec else {}
        self.shaper = shaper

    def reset(self) -> None:
        """Return the filters (and the shaper) to rest."""
        self.gth.reset()
        if self.ga is not None:
            self.ga.reset()
        if self.shaper is not None:
            self.shaper.reset()

    def step(self, u: float, theta: float, a: float) -> tuple[float, float]:
        """Compute one command.

        Parameters
        ----------
        u : float
            Reference for this tick, encoder counts.
        theta : float
            Encoder reading used (per the alignment), encoder counts.
        a : float
            Accelerometer reading used, accelerometer counts.

        Returns
        -------
        v : float
            Command, DAC counts, within +-limit (a whole count with a quantized ``recursion``).
        theta_d_hat : float
            The reference after the shaper and accelerometer feedback, encoder counts.
        """
        if self.shaper is not None:
            u = self.shaper.step(u)
        ga = self.ga
        theta_d_hat = u - ga.step(a) if ga is not None else u
        e = theta_d_hat - theta
        gth = self.gth
        v = gth.output(e)
        if self._store is not None:  # the integer the lab's software stored, then its clamp
            v = self._store(v)
        v = saturate(v, self.limit)
        gth.commit(e, v)
        if self._send is not None:  # the float remembered, its whole count sent
            v = self._send(v)
        return v, theta_d_hat

    def prime(self, u: float, theta: float, a: float, v: float) -> tuple[float, float]:
        """Take one logged sample and its logged command into the filters' history without
        computing the command: the state a run cut from a longer one had at its first rows
        (:func:`station.control.rerun.replay_commands` with ``primed``).

        Parameters
        ----------
        u, theta, a : float
            As :meth:`step`.
        v : float
            The command logged for this sample, DAC counts (what the recursion remembered).

        Returns
        -------
        v : float
            The logged command, as given.
        theta_d_hat : float
            The reference after the shaper and accelerometer feedback, encoder counts.
        """
        if self.shaper is not None:
            u = self.shaper.step(u)
        theta_d_hat = u - self.ga.step(a) if self.ga is not None else u
        self.gth.commit(theta_d_hat - theta, v)
        return v, theta_d_hat

    @property
    def history(self) -> int:
        """Samples of e and v the Gth recursion remembers (its order)."""
        return max(self.gth.num.size, self.gth.den.size) - 1

    def __repr__(self) -> str:
        shaped = "" if self.shaper is None else f", shaper={self.shaper!r}"
        stored = "" if self.recursion == "none" else f", recursion={self.recursion!r}"
        return (f"Compensator(name={self.name!r}, gth={self.gth!r}, ga={self.ga!r}, limit={self.limit}"
                f"{shaped}{stored})")


class OpenLoop:
    """Open loop: the reference is the command, v = u (clamped when a limit is given).

    Parameters
    ----------
    limit : float or None
        Clamp of v, DAC counts; None for none.
    name : str
        Short name for reports.
    """

    gth = None
    ga = None
    shaper = None

    def __init__(self, limit: float | None = None, name: str = "open-loop"):
        if limit is not None and not limit > 0:
            raise ValueError(f"limit must be positive or None, got {limit}")
        self.limit = None if limit is None else float(limit)
        self.name = name
        self.spec = {"kind": "open-loop", "limit": self.limit}

    def reset(self) -> None:
        """Nothing to reset (no state)."""

    def step(self, u: float, theta: float, a: float) -> tuple[float, float]:
        """Return ``(v, theta_d_hat) = (u, u)``, v clamped to +-limit; theta and a unused.

        Parameters
        ----------
        u : float
            The reference: the command itself in open loop, DAC counts.
        theta, a : float
            Sensor readings (unused).
        """
        return saturate(u, self.limit), u

    def __repr__(self) -> str:
        return f"OpenLoop(limit={self.limit})"
