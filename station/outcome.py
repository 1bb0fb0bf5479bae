"""How a run ended: one vocabulary for the loop, the log's end record, reports and exit codes.

Source: ``shared/DESIGN.md`` "Run outcome". Every run ends with a ``reason`` and the
run's counters; our log's last line is ``# end {json}`` with this object, ``station step
--json`` and ``station replay --json`` carry it as ``"outcome"``, and ``station step``'s
exit code follows from it (:attr:`Outcome.exit_code`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

REASONS = {
    "completed": "the planned ticks ran",
    "sigint": "Ctrl-C (SIGINT)",
    "sigterm": "SIGTERM",
    "timeout": "no new valid sample within the sample timeout",
    "soft-limit": "the encoder passed the soft limit",
    "controller-fault": "the controller raised or returned NaN",
    "lag": "the station fell behind the device and could not catch up (--max-lag, or held ticks above --max-miss)",
    "rate": "the device ticks at the wrong rate",
    "sequence": "samples lost, duplicated, reordered or implausible beyond the allowed",
    "link": "the port failed or the device ended the run on its own",
}
"""Every reason a run can end for, with what it means (DESIGN.md "Run outcome")."""

EXIT_CODES = {"completed": 0, "sigint": 130, "sigterm": 143}
"""Exit code of ``station step`` per reason; any other reason exits 1 (and so does a
completed run during which the device's watchdog tripped)."""


@dataclass
class Outcome:
    """A run's outcome: why it ended and its counters.

    Attributes
    ----------
    reason : str
        One of :data:`REASONS`.
    message : str
        One line for the user (what happened, at which tick).
    ticks : int
        Samples received and logged.
    late : int
        Late commands: reported by the device (v1 LATE status) or, where the device
        cannot tell (legacy), seen by the station (``late_seen``).
    late_seen : int
        Commands the station wrote after the next sample had already arrived.
    skipped : int
        Samples logged but not answered: the station had been held up and a newer one
        was already waiting (the log marks them, :data:`station.runlog.SKIPPED`).
    dropped : int
        Samples missing from the sequence numbers (a gap of g counts g − 1).
    stale : int
        v1 samples from the past (sequence number behind the last one), discarded.
    duplicates : int
        v1 samples repeated (same sequence number), discarded.
    rx_errors : int
        Bad frames received (v1).
    watchdog_trips : int
        Device watchdog trips (v1: STOPPED's count or WATCHDOG status edges, the larger).
    command_zero_sent : bool
        Command 0 and stop were written to the port at the end (False: the write
        failed, e.g. the port vanished).
    """

    reason: str
    message: str
    ticks: int = 0
    late: int = 0
    late_seen: int = 0
    skipped: int = 0
    dropped: int = 0
    stale: int = 0
    duplicates: int = 0
    rx_errors: int = 0
    watchdog_trips: int = 0
    command_zero_sent: bool = True

    def __post_init__(self) -> None:
        if self.reason not in REASONS:
            raise ValueError(f"unknown run outcome reason {self.reason!r}: expected one of {', '.join(REASONS)}")

    @property
    def ok(self) -> bool:
        """True when the planned ticks ran."""
        return self.reason == "completed"

    @property
    def exit_code(self) -> int:
        """0 completed without a watchdog trip; 130 SIGINT; 143 SIGTERM; 1 otherwise."""
        if self.reason == "completed" and self.watchdog_trips:
            return 1
        return EXIT_CODES.get(self.reason, 1)

    def to_json(self) -> dict[str, Any]:
        """The outcome as a JSON-able dict (the log's end record, ``"outcome"`` in reports)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_json(cls, obj: Any) -> Outcome | None:
        """Read an outcome written by :meth:`to_json`; None when ``obj`` is not one
        (unknown keys are ignored, so newer logs still read).

        Parameters
        ----------
        obj : object
            What the log's ``# end`` record holds (a dict from JSON).
        """
        if not isinstance(obj, dict) or obj.get("reason") not in REASONS:
            return None
        names = {f.name for f in dataclasses.fields(cls)}
        try:
            return cls(**{k: v for k, v in obj.items() if k in names})
        except (TypeError, ValueError):
            return None
