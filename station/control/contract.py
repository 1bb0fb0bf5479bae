"""The controller contract: what the loop and the simulation ask of a controller, and the
one guard every command passes before it acts.

A controller is any object with ``step(u, theta, a) -> (v, theta_d_hat)`` and
``reset()`` (:class:`Controller`); `Compensator` and `OpenLoop` are the station's own.
Whatever it returns, the command that reaches the device (:func:`station.loop.run_loop`)
or the simulated plant (:func:`station.plant.simulate.simulate`, a controller of another
type) goes through :func:`guard_command`: clamped to ±limit, NaN a
:class:`ControllerFault`. The limit is :func:`wire_limit`'s.

Imports only :mod:`station.errors` and :mod:`station.rig`.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

from station.errors import StationError
from station.rig import DAC_LIMIT  # the clamp of last resort before the wire (re-exported)


class ControllerFault(StationError):
    """The controller raised or returned NaN (outcome reason "controller-fault")."""


class Controller(Protocol):
    """What the loop and the simulation call: the station's compensators and any user object.

    A structural type (``typing.Protocol``): nothing needs to inherit from it, and the
    station never checks it with ``isinstance``; callers check ``step`` and ``reset``. It is
    never instantiated: an implementation takes its own constructor's parameters.

    Attributes
    ----------
    spec : dict
        JSON-able description for log headers (kind, coefficients, limit).
    limit : float or None
        The controller's own clamp, ±DAC counts (None: none); optional on a user
        object, :func:`wire_limit` reads it.
    """

    spec: dict[str, Any]
    limit: float | None

    def step(self, u: float, theta: float, a: float) -> tuple[float, float]:
        """One command from one sample.

        Parameters
        ----------
        u : float
            The reference for the tick the command acts in, encoder counts (DAC counts
            open loop).
        theta : float
            Encoder reading used (per the alignment), encoder counts.
        a : float
            Accelerometer reading used, accelerometer counts.

        Returns
        -------
        v : float
            The command, DAC counts (the caller guards it: :func:`guard_command`).
        theta_d_hat : float
            The reference after accelerometer feedback, encoder counts.
        """
        ...

    def reset(self) -> None:
        """Back to rest (called before a run)."""
        ...


def wire_limit(controller, limit: float | None = None) -> float:
    """The clamp every command gets before it acts, ±DAC counts.

    The controller's own clamp when it has a finite one (a compensator file's ``limit``
    wins over ``--limit``), else ``limit``, else the DAC's range; never above the DAC's
    range.

    Parameters
    ----------
    controller : Controller
        Its ``limit`` attribute (if any), when finite and positive, wins.
    limit : float or None, optional
        The run's ``--limit`` option, ±DAC counts.
    """
    own = getattr(controller, "limit", None)
    for value in (own, limit):
        if isinstance(value, (int, float)) and math.isfinite(value) and value > 0:
            return min(float(value), DAC_LIMIT)
    return DAC_LIMIT


def guard_command(v: float, limit: float, tick: int | None = None) -> float:
    """The command a controller returned, made safe to act: clamped to ±limit.

    Parameters
    ----------
    v : float
        What the controller returned, DAC counts (±inf and 1e300 are clamped too).
    limit : float
        The clamp, DAC counts, > 0 (:func:`wire_limit`).
    tick : int, optional
        The sample it was computed on, named in the fault's message.

    Returns
    -------
    float
        ``v`` itself when within ±limit, else ±limit.

    Raises
    ------
    ControllerFault
        ``v`` is NaN ("controller returned NaN at tick N").
    """
    if -limit <= v <= limit:
        return v
    if v != v:
        where = "" if tick is None else f" at tick {tick}"
        raise ControllerFault(f"controller returned NaN{where}")
    return limit if v > 0 else -limit


__all__ = ["DAC_LIMIT", "Controller", "ControllerFault", "guard_command", "wire_limit"]
