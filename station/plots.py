"""Every figure the station draws, in one module.

Run logs: one run (``<log stem>.png`` after ``station step``) or several overlaid
(``station plot``): θ and u (encoder counts), v and v_applied (DAC counts), a
(accelerometer counts). Model against measurement: ``station compare`` (:func:`plot_comparison`),
``station bode`` (:func:`plot_bode`), ``station diagnose`` (:func:`diagnosis_run_figure`,
:func:`diagnosis_resid_figure`), ``station identify`` (:func:`identify_design_figure`).

matplotlib :class:`~matplotlib.figure.Figure` objects with the Agg canvas only - no
pyplot, no global backend - so library users' own matplotlib set-up is never touched.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from station.errors import StationError
from station.logged.reference import classify_reference
from station.outputs import Transaction
from station.rig import DT
from station.runlog import read_log


def new_figure(width: float = 9.0, height: float = 8.0):
    """A Figure with its Agg canvas attached (no pyplot state).

    Parameters
    ----------
    width, height : float
        Size, inches.
    """
    # lazy: start-up time (matplotlib)
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path: str | Path, dpi: int = 100, transaction=None) -> Path:
    """Write ``fig`` as PNG to ``path``, whole or not at all (:mod:`station.outputs`).

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        The PNG file (written as PNG whatever its suffix).
    dpi : int, default 100
        Resolution, dots per inch.
    transaction : station.outputs.Transaction, optional
        Write through it (renamed into place when it commits, with the command's other
        files); default: at once.

    Raises
    ------
    StationError
        The file cannot be written (names it); an existing file is unchanged then.
    """
    if transaction is None:
        with Transaction() as tx:
            return save_figure(fig, path, dpi, tx)
    with transaction.open(path, "the figure") as fh:
        fig.savefig(fh, format="png", dpi=dpi)
    return Path(path)


def source_label(log) -> str:
    """Where a log comes from: "rig" (the rig's lab software), "simulated" (our log of the
    simulated rig, sim:// or sim-device) or "station" (our log of a real device).

    Parameters
    ----------
    log : RunLog
        A read log (its format, header port, device name and plant).
    """
    if log.format != "station":
        return "rig"
    meta = log.meta
    port = str(meta.get("port", ""))
    device = meta.get("device") or {}
    name = str(device.get("name", "")) if isinstance(device, dict) else ""
    if meta.get("plant") or port.lower().startswith("sim://") or name.startswith(("SFLR-SIM", "SIMRIG")):
        return "simulated"
    return "station"


def outcome_text(log) -> str:
    """The end record in a few words: "completed", "stopped: timeout", or "no end record" (SIGKILL or a rig log).

    Parameters
    ----------
    log : RunLog
        A read log.
    """
    o = log.outcome
    if o is None:
        return "no end record (killed?)" if log.format == "station" else ""
    return "completed" if o.get("reason") == "completed" else f"stopped: {o.get('reason')}"


ALIGN = ("time", "step")
"""How :func:`plot_runs` lines logs up on t: as logged, or each log's step at t = 0."""


def step_offset(log) -> float:
    """The t of a log's step (:func:`station.logged.reference.classify_reference`), s; 0.0
    when its u is not a step (nothing to line up on).

    Parameters
    ----------
    log : station.runlog.RunLog

    Returns
    -------
    float
    """
    ref = classify_reference(log.data["u"])
    return float(log.data["t"][ref.step_tick]) if ref.is_step else 0.0


def plot_runs(logs: Sequence, title: str | None = None, titles: Sequence[str] | None = None,
              align: str = "time"):
    """Figure of one or several run logs overlaid.

    Parameters
    ----------
    logs : sequence of station.runlog.RunLog
        Read by :func:`station.runlog.read_log` (ours or the rig's).
    title : str, optional
        Figure title (default: the file names with their source and outcome).
    titles : sequence of str, optional
        Legend label per log (default: file name and source).
    align : {"time", "step"}
        "time": t as logged; "step": each log's t shifted so its step is at t = 0
        (:func:`step_offset`; the rig's logs step at 0.1 s, ``station step`` at 0.02 s).

    Returns
    -------
    matplotlib.figure.Figure
        Three panels sharing t (s): θ with u dashed; v with v_applied dotted; a.
        Columns a log lacks (all NaN) are left out.

    Raises
    ------
    StationError
        No log, or an ``align`` not in :data:`ALIGN`.
    """
    if not logs:
        raise StationError("nothing to plot: no run log given")
    if align not in ALIGN:
        raise StationError(f"align {align!r}: expected one of {', '.join(ALIGN)}")
    fig = new_figure()
    ax_theta, ax_v, ax_a = fig.subplots(3, 1, sharex=True)
    for i, log in enumerate(logs):
        d = log.data
        label = titles[i] if titles is not None else f"{log.path.name} ({source_label(log)})"
        color = f"C{i % 10}"
        t = d["t"] - (step_offset(log) if align == "step" else 0.0)
        ax_theta.plot(t, d["theta"], color=color, lw=1.0, label=f"θ {label}")
        if np.isfinite(d["u"]).any():
            ax_theta.plot(t, d["u"], color=color, lw=0.8, ls="--", label=f"u {label}" if len(logs) == 1 else None)
        ax_v.plot(t, d["v"], color=color, lw=0.8, label=f"v {label}" if len(logs) == 1 else label)
        if np.isfinite(d["v_applied"]).any():
            ax_v.plot(t, d["v_applied"], color="k" if len(logs) == 1 else color, lw=0.8, ls=":",
                      label="v_applied (the device's output)" if len(logs) == 1 else None)
        if np.isfinite(d["a"]).any():
            ax_a.plot(t, d["a"], color=color, lw=0.7, label=label)
    ax_theta.set_ylabel("θ, u (encoder counts)")
    ax_v.set_ylabel("v (DAC counts)")
    ax_a.set_ylabel("a (accelerometer counts)")
    ax_a.set_xlabel("t (s)")
    for ax in (ax_theta, ax_v, ax_a):
        ax.grid(True, lw=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(loc="best", fontsize=7)
    if len(logs) > 1:  # one legend is enough; the others would hide the curves
        for ax in (ax_v, ax_a):
            if ax.get_legend() is not None:
                ax.get_legend().remove()
    if title is None:
        title = (run_title(logs[0]) if len(logs) == 1 else
                 f"{len(logs)} run logs overlaid (" + ", ".join(sorted({source_label(g) for g in logs})) + ")")
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    return fig


def run_title(log, metrics_text: str = "") -> str:
    """Title of a run's figure: file, source, outcome, and the step metrics' text when given.

    Parameters
    ----------
    log : RunLog
        A read log.
    metrics_text : str, optional
        The step metrics in a few words.
    """
    parts = [f"{log.path.name} ({source_label(log)})", outcome_text(log)]
    parts = [p for p in parts if p]
    if metrics_text:
        parts.append(metrics_text)
    return " - ".join(parts)


def plot_log_files(paths: Sequence[str | Path], out: str | Path, transaction=None, align: str = "time") -> Path:
    """Read ``paths`` and write their overlay to ``out`` (``station plot``).

    Parameters
    ----------
    paths : sequence of str or Path
        Run logs, any format :func:`station.runlog.read_log` reads.
    out : str or Path
        The PNG to write.
    transaction : station.outputs.Transaction, optional
        Write through it (see :func:`save_figure`).
    align : {"time", "step"}
        As :func:`plot_runs`.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    StationError
        An unreadable log (the reader's one-line error) or an unwritable ``out``.
    """
    logs = [read_log(p).require_rows("draw") for p in paths]
    return save_figure(plot_runs(logs, align=align), out, transaction=transaction)


# --- model comparisons: station compare, station bode, station diagnose --------------------

def plot_comparison(c, path: Path, transaction=None):
    """Write θ, a and v of the log and the model over time as a PNG.

    Parameters
    ----------
    c : station.compare.RunComparison
    path : Path
        PNG file.
    transaction : station.outputs.Transaction, optional
        Write through it (see :func:`save_figure`).

    Returns
    -------
    matplotlib.figure.Figure
        θ (with u; open loop u in DAC counts on its own right-hand axis), a, v; the log
        labelled by its source, the model beside it (none for a hub-held beam test).
    """
    t = c.data["t"]
    fig = new_figure(8, 8)
    ax = fig.subplots(3, 1, sharex=True)
    if c.step is None:  # open loop: u is a command in DAC counts, not an angle: its own axis
        ax_u = ax[0].twinx()
        ax_u.plot(t, c.data["u"], "k:", lw=0.8, label="u")
        ax_u.set_ylabel("u (DAC counts)")
        ax_u.legend(loc="lower right", fontsize=8)
    else:
        ax[0].plot(t, c.data["u"], "k:", lw=0.8, label="u")
    for row, key, label in ((0, "theta", "θ (encoder counts)"), (1, "a", "a (counts)"), (2, "v", "v (DAC counts)")):
        logged = np.any(np.isfinite(c.data[key]))
        ax[row].plot(t, c.data[key], lw=0.9, label=c.source if logged else f"{c.source}: no {key} column")
        if c.prediction is not None:  # None: a hub-held beam test, which the model cannot represent
            ax[row].plot(c.prediction["t"], c.prediction[key], lw=0.9, label="model")
        ax[row].set_ylabel(label)
        ax[row].legend(loc="best", fontsize=8)
    ax[2].set_xlabel("t (s)")
    fits = ", ".join(f"{k} {v:.1f} %" for k, v in c.fit_pct.items() if v is not None)
    fits = f"NRMSE fit {fits}" if c.prediction is not None else "hub-held beam test, no model fit"
    fig.suptitle(f"{Path(c.file).name} ({c.source})\n{c.controller}: {fits}", fontsize=9)
    fig.tight_layout()
    save_figure(fig, path, transaction=transaction)
    return fig


def plot_bode(cmp, path: Path, title: str, transaction=None) -> None:
    """Write the Bode magnitude/phase of θ/v, a/v (measured and model) and the coherence.

    Parameters
    ----------
    cmp : station.analysis.frequency.BodeComparison
    path : Path
        PNG file to write.
    title : str
        Figure title.
    transaction : station.outputs.Transaction, optional
        Write through it (see :func:`save_figure`).
    """
    f = cmp.theta.f
    band = (f >= 0.5) & (f <= 40.0)
    fig = new_figure(8, 10)
    ax = fig.subplots(4, 1, sharex=True)
    for row, (est, model, label) in enumerate(((cmp.theta, cmp.model[0], "θ/v"), (cmp.accel, cmp.model[1], "a/v"))):
        ax[row].semilogx(f[band], 20 * np.log10(np.abs(est.H[band])), label=f"measured {label} (H1)")
        ax[row].semilogx(f[band], 20 * np.log10(np.abs(model[band])), label=f"model {label}, n = {cmp.n_elements}")
        ax[row].set_ylabel(f"|{label}| (dB)\ncounts/count")  # two lines each: the panels' labels must not meet
        ax[row].legend(loc="lower left", fontsize=8)
    from station.analysis.frequency import phase_beside  # lazy: start-up time (scipy via the plant)

    # the measured phase on the model's branch: unwrapped apart, they can sit 360° apart (no error)
    ax[2].semilogx(f[band], phase_beside(cmp.theta.H[band], cmp.model[0][band]), ".", ms=2, label="measured θ/v")
    ax[2].semilogx(f[band], np.degrees(np.unwrap(np.angle(cmp.model[0][band]))), label="model θ/v")
    ax[2].set_ylabel("phase θ/v (deg)\nunwrapped on the model's")
    ax[2].legend(loc="lower left", fontsize=8)
    ax[3].semilogx(f[band], cmp.theta.coherence[band], label="θ")
    ax[3].semilogx(f[band], cmp.accel.coherence[band], label="a")
    ax[3].set_ylabel("coherence γ²")
    ax[3].set_xlabel("frequency (Hz)")
    ax[3].set_ylim(0, 1.05)
    ax[3].legend(loc="lower left", fontsize=8)
    for i, fz in enumerate(cmp.antiresonances_measured_hz, 1):
        for a in ax[:3]:
            a.axvline(fz, color="grey", lw=0.6, ls=":")
        ax[0].annotate(f"antiresonance {i}: {fz:.2f} Hz", xy=(fz, 1.0), xycoords=("data", "axes fraction"),
                       xytext=(2, -2), textcoords="offset points", rotation=90, va="top", fontsize=7, color="grey")
    fig.suptitle(title)
    fig.tight_layout()
    save_figure(fig, path, transaction=transaction)


def short_name(name: str, width: int = 56) -> str:
    """A run's file name cut in the middle to at most ``width`` characters (titles must not clip).

    Parameters
    ----------
    name : str
    width : int
    """
    if len(name) <= width:
        return name
    keep = (width - 1) // 2
    return f"{name[:keep]}…{name[len(name) - (width - 1 - keep):]}"


def _mark_sticking(ax, t, spans, label: str) -> None:
    """Shade where the measured hub sticks while the beam rings."""
    for k, (s, e) in enumerate(spans):
        ax.axvspan(t[s], t[min(e, t.size) - 1], color="tab:orange", alpha=0.15, lw=0, label=label if k == 0 else None)


def diagnosis_run_figure(run, overshoot_points: float = 3.0):
    """Measured vs nominal vs extended θ and a of one run (a :class:`RunReport`), with the
    stretches where the measured hub sticks while the beam rings shaded; a closed-loop
    step's title gives the overshoots and says when the extended model misses the rig's.

    Parameters
    ----------
    run : RunReport
        One run of a :class:`station.diagnosis.Diagnosis`.
    overshoot_points : float
        The extended model's overshoot is on target within this many percentage points of
        the rig's.

    Returns
    -------
    matplotlib.figure.Figure
    """
    from station.analysis.residuals import sticking_spans  # lazy: start-up time (scipy)

    fig = new_figure(9, 5.2)
    fig.set_layout_engine("constrained")
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    t = run.t
    label = "extended (held out)" if run.role == "validation" else "extended"
    spans = sticking_spans(run.theta, run.a)
    _mark_sticking(ax1, t, spans, "measured hub sticks, beam rings")
    _mark_sticking(ax2, t, spans, None)
    ax1.plot(t, run.theta, color="k", lw=1.2, label="measured")
    ax1.plot(t, run.nominal["theta"], color="tab:red", lw=1, label="nominal")
    ax1.plot(t, run.extended["theta"], color="tab:blue", lw=1, ls="--", label=label)
    if run.controller not in ("open-loop", "unknown"):
        ax1.plot(t, run.u, color="0.6", lw=0.8, label="reference u")
    ax1.set_ylabel("θ (encoder counts)")
    ax1.legend(loc="best", fontsize=8)
    title = (f"{short_name(run.file)} ({run.controller})\nθ fit nominal {_fit_text(run.fit_nominal.get('theta'))}, "
             f"extended {_fit_text(run.fit_extended.get('theta'))}; θ RMS gain {run.gain_pct:.1f} %")
    m = run.metrics
    if m is not None and m.get("rig") is not None and m.get("extended") is not None:
        rig, ext = m["rig"].overshoot_pct, m["extended"].overshoot_pct
        title += f"; overshoot rig {rig:.1f} %, extended {ext:.1f} %"
        if abs(ext - rig) > overshoot_points:
            title += f" (target ±{overshoot_points:g} points missed)"
    fig.suptitle(title, fontsize=9)
    if run.a_logged:
        ax2.plot(t, run.a, color="k", lw=0.8, label="measured")
    else:
        ax2.set_title("a: not logged (no a column); the models' only", fontsize=8)
    ax2.plot(t, run.nominal["a"], color="tab:red", lw=0.8, label="nominal")
    ax2.plot(t, run.extended["a"], color="tab:blue", lw=0.8, ls="--", label=label)
    ax2.set_ylabel("a (accelerometer counts)")
    ax2.set_xlabel("t (s)")
    return fig


def diagnosis_resid_figure(run, max_lag_s: float = 0.5):
    """The θ and a residuals of one run, nominal and extended on the same axes, so the two
    models can be told apart: θ residual against time (±1 count: encoder rounding) and a's;
    the θ residual's autocorrelation to ``max_lag_s`` with the 99 % band of a white residual;
    the θ residual's spectrum (Welch).

    Parameters
    ----------
    run : RunReport
        One run of a :class:`station.diagnosis.Diagnosis`.
    max_lag_s : float
        Longest lag of the autocorrelation, s.

    Returns
    -------
    matplotlib.figure.Figure
    """
    # lazy: start-up time (scipy)
    import scipy.signal

    from station.analysis.residuals import resid_test  # lazy: start-up time (scipy)

    fig = new_figure(9, 6.4)
    fig.set_layout_engine("constrained")
    (ax1, ax2), (ax3, ax4) = fig.subplots(2, 2)
    t = run.t
    dt = float(np.median(np.diff(t))) if t.size > 1 else DT
    lag = int(max(1, min(max_lag_s / dt, t.size // 2)))
    outside = {}
    for pred, color, name in ((run.nominal, "tab:red", "nominal"), (run.extended, "tab:blue", "extended")):
        et, ea = run.theta - pred["theta"], run.a - pred["a"]
        if not (np.all(np.isfinite(et)) and np.all(np.isfinite(ea))):
            continue
        ax1.plot(t, et, color=color, lw=0.8, label=name)
        if run.a_logged:
            ax2.plot(t, ea, color=color, lw=0.6, alpha=0.8, label=name)
        r = resid_test(et, run.v, max_lag=lag)
        ax3.plot(r.lags[1:] * dt, r.autocorr[1:], color=color, lw=1, label=f"{name}: {r.outside_pct:.0f} % outside")
        bound = r.bound
        outside[name] = r.outside_pct
        f, pxx = scipy.signal.welch(et, fs=1.0 / dt, nperseg=min(512, et.size))
        ax4.loglog(f[1:], pxx[1:] + 1e-12, color=color, lw=1, label=name)
    ax1.axhspan(-1, 1, color="0.88", label="±1 count (rounding)")
    ax1.set_ylabel("θ residual (counts)")
    ax1.set_xlabel("t (s)")
    ax1.legend(fontsize=7)
    ax2.set_ylabel("a residual (counts)")
    ax2.set_xlabel("t (s)")
    if not run.a_logged:
        ax2.text(0.5, 0.5, "not logged (no a column)", ha="center", va="center", transform=ax2.transAxes)
        ax2.set_xticks([])
        ax2.set_yticks([])
    if outside:
        ax3.axhspan(-bound, bound, color="0.85", label="99 % band (white)")
    ax3.axhline(0, color="0.5", lw=0.5)
    ax3.set_xlabel("lag (s)")
    ax3.set_ylabel("autocorrelation of θ residual")
    ax3.legend(fontsize=7)
    # white encoder rounding (1/12 counts²) spread over 0..fs/2, one-sided density
    ax4.axhline((1 / 12) * 2 * dt, color="0.5", ls=":", lw=1, label="encoder rounding, white")
    ax4.set_xlabel("frequency (Hz)")
    ax4.set_ylabel("θ residual PSD (counts²/Hz)")
    ax4.legend(fontsize=7)
    far = outside.get("extended", 0.0) > 25.0
    fig.suptitle(f"{short_name(run.file)} ({run.controller}): residuals\nautocorrelation lags outside the 99 % band: "
                 + ", ".join(f"{k} {v:.0f} %" for k, v in outside.items())
                 + (" (extended: still far from white)" if far else ""), fontsize=9)
    return fig


def _fit_text(x) -> str:
    return "n/a" if x is None or not np.isfinite(x) else f"{x:.1f} %"


def identify_design_figure(t, predicted, measured=None, title: str = ""):
    """A designed experiment (``station identify --report``): θ and a predicted on the chosen
    model and on each rival it was chosen to separate, and what the device measured.

    Parameters
    ----------
    t : ndarray, shape (N,)
        Time, s.
    predicted : mapping of str to (ndarray, ndarray)
        Model label -> predicted θ and a, counts, shape (N,) each; the first is the chosen model.
    measured : (ndarray, ndarray), optional
        The run's θ and a, counts (None when it did not complete).
    title : str
        The figure's title (the experiment and why).

    Returns
    -------
    matplotlib.figure.Figure
    """
    fig = new_figure(9, 5.2)
    fig.set_layout_engine("constrained")
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    for k, (label, (theta, a)) in enumerate(predicted.items()):
        style = {"lw": 1.2, "color": "C0"} if k == 0 else {"lw": 0.9, "ls": "--", "color": f"C{k % 10}"}
        ax1.plot(t[:len(theta)], theta, label=label, **style)
        ax2.plot(t[:len(a)], a, **style)
    if measured is not None:
        ax1.plot(t[:len(measured[0])], measured[0], color="k", lw=0.8, label="measured")
        ax2.plot(t[:len(measured[1])], measured[1], color="k", lw=0.6)
    ax1.set_ylabel("θ (encoder counts)")
    ax1.legend(loc="best", fontsize=7)
    ax1.set_title(title, fontsize=8, wrap=True)
    ax2.set_ylabel("a (accelerometer counts)")
    ax2.set_xlabel("t (s)")
    return fig
