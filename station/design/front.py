"""The trade-off between the hub and the tip: the designs no other design beats on both.

A fast hub and a quiet tip pull apart (docs/tuning.md "What each structure can do"): a
higher lead gain stops the hub sooner, and every encoder count the hub then hunts across
kicks the command and rings the beam's lightly damped second mode. Each design judged on
every model of the set is a point (:class:`TradePoint`): its worst hub 2 % settling time and
its worst tip residual RMS over the models, each relative to the thesis's compensator on
the same model (:func:`ratios`). Among the designs that meet the other requirements
(overshoot, margins, at rest) on every model, the non-dominated ones (:func:`pareto`: no
other is at least as good on both and better on one) are the front; the chosen design is
marked, on the front or not.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from station.design.evaluate import RUN_S, tip_reference, violations


class TradePoint(NamedTuple):
    """One design's worst case over the set, relative to the thesis's compensator.

    Attributes
    ----------
    x : ndarray
        The design's unit-cube point.
    hub_ratio : float
        Worst over the models of its hub 2 % settling time / the thesis's (a model where
        either does not settle counts with the run's length).
    tip_ratio : float
        Worst over the models of its tip residual RMS / the thesis's
        (:func:`station.design.evaluate.tip_reference`).
    overshoot_pct : float
        Worst overshoot, %.
    hub_s, tip_rms : float
        Worst hub 2 % settling time (s; the run's length: not settled) and worst tip residual
        RMS (accelerometer counts).
    others_met : bool
        Overshoot, margins and rest met on every model (the requirements besides the two axes).
    met : bool
        Every requirement met on every model.
    """

    x: np.ndarray
    hub_ratio: float
    tip_ratio: float
    overshoot_pct: float
    hub_s: float
    tip_rms: float
    others_met: bool
    met: bool


def ratios(figures, baseline, run_s: float = RUN_S) -> tuple[list[float], list[float]]:
    """Per model: hub 2 % settling and tip residual RMS, each / the thesis's compensator's.

    Parameters
    ----------
    figures, baseline : sequence of Figures
        The design and the thesis's compensator, one per model.
    run_s : float
        The run's length, s (stands for "not settled").

    Returns
    -------
    tuple of (list of float, list of float)
        ``(hub, tip)``, one per model, dimensionless: the design's 2 % settling time over the
        thesis's (``run_s`` standing for "not settled" on either side), and its tip residual RMS
        over :func:`~station.design.evaluate.tip_reference` of the thesis's (inf where the design
        was not simulated).
    """
    def settle(f):
        return run_s if f.settling_2pct_s is None else f.settling_2pct_s

    hub = [settle(f) / settle(b) for f, b in zip(figures, baseline)]
    tip = [f.tip_residual_rms / tip_reference(b.tip_residual_rms) if math.isfinite(f.tip_residual_rms) else math.inf
           for f, b in zip(figures, baseline)]
    return hub, tip


def trade_point(x, figures, baseline, requirements, run_s: float = RUN_S) -> TradePoint:
    """A design's :class:`TradePoint`.

    Parameters
    ----------
    x : array_like
        Its unit-cube point.
    figures, baseline : sequence of Figures
        The design and the thesis's compensator, one per model.
    requirements : sequence of Requirements
        One per model (the tip's bound its own).
    run_s : float
        The run's length, s.

    Returns
    -------
    TradePoint
        The worst ratios and figures over the models (NaN where a model was not simulated)
        and whether the requirements other than the tip and the band, and all of them, hold on
        every model.
    """
    hub, tip = ratios(figures, baseline, run_s)
    broken = [set(violations(f, r)) for f, r in zip(figures, requirements)]
    axes = {"tip", "not_settled"}

    def worst(values):  # NaN where a model was not simulated (its margins failed)
        values = [float(v) for v in values]
        return math.nan if any(math.isnan(v) for v in values) else max(values)
    return TradePoint(np.asarray(x, dtype=float), worst(hub), worst(tip), worst(f.overshoot_pct for f in figures),
                      max(run_s if f.settling_2pct_s is None else f.settling_2pct_s for f in figures),
                      worst(f.tip_residual_rms for f in figures), all(not (b - axes) for b in broken),
                      all(not b for b in broken))


def pareto(points) -> list[int]:
    """Indices of the non-dominated points on (hub_ratio, tip_ratio), both minimized, among
    those with ``others_met``; sorted by hub_ratio. Of equal points the first counts.

    Parameters
    ----------
    points : sequence of TradePoint

    Returns
    -------
    list of int
        Indices into ``points`` of the front, sorted by hub_ratio then tip_ratio; empty when no
        point meets the other requirements with finite ratios.
    """
    ok = [i for i, p in enumerate(points) if p.others_met and math.isfinite(p.hub_ratio) and math.isfinite(p.tip_ratio)]
    front = []
    for i in ok:
        a = points[i]
        dominated = any((b.hub_ratio <= a.hub_ratio and b.tip_ratio <= a.tip_ratio
                         and (b.hub_ratio < a.hub_ratio or b.tip_ratio < a.tip_ratio or j < i))
                        for j, b in ((j, points[j]) for j in ok if j != i))
        if not dominated:
            front.append(i)
    return sorted(front, key=lambda i: (points[i].hub_ratio, points[i].tip_ratio, i))


def spread_along(values, n: int) -> list[int]:
    """Up to ``n`` indices of ``values`` spread evenly from the smallest to the largest
    (ties to the lower index): where to sample a front.

    Parameters
    ----------
    values : sequence of float
    n : int

    Returns
    -------
    list of int
        Distinct indices into ``values``, ordered from the smallest value to the largest; all of
        them (sorted so) when there are at most ``n``.
    """
    order = sorted(range(len(values)), key=lambda i: (values[i], i))
    if len(order) <= n:
        return order
    picks = np.unique(np.round(np.linspace(0, len(order) - 1, n)).astype(int))
    return [order[k] for k in picks]
