"""Checked command-line values: one mechanism for every command's numeric options and output paths.

A numeric option is declared with ``type=number(low, high, ...)``: argparse calls it on
the text, so a value that is not finite or outside the range is refused while the
arguments are parsed - before any file is opened or any device is touched - with
argparse's own one-line ``argument --x: ...`` error and exit code 2
(:class:`StationParser`). :func:`document_ranges` appends each option's range to its
``--help`` text, so the documented range is the checked one.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile
from pathlib import Path

from station.errors import StationError


class Number:
    """An argparse ``type=`` that parses a finite number within ``[low, high]``.

    Parameters
    ----------
    low, high : float
        Inclusive bounds (``integer``: whole numbers only).
    integer : bool
        Accept whole numbers only (returns ``int``).
    unit : str
        Unit shown in the range and the error (e.g. "s", "encoder counts").
    nonzero : bool
        Refuse 0 inside the range (e.g. a step height).
    """

    def __init__(self, low: float, high: float, integer: bool = False, unit: str = "", nonzero: bool = False):
        self.low, self.high, self.integer, self.unit, self.nonzero = low, high, integer, unit, nonzero
        self.__name__ = "integer" if integer else "number"  # argparse names the type in its errors

    def range_text(self) -> str:
        """The documented range, e.g. ``range 0.001..60 s`` or ``range 1..100, integer``."""
        unit = f" {self.unit}" if self.unit else ""
        kind = ", whole number" if self.integer else ""
        nz = ", not 0" if self.nonzero else ""
        fmt = (lambda x: str(int(x))) if self.integer else (lambda x: f"{x:.10g}")
        return f"range {fmt(self.low)}..{fmt(self.high)}{unit}{kind}{nz}"

    def __call__(self, text: str):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number (expected {self.range_text()})") from None
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"{text} is not a finite number (expected {self.range_text()})")
        if self.integer:
            if value != int(value):
                raise argparse.ArgumentTypeError(f"{text} is not a whole number (expected {self.range_text()})")
            value = int(value)
        if not self.low <= value <= self.high or (self.nonzero and value == 0):
            raise argparse.ArgumentTypeError(f"{text} is out of range (expected {self.range_text()})")
        return value

    def __repr__(self) -> str:
        return f"number({self.low!r}, {self.high!r}, integer={self.integer})"


def number(low: float, high: float, integer: bool = False, unit: str = "", nonzero: bool = False) -> Number:
    """``type=`` for a numeric option: finite and within ``[low, high]`` (see :class:`Number`).

    Parameters
    ----------
    low, high : float
        Inclusive bounds.
    integer : bool, default False
        Accept whole numbers only (returns ``int``).
    unit : str, optional
        Unit shown in the range and the error.
    nonzero : bool, default False
        Refuse 0 inside the range.
    """
    return Number(low, high, integer=integer, unit=unit, nonzero=nonzero)


class StationParser(argparse.ArgumentParser):
    """An ArgumentParser whose errors are one line: ``station step: error: argument --x: ...``, exit 2.

    (argparse's default prints the usage first; the user asked for one line naming the
    option, and ``--help`` is there for the usage.)
    """

    def error(self, message: str):
        """argparse's hook: print ``PROG: error: MESSAGE`` on one line and exit 2.

        Parameters
        ----------
        message : str
            argparse's message (names the option and what was expected).
        """
        self.exit(2, f"{self.prog}: error: {message}\n")


def document_ranges(parser: argparse.ArgumentParser) -> None:
    """Append each :class:`Number` option's range to its help text (idempotent).

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A command's parser, its options added.
    """
    for action in parser._actions:
        if isinstance(action.type, Number) and action.help not in (None, argparse.SUPPRESS):
            text = action.type.range_text()
            if text not in action.help:
                action.help = f"{action.help} [{text}]"


def numeric_actions(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """The parser's options that take numbers: those with a :class:`Number` type or int/float.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        A command's parser, its options added.
    """
    return [a for a in parser._actions if a.option_strings and (isinstance(a.type, Number) or a.type in (int, float))]


def check_writable(path: Path | None, option: str, overwrite: bool = True) -> None:
    """Refuse, before a run, an output file that could not be written afterwards.

    Parameters
    ----------
    path : Path or None
        The output file (None: nothing to check).
    option : str
        The option's name, for the message (e.g. "--json").
    overwrite : bool
        False: an existing file is an error (``--out`` without ``--force``).

    Raises
    ------
    StationError
        The file exists and ``overwrite`` is False, it is a folder, it exists read-only,
        or its folder cannot be created or written.
    """
    if path is None:
        return
    path = Path(path)
    if path.is_dir():
        raise StationError(f"{option} {path}: is a folder, expected a file")
    if path.exists():
        if not overwrite and path.is_file():
            raise StationError(f"{option} {path}: exists; use --force to overwrite it, or another name")
        if not os.access(path, os.W_OK):
            raise StationError(f"{option} {path}: exists and is not writable")
        return
    check_writable_dir(path.parent, option, what=f"{option} {path}: its folder")


def check_writable_dir(folder: Path | None, option: str, what: str | None = None) -> None:
    """Refuse an output folder that does not exist and cannot be created, or is not writable.

    Parameters
    ----------
    folder : Path or None
        The output folder (None: nothing to check); created later if missing.
    option : str
        The option that named it, for the message.
    what : str, optional
        How the message names it (default ``"OPTION FOLDER"``).

    Raises
    ------
    StationError
        Naming ``option`` and the folder.
    """
    if folder is None:
        return
    folder = Path(folder)
    what = what or f"{option} {folder}"
    existing = folder
    while not existing.exists():  # the nearest existing ancestor decides whether it can be created
        if existing.parent == existing:
            break
        existing = existing.parent
    if existing.exists() and not existing.is_dir():
        raise StationError(f"{what}: {existing} is a file, not a folder")
    try:  # a real probe: permission bits say nothing for root or on /proc-like file systems
        with tempfile.TemporaryFile(dir=existing):
            pass
    except OSError as exc:
        raise StationError(f"{what}: {existing} is not writable ({exc.strerror or exc})") from None


def warn(message: str) -> None:
    """One line on stderr that says which value wins (``station: note: ...``).

    Parameters
    ----------
    message : str
        The note, one line.
    """
    print(f"station: note: {message}", file=sys.stderr)


def add_model_options(parser: argparse.ArgumentParser, model_help: str = "") -> None:
    """``--model NAME|FILE``, ``--elements N`` and ``--params SET`` (DESIGN.md "Model file"),
    the same for every command that simulates the model against logs.

    Parameters
    ----------
    parser : argparse.ArgumentParser
        The command's subparser.
    model_help : str
        What the command does with the model, appended to ``--model``'s help.
    """
    parser.add_argument("--model", default=None, metavar="NAME|FILE",
                        help="the model: a built-in model's name (station/plant/models) or a model file "
                             "(default tmm-fit)" + (f"; {model_help}" if model_help else ""))
    parser.add_argument("--elements", type=number(1, 100, integer=True), default=None, metavar="N",
                        help="beam elements of the model (default: the model's, 4)")
    parser.add_argument("--params", default=None, metavar="SET",
                        help="parameter set name or TOML file (default: the model's, tmm-fit)")
