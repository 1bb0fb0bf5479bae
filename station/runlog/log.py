"""A run log as read (:class:`RunLog`), with the one definition of its sample time.

Imports :mod:`station.runlog.schema` and :mod:`station.runlog.timebase`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from station.rig import DT
from station.runlog.schema import log_error
from station.runlog.timebase import header_dt


@dataclass
class RunLog:
    """A run log read by :func:`station.runlog.read_log`.

    Attributes
    ----------
    path : Path
    format : {"station", "rig"}
    meta : dict
        Ours: the header JSON. The rig's: ``title`` (whole first line), ``test``
        (e.g. "P_control_Test"), gains (``kp``, ``ki``, ``kd``) as floats, ``Gth`` / ``Ga``
        as ``{"num": [...], "den": [...]}`` (empty lists when printed empty), and
        ``columns`` (the names as printed).
    data : dict of numpy.ndarray
        Shape (rows,), float64, for every name in :data:`COLUMNS` (NaN where the format
        lacks the column), plus any extra columns under their own names.
    header : list of str
        The header lines as in the file (without newlines).
    layout : str
        How the file was laid out: "station" (ours), "rig" (``#`` header lines, the last
        naming the columns) or "columns" (no ``#`` header: a first line of column names,
        e.g. the rig's 2014 logs ``Time (sec.)	u	theta	accel	v`` and cut-down copies
        ``t	v	theta	a``; their ``format`` is "rig") or "bare" (the rig's rows without any
        header: its column order assumed, :data:`station.runlog.rig_layouts.BARE_ORDER`).
    sample_time : float or None
        The sample time found in t, s (median step, rounded to 1 ns; None with fewer
        than two rows or when t does not increase); what reports show as
        ``sample_time_s``. Code that needs the sample time uses :attr:`dt`.
    outcome : dict or None
        Our log's end record ``# end {json}`` (DESIGN.md "Run outcome"); None when the
        log has none (the rig's logs, SIGKILL, power loss).
    notes : list of str
        What the reader derived or assumed (columns renamed, n derived from t, ...).
    """

    path: Path
    format: str
    meta: dict[str, Any]
    data: dict[str, np.ndarray]
    header: list[str] = field(default_factory=list)
    layout: str = ""
    sample_time: float | None = None
    outcome: dict[str, Any] | None = None
    notes: list[str] = field(default_factory=list)

    def __len__(self) -> int:
        return int(self.data["t"].size)

    def require_rows(self, doing: str) -> RunLog:
        """This log, refused when it has no rows (a header only: a run that never started).

        Parameters
        ----------
        doing : str
            What the command would do with it ("replay", "compare", "draw").

        Returns
        -------
        RunLog
            ``self``.

        Raises
        ------
        RunLogError
            ``PATH: the log has no rows; nothing to DOING`` (a command's exit code 2: nothing ran).
        """
        if not len(self):
            raise log_error(self.path, None, f"the log has no rows; nothing to {doing}")
        return self

    @property
    def dt(self) -> float:
        """The log's sample time, s: the one definition (replay, the model run, bode).

        The header's ``dt`` when it is a finite positive number (our logs carry one; the
        reader refuses one outside (0, 1]); else :attr:`sample_time`, the median step of
        t rounded to 1 ns; else (fewer than two rows, t not increasing) the rig's
        0.002 s (:data:`station.rig.DT`).
        """
        dt = header_dt(self.meta)
        if dt is not None:
            return dt
        return self.sample_time if self.sample_time is not None else DT
