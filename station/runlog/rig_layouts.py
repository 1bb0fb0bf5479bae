"""The rig's layouts: its ``#`` header (test name, gains, filter coefficients, the last line
naming the columns) and a bare first line of column names (its 2014 logs, cut-down copies).

Imports :mod:`station.runlog.schema` and :mod:`station.runlog.rows`.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any, NamedTuple

from station.runlog.rows import decimal_comma, is_number
from station.runlog.schema import MAGIC, SIGNAL_COLUMNS, log_error, standard_column


class Header(NamedTuple):
    """A log's header understood.

    Attributes
    ----------
    meta : dict
        What the header says (see :class:`station.runlog.RunLog`).
    names : list of str
        The columns' standard names, in file order.
    sep : str or None
        The rows' delimiter; None: any whitespace.
    notes : list of str
        What the reader assumed (columns named by synonyms).
    """

    meta: dict[str, Any]
    names: list[str]
    sep: str | None
    notes: list[str]


_KV = re.compile(r"^\s*([A-Za-z_]\w*)\s*=\s*(.*?)\s*$")
_COEF = re.compile(r"^\s*(\w+)\s+(num|den)\s*=\s*\[(.*)\]\s*$")
_COEF_START = re.compile(r"^\s*(gth|ga)\b\s*(num|den)?", re.IGNORECASE)
"""The start of a filter's coefficient line, however it goes on (:data:`_COEF` is its whole form)."""
_KV_ALL = re.compile(r"^\s*(?:[A-Za-z_]\w*\s*=\s*[^\s,;=]+\s*[,;]?\s*){2,}$")
_KV_EACH = re.compile(r"([A-Za-z_]\w*)\s*=\s*([^\s,;=]+)")
"""Several ``key=value`` fields on one line (``#kp=2.0 ki=0 kd=0``, ``#kp=2.0, ki=0.0, kd=0.0``)."""
_DECIMAL_COMMA = re.compile(r"\d,\d")
"""A comma between two digits in a coefficient list: a decimal comma or a list with no spaces
(``[18,3 -17,2]`` or ``[1,2]``), which cannot be told apart and is refused."""
_KEYS = {name.lower(): name for name in ("kp", "ki", "kd", "b0", "b1", "a1", "Gth", "Ga")}
"""The controller's fields by their lower case: a header's ``#Kp=2`` or ``#GTH num=`` is the
rig software's ``#kp=2`` and ``#Gth num=``."""


def _split_names(line: str) -> tuple[list[str], str | None]:
    """The names of a column-name line and its delimiter (tab, comma, semicolon; None:
    whitespace)."""
    for sep in ("\t", ",", ";"):
        if sep in line:
            names = [c.strip() for c in line.split(sep)]
            return (names[:-1] if len(names) > 1 and not names[-1] else names), sep  # a trailing delimiter
    return line.split(), None


def _map_columns(path: Path, lineno: int, printed: list[str]) -> list[str]:
    """Standard names of the printed column names; RunLogError when none is usable."""
    std = [standard_column(c) for c in printed]
    if not ({"t", "n"} & set(std) and set(SIGNAL_COLUMNS) & set(std)):
        found = ", ".join(repr(c[:30]) for c in printed[:10]) + (", ..." if len(printed) > 10 else "") or "none"
        raise log_error(path, lineno, f"no usable columns: found {found}; expected a time "
                        f"column (t, time, 'Time (sec.)' or n) and at least one of u, v, "
                        f"theta ($\\theta$), a (accel)")
    dup = next((c for c in std if std.count(c) > 1), None)
    if dup is not None:
        raise log_error(path, lineno, f"column {dup!r} appears twice "
                        f"(as {', '.join(repr(p) for p, s in zip(printed, std) if s == dup)})")
    return std


def parse_rig_header(path: Path, comment_lines: list[str]) -> Header:
    """The rig's ``#`` header lines (the last names the columns) understood.

    Parameters
    ----------
    path : Path
        The log (for errors).
    comment_lines : list of str
        The header lines from line 1 on, each starting with ``#``.

    Returns
    -------
    Header
        meta: ``title`` (whole first line), ``test`` (its last word), gains as floats
        (other ``key=value`` fields as text), ``Gth`` / ``Ga`` as
        ``{"num": [...], "den": [...]}``, ``columns`` (the names as printed), ``notes``
        (other lines).

    Raises
    ------
    RunLogError
        No header, no usable columns, coefficients that are not finite numbers, den[0]
        = 0 or a num without den (names the line and the field).
    """
    if not comment_lines:
        raise log_error(path, 1, "expected '#' header lines naming the columns")
    meta: dict[str, Any] = {}
    *info, col_line = comment_lines
    names, sep = _split_names(col_line[1:])
    std = _map_columns(path, len(comment_lines), names)
    meta["columns"] = names
    other = []
    coef_lines: dict[str, int] = {}
    kv_lines: dict[str, int] = {}
    notes: list[str] = []
    for i, line in enumerate(info):
        body = line[1:].strip()
        coef = _COEF.match(body)
        kv = _KV.match(body)
        if not coef and i > 0 and (start := _COEF_START.match(body)) is not None:
            raise log_error(path, i + 1, f"expected {start.group(1)} num=[c0 c1 ...] or {start.group(1)} den=[...] "
                            f"(numbers between brackets, on one line), got {line[:80]!r}", key=start.group(1))
        if i == 0 and not kv and not coef:
            meta["title"] = body
            parts = body.split()
            meta["test"] = parts[-1] if parts else ""
        elif coef:
            text = coef.group(3)
            try:
                if _DECIMAL_COMMA.search(text):
                    raise ValueError
                # numpy's print (spaces) or a Python list's (commas): [ 18.3 -17.2] or [18.3, -17.2]
                values = [float(x) for x in re.split(r"[\s,]+", text.strip()) if x]
            except ValueError:
                why = (" (a comma between digits: a decimal comma, or numbers not spaced; expected "
                       "[c0 c1 ...] or [c0, c1, ...] with '.' decimals)" if _DECIMAL_COMMA.search(text) else "")
                raise log_error(path, i + 1, f"expected numbers in {coef.group(1)} "
                                f"{coef.group(2)}=[...], got {line!r}{why}", key=coef.group(1)) from None
            if not all(math.isfinite(x) for x in values) or (coef.group(2) == "den" and values and values[0] == 0):
                raise log_error(path, i + 1, f"{coef.group(1)} {coef.group(2)}={values}: expected finite "
                                f"coefficients" + (", den[0] not 0 (the filter would be non-causal)"
                                                   if coef.group(2) == "den" else ""), key=coef.group(1))
            name = _KEYS.get(coef.group(1).lower(), coef.group(1))
            if coef.group(2) in meta.get(name, {}):
                raise log_error(path, i + 1, f"{name} {coef.group(2)} given twice: expected one", key=name)
            meta.setdefault(name, {})[coef.group(2)] = values
            coef_lines[name] = i + 1
        elif kv:
            parts = [part for part in body.split(";") if part.strip()]
            fields = [_KV.match(part) for part in parts]
            # ';' parts fields whose values may hold spaces (#kp=2.0; title=foo bar)
            pairs = (_KV_EACH.findall(body) if _KV_ALL.match(body) else [f.groups() for f in fields]
                     if len(parts) > 1 and all(fields) else [kv.groups()])
            for key, val in pairs:
                key = _KEYS.get(key.lower(), key)
                if key in kv_lines:
                    raise log_error(path, i + 1, f"{key} given twice (lines {kv_lines[key]} and {i + 1}): "
                                    f"expected one", key=key)
                kv_lines[key] = i + 1
                try:
                    meta[key] = float(val)
                except ValueError:
                    if key in _KEYS.values() and "\ufffd" in val:  # read past a byte of another code page
                        raise log_error(path, i + 1, f"{key}: expected a number, got {val!r} (a byte that is not "
                                        f"UTF-8 text)", key=key) from None
                    if key in _KEYS.values() and decimal_comma(val):
                        meta[key] = float(val.replace(",", "."))  # one number: its comma can be nothing else
                        notes.append(f"{key}={val} read as {meta[key]:g} (a decimal comma)")
                    else:
                        meta[key] = val
        else:
            other.append(body)
    for key, lineno in coef_lines.items():  # a filter printed with a numerator needs its denominator
        if meta[key].get("num") and not meta[key].get("den"):
            raise log_error(path, lineno, f"{key} num={meta[key]['num']} has no den=[...] "
                            f"(expected both, as the rig's software prints them)", key=key)
    if other:
        meta["notes"] = other
    return Header(meta, std, sep, notes)


BARE_ORDER = ("t", "n", "u", "v", "theta", "a", "theta_d_hat")
"""The rig's columns in its logs' order (its header's last line: ``#t n u v $\\theta$ a
$\\hat{\\theta}_d$``), taken for rows saved without a header."""
BARE_COLUMNS = (6, 7)
"""How many numbers a row of the rig's own has (with or without θ̂_d)."""

BARE_ORDER_2014 = ("t", "u", "theta", "a", "v")
"""The 2014 logs' columns in their order (their line ``Time (sec.) u theta accel v``), taken for
rows of 5 numbers saved without it (a script that dropped the column line)."""

BARE_ORDERS = {len(BARE_ORDER_2014): BARE_ORDER_2014, **{k: BARE_ORDER[:k] for k in BARE_COLUMNS}}
"""The column order assumed for a bare row, by how many numbers it holds."""


def parse_column_line(path: Path, line: str) -> Header:
    """A first line of column names, without a ``#`` header, understood.

    Parameters
    ----------
    path : Path
        The log (for errors).
    line : str
        Line 1 of the file: names separated by tabs, commas, semicolons or whitespace.

    Returns
    -------
    Header
        meta ``{"columns": [names as printed]}``; a note lists the names taken as synonyms.
        A line of 6 or 7 numbers is a row of the rig's saved without a header (:data:`BARE_ORDER`
        assumed), one of 5 a row of its 2014 logs saved without their column line
        (:data:`BARE_ORDER_2014`); said in a note, ``columns`` empty: the caller reads it as data.

    Raises
    ------
    RunLogError
        A line of other numbers (no header at all), no usable columns, or a column twice.
    """
    printed, sep = _split_names(line)
    if printed and all(is_number(c) for c in printed):
        order = BARE_ORDERS.get(len(printed))
        if order is not None:  # the rig's rows saved without their header
            era = "2014 logs'" if order == BARE_ORDER_2014 else "rig's"
            return Header({"columns": []}, list(order), sep,
                          [f"no header: the {era} column order {' '.join(order)} assumed "
                           f"(the log audit checks it against the data)"])
        raise log_error(path, 1, f"expected '{MAGIC}' (station run log), the rig's '#' header or a line "
                        f"of column names, got {len(printed)} numbers {line[:60]!r} (the rig's rows without a "
                        f"header hold {' or '.join(map(str, sorted(BARE_ORDERS)))})")
    names = _map_columns(path, 1, printed)
    renamed = [f"{p!r} -> {s}" for p, s in zip(printed, names) if p != s]
    notes = ["columns named by synonyms: " + ", ".join(renamed)] if renamed else []
    return Header({"columns": printed}, names, sep, notes)
