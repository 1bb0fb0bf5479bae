"""Run logs: a lossless streaming writer for ours, one reader for ours and the rig's.

Our format (tab-separated text, one row per tick, DESIGN.md "Timing and log rows")::

    t	n	u	v	theta	a	theta_d_hat	v_applied	status	latency_us
    # station-runlog 1
    # {"controller": {...}, "reference": {...}, ...}      (one-line JSON metadata)
    0.0	0	0.0	0.0	0	0	0.0	0	0	nan
    ...
    # end {"reason": "completed", ...}                   (the run's outcome, when it has one)

The column-name line comes first so that both ``pandas.read_csv(path, sep="\\t",
comment="#")`` and ``numpy.genfromtxt(path, names=True, delimiter="\\t", comments="#")``
read the file as is (genfromtxt takes its names from the first line, commented or not).
:func:`read_log` also accepts the two ``#`` lines before the column-name line.
Numbers are written so that they round-trip: ints as ints, floats by ``repr`` (shortest
exact form), NaN as ``nan``.

The rig's format (its lab software, ../shared/data/rig): ``#`` header lines (test name
``#SLFR RTP P_control_Test``, gains ``#kp=2.0`` or ``#kp = 1.0``, filter coefficients
``#Gth num=[ 18.3 -17.2]``, ``#Ga num=[]``) of which the last names the columns
(``#t	n	u	v	$\\theta$	a	$\\hat{\\theta}_d$``), then tab-separated rows; or,
without ``#`` lines, a first line of column names (its 2014 logs, cut-down copies).

What lives where, from the bottom up (each module imports only those above it in this
list, plus :mod:`station.rig` for ``DT``, :mod:`station.errors` and :mod:`station.jsonio`;
nothing here imports the rest of the station):

- ``schema``: the row (:class:`LogRow`, :data:`COLUMNS`, the station's status bit
  :data:`SKIPPED`), column synonyms, the format's marks, :class:`RunLogError` and its one form.
- ``text``: values, rows, header and end record as text.
- ``writer``: :class:`RunLogWriter` (queue, writer thread, sink thread, rescue file).
- ``rows``: the lines of a file, the data lines (the torn last line decided once) and
  the rows as an array (numpy's parser from a line stream).
- ``rig_layouts``: the rig's two header layouts.
- ``timebase``: t and n completed, the sample time found in t or given by the header.
- ``log``: :class:`RunLog`, with :attr:`RunLog.dt`, the one definition of a log's
  sample time.
- ``reader``: :func:`read_log`.
"""

from station.runlog.log import RunLog
from station.runlog.reader import read_log
from station.runlog.schema import (
    COLUMN_SYNONYMS,
    COLUMNS,
    END_PREFIX,
    FINITE_COLUMNS,
    MAGIC,
    SIGNAL_COLUMNS,
    SKIPPED,
    LogRow,
    RunLogError,
    standard_column,
)
from station.runlog.text import format_lines, format_value, header_lines
from station.runlog.writer import FLUSH_INTERVAL_S, RunLogWriter

__all__ = [
    "COLUMNS", "COLUMN_SYNONYMS", "END_PREFIX", "FINITE_COLUMNS", "FLUSH_INTERVAL_S", "MAGIC",
    "SIGNAL_COLUMNS", "SKIPPED", "LogRow", "RunLog", "RunLogError", "RunLogWriter", "format_lines", "format_value",
    "header_lines", "read_log", "standard_column",
]
