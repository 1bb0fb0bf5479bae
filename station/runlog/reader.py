"""The reader: one function, :func:`read_log`, for ours and the rig's layouts.

The header is read line by line and decides the layout (ours, or one of :mod:`station.runlog.rig_layouts`'s
two); the rows go through :func:`station.runlog.rows.load_rows`; then the checks that need
whole columns (finite numbers where they belong), the time base and the end record.

Imports :mod:`station.runlog.schema`, ``.rows``, ``.rig``, ``.timebase`` and ``.log``, and
:func:`station.inputs.check_regular` (a log is a regular file).
"""

from __future__ import annotations

import json
import math
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from station.errors import StationError
from station.inputs import MAX_JSON_DEPTH, json_depth, open_regular
from station.runlog.log import RunLog
from station.runlog.rig_layouts import Header, parse_column_line, parse_rig_header
from station.runlog.rows import MAX_LINE, LineTooLong, Lines, load_rows, rows_separator
from station.runlog.schema import (COLUMN_LINE, COLUMNS, END_PREFIX, FINITE_COLUMNS, MAGIC, MAX_ABS_VALUE, RunLogError,
                                   log_error)

MAX_HEADER_LINES = 1000
"""Most ``#`` lines of a rig log's header (it has about ten): a file of comments is no log."""
from station.runlog.timebase import complete_time_base


def read_log(path: str | Path) -> RunLog:
    """Read a run log, ours or the rig's (format detected from the header).

    Layouts: ours; the rig's ``#`` header whose last line names the columns; or, without
    a ``#`` header, a first line of column names (tab, comma, semicolon or whitespace
    separated; the rig's 2014 logs and cut-down copies). Columns are mapped to the
    standard names by :data:`COLUMN_SYNONYMS`; n is derived from t when missing (t from
    n at 0.002 s when t is missing). A last line ``# end {json}`` is the run's outcome.

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    RunLog
        ``data`` holds every name of :data:`COLUMNS` (NaN-filled where the format lacks
        the column; the rig's logs have no v_applied, status, latency_us, and no
        theta_d_hat without accelerometer feedback; cut-down copies may lack u, n, a),
        ``sample_time`` the sample time found in t (``dt`` the one to use), ``notes``
        what was derived.

    Raises
    ------
    RunLogError
        File missing, not a regular file or unreadable, a line longer than
        :data:`station.runlog.rows.MAX_LINE`, more than :data:`MAX_HEADER_LINES` header
        lines, unknown format, bad header, no usable columns (lists
        the columns found and expected), or a malformed row other than a torn last line
        (names the file, line number and what was expected).

    Warns
    -----
    RuntimeWarning
        When a torn last line (interrupted write) is skipped.

    Examples
    --------
    A cut-down copy of a rig log, a first line of column names and three rows:

    >>> import tempfile
    >>> from pathlib import Path
    >>> import numpy as np
    >>> from station.runlog import read_log
    >>> path = Path(tempfile.mkdtemp()) / "step.csv"
    >>> rows = [[0.000, 0, 0, 0, 0], [0.002, 50, 100, 0, 2], [0.004, 50, 100, 3, 5]]
    >>> np.savetxt(path, rows, fmt="%g", delimiter=",", header="t,u,v,theta,a", comments="")
    >>> log = read_log(path)
    >>> log.data["theta"].tolist(), log.dt
    ([0.0, 0.0, 3.0], 0.002)
    >>> log.notes                                                 # what was derived
    ['no sample column: n derived from t (sample time 0.002 s)']
    >>> bool(np.isnan(log.data["v_applied"]).all())               # not in the rig's logs
    True
    >>> from station.runlog import RunLogError
    >>> try:
    ...     read_log(path.with_name("missing.tsv"))
    ... except RunLogError as exc:                            # a StationError: one line
    ...     print(exc)
    /.../missing.tsv: run log not found
    """
    path = Path(path)
    try:
        return _read_path(path, "strict")
    except UnicodeDecodeError as exc:
        byte = exc.object[exc.start:exc.start + 1].hex()
        bad = _undecodable_lines(path)
        if not bad or not all(text.startswith("#") for _, text in bad):
            raise log_error(path, bad[0][0] if bad else None, f"not a text run log (byte 0x{byte}: not UTF-8 "
                            f"text, which a run log is)") from None
    # only '#' lines are not UTF-8 (a comment written in a Windows code page: "20°C"); a field's
    # line among them is refused by the header's parser (a number with "\ufffd" is none)
    log = _read_path(path, "replace")
    warnings.warn(f"{path}: line {bad[0][0]}: {len(bad)} '#' line(s) not UTF-8 text (a comment written in "
                  f"another code page): read with those characters replaced", RuntimeWarning, stacklevel=2)
    return log


def _read_path(path: Path, errors: str) -> RunLog:
    """:func:`read_log` with the text decoder's error handling ``errors``."""
    with open_log(path, errors) as fh:
        try:
            return _read_stream(path, Lines(fh))
        except LineTooLong as exc:
            raise log_error(path, exc.lineno, f"longer than {MAX_LINE} characters: not a run log") from None
        except OSError as exc:
            raise log_error(path, None, f"cannot read run log: {exc.strerror or exc}") from None


def open_log(path: Path, errors: str = "strict"):
    """``path`` opened as a run log's text (:func:`station.inputs.open_regular`: a folder, a FIFO
    (opening it would block) or a device (/dev/zero never ends) is no log).

    Parameters
    ----------
    path : Path
        The log.
    errors : str
        The text decoder's error handling ("replace" to find a line's number in a bad file).

    Returns
    -------
    file object
        Text, UTF-8 (a leading byte-order mark dropped), lines as written.

    Raises
    ------
    RunLogError
        Not a regular file, missing or unreadable (naming the file).
    """
    try:
        return open_regular(path, "run log", text=True, errors=errors)
    except StationError as exc:
        if exc.__class__ is RunLogError:
            raise
        raise RunLogError(str(exc), file=path) from None


def _names(text: str) -> bool:
    """Whether a line under the ``#`` lines names columns (a 2014 log's first line with a comment
    put above it) rather than holding the first row: its first field is no number."""
    first = re.split(r"[\t,;]|\s+", text.strip(), maxsplit=1)[0].strip().strip('"')
    if not first:
        return False
    try:
        float(first.replace(",", "."))
    except ValueError:
        return True
    return False


def _read_stream(path: Path, lines: Lines) -> RunLog:
    """:func:`read_log` on an open text file: header line by line, rows by numpy's parser."""
    head: list[tuple[int, str, bool]] = []
    while len(head) < 3 and (item := lines.next()) is not None:
        head.append(item)
    while head and not head[-1][1].strip() and (item := lines.next()) is not None:
        head.append(item)  # (leading blank lines: keep looking for a header)
    if not head or not any(h[1].strip() for h in head):
        raise log_error(path, None, "empty file, expected a run log header")
    texts = [h[1] for h in head]

    if MAGIC in texts[:2]:
        fmt = layout = "station"
        for extra in reversed(head[3:]):
            lines.push(extra)
        found = _station_header(path, texts)
        header = texts[:3]
    elif texts[0].startswith("#"):
        fmt = layout = "rig"
        for extra in reversed(head):
            lines.push(extra)
        header = []
        while (item := lines.next()) is not None:
            if not item[1].strip():  # a blank line among the header's: it ends nothing
                continue
            if not item[1].startswith("#"):
                lines.push(item)
                break
            header.append(item[1])
            if len(header) > MAX_HEADER_LINES:
                raise log_error(path, item[0], f"more than {MAX_HEADER_LINES} '#' header lines before the first "
                                f"row: not a run log (the rig's header has about ten)")
        if (item := lines.next()) is not None and _names(item[1]):  # a line of names under the comments: the columns
            header.append("#" + item[1])
        elif item is not None:
            lines.push(item)
        found = parse_rig_header(path, header)
    else:
        fmt, layout = "rig", "columns"
        found = parse_column_line(path, texts[0])
        bare = not found.meta["columns"]  # line 1 is a row: the rig's rows without a header
        for extra in reversed(head if bare else head[1:]):
            lines.push(extra)
        header = [] if bare else texts[:1]
        layout = "bare" if bare else layout

    names, notes = found.names, list(found.notes)
    sep = found.sep
    if fmt == "rig" and (item := _first_row(lines)) is not None:
        sep = rows_separator(item[1], names, found.sep)
    arr, data_lines = load_rows(path, lines, fmt, names, sep)
    if data_lines.decimal_comma:
        notes.append("numbers written with decimal commas (a spreadsheet's export): read with their commas as points")
    n = arr.shape[0]
    data = {name: np.full(n, np.nan) for name in COLUMNS}
    for j, name in enumerate(names):
        data[name] = arr[:, j]
    del arr
    _check_finite(path, data, names, fmt, data_lines.first_lineno)
    _one_run(path, data, data_lines.resumed)
    sample_time = complete_time_base(data, names, notes)
    outcome = None if data_lines.last is None else _end_record(path, *data_lines.last)
    return RunLog(path=path, format=fmt, meta=found.meta, data=data, header=header, layout=layout,
                  sample_time=sample_time, outcome=outcome, notes=notes)


def _station_header(path: Path, texts: list[str]) -> Header:
    """Our header from the file's first lines: column line, magic, JSON (what we write);
    or magic, JSON, column line."""
    if len(texts) < 3:
        raise log_error(path, len(texts) + 1, f"expected the header to go on "
                        f"(column names, '{MAGIC}', '# ' and the JSON metadata)")
    if texts[0] == MAGIC:
        (json_no, json_line), (col_no, col_line) = (2, texts[1]), (3, texts[2])
    else:
        (json_no, json_line), (col_no, col_line) = (3, texts[2]), (1, texts[0])
    if not json_line.startswith("# "):
        raise log_error(path, json_no, f"expected '# ' and the JSON metadata, got {json_line[:60]!r}")
    try:
        meta = json.loads(json_line[2:])
    except json.JSONDecodeError as exc:
        raise log_error(path, json_no, f"metadata is not valid JSON ({exc.msg})") from None
    except RecursionError:
        raise log_error(path, json_no, "metadata JSON is nested too deeply") from None
    if json_depth(meta) > MAX_JSON_DEPTH:
        raise log_error(path, json_no, f"metadata JSON is nested too deeply (at most {MAX_JSON_DEPTH} levels)")
    if not isinstance(meta, dict):
        raise log_error(path, json_no, "expected a JSON object of metadata")
    _check_meta(path, json_no, meta)
    names = col_line.split("\t")
    if tuple(names[:len(COLUMNS)]) != COLUMNS:
        raise log_error(path, col_no, f"expected the column names {COLUMN_LINE!r}, got {col_line!r}")
    return Header(meta, names, "\t", [])


def _first_row(lines: Lines) -> tuple[int, str, bool] | None:
    """The first non-blank line after the header (as :meth:`Lines.next` gives it), left in ``lines``."""
    seen = []
    while (item := lines.next()) is not None:
        seen.append(item)
        if item[1].strip():
            break
    for back in reversed(seen):
        lines.push(back)
    return seen[-1] if seen and seen[-1][1].strip() else None


def _one_run(path: Path, data: dict[str, np.ndarray], resumed: list[tuple[int, int]]) -> None:
    """Refuse a file that holds more than one run: rows that start again after ``#`` lines
    with t (or n) back at or before the file's first."""
    clock = next((data[c] for c in ("t", "n") if np.all(np.isfinite(data[c]))), None)
    for lineno, before in resumed:
        if clock is not None and 0 < before < clock.size and clock[before] <= clock[0]:
            raise log_error(path, lineno, f"a second header: the file holds more than one run (after {before} rows, "
                            f"{'t' if clock is data['t'] else 'n'} starts again at {clock[before]:g}); split it "
                            f"at line {lineno}")


def _check_finite(path: Path, data: dict[str, np.ndarray], names: list[str], fmt: str,
                  first_lineno: int | None) -> None:
    """RunLogError naming the line and the field of the first non-finite value where a number
    belongs, or of the first number of a measured column (the time base, reference, command and
    sensors) past :data:`MAX_ABS_VALUE` in magnitude."""
    must = FINITE_COLUMNS + (("v", "theta_d_hat") if fmt == "rig" else ())
    measured = must + ("v", "v_applied")  # what analysis computes with; ours may log any theta_d_hat, latency
    for name in names:
        col = data[name]
        if name in must:
            bad = np.flatnonzero(~np.isfinite(col))
            if bad.size:
                line = _line_of_row(path, first_lineno, int(bad[0]))
                raise log_error(path, line, f"{name} is {float(col[bad[0]])!r}, expected a finite number "
                                f"(a log with missing samples cannot be used as it is)", key=name)
        if name not in measured:
            continue
        with np.errstate(invalid="ignore"):
            big = np.flatnonzero(np.abs(col) > MAX_ABS_VALUE)  # (NaN compares False: allowed where it is)
        if big.size:
            line = _line_of_row(path, first_lineno, int(big[0]))
            value = float(col[big[0]])
            raise log_error(path, line, f"{name} is {value:.6g}, past any measurement (at most ±2^31 = "
                            f"±{MAX_ABS_VALUE:.0f}, a 32-bit counter's range)", key=name)


def _undecodable_lines(path: Path) -> list[tuple[int, str]]:
    """The lines that are not UTF-8 text, (number, text with U+FFFD for each bad byte); [] for
    none found again, or a binary file without newlines."""
    bad = []
    with open_log(path, errors="replace") as fh:
        lines = Lines(fh)
        try:
            while (item := lines.next()) is not None:
                if "\ufffd" in item[1]:
                    bad.append(item[:2])
        except LineTooLong:  # a binary file without newlines: no line to name
            return []
    return bad


def _line_of_row(path: Path, first_lineno: int | None, row: int) -> int:
    """The line number of data row ``row`` (0-based), counting blank and ``#`` lines."""
    if first_lineno is None:
        return 0
    seen = -1
    with open_log(path, errors="replace") as fh:
        for lineno, line in enumerate(fh, 1):
            if lineno < first_lineno or not line.strip() or line.startswith("#"):
                continue
            seen += 1
            if seen == row:
                return lineno
    return first_lineno + row


def _check_meta(path: Path, lineno: int, meta: dict[str, Any]) -> None:
    """RunLogError for header fields the readers rely on that make no sense (dt)."""
    if "dt" in meta:
        dt = meta["dt"]
        if isinstance(dt, bool) or not isinstance(dt, (int, float)) or not (math.isfinite(dt) and 0 < dt <= 1):
            raise log_error(path, lineno, f"header field dt is {dt!r}, expected the sample time "
                            f"in s, a number in (0, 1]", key="dt")


def _end_record(path: Path, lineno: int, line: str, terminated: bool) -> dict[str, Any] | None:
    """The run's outcome from the last non-blank line when it is ``# end {json}`` (DESIGN.md "Run outcome"), or None."""
    if not line.startswith(END_PREFIX):
        return None
    try:
        outcome = json.loads(line[len(END_PREFIX):])
    except (json.JSONDecodeError, RecursionError) as exc:
        if not terminated:  # torn while being written
            warnings.warn(f"{path}: line {lineno}: torn end record skipped (outcome unknown)",
                          RuntimeWarning, stacklevel=3)
            return None
        msg = exc.msg if isinstance(exc, json.JSONDecodeError) else "nested too deeply"
        raise log_error(path, lineno, f"end record is not valid JSON ({msg})") from None
    if not isinstance(outcome, dict):
        raise log_error(path, lineno, f"expected a JSON object after '{END_PREFIX.strip()}'")
    if json_depth(outcome) > MAX_JSON_DEPTH:
        raise log_error(path, lineno, f"end record nested too deeply (at most {MAX_JSON_DEPTH} levels)")
    return outcome
