"""The streaming writer of our run log: ``append`` from the real-time loop is O(1) and
never blocks; a thread writes and flushes, a second one feeds the sinks; rows the disk
refused go to a rescue file.

Imports :mod:`station.runlog.schema` and :mod:`station.runlog.text`.
"""

from __future__ import annotations

import os
import tempfile
import threading
import warnings
import weakref
from collections import deque
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import numpy as np

from station.runlog.schema import COLUMNS, log_error
from station.runlog.text import end_record_line, format_lines, header_lines

FLUSH_INTERVAL_S = 0.005
"""How often the writer thread wakes to write and flush (the contract: at least every 20 ms)."""

_NCOL = len(COLUMNS)


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
            raise log_error(self.path, None, f"cannot create run log: {exc.strerror or exc}") from None
        try:
            header = ("\n".join(lines) + "\n").encode("utf-8")
            done = 0
            while done < len(header):
                done += fh.write(header[done:])
        except OSError as exc:
            fh.close()
            raise log_error(self.path, None, f"cannot write run log header: {exc.strerror or exc}") from None
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
            raise log_error(self.path, None, "append after close")
        if len(row) != _NCOL:
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
            self._pump.end_line = end_record_line(outcome)
        self._finalizer()
        err = self._pump.write_error
        if err is not None:
            missing = len(self._pump.unwritten)
            rescued = self._rescue()
            where = (f"; they were saved to {rescued}" if rescued is not None
                     else "; saving them to the temporary folder failed too" if missing else "")
            raise log_error(self.path, None, f"writing the run log failed ({err.strerror or err}); "
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
