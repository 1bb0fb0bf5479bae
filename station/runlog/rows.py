"""A log's rows: its lines numbered, the data lines (the torn last line decided here, once),
and the rows as an array.

The rows are parsed by ``numpy.loadtxt`` from a stream of lines, without a Python list per
row (a 100 MB log reads within a few times its size, ``scripts/bench_read.py``). Only a
file that numpy refuses is read again, through the same :class:`DataLines`, row by row, to
name the bad row's line and field.

Imports :mod:`station.runlog.schema` and :func:`station.inputs.open_regular` (the one way a given file is opened).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np

from station.inputs import open_regular
from station.runlog.schema import log_error

SEPARATOR_NAMES = {"\t": "tab", ",": "comma", ";": "semicolon", None: "whitespace"}
"""How an error names a delimiter (None: any whitespace)."""


def is_number(text: str) -> bool:
    """Whether Python reads ``text`` as a float.

    Parameters
    ----------
    text : str
        One field.
    """
    try:
        float(text)
    except ValueError:
        return False
    return True


def rows_separator(line: str, names: list[str], sep: str | None) -> str | None:
    """The delimiter of a log's rows: the column line's, unless it does not part the first data
    row into one field per column and another delimiter does (a script that printed its column
    line with tabs and its rows with spaces or commas).

    Parameters
    ----------
    line : str
        The first data row, without its newline.
    names : list of str
        The columns' standard names.
    sep : str or None
        The column line's delimiter; None: any whitespace.

    Returns
    -------
    str or None
        The delimiter to read every row with (None: any whitespace).
    """
    if len(line.split(sep)) == len(names):
        return sep
    others = [d for d in ("\t", ",", ";") if d != sep and d in line] + ([None] if sep is not None else [])
    return next((d for d in others if len(line.split(d)) == len(names)), sep)


def decimal_comma(text: str) -> bool:
    """Whether one field is a number written with a decimal comma (``0,002``; not ``1.000,5``).

    Parameters
    ----------
    text : str
        One field.
    """
    return "," in text and "." not in text and is_number(text.replace(",", ".", 1))


def parse_row(line: str, names: list[str], sep: str | None) -> tuple[list[float] | None, str | None]:
    """One data line as numbers, or what is wrong with it.

    Parameters
    ----------
    line : str
        The line without its newline.
    names : list of str
        The columns' standard names (the row needs one number for each).
    sep : str or None
        The delimiter; None: any whitespace.

    Returns
    -------
    values : list of float or None
        The row's numbers, None when it is malformed.
    problem : str or None
        What was expected and found (names the column), None for a good row.
    """
    parts = line.split(sep)
    if len(parts) != len(names):
        return None, f"expected {len(names)} {SEPARATOR_NAMES[sep]}-separated numbers, got {len(parts)}"
    wide = next((j for j, p in enumerate(parts) if not p.isascii()), None)
    if wide is not None:  # float() reads other scripts' digits ("١٢" is 12): no log writes them
        return None, f"expected a number in column {names[wide]!r}, got {parts[wide]!r} (characters outside ASCII)"
    try:
        return [float(p) for p in parts], None
    except ValueError:
        bad = next(j for j, p in enumerate(parts) if not is_number(p))
        comma = sep != "," and decimal_comma(parts[bad])
        return None, (f"expected a number in column {names[bad]!r}, got {parts[bad]!r}"
                      + (" (a decimal comma: the log must be written with '.' decimals)" if comma else ""))


def decimal_comma_row(line: str, names: list[str], sep: str | None) -> bool:
    """Whether a data line is written with decimal commas (a spreadsheet's export where the
    fields are parted by ';', tabs or spaces: ``0,002;1;50``): it has a comma, no point, fields
    that are not all numbers as written, and every field a number with its comma a point.
    With commas between fields a decimal comma cannot be told from them: never.

    Parameters
    ----------
    line : str
        The line without its newline.
    names : list of str
        The columns' standard names.
    sep : str or None
        The delimiter; None: any whitespace.
    """
    if sep == "," or "," not in line or "." in line:
        return False
    return parse_row(line, names, sep)[1] is not None and parse_row(line.replace(",", "."), names, sep)[1] is None


MAX_LINE = 1_000_000
"""Longest line of a run log, characters: a row is under 200, our JSON header a few
thousand; a longer line (a binary file, a file without newlines) is no log, and reading
it whole could take all the memory there is."""


class LineTooLong(Exception):
    """A line of more than :data:`MAX_LINE` characters (:meth:`Lines.next`).

    Parameters
    ----------
    lineno : int
        Its 1-based line number.
    """

    def __init__(self, lineno: int):
        super().__init__(f"line {lineno}: longer than {MAX_LINE} characters")
        self.lineno = lineno


class Lines:
    """A text file's lines, numbered from 1, without their newline (and a trailing CR),
    with a push-back for the header parsers; no line longer than :data:`MAX_LINE` is read.

    Parameters
    ----------
    fh : text file
        Opened with ``newline=""`` (line ends kept, so a last line without one shows).
    """

    def __init__(self, fh) -> None:
        self.fh = fh
        self.lineno = 0
        self._back: list[tuple[int, str, bool]] = []

    def next(self) -> tuple[int, str, bool] | None:
        """The next line as (line number, text, terminated), None at the end of the file;
        ``terminated`` is False for a last line with no newline.

        Raises
        ------
        LineTooLong
            The line is longer than :data:`MAX_LINE` characters (not read further).
        """
        if self._back:
            return self._back.pop()
        raw = self.fh.readline(MAX_LINE + 2)  # (+2: the line's end, "\r\n")
        if not raw:
            return None
        if len(raw) > MAX_LINE and len(raw.rstrip("\r\n")) > MAX_LINE:
            raise LineTooLong(self.lineno + 1)
        self.lineno += 1
        terminated = raw.endswith("\n")
        return self.lineno, raw.rstrip("\n").rstrip("\r"), terminated

    def push(self, item: tuple[int, str, bool]) -> None:
        """Put a line back; :meth:`next` returns it again (last pushed, first returned).

        Parameters
        ----------
        item : tuple
            As :meth:`next` returned it.
        """
        self._back.append(item)

    @property
    def next_lineno(self) -> int:
        """The number of the line :meth:`next` returns next."""
        return self._back[-1][0] if self._back else self.lineno + 1


class DataLines:
    """The data lines of a log, for numpy's parser or a row-by-row pass: blank and ``#``
    lines left out (the last non-blank line is kept for the end record), a rig log's row
    ending in its delimiter taken without it, and a torn last line skipped with a warning.

    A last line without a newline is torn (the writer was interrupted mid-row) in our
    format, whose writer ends every row; in the rig's formats only when it is not a whole
    row (:func:`parse_row`).

    Parameters
    ----------
    path : Path
        The log (for the warning).
    lines : Lines
        Positioned at the first line after the header.
    fmt : {"station", "rig"}
        The log's format.
    names : list of str
        The columns' standard names.
    sep : str or None
        The delimiter; None: any whitespace.

    Attributes
    ----------
    lineno : int or None
        Line number of the line last yielded.
    first_lineno : int or None
        Line number of the first data line.
    last : tuple or None
        The last non-blank line seen, as :meth:`Lines.next` returns it.
    torn : int
        Torn lines skipped (0 or 1).
    resumed : list of (int, int)
        Where rows start again after ``#`` lines among them: the first such line's number and
        the rows before it.
    """

    def __init__(self, path: Path, lines: Lines, fmt: str, names: list[str], sep: str | None) -> None:
        self.path, self.lines, self.fmt, self.names, self.sep = path, lines, fmt, names, sep
        self.lineno: int | None = None
        self.first_lineno: int | None = None
        self.last: tuple[int, str, bool] | None = None
        self.torn = 0
        self.resumed: list[tuple[int, int]] = []
        self._comment: int | None = None
        self._rows = 0
        self.non_ascii = False
        self._comma: bool | None = None

    @property
    def decimal_comma(self) -> bool:
        """Whether the rows are written with decimal commas (:func:`decimal_comma_row`), read as points."""
        return bool(self._comma)

    def __iter__(self):
        while (item := self.lines.next()) is not None:
            lineno, line, terminated = item
            if not line.strip():
                continue
            self.last = item
            if line.startswith("#"):
                if self.first_lineno is not None and self._comment is None:
                    self._comment = lineno
                continue
            if self._comment is not None:  # rows again after '#' lines among the rows
                self.resumed.append((self._comment, self._rows))
                self._comment = None
            if self.first_lineno is None:
                self.first_lineno = lineno
            if self._comma is None and "," in line:  # decided on the first row with a comma
                self._comma = self.fmt != "station" and decimal_comma_row(line, self.names, self.sep)
            if self.fmt != "station" and '"' in line:
                line = line.replace('"', "")  # a spreadsheet's or R's write.csv's quoted fields ("1",0.002,...)
            if self._comma:
                line = line.replace(",", ".")
            if self.sep and self.fmt != "station" and line.endswith(self.sep):
                line = line[:-len(self.sep)]  # a lab script's `"%g\t" % x` for every field, the last too
            if not terminated and (self.fmt == "station" or parse_row(line, self.names, self.sep)[1] is not None):
                self.torn += 1
                warnings.warn(f"{self.path}: line {lineno}: torn last line (no newline; the writer was "
                              f"interrupted mid-row) skipped", RuntimeWarning, stacklevel=4)
                continue
            if not line.isascii():  # Python reads "١٢" as 12: the row-by-row pass names it (parse_row)
                self.non_ascii = True
            self.lineno = lineno
            self._rows += 1
            yield line


def load_rows(path: Path, lines: Lines, fmt: str, names: list[str], sep: str | None) -> tuple[np.ndarray, DataLines]:
    """The rows after the header as an array, by numpy's parser from a line stream.

    Parameters
    ----------
    path : Path
        The log; read again, line by line, only when numpy refuses a row.
    lines : Lines
        The open file, positioned after the header.
    fmt : {"station", "rig"}
        The log's format (decides a torn last line, see :class:`DataLines`).
    names : list of str
        The columns' standard names.
    sep : str or None
        The delimiter; None: any whitespace.

    Returns
    -------
    rows : numpy.ndarray
        Shape (rows, len(names)), float64.
    data_lines : DataLines
        The pass that read them (first data line, last non-blank line, torn lines).

    Raises
    ------
    RunLogError
        A malformed row other than a torn last line: names the line and the field.
    """
    first = lines.next_lineno
    data_lines = DataLines(path, lines, fmt, names, sep)
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*input contained no data", category=UserWarning)
            arr = np.loadtxt(iter(data_lines), dtype=float, delimiter=sep, comments=None, ndmin=2, encoding=None)
        if arr.size == 0:
            arr = np.empty((0, len(names)))
        if arr.shape[1] == len(names) and not data_lines.non_ascii:
            return arr, data_lines
    except UnicodeDecodeError:
        raise
    except ValueError:
        pass
    return _rows_one_by_one(path, first, fmt, names, sep)


def _rows_one_by_one(path: Path, first: int, fmt: str, names: list[str],
                     sep: str | None) -> tuple[np.ndarray, DataLines]:
    """:func:`load_rows`'s exact (slow) pass from line ``first`` on, only for a file numpy
    refused: the same data lines, each parsed by :func:`parse_row` to name the bad one."""
    with open_regular(path, "run log", text=True) as fh:
        lines = Lines(fh)
        while lines.lineno < first - 1 and lines.next() is not None:
            pass
        data_lines = DataLines(path, lines, fmt, names, sep)
        rows: list[list[float]] = []
        for line in data_lines:
            values, problem = parse_row(line, names, sep)
            if problem is not None:
                raise log_error(path, data_lines.lineno, problem)
            rows.append(values)
    return np.array(rows, dtype=float).reshape(len(rows), len(names)), data_lines
