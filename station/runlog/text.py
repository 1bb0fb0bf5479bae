"""Our format as text: values that read back to the same number, rows as lines, the header
and the end record.

Imports :mod:`station.runlog.schema` and :mod:`station.jsonio`.
"""

from __future__ import annotations

import json
import numbers
from collections.abc import Iterable
from typing import Any

import numpy as np

from station.jsonio import to_jsonable
from station.runlog.schema import COLUMN_LINE, END_PREFIX, MAGIC, RunLogError


def format_value(x: Any) -> str:
    """One value as text that reads back to the same number.

    Parameters
    ----------
    x : int, float, bool, None or numpy scalar

    Returns
    -------
    str
        ints as ints; floats by ``repr`` (shortest exact form, ``nan``, ``inf``); None
        as ``nan``.
    """
    tp = type(x)
    if tp is float:
        return repr(x)
    if tp is int:
        return str(x)
    if x is None:
        return "nan"
    if isinstance(x, (bool, np.bool_)):
        return "1" if x else "0"
    if isinstance(x, numbers.Integral):
        return str(int(x))
    return repr(float(x))


def format_lines(rows: Iterable[tuple]) -> list[str]:
    """Rows (tuples in :data:`COLUMNS` order) as tab-separated lines, each ending in a newline.

    Parameters
    ----------
    rows : iterable of tuple
        Rows in :data:`COLUMNS` order.
    """
    fmt = format_value
    return ["\t".join([fmt(x) for x in row]) + "\n" for row in rows]


def header_lines(meta: dict[str, Any]) -> list[str]:
    """The header of our format for ``meta``: column names, magic line, ``# {json}``.

    Parameters
    ----------
    meta : dict
        JSON-able metadata (numpy arrays and scalars and Paths are converted);
        non-finite floats become JSON ``null`` (strict JSON).

    Returns
    -------
    list of str
        Three lines without newlines.

    Raises
    ------
    RunLogError
        If ``meta`` is not JSON-serializable.
    """
    try:
        text = json.dumps(to_jsonable(meta), allow_nan=False, separators=(", ", ": "))
    except (TypeError, ValueError, RecursionError) as exc:
        raise RunLogError(f"run log metadata is not JSON-serializable: {exc}") from None
    return [COLUMN_LINE, MAGIC, "# " + text]


def end_record_line(outcome: dict[str, Any]) -> str:
    """Our log's last line, ``# end {json}`` and a newline (DESIGN.md "Run outcome").

    Parameters
    ----------
    outcome : dict
        The run's outcome (reason and counters); non-finite floats become ``null``.

    Raises
    ------
    TypeError
        If ``outcome`` holds a value JSON cannot represent.
    """
    return f"{END_PREFIX}{json.dumps(to_jsonable(outcome))}\n"
