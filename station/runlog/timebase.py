"""A log's time base: the sample time found in t or given by the header, and t or n
derived when a layout lacks one of them (:attr:`station.runlog.RunLog.dt` combines them).

Imports :mod:`station.runlog.schema`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from station.rig import DT


def _step_of(steps: np.ndarray) -> float | None:
    """The median of t's steps rounded to 1 ns, None when it is not positive."""
    dt = float(round(float(np.median(steps)), 9))
    return dt if dt > 0 else None


def header_dt(meta: dict[str, Any]) -> float | None:
    """The sample time a log's header gives.

    Parameters
    ----------
    meta : dict
        The header (:attr:`station.runlog.RunLog.meta`).

    Returns
    -------
    float or None
        ``meta["dt"]`` in s when it is a finite positive number (not a bool), else None.
    """
    dt = meta.get("dt")
    if isinstance(dt, (int, float)) and not isinstance(dt, bool) and math.isfinite(dt) and dt > 0:
        return float(dt)
    return None


def complete_time_base(data: dict[str, np.ndarray], names: list[str], notes: list[str]) -> float | None:
    """Fill t from n (at the rig's 0.002 s) or n from t, in place, and say so in ``notes``.

    Parameters
    ----------
    data : dict of numpy.ndarray
        The log's columns by standard name, shape (rows,) each; t and n may be all NaN.
    names : list of str
        The columns the file has (the others are NaN).
    notes : list of str
        The reader's notes; appended to.

    Returns
    -------
    float or None
        The sample time found in t, s: the median step rounded to 1 ns; None with fewer
        than two rows, a non-finite t, or a median step that is not positive.
    """
    t, n = data["t"], data["n"]
    if "t" not in names and "n" in names:
        data["t"] = t = n * DT
        notes.append(f"no time column: t = n * {DT} s (the rig's sample time)")
    if t.size < 2 or not np.all(np.isfinite(t)):
        return None
    steps = np.diff(t)
    dt = _step_of(steps)
    if dt is None:
        return None
    if "n" not in names:
        data["n"] = np.round((t - t[0]) / dt)
        notes.append(f"no sample column: n derived from t (sample time {dt:g} s)")
    if np.max(np.abs(steps - dt)) > 0.01 * dt:
        notes.append(f"t is not evenly spaced (steps {np.min(steps):g} .. {np.max(steps):g} s; "
                     f"median {dt:g} s used)")
    return dt
