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
with its 0.1 s hold), peak_command (max |v|), saturated_s (time with |v| at the clamp); and
the tip's (:mod:`station.design.tip`): tip_settling_2pct_s (the tip position, hub angle plus
tip deflection / L in encoder counts, into the same 2 % band, the same definition),
tip_residual_rms and tip_residual_peak (the accelerometer from 0.6 s after the step to the
run's end, counts).

Constraints (:class:`Requirements`): overshoot ≤ the bound; the closed loop's linear part
stable with gain margin ≥ 6 dB and phase margin ≥ 30° (:mod:`station.design.linear`);
the tip's residual RMS within its bound (given per model: ``station tune`` sets it to the
thesis's compensator's on the same model, :func:`tip_bound`); settled into the 2 % band
within the run; and at rest at its end — no limit cycle: over the
run's last :data:`REST_WINDOW_S`, θ moves by at most 1 encoder count (one quantization step)
and the command by at most :data:`REST_COMMAND` DAC counts. A loop still swinging there
(a limit cycle of the clamp or the friction, a beam mode the hub no longer damps) is not at
rest. The commands stay within the clamp by construction (the compensator's ``limit``).

Held by friction (:func:`friction_held`): a loop without integral action comes to rest
wherever its command stays below the motor's dry friction, so on some models it holds the hub
a few counts off the target, outside the 2 % band (1 count of a 50-count step) for good,
while meeting everything else. There the step is also measured to the band the hub holds:
:attr:`Figures.rest_band`, the largest |step − θ| over the rest window (the steady-state
error it holds, encoder counts), and :attr:`Figures.settling_rest_s`, the settling time into
that band (the same definition and hold).

Cost (:func:`cost`): the 2 % settling time when every constraint holds (times the model's
:attr:`Requirements.settling_scale`: relative to the thesis's compensator on the same model);
held by friction (and ``held=True``), as infeasible, its "not settled" graded by the settling time into the
held band plus the held error's fraction of the step times the rest of the run (:func:`cost`),
so a hub held farther off costs more, and any design that meets the band costs less; otherwise the time the response last leaves
the band, plus the run's length, plus the constraints' normalised violations, so any feasible
design beats any infeasible one and an infeasible one still shows the way to feasibility.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from station.analysis.metrics import settled_index, step_info_band, step_metrics, time_at_clamp
from station.control.reference import step_reference
from station.design.linear import ALIGNMENT, loop_model
from station.design.tip import residual, tip_position
from station.plant.simulate import simulate
from station.rig import DEFAULT_DURATION, DEFAULT_STEP_TICK, DT, STEP_INFO_BAND

RUN_S = DEFAULT_DURATION
"""Length of a judged step run, s: ``station step``'s default, so its metrics are the design's."""

REST_WINDOW_S = 0.5
"""The run's end over which the loop must be at rest, s."""

TIP_RMS_FLOOR = 0.3
"""Least bound on the tip's residual RMS, accelerometer counts: the simulated rig's
accelerometer noise (0.3 counts std, DESIGN.md "FEM plant"), under which no run on it could
show a difference (the design's own runs are noise-free)."""

FEASIBLE_CAP = 0.999
"""Largest cost of a design that meets every requirement, a fraction of the run's length: a
scaled settling time (:attr:`Requirements.settling_scale`) stays below any infeasible cost."""

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
    tip_rms : float or None
        Largest tip residual RMS, accelerometer counts (None: no bound); per model
        (:func:`tip_bound`).
    settling_scale : float
        What the hub's 2 % settling time counts times in the :func:`cost` when every requirement
        holds (per model: ``station tune`` sets it to the thesis's compensator's settling on the
        design model over its settling on this one, so the worst case over a set is the worst
        ratio to the thesis's; 1: plain seconds). Not a requirement: no violation depends on it.
    """

    overshoot_pct: float = 5.0
    gain_margin_db: float = 6.0
    phase_margin_deg: float = 30.0
    tip_rms: float | None = None
    settling_scale: float = 1.0


def tip_reference(thesis_rms: float) -> float:
    """What a model's tip residual RMS is measured against: the thesis's compensator's there,
    at least :data:`TIP_RMS_FLOOR`, accelerometer counts.

    Parameters
    ----------
    thesis_rms : float
        The thesis's compensator's tip residual RMS on the model, accelerometer counts.

    Returns
    -------
    float
        The reference RMS, accelerometer counts: ``thesis_rms``, or :data:`TIP_RMS_FLOOR` when
        that is larger.
    """
    return max(float(thesis_rms), TIP_RMS_FLOOR)


def tip_bound(ratio: float | None, thesis_rms: float) -> float | None:
    """The bound on a model's tip residual RMS: ``ratio`` times :func:`tip_reference` (None: no bound).

    Parameters
    ----------
    ratio : float or None
        The requirement, a multiple of the thesis's RMS (1: as quiet; None: none).
    thesis_rms : float
        The thesis's compensator's tip residual RMS on the model, accelerometer counts.

    Returns
    -------
    float or None
        The largest tip residual RMS a design may show on the model, accelerometer counts; None
        when ``ratio`` is None or ``thesis_rms`` is not finite (no bound).
    """
    if ratio is None or not math.isfinite(thesis_rms):
        return None
    return float(ratio) * tip_reference(thesis_rms)


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
    band : float
        The 2 % band's half-width, encoder counts (2 % of the step).
    rest_band : float
        The band the hub holds at the run's end: the larger of ``band`` and the largest
        |step − θ| over the rest window, encoder counts (NaN: not simulated).
    settling_rest_s : float or None
        Settling time into ``rest_band`` after the step, s (None: not settled within the run);
        the 2 % settling time when the hub rests inside the 2 % band.
    tip_settling_2pct_s : float or None
        The tip position's 2 % settling time after the step, s (None: not settled, or not
        simulated).
    tip_residual_rms, tip_residual_peak : float
        RMS and largest |a| of the accelerometer from 0.6 s after the step to the run's end,
        accelerometer counts (NaN: not simulated).
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
    band: float = math.nan
    rest_band: float = math.nan
    settling_rest_s: float | None = None
    tip_settling_2pct_s: float | None = None
    tip_residual_rms: float = math.nan
    tip_residual_peak: float = math.nan

    def to_json(self) -> dict:
        """The DESIGN.md metrics (overshoot_pct, settling_2pct_s, settling_thesis_s,
        peak_command, saturated_s, tip_settling_2pct_s, tip_residual_rms, tip_residual_peak)
        and the checks (at_rest, margins, spectral radius).

        Returns
        -------
        dict
            JSON-ready mapping of those names to floats rounded to 6 decimals (None where a figure
            is None or not finite; units as the attributes), plus ``limit_cycle`` (bool, not
            :attr:`at_rest`).
        """
        def num(x):
            return None if x is None or not math.isfinite(x) else round(float(x), 6)
        return {"overshoot_pct": num(self.overshoot_pct), "settling_2pct_s": num(self.settling_2pct_s),
                "settling_thesis_s": num(self.settling_thesis_s), "peak_command": num(self.peak_command),
                "saturated_s": num(self.saturated_s), "tip_settling_2pct_s": num(self.tip_settling_2pct_s),
                "tip_residual_rms": num(self.tip_residual_rms), "tip_residual_peak": num(self.tip_residual_peak),
                "limit_cycle": not self.at_rest,
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
    u = step_reference(amplitude, int(round(run_s / dt)), at_tick=DEFAULT_STEP_TICK)
    return simulate(model, compensator, u, alignment=ALIGNMENT, command="round", dt=dt)


def step_figures(run, amplitude: float, limit: float | None, tip=None) -> tuple:
    """The step figures of a run: (overshoot_pct, settling_2pct_s, settling_thesis_s,
    peak_command, saturated_s, at_rest, final_error, last_out_s, band, rest_band, settling_rest_s,
    tip_settling_2pct_s, tip_residual_rms, tip_residual_peak).

    Parameters
    ----------
    run : SimResult or a logged run's columns
        ``t`` (s), ``theta`` (encoder counts), ``v`` (DAC counts), ``a`` (accelerometer
        counts), the step at tick :data:`station.rig.DEFAULT_STEP_TICK`.
    amplitude : float
        Step height, encoder counts.
    limit : float or None
        The clamp, DAC counts (None: no time at the clamp).
    tip : array_like, shape (N,), optional
        The tip position, encoder counts (:func:`station.design.tip.tip_position`; None: its
        settling time is None).

    Returns
    -------
    tuple
        The 14 figures in the order above, as the fields of :class:`Figures` of the same names
        (units there): floats, with the settling times None when not settled within the run and
        ``at_rest`` a bool.

    Raises
    ------
    ValueError
        A zero ``amplitude``, NaN in θ, or mismatched columns
        (:func:`~station.analysis.metrics.step_metrics`).
    """
    t, theta, v = np.asarray(run["t"]), np.asarray(run["theta"]), np.asarray(run["v"])
    dt = float(t[1] - t[0])
    thesis = step_metrics(t, theta, amplitude)
    after = slice(DEFAULT_STEP_TICK, None)
    ts, ys = t[after] - t[DEFAULT_STEP_TICK], theta[after]
    band = step_info_band(amplitude)
    k = settled_index(ts, ys, amplitude, band)  # as step_info's 2 % settling time
    sat = time_at_clamp(v, limit, dt) if limit is not None else 0.0
    tail = max(2, int(round(REST_WINDOW_S / dt)))
    at_rest = bool(np.ptp(theta[-tail:]) <= 1.0 and np.ptp(v[-tail:]) <= REST_COMMAND)
    out = np.flatnonzero(np.abs(ys - amplitude) > band)
    last_out = 0.0 if out.size == 0 else float(ts[-1] + dt if out[-1] == ys.size - 1 else ts[out[-1] + 1])
    rest_band = max(band, float(np.max(np.abs(amplitude - theta[-tail:]))))
    k_rest = k if rest_band == band else settled_index(ts, ys, amplitude, rest_band)
    k_tip = None if tip is None else settled_index(ts, np.asarray(tip, dtype=float)[after], amplitude, band)
    res = residual(run["a"], DEFAULT_STEP_TICK, dt)
    return (thesis.overshoot_pct, None if k is None else float(ts[k]), thesis.settling_time_s,
            float(np.max(np.abs(v))), sat, at_rest, float(abs(amplitude - ys[-1])), last_out, band, rest_band,
            None if k_rest is None else float(ts[k_rest]), None if k_tip is None else float(ts[k_tip]),
            res.rms, res.peak)


def linear_key(model) -> tuple:
    """What a model's linear checks depend on: its linear part's parameters, element count,
    extra delay and accelerometer gain (friction, offsets and the like leave them alone).

    Parameters
    ----------
    model : station.plant.model.Model

    Returns
    -------
    tuple
        ``(linear_params, n_elements, delay, accel_gain)``: hashable, equal for two models
        whose :func:`linear_checks` agree; a cache key.
    """
    return model.linear_params(), model.n_elements, int(model.effect("delay")), float(model.effect("accel_gain"))


def linear_checks(model, compensator, dt: float = DT) -> tuple[float, object]:
    """(spectral radius, margins) of a compensator's loop on a model's linear part
    (:mod:`station.design.linear`).

    Parameters
    ----------
    model : station.plant.model.Model
    compensator : station.control.Compensator
    dt : float
        Sample time, s.

    Returns
    -------
    tuple of (float, Margins)
        The closed loop's spectral radius (largest pole magnitude, dimensionless; < 1: stable)
        and its margins (:meth:`station.design.linear.LoopModel.margins`: gain margin dB, phase
        margin degrees).
    """
    lm = loop_model(model, dt)
    return lm.spectral_radius(compensator), lm.margins(compensator)


def judge(model, compensator, amplitude: float, run_s: float = RUN_S, dt: float = DT,
          requirements: Requirements | None = None, linear: tuple | None = None, tip: bool = True) -> Figures:
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
    linear : tuple, optional
        :func:`linear_checks` of this compensator on a model with the same :func:`linear_key`
        (computed here when not given).
    tip : bool
        Simulate the tip position too (its settling time; otherwise None: the search does not
        use it).

    Returns
    -------
    Figures
        The linear checks and, unless skipped as above, the step's figures.
    """
    rho, mg = linear_checks(model, compensator, dt) if linear is None else linear
    failed = requirements is not None and (mg.gain_margin_db < requirements.gain_margin_db
                                           or mg.phase_margin_deg < requirements.phase_margin_deg)
    if not rho < 1.0 or failed:
        nan = math.nan
        return Figures(nan, None, None, nan, nan, False, mg.gain_margin_db, mg.phase_margin_deg, rho, nan, nan,
                       step_info_band(amplitude))
    run = step_run(model, compensator, amplitude, run_s, dt)
    fig = step_figures(run, amplitude, compensator.limit, tip_position(model, run.v, dt) if tip else None)
    return Figures(*fig[:6], mg.gain_margin_db, mg.phase_margin_deg, rho, *fig[6:])


def violations(f: Figures, req: Requirements) -> dict[str, float]:
    """The constraints a design breaks on one model, each normalised (0: met).

    Parameters
    ----------
    f : Figures
    req : Requirements

    Returns
    -------
    dict of str to float
        Each broken constraint's name (``unstable``, ``gain_margin``, ``phase_margin``,
        ``not_simulated``, ``overshoot``, ``tip``, ``not_settled``, ``limit_cycle``) to its
        normalised violation (> 0, dimensionless); empty when the design is feasible on the model.
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
    if req.tip_rms is not None and f.tip_residual_rms > req.tip_rms:
        out["tip"] = min((f.tip_residual_rms - req.tip_rms) / req.tip_rms, 100.0)
    if f.settling_2pct_s is None:
        out["not_settled"] = 0.2 + min(f.final_error, 1e3) / 100.0
    if not f.at_rest:
        out["limit_cycle"] = 1.0
    return out


def friction_held(f: Figures, req: Requirements) -> bool:
    """The loop meets every requirement but the 2 % band, at rest outside it: something (dry
    friction) holds the hub off the target (module docstring).

    Parameters
    ----------
    f : Figures
    req : Requirements

    Returns
    -------
    bool
        True when the only violation is ``not_settled`` while the loop is at rest and settled
        into the band it holds (:attr:`Figures.settling_rest_s` not None).
    """
    return (f.at_rest and f.settling_2pct_s is None and f.settling_rest_s is not None
            and set(violations(f, req)) == {"not_settled"})


def held_error(f: Figures) -> int:
    """The steady-state error the hub is held at, whole encoder counts (|step − θ| at the
    run's end; θ is counted, so it is whole).

    Parameters
    ----------
    f : Figures

    Returns
    -------
    int
        :attr:`Figures.final_error` rounded to whole encoder counts.
    """
    return int(round(f.final_error))


def cost(f: Figures, req: Requirements, run_s: float = RUN_S, held: bool = True) -> float:
    """One model's cost of a design (module docstring), s.

    Feasible: the 2 % settling time times ``req.settling_scale`` (below ``run_s``). Infeasible: how late the response leaves the band for
    the last time (:attr:`Figures.last_out_s`), plus ``run_s``, plus the violations
    (:func:`violations`): every feasible design costs less than any infeasible one, and the
    infeasible ones are graded by how close they come. Held by friction (:func:`friction_held`,
    with ``held``), the one violation, not settled, is graded by the band the hub holds: the
    settling time ts into it plus the held band's excess over the 2 % band as a fraction r of
    the step times the rest of the run, ts + r·(run_s − ts), so the held designs are ranked by
    how soon and how close to the target they come to rest.

    Parameters
    ----------
    f : Figures
    req : Requirements
    run_s : float
        The run's length, s.
    held : bool
        Grade a design held by friction as above (False: as infeasible).

    Returns
    -------
    float
        The cost, s: below ``run_s`` when feasible, at least ``run_s`` otherwise.
    """
    bad = violations(f, req)
    if not bad:
        return min(f.settling_2pct_s * req.settling_scale, FEASIBLE_CAP * run_s)
    if held and friction_held(f, req):
        r = (f.rest_band - f.band) / (f.band / STEP_INFO_BAND)  # the held excess, a fraction of the step
        bad["not_settled"] = f.settling_rest_s + r * (run_s - f.settling_rest_s)
    late = run_s if math.isnan(f.last_out_s) else f.last_out_s
    return late + run_s + sum(bad.values())
