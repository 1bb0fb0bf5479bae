"""The diagnosis report: ``report.html`` with its figures embedded, and the same figures as
PNG files beside it (``station diagnose --report DIR``).

The page leads with the answer in words (the cause in plain words and code name, its value
with its 95 % interval, the gain on held-out data, what is still unexplained, the
alternatives, the targets missed), then the evidence: the result, the candidates (alone
and in the extended model, in separate columns), the alternatives, what the extended model
leaves against the sensor model, the runs, and per run two figures.

Figures are :class:`matplotlib.figure.Figure` objects rendered with the Agg canvas (no
pyplot, no global backend): per run, measured vs nominal vs extended θ and a with the
stretches where the hub sticks shaded; per run, the θ and a residuals of both models on
the same axes, the θ residual's autocorrelation to 0.5 s and its spectrum. The files' names
are known before the diagnosis starts (:func:`report_files`: the command checks them,
:mod:`station.outputs`), unique even for runs of the same name, and written whole or not at
all (:class:`station.outputs.Transaction`).
"""

from __future__ import annotations

import base64
import html
import io
import re
from collections.abc import Sequence
from pathlib import Path

from matplotlib.figure import Figure

from station.diagnosis.answer.prose import (
    OVERSHOOT_POINTS,
    answer_points,
    at_range_end,
    format_pct,
    interval_words,
    plain_name,
    plain_value,
)
from station.outputs import Transaction, unique_names
from station.plant.effects import EFFECTS
from station.plots import diagnosis_resid_figure, diagnosis_run_figure, short_name
from station.htmlpage import html_page


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




def _answer(diag) -> list[str]:
    esc = html.escape
    items = "".join(f"<li><b>{esc(label)}:</b> <span class='{'warn' if label in WARN_LABELS else ''}'>"
                    f"{esc(text)}</span></li>" for label, text in answer_points(diag))
    return [f"<h1>Model diagnosis: {esc(diag.nominal_model.name)} on {len(diag.runs)} runs</h1>",
            f"<h2>Answer</h2><ul class='answer'>{items}</ul>"]


WARN_LABELS = ("Audit", "Still unexplained", "Target missed", "Residuals", "Alternatives")


def _result_table(diag) -> list[str]:
    esc, pct = html.escape, format_pct
    effects = ", ".join(f"{k} = {v:.4g}" for k, v in diag.extended_model.effect_dict().items()) or "no effects"
    return ["<h2>Evidence</h2><h3>Result</h3><table>",
            f"<tr><th>cause</th><td>{esc(diag.cause)}</td></tr>",
            f"<tr><th>causes</th><td>{esc(', '.join(diag.causes) or '[]')}</td></tr>",
            f"<tr><th>validation</th><td>{esc(diag.validation)}</td></tr>",
            f"<tr><th>θ fit nominal → extended</th><td>{pct(diag.baseline_fit.get('theta'))} → "
            f"{pct(diag.extended_fit.get('theta'))}</td></tr>",
            f"<tr><th>a fit nominal → extended</th><td>{pct(diag.baseline_fit.get('accel'))} → "
            f"{pct(diag.extended_fit.get('accel'))}</td></tr>",
            f"<tr><th>θ RMS gain (pooled, held out)</th><td>{diag.gain_pct:.1f} %</td></tr>",
            f"<tr><th>extended model</th><td>{esc(diag.extended_model.name)}: {esc(effects)}</td></tr>",
            f"<tr><th>intervals</th><td>{esc(diag.interval_method or 'none (no accepted effect)')}</td></tr>",
            f"<tr><th>simulations</th><td>{diag.simulations} in {diag.elapsed_s:.1f} s</td></tr></table>"]


def _candidates_table(diag) -> list[str]:
    esc = html.escape
    rows = ["<h3>Candidates</h3><p class='note'>“Alone”: the nominal model plus this effect only, fitted and "
            "judged on held-out data. “In the extended model”: its value fitted jointly with the other accepted "
            "effects, and its 95 % interval.</p><table>"
            "<tr><th rowspan=2>effect</th><th colspan=3>alone</th><th colspan=2>in the extended model</th>"
            "<th rowspan=2>accepted</th><th rowspan=2>evidence</th></tr>"
            "<tr><th>value</th><th>θ RMS gain (held out)</th><th>θ+a cost gain</th><th>value</th>"
            "<th>95 % interval</th></tr>"]
    warn = " <span class='warn'>(at the end of its search range)</span>"
    held = diag.held
    for e in diag.effects:
        alone = e.value_alone if e.accepted else e.value
        cells = [esc(plain_name(e.name)),
                 esc(plain_value(e.name, alone, e.unit)) + (warn if at_range_end(e.name, alone) else ""),
                 f"{e.gain_pct:.1f} %", f"{e.cost_gain_pct:.1f} %"]
        if e.accepted:
            cells += [esc(plain_value(e.name, e.value, e.unit)) + (warn if e.at_range_end else ""),
                      esc(interval_words(e.name, e.interval, e.unit).replace("95 % interval ", "")), "yes"]
        elif e.name in held:  # in the model, held by an accepted effect or decided from the data
            cells += [esc(plain_value(e.name, held[e.name], e.unit)), "", "held"]
        else:
            cells += ["", "", ""]
        rows.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + f"<td class='ev'>{esc(e.evidence)}</td></tr>")
    rows.append("</table>")
    return rows


def _alternatives_table(diag) -> list[str]:
    if not diag.accepted:
        return []
    esc = html.escape
    if not diag.alternatives:
        alike = (f" The sensor wiring the data cannot decide, {html.escape(diag.wiring_alike)}, reads the same "
                 "signs (the audit above).") if diag.wiring_alike else ""
        return ["<h3>Alternatives</h3><p>None: every other candidate's validation cost is further from the chosen "
                f"explanation's than luck and the data's information reach.{alike}</p>"]
    rows = ["<h3>Alternatives the validation data cannot tell apart</h3><table><tr><th>causes</th><th>instead of</th>"
            "<th>values (refitted jointly)</th><th>θ RMS gain</th><th>validation cost / chosen</th></tr>"]
    for a in diag.alternatives:
        vals = ", ".join(f"{n} {plain_value(n, v, EFFECTS[n].unit if n in EFFECTS else '1')}"
                         for n, v in a.values.items())
        rows.append(f"<tr><td>{esc(' + '.join(a.causes))}</td><td>{esc(a.instead_of)}</td><td>{esc(vals)}</td>"
                    f"<td>{a.gain_pct:.1f} %</td><td>{a.cost_ratio:.3f}</td></tr>")
    rows.append("</table>")
    return rows


def _residual_table(diag) -> list[str]:
    u = diag.unexplained
    if u is None:
        return []
    esc = html.escape
    rows = ["<h3>What the extended model leaves</h3><p class='note'>Against the sensor model alone: the extended "
            f"model simulated again with {u.replicates} realisations of accelerometer noise (going round the loop "
            "where a is fed back) and tiny perturbations. θ: share of samples off by 2 counts or more (rounding "
            "makes at most 1); a: RMS of the residual below 25 Hz.</p><table><tr><th>run</th>"
            "<th>θ off ≥ 2 counts</th><th>sensor model alone</th><th>θ RMS (counts)</th>"
            "<th>a below 25 Hz (counts)</th>"
            "<th>sensor model alone</th><th>structure</th></tr>"]
    for r in u.runs:
        what = ", ".join(n for n, c in (("θ", r.theta), ("a", r.accel)) if c.structured) or "none"
        rows.append(f"<tr><td title='{esc(r.run)}'>{esc(short_name(r.run))}</td>"
                    f"<td>{100 * r.theta.statistic:.1f} %</td>"
                    f"<td>{100 * r.theta.null:.1f} %</td><td>{r.theta.rms:.2f}</td><td>{r.accel.statistic:.2f}</td>"
                    f"<td>{r.accel.null:.2f}</td><td class='{'warn' if what != 'none' else ''}'>{what}</td></tr>")
    rows.append("</table>")
    return rows


def _runs_table(diag) -> list[str]:
    esc, pct = html.escape, format_pct
    rows = ["<h3>Runs</h3><table><tr><th>run</th><th>role</th><th>controller</th>"
            "<th>θ fit nominal</th><th>θ fit extended</th><th>θ RMS gain</th><th>overshoot rig / nominal / "
            f"extended (target ±{OVERSHOOT_POINTS:g} points)</th></tr>"]
    for r in diag.runs:
        m = r.metrics
        ov = ""
        if m is not None:
            ov = " / ".join(f"{m[k].overshoot_pct:.1f} %" for k in ("rig", "nominal", "extended"))
            if abs(m["extended"].overshoot_pct - m["rig"].overshoot_pct) > OVERSHOOT_POINTS:
                ov += " <span class='warn'>missed</span>"
        rows.append(f"<tr><td title='{esc(r.file)}'>{esc(short_name(r.file))}</td><td>{r.role}</td>"
                    f"<td>{esc(r.controller)}</td><td>{pct(r.fit_nominal.get('theta'))}</td>"
                    f"<td>{pct(r.fit_extended.get('theta'))}</td><td>{r.gain_pct:.1f} %</td><td>{ov}</td></tr>")
    rows.append("</table>")
    return rows


def _run_section(run, slug: str, folder: Path, extended: bool, tx: Transaction) -> list[str]:
    """One run's signatures and figures; writes its PNGs into ``folder`` through ``tx``."""
    esc = html.escape
    out = [f"<h3 title='{esc(run.file)}'>{esc(run.file)}</h3>"]
    sig_b = run.residuals_before.signatures() if run.residuals_before else []
    sig_a = run.residuals_after.signatures() if run.residuals_after else []
    out.append("<p>Nominal model: " + esc("; ".join(sig_b) or "no notable signature") + "</p>")
    if extended:
        out.append("<p>Extended model: " + esc("; ".join(sig_a) or "no notable signature") + "</p>")
    for kind, fig in zip(FIGURES, (diagnosis_run_figure(run, OVERSHOOT_POINTS), diagnosis_resid_figure(run))):
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
    body = (_answer(diag) + _result_table(diag) + _candidates_table(diag) + _alternatives_table(diag)
            + _residual_table(diag) + _runs_table(diag) + ["<h3>Each run</h3>"])
    for r, slug in zip(diag.runs, _slugs([r.file for r in diag.runs])):
        body += _run_section(r, slug, folder, bool(diag.accepted), transaction)
    page = html_page("Model diagnosis", body)
    out = folder / PAGE
    transaction.write(out, page, "the report")
    return out


__all__ = ["report_files", "write_report"]
