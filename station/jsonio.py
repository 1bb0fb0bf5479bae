"""JSON the station writes: one conversion of numpy values, paths and non-finite floats.

Every JSON the station writes (log headers and end records, reports) is strict JSON: a NaN
or an infinity becomes ``null`` (the field's "no value"), never the non-standard ``NaN``
token that other readers refuse. Imports numpy only.
"""

from __future__ import annotations

import math
from pathlib import PurePath
from typing import Any

import numpy as np


def to_jsonable(obj: Any) -> Any:
    """``obj`` as plain JSON values, non-finite floats as None.

    Parameters
    ----------
    obj : any
        dicts, lists, tuples, str, int, float, bool, None, numpy arrays and scalars,
        paths, nested in any way.

    Returns
    -------
    any
        The same structure with dicts and lists only (tuples and arrays as lists), numpy
        scalars as Python numbers, paths as str, NaN and ±inf as None. Dict keys are kept
        (``json.dumps`` turns number keys into strings).

    Raises
    ------
    TypeError
        For a value of another type (names the type).
    """
    if obj is None or isinstance(obj, (str, bool, int)):
        return obj
    if isinstance(obj, float):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, PurePath):
        return str(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON serializable")
