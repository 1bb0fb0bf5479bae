"""What a sessions diagnosis says (:mod:`station.diagnosis.sessions.diagnose`): the text ``station
survey --diagnose`` prints, the drift figure and ``report.html`` (``--report DIR``).

The page leads with the answer in words (which effects drift, their value in each session,
by how much per-session values pay on held-out runs; the shared ones), then the evidence:
the sessions with their runs and held-out gains, the decisions with their numbers, what
was set aside or cut, and the figure: per effect of the structure its value in each
session, with the refits that left one run out (``drift.png``, also embedded in the page).
The files' names are fixed (:data:`REPORT_FILES`), so the command checks them before it starts.
"""

from __future__ import annotations

import base64
import html
import io
import math
from collections.abc import Mapping
from pathlib import Path

from station.diagnosis.sessions.drift import Decision
from station.diagnosis.sessions.layout import as_held
from station.diagnosis.answer.prose import plain_name
from station.diagnosis.units import format_quantity
from station.diagnosis.search.selection import MIN_NOISE_GAIN, MIN_RELATIVE_GAIN
from station.outputs import Transaction
from station.plant.effects import EFFECTS
from station.plots import new_figure
from station.htmlpage import html_page

PAGE = "report.html"
FIGURE = "drift.png"
REPORT_FILES = (PAGE, FIGURE)
"""The files ``--report DIR`` writes, in DIR."""


def _value(name: str, x: float) -> str:
    return format_quantity(x, EFFECTS[name].unit)


def decision_words(result, d: Decision) -> str:
    """One sentence on whether an effect drifts, with its values and numbers, e.g.
    "coulomb_friction drifts: 2.09 DAC counts in 2009, 14.6 DAC counts in rig-session; per-session
    values lower the held-out θ + a cost by 50.5 % (θ RMS 29.9 %) against one shared value
    (9.81 DAC counts); ...".

    Parameters
    ----------
    result : SessionsDiagnosis
    d : station.diagnosis.sessions.drift.Decision

    Returns
    -------
    str
        The sentence, without a final period: "NAME drifts: ..." or "NAME is shared: ...".
    """
    # a shared effect's value is said once, the final model's (the test's shared fit differs in its last digits)
    pay = d.pay(_shared(result, d.name, d.shared_value) if d.drifts else None)
    luck = f", tiny perturbations of the shared model by {d.luck_gain_pct:.1f} % (luck alone)"
    ranges = ", ".join(f"{_range(s, d.name, lo, hi)} in {s.name}" for (lo, hi), s in zip(d.ranges, result.sessions))
    if d.drifts:
        values = ", ".join(f"{_value(d.name, s.effects[d.name])} in {s.name}" for s in result.sessions)
        return f"{d.name} drifts: {values}; {pay}{luck}; refits leaving one run out: {ranges}"
    why = ""
    if d.cost_gain_pct > 0:
        why = (f"; the sessions' refits leaving one run out overlap ({ranges})" if not d.apart else
               f"; a drift must pay {100 * MIN_RELATIVE_GAIN:.0f} % and {MIN_NOISE_GAIN:g} noise variances per "
               "sample beyond the lower of the shared model and luck")
    return f"{d.name} is shared: {_shared(result, d.name, result.shared[d.name])} in every session; {pay}{luck}{why}"


def _range(session, name: str, lo: float, hi: float) -> str:
    """A session's refits of an effect, lo..hi, with the sign its sensors give a size searched
    beside them (:class:`station.diagnosis.sessions.layout.PerSession`)."""
    lo, hi = sorted((as_held(name, lo, session.faults), as_held(name, hi, session.faults)))
    return f"{_value(name, lo)}..{_value(name, hi)}"


def _shared(result, name: str, value: float) -> str:
    """A shared value with its unit, as the sessions' models hold it (:meth:`SessionsDiagnosis.held`)."""
    text = _value(name, result.held(name, value))
    return text + " in size (its sign each session's sensors')" if result.sign_differs(name) else text


def answer_lines(result) -> list[str]:
    """The answer in a few lines: the structure and its gain, what drifts and what is shared.

    Parameters
    ----------
    result : SessionsDiagnosis

    Returns
    -------
    list of str
        The lines, without newlines: the sessions and runs, the structure, then (when an
        effect was accepted) what drifts and what is shared and one indented line per decision.
    """
    n_runs = sum(len(s.runs) for s in result.sessions)
    lines = [f"{s.name}: {line}" for s in result.sessions for line in s.said]  # the data's answers first
    lines.append(f"{len(result.sessions)} session(s), {n_runs} runs ({result.samples[0]} of {result.samples[1]} "
                 f"samples used); one structure judged by {result.validation}")
    if not result.accepted:
        lines.append("structure: none (no effect lowers the held-out cost beyond what noise reaches); nothing drifts")
        return lines
    lines.append(f"structure: {', '.join(plain_name(n) for n in result.accepted)}; θ RMS gain on runs not used "
                 f"to fit ({result.validation}) {result.gain_pct:.1f} % over the nominal model")
    if len(result.sessions) < 2:
        lines.append("one session: nothing can drift")
    lines.append("drifting: " + (", ".join(result.drifting) or "none"))
    lines.append("shared: " + (", ".join(f"{n} = {_shared(result, n, v)}" for n, v in result.shared.items())
                               or "none"))
    lines += [f"  {decision_words(result, d)}" for d in result.decisions]
    return lines


def format_sessions(result, models: Mapping[str, str] | None = None) -> str:
    """What ``station survey --diagnose`` prints: the answer, a line per session, the notes.

    Parameters
    ----------
    result : SessionsDiagnosis
    models : mapping of str to str, optional
        Session name -> its saved model file.

    Returns
    -------
    str
        :func:`answer_lines`, one line per session, the notes and the simulations' count,
        joined by newlines (no final newline).
    """
    models = models or {}
    lines = answer_lines(result)
    for s in result.sessions:
        eff = ", ".join(f"{n} = {_value(n, v)}" for n, v in s.effects.items()) or "no effects"
        lines.append(f"session {s.name}: {len(s.runs)} runs, held-out θ RMS {s.fit_nominal.rms_theta:.2f} -> "
                     f"{s.fit_final.rms_theta:.2f} counts (gain {s.gain_pct:.1f} %); {eff}"
                     + (f"; model {models[s.name]}" if s.name in models else ""))
    lines += [f"note: {n}" for n in result.notes]
    lines.append(f"{result.simulations} simulations in {result.elapsed_s:.1f} s")
    return "\n".join(lines)


def drift_figure(result):
    """Per effect of the structure, its value in each session: the final value (drifting:
    one per session; shared: one line), and with every effect fitted per session (before
    the decision) on all runs and leaving each run out.

    Parameters
    ----------
    result : SessionsDiagnosis

    Returns
    -------
    matplotlib.figure.Figure
    """
    names = list(result.accepted)
    fig = new_figure(8.0, 2.6 * max(1, len(names)) + 0.6)
    x = list(range(len(result.sessions)))
    labels = [s.name for s in result.sessions]
    if not names:
        ax = fig.add_subplot(1, 1, 1)
        ax.text(0.5, 0.5, "no effect accepted: nothing can drift", ha="center", va="center", transform=ax.transAxes)
        ax.set_axis_off()
        return fig
    for k, n in enumerate(names):
        ax = fig.add_subplot(len(names), 1, k + 1)
        for j, s in enumerate(result.sessions):
            ys = s.refits.get(n, [])
            ax.plot([j] * len(ys), ys, "o", ms=3, color="0.6", label="per session, leaving one run out" if j == 0 else None)
        ax.plot(x, [s.separate[n] for s in result.sessions], "s", mfc="none", color="tab:blue",
                label="each effect fitted per session")
        if n in result.drifting:
            ax.plot(x, [s.effects[n] for s in result.sessions], "o-", ms=8, color="tab:red", label="drifts: per session")
            title = f"{n}: drifts"
        else:
            ax.axhline(result.shared[n], color="tab:green", lw=2, label="shared value")
            title = f"{n}: shared" if len(result.sessions) > 1 else f"{n} (one session: cannot drift)"
        neutral = EFFECTS[n].neutral
        if math.isfinite(neutral):  # the nominal model's value keeps the scale honest
            ax.axhline(neutral, color="0.3", ls="--", lw=1, label="nominal model (no effect)")
        ax.set_title(title, fontsize=10)
        ax.set_ylabel("fitted / nominal" if n.startswith("param:") else EFFECTS[n].unit)
        ax.set_xticks(x)
        ax.set_xticklabels(labels)
        ax.set_xlim(-0.5, len(x) - 0.5)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle(f"{result.nominal_model.name}: effects per session", fontsize=11)
    fig.tight_layout()
    return fig




def write_report(result, folder: str | Path, transaction: Transaction | None = None,
                 models: Mapping[str, str] | None = None) -> Path:
    """Write ``report.html`` (the figure embedded) and ``drift.png`` beside it, whole or not at all.

    Parameters
    ----------
    result : SessionsDiagnosis
    folder : str or Path
        Created if needed.
    transaction : station.outputs.Transaction, optional
        Write through it (renamed into place with the command's other files when it commits).
    models : mapping of str to str, optional
        Session name -> its saved model file.

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
            return write_report(result, folder, tx, models)
    folder, esc, models = Path(folder), html.escape, models or {}
    buf = io.BytesIO()
    drift_figure(result).savefig(buf, format="png", dpi=100)
    png = buf.getvalue()
    transaction.write(folder / FIGURE, png, "the drift figure")
    body = [f"<h1>Sessions and drift: {esc(result.nominal_model.name)}</h1><h2>Answer</h2><ul>"]
    body += [f"<li>{esc(line.strip())}</li>" for line in answer_lines(result)] + ["</ul>"]
    body.append(f"<img alt='{FIGURE}' src='data:image/png;base64,{base64.b64encode(png).decode()}'>")
    body.append("<h2>Sessions</h2><table><tr><th>session</th><th>runs</th><th>effects</th>"
                "<th>held-out θ RMS nominal → final (counts)</th><th>gain</th><th>model file</th></tr>")
    for s in result.sessions:
        eff = ", ".join(f"{n} = {_value(n, v)}" for n, v in s.effects.items()) or "none"
        runs = "<br>".join(esc(Path(r).name) for r in s.runs)
        body.append(f"<tr><td>{esc(s.name)}</td><td>{runs}</td><td>{esc(eff)}</td>"
                    f"<td>{s.fit_nominal.rms_theta:.2f} → {s.fit_final.rms_theta:.2f}</td><td>{s.gain_pct:.1f} %</td>"
                    f"<td>{esc(models.get(s.name, '-'))}</td></tr>")
    body.append("</table>")
    if result.decisions:
        body.append("<h2>Decisions</h2><p class='note'>For each effect of the structure: the structure with that "
                    "effect shared by all sessions (the others per session), fitted and judged leaving one run out, "
                    "against the structure with every effect per session.</p><table><tr><th>effect</th>"
                    "<th>drifts</th><th>held-out cost gain of per-session values</th><th>θ RMS gain</th>"
                    "<th>luck alone</th><th>shared value</th><th>refits leaving one run out</th></tr>")
        for d in result.decisions:
            body.append(f"<tr><td>{esc(plain_name(d.name))}</td><td>{'yes' if d.drifts else 'no'}</td>"
                        f"<td>{d.cost_gain_pct:.1f} %</td><td>{d.theta_gain_pct:.1f} %</td>"
                        f"<td>{d.luck_gain_pct:.1f} %</td><td>{esc(_shared(result, d.name, d.shared_value))}</td>"
                        f"<td>{esc(', '.join(f'{_range(s, d.name, lo, hi)} ({s.name})' for (lo, hi), s in zip(d.ranges, result.sessions)))}"
                        f"{'' if d.apart else ' (overlap)'}</td></tr>")
        body.append("</table>")
    if result.notes:
        body.append("<h2>Notes</h2>" + "".join(f"<p class='note'>{esc(n)}</p>" for n in result.notes))
    body.append(f"<p class='note'>{result.simulations} simulations in {result.elapsed_s:.1f} s</p>")
    page = html_page("Sessions and drift", body)
    out = folder / PAGE
    transaction.write(out, page, "the report")
    return out
