"""A live progress line on stderr during a run, fed by the run log's sink thread (off the hot path).

``step: 1.24 / 2.00 s   θ 98   v 12   late 0   skipped 0   dropped 0`` rewritten in place (``\\r``)
at most every :data:`INTERVAL_S`; the loop never waits for it (the run log's writer
hands it the rows on its own thread, see :class:`station.runlog.RunLogWriter`).
"""

from __future__ import annotations

import sys
import time

from station.protocol import v1
from station.runlog.schema import SKIPPED

INTERVAL_S = 0.2
"""Shortest time between two updates of the line, s."""


class ProgressSink:
    """A run-log sink (``write_rows``) that shows elapsed / total, θ, v, late, skipped and dropped.

    Parameters
    ----------
    total_s : float
        The run's planned length, s.
    stream : text file, default sys.stderr
        Where the line goes (the caller decides whether it is a terminal).
    label : str
        Start of the line.

    Notes
    -----
    late counts samples with the v1 LATE status bit; skipped those with the station's own
    :data:`~station.runlog.SKIPPED` bit; dropped counts the ticks missing from the logged
    tick numbers n (a gap of g counts g - 1).
    """

    def __init__(self, total_s: float, stream=None, label: str = "step") -> None:
        self.total_s = float(total_s)
        self.stream = stream if stream is not None else sys.stderr
        self.label = label
        self.late = 0
        self.skipped = 0
        self.dropped = 0
        self._last_n = None
        self._shown_at = 0.0
        self._width = 0
        self.updates = 0

    def write_rows(self, columns) -> None:
        """Take a batch of rows (column name -> array) and redraw the line if it is time.

        Parameters
        ----------
        columns : mapping of str to ndarray
            One batch of log rows by column name (:data:`station.runlog.COLUMNS`), shape (B,) each.
        """
        n, status = columns["n"], columns["status"]
        if n.size == 0:
            return
        bits = status.astype(int)
        self.late += int(((bits & v1.LATE) != 0).sum())
        self.skipped += int(((bits & SKIPPED) != 0).sum())
        gaps = n[1:] - n[:-1]
        first_gap = 0 if self._last_n is None else n[0] - self._last_n
        self.dropped += int(sum(g - 1 for g in gaps if g > 1)) + int(max(0, first_gap - 1))
        self._last_n = n[-1]
        now = time.monotonic()
        if now - self._shown_at >= INTERVAL_S:
            self._shown_at = now
            self._show(columns["t"][-1], columns["theta"][-1], columns["v"][-1])

    def _show(self, t: float, theta: float, v: float) -> None:
        line = (f"{self.label}: {t:.2f} / {self.total_s:.2f} s   θ {theta:.0f}   v {v:.0f}   "
                f"late {self.late}   skipped {self.skipped}   dropped {self.dropped}")
        pad = " " * max(0, self._width - len(line))
        self._width = len(line)
        self.stream.write("\r" + line + pad)
        self.stream.flush()
        self.updates += 1

    def close(self) -> None:
        """Clear the line so the report starts on a clean one."""
        if self._width:
            self.stream.write("\r" + " " * self._width + "\r")
            self.stream.flush()
            self._width = 0
