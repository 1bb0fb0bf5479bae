"""The design's report: ``report.html`` with its figures embedded, and each figure as a PNG
beside it (``station tune --report DIR``): the step responses of the thesis's compensator
and the tuned one on the design model, the loop's Bode plot with margins, the spread over
the model set, and the tables behind them.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path

from station.design.figures import bode_figure, robust_figure, steps_figure
from station.design.space import thesis_compensator
from station.outputs import Transaction
from station.design.hold import held_summary

_STYLE = ("body{font-family:sans-serif;max-width:1100px;margin:auto}table{border-collapse:collapse}"
          "td,th{border:1px solid #ccc;padding:2px 6px;font-size:90%}img{max-width:100%}")


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
    rows = [f"<h1>Compensator design: {esc(result.space.structure)} on {esc(result.nominal.name)}</h1>",
            f"<p>{esc(d['objective'])}; requirements: overshoot ≤ {result.requirements.overshoot_pct:g} %, "
            f"gain margin ≥ {result.requirements.gain_margin_db:g} dB, phase margin ≥ "
            f"{result.requirements.phase_margin_deg:g}°, no limit cycle, settled within the run. "
            f"{'All met on every model.' if d['feasible'] else 'NOT met on every model: see the table.'}</p>",
            *[f"<p><b>Warning:</b> {esc(w)}.</p>" for w in d["warnings"]],
            *([f"<p>Friction: {esc(note)}.</p>"] if (note := held_summary(result.figures,
                                                                       result.requirements)["note"]) else []),
            "<h2>Parameters</h2><table><tr><th>parameter</th><th>value</th><th>unit</th></tr>"]
    for k, v in d["parameters"].items():
        rows.append(f"<tr><td>{esc(k)}</td><td>{v['value']:.6g}</td><td>{esc(v['unit'])}</td></tr>")
    rows.append("</table>")
    if result.verification is not None:
        v = result.verification
        rows.append(f"<p>Run as <code>station step</code> on the simulated rig: {esc(v.reason)}; max |Δθ| "
                    f"{v.max_abs_dtheta:g}, |Δa| {v.max_abs_da:g}, |Δv| {v.max_abs_dv:g} against the simulation "
                    f"({'identical' if v.matches else 'DIFFERENT'}).</p>")
    rows.append("<h2>Models</h2><table><tr><th>model</th><th>effects</th><th>tuned overshoot</th>"
                "<th>tuned 2 % settling</th><th>thesis overshoot</th><th>thesis 2 % settling</th><th>met</th></tr>")
    for m, lab, f, b, ok in zip(result.robust.models, result.robust.labels, result.figures, result.baseline,
                                result.met()):
        eff = ", ".join(f"{k} = {v:.4g}" for k, v in m.effect_dict().items()) or "none"
        rows.append(f"<tr><td>{esc(lab)}</td><td>{esc(eff)}</td><td>{f.overshoot_pct:.1f} %</td>"
                    f"<td>{_fmt(f.settling_2pct_s, ' s')}</td><td>{b.overshoot_pct:.1f} %</td>"
                    f"<td>{_fmt(b.settling_2pct_s, ' s')}</td><td>{'yes' if ok else 'NO'}</td></tr>")
    rows.append("</table>")
    return rows


REPORT_FILES = ("report.html", "steps.png", "bode.png", "robust.png", "verify-step.tsv")
"""What ``station tune --report DIR`` writes in DIR (the command checks them first)."""


def write_report(result, folder: str | Path, transaction: Transaction | None = None,
                 verify_log: bytes | None = None) -> Path:
    """Write ``report.html`` (figures embedded as base64 PNG) and ``steps.png``, ``bode.png``,
    ``robust.png`` beside it (and the verification run's log, ``verify-step.tsv``), whole or
    not at all (:mod:`station.outputs`).

    Parameters
    ----------
    result : station.design.tuning.TuneResult
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
    page = ("<!doctype html><html><head><meta charset='utf-8'><title>Compensator design</title><style>"
            + _STYLE + "</style></head><body>" + "\n".join(body) + "</body></html>")
    out = folder / "report.html"
    transaction.write(out, page, "the report")
    return out
