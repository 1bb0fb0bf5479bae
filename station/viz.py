"""Rerun recordings of runs and replays: theta, a, u, v, theta_d_hat as time series.

Uses a :class:`rerun.RecordingStream` object per sink (no global recording), columnar
``send_columns`` on the ``sample`` sequence timeline (tick n) and a ``time`` duration
timeline (s). Entity layout, one plot per parent in the viewer:

- ``theta/measured``, ``theta/reference`` (u), ``theta/theta_d_hat``, ``theta/model``
  (encoder counts);
- ``a/measured``, ``a/model`` (accelerometer counts);
- ``v/command``, ``v/applied``, ``v/model`` (DAC counts).
"""

from __future__ import annotations

import os
import sys
import uuid
import warnings
from pathlib import Path
from collections.abc import Mapping

import numpy as np

from station.errors import StationError
from station.outputs import write_bytes

LOG_ENTITIES = {
    "theta": "theta/measured",
    "u": "theta/reference",
    "theta_d_hat": "theta/theta_d_hat",
    "a": "a/measured",
    "v": "v/command",
    "v_applied": "v/applied",
}
"""Run-log column -> rerun entity path."""

MODEL_ENTITIES = {"theta": "theta/model", "a": "a/model", "v": "v/model"}
"""Model prediction key -> rerun entity path."""

RRD_BYTES_PER_TICK = 300
"""Memory an .rrd recording of a run takes per tick until it is written, bytes, rounded up
(its six series of a run log; measured about 36 bytes per sample of one series)."""


def _check_display() -> None:
    """On Linux the viewer needs a display; fail before the run rather than hang after it."""
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise StationError("--spawn needs a display (neither DISPLAY nor WAYLAND_DISPLAY is set): "
                           "record with --rrd FILE and open it with `rerun FILE` where there is a screen")


def _viewer_executable() -> str | None:
    """The ``rerun`` viewer installed beside this Python (a venv's bin/), else None (PATH lookup).

    A venv's console scripts run without the venv on PATH, where the SDK alone would
    not find the viewer that rerun-sdk installed.
    """
    candidate = Path(sys.executable).parent / "rerun"
    return str(candidate) if candidate.is_file() else None


class RerunSink:
    """A run-log sink (``write_rows``) that records time series with rerun.

    Parameters
    ----------
    rrd_path : str or Path, optional
        Write the recording to this .rrd file when the sink is closed: the stream is kept
        in memory (:data:`RRD_BYTES_PER_TICK`) and written whole or not at all by
        :class:`station.outputs.Transaction` (a write error is raised, not lost in the
        SDK's log; a recording's stream cannot be written in pieces: each read of it is a
        stream of its own).
    spawn : bool
        Stream to a newly spawned rerun viewer instead.
    name : str
        Application id shown in the viewer.

    Raises
    ------
    StationError
        Both ``rrd_path`` and ``spawn`` given, or the viewer cannot be spawned.

    Notes
    -----
    Without ``rrd_path`` or ``spawn`` the data stays in the stream's memory buffer
    (useful in notebooks and tests only).
    """

    def __init__(self, rrd_path: str | Path | None = None, spawn: bool = False, name: str = "station"):
        import rerun as rr  # lazy: start-up time (rerun)

        if rrd_path is not None and spawn:
            raise StationError("rerun: give either an .rrd file or --spawn, not both")
        self._rr = rr
        self.rrd_path = None if rrd_path is None else Path(rrd_path)
        self.rec = rr.RecordingStream(application_id=name, recording_id=uuid.uuid4())
        self._stream = self.rec.binary_stream() if self.rrd_path is not None else None
        if spawn:
            try:
                _check_display()
                rr.spawn(executable_path=_viewer_executable(), recording=self.rec)
            except Exception as exc:  # noqa: BLE001 - the SDK raises various types
                first_line = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
                raise StationError(f"rerun: cannot record to a rerun viewer: {first_line}") from None
        self._closed = False

    def log_series(self, entity: str, values, n=None, t=None) -> None:
        """Record one scalar time series (NaN samples skipped).

        Parameters
        ----------
        entity : str
            Rerun entity path, e.g. "v/replayed".
        values : array_like, shape (N,)
        n : array_like of int, shape (N,), optional
            Ticks (``sample`` timeline); default 0..N-1.
        t : array_like, shape (N,), optional
            Times, s (``time`` timeline).
        """
        values = np.asarray(values, dtype=float)
        n = np.arange(values.size) if n is None else np.asarray(n, dtype=np.int64)
        self._send(n, None if t is None else np.asarray(t, dtype=float), entity, values)

    def _send(self, n: np.ndarray, t: np.ndarray | None, entity: str, values: np.ndarray) -> None:
        if self._closed:
            raise StationError("rerun sink: write after close")
        rr = self._rr
        values = np.asarray(values, dtype=float)
        keep = ~np.isnan(values)
        if not np.any(keep):
            return
        indexes = [rr.TimeColumn("sample", sequence=n[keep].astype(np.int64))]
        if t is not None:
            indexes.append(rr.TimeColumn("time", duration=t[keep]))
        self.rec.send_columns(entity, indexes=indexes, columns=rr.Scalars.columns(scalars=values[keep]))

    def write_rows(self, columns: Mapping[str, np.ndarray]) -> None:
        """Record a batch of run-log rows.

        Parameters
        ----------
        columns : mapping of str to numpy.ndarray, each shape (rows,)
            At least ``n`` (tick); ``t`` (s) when present; any of ``theta``, ``u``,
            ``theta_d_hat``, ``a``, ``v``, ``v_applied`` (NaN samples are skipped).
        """
        n = np.asarray(columns["n"], dtype=float)
        t = np.asarray(columns["t"], dtype=float) if "t" in columns else None
        ok = ~np.isnan(n)
        n = n[ok].astype(np.int64)
        t = None if t is None else t[ok]
        for key, entity in LOG_ENTITIES.items():
            if key in columns:
                self._send(n, t, entity, np.asarray(columns[key], dtype=float)[ok])

    def log_prediction(self, prediction: Mapping[str, np.ndarray], n=None) -> None:
        """Record a model prediction beside the logged signals.

        Parameters
        ----------
        prediction : mapping of str to numpy.ndarray, each shape (N,)
            ``station.plant.simulate`` output: ``theta`` (encoder counts), ``a``
            (accelerometer counts), ``v`` (DAC counts), optionally ``t`` (s).
        n : array_like of int, shape (N,), optional
            Ticks of the samples; default 0..N-1.
        """
        theta = np.asarray(prediction["theta"], dtype=float)
        n = np.arange(theta.size) if n is None else np.asarray(n, dtype=np.int64)
        t = np.asarray(prediction["t"], dtype=float) if "t" in prediction else None
        for key, entity in MODEL_ENTITIES.items():
            if key in prediction:
                self._send(n, t, entity, prediction[key])

    def close(self, keep: bool = True, transaction=None) -> None:
        """Flush the recording and write the .rrd file, or close the viewer connection. Idempotent.

        Parameters
        ----------
        keep : bool, default True
            Write the .rrd file (False: drop the recording, e.g. of a run that never
            started). A recording that cannot be flushed is dropped too (with a warning).
        transaction : station.outputs.Transaction, optional
            Write the .rrd file through it (renamed into place with the command's other
            files); default: at once.

        Raises
        ------
        StationError
            The .rrd file cannot be written (an existing file is unchanged, no part is left).
        """
        if self._closed:
            return
        self._closed = True
        data = None
        try:
            if self._stream is not None:
                data = self._stream.read(flush=True) or b""
            else:
                self.rec.flush(timeout_sec=2.0)
            self.rec.disconnect()
        except Exception as exc:  # noqa: BLE001 - the run and its log are done; only the view is lost
            first_line = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
            warnings.warn(f"rerun: the recording could not be flushed: {first_line}", RuntimeWarning, stacklevel=2)
            return
        if keep and data is not None:
            if transaction is not None:
                transaction.write(self.rrd_path, data, "the rerun recording")
            else:
                write_bytes(self.rrd_path, data, "the rerun recording")
