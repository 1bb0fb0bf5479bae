"""What the link tolerates and what it raises when a run must end (DESIGN.md "Run outcome").

:class:`LinkLimits` holds the fail-safe bounds; each :class:`LinkFault` subclass carries
its outcome ``reason``; :class:`DeviceStopped` is the device ending the run on its own.
"""

from __future__ import annotations

from dataclasses import dataclass

from station.errors import StationError
from station.rig import DEFAULT_TIMEOUT, MAX_ENCODER_STEP

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
    max_lag : float
        s: how far the station may fall behind the device and still catch up, in the
        device's time: 2 ms for each sample it skips in a row or that arrives while it
        computes the command. Above it, reason "lag". Default
        20 ms: the v1 device's watchdog (10 ticks) would zero the output from the 10th
        missed tick on; at the motor's top speed (about 2 encoder counts per ms at ±200
        DAC counts) a command held that long moves the hub at most ~40 counts from where
        a fresh one would have taken it (README "Safety").
    max_miss : int
        Two budgets over the last :data:`MISS_WINDOW` ticks: ticks dropped, stale or
        duplicated (above it, reason "sequence"), and ticks that ran on a held command (v1
        LATE, a skipped sample, a command written after the next sample had arrived, each
        tick once) beyond one catch-up's worth (``max_lag`` / 2 ms: a stall the station may
        catch up from must not spend the budget by itself); above it, reason "lag": the
        station cannot keep up.
    max_step : float
        Largest plausible encoder change per tick, counts; above it (a byte slip, a
        corrupted sample), reason "sequence". Default: :data:`station.rig.MAX_ENCODER_STEP`
        (the rig's top motor speed with a margin for the beam's swing of the hub).
    check_rate : bool
        Check the device's tick rate (reason "rate"): samples more than 1.5× the
        nominal period apart on average over 0.5 s (time the station spent on a sample
        is not counted, and a window in which the station waited on the device less than
        a quarter of the time is no evidence: the host was held up); a self-paced v1 device (INFO rate_hz ≠ 0) more than 20 % fast.
        A lockstep device (v1 INFO rate_hz = 0) ticks when asked and is not checked: a
        wait on it is the host's, bounded by ``timeout``.
    """

    timeout: float = DEFAULT_TIMEOUT
    max_lag: float = 0.020
    max_miss: int = 10
    max_step: float = MAX_ENCODER_STEP
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
    """The station fell behind the device and cannot catch up: behind by more than
    ``max_lag``, or more held ticks than ``max_miss`` in the window (bursts of samples
    included: the message names the latency timer then)."""

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
