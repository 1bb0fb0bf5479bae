"""The diagnosis report: ``report.html`` with its figures embedded, and the same figures as
PNG files beside it (``station diagnose --report DIR``).

Figures are :class:`matplotlib.figure.Figure` objects rendered with the Agg canvas (no
pyplot, no global backend): per run, measured vs nominal vs extended θ and a; per run, the
``resid`` tests of the θ residual before and after (autocorrelation and cross-correlation
with the command, 99 % band).
"""

from __future__ import annotations

import base64
import html
import io
import re
from pathlib import Path

from matplotlib.figure import Figure

from station.diagnosis.prose import format_pct, format_value, summary_paragraph
from station.errors import StationError
from station.plots import diagnosis_resid_figure, diagnosis_run_figure


def _slug(name: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", Path(name).stem)[:60]


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


def _run_section(run, folder: Path, extended: bool) -> list[str]:
    """One run's signatures and figures; writes its PNGs into ``folder`` (OSError)."""
    esc = html.escape
    out = [f"<h3>{esc(run.file)}</h3>"]
    sig_b = run.residuals_before.signatures() if run.residuals_before else []
    sig_a = run.residuals_after.signatures() if run.residuals_after else []
    out.append("<p>Nominal model: " + esc("; ".join(sig_b) or "no notable signature") + "</p>")
    if extended:
        out.append("<p>Extended model: " + esc("; ".join(sig_a) or "no notable signature") + "</p>")
    for kind, fig in (("run", diagnosis_run_figure(run)), ("resid", diagnosis_resid_figure(run))):
        png = _png(fig)
        name = f"{_slug(run.file)}_{kind}.png"
        (folder / name).write_bytes(png)
        out.append(f"<img alt='{esc(name)}' src='data:image/png;base64,{base64.b64encode(png).decode()}'>")
    for note in run.notes:
        out.append(f"<p class='note'>note: {esc(note)}</p>")
    return out


def write_report(diag, folder: str | Path) -> Path:
    """Write ``report.html`` (figures embedded as base64 PNG) and the PNGs beside it.

    Parameters
    ----------
    diag : Diagnosis
        What :func:`station.diagnosis.diagnose` returned.
    folder : str or Path
        Created if needed.

    Returns
    -------
    Path
        The HTML file.

    Raises
    ------
    StationError
        The folder or a file cannot be written.
    """
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
        body = _result_table(diag) + _candidates_table(diag) + _runs_table(diag)
        for r in diag.runs:
            body += _run_section(r, folder, bool(diag.causes))
        page = ("<!doctype html><html><head><meta charset='utf-8'><title>Model diagnosis</title><style>"
                + _STYLE + "</style></head><body>" + "\n".join(body) + "</body></html>")
        out = folder / "report.html"
        out.write_text(page, encoding="utf-8")
    except OSError as exc:
        raise StationError(f"--report {folder}: cannot write: {exc}") from None
    return out


__all__ = ["write_report"]
