"""What the link tolerates and what it raises when a run must end (DESIGN.md "Run outcome").

:class:`LinkLimits` holds the fail-safe bounds; each :class:`LinkFault` subclass carries
its outcome ``reason``; :class:`DeviceStopped` is the device ending the run on its own.
"""

from __future__ import annotations

from dataclasses import dataclass

from station.errors import StationError

MISS_WINDOW = 100
"""Ticks over which --max-miss is counted."""
RATE_WINDOW_S = 0.5
"""Wall-clock window of the rate check, s."""
RATE_SLOW = 1.5
"""Average sample period above this many nominal periods is too slow."""
RATE_FAST = 1.2
"""A self-paced device sending more than this times the nominal count of samples is too fast."""
POLL_S = 0.01
"""Longest single blocking read, s: deadlines and signals are checked at least this often."""


@dataclass(frozen=True)
class LinkLimits:
    """What the link tolerates before it stops the run (the fail-safe bounds).

    Attributes
    ----------
    timeout : float
        s: the next valid, new sample must arrive within this of the last one (of
        START for the first), whatever else arrives in between; else reason "timeout".
    max_lag : int
        Samples already waiting (port input buffer + decoded, unprocessed) when a
        command is about to be written; above it, reason "lag".
    max_miss : int
        Ticks among the last :data:`MISS_WINDOW` that were dropped, stale, duplicated
        or LATE; above it, reason "sequence".
    max_step : float
        Largest plausible encoder change per tick, counts; above it (a byte slip, a
        corrupted sample), reason "sequence". Default: the rig's top motor speed
        (act_K·|2πj + act_p|/act_p ≈ 0.067 rad/s per DAC count, at 255 counts ≈ 5.6
        counts per tick) with a margin of 7 for the beam's swing of the hub.
    check_rate : bool
        Check the device's tick rate (reason "rate"): samples more than 1.5× the
        nominal period apart on average over 0.5 s (time the station spent on a sample
        is not counted, so a lockstep device never trips it); a self-paced v1 device
        (INFO rate_hz ≠ 0) more than 20 % fast.
    """

    timeout: float = 0.1
    max_lag: int = 2
    max_miss: int = 10
    max_step: float = 40.0
    check_rate: bool = True


class LinkFault(StationError):
    """The link ended the run; ``reason`` is its outcome reason (DESIGN.md "Run outcome")."""

    reason = "link"


class LinkTimeout(LinkFault):
    """No valid, new sample arrived within the sample timeout: the device went silent
    (or sends only noise, repeats, or messages that are not samples)."""

    reason = "timeout"


class SequenceError(LinkFault):
    """Samples lost, duplicated, reordered or implausible beyond the allowed (legacy: n
    did not advance by one; the stream is out of step)."""

    reason = "sequence"


class LagError(LinkFault):
    """The station fell behind: more samples waiting than ``max_lag`` when a command was due."""

    reason = "lag"


class RateError(LinkFault):
    """A self-paced device ticks at the wrong rate."""

    reason = "rate"


class Interrupted(LinkFault):
    """A stop signal was recorded while waiting for a sample (see :mod:`station.signals`)."""

    reason = "sigint"


class DeviceStopped(StationError):
    """The device ended the run on its own (v1 STOPPED); ``stopped`` holds its counters.

    Parameters
    ----------
    message : str
        One line for the user.
    stopped : dict
        The STOPPED message's fields (reason, ticks, late, watchdog_trips, rx_errors).
    """

    def __init__(self, message: str, stopped: dict):
        super().__init__(message)
        self.stopped = stopped
