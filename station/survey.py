"""Survey a lab's logs: replay every file of a folder and tabulate what each one is.

Each file is replayed (:func:`station.replay.replay`; what the log was, its controller,
alignment and sample time, comes from the report's :class:`station.logged.LoggedRun`) in a
worker process
(concurrent.futures.ProcessPoolExecutor, one per core); a file that cannot be used
(binary, empty, a foreign CSV, a broken row) becomes a row with the one-line reason,
never an abort. A file the station wrote beside its logs (a figure, a JSON report, a
model file, a survey table: :func:`not_a_log`) is "not a log", a status of its own: it is
neither replayed nor counted as a broken log. SIGINT / SIGTERM stop the worker processes
at once (:mod:`station.pools`).
"""

from __future__ import annotations

import csv
import io
import os
import re
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

from station.analysis.metrics import FROM_START, NOT_SETTLED, SETTLE_HOLD_S, THESIS_BAND_PCT, settling_label
from station.errors import StationError
from station.inputs import exists, is_folder, open_regular
from station.logged.reproduction import reproduction_lines
from station.logged.sensors import DOUBT_WORDS
from station.outputs import WRITTEN_SUFFIXES, Transaction
from station.pools import as_finished, lost, process_pool, submit_all
from station.replay import NOT_TIP, replay

STATUSES = ("ok", "unusable", "not a log")
"""A file's status: replayed; a log (or what claims to be one) that could not be used; a file
the station writes besides logs (:func:`not_a_log`)."""

FIELDS = ("file", "status", "format", "rows", "sample_time_s", "controller", "controller_source", "alignment",
          "max_abs_dv", "overshoot_pct", "settling_thesis_s", "fit_theta_pct", "fit_accel_pct", "accel_is_tip",
          "f1_hz", "zeta1", "f1_model_hz", "zeta1_model", "reason")
"""Columns of the survey table and CSV, in order."""


@dataclass
class SurveyRow:
    """One file of a survey (the CSV's columns, :data:`FIELDS`).

    Attributes
    ----------
    file : str
        The log's path.
    status : str
        One of :data:`STATUSES` ("unusable" whenever ``reason`` is given without one).
    format : str
        Its layout ("station", "rig", "columns", ...; :attr:`station.runlog.RunLog.layout`).
    rows : int or None
        Samples in the log.
    sample_time_s : float or None
        The log's sample time, s.
    controller : str
        The replayed controller's name ("" when none).
    controller_source : str
        "header", "inferred", "inferred (header contradicted)" or "" (none).
    alignment : int or None
        Computational delay detected by the replay, samples.
    max_abs_dv : float or None
        Largest |replayed v − logged v|, DAC counts (None: not replayed, or judged on no row,
        a law with memory on a copy that skips ticks).
    overshoot_pct, settling_thesis_s : float or None
        Step metrics of the logged θ (:class:`station.analysis.metrics.StepMetrics`).
    fit_theta_pct, fit_accel_pct : float or None
        NRMSE fit of the model to the logged θ and a, %.
    accel_is_tip : bool or None
        False when the log audit found a no tip acceleration (its fit is then no model error:
        the table says so beside it, as replay does); None without an audit.
    f1_hz, zeta1 : float or None
        Hub-held beam test: measured first mode, Hz, and its damping ratio.
    f1_model_hz, zeta1_model : float or None
        The model's hub-held first mode beside it.
    reason : str
        Empty for a usable file, else one line saying why it could not be used, or what
        the file is when it is not a log.
    report : dict or None
        The replay's JSON (:meth:`station.replay.ReplayReport.to_json`, its ``audit``
        included); not a CSV column.
    contradictions : list of str
        The log's claims its data contradicted, one line each (DESIGN.md "Log audit"), then
        what its replay set aside or could not confirm (a corrupted field, a law no row pins:
        :func:`station.logged.reproduction.reproduction_lines`; what the sensors' ratios point at
        but do not decide: :attr:`station.replay.ReplayReport.doubt`); not a CSV column.
    """

    file: str
    status: str = "ok"
    format: str = ""
    rows: int | None = None
    sample_time_s: float | None = None
    controller: str = ""
    controller_source: str = ""
    alignment: int | None = None
    max_abs_dv: float | None = None
    overshoot_pct: float | None = None
    settling_thesis_s: float | None = None
    fit_theta_pct: float | None = None
    fit_accel_pct: float | None = None
    accel_is_tip: bool | None = None
    f1_hz: float | None = None
    zeta1: float | None = None
    f1_model_hz: float | None = None
    zeta1_model: float | None = None
    reason: str = ""
    report: dict[str, Any] | None = field(default=None, repr=False)
    contradictions: list[str] = field(default_factory=list, repr=False)

    def __post_init__(self) -> None:
        if self.reason and self.status == "ok":
            self.status = "unusable"

    @property
    def usable(self) -> bool:
        """True when the file was read and replayed."""
        return self.status == "ok"


_SURVEY_TABLE = re.compile(r"file +format +rows +dt s +controller")


def not_a_log(path: str | Path) -> str | None:
    """What a file is when the station wrote it and it is no run log, else None.

    By suffix (:data:`station.outputs.WRITTEN_SUFFIXES`: figures, JSON reports, rerun
    recordings, report pages, model and compensator files), a PNG by its signature, and the
    survey's own table and CSV by their first line.

    Parameters
    ----------
    path : str or Path
        Any file.
    """
    path = Path(path)
    what = WRITTEN_SUFFIXES.get(path.suffix.lower())
    if what is not None:
        return what
    try:
        with open_regular(path, "run log") as fh:
            head = fh.read(4096)
    except (OSError, StationError):  # not a regular file, unreadable: replay names it
        return None
    if head.startswith(b"\x89PNG\r\n\x1a\n"):
        return WRITTEN_SUFFIXES[".png"]
    first = head.split(b"\n", 1)[0].decode("utf-8", "replace")
    if first.startswith(",".join(FIELDS[:4]) + ",") or _SURVEY_TABLE.match(first):
        return "a survey table"
    return None


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
        if is_folder(p):
            for f in sorted(p.rglob("*")):
                rel = f.relative_to(p).parts
                if f.is_file() and not any(part.startswith(".") for part in rel):
                    out[f] = None
        elif exists(p) or os.path.islink(p):  # (a dangling link: its reading names it)
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
        ``reason`` holds the one-line error when the file could not be used (status
        "unusable"), or what the file is when it is not a log (status "not a log": it is
        not replayed).
    """
    what = not_a_log(path)
    if what is not None:
        return SurveyRow(file=str(path), status="not a log", reason=what)
    row = SurveyRow(file=str(path))
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            rep = replay(path, model=model)
    except StationError as exc:
        return SurveyRow(file=str(path), status="unusable", reason=str(exc).replace(str(path) + ": ", "", 1))
    except Exception as exc:  # noqa: BLE001 - a survey never stops at a file
        return SurveyRow(file=str(path), status="unusable",
                         reason=f"replay failed: {type(exc).__name__}: {exc}".splitlines()[0])
    run = rep.run
    row.report = rep.to_json()
    row.contradictions = [] if rep.audit is None else rep.audit.lines()
    if rep.max_abs_dv is not None:  # what the replay set aside or could not confirm, as replay says it
        row.contradictions += [f"replay reproduces the logged v, {line}" for line in
                               reproduction_lines(rep.max_abs_dv, rep.alignment, rep.audit, rep.judged_to)[1:]]
    if rep.doubt:  # as replay says it beside its fit
        row.contradictions.append(DOUBT_WORDS + rep.doubt)
    row.accel_is_tip = None if rep.audit is None else bool(rep.audit.accel_is_tip)
    row.format = run.log.layout or run.log.format
    row.rows = len(run)
    row.sample_time_s = run.log.sample_time
    if run.replayed is not None:  # a controller was replayed
        row.controller, row.controller_source = run.controller.name, run.source or ""
        row.alignment, row.max_abs_dv = run.alignment, run.max_abs_dv
        if rep.judged_to == 0:  # a law with memory on rows that skip ticks: judged on none
            row.max_abs_dv = None
            row.contradictions += reproduction_lines(rep.max_abs_dv, rep.alignment, rep.audit, 0)
    if rep.metrics is not None:
        row.overshoot_pct, row.settling_thesis_s = rep.metrics.overshoot_pct, rep.metrics.settling_time_s
    if rep.fit_pct is not None:
        row.fit_theta_pct, row.fit_accel_pct = rep.fit_pct["theta"], rep.fit_pct["accel"]
    if rep.beam_test is not None:  # run.held: a hub-held beam test
        bt = rep.beam_test
        row.f1_hz, row.zeta1 = bt.measured.f1_hz, bt.measured.zeta1
        row.f1_model_hz, row.zeta1_model = bt.f1_model_hz, bt.zeta1_model
    if not len(run):
        row.reason, row.status = "the log has no rows", "unusable"
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
        # a worker that dies (killed, out of memory, crashed) breaks the pool and fails every file
        # not yet replayed, through no fault of theirs: they are replayed again in a new pool, and
        # those lost once more one by one, each in a process of its own (twice), so only a file
        # whose replay kills its worker is a row saying so
        pending = list(files)
        for attempt in ("pool", "alone", "alone again"):
            lost_now: list[Path] = []
            for group in ([pending] if attempt == "pool" else [[f] for f in pending]):
                lost_now += _survey_pool(group, model, min(workers, len(group)), rows, len(files), progress,
                                         last_try=attempt == "alone again")
            pending = lost_now
            if not pending:
                break
    return [rows[f] for f in files]


WORKER_DIED = ("its replay ended the worker process abruptly twice, alone in a process of its own (crashed or out "
               "of memory)")
"""The row of a file whose replay kills the worker process every time."""


def _survey_pool(files: list[Path], model: bool, workers: int, rows: dict, total: int, progress,
                 last_try: bool) -> list[Path]:
    """Replay ``files`` in a new pool into ``rows``; return the files a dead worker lost (on the
    last try, their row says so instead)."""
    lost_files = []
    with process_pool(workers) as pool:  # a signal, an error: the workers stop now
        futures = dict(zip(submit_all(pool, survey_one, [(f, model) for f in files]), files))
        for fut in as_finished(futures):
            f = futures[fut]
            if lost(fut) and not last_try:
                lost_files.append(f)
                continue
            try:
                rows[f] = fut.result()
            except Exception as exc:  # noqa: BLE001 - a failed replay costs one row, not the survey
                reason = WORKER_DIED if lost(fut) else f"worker failed: {type(exc).__name__}: {exc}"
                rows[f] = SurveyRow(file=str(f), reason=reason)
            if progress:
                progress(len(rows), total, rows[f])
    return lost_files


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
        First each log's claims its data contradicted (``FILE: header: ...; data: ...``), then
        columns: file, format, rows, dt (s), controller (name and h = named by the
        header / i = inferred), d (alignment), max|dv| (DAC counts), overshoot (%),
        settling (1 %) (s, the thesis's), fit θ / a (%) or, for beam tests, f1 (Hz) and ζ1 with the model's;
        an unusable file shows its reason instead. Files that are not logs are counted
        in the last line, by kind, not listed.
    """
    head = ["file", "format", "rows", "dt s", "controller", "d", "max|dv|", "OS %",
            f"{settling_label(THESIS_BAND_PCT)} s", "model / beam test"]
    lines = []
    first = []  # the audit's contradictions, said before the table
    others: dict[str, int] = {}
    for r in rows:
        if r.status == "not a log":
            others[r.reason] = others.get(r.reason, 0) + 1
            continue
        name = r.file
        if root is not None:
            try:
                name = str(Path(r.file).relative_to(root))
            except ValueError:
                pass
        first += [f"{name}: {line}" for line in r.contradictions]
        if not r.usable:
            lines.append([name, "-", "-", "-", "-", "-", "-", "-", "-", f"UNUSABLE: {r.reason}"])
            continue
        src = {"header": "", "inferred": " (inferred)",
               "inferred (header contradicted)": " (inferred; header contradicted)"}.get(r.controller_source, "")
        ctl = (r.controller + src) if r.controller else "none"
        if r.f1_hz is not None or r.zeta1 is not None or r.f1_model_hz is not None:
            last = (f"beam: f1 {_cell(r.f1_hz, '.3f')} Hz, zeta {_cell(r.zeta1, '.4f')} "
                    f"(model {_cell(r.f1_model_hz, '.3f')} Hz, {_cell(r.zeta1_model, '.4f')})")
        elif r.fit_theta_pct is not None or r.fit_accel_pct is not None:
            why = f" ({NOT_TIP})" if r.accel_is_tip is False else ""
            pct = lambda x: "-" if x is None else f"{x:.1f} %"  # noqa: E731 - "-": not fitted (no a column)
            last = f"fit theta {pct(r.fit_theta_pct)}, a {pct(r.fit_accel_pct)}{why}"
        else:
            last = "-"
        lines.append([name, r.format, _cell(r.rows), _cell(r.sample_time_s, "g"), ctl, _cell(r.alignment),
                      _cell(r.max_abs_dv, ".2g"), _cell(r.overshoot_pct, ".2f"),
                      "not settled" if r.overshoot_pct is not None and r.settling_thesis_s is None
                      else _cell(r.settling_thesis_s, ".3f"), last])
    widths = [max(len(head[i]), *(len(line[i]) for line in lines)) if lines else len(head[i])
              for i in range(len(head) - 1)]
    fmt_line = lambda cells: "  ".join(c.ljust(w) for c, w in zip(cells, widths)) + "  " + cells[-1]  # noqa: E731
    used, bad = sum(r.usable for r in rows), sum(r.status == "unusable" for r in rows)
    out = first + [fmt_line(head), fmt_line(["-" * w for w in widths] + ["-" * 17])]
    out += [fmt_line(line) for line in lines]
    if any(r.overshoot_pct is not None for r in rows):
        out.append(f"{settling_label(THESIS_BAND_PCT)} s: {FROM_START} of the log (the thesis's definition); not "
                   f"settled: {NOT_SETTLED} (outside the band at its end, or inside it for less than "
                   f"{SETTLE_HOLD_S:g} s); -: not a step")
    summary = f"{len(rows)} files: {used} replayed, {bad} unusable"
    if others:
        n = sum(others.values())
        summary += (f", {n} {'not a log' if n == 1 else 'not logs'} (not listed: "
                    + ", ".join(f"{k} x {what}" for what, k in others.items()) + ")")
    out.append(summary)
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


TABLE = "survey.txt"
"""The table's file in a ``--report`` folder."""


def report_files(files: Sequence[str | Path]) -> list[str]:
    """The names :func:`write_reports` gives, in a folder, to the survey of these files:
    ``<n>_<stem>.json`` per log (n: its place among all files; none for a file that is not
    a log), then the table.

    Parameters
    ----------
    files : sequence of str or Path
        What :func:`find_logs` found, in its order.
    """
    return [_report_name(i, f) for i, f in enumerate(files) if not_a_log(f) is None] + [TABLE]


def _report_name(i: int, file: str | Path) -> str:
    return f"{i:03d}_{Path(file).stem}.json"  # the place keeps names of equal stems apart


def write_reports(rows: Sequence[SurveyRow], folder: str | Path, transaction: Transaction | None = None) -> list[Path]:
    """Write each log's replay JSON (its reason for an unusable one) and the table into
    ``folder`` (created), named by :func:`report_files`, whole or not at all.

    Parameters
    ----------
    rows : sequence of SurveyRow
        The survey's rows (files that are not logs get no JSON).
    folder : str or Path
        Output folder.
    transaction : station.outputs.Transaction, optional
        Write through it (renamed into place when it commits); default: at once.

    Returns
    -------
    list of Path
        The files written.

    Raises
    ------
    StationError
        A file cannot be written (then none of them is).
    """
    if transaction is None:
        with Transaction() as tx:
            return write_reports(rows, folder, tx)
    folder = Path(folder)
    written = []
    for i, r in enumerate(rows):
        if r.status == "not a log":
            continue
        body = r.report if r.report is not None else {"file": r.file, "reason": r.reason}
        p = folder / _report_name(i, r.file)
        transaction.write_json(p, body, "the survey report")
        written.append(p)
    p = folder / TABLE
    transaction.write(p, format_table(rows) + "\n", "the survey table")
    written.append(p)
    return written
