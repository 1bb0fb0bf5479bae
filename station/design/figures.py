"""The figures of a design (``station tune --report``), by :mod:`station.plots`' rules:
matplotlib :class:`~matplotlib.figure.Figure` objects on the Agg canvas
(:func:`station.plots.new_figure`), never pyplot.

- :func:`steps_figure`: the thesis's compensator and the tuned one side by side on the same
  model: θ and u, v, a of the step.
- :func:`bode_figure`: the loop transfer function L of both on the model's linear part, with
  the tuned one's gain and phase margins.
- :func:`robust_figure`: the spread over the set: θ of every model for both, and each
  model's overshoot against its 2 % settling time.
"""

from __future__ import annotations

import numpy as np

from station.design.evaluate import RUN_S, step_run
from station.design.linear import loop_model
from station.plots import new_figure


def steps_figure(model, tuned, thesis, amplitude: float, names=("thesis", "tuned")):
    """Step responses (θ, v, a) of two compensators on one model, side by side.

    Parameters
    ----------
    model : station.plant.model.Model
    tuned, thesis : station.control.Compensator
    amplitude : float
        Step height, encoder counts.
    names : tuple of str
        Column titles (thesis's first).

    Returns
    -------
    matplotlib.figure.Figure
        Three rows (θ with u dashed and the 2 % band, v with the clamp, a), two columns
        sharing their axes.
    """
    fig = new_figure(10, 8)
    ax = fig.subplots(3, 2, sharex=True, sharey="row")
    for col, (comp, name) in enumerate(((thesis, names[0]), (tuned, names[1]))):
        r = step_run(model, comp, amplitude)
        ax[0, col].plot(r.t, r.theta, lw=1.0, label="θ")
        ax[0, col].plot(r.t, r.u, "k--", lw=0.7, label="u")
        ax[0, col].axhspan(amplitude * 0.98, amplitude * 1.02, color="g", alpha=0.12, label="2 % band")
        ax[1, col].plot(r.t, r.v, lw=0.8, color="C1")
        if comp.limit is not None:
            for s in (1, -1):
                ax[1, col].axhline(s * comp.limit, color="grey", lw=0.6, ls=":")
        ax[2, col].plot(r.t, r.a, lw=0.7, color="C2")
        ax[0, col].set_title(name, fontsize=9)
        ax[2, col].set_xlabel("t (s)")
        for a in ax[:, col]:
            a.grid(True, lw=0.3)
    ax[0, 0].legend(loc="lower right", fontsize=7)
    ax[0, 0].set_ylabel("θ, u (encoder counts)")
    ax[1, 0].set_ylabel("v (DAC counts)")
    ax[2, 0].set_ylabel("a (accelerometer counts)")
    fig.suptitle(f"step of {amplitude:g} counts on model {model.name!r}", fontsize=10)
    fig.tight_layout()
    return fig


def bode_figure(model, tuned, thesis, margins, names=("thesis", "tuned")):
    """Bode plot of the loop transfer function L of both compensators, the tuned one's margins marked.

    Parameters
    ----------
    model : station.plant.model.Model
        Its linear part (:class:`station.design.linear.LoopModel`).
    tuned, thesis : station.control.Compensator
    margins : station.design.linear.Margins
        The tuned loop's margins (written in the title).
    names : tuple of str
        Legend labels (thesis's first).
    """
    lm = loop_model(model)
    f = lm.omega / (2 * np.pi)
    fig = new_figure(9, 7)
    ax_m, ax_p = fig.subplots(2, 1, sharex=True)
    for comp, name, style in ((thesis, names[0], "--"), (tuned, names[1], "-")):
        L = lm.loop(comp)
        ax_m.semilogx(f, 20 * np.log10(np.abs(L)), style, lw=1.0, label=name)
        ax_p.semilogx(f, np.degrees(np.unwrap(np.angle(L))), style, lw=1.0, label=name)
    ax_m.axhline(0, color="grey", lw=0.6)
    ax_p.axhline(-180, color="grey", lw=0.6)
    if np.isfinite(margins.crossover_rad_s):
        for a in (ax_m, ax_p):
            a.axvline(margins.crossover_rad_s / (2 * np.pi), color="C1", lw=0.6, ls=":")
    ax_m.set_ylabel("|L| (dB)")
    ax_p.set_ylabel("∠L (deg, unwrapped)")
    ax_p.set_xlabel("frequency (Hz)")
    for a in (ax_m, ax_p):
        a.grid(True, which="both", lw=0.3)
        a.legend(loc="lower left", fontsize=8)
    fig.suptitle(f"loop L(z) = z^-d Gth (Pθ + Ga Pa) on {model.name!r}: tuned gain margin "
                 f"{margins.gain_margin_db:.1f} dB, phase margin {margins.phase_margin_deg:.1f}°", fontsize=9)
    fig.tight_layout()
    return fig


def robust_figure(models, tuned, thesis, amplitude: float, figures, baseline, overshoot_limit: float,
                  names=("thesis", "tuned")):
    """The spread over the model set: θ of every model for both, and overshoot vs 2 % settling.

    Parameters
    ----------
    models : sequence of Model
    tuned, thesis : station.control.Compensator
    amplitude : float
        Step height, encoder counts.
    figures, baseline : sequence of station.design.evaluate.Figures
        Tuned and thesis, one per model.
    overshoot_limit : float
        The requirement, % (a line).
    names : tuple of str
        Labels (thesis's first).
    """
    fig = new_figure(12, 4.5)
    ax0, ax1, ax2 = fig.subplots(1, 3)
    for ax, comp, name in ((ax0, thesis, names[0]), (ax1, tuned, names[1])):
        for i, m in enumerate(models):
            r = step_run(m, comp, amplitude)
            ax.plot(r.t, r.theta, lw=1.2 if i == 0 else 0.5, color="k" if i == 0 else "C0", alpha=1 if i == 0 else 0.5)
        ax.axhspan(amplitude * 0.98, amplitude * 1.02, color="g", alpha=0.12)
        ax.set_title(f"{name}: θ on {len(models)} model(s) (nominal black)", fontsize=9)
        ax.set_xlabel("t (s)")
        ax.grid(True, lw=0.3)
    ax0.set_ylabel("θ (encoder counts)")
    ax1.sharey(ax0)
    for figs, name, marker in ((baseline, names[0], "x"), (figures, names[1], "o")):
        xs = [RUN_S if f.settling_2pct_s is None else f.settling_2pct_s for f in figs]
        ys = [f.overshoot_pct for f in figs]
        ax2.scatter(xs, ys, marker=marker, label=name)
    ax2.axhline(overshoot_limit, color="r", lw=0.7, ls="--", label=f"overshoot ≤ {overshoot_limit:g} %")
    ax2.set_xlabel(f"2 % settling time (s; {RUN_S:g} = not settled)")
    ax2.set_ylabel("overshoot (%)")
    ax2.grid(True, lw=0.3)
    ax2.legend(fontsize=7)
    fig.tight_layout()
    return fig
