"""The diagnosis report: ``report.html`` with its figures embedded, and the same figures as
PNG files beside it (``station diagnose --report DIR``).

Figures are :class:`matplotlib.figure.Figure` objects rendered with the Agg canvas (no
pyplot, no global backend): per run, measured vs nominal vs extended θ and a; per run, the
``resid`` tests of the θ residual before and after (autocorrelation and cross-correlation
with the command, 99 % band). The files' names are known before the diagnosis starts
(:func:`report_files`: the command checks them, :mod:`station.outputs`), unique even for
runs of the same name, and written whole or not at all (:class:`station.outputs.Transaction`).
"""

from __future__ import annotations

import base64
import html
import io
import re
from collections.abc import Sequence
from pathlib import Path

from matplotlib.figure import Figure

from station.diagnosis.prose import format_pct, format_value, summary_paragraph
from station.outputs import Transaction, unique_names
from station.plots import diagnosis_resid_figure, diagnosis_run_figure


PAGE = "report.html"
"""The report's page in its folder."""
FIGURES = ("run", "resid")
"""Each run's figures, ``<run>_run.png`` and ``<run>_resid.png``."""


def _slugs(names: Sequence[str]) -> list[str]:
    """File-name stems of the runs' figures: their names made safe, unique within the report."""
    return unique_names([re.sub(r"[^A-Za-z0-9_.-]+", "_", Path(n).stem)[:60] for n in names])


def report_files(run_names: Sequence[str]) -> list[str]:
    """The files :func:`write_report` writes for runs of these names, the page first.

    Parameters
    ----------
    run_names : sequence of str
        The runs' file names (``RunReport.file``), in the diagnosis's order (RUNs then
        ``--validate`` runs).

    Returns
    -------
    list of str
        Names inside the report folder: ``report.html``, then per run its figures.
    """
    return [PAGE] + [f"{slug}_{kind}.png" for slug in _slugs(run_names) for kind in FIGURES]


def _png(fig: Figure) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


_STYLE = ("body{font-family:sans-serif;max-width:1000px;margin:auto}table{border-collapse:collapse}"
          "td,th{border:1px solid #ccc;padding:2px 6px;font-size:90%}td.ev{font-size:80%}"
          "img{max-width:100%}.note{color:#666;font-size:85%}")


def _result_table(diag) -> list[str]:
    esc, pct = html.escape, format_pct
    effects = ", ".join(f"{k} = {v:.4g}" for k, v in diag.extended_model.effect_dict().items()) or "no effects"
    return [f"<h1>Model diagnosis: {esc(diag.nominal_model.name)}</h1>",
            f"<p><b>{esc(summary_paragraph(diag))}</b></p>",
            "<h2>Result</h2><table>",
            f"<tr><th>cause</th><td>{esc(diag.cause)}</td></tr>",
            f"<tr><th>causes</th><td>{esc(', '.join(diag.causes) or '[]')}</td></tr>",
            f"<tr><th>validation</th><td>{esc(diag.validation)}</td></tr>",
            f"<tr><th>θ fit nominal → extended</th><td>{pct(diag.baseline_fit.get('theta'))} → "
            f"{pct(diag.extended_fit.get('theta'))}</td></tr>",
            f"<tr><th>a fit nominal → extended</th><td>{pct(diag.baseline_fit.get('accel'))} → "
            f"{pct(diag.extended_fit.get('accel'))}</td></tr>",
            f"<tr><th>θ RMS gain (pooled)</th><td>{diag.gain_pct:.1f} %</td></tr>",
            f"<tr><th>extended model</th><td>{esc(diag.extended_model.name)}: {esc(effects)}</td></tr>",
            f"<tr><th>simulations</th><td>{diag.simulations} in {diag.elapsed_s:.1f} s</td></tr></table>"]


def _candidates_table(diag) -> list[str]:
    esc = html.escape
    rows = ["<h2>Candidates</h2><table><tr><th>effect</th><th>value</th><th>θ gain</th><th>θ+a cost gain</th>"
            "<th>accepted</th><th>evidence</th></tr>"]
    for e in diag.effects:
        rows.append(f"<tr><td>{esc(e.name)}</td><td>{esc(format_value(e.value, e.unit))}</td>"
                    f"<td>{e.gain_pct:.1f} %</td><td>{e.cost_gain_pct:.1f} %</td><td>{'yes' if e.accepted else ''}</td>"
                    f"<td class='ev'>{esc(e.evidence)}</td></tr>")
    return rows


def _runs_table(diag) -> list[str]:
    esc, pct = html.escape, format_pct
    rows = ["</table><h2>Runs</h2><table><tr><th>run</th><th>role</th><th>controller</th>"
            "<th>θ fit nominal</th><th>θ fit extended</th><th>θ RMS gain</th><th>overshoot rig / nominal / "
            "extended</th></tr>"]
    for r in diag.runs:
        m = r.metrics
        ov = "" if m is None else " / ".join(f"{m[k].overshoot_pct:.2f} %" for k in ("rig", "nominal", "extended"))
        rows.append(f"<tr><td>{esc(r.file)}</td><td>{r.role}</td><td>{esc(r.controller)}</td>"
                    f"<td>{pct(r.fit_nominal.get('theta'))}</td><td>{pct(r.fit_extended.get('theta'))}</td>"
                    f"<td>{r.gain_pct:.1f} %</td><td>{ov}</td></tr>")
    rows.append("</table>")
    return rows


def _run_section(run, slug: str, folder: Path, extended: bool, tx: Transaction) -> list[str]:
    """One run's signatures and figures; writes its PNGs into ``folder`` through ``tx``."""
    esc = html.escape
    out = [f"<h3>{esc(run.file)}</h3>"]
    sig_b = run.residuals_before.signatures() if run.residuals_before else []
    sig_a = run.residuals_after.signatures() if run.residuals_after else []
    out.append("<p>Nominal model: " + esc("; ".join(sig_b) or "no notable signature") + "</p>")
    if extended:
        out.append("<p>Extended model: " + esc("; ".join(sig_a) or "no notable signature") + "</p>")
    for kind, fig in zip(FIGURES, (diagnosis_run_figure(run), diagnosis_resid_figure(run))):
        png = _png(fig)
        name = f"{slug}_{kind}.png"
        tx.write(folder / name, png, "the report's figure")
        out.append(f"<img alt='{esc(name)}' src='data:image/png;base64,{base64.b64encode(png).decode()}'>")
    for note in run.notes:
        out.append(f"<p class='note'>note: {esc(note)}</p>")
    return out


def write_report(diag, folder: str | Path, transaction: Transaction | None = None) -> Path:
    """Write ``report.html`` (figures embedded as base64 PNG) and the PNGs beside it
    (:func:`report_files`), whole or not at all.

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned.
    folder : str or Path
        Created if needed.
    transaction : station.outputs.Transaction, optional
        Write through it (renamed into place with the command's other files when it
        commits); default: a transaction of the report's own files.

    Returns
    -------
    Path
        The HTML file.

    Raises
    ------
    StationError
        A file cannot be written (nothing of the report is left then).
    """
    if transaction is None:
        with Transaction() as tx:
            return write_report(diag, folder, tx)
    folder = Path(folder)
    body = _result_table(diag) + _candidates_table(diag) + _runs_table(diag)
    for r, slug in zip(diag.runs, _slugs([r.file for r in diag.runs])):
        body += _run_section(r, slug, folder, bool(diag.causes), transaction)
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>Model diagnosis</title><style>"
            + _STYLE + "</style></head><body>" + "\n".join(body) + "</body></html>")
    out = folder / PAGE
    transaction.write(out, page, "the report")
    return out


__all__ = ["report_files", "write_report"]
