"""Survey a lab's logs: replay every file of a folder and tabulate what each one is.

Each file is replayed (:func:`station.replay.replay`; what the log was, its controller,
alignment and sample time, comes from the report's :class:`station.logged.LoggedRun`) in a
worker process
(concurrent.futures.ProcessPoolExecutor, one per core); a file that cannot be used
(binary, empty, a foreign CSV, a broken row) becomes a row with the one-line reason,
never an abort.
"""

from __future__ import annotations

import csv
import io
import json
import os
import warnings
from collections.abc import Callable, Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from station.errors import StationError
from station.replay import replay

FIELDS = ("file", "format", "rows", "sample_time_s", "controller", "controller_source", "alignment",
          "max_abs_dv", "overshoot_pct", "settling_time_s", "fit_theta_pct", "fit_accel_pct",
          "f1_hz", "zeta1", "f1_model_hz", "zeta1_model", "reason")
"""Columns of the survey table and CSV, in order."""


@dataclass
class SurveyRow:
    """One file of a survey (the CSV's columns, :data:`FIELDS`).

    Attributes
    ----------
    file : str
        The log's path.
    format : str
        Its layout ("station", "rig", "columns", ...; :attr:`station.runlog.RunLog.layout`).
    rows : int or None
        Samples in the log.
    sample_time_s : float or None
        The log's sample time, s.
    controller : str
        The replayed controller's name ("" when none).
    controller_source : str
        "header", "inferred" or "" (none).
    alignment : int or None
        Computational delay detected by the replay, samples.
    max_abs_dv : float or None
        Largest |replayed v − logged v|, DAC counts.
    overshoot_pct, settling_time_s : float or None
        Step metrics of the logged θ (:class:`station.analysis.metrics.StepMetrics`).
    fit_theta_pct, fit_accel_pct : float or None
        NRMSE fit of the model to the logged θ and a, %.
    f1_hz, zeta1 : float or None
        Hub-held beam test: measured first mode, Hz, and its damping ratio.
    f1_model_hz, zeta1_model : float or None
        The model's hub-held first mode beside it.
    reason : str
        Empty for a usable file, else one line saying why it could not be used.
    report : dict or None
        The replay's JSON (:meth:`station.replay.ReplayReport.to_json`); not a CSV column.
    """

    file: str
    format: str = ""
    rows: int | None = None
    sample_time_s: float | None = None
    controller: str = ""
    controller_source: str = ""
    alignment: int | None = None
    max_abs_dv: float | None = None
    overshoot_pct: float | None = None
    settling_time_s: float | None = None
    fit_theta_pct: float | None = None
    fit_accel_pct: float | None = None
    f1_hz: float | None = None
    zeta1: float | None = None
    f1_model_hz: float | None = None
    zeta1_model: float | None = None
    reason: str = ""
    report: dict[str, Any] | None = field(default=None, repr=False)

    @property
    def usable(self) -> bool:
        """True when the file was read and replayed."""
        return not self.reason


def find_logs(paths: Iterable[str | Path]) -> list[Path]:
    """The files to survey: each FILE as given, every file under each DIR (recursive,
    hidden files and folders skipped), sorted, without duplicates.

    Parameters
    ----------
    paths : iterable of str or Path
        Files and folders.

    Raises
    ------
    StationError
        A path that does not exist.
    """
    out: dict[Path, None] = {}
    for p in map(Path, paths):
        if p.is_dir():
            for f in sorted(p.rglob("*")):
                rel = f.relative_to(p).parts
                if f.is_file() and not any(part.startswith(".") for part in rel):
                    out[f] = None
        elif p.exists():
            out[p] = None
        else:
            raise StationError(f"{p}: no such file or folder")
    return list(out)


def survey_one(path: str | Path, model: bool = True) -> SurveyRow:
    """Replay one file into a :class:`SurveyRow`; never raises for a bad file.

    Parameters
    ----------
    path : str or Path
    model : bool
        Also run the FEM model (fits); hub-held beam tests are analyzed either way.

    Returns
    -------
    SurveyRow
        ``reason`` holds the one-line error when the file could not be used.
    """
    row = SurveyRow(file=str(path))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rep = replay(path, model=model)
    except StationError as exc:
        row.reason = str(exc).replace(str(path) + ": ", "", 1)
        return row
    except Exception as exc:  # noqa: BLE001 - a survey never stops at a file
        row.reason = f"replay failed: {type(exc).__name__}: {exc}".splitlines()[0]
        return row
    run = rep.run
    row.report = rep.to_json()
    row.format = run.log.layout or run.log.format
    row.rows = len(run)
    row.sample_time_s = run.log.sample_time
    if run.replayed is not None:  # a controller was replayed
        row.controller, row.controller_source = run.controller.name, run.source or ""
        row.alignment, row.max_abs_dv = run.alignment, run.max_abs_dv
    if rep.metrics is not None:
        row.overshoot_pct, row.settling_time_s = rep.metrics.overshoot_pct, rep.metrics.settling_time_s
    if rep.fit_pct is not None:
        row.fit_theta_pct, row.fit_accel_pct = rep.fit_pct["theta"], rep.fit_pct["accel"]
    if rep.beam_test is not None:  # run.held: a hub-held beam test
        bt = rep.beam_test
        row.f1_hz, row.zeta1 = bt.measured.f1_hz, bt.measured.zeta1
        row.f1_model_hz, row.zeta1_model = bt.f1_model_hz, bt.zeta1_model
    if not len(run):
        row.reason = "the log has no rows"
    return row


def survey(paths: Sequence[str | Path], model: bool = True, workers: int | None = None,
           progress: Callable[[int, int, SurveyRow], None] | None = None) -> list[SurveyRow]:
    """Replay every log found under ``paths``, in parallel.

    Parameters
    ----------
    paths : sequence of str or Path
        Files and folders (searched recursively, see :func:`find_logs`).
    model : bool
        Run the FEM model for each log (fits).
    workers : int, optional
        Worker processes (default: the machine's cores, ``os.cpu_count()``); 1 runs in
        this process.
    progress : callable(done, total, row), optional
        Called after each file, in completion order.

    Returns
    -------
    list of SurveyRow
        In the order of :func:`find_logs` (sorted paths).

    Raises
    ------
    StationError
        A path that does not exist, or nothing to survey.
    """
    files = find_logs(paths)
    if not files:
        raise StationError(f"{', '.join(map(str, paths))}: no files to survey")
    workers = workers or os.cpu_count() or 1
    rows: dict[Path, SurveyRow] = {}
    if workers == 1 or len(files) == 1:
        for f in files:
            rows[f] = survey_one(f, model)
            if progress:
                progress(len(rows), len(files), rows[f])
    else:
        with ProcessPoolExecutor(max_workers=min(workers, len(files))) as pool:
            futures = {pool.submit(survey_one, f, model): f for f in files}
            for fut in as_completed(futures):
                f = futures[fut]
                try:
                    rows[f] = fut.result()
                except Exception as exc:  # noqa: BLE001 - a dead worker costs one row, not the survey
                    rows[f] = SurveyRow(file=str(f), reason=f"worker failed: {type(exc).__name__}: {exc}")
                if progress:
                    progress(len(rows), len(files), rows[f])
    return [rows[f] for f in files]


def _cell(value: Any, fmt: str = "") -> str:
    if value is None or value == "":
        return "-"
    if isinstance(value, float):
        return format(value, fmt or ".4g")
    return str(value)


def format_table(rows: Sequence[SurveyRow], root: str | Path | None = None) -> str:
    """The survey as one plain-text table (what ``station survey`` prints).

    Parameters
    ----------
    rows : sequence of SurveyRow
    root : str or Path, optional
        File names are shown relative to it.

    Returns
    -------
    str
        Columns: file, format, rows, dt (s), controller (name and h = named by the
        header / i = inferred), d (alignment), max|dv| (DAC counts), overshoot (%),
        settling (s), fit θ / a (%) or, for beam tests, f1 (Hz) and ζ1 with the model's;
        an unusable file shows its reason instead.
    """
    head = ["file", "format", "rows", "dt s", "controller", "d", "max|dv|", "OS %", "Ts s", "model / beam test"]
    lines = []
    for r in rows:
        name = r.file
        if root is not None:
            try:
                name = str(Path(r.file).relative_to(root))
            except ValueError:
                pass
        if not r.usable:
            lines.append([name, "-", "-", "-", "-", "-", "-", "-", "-", f"UNUSABLE: {r.reason}"])
            continue
        src = {"header": "", "inferred": " (inferred)"}.get(r.controller_source, "")
        ctl = (r.controller + src) if r.controller else "none"
        if r.f1_hz is not None or r.zeta1 is not None or r.f1_model_hz is not None:
            last = (f"beam: f1 {_cell(r.f1_hz, '.3f')} Hz, zeta {_cell(r.zeta1, '.4f')} "
                    f"(model {_cell(r.f1_model_hz, '.3f')} Hz, {_cell(r.zeta1_model, '.4f')})")
        elif r.fit_theta_pct is not None or r.fit_accel_pct is not None:
            last = f"fit theta {_cell(r.fit_theta_pct, '.1f')} %, a {_cell(r.fit_accel_pct, '.1f')} %"
        else:
            last = "-"
        lines.append([name, r.format, _cell(r.rows), _cell(r.sample_time_s, "g"), ctl, _cell(r.alignment),
                      _cell(r.max_abs_dv, ".2g"), _cell(r.overshoot_pct, ".2f"), _cell(r.settling_time_s, ".3f"),
                      last])
    widths = [max(len(head[i]), *(len(line[i]) for line in lines)) if lines else len(head[i])
              for i in range(len(head) - 1)]
    fmt_line = lambda cells: "  ".join(c.ljust(w) for c, w in zip(cells, widths)) + "  " + cells[-1]  # noqa: E731
    used = sum(r.usable for r in rows)
    out = [fmt_line(head), fmt_line(["-" * w for w in widths] + ["-" * 17])]
    out += [fmt_line(line) for line in lines]
    out.append(f"{len(rows)} files: {used} replayed, {len(rows) - used} unusable")
    return "\n".join(out)


def to_csv(rows: Sequence[SurveyRow]) -> str:
    """The survey as CSV text, columns :data:`FIELDS` (empty cells for None).

    Parameters
    ----------
    rows : sequence of SurveyRow
        The survey's rows, in order.
    """
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(FIELDS)
    for r in rows:
        d = asdict(r)
        w.writerow(["" if d[k] is None else d[k] for k in FIELDS])
    return buf.getvalue()


def write_reports(rows: Sequence[SurveyRow], folder: str | Path) -> list[Path]:
    """Write each usable file's replay JSON (``<n>_<stem>.json``) and the table
    (``survey.txt``) into ``folder`` (created).

    Parameters
    ----------
    rows : sequence of SurveyRow
        The survey's rows (unusable files get no JSON).
    folder : str or Path
        Output folder.

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    StationError
        The folder cannot be created or written.
    """
    folder = Path(folder)
    written = []
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for i, r in enumerate(rows):
            body = r.report if r.report is not None else {"file": r.file, "reason": r.reason}
            p = folder / f"{i:03d}_{Path(r.file).stem}.json"
            p.write_text(json.dumps(body, indent=1) + "\n")
            written.append(p)
        p = folder / "survey.txt"
        p.write_text(format_table(rows) + "\n")
        written.append(p)
    except OSError as exc:
        raise StationError(f"{folder}: cannot write the survey report: {exc.strerror or exc}") from None
    return written
