"""One design judged on one model: the step as the station runs it, its figures and its cost.

The step is what ``station step`` runs on the simulated rig serving the model: a step of the
amplitude at tick 10 (t = 0.02 s), alignment 1, the commands rounded to whole DAC counts as
protocol v1's device does, θ and a rounded to counts, the model's effects (friction,
saturation, offset, ...) in the simulation (:func:`station.plant.simulate`, the compiled
kernel), :data:`RUN_S` long.

Figures (DESIGN.md "Designing a compensator on a model"): overshoot_pct and
settling_thesis_s (the thesis's, :func:`station.analysis.metrics.step_metrics`: 1 % band,
from t = 0 of the run), settling_2pct_s (the 2 % band after the step, as
:func:`station.analysis.metrics.step_info`: :func:`~station.analysis.metrics.settled_index`
with its 0.1 s hold), peak_command (max |v|), saturated_s (time with |v| at the clamp).

Constraints (:class:`Requirements`): overshoot ≤ the bound; the closed loop's linear part
stable with gain margin ≥ 6 dB and phase margin ≥ 30° (:mod:`station.design.linear`);
settled into the 2 % band within the run; and at rest at its end — no limit cycle: over the
run's last :data:`REST_WINDOW_S`, θ moves by at most 1 encoder count (one quantization step)
and the command by at most :data:`REST_COMMAND` DAC counts. A loop still swinging there
(a limit cycle of the clamp or the friction, a beam mode the hub no longer damps) is not at
rest. The commands stay within the clamp by construction (the compensator's ``limit``).

Cost (:func:`cost`): the 2 % settling time when every constraint holds; otherwise the time
the response last leaves the band, plus the run's length, plus the constraints' normalised
violations, so any feasible design beats any infeasible one and an infeasible one still
shows the way to feasibility.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from station import DT
from station.analysis.metrics import settled_index, step_metrics
from station.control.reference import step_reference
from station.design.linear import ALIGNMENT, loop_model
from station.plant.simulate import simulate

RUN_S = 2.0
"""Length of a judged step run, s: ``station step``'s default, so its metrics are the design's."""

STEP_TICK = 10
"""The step's tick (t = 0.02 s), as ``station step``."""

REST_WINDOW_S = 0.5
"""The run's end over which the loop must be at rest, s."""

REST_COMMAND = 50.0
"""Largest peak-to-peak command over the rest window, DAC counts: a quarter of the rig's clamp.
(One count of θ flickering moves v by Gth's high-frequency gain, 20 for the thesis's lead:
that is quantization, not a limit cycle.)"""


class Requirements(NamedTuple):
    """What a design must meet.

    Attributes
    ----------
    overshoot_pct : float
        Largest overshoot, % of the step.
    gain_margin_db : float
        Least gain margin, dB.
    phase_margin_deg : float
        Least phase margin, degrees.
    """

    overshoot_pct: float = 5.0
    gain_margin_db: float = 6.0
    phase_margin_deg: float = 30.0


class Figures(NamedTuple):
    """A design's step on one model, and its loop's linear checks.

    Attributes
    ----------
    overshoot_pct : float
        (max θ − step)/step, %.
    settling_2pct_s : float or None
        2 % settling time after the step, s (None: not settled within the run).
    settling_thesis_s : float or None
        The thesis's settling time (1 % band, min 1 count), s from t = 0 of the run.
    peak_command : float
        max |v|, DAC counts.
    saturated_s : float
        Time the command spent at the clamp, s.
    at_rest : bool
        No limit cycle: θ and v still at the run's end (module docstring).
    gain_margin_db, phase_margin_deg : float
        The linear loop's margins (inf: no crossing).
    spectral_radius : float
        Largest closed-loop pole magnitude (< 1: stable).
    final_error : float
        |step − θ| at the run's end, encoder counts.
    last_out_s : float
        Time after the step of the first sample after the last one outside the 2 % band,
        without the hold (the run's end when the last sample is outside), s: how late the
        response is, also for a design that does not settle (it grades the infeasible ones).
    """

    overshoot_pct: float
    settling_2pct_s: float | None
    settling_thesis_s: float | None
    peak_command: float
    saturated_s: float
    at_rest: bool
    gain_margin_db: float
    phase_margin_deg: float
    spectral_radius: float
    final_error: float
    last_out_s: float

    def to_json(self) -> dict:
        """The DESIGN.md metrics (overshoot_pct, settling_2pct_s, settling_thesis_s,
        peak_command, saturated_s) and the checks (at_rest, margins, spectral radius)."""
        def num(x):
            return None if x is None or not math.isfinite(x) else round(float(x), 6)
        return {"overshoot_pct": num(self.overshoot_pct), "settling_2pct_s": num(self.settling_2pct_s),
                "settling_thesis_s": num(self.settling_thesis_s), "peak_command": num(self.peak_command),
                "saturated_s": num(self.saturated_s), "limit_cycle": not self.at_rest,
                "gain_margin_db": num(self.gain_margin_db), "phase_margin_deg": num(self.phase_margin_deg),
                "spectral_radius": num(self.spectral_radius)}


def step_run(model, compensator, amplitude: float, run_s: float = RUN_S, dt: float = DT):
    """The step run as ``station step`` makes it on the simulated rig (module docstring).

    Parameters
    ----------
    model : station.plant.model.Model
    compensator : station.control.Compensator
    amplitude : float
        Step height, encoder counts.
    run_s : float
        Run length, s.
    dt : float
        Sample time, s.

    Returns
    -------
    station.plant.simulate.SimResult
    """
    u = step_reference(amplitude, int(round(run_s / dt)), at_tick=STEP_TICK)
    return simulate(model, compensator, u, alignment=ALIGNMENT, command="round", dt=dt)


def step_figures(run, amplitude: float, limit: float | None) -> tuple:
    """The step figures of a run: (overshoot_pct, settling_2pct_s, settling_thesis_s,
    peak_command, saturated_s, at_rest, final_error, last_out_s).

    Parameters
    ----------
    run : SimResult or a logged run's columns
        ``t`` (s), ``theta`` (encoder counts), ``v`` (DAC counts), the step at tick
        :data:`STEP_TICK`.
    amplitude : float
        Step height, encoder counts.
    limit : float or None
        The clamp, DAC counts (None: no time at the clamp).
    """
    t, theta, v = np.asarray(run["t"]), np.asarray(run["theta"]), np.asarray(run["v"])
    dt = float(t[1] - t[0])
    thesis = step_metrics(t, theta, amplitude)
    after = slice(STEP_TICK, None)
    ts, ys = t[after] - t[STEP_TICK], theta[after]
    k = settled_index(ts, ys, amplitude, 0.02 * abs(amplitude))  # as step_info's 2 % settling time
    sat = float(np.count_nonzero(np.abs(v) >= limit) * dt) if limit is not None else 0.0
    tail = max(2, int(round(REST_WINDOW_S / dt)))
    at_rest = bool(np.ptp(theta[-tail:]) <= 1.0 and np.ptp(v[-tail:]) <= REST_COMMAND)
    out = np.flatnonzero(np.abs(ys - amplitude) > 0.02 * abs(amplitude))
    last_out = 0.0 if out.size == 0 else float(ts[-1] + dt if out[-1] == ys.size - 1 else ts[out[-1] + 1])
    return (thesis.overshoot_pct, None if k is None else float(ts[k]), thesis.settling_time_s,
            float(np.max(np.abs(v))), sat, at_rest, float(abs(amplitude - ys[-1])), last_out)


def judge(model, compensator, amplitude: float, run_s: float = RUN_S, dt: float = DT,
          requirements: Requirements | None = None) -> Figures:
    """A compensator's figures on a model: linear checks, then the step.

    The step is not simulated (its figures NaN, ``settling_2pct_s`` None) when the linear
    loop is unstable, or, given ``requirements``, when its margins already fail them: such a
    design is out whatever its step (the search saves the time).

    Parameters
    ----------
    model : station.plant.model.Model
    compensator : station.control.Compensator
    amplitude : float
        Step height, encoder counts.
    run_s : float
        Run length, s.
    dt : float
        Sample time, s.
    requirements : Requirements, optional
        Skip the step when the margins fail these.
    """
    lm = loop_model(model, dt)
    rho = lm.spectral_radius(compensator)
    mg = lm.margins(compensator)
    failed = requirements is not None and (mg.gain_margin_db < requirements.gain_margin_db
                                           or mg.phase_margin_deg < requirements.phase_margin_deg)
    if not rho < 1.0 or failed:
        nan = math.nan
        return Figures(nan, None, None, nan, nan, False, mg.gain_margin_db, mg.phase_margin_deg, rho, nan, nan)
    fig = step_figures(step_run(model, compensator, amplitude, run_s, dt), amplitude, compensator.limit)
    return Figures(*fig[:6], mg.gain_margin_db, mg.phase_margin_deg, rho, *fig[6:])


def violations(f: Figures, req: Requirements) -> dict[str, float]:
    """The constraints a design breaks on one model, each normalised (0: met).

    Parameters
    ----------
    f : Figures
    req : Requirements
    """
    out = {}
    if not f.spectral_radius < 1.0:
        out["unstable"] = 10.0 + 100.0 * (f.spectral_radius - 1.0)
        return out
    if f.gain_margin_db < req.gain_margin_db:
        out["gain_margin"] = (req.gain_margin_db - f.gain_margin_db) / req.gain_margin_db
    if f.phase_margin_deg < req.phase_margin_deg:
        out["phase_margin"] = (req.phase_margin_deg - f.phase_margin_deg) / req.phase_margin_deg
    if math.isnan(f.overshoot_pct):
        out["not_simulated"] = 2.0
        return out
    if f.overshoot_pct > req.overshoot_pct:
        out["overshoot"] = (f.overshoot_pct - req.overshoot_pct) / 5.0
    if f.settling_2pct_s is None:
        out["not_settled"] = 0.2 + min(f.final_error, 1e3) / 100.0
    if not f.at_rest:
        out["limit_cycle"] = 1.0
    return out


def cost(f: Figures, req: Requirements, run_s: float = RUN_S) -> float:
    """One model's cost of a design (module docstring), s.

    Feasible: the 2 % settling time. Infeasible: how late the response leaves the band for
    the last time (:attr:`Figures.last_out_s`), plus ``run_s``, plus the violations
    (:func:`violations`): every feasible design costs less than any infeasible one, and the
    infeasible ones are graded by how close they come.

    Parameters
    ----------
    f : Figures
    req : Requirements
    run_s : float
        The run's length, s.
    """
    bad = violations(f, req)
    if not bad:
        return f.settling_2pct_s
    late = run_s if math.isnan(f.last_out_s) else f.last_out_s
    return late + run_s + sum(bad.values())
