"""The figures of a design (``station tune --report``), by :mod:`station.plots`' rules:
matplotlib :class:`~matplotlib.figure.Figure` objects on the Agg canvas
(:func:`station.plots.new_figure`), never pyplot.

- :func:`steps_figure`: the thesis's compensator and the tuned one side by side on the same
  model: θ, the tip position and u, v, a of the step (the tip's residual window shaded).
- :func:`bode_figure`: the loop transfer function L of both on the model's linear part, with
  the tuned one's gain and phase margins.
- :func:`robust_figure`: the spread over the set: θ of every model for both, each model's
  overshoot against its 2 % settling time, and each model's tip residual RMS, tuned against
  the thesis's.
- :func:`tradeoff_figure`: the hub-tip trade-off (:mod:`station.design.front`): every design
  judged on every model, the front, the chosen design.
"""

from __future__ import annotations

import numpy as np

from station.analysis.metrics import STEP_INFO_BAND_PCT, settling_label
from station.design.evaluate import RUN_S, step_run
from station.design.linear import loop_model
from station.design.tip import residual, tip_position
from station.plots import new_figure
from station.rig import DEFAULT_STEP_TICK, RESIDUAL_AFTER_S


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
        Three rows (θ and the tip position with u dashed and the 2 % band, v with the clamp,
        a with its residual window shaded and its RMS there), two columns sharing their axes.
    """
    fig = new_figure(10, 8)
    ax = fig.subplots(3, 2, sharex=True, sharey="row")
    for col, (comp, name) in enumerate(((thesis, names[0]), (tuned, names[1]))):
        r = step_run(model, comp, amplitude)
        ax[0, col].plot(r.t, tip_position(model, r.v), lw=0.8, color="C3", label="tip (hub + deflection / L)")
        ax[0, col].plot(r.t, r.theta, lw=1.0, color="C0", label="θ (hub)")
        ax[0, col].plot(r.t, r.u, "k--", lw=0.7, label="u")
        ax[0, col].axhspan(amplitude * 0.98, amplitude * 1.02, color="g", alpha=0.12, label="2 % band")
        ax[1, col].plot(r.t, r.v, lw=0.8, color="C1")
        if comp.limit is not None:
            for s in (1, -1):
                ax[1, col].axhline(s * comp.limit, color="grey", lw=0.6, ls=":")
        start = r.t[DEFAULT_STEP_TICK] + RESIDUAL_AFTER_S
        res = residual(r.a, DEFAULT_STEP_TICK, float(r.t[1] - r.t[0]))
        ax[2, col].axvspan(start, r.t[-1], color="C2", alpha=0.08)
        ax[2, col].plot(r.t, r.a, lw=0.7, color="C2")
        ax[2, col].text(0.98, 0.95, f"from {RESIDUAL_AFTER_S:g} s after the step: RMS {res.rms:.2f}, "
                        f"peak {res.peak:.0f}", transform=ax[2, col].transAxes, ha="right", va="top", fontsize=8)
        ax[0, col].set_title(name, fontsize=9)
        ax[2, col].set_xlabel("t (s)")
        for a in ax[:, col]:
            a.grid(True, lw=0.3)
    ax[0, 0].legend(loc="lower right", fontsize=7)
    ax[0, 0].set_ylabel("θ, tip, u (encoder counts)")
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

    Returns
    -------
    matplotlib.figure.Figure
        Two panels over frequency (Hz): |L| in dB and its unwrapped phase in degrees, both
        compensators, the tuned loop's gain crossover marked.
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

    Returns
    -------
    matplotlib.figure.Figure
        Four panels: θ (encoder counts) over t (s) on every model for the thesis's and the tuned
        compensator, overshoot (%) against 2 % settling time (s) per model, and the tuned against
        the thesis's tip residual RMS (accelerometer counts) per model.
    """
    fig = new_figure(16, 4.5)
    ax0, ax1, ax2, ax3 = fig.subplots(1, 4)
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
    ax2.set_xlabel(f"hub {settling_label(STEP_INFO_BAND_PCT)} (s; {RUN_S:g} = not settled)")
    ax2.set_ylabel("overshoot (%)")
    ax2.grid(True, lw=0.3)
    ax2.legend(fontsize=7)
    xs = [b.tip_residual_rms for b in baseline]
    ax3.scatter(xs, [f.tip_residual_rms for f in figures], marker="o", color="C1", label=f"{names[1]} on each model")
    top = max([*xs, *(f.tip_residual_rms for f in figures), 1.0])
    ax3.plot([0, top], [0, top], "k:", lw=0.7, label="as quiet as the thesis's")
    ax3.set_xlabel(f"{names[0]}: tip residual RMS (counts)")
    ax3.set_ylabel(f"{names[1]}: tip residual RMS (counts)")
    ax3.set_title(f"the tip from {RESIDUAL_AFTER_S:g} s after the step", fontsize=9)
    ax3.grid(True, lw=0.3)
    ax3.legend(fontsize=7)
    fig.tight_layout()
    return fig


def tradeoff_figure(tradeoff, tip_rms: float | None = None):
    """The hub-tip trade-off: every design judged on every model, the front, the chosen one.

    Parameters
    ----------
    tradeoff : station.design.result.TradeOff
    tip_rms : float, optional
        The tip's requirement, a multiple of the thesis's (a line).

    Returns
    -------
    matplotlib.figure.Figure
        Worst hub 2 % settling / the thesis's against worst tip residual RMS / the thesis's,
        over the set; the thesis's own compensator at (1, 1).
    """
    pts = tradeoff.points
    fig = new_figure(8, 6)
    ax = fig.subplots()
    for ok, style in ((False, dict(color="0.7", marker="x", label="fails overshoot, margins or rest on a model")),
                      (True, dict(color="C0", marker="o", label="meets overshoot, margins and rest"))):
        sel = [p for p in pts if p.others_met == ok and np.isfinite(p.hub_ratio) and np.isfinite(p.tip_ratio)]
        if sel:
            ax.scatter([p.hub_ratio for p in sel], [p.tip_ratio for p in sel], s=18, alpha=0.8, **style)
    front = [pts[i] for i in tradeoff.front]
    if front:
        ax.step([p.hub_ratio for p in front], [p.tip_ratio for p in front], where="post", color="C0", lw=1.0,
                label="front: no other design beats these on both")
    c = pts[tradeoff.chosen]
    ax.scatter([c.hub_ratio], [c.tip_ratio], marker="*", s=220, color="C3", zorder=5, label="chosen")
    ax.scatter([1.0], [1.0], marker="s", s=60, color="k", zorder=5, label="the thesis's compensator")
    if tip_rms is not None:
        ax.axhline(tip_rms, color="C3", lw=0.7, ls="--", label=f"tip requirement (≤ {tip_rms:g}× the thesis's)")
    ax.axvline(0.6, color="C2", lw=0.7, ls=":", label="hub at 0.6× the thesis's")
    from matplotlib.ticker import FormatStrFormatter  # lazy: start-up time (matplotlib)

    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):
        axis.set_major_formatter(FormatStrFormatter("%g"))
        axis.set_minor_formatter(FormatStrFormatter("%g"))
    ax.set_xlabel(f"worst hub {settling_label(STEP_INFO_BAND_PCT)} / the thesis's, over the models (not settled: the run's length)")
    ax.set_ylabel("worst tip residual RMS / the thesis's, over the models")
    ax.set_title(f"{len(pts)} designs judged on every model of the set", fontsize=9)
    ax.grid(True, which="both", lw=0.3)
    ax.legend(fontsize=7, loc="upper right")
    fig.tight_layout()
    return fig
