"""Figures of run logs: one run (``<log stem>.png`` after ``station step``) or several overlaid (``station plot``).

matplotlib :class:`~matplotlib.figure.Figure` objects with the Agg canvas only - no
pyplot, no global backend - so library users' own matplotlib set-up is never touched.
Panels: θ and u (encoder counts), v and v_applied (DAC counts), a (accelerometer counts).
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from station.errors import StationError


def new_figure(width: float = 9.0, height: float = 8.0):
    """A Figure with its Agg canvas attached (no pyplot state).

    Parameters
    ----------
    width, height : float
        Size, inches.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    FigureCanvasAgg(fig)
    return fig


def save_figure(fig, path: str | Path, dpi: int = 100) -> Path:
    """Write ``fig`` as PNG to ``path``.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or Path
        The PNG file.
    dpi : int, default 100
        Resolution, dots per inch.

    Raises
    ------
    StationError
        The file cannot be written (names it).
    """
    path = Path(path)
    try:
        fig.savefig(path, dpi=dpi)
    except OSError as exc:
        raise StationError(f"{path}: cannot write the figure: {exc.strerror or exc}") from None
    return path


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


def plot_runs(logs: Sequence, title: str | None = None, titles: Sequence[str] | None = None):
    """Figure of one or several run logs overlaid.

    Parameters
    ----------
    logs : sequence of station.runlog.RunLog
        Read by :func:`station.runlog.read_log` (ours or the rig's).
    title : str, optional
        Figure title (default: the file names with their source and outcome).
    titles : sequence of str, optional
        Legend label per log (default: file name and source).

    Returns
    -------
    matplotlib.figure.Figure
        Three panels sharing t (s): θ with u dashed; v with v_applied dotted; a.
        Columns a log lacks (all NaN) are left out.
    """
    if not logs:
        raise StationError("nothing to plot: no run log given")
    fig = new_figure()
    ax_theta, ax_v, ax_a = fig.subplots(3, 1, sharex=True)
    for i, log in enumerate(logs):
        d = log.data
        label = titles[i] if titles is not None else f"{log.path.name} ({source_label(log)})"
        color = f"C{i % 10}"
        t = d["t"]
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


def plot_log_files(paths: Sequence[str | Path], out: str | Path) -> Path:
    """Read ``paths`` and write their overlay to ``out`` (``station plot``).

    Parameters
    ----------
    paths : sequence of str or Path
        Run logs, any format :func:`station.runlog.read_log` reads.
    out : str or Path
        The PNG to write.

    Returns
    -------
    Path
        ``out``.

    Raises
    ------
    StationError
        An unreadable log (the reader's one-line error) or an unwritable ``out``.
    """
    from station.runlog import read_log

    logs = [read_log(p) for p in paths]
    return save_figure(plot_runs(logs), out)
