"""The rows of a log as one candidate control law sees them (:class:`LawRows`): the
regression and the linear program that fit a law's coefficients to the logged commands, the
rows only the lab's floating-point arithmetic decided (:func:`tie_rows`), and the law the rows
pin with its continuous design (:func:`pinned_law`).

Used by :mod:`station.analysis.controller_id`; see its docstring for the laws tried.
"""

from __future__ import annotations

from dataclasses import replace
from fractions import Fraction
from functools import partial

import numpy as np

from station.analysis.continuous_design import MAX_DIGITS, ContinuousDesign, nicest_between, recognize, to_continuous
from station.analysis.design_doubt import design_span, round_roots
from station.control.rerun import judged_rows, print_allowance, printed_commands

TOLERANCE = 1e-6
"""max |v_replayed - v_logged| (DAC counts) a law must meet to be accepted."""

SCREEN_ROWS = 64
"""Rows :meth:`LawRows.deepest_fit` asks first, those least squares misses most: a subset with
no inside has none in all the rows."""

BOUNDARY = 1e-9
"""How close (counts) x may come to an integer recursion's interval and still count as in
it while a continuous design is recognised: the lab's discretization and ours may differ in
the last bit, and a row whose x falls on a whole count is decided by that bit."""

MIN_FREE_ROWS = 10
"""Rows a law must be judged on, where the logged v is neither 0 nor at its largest |v|: a log
whose commands are only 0 and one level (a step column, a bang-bang run) is reproduced by
any law of high enough gain at a clamp of that level, and identifies none."""


def pins_a_law(v) -> bool:
    """Whether logged commands can pin a closed-loop law: at least :data:`MIN_FREE_ROWS` rows
    of v neither 0 nor at its largest |v|.

    Parameters
    ----------
    v : array_like, shape (N,)
        The logged commands, DAC counts.
    """
    v = np.asarray(v, dtype=float)
    if not v.size or not np.all(np.isfinite(v)):
        return False
    return _free_rows(v) >= MIN_FREE_ROWS


def _free_rows(v: np.ndarray) -> int:
    """Rows of finite v neither 0 nor at its largest |v| (the rows that can pin a law)."""
    return int(np.count_nonzero((v != 0) & (np.abs(v) < np.max(np.abs(v), initial=0.0))))


def unpinned_words(v) -> str:
    """Why logged commands cannot pin a closed-loop law (:func:`pins_a_law` false), in words:
    "v is 0 on every row, which every law gives while e = 0", "v is only 0 and ±200, which any
    law of high gain gives at that clamp", or "v is free of 0 and ±200 on only 3 rows (10
    needed)".

    Parameters
    ----------
    v : array_like, shape (N,)
        The logged commands, DAC counts.

    Returns
    -------
    str
    """
    v = np.asarray(v, dtype=float)
    v = v[np.isfinite(v)]
    peak = float(np.max(np.abs(v), initial=0.0))
    if peak == 0:
        return "v is 0 on every row, which every law gives while e = 0"
    free = _free_rows(v)
    if not free:
        return f"v is only 0 and ±{peak:g}, which any law of high gain gives at that clamp"
    return f"v is free of 0 and ±{peak:g} on only {free} row{'s' * (free != 1)} ({MIN_FREE_ROWS} needed)"


def no_dac_command(v, theta) -> bool:
    """Whether logged commands can be no DAC command as written: every |v| under one count
    (the device applies whole counts, so 0) while the hub moved. Such a v is written in another
    unit (volts of a converter: a count is 5/2048 V), and a law fitted to it as counts is judged
    with tolerances a thousand times too wide: none is inferred on it.

    Parameters
    ----------
    v, theta : array_like, shape (N,)
        The logged commands (DAC counts, as claimed) and hub angle (encoder counts).
    """
    v, theta = np.asarray(v, dtype=float), np.asarray(theta, dtype=float)
    finite = np.isfinite(theta)
    return bool(v.size) and bool(np.all(np.isfinite(v))) and float(np.max(np.abs(v))) < 1.0 \
        and np.any(v != 0) and np.count_nonzero(finite) > 1 and float(np.ptp(theta[finite])) > 0


class LawRows:
    """The rows of a log as one candidate law sees them: x[k] = Σ b_i e[k-i] − Σ a_j v[k-j]
    with the logged v as the recursion's history (exact for an integer recursion, whose
    history is the logged integer; one step ahead for a float one).

    Parameters
    ----------
    e, v : numpy.ndarray, shape (N,)
        The error u[k] − θ[k-d] (0 for k < d) and the logged command, DAC counts.
    d : int
        The alignment (rows k >= d are the controller's).
    order : int
        0 (P) to :data:`MAX_ORDER`.
    limit : float
        The clamp, DAC counts.
    skip : int
        Rows from d on left out (a copy cut from a longer run: their lags reach before its
        first row).
    restarts : sequence of int
        Rows where the log's ticks jump (:func:`station.runlog.timebase.restart_rows`): the
        rows whose lags reach across a jump are left out
        (:func:`station.control.rerun.judged_rows`).
    """

    def __init__(self, e: np.ndarray, v: np.ndarray, d: int, order: int, limit: float, skip: int = 0,
                 restarts=()):
        self._given = (v, skip, tuple(restarts))  # for the same law's rows at another alignment (at)
        rows = np.arange(d + skip, v.size)
        if len(restarts):
            rows = np.flatnonzero(judged_rows(v.size, d, skip, restarts, order))
        lag = lambda x, j: np.where(rows - j >= 0, x[np.maximum(rows - j, 0)], 0.0)  # noqa: E731
        cols = [lag(e, i) for i in range(order + 1)] + [-lag(v, j) for j in range(1, order + 1)]
        self.X = np.column_stack(cols)
        self.v = v[rows]
        self.order, self.limit = order, float(limit)
        self.clamped = np.abs(self.v) >= self.limit
        printing = printed_commands(v)
        # a float law on a printed v: the row's own printing and its history's (command_error's allowance)
        self.printed = printing is not None
        self.tolerance = np.full(self.v.shape, TOLERANCE) if printing is None else \
            TOLERANCE + print_allowance(v, printing, history=True)[rows]

    def at(self, e: np.ndarray, d: int) -> LawRows:
        """The same log's rows at another alignment: its order, clamp, rows left out and
        restarts as these.

        Parameters
        ----------
        e : numpy.ndarray, shape (N,)
            The error the law sees at alignment ``d``, counts.
        d : int
            The alignment.
        """
        v, skip, restarts = self._given
        return LawRows(e, v, d, self.order, self.limit, skip, restarts)

    def predict(self, c: np.ndarray, recursion: str) -> np.ndarray:
        """The commands the law gives, row by row (its history the logged v).

        Parameters
        ----------
        c : numpy.ndarray, shape (2·order + 1,)
            [b_0..b_m, a_1..a_m].
        recursion : {"none", "trunc", "round"}
        """
        x = self.X @ c
        if recursion == "trunc":
            x = np.trunc(x)
        elif recursion == "round":  # halves away from zero, exactly (station.rounding's rule)
            mag = np.abs(x)
            whole = np.floor(mag)
            x = np.copysign(whole + (mag - whole >= 0.5), x)
        return np.clip(x, -self.limit, self.limit)

    def reproduces(self, c: np.ndarray, recursion: str, slack: float = 0.0) -> bool:
        """Whether ``c`` gives every logged v: exactly for an integer recursion, to
        :data:`TOLERANCE` for a float one (or, for a v printed to fewer digits, to its
        printing and its history's: :func:`station.control.rerun.command_error`).

        Parameters
        ----------
        c : numpy.ndarray, shape (2·order + 1,)
            [b_0..b_m, a_1..a_m].
        recursion : {"none", "trunc", "round"}
        slack : float
            > 0: an integer recursion's x may also sit within ``slack`` counts of its
            interval (where the lab's floating-point arithmetic, not the law, decided which
            integer it stored).
        """
        if recursion != "none" and slack > 0:
            x = self.X @ c
            lo, hi = self.bounds(recursion)
            return bool(np.all((x >= lo - slack) & (x <= hi + slack)))
        dv = np.abs(self.predict(c, recursion) - self.v)
        return bool(np.all(dv == 0.0)) if recursion != "none" else bool(np.all(dv <= self.tolerance))

    def reach(self, c: np.ndarray) -> float:
        """How far, in counts, a float law's fit to whole logged counts may miss a row: the
        count's own truncation or rounding (< 1) and the history's, through the recursion
        (v[k] = x[k] − r[k], |r| < 1, so the residual is −r[k] − Σ a_j r[k−j]): 1 + Σ|a_j|.

        Parameters
        ----------
        c : numpy.ndarray, shape (2·order + 1,)
            [b_0..b_m, a_1..a_m].

        Returns
        -------
        float
            Counts.
        """
        return 1.0 + float(np.sum(np.abs(c[self.order + 1:])))

    def short_of_clamp(self, c: np.ndarray, slack: float) -> np.ndarray:
        """The rows logged at the clamp that the law ``c`` does not reach by more than its
        :meth:`reach` and ``slack``: no clamp of this law (the log's own largest |v| tried as
        a clamp, where that v is a corrupted field).

        Parameters
        ----------
        c : numpy.ndarray, shape (2·order + 1,)
        slack : float
            Counts.

        Returns
        -------
        numpy.ndarray of bool, shape (rows,)
        """
        x = self.X @ c
        return self.clamped & (np.sign(self.v) * x < self.limit - self.reach(c) - slack)

    def least_squares(self, recursion: str) -> np.ndarray | None:
        """Coefficients by least squares over the unclamped rows (for a truncated integer,
        against v + sign(v)/2, the middle of its interval); None with too few rows.

        Parameters
        ----------
        recursion : {"none", "trunc", "round"}
        """
        keep = ~self.clamped
        if np.count_nonzero(keep) < 4 * (2 * self.order + 1) or not np.any(self.X[keep]):
            return None
        target = self.v[keep]
        if recursion == "trunc":
            target = target + 0.5 * np.sign(target)
        c, *_ = np.linalg.lstsq(self.X[keep], target, rcond=None)
        return c if np.all(np.isfinite(c)) else None

    def gain_interval(self, num: np.ndarray, den: np.ndarray, recursion: str,
                      slack: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        """The gains K with which laws K·num[i]/den[i] reproduce every row
        (:data:`station.analysis.continuous_design.GainInterval`).

        Parameters
        ----------
        num, den : numpy.ndarray, shape (L, order+1)
            Unit-gain laws, ascending powers of z⁻¹, ``den[:, 0] = 1``.
        recursion : {"none", "trunc", "round"}
        slack : float
            As :meth:`reproduces`.

        Returns
        -------
        lo, hi : numpy.ndarray, shape (L,)
            lo > hi where no gain does.
        """
        m = self.order + 1
        lo, hi = self.bounds(recursion)
        if recursion != "none":
            lo, hi = lo - slack, hi + slack
        out_lo, out_hi = np.empty(num.shape[0]), np.empty(num.shape[0])
        for start in range(0, num.shape[0], 256):  # rows x laws at a time: bounded memory
            a = self.X[:, :m] @ num[start:start + 256].T
            w = self.X[:, m:] @ den[start:start + 256, 1:].T if m > 1 else np.zeros_like(a)
            with np.errstate(divide="ignore", invalid="ignore"):
                k1, k2 = (lo[:, None] - w) / a, (hi[:, None] - w) / a
            low = np.where(a > 0, k1, np.where(a < 0, k2, -np.inf))
            high = np.where(a > 0, k2, np.where(a < 0, k1, np.inf))
            dead = (a == 0) & ((w < lo[:, None]) | (w > hi[:, None]))  # no gain moves such a row
            low = np.where(np.isnan(low), -np.inf, low)
            high = np.where(np.isnan(high), np.inf, high)
            out_lo[start:start + 256] = np.max(low, axis=0)
            out_hi[start:start + 256] = np.where(np.any(dead, axis=0), -np.inf, np.min(high, axis=0))
        return out_lo, out_hi

    def bounds(self, recursion: str) -> tuple[np.ndarray, np.ndarray]:
        """(lo, hi) of x per row for the logged v: Q(x) = v for an integer recursion, within
        :attr:`tolerance` of v for a float one, or x beyond the clamp.

        Parameters
        ----------
        recursion : {"none", "trunc", "round"}
        """
        v, lim = self.v, self.limit
        if recursion == "none":
            lo = np.where(self.clamped & (v > 0), lim, v - self.tolerance)
            hi = np.where(self.clamped & (v < 0), -lim, v + self.tolerance)
            return np.where(self.clamped & (v < 0), -np.inf, lo), np.where(self.clamped & (v > 0), np.inf, hi)
        if recursion == "trunc":
            lo = np.where(v > 0, v, np.where(v < 0, v - 1.0, -1.0))
            hi = np.where(v > 0, v + 1.0, np.where(v < 0, v, 1.0))
            edge = 0.0
        else:
            lo, hi = v - 0.5, v + 0.5
            edge = 0.5
        lo = np.where(v >= lim, lim - edge, np.where(v <= -lim, -np.inf, lo))
        hi = np.where(v <= -lim, -lim + edge, np.where(v >= lim, np.inf, hi))
        return lo, hi

    def deepest_fit(self, recursion: str) -> np.ndarray | None:
        """Coefficients deepest inside the inequalities the logged v sets (:meth:`bounds`; a
        linear program: maximise the margin t with lo - BOUNDARY + t <= x <= hi + BOUNDARY - t),
        None when there are none: an integer recursion's law, or a float one's where least
        squares on a v printed to few digits (:attr:`tolerance`) misses the band.

        The inequalities are widened by :data:`BOUNDARY`: a law with round numbers (Tustin of
        integer poles and zeros gives rational coefficients) puts some rows' x exactly on a
        whole count or a half, from both sides, so the set of laws that reproduce the log is
        that one law and has no inside; the lab's floating-point arithmetic decided those rows.

        Parameters
        ----------
        recursion : {"none", "trunc", "round"}
        """
        from scipy.optimize import linprog  # lazy: start-up time (scipy.optimize), loaded when an integer recursion, or a float one on a printed v, is looked for

        guess = self.least_squares(recursion)  # the scale of the coefficients (its bias can be several counts)
        if guess is None:
            return None
        lo, hi = self.bounds(recursion)
        lo, hi = lo - BOUNDARY, hi + BOUNDARY
        p = self.X.shape[1]
        bound = 1e3 * max(1.0, float(np.max(np.abs(guess))))

        def deepest(rows: np.ndarray) -> np.ndarray | None:
            up, low = rows & np.isfinite(hi), rows & np.isfinite(lo)
            a_ub = np.vstack([np.column_stack([self.X[up], np.ones(up.sum())]),
                              np.column_stack([-self.X[low], np.ones(low.sum())])])
            cost = np.zeros(p + 1)
            cost[-1] = -1.0
            res = linprog(cost, A_ub=a_ub, b_ub=np.concatenate([hi[up], -lo[low]]),
                          bounds=[(-bound, bound)] * p + [(None, 0.25)], method="highs")
            return None if res.status != 0 or -res.fun <= 0.0 else res.x[:p]

        # the rows least squares misses most first: where they leave no inside, no law is in
        # all of them (a log no law gives, in a few milliseconds rather than a full program)
        x = self.X @ guess
        miss = np.fmax(lo - x, x - hi)
        if miss.size > SCREEN_ROWS:
            worst = np.zeros(miss.size, bool)
            worst[np.argsort(miss)[-SCREEN_ROWS:]] = True
            if deepest(worst) is None:
                return None
        return deepest(np.ones(miss.size, bool))


def tie_rows(rows: LawRows, c: np.ndarray, recursion: str) -> int:
    """How many rows an integer law reproduces only as the lab's floating-point arithmetic
    decided them (x within :data:`BOUNDARY` of a quantization boundary, not exactly on it),
    when it reproduces every other row with the logged integers as its history; 0 when it
    does not (or needs none).

    With its history the stored integer, a law that gives every logged v from the logged
    history gives the log when run on its own: a replay differs only where the last bit of
    the arithmetic (the order of its sums, the discretization's rounding) falls on the other
    side of a boundary, and from there on through its own history. A row whose exact value
    (the coefficients and the row as exact binary fractions) is a boundary has no last bit to
    decide it: the quantization's own rule does.

    Parameters
    ----------
    rows : LawRows
    c : numpy.ndarray, shape (2·order + 1,)
        [b_0..b_m, a_1..a_m].
    recursion : {"none", "trunc", "round"}

    Returns
    -------
    int
        The rows on a boundary (0 for a float recursion).
    """
    if recursion == "none" or not rows.reproduces(c, recursion, BOUNDARY):
        return 0
    x = rows.X @ c
    lo, hi = rows.bounds(recursion)
    near = (np.abs(x - lo) <= BOUNDARY) | (np.abs(x - hi) <= BOUNDARY)
    for k in np.flatnonzero(near):
        # a row whose exact value is a boundary (a whole gain times whole counts) has no last
        # bit to decide it: the quantization's own rule does, and the logged v must follow it
        exact = sum(Fraction(float(ci)) * Fraction(float(xi)) for ci, xi in zip(c, rows.X[k]))
        if exact in (lo[k], hi[k]):
            near[k] = False
    if np.any((rows.predict(c, recursion) != rows.v) & ~near):
        return 0
    return int(np.count_nonzero(near))


SAME_MISS = 1.5
"""An equally simple design is named beside the one nearest a printed v while its squared miss
is within this factor of that one's (:func:`pinned_law`)."""


def _nearest_first(rows: LawRows, design: ContinuousDesign, dt: float) -> ContinuousDesign:
    """Of a design and its equally simple alternatives, the one nearest the printed v
    (least squares over the unclamped rows) first: a v printed to few digits leaves them all
    in its band, and only the true law replays to its last digit."""
    pool = [replace(design, alternatives=(), more=0)] + [d for d in design.alternatives if not d.recursion]
    if len(pool) < 2:
        return design
    keep = ~rows.clamped

    def miss(d: ContinuousDesign) -> float:
        num_z, den_z = d.discretize(dt, rows.order)
        return float(np.sum((rows.X[keep] @ np.concatenate([num_z, den_z[1:]]) - rows.v[keep]) ** 2))

    ranked = sorted((miss(d), i, d) for i, d in enumerate(pool))
    floor = ranked[0][0]
    # kept beside it only where the log cannot tell them apart: the same print noise, its
    # squared miss within SAME_MISS of the best's (a pole 0.05 % off misses 3x here)
    rest = [d for m, _, d in ranked[1:] if m <= SAME_MISS * floor + 1e-12 * rows.v.size]
    others = [d for d in design.alternatives if d.recursion]
    return replace(ranked[0][2], alternatives=tuple(rest + others), more=design.more)


def pinned_law(rows: LawRows, recursion: str, dt: float) -> tuple[np.ndarray, ContinuousDesign | None] | None:
    """The law the rows pin: its coefficients (the nicest numbers that still reproduce every
    row) and its continuous design when one is recognised
    (:func:`station.analysis.continuous_design.recognize`; a first-order one on an integer or
    printed command with its span, :func:`station.analysis.design_doubt.design_span`, whose
    round numbers are tried too); None when no law of the rows' order reproduces them.

    Parameters
    ----------
    rows : LawRows
    recursion : {"none", "trunc", "round"}
    dt : float
        Sample time, s.
    """
    c = rows.least_squares("none") if recursion == "none" else rows.deepest_fit(recursion)
    if recursion == "none" and c is not None and not rows.reproduces(c, recursion) and rows.printed:
        c = rows.deepest_fit(recursion)  # a v printed to few digits: least squares' errors can leave its band
    if c is None or not (rows.reproduces(c, recursion) or tie_rows(rows, c, recursion)):
        return None
    order = rows.order
    if order == 0:  # the gain with the fewest digits among those that reproduce the log
        lo, hi = rows.gain_interval(np.ones((1, 1)), np.ones((1, 1)), recursion)
        nice = nicest_between(float(lo[0]), float(hi[0]), 9)
        if nice is not None and rows.reproduces(np.array([nice[0]]), recursion):
            return np.array([nice[0]]), None
        return c, None

    def interval(num, den):
        return rows.gain_interval(num, den, recursion, BOUNDARY)

    span_of = None  # how far the rows pin a first-order design at all, by a method's map
    if order == 1 and (recursion != "none" or rows.printed):
        lo, hi = rows.bounds(recursion)
        span_of = partial(design_span, rows.X, lo - BOUNDARY, hi + BOUNDARY, dt,
                          box=1e3 * max(1.0, float(np.max(np.abs(c)))))  # deepest_fit's box
    span, within = (None if span_of is None else span_of("Tustin")), None
    if span is not None:  # the family's round numbers, those nearest the fit's roots first
        back = to_continuous(c[:2], np.array([1.0, c[2]]), dt, "Tustin")
        near = (None, None) if back is None or back[0][0] == 0 else (back[0][1] / back[0][0], back[1][1])
        within = {"Tustin": [round_roots(r, MAX_DIGITS, x) for r, x in zip((span.zero, span.pole), near)]}
    design = recognize(c[:order + 1], np.concatenate(([1.0], c[order + 1:])), dt, interval, within=within)
    if design is None:
        return c, None
    if rows.printed and recursion == "none":
        design = _nearest_first(rows, design, dt)
    num_z, den_z = design.discretize(dt, order)
    inside = nudged_inside(rows, np.concatenate([num_z, den_z[1:]]), c, recursion)
    if inside is None:
        return c, None
    if span_of is not None:
        design = replace(design, span=span if design.method == "Tustin" else span_of(design.method))
    return inside, design


def nudged_inside(rows: LawRows, exact: np.ndarray, c: np.ndarray, recursion: str) -> np.ndarray | None:
    """A design's exact coefficients as the rows take them: on a row whose exact value is a
    quantization boundary our discretization's last bit may differ from the lab's, so the law is
    stepped towards ``c`` (one deep inside the rows' inequalities: convex, every row keeps its
    side) by the least of 1e-13..0.1 of the way that reproduces every row.

    Parameters
    ----------
    rows : LawRows
    exact : numpy.ndarray, shape (2·order + 1,)
        The design's discretization, [b_0..b_m, a_1..a_m].
    c : numpy.ndarray, shape (2·order + 1,)
        A law that reproduces the rows (:meth:`LawRows.deepest_fit`).
    recursion : {"none", "trunc", "round"}

    Returns
    -------
    numpy.ndarray or None
        The coefficients; ``exact`` itself where rows sit on a boundary from both sides (the
        replay decides); None when neither reproduces the rows.
    """
    for step in [0.0] + [10.0 ** -k for k in range(13, 0, -1)]:
        nudged = exact + step * (c - exact)
        if rows.reproduces(nudged, recursion):
            return nudged
    if recursion != "none" and rows.reproduces(exact, recursion, BOUNDARY):
        return exact  # rows on a boundary from both sides: the replay decides
    return None
