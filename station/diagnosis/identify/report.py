"""The identification report (``station identify --report DIR``): the last diagnosis's
``report.html`` (:func:`station.diagnosis.answer.report.write_report`) and ``identify.html``: how the
identification ended, every experiment with why it was run and its outcome, and for each
designed one a figure of θ and a predicted on the chosen model and on its rivals beside what
the device measured (also as ``experiment-NN.png``)."""

from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from station.rig import DT
from station.diagnosis.runs.cases import load_case
from station.diagnosis.answer.report import write_report
from station.outputs import Transaction
from station.plots import identify_design_figure, save_figure
from station.htmlpage import html_page



def _measured(record):
    """θ and a of a completed experiment as the diagnosis compares them (None when not used)."""
    if not record.used:
        return None
    case = load_case(record.log)
    return case.theta, case.a


def write_identify_report(ident, folder: str | Path, transaction: Transaction | None = None) -> Path:
    """Write ``identify.html`` and its PNGs, and the last diagnosis's ``report.html``, to a folder.

    Parameters
    ----------
    ident : Identification
        What :func:`station.diagnosis.identify.loop.identify` returned.
    folder : str or Path
        Created if needed.
    transaction : station.outputs.Transaction, optional
        Write through it (renamed into place with the command's other files); default: a
        transaction of its own.

    Returns
    -------
    Path
        ``identify.html``.

    Raises
    ------
    StationError
        The folder or a file cannot be written.
    """
    if transaction is None:
        with Transaction() as tx:
            return write_identify_report(ident, folder, tx)
    folder = Path(folder)
    diag = ident.diagnosis
    body = ["<h1>Identifying the rig</h1>", f"<p>{html.escape(ident.stopped)}.</p>"]
    if diag is not None:
        write_report(diag, folder, transaction)
        causes = ", ".join(diag.causes) or "none"
        body.append(f"<p>Last diagnosis ({ident.diagnoses} made): causes <b>{html.escape(causes)}</b>, θ RMS gain "
                    f"{diag.gain_pct:.1f} % on held-out runs; <a href='report.html'>the diagnosis report</a>.</p>")
    rows = ["<tr><th>#</th><th>experiment</th><th>why</th><th>outcome</th><th>used</th><th>log</th></tr>"]
    for k, r in enumerate(ident.experiments, 1):
        rows.append(f"<tr><td>{k}</td><td>{html.escape(r.experiment.label)}</td><td>{html.escape(r.why)}</td>"
                    f"<td>{html.escape(r.reason)}</td><td>{'yes' if r.used else 'no'}</td>"
                    f"<td>{html.escape(Path(r.log).name)}</td></tr>")
    body.append("<table>" + "".join(rows) + "</table>")
    for k, r in enumerate(ident.experiments, 1):
        if r.design is None or not r.design.predictions:
            continue
        preds = {label: (p.theta, p.a) for label, p in r.design.predictions.items()}
        t = np.arange(max(p.theta.size for p in r.design.predictions.values())) * DT
        fig = identify_design_figure(t, preds, _measured(r), title=r.why)
        png = save_figure(fig, folder / f"experiment-{k:02d}.png", transaction=transaction)
        body.append(f"<h2>Experiment {k}: {html.escape(r.experiment.label)}</h2><p>{html.escape(r.why)}</p>"
                    f"<img src='{png.name}' alt='experiment {k}'>")
    page = html_page("Identifying the rig", body)
    out = folder / "identify.html"
    transaction.write(out, page, "the report")
    return out
