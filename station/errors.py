"""Errors meant for the user: the CLI prints them as one line, without a traceback."""

from __future__ import annotations

from pathlib import Path


class StationError(Exception):
    """A failure the user can act on (bad file, missing port, bad option).

    The message names the file, line, field or port and what was expected. Where the
    error is about a place, it also carries it as attributes, so other code never parses
    the message.

    Parameters
    ----------
    message : str
        One line for the user.
    file : str or Path, optional
        The file at fault.
    line : int, optional
        Its 1-based line number.
    key : str, optional
        The field, header key, column or option at fault.
    """

    exit_code = 2
    """The CLI's exit code for it: 2, bad input or a set-up error (nothing started); a failure
    of the work itself (:class:`station.pools.WorkerLost`) says 1."""

    def __init__(self, message: str = "", *, file: str | Path | None = None, line: int | None = None,
                 key: str | None = None):
        super().__init__(message)
        self.file = None if file is None else str(file)
        self.line = line
        self.key = key


def one_line(text: str) -> str:
    """``text`` as one line for the user: control characters and Unicode line or paragraph
    separators (which a file's key or a path may hold) shown as escapes (``\\n``, ``\\x1e``).

    Parameters
    ----------
    text : str
        A message.
    """
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() or c == " " else c.encode("unicode_escape").decode("ascii") for c in text)
