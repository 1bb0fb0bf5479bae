"""Run logs: a lossless streaming writer for ours, one reader for ours and the rig's.

Our format (tab-separated text, one row per tick, DESIGN.md "Timing and log rows")::

    t	n	u	v	theta	a	theta_d_hat	v_applied	status	latency_us
    # station-runlog 1
    # {"controller": {...}, "reference": {...}, ...}      (one-line JSON metadata)
    0.0	0	0.0	0.0	0	0	0.0	0	0	nan
    ...

The column-name line comes first so that both ``pandas.read_csv(path, sep="\\t",
comment="#")`` and ``numpy.genfromtxt(path, names=True, delimiter="\\t", comments="#")``
read the file as is (genfromtxt takes its names from the first line, commented or not).
:func:`read_log` also accepts the two ``#`` lines before the column-name line.
Numbers are written so that they round-trip: ints as ints, floats by ``repr`` (shortest
exact form), NaN as ``nan``.

The rig's format (its lab software, ../shared/data/rig): ``#`` header lines (test name
``#SLFR RTP P_control_Test``, gains ``#kp=2.0`` or ``#kp = 1.0``, filter coefficients
``#Gth num=[ 18.3 -17.2]``, ``#Ga num=[]``) of which the last names the columns
(``#t	n	u	v	$\\theta$	a	$\\hat{\\theta}_d$``), then tab-separated rows.
"""

from __future__ import annotations

import json
import os
import math
import numbers
import re
import tempfile
import threading
import warnings
import weakref
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, NamedTuple
from collections.abc import Iterable

import numpy as np

from station.errors import StationError

class LogRow(NamedTuple):
    """One row of our run log: tick k (DESIGN.md "Timing and log rows"); a tuple with names.

    Attributes
    ----------
    t : float
        Time, s.
    n : int
        Tick number.
    u : float
        Reference, encoder counts (open loop: DAC counts).
    v : float
        Command acting during tick k, DAC counts.
    theta : float
        Encoder counts.
    a : float
        Accelerometer, ADC counts.
    theta_d_hat : float
        The controller's θ_d estimate, encoder counts.
    v_applied : float
        DAC counts the device reports, NaN when it does not.
    status : int
        v1 status bits.
    latency_us : float
        Compute latency of v[k], µs; NaN for tick 0.
    """

    t: float
    n: int
    u: float
    v: float
    theta: float
    a: float
    theta_d_hat: float
    v_applied: float
    status: int
    latency_us: float


COLUMNS = LogRow._fields
"""Columns of our run log, in row order (units: s, tick, counts, DAC counts, encoder
counts, accelerometer counts, encoder counts, DAC counts, status bits, µs)."""

END_PREFIX = "# end "
"""Start of our log's last line, the run's outcome as JSON (DESIGN.md "Run outcome")."""

MAGIC = "# station-runlog 1"
"""First ``#`` line of our format (version 1)."""

FLUSH_INTERVAL_S = 0.005
"""How often the writer thread wakes to write and flush (the contract: at least every 20 ms)."""

_COLUMN_LINE = "\t".join(COLUMNS)

COLUMN_SYNONYMS = {
    "t": ("t", "time", "time (sec.)", "time (s)", "time [s]", "time_s", "time_sec", "seconds"),
    "n": ("n", "tick", "ticks", "sample", "index"),
    "u": ("u", "r", "ref", "reference"),
    "v": ("v", "cmd", "command", "v_cmd", "dac"),
    "theta": ("theta", "θ", "$\\theta$", "\\theta", "enc", "encoder", "theta_counts"),
    "a": ("a", "accel", "acc", "acceleration", "accelerometer", "a_counts"),
    "theta_d_hat": ("theta_d_hat", "$\\hat{\\theta}_d$", "\\hat{\\theta}_d", "θ̂_d", "thetadhat"),
    "v_applied": ("v_applied",),
    "status": ("status",),
    "latency_us": ("latency_us",),
}
"""Standard column name -> the names logs use for it (compared case-insensitively,
whitespace-trimmed): ours, the rig's (``$\\theta$``), its 2014 logs (``Time (sec.)``,
``accel``) and cut-down copies (``t v theta a``)."""

_SYNONYM_OF = {alias.lower(): std for std, aliases in COLUMN_SYNONYMS.items() for alias in aliases}

SIGNAL_COLUMNS = ("u", "v", "theta", "a")
"""A log is usable when it has a time base (t or n) and at least one of these."""

RIG_DT = 0.002
"""The rig's sample time, s (DESIGN.md); t = n·RIG_DT when a log has n but no t."""


def standard_column(name: str) -> str:
    """The standard name of a column as printed in a log (itself when not a known synonym).

    Parameters
    ----------
    name : str
        e.g. ``"Time (sec.)"``, ``"$\\theta$"``, ``"accel"``.

    Returns
    -------
    str
        One of :data:`COLUMNS` (see :data:`COLUMN_SYNONYMS`), else ``name`` stripped.
    """
    key = name.strip()
    return _SYNONYM_OF.get(key.lower(), key)


class RunLogError(StationError):
    """A run log that cannot be read or written; names the file, line and what was expected
    (also as the attributes ``file``, ``line`` and ``key``, see :class:`StationError`)."""


def _log_error(path: str | Path, line: int | None, what: str, key: str | None = None) -> RunLogError:
    """The one form of a run log error: ``"{path}: line {line}: {what}"`` with its place as attributes.

    Parameters
    ----------
    path : str or Path
        The log.
    line : int or None
        1-based line number, None when the error is about the whole file.
    what : str
        What is wrong and what was expected.
    key : str, optional
        The column or header field at fault.

    Returns
    -------
    RunLogError
    """
    where = f"{path}: line {line}: " if line is not None else f"{path}: "
    return RunLogError(where + what, file=path, line=None if line is None else int(line), key=key)


# --- writing ----------------------------------------------------------------------------

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


def _json_default(obj: Any) -> Any:
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, Path):
        return str(obj)
    raise TypeError(f"{type(obj).__name__} is not JSON serializable")


def _nan_to_none(obj: Any) -> Any:
    if isinstance(obj, float) and not math.isfinite(obj):
        return None
    if isinstance(obj, dict):
        return {k: _nan_to_none(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_nan_to_none(v) for v in obj]
    return obj


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
        text = json.dumps(_nan_to_none(json.loads(json.dumps(meta, default=_json_default))),
                          allow_nan=False, separators=(", ", ": "))
    except (TypeError, ValueError) as exc:
        raise RunLogError(f"run log metadata is not JSON-serializable: {exc}") from None
    return [_COLUMN_LINE, MAGIC, "# " + text]


class _Pump:
    """The writer threads' state: queue -> text file, and batches -> sinks on a second
    thread so that a slow sink never delays the file's flushes. Holds no reference to
    the writer (so the writer can be finalized)."""

    def __init__(self, path: Path, fh, sinks: Iterable[Any]):
        self.path = path
        self.fh = fh
        self.queue: deque = deque()
        self.sinks = list(sinks)
        self.sink_errors: list[str] = []
        self.write_error: OSError | None = None
        self.unwritten: list[tuple] = []
        self.rows_written = 0
        self.sink_queue: deque = deque()
        self.stop_event = threading.Event()
        self.sink_stop = threading.Event()
        self.thread = threading.Thread(target=self.run, name=f"runlog:{path.name}", daemon=True)
        self.sink_thread = threading.Thread(target=self.run_sinks, name=f"runlog-sinks:{path.name}", daemon=True)
        self.closed = False
        self.end_line: str | None = None  # "# end {json}": written after the last row at shutdown

    def start(self) -> None:
        self.thread.start()
        if self.sinks:
            self.sink_thread.start()

    def run(self) -> None:
        while not self.stop_event.wait(FLUSH_INTERVAL_S):
            self.drain()
        self.drain()

    def run_sinks(self) -> None:
        while not self.sink_stop.wait(FLUSH_INTERVAL_S):
            self.drain_sinks()
        self.drain_sinks()

    def drain_sinks(self) -> None:
        q = self.sink_queue
        while q:
            self._feed_sinks(q.popleft())

    def drain(self) -> None:
        q = self.queue
        batch = []
        pop = q.popleft
        try:
            while True:
                batch.append(pop())
        except IndexError:
            pass
        if not batch:
            return
        try:
            self._write(batch)
        except Exception as exc:  # noqa: BLE001 - a bug here must not lose rows: keep them for the rescue
            if self.write_error is None:
                self.write_error = OSError(f"run log writer failed: {type(exc).__name__}: {exc}")
            self.unwritten.extend(batch)
        if self.sinks:
            self.sink_queue.append(batch)

    def _write(self, batch: list[tuple]) -> None:
        """Write a batch with unbuffered writes, so that after an error exactly the rows
        whose bytes all reached the file count as written (no buffer is left to reach it
        later, at close, behind the count's back); the rest go to ``unwritten``."""
        if self.write_error is not None:
            self.unwritten.extend(batch)
            return
        lines = format_lines(batch)
        data = "".join(lines).encode("utf-8")
        done = 0
        try:
            while done < len(data):
                n = self.fh.write(data[done:])  # raw file: may write part of it
                if not n:
                    raise OSError(f"write returned {n!r} with {len(data) - done} bytes left")
                done += n
        except OSError as exc:
            self.write_error = exc
            complete, end = 0, 0
            for line in lines:  # rows entirely in the file (a torn one is not: the reader skips it)
                end += len(line.encode("utf-8"))
                if end > done:
                    break
                complete += 1
            self.rows_written += complete
            self.unwritten.extend(batch[complete:])
            return
        self.rows_written += len(batch)

    def _feed_sinks(self, batch: list[tuple]) -> None:
        if not self.sinks:
            return
        arr = np.array(batch, dtype=float).reshape(len(batch), len(COLUMNS))
        columns = {name: arr[:, i] for i, name in enumerate(COLUMNS)}
        for sink in list(self.sinks):
            try:
                sink.write_rows(columns)
            except Exception as exc:  # noqa: BLE001 - a sink must never cost log rows
                self.sinks.remove(sink)
                msg = f"{self.path}: run log sink {sink!r} failed and was dropped ({type(exc).__name__}: {exc}); the log file is unaffected"
                self.sink_errors.append(msg)
                warnings.warn(msg, RuntimeWarning, stacklevel=1)

    def shutdown(self) -> None:
        if self.closed:
            return
        self.closed = True
        self.stop_event.set()
        if self.thread.is_alive() and self.thread is not threading.current_thread():
            self.thread.join()
        self.drain()
        if self.end_line is not None and self.write_error is None:
            try:
                self.fh.write(self.end_line.encode("utf-8"))
            except OSError as exc:
                self.write_error = exc
        self.sink_stop.set()
        if self.sink_thread.is_alive() and self.sink_thread is not threading.current_thread():
            self.sink_thread.join()
        self.drain_sinks()
        try:
            self.fh.close()
        except OSError as exc:
            if self.write_error is None:
                self.write_error = exc


class RunLogWriter:
    """Streaming writer of our run log; safe to feed from a real-time loop.

    ``append`` only puts the row on a queue (O(1), no formatting, no I/O). A background
    thread formats the queued rows, writes them and flushes them to the OS every
    ``FLUSH_INTERVAL_S`` (well inside the 20 ms of the contract, so a killed process loses
    at most the last few ms); a second thread hands each written batch to every sink, so
    a slow sink never delays the file. A sink that raises is reported once
    (``RuntimeWarning``, ``sink_errors``) and dropped; the file never loses a row because
    of it.

    Parameters
    ----------
    path : str or Path
        Log file to create (overwritten). Its folder must exist.
    meta : dict
        JSON-able metadata for the header: controller spec, reference, protocol,
        device info, plant parameters, alignment, start time.
    sinks : iterable
        Objects with ``write_rows(columns: dict[str, numpy.ndarray])`` (one array of
        shape (rows,) per name in :data:`COLUMNS`, float, NaN where missing), e.g.
        :class:`station.viz.RerunSink`. Called from the sink thread, in row order; not
        closed here.

    Raises
    ------
    RunLogError
        If the file cannot be created or ``meta`` is not JSON-serializable.

    Examples
    --------
    >>> with RunLogWriter("run.tsv", {"controller": spec}) as log:   # doctest: +SKIP
    ...     log.append((t, n, u, v, theta, a, theta_d_hat, v_applied, status, latency_us))
    """

    def __init__(self, path: str | Path, meta: dict[str, Any], sinks: Iterable[Any] = ()):
        self.path = Path(path)
        self.meta = meta
        lines = header_lines(meta)
        try:
            fh = open(self.path, "wb", buffering=0)  # raw: each write reaches the OS at once
        except OSError as exc:
            raise _log_error(self.path, None, f"cannot create run log: {exc.strerror or exc}") from None
        try:
            header = ("\n".join(lines) + "\n").encode("utf-8")
            done = 0
            while done < len(header):
                done += fh.write(header[done:])
        except OSError as exc:
            fh.close()
            raise _log_error(self.path, None, f"cannot write run log header: {exc.strerror or exc}") from None
        self._pump = _Pump(self.path, fh, sinks)
        self._queue_append = self._pump.queue.append
        self._finalizer = weakref.finalize(self, self._pump.shutdown)
        self._pump.start()

    def append(self, row: tuple) -> None:
        """Queue one row (a tuple in :data:`COLUMNS` order). O(1); no formatting or I/O.

        Parameters
        ----------
        row : tuple
            One row in :data:`COLUMNS` order (a :class:`LogRow` or plain tuple).

        Raises
        ------
        RunLogError
            If the writer is closed.
        ValueError
            If the row does not have ``len(COLUMNS)`` values.
        """
        if self._pump.closed:
            raise _log_error(self.path, None, "append after close")
        if len(row) != 10:
            raise ValueError(f"run log row needs {len(COLUMNS)} values ({', '.join(COLUMNS)}), got {len(row)}")
        self._queue_append(row)

    @property
    def rows_written(self) -> int:
        """Rows written to the file so far."""
        return self._pump.rows_written

    @property
    def sink_errors(self) -> list[str]:
        """One message per sink that failed and was dropped."""
        return list(self._pump.sink_errors)

    def close(self, outcome: dict[str, Any] | None = None) -> None:
        """Write every queued row, flush and close the file. Idempotent.

        Parameters
        ----------
        outcome : dict, optional
            The run's outcome (DESIGN.md "Run outcome": reason and counters), written
            after the last row as the end record ``# end {json}``. A log without it
            (closed without an outcome, SIGKILL, power loss) has outcome null.

        Raises
        ------
        RunLogError
            If writing failed (disk full, ...): names the file, how many rows are
            missing from it, and the rescue file in the temporary folder that holds
            them with the same header (they also stay available as ``unwritten_rows``).
        """
        if outcome is not None and not self._pump.closed:
            self._pump.end_line = f"{END_PREFIX}{json.dumps(_nan_to_none(outcome), default=_json_default)}\n"
        self._finalizer()
        err = self._pump.write_error
        if err is not None:
            missing = len(self._pump.unwritten)
            rescued = self._rescue()
            where = (f"; they were saved to {rescued}" if rescued is not None
                     else "; saving them to the temporary folder failed too" if missing else "")
            raise _log_error(self.path, None, f"writing the run log failed ({err.strerror or err}); "
                              f"{missing} rows are not in the file{where}")

    def _rescue(self) -> Path | None:
        """Write the unwritten rows, with this log's header, to a file in the temporary
        folder (another disk, often): never lose rows. Returns its path, or None."""
        rows = self._pump.unwritten
        if not rows:
            return None
        path = Path(tempfile.gettempdir()) / f"{self.path.stem}.rescued-{os.getpid()}.tsv"
        meta = {**self.meta, "rescued_from": str(self.path), "rescued_rows": len(rows)}
        try:
            with open(path, "w", encoding="utf-8") as fh:
                fh.write("\n".join(header_lines(meta)) + "\n" + "".join(format_lines(rows)))
        except (OSError, TypeError, ValueError):
            return None
        return path

    @property
    def unwritten_rows(self) -> list[tuple]:
        """Rows that could not be written because of a write error (normally empty)."""
        return list(self._pump.unwritten)

    def __enter__(self) -> RunLogWriter:
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()


# --- reading ----------------------------------------------------------------------------

@dataclass
class RunLog:
    """A run log read by :func:`read_log`.

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
        ``t	v	theta	a``; their ``format`` is "rig").
    sample_time : float or None
        The sample time found in t, s (median step, rounded to 1 ns; None with fewer
        than two rows).
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


_KV = re.compile(r"^\s*([A-Za-z_]\w*)\s*=\s*(.*?)\s*$")
_COEF = re.compile(r"^\s*(\w+)\s+(num|den)\s*=\s*\[(.*)\]\s*$")


def _split_names(line: str) -> tuple[list[str], str | None]:
    """The names of a column-name line and its delimiter (tab, comma, semicolon; None:
    whitespace)."""
    for sep in ("\t", ",", ";"):
        if sep in line:
            return [c.strip() for c in line.split(sep)], sep
    return line.split(), None


def _map_columns(path: Path, lineno: int, printed: list[str]) -> list[str]:
    """Standard names of the printed column names; RunLogError when none is usable."""
    std = [standard_column(c) for c in printed]
    if not ({"t", "n"} & set(std) and set(SIGNAL_COLUMNS) & set(std)):
        found = ", ".join(repr(c[:30]) for c in printed[:10]) + (", ..." if len(printed) > 10 else "") or "none"
        raise _log_error(path, lineno, f"no usable columns: found {found}; expected a time "
                          f"column (t, time, 'Time (sec.)' or n) and at least one of u, v, "
                          f"theta ($\\theta$), a (accel)")
    dup = next((c for c in std if std.count(c) > 1), None)
    if dup is not None:
        raise _log_error(path, lineno, f"column {dup!r} appears twice "
                          f"(as {', '.join(repr(p) for p, s in zip(printed, std) if s == dup)})")
    return std


def _parse_rig_header(path: Path, comment_lines: list[str]) -> tuple[dict[str, Any], list[str], str | None]:
    """meta, standard column names and delimiter from the rig's ``#`` lines (the last
    names the columns)."""
    if not comment_lines:
        raise _log_error(path, 1, "expected '#' header lines naming the columns")
    meta: dict[str, Any] = {}
    *info, col_line = comment_lines
    names, sep = _split_names(col_line[1:])
    std = _map_columns(path, len(comment_lines), names)
    meta["columns"] = names
    other = []
    coef_lines: dict[str, int] = {}
    for i, line in enumerate(info):
        body = line[1:].strip()
        coef = _COEF.match(body)
        kv = _KV.match(body)
        if i == 0 and not kv and not coef:
            meta["title"] = body
            parts = body.split()
            meta["test"] = parts[-1] if parts else ""
        elif coef:
            try:
                values = [float(x) for x in coef.group(3).split()]
            except ValueError:
                raise _log_error(path, i + 1, f"expected numbers in {coef.group(1)} "
                                  f"{coef.group(2)}=[...], got {line!r}", key=coef.group(1)) from None
            if not all(math.isfinite(x) for x in values) or (coef.group(2) == "den" and values and values[0] == 0):
                raise _log_error(path, i + 1, f"{coef.group(1)} {coef.group(2)}={values}: expected finite "
                                  f"coefficients" + (", den[0] not 0 (the filter would be non-causal)"
                                                     if coef.group(2) == "den" else ""), key=coef.group(1))
            meta.setdefault(coef.group(1), {})[coef.group(2)] = values
            coef_lines[coef.group(1)] = i + 1
        elif kv:
            key, val = kv.groups()
            try:
                meta[key] = float(val)
            except ValueError:
                meta[key] = val
        else:
            other.append(body)
    for key, lineno in coef_lines.items():  # a filter printed with a numerator needs its denominator
        if meta[key].get("num") and not meta[key].get("den"):
            raise _log_error(path, lineno, f"{key} num={meta[key]['num']} has no den=[...] "
                              f"(expected both, as the rig's software prints them)", key=key)
    if other:
        meta["notes"] = other
    return meta, std, sep


def _parse_rows(path: Path, lines: list[str], first_lineno: int, names: list[str],
                ends_with_newline: bool, fmt: str, sep: str | None = "\t") -> tuple[np.ndarray, int]:
    """Rows -> array (rows, len(names)); returns also the number of torn rows skipped (0/1).
    ``sep``: the delimiter (None: any whitespace)."""
    ncol = len(names)
    rows: list[list[float]] = []
    torn = 0
    last = len(lines) - 1
    while last >= 0 and not lines[last].strip():
        last -= 1
    for idx, raw in enumerate(lines):
        line = raw.rstrip("\r")
        if not line.strip() or line.startswith("#"):
            continue
        lineno = first_lineno + idx
        parts = line.split(sep)
        problem = None
        if len(parts) != ncol:
            what = {"\t": "tab", ",": "comma", ";": "semicolon", None: "whitespace"}[sep]
            problem = f"expected {ncol} {what}-separated numbers, got {len(parts)}"
        else:
            try:
                values = [float(p) for p in parts]
            except ValueError:
                bad = next(j for j, p in enumerate(parts) if not _is_number(p))
                problem = f"expected a number in column {names[bad]!r}, got {parts[bad]!r}"
        is_last_unterminated = idx == last and not ends_with_newline
        if is_last_unterminated and (problem is not None or fmt == "station"):
            torn += 1
            warnings.warn(f"{path}: line {lineno}: torn last line (no newline; the writer was "
                          f"interrupted mid-row) skipped", RuntimeWarning, stacklevel=3)
            continue
        if problem is not None:
            raise _log_error(path, lineno, problem)
        rows.append(values)
    arr = np.array(rows, dtype=float).reshape(len(rows), ncol)
    return arr, torn


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


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
        ``sample_time`` the sample time found, ``notes`` what was derived.

    Raises
    ------
    RunLogError
        File missing or unreadable, unknown format, bad header, no usable columns (lists
        the columns found and expected), or a malformed row other than a torn last line
        (names the file, line number and what was expected).

    Warns
    -----
    RuntimeWarning
        When a torn last line (interrupted write) is skipped.
    """
    path = Path(path)
    try:
        with open(path, "rb") as fb:
            size = fb.seek(0, os.SEEK_END)
            ends_with_newline = size > 0 and (fb.seek(-1, os.SEEK_END) or True) and fb.read(1) == b"\n"
        fh = open(path, encoding="utf-8", newline="")
    except OSError as exc:
        raise _log_error(path, None, f"cannot read run log: {exc.strerror or exc}") from None
    with fh:
        try:
            return _read_stream(path, fh, ends_with_newline)
        except UnicodeDecodeError as exc:
            raise _log_error(path, None, f"not a text run log ({exc.reason} at byte {exc.start} of a block)") from None
        except OSError as exc:
            raise _log_error(path, None, f"cannot read run log: {exc.strerror or exc}") from None


class _Lines:
    """The file's lines, numbered from 1, without their newline (and a trailing CR), with
    a push-back for the header parser; ``terminated`` is False for a last line with no
    newline."""

    def __init__(self, fh) -> None:
        self.fh = fh
        self.lineno = 0
        self._back: list[tuple[int, str, bool]] = []

    def next(self) -> tuple[int, str, bool] | None:
        if self._back:
            return self._back.pop()
        raw = self.fh.readline()
        if not raw:
            return None
        self.lineno += 1
        terminated = raw.endswith("\n")
        return self.lineno, raw.rstrip("\n").rstrip("\r"), terminated

    def push(self, item: tuple[int, str, bool]) -> None:
        self._back.append(item)


class _DataLines:
    """Iterates the data lines for numpy's parser: blank and ``#`` lines left out (the
    last non-blank line is kept for the end record), the first data line number kept, an
    unterminated last data line held back (a torn row)."""

    def __init__(self, path: Path, lines: _Lines, fmt: str, ncol: int, sep: str | None) -> None:
        self.path, self.lines, self.fmt, self.ncol, self.sep = path, lines, fmt, ncol, sep
        self.last: tuple[int, str, bool] | None = None  # last non-blank line
        self.first_lineno: int | None = None
        self.torn = 0
        self.rows = 0

    def __iter__(self):
        while (item := self.lines.next()) is not None:
            lineno, line, terminated = item
            if not line.strip():
                continue
            self.last = item
            if line.startswith("#"):
                continue
            if self.first_lineno is None:
                self.first_lineno = lineno
            if not terminated and not self._keep_unterminated(line):
                self.torn += 1
                warnings.warn(f"{self.path}: line {lineno}: torn last line (no newline; the writer was "
                              f"interrupted mid-row) skipped", RuntimeWarning, stacklevel=4)
                continue
            self.rows += 1
            yield line

    def _keep_unterminated(self, line: str) -> bool:
        """Ours: never (our writer ends every row); the rig's: when it is a whole row."""
        if self.fmt == "station":
            return False
        parts = line.split(self.sep)
        return len(parts) == self.ncol and all(_is_number(p) for p in parts)


def _read_stream(path: Path, fh, ends_with_newline: bool) -> RunLog:
    """:func:`read_log` on an open text file: header line by line, rows by numpy's parser."""
    lines = _Lines(fh)
    head: list[tuple[int, str, bool]] = []
    while len(head) < 3 and (item := lines.next()) is not None:
        head.append(item)
    while head and not head[-1][1].strip() and (item := lines.next()) is not None:
        head.append(item)  # (leading blank lines: keep looking for a header)
    if not head or not any(h[1].strip() for h in head):
        raise _log_error(path, None, "empty file, expected a run log header")
    texts = [h[1] for h in head]

    reader_notes: list[str] = []
    sep: str | None = "\t"
    if MAGIC in texts[:2]:
        fmt = layout = "station"
        header = texts[:3]
        if len(header) < 3:
            raise _log_error(path, len(header) + 1, f"expected the header to go on "
                              f"(column names, '{MAGIC}', '# ' and the JSON metadata)")
        # Ours: column line, magic, JSON (what we write); or magic, JSON, column line.
        if texts[0] == MAGIC:
            (json_no, json_line), (col_no, col_line) = (2, texts[1]), (3, texts[2])
        else:
            (json_no, json_line), (col_no, col_line) = (3, texts[2]), (1, texts[0])
        for extra in reversed(head[3:]):
            lines.push(extra)
        if not json_line.startswith("# "):
            raise _log_error(path, json_no, f"expected '# ' and the JSON metadata, got {json_line[:60]!r}")
        try:
            meta = json.loads(json_line[2:])
        except json.JSONDecodeError as exc:
            raise _log_error(path, json_no, f"metadata is not valid JSON ({exc.msg})") from None
        except RecursionError:
            raise _log_error(path, json_no, "metadata JSON is nested too deeply") from None
        if not isinstance(meta, dict):
            raise _log_error(path, json_no, "expected a JSON object of metadata")
        _check_meta(path, json_no, meta)
        names = col_line.split("\t")
        if tuple(names[:len(COLUMNS)]) != COLUMNS:
            raise _log_error(path, col_no, f"expected the column names {_COLUMN_LINE!r}, got {col_line!r}")
    elif texts[0].startswith("#"):
        fmt = layout = "rig"
        for extra in reversed(head):
            lines.push(extra)
        header = []
        while (item := lines.next()) is not None:
            if not item[1].startswith("#"):
                lines.push(item)
                break
            header.append(item[1])
        meta, names, sep = _parse_rig_header(path, header)
    else:
        # No '#' header: a first line of column names (the rig's 2014 logs, cut-down copies).
        for extra in reversed(head[1:]):
            lines.push(extra)
        printed, sep = _split_names(texts[0])
        if printed and all(_is_number(c) for c in printed):
            raise _log_error(path, 1, f"expected '{MAGIC}' (station run log), the rig's '#' "
                              f"header or a line of column names, got numbers {texts[0][:60]!r}")
        fmt, layout = "rig", "columns"
        names = _map_columns(path, 1, printed)
        meta = {"columns": printed}
        header = texts[:1]
        renamed = [f"{p!r} -> {s}" for p, s in zip(printed, names) if p != s]
        if renamed:
            reader_notes.append("columns named by synonyms: " + ", ".join(renamed))

    first_data_line = lines.lineno - len(lines._back) + 1
    data_lines = _DataLines(path, lines, fmt, len(names), sep)
    arr = _load_rows(path, data_lines, names, fmt, sep, first_data_line, ends_with_newline)
    n = arr.shape[0]
    data = {name: np.full(n, np.nan) for name in COLUMNS}
    for j, name in enumerate(names):
        data[name] = arr[:, j]
    del arr
    _check_finite(path, data, names, fmt, data_lines.first_lineno)
    sample_time = _complete_time_base(data, names, reader_notes)
    outcome = None if data_lines.last is None else _end_record(path, *data_lines.last)
    return RunLog(path=path, format=fmt, meta=meta, data=data, header=header, layout=layout,
                  sample_time=sample_time, outcome=outcome, notes=reader_notes)


def _load_rows(path: Path, data_lines: _DataLines, names: list[str], fmt: str, sep: str | None,
               first_line: int, ends_with_newline: bool) -> np.ndarray:
    """The rows as an array (rows, len(names)), parsed by numpy without a Python list per
    row (a 100 MB log stays within a few times its size). On any parse error the file is
    read again line by line to name the line and the field (:func:`_parse_rows`)."""
    ncol = len(names)
    try:
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message=".*input contained no data", category=UserWarning)
            arr = np.loadtxt(iter(data_lines), dtype=float, delimiter=sep, comments=None, ndmin=2, encoding=None)
        if arr.size == 0:
            arr = np.empty((0, ncol))
        if arr.shape[1] != ncol:
            raise ValueError("column count")
        return arr
    except UnicodeDecodeError:
        raise
    except ValueError:
        pass
    # the exact (slow) path, only for a file with a bad row: it names the line and the field
    text = path.read_text(encoding="utf-8")
    all_lines = [ln.rstrip("\r") for ln in text.split("\n")]
    if ends_with_newline:
        all_lines.pop()
    del text
    arr, _ = _parse_rows(path, all_lines[first_line - 1:], first_line, names, ends_with_newline, fmt, sep)
    return arr


FINITE_COLUMNS = ("t", "n", "u", "theta", "a")
"""Columns that must hold finite numbers in every log (time base, reference, sensors);
the rig's logs must also have a finite v and theta_d_hat. Ours may log v = nan (the row
of a controller fault) and nan latency or theta_d_hat."""


def _check_finite(path: Path, data: dict[str, np.ndarray], names: list[str], fmt: str,
                  first_lineno: int | None) -> None:
    """RunLogError naming the line and the field of the first non-finite value where a number belongs."""
    must = FINITE_COLUMNS + (("v", "theta_d_hat") if fmt == "rig" else ())
    for name in names:
        if name not in must:
            continue
        col = data[name]
        bad = np.flatnonzero(~np.isfinite(col))
        if bad.size:
            line = _line_of_row(path, first_lineno, int(bad[0]))
            raise _log_error(path, line, f"{name} is {float(col[bad[0]])!r}, expected a finite number "
                              f"(a log with missing samples cannot be used as it is)", key=name)


def _line_of_row(path: Path, first_lineno: int | None, row: int) -> int:
    """The line number of data row ``row`` (0-based), counting blank and ``#`` lines."""
    if first_lineno is None:
        return 0
    seen = -1
    with open(path, encoding="utf-8", errors="replace") as fh:
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
            raise _log_error(path, lineno, f"header field dt is {dt!r}, expected the sample time "
                              f"in s, a number in (0, 1]", key="dt")


def _complete_time_base(data: dict[str, np.ndarray], names: list[str], notes: list[str]) -> float | None:
    """Fill t from n (at the rig's 0.002 s) or n from t, in place; return the sample time
    found in t (None with fewer than two rows)."""
    t, n = data["t"], data["n"]
    if "t" not in names and "n" in names:
        data["t"] = t = n * RIG_DT
        notes.append(f"no time column: t = n * {RIG_DT} s (the rig's sample time)")
    if t.size < 2 or not np.all(np.isfinite(t)):
        return None
    steps = np.diff(t)
    dt = float(round(float(np.median(steps)), 9))
    if dt <= 0:
        return None
    if "n" not in names:
        data["n"] = np.round((t - t[0]) / dt)
        notes.append(f"no sample column: n derived from t (sample time {dt:g} s)")
    if np.max(np.abs(steps - dt)) > 0.01 * dt:
        notes.append(f"t is not evenly spaced (steps {np.min(steps):g} .. {np.max(steps):g} s; "
                     f"median {dt:g} s used)")
    return dt


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
        raise _log_error(path, lineno, f"end record is not valid JSON ({msg})") from None
    if not isinstance(outcome, dict):
        raise _log_error(path, lineno, f"expected a JSON object after '{END_PREFIX.strip()}'")
    return outcome
