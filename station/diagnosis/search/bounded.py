"""Fitting effect values to measured runs on a piecewise-constant objective.

Quantized θ and stick-slip make a simulation's error a piecewise-constant function of an
effect's value: finite-difference gradients are zero or huge, and least squares alone
stalls (issue 8). So every parameter is first bracketed on a grid (log-spaced for ratios,
square-root spaced for magnitudes that start at zero, whole numbers for the delay), then
refined locally: ``scipy.optimize.minimize_scalar`` (bounded, inside the bracket) for one
parameter, Nelder-Mead for several (whole-number ones by enumeration around their value).
The best value *seen* is returned, so a refinement never makes a fit worse than its grid.

The objective is any callable ``cost(effects: dict[str, float]) -> float``; see
:mod:`station.diagnosis.runs.cost` for the one the diagnosis uses.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import scipy.optimize

GRID_POINTS = 17
"""Grid values per continuous parameter (ratios 0.1..10: a factor 1.33 apart)."""

LATTICE = 64
"""Refined values lie on a lattice of 1/LATTICE grid step (well inside any tolerance), so
the folds of a cross-validation, refining near the same grid point, share simulations."""

REFINE_ITERATIONS = 12
"""Bounded scalar refinement: at most this many evaluations inside the bracket."""

REFINE_JOINT = 12
"""Nelder-Mead evaluations per continuous axis of a joint refinement (plus 8)."""

RESOLUTION_STEPS = 1.0 / 16.0
"""An interval is at least ± this many grid steps of the effect's search coordinate: the
fit's own resolution (refinement to 0.02 grid step on a piecewise-constant cost)."""


@dataclass(frozen=True)
class Axis:
    """How a parameter is searched: its range, its spacing and whether it is whole.

    Attributes
    ----------
    name : str
    lower, upper : float
        The range searched, in the effect's unit.
    scale : {"log", "sqrt", "linear", "int"}
        Spacing of the grid: "log" for ratios (lower > 0), "sqrt" for magnitudes from 0
        (fine near 0), "linear", "int" (every whole number).
    """

    name: str
    lower: float
    upper: float
    scale: str

    def to_unit(self, x: float) -> float:
        """Value -> search coordinate (grid points equally spaced in it).

        Parameters
        ----------
        x : float
            A value in the effect's unit.

        Returns
        -------
        float
            log x ("log"), √max(x, 0) ("sqrt"), or x itself ("linear", "int").
        """
        if self.scale == "log":
            return math.log(x)
        if self.scale == "sqrt":
            return math.sqrt(max(x, 0.0))
        return float(x)

    def from_unit(self, t: float) -> float:
        """Search coordinate -> value, clipped to [lower, upper].

        Parameters
        ----------
        t : float
            A search coordinate.

        Returns
        -------
        float
            The value in the effect's unit, in [lower, upper]: on a lattice of 1/64 grid step in
            the coordinate, a whole number on an "int" axis.
        """
        lo, hi = self.to_unit(self.lower), self.to_unit(self.upper)
        t = min(max(t, lo), hi)
        if self.scale != "int":  # on a lattice of 1/64 grid step: refinements share simulations
            q = self.step / LATTICE
            t = lo + round((t - lo) / q) * q
        if self.scale == "log":
            x = math.exp(t)
        elif self.scale == "sqrt":
            x = t * t
        elif self.scale == "int":
            x = float(round(t))
        else:
            x = t
        return float(min(max(x, self.lower), self.upper))

    def grid(self, points: int = GRID_POINTS) -> np.ndarray:
        """The bracketing grid, shape (G,), in the effect's unit.

        Parameters
        ----------
        points : int, default GRID_POINTS
            Grid points (whole-number axes ignore it: every integer in range).

        Returns
        -------
        ndarray, shape (G,)
            Increasing values in [lower, upper]: ``points`` equally spaced in the coordinate (a
            "sqrt" axis from 0 leaves 0 out), or every integer in range.
        """
        if self.scale == "int":
            return np.arange(math.ceil(self.lower), math.floor(self.upper) + 1, dtype=float)
        lo, hi = self.to_unit(self.lower), self.to_unit(self.upper)
        ts = np.linspace(lo, hi, points)
        if self.scale == "sqrt" and ts[0] == 0.0:
            ts = np.linspace(lo, hi, points + 1)[1:]  # 0 is the nominal model, judged anyway
        return np.array([self.from_unit(t) for t in ts])

    @property
    def step(self) -> float:
        """Grid spacing in the search coordinate."""
        if self.scale == "int":
            return 1.0
        return (self.to_unit(self.upper) - self.to_unit(self.lower)) / (GRID_POINTS - 1)


def axis_for(name: str, lower: float, upper: float, neutral: float) -> Axis:
    """The search axis of an effect from its range (station.plant.effects.EffectSpec).

    Whole-number effects ("delay") are enumerated; ranges with lower > 0 spanning a factor
    of 4 or more are log-spaced (ratios, damping ratios); ranges from 0 are square-root
    spaced; the rest (saturation) linear.

    Parameters
    ----------
    name : str
        The effect's name.
    lower, upper : float
        Its search range, in its unit.
    neutral : float
        Its "no effect" value.

    Returns
    -------
    Axis
        The range with its scale: "int", "log", "sqrt" or "linear" as above.
    """
    if name == "delay":
        return Axis(name, lower, upper, "int")
    if lower > 0 and upper / lower >= 4.0:
        return Axis(name, lower, upper, "log")
    if lower == 0.0:
        return Axis(name, lower, upper, "sqrt")
    return Axis(name, lower, upper, "linear")


@dataclass(frozen=True)
class FitResult:
    """Values fitted by :func:`fit`.

    Attributes
    ----------
    values : dict of str to float
        Every fitted axis's value (and the fixed ones passed in ``start``).
    cost : float
        The objective there.
    evaluations : int
        Objective calls made by this fit (cached ones included).
    """

    values: dict
    cost: float
    evaluations: int


class _Tracker:
    """Calls the objective and remembers the best point seen."""

    def __init__(self, cost: Callable[[dict], float]):
        self.cost = cost
        self.best: tuple[float, dict] = (math.inf, {})
        self.calls = 0

    def __call__(self, values: dict) -> float:
        self.calls += 1
        c = float(self.cost(values))
        if not math.isfinite(c):
            c = math.inf
        if c < self.best[0]:
            self.best = (c, dict(values))
        return c


def fit(cost: Callable[[dict], float], axes: Sequence[Axis], start: Mapping[str, float] | None = None,
        fixed: Mapping[str, float] | None = None, grid_cost: Callable[[list[dict]], list[float]] | None = None,
        refine: int = REFINE_JOINT) -> FitResult:
    """Fit effect values: bracket the last axis on its grid, then refine all axes locally.

    Parameters
    ----------
    cost : callable
        ``cost(values) -> float`` for a dict {name: value} of every axis (and ``fixed``).
    axes : sequence of Axis
        The parameters fitted. The last is the one being added: it is bracketed on its
        grid with the others at their ``start`` values; then one axis is refined with
        bounded Brent inside the grid cell either side of the best grid value, several
        axes with Nelder-Mead in the search coordinates (initial simplex one grid step),
        whole-number axes by enumeration of ±1 around their value.
    start : mapping, optional
        Starting values of all axes but the last (required for them).
    fixed : mapping, optional
        Values passed to ``cost`` unchanged (not fitted).
    grid_cost : callable, optional
        ``grid_cost(list_of_values) -> list of costs``: evaluates the grid at once (e.g. in
        parallel threads); default: ``cost`` one by one.
    refine : int, optional
        Nelder-Mead evaluations per continuous axis of a joint refinement (and as many again
        once); default :data:`REFINE_JOINT`.

    Returns
    -------
    FitResult
        The best point seen (never worse than the best grid point).
    """
    axes = list(axes)
    start = dict(start or {})
    fixed = dict(fixed or {})
    track = _Tracker(lambda vals: cost({**fixed, **vals}))
    new = axes[-1]
    base = {a.name: float(start[a.name]) for a in axes[:-1]}
    grid = new.grid()
    points = [{**base, new.name: float(g)} for g in grid]
    if grid_cost is not None:
        costs = grid_cost([{**fixed, **p} for p in points])
        for p, c in zip(points, costs):
            track.calls += 1
            c = float(c) if math.isfinite(c) else math.inf
            if c < track.best[0]:
                track.best = (c, dict(p))
    else:
        costs = [track(p) for p in points]
    if not math.isfinite(track.best[0]):
        return FitResult({**fixed, **points[0]}, math.inf, track.calls)
    ibest = int(np.argmin(costs))
    if len(axes) == 1:
        if new.scale != "int":
            lo = new.to_unit(grid[ibest - 1]) if ibest > 0 else new.to_unit(new.lower)
            hi = new.to_unit(grid[ibest + 1]) if ibest + 1 < grid.size else new.to_unit(new.upper)
            if hi > lo:
                scipy.optimize.minimize_scalar(
                    lambda t: track({new.name: new.from_unit(t)}), bounds=(lo, hi), method="bounded",
                    options={"xatol": 0.02 * new.step, "maxiter": REFINE_ITERATIONS})
    else:
        _refine_joint(track, axes, refine)
    best_cost, best = track.best
    return FitResult({**fixed, **best}, best_cost, track.calls)


def _refine_joint(track: _Tracker, axes: list[Axis], refine: int = 12) -> None:
    """Nelder-Mead over the continuous axes (at most ``refine`` evaluations per axis, and as
    many again), enumeration of whole-number ones, twice."""
    cont = [a for a in axes if a.scale != "int"]
    ints = [a for a in axes if a.scale == "int"]
    for _ in range(2):
        before = track.best[0]
        _, point = track.best
        if cont:
            x0 = np.array([a.to_unit(point[a.name]) for a in cont])
            steps = np.array([a.step for a in cont])
            simplex = np.vstack([x0] + [x0 + np.eye(len(cont))[i] * steps[i] * (1 if x0[i] + steps[i] <=
                                        a.to_unit(a.upper) else -1) for i, a in enumerate(cont)])

            def f(x, point=point):
                vals = dict(point)
                vals.update({a.name: a.from_unit(t) for a, t in zip(cont, x)})
                return track(vals)

            scipy.optimize.minimize(f, x0, method="Nelder-Mead",
                                    options={"initial_simplex": simplex, "maxfev": refine * len(cont) + 8,
                                             "xatol": 0.02 * float(steps.min()), "fatol": 1e-9})
        for a in ints:
            _, point = track.best
            for d in (-1.0, 1.0):
                x = point[a.name] + d
                if a.lower <= x <= a.upper:
                    track({**point, a.name: x})
        if not ints or track.best[0] >= before:
            break
