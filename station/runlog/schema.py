"""What a run log holds: the row, the column names and their synonyms, the format's marks,
and the one form of a run log error.

Imports only :mod:`station.errors`.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple

from station.errors import StationError


class LogRow(NamedTuple):
    """One row of our run log: tick k (DESIGN.md "Timing and log rows"); a tuple with names.

    Attributes
    ----------
    t : float
        Time, s.
    n : int
        Tick number.
    u : float
        Reference, encoder counts (open loop: DAC counts).
    v : float
        Command acting during tick k, DAC counts.
    theta : float
        Encoder counts.
    a : float
        Accelerometer, ADC counts.
    theta_d_hat : float
        The controller's θ_d estimate, encoder counts.
    v_applied : float
        DAC counts the device reports, NaN when it does not.
    status : int
        v1 status bits (bits 0-4), plus the station's own :data:`SKIPPED` (bit 7).
    latency_us : float
        Compute latency of v[k], µs; NaN for tick 0.
    """

    t: float
    n: int
    u: float
    v: float
    theta: float
    a: float
    theta_d_hat: float
    v_applied: float
    status: int
    latency_us: float


SKIPPED = 0x80
"""The station's own status bit (bit 7; the device's v1 bits are 0-4): the station did
not answer this sample, because a newer one was already waiting when it got to it (it
had been held up). No command was computed from it and the controller was not stepped
on it: the next row's v is the command held from before (the device holds its output;
a v1 device marks that tick LATE). Replay knows it (:func:`station.control.rerun.replay_commands`)."""

COLUMNS = LogRow._fields
"""Columns of our run log, in row order (units: s, tick, counts, DAC counts, encoder
counts, accelerometer counts, encoder counts, DAC counts, status bits, µs)."""

COLUMN_LINE = "\t".join(COLUMNS)
"""Our format's column-name line (its first line)."""

END_PREFIX = "# end "
"""Start of our log's last line, the run's outcome as JSON (DESIGN.md "Run outcome")."""

MAGIC = "# station-runlog 1"
"""First ``#`` line of our format (version 1)."""

COLUMN_SYNONYMS = {
    "t": ("t", "time", "time (sec.)", "time (s)", "time [s]", "time_s", "time_sec", "seconds"),
    "n": ("n", "tick", "ticks", "sample", "index"),
    "u": ("u", "r", "ref", "reference"),
    "v": ("v", "cmd", "command", "v_cmd", "dac"),
    "theta": ("theta", "θ", "$\\theta$", "\\theta", "enc", "encoder", "theta_counts"),
    "a": ("a", "accel", "acc", "acceleration", "accelerometer", "a_counts"),
    "theta_d_hat": ("theta_d_hat", "$\\hat{\\theta}_d$", "\\hat{\\theta}_d", "θ̂_d", "thetadhat"),
    "v_applied": ("v_applied",),
    "status": ("status",),
    "latency_us": ("latency_us",),
}
"""Standard column name -> the names logs use for it (compared case-insensitively,
whitespace-trimmed): ours, the rig's (``$\\theta$``), its 2014 logs (``Time (sec.)``,
``accel``) and cut-down copies (``t v theta a``)."""

_SYNONYM_OF = {alias.lower(): std for std, aliases in COLUMN_SYNONYMS.items() for alias in aliases}
_UNIT = re.compile(r"\s*[(\[][^()\[\]]*[)\]]\s*$")  # a trailing "(unit)" or "[unit]"

SIGNAL_COLUMNS = ("u", "v", "theta", "a")
"""A log is usable when it has a time base (t or n) and at least one of these."""

FINITE_COLUMNS = ("t", "n", "u", "theta", "a")
"""Columns that must hold finite numbers in every log (time base, reference, sensors);
the rig's logs must also have a finite v and theta_d_hat. Ours may log v = nan (the row
of a controller fault) and nan latency or theta_d_hat."""

MAX_ABS_VALUE = 2.0 ** 31
"""Largest magnitude of a measured number in a log's rows (time base, reference, command, sensors): a 32-bit counter's range, past every
encoder, accelerometer, DAC or reference count and any run's time in s or ms. A larger finite
number (1e160, 1e308) is no measurement, and its squares, sums and conversions to whole
counts overflow in whatever reads the log next (a diagnosis's cost, a table's format): the
reader refuses it, naming its line and field."""

def standard_column(name: str) -> str:
    """The standard name of a column as printed in a log (itself when not a known synonym).

    Parameters
    ----------
    name : str
        e.g. ``"Time (sec.)"``, ``"$\\theta$"``, ``"accel"``.

    Returns
    -------
    str
        One of :data:`COLUMNS` (see :data:`COLUMN_SYNONYMS`), else ``name`` stripped. A name
        in quotes (a spreadsheet's CSV) or with its unit after it (``"theta (counts)"``,
        ``cmd [DAC]``) is its synonym's too.
    """
    key = name.strip()
    if len(key) > 1 and key[0] == key[-1] and key[0] in "\"'":
        key = key[1:-1].strip()
    std = _SYNONYM_OF.get(key.lower())
    if std is None:
        std = _SYNONYM_OF.get(_UNIT.sub("", key).lower())
    return key if std is None else std


class RunLogError(StationError):
    """A run log that cannot be read or written; names the file, line and what was expected
    (also as the attributes ``file``, ``line`` and ``key``, see :class:`StationError`)."""


def log_error(path: str | Path, line: int | None, what: str, key: str | None = None) -> RunLogError:
    """The one form of a run log error: ``"{path}: line {line}: {what}"`` with its place as attributes.

    Parameters
    ----------
    path : str or Path
        The log.
    line : int or None
        1-based line number, None when the error is about the whole file.
    what : str
        What is wrong and what was expected.
    key : str, optional
        The column or header field at fault.

    Returns
    -------
    RunLogError
    """
    where = f"{path}: line {line}: " if line is not None else f"{path}: "
    return RunLogError(where + what, file=path, line=None if line is None else int(line), key=key)
