"""The design's report: ``report.html`` with its figures embedded, and each figure as a PNG
beside it (``station tune --report DIR``): the step responses of the thesis's compensator
and the tuned one on the design model (the hub and the tip), the loop's Bode plot with
margins, the spread over the model set, the hub-tip trade-off, and the tables behind them.
Settling times are named by their band (:func:`station.analysis.metrics.settling_label`).
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

from station.analysis.metrics import STEP_INFO_BAND_PCT, THESIS_BAND_PCT, settling_label
from station.design.figures import bode_figure, robust_figure, steps_figure, tradeoff_figure
from station.design.space import thesis_compensator
from station.outputs import Transaction
from station.design.hold import held_summary
from station.htmlpage import html_page



def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return buf.getvalue()


def _fmt(x, unit: str = "", digits: int = 3) -> str:
    if x is None:
        return "not settled"
    return f"{x:.{digits}f}{unit}"


def _tables(result) -> list[str]:
    esc = html.escape
    d = result.design_json()
    s2, s1 = settling_label(STEP_INFO_BAND_PCT), settling_label(THESIS_BAND_PCT)
    tip = ("no bound on the tip" if result.tip_rms is None else
           f"tip residual RMS (accelerometer, from 0.6 s after the step) ≤ {result.tip_rms:g}× the thesis's "
           f"compensator's on the same model")
    rows = [f"<h1>Compensator design: {esc(result.space.structure)} on {esc(result.nominal.name)}</h1>",
            f"<p>{esc(d['objective'])}; requirements: overshoot ≤ {result.requirements.overshoot_pct:g} %, "
            f"gain margin ≥ {result.requirements.gain_margin_db:g} dB, phase margin ≥ "
            f"{result.requirements.phase_margin_deg:g}°, {esc(tip)}, no limit cycle, settled within the run. "
            f"{'All met on every model.' if d['feasible'] else 'NOT met on every model: see the table.'}</p>",
            f"<p>Gth: the structure's gain{'' if result.space.filter == 'none' else ' and a ' + result.space.filter}"
            f"; shaper: {esc(result.space.shaper)}. The compensator file records its design model: "
            + ("none" if result.file.design is None else
               f"<code>model = {esc(result.file.design.model)}</code>, <code>model_sha256 = "
               f"{esc(result.file.design.model_sha256)}</code>") + ".</p>",
            *[f"<p><b>Warning:</b> {esc(w)}.</p>" for w in d["warnings"]],
            *([f"<p>Friction: {esc(note)}.</p>"] if (note := held_summary(result.figures,
                                                                       result.model_requirements())["note"])
              else []),
            "<h2>Parameters</h2><table><tr><th>parameter</th><th>value</th><th>unit</th></tr>"]
    for k, v in d["parameters"].items():
        rows.append(f"<tr><td>{esc(k)}</td><td>{v['value']:.6g}</td><td>{esc(v['unit'])}</td></tr>")
    rows.append("</table>")
    if result.verification is not None:
        v = result.verification
        rows.append(f"<p>Run as <code>station step</code> on the simulated rig: {esc(v.reason)}; max |Δθ| "
                    f"{v.max_abs_dtheta:g}, |Δa| {v.max_abs_da:g}, |Δv| {v.max_abs_dv:g} against the simulation "
                    f"({'identical' if v.matches else 'DIFFERENT'}).</p>")
    rows.append(f"<h2>Models</h2><p>Hub: θ; tip: the tip position (hub angle + tip deflection / L, encoder "
                f"counts) and the accelerometer's RMS from 0.6 s after the step to the run's end (counts). "
                f"{esc(s1)} is the thesis's definition (from t = 0 of the run).</p>"
                f"<table><tr><th>model</th><th>effects</th><th>compensator</th><th>overshoot</th>"
                f"<th>hub {esc(s2)}</th><th>hub {esc(s1)}</th><th>tip {esc(s2)}</th><th>tip residual RMS</th>"
                f"<th>tip residual peak</th><th>met</th></tr>")
    for m, lab, f, b, ok in zip(result.robust.models, result.robust.labels, result.figures, result.baseline,
                                result.met()):
        eff = ", ".join(f"{k} = {v:.4g}" for k, v in m.effect_dict().items()) or "none"
        for who, g, met in (("tuned", f, "yes" if ok else "NO"), ("thesis", b, "")):
            head = f"<td rowspan='2'>{esc(lab)}</td><td rowspan='2'>{esc(eff)}</td>" if who == "tuned" else ""
            rows.append(f"<tr>{head}<td>{who}</td><td>{g.overshoot_pct:.1f} %</td>"
                        f"<td>{_fmt(g.settling_2pct_s, ' s')}</td><td>{_fmt(g.settling_thesis_s, ' s')}</td>"
                        f"<td>{_fmt(g.tip_settling_2pct_s, ' s')}</td><td>{g.tip_residual_rms:.2f}</td>"
                        f"<td>{g.tip_residual_peak:.0f}</td><td>{met}</td></tr>")
    rows.append("</table>")
    if result.tradeoff is not None:
        rows += tradeoff_table(result.tradeoff, result.space)
    return rows


def tradeoff_table(tradeoff, space) -> list[str]:
    """The trade-off front as an HTML table, the chosen design marked (its row, on the front or not).

    Parameters
    ----------
    tradeoff : station.design.result.TradeOff
    space : station.design.space.DesignSpace

    Returns
    -------
    list of str
        HTML fragments, in order: a heading with a paragraph, the table's opening and header
        row, one row per front design (and the chosen one when off the front), the table's close.
    """
    esc = html.escape
    s2 = esc(settling_label(STEP_INFO_BAND_PCT))
    rows = [f"<h2>Hub against tip</h2><p>{len(tradeoff.points)} designs judged on every model; the "
            f"{len(tradeoff.front)} that no other beats on both the worst hub {s2} and the worst tip residual RMS "
            f"(each relative to the thesis's compensator on the same model), among those meeting overshoot, "
            f"margins and rest on every model. ★: the chosen design.</p>",
            f"<table><tr><th></th><th>hub {s2} / thesis's</th><th>tip RMS / thesis's</th><th>worst hub {s2}</th>"
            f"<th>worst tip RMS</th><th>worst overshoot</th><th>all met</th><th>parameters</th></tr>"]
    order = list(tradeoff.front) + ([] if tradeoff.chosen in tradeoff.front else [tradeoff.chosen])
    for i in order:
        p = tradeoff.points[i]
        params = ", ".join(f"{k} {v:.4g}" for k, v in tradeoff.values[i].items())
        rows.append(f"<tr><td>{'★' if i == tradeoff.chosen else ''}</td><td>{p.hub_ratio:.2f}</td>"
                    f"<td>{p.tip_ratio:.2f}</td><td>{p.hub_s:.3f} s</td><td>{p.tip_rms:.2f}</td>"
                    f"<td>{p.overshoot_pct:.1f} %</td><td>{'yes' if p.met else 'no'}</td><td>{esc(params)}</td></tr>")
    rows.append("</table>")
    return rows


REPORT_FILES = ("report.html", "steps.png", "bode.png", "robust.png", "tradeoff.png", "verify-step.tsv")
"""What ``station tune --report DIR`` writes in DIR (the command checks them first)."""


def write_report(result, folder: str | Path, transaction: Transaction | None = None,
                 verify_log: bytes | None = None) -> Path:
    """Write ``report.html`` (figures embedded as base64 PNG) and ``steps.png``, ``bode.png``,
    ``robust.png``, ``tradeoff.png`` beside it (and the verification run's log,
    ``verify-step.tsv``), whole or not at all (:mod:`station.outputs`).

    Parameters
    ----------
    result : station.design.result.TuneResult
    folder : str or Path
        Created if needed.
    transaction : station.outputs.Transaction, optional
        Write through it (renamed into place with the command's other files); default: a
        transaction of its own.
    verify_log : bytes, optional
        The verification run's log, written as ``verify-step.tsv``.

    Returns
    -------
    Path
        The HTML file.

    Raises
    ------
    StationError
        The folder or a file cannot be written.
    """
    if transaction is None:
        with Transaction() as tx:
            return write_report(result, folder, tx, verify_log)
    folder = Path(folder)
    tuned = result.file.compensator()
    thesis = thesis_compensator(result.space.structure, result.space.limit)
    names = (f"thesis {result.space.structure}", f"tuned {result.space.structure}")
    figures = (
        ("steps", "Step responses on the design model", steps_figure(result.nominal, tuned, thesis, result.amplitude,
                                                                      names)),
        ("bode", "Loop Bode plot with margins", bode_figure(result.nominal, tuned, thesis, result.margins, names)),
        ("robust", "Spread over the model set", robust_figure(result.robust.models, tuned, thesis, result.amplitude,
                                                               result.figures, result.baseline,
                                                               result.requirements.overshoot_pct, names)),
    )
    if result.tradeoff is not None:
        figures += (("tradeoff", "Hub against tip: the trade-off", tradeoff_figure(result.tradeoff, result.tip_rms)),)
    body = _tables(result)
    for name, title, fig in figures:
        png = _png(fig)
        transaction.write(folder / f"{name}.png", png, "the report's figure")
        body.append(f"<h2>{html.escape(title)}</h2><img alt='{name}.png' "
                    f"src='data:image/png;base64,{base64.b64encode(png).decode()}'>")
    if verify_log is not None:
        transaction.write(folder / "verify-step.tsv", verify_log, "the verification run's log")
        body.append("<p>The verification run (<code>station step</code> on the simulated rig serving the model): "
                    "<a href='verify-step.tsv'>verify-step.tsv</a>.</p>")
    page = html_page("Compensator design", body)
    out = folder / "report.html"
    transaction.write(out, page, "the report")
    return out
