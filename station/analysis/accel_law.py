"""The accelerometer feedback behind a log's commands, identified from u, θ, a and v.

The rig's two-input law (DESIGN.md "Compensators"): θ̂_d = u − Ga(a), e = θ̂_d − θ,
v = sat(Gth(e)), Gth's recursion on the clamped v, Ga's on its own output. A header that
names open loop, or a lead without its Ga, on such a run leaves :mod:`controller_id`'s
one-input laws e -> v without an answer; this module finds Ga, after which e = u − θ − Ga(a)
is a one-input law's error and :mod:`controller_id` finds Gth (its
nicest numbers, its continuous design) as it does for any lead.

With Gth = B/A of order m and Ga = C/D of order p, on every row whose p predecessors the
clamp did not touch either, multiplying Gth's recursion A·v = B·(w − x) (w = u − θ, x = Ga(a))
through by D gives a law linear in the products' coefficients:

    (AD)·v = (DB)·w − (BC)·a,

an ARX law with two inputs (Ljung, System Identification, 2nd ed., §4.2) of order
N = m + p, exact where the recursion is on the float command. Linear least squares gives
AD, DB and BC; the roots AD shares with DB are D's, the others A's; polynomial division
gives B = DB/D and C = BC/B. Ga's slow poles make those coefficients ill-conditioned, so
they are only a start: D's poles are then searched (:func:`accel_feedback`, variable
projection), and last the law itself with every factor free over every unclamped row
(:func:`scipy.optimize.least_squares`), to the data's last digits (the thesis's Ga to 1e-12
of its design from its 10-digit log).

A recursion on the stored integer is not identified beside Ga here: the least-squares D is
off by enough that no Gth reproduces the integers (on a blind case the deepest linear
program's margin was −0.021 counts at that D, −0.0034 after 400 programs searching D's
poles); beside whole counts :mod:`station.analysis.controller_id` tries the thesis's Ga.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from station.analysis.continuous_design import discretize, to_continuous
from station.rig import DT

LOG_POLE = 40.0
"""Largest |log| of a pole's magnitude (rad/s) a search may step to."""

ARX_SLACK = 1e-6
"""Largest ARX residual of a float recursion's law worth factoring, relative to max |v| (at least 1 count)."""

GIVE_UP_EVALUATIONS = 10
"""Evaluations per parameter after which a search still more than :data:`GIVE_UP_COUNTS` from
some logged v is abandoned (:func:`_give_up`)."""

GIVE_UP_COUNTS = 1.0
"""A search's largest miss of a logged v (DAC counts) past which it is not a law that will
reproduce the log."""


def _give_up(n: int):
    """A :func:`scipy.optimize.least_squares` callback: stop a search of ``n`` parameters still
    more than :data:`GIVE_UP_COUNTS` from some logged v after :data:`GIVE_UP_EVALUATIONS` per
    parameter. Measured over the audit's tests and 210 blind logs (613 searches, 2026-11-29):
    every search that reproduced v (to 1e-6 counts) started within a count of it, every one that
    came within a count did so within 3.5 evaluations per parameter; the searches that came
    nowhere near (a law of the wrong order or alignment) ran to scipy's 100 per parameter and
    took two thirds of the evaluations. The searches that come within a count run as before."""
    def callback(intermediate_result):
        if intermediate_result.nfev >= GIVE_UP_EVALUATIONS * n and \
                np.max(np.abs(intermediate_result.fun)) > GIVE_UP_COUNTS:
            raise StopIteration

    return callback


class AccelFeedback(NamedTuple):
    """An accelerometer feedback Ga found in a log (:func:`accel_feedback`).

    Attributes
    ----------
    num, den : numpy.ndarray
        Ga's z-law, ascending powers of z⁻¹, ``den[0] = 1`` (accelerometer counts to encoder
        counts).
    x : numpy.ndarray, shape (N,)
        Ga(a − a0) on every row (0 before the alignment), encoder counts: e = u − θ − x.
    a0 : float
        The zero the loop took off a before Ga, accelerometer counts (0 unless fitted:
        :func:`accel_feedback`'s ``zero``).
    """

    num: np.ndarray
    den: np.ndarray
    x: np.ndarray
    a0: float = 0.0


def lagged(x: np.ndarray, d: int) -> np.ndarray:
    """``x`` as the controller read it at alignment d: x[k − d] on row k, 0 before.

    Parameters
    ----------
    x : numpy.ndarray, shape (N,)
    d : int
        The alignment, samples (>= 0).
    """
    out = np.zeros(x.size)
    out[d:] = x[:x.size - d]
    return out


def _filter(num: np.ndarray, den: np.ndarray, x: np.ndarray, d: int) -> np.ndarray:
    """The filter num/den run from rest on rows d.. (the controller is not stepped before)."""
    from scipy.signal import lfilter  # lazy: start-up time

    out = np.zeros(x.size)
    out[d:] = lfilter(num, den, x[d:])
    return out


def _columns(x: np.ndarray, rows: np.ndarray, lags: range) -> list[np.ndarray]:
    return [x[rows - j] for j in lags]


def arx_rows_off(u, theta, a, v, d: int, n: int, limit: float, fitted: int) -> np.ndarray | None:
    """The rows of a whole log that the two-input ARX law of total order ``n`` (the products
    AD, DB, BC of the module docstring), fitted on its first ``fitted`` rows, misses past its
    slack: with the logged v as its history a corrupted field's miss spans n + 1 rows.

    Parameters
    ----------
    u, theta, a, v : numpy.ndarray, shape (N,)
        The log's reference, θ, a and v (counts).
    d : int
        The alignment, samples.
    n : int
        The law's total order m + p.
    limit : float
        The clamp, DAC counts (rows at it are not judged).
    fitted : int
        The first rows the law is fitted on.

    Returns
    -------
    numpy.ndarray of int or None
        The rows missed; None when no such law holds on the first rows.
    """
    alpha, w, free = lagged(a, d), np.zeros(v.size), np.abs(v) < limit
    w[d:] = u[d:] - theta[:v.size - d]
    with np.errstate(all="ignore"):
        products = _arx(w[:fitted], alpha[:fitted], v[:fitted], d, n, free[:fitted])
        if products is None:
            return None
        ad, db, bc = products[:3]
        miss = np.convolve(v, ad)[:v.size] - np.convolve(w, db)[:v.size] + np.convolve(alpha, bc)[:v.size]
    judged = np.zeros(v.size, dtype=bool)
    judged[d + n:] = np.all([free[d + n - j:v.size - j] for j in range(n + 1)], axis=0)
    return np.flatnonzero(judged & ~(np.abs(miss) <= ARX_SLACK * max(1.0, float(np.max(np.abs(v[:fitted]))))))


def _arx(w, alpha, v, d: int, n: int, free: np.ndarray, zero: bool = False):
    """The products (AD, DB, BC) of order n by least squares, and the zero a0 the law took
    off a (with ``zero``: a constant column, (BC)(1)·a0; else 0), or None when they do not fit."""
    k = np.arange(d + n, v.size)
    k = k[np.all([free[k - j] for j in range(n + 1)], axis=0)] if k.size else k
    width = 3 * n + 2 + zero
    if k.size < 4 * width:
        return None
    x = np.column_stack(_columns(-v, k, range(1, n + 1)) + _columns(w, k, range(n + 1))
                        + _columns(-alpha, k, range(n + 1)) + ([np.ones(k.size)] if zero else []))
    if not np.any(x[:, n + n + 1:3 * n + 2]):
        return None
    target = v[k]
    c, *_ = np.linalg.lstsq(x, target, rcond=None)
    if not np.all(np.isfinite(c)):
        return None
    slack = ARX_SLACK * max(1.0, float(np.max(np.abs(v))))
    if float(np.max(np.abs(x @ c - target))) > slack:
        return None
    bc = c[2 * n + 1:3 * n + 2]
    if zero:  # a law that holds without a feeds no a back: no zero of a to find
        lone, *_ = np.linalg.lstsq(x[:, :2 * n + 1], target, rcond=None)
        if not np.sum(bc) or float(np.max(np.abs(x[:, :2 * n + 1] @ lone - target))) <= slack:
            return None
    return np.concatenate(([1.0], c[:n])), c[n:2 * n + 1], bc, float(c[-1] / np.sum(bc)) if zero else 0.0


def _factor(ad, db, bc, m: int, p: int):
    """(B, A, C, D) from the products, or None when they do not factor so."""
    from scipy.optimize import linear_sum_assignment  # lazy: start-up time

    if p == 0:
        b, a, d = db, ad, np.ones(1)
    else:
        if abs(db[0]) == 0.0:
            return None
        r_ad, r_db = np.roots(ad), np.roots(db)
        if r_ad.size != m + p or r_db.size < p:
            return None
        dist = np.abs(r_ad[:, None] - r_db[None, :])
        rows, cols = linear_sum_assignment(dist)
        shared = rows[np.argsort(dist[rows, cols])[:p]]  # D's roots: the p AD shares with DB
        d = np.atleast_1d(np.real(np.poly(r_ad[shared])))
        a = np.atleast_1d(np.real(np.poly(np.delete(r_ad, shared))))
        b, _ = np.polydiv(db, d)
    if b.size != m + 1 or abs(b[0]) == 0.0:
        return None
    c, _ = np.polydiv(bc, b)
    c = np.concatenate((np.zeros(p + 1 - c.size), c)) if c.size < p + 1 else c[-(p + 1):]
    return b, a, c, d


def _exp(x: float) -> float:
    """exp within ±:data:`LOG_POLE` (a search's step into nonsense stays finite)."""
    return math.exp(min(max(float(x), -LOG_POLE), LOG_POLE))


def _sign_starts(den_s: np.ndarray) -> list[np.ndarray]:
    """Ga's s-denominator as the products give it, and, where its slowest real pole lies right
    of 0, with that pole's sign turned. :func:`_pole_params` keeps each real pole's sign; on a
    short or printed log the products can put the slowest pole (the thesis's at −0.064 rad/s,
    under a run's 1/T) a hair right of 0, and the polish from there only slides toward an
    integrator (a Ga that stays unstable is refused anyway)."""
    roots = np.roots(den_s)
    real = [i for i, r in enumerate(roots) if abs(r.imag) <= 1e-9 * max(1.0, abs(r))]
    if not real:
        return [den_s]
    slowest = min(real, key=lambda i: abs(roots[i]))
    if roots[slowest].real <= 0.0:
        return [den_s]
    turned = roots.copy()
    turned[slowest] = -turned[slowest].real
    return [den_s, np.real(np.poly(turned)) * den_s[0]]


def _pole_params(den_s: np.ndarray):
    """Ga's s-poles as parameters, and the map back to its monic s-denominator: a real pole
    as log |p| (its sign kept), a complex pair as (log ωn, ζ). Ga's poles span decades (the
    thesis's at −0.064, −3.8 and −22 rad/s: a, integrated, is a position), where its z and
    s coefficients are ill-conditioned and its poles' logarithms are not."""
    roots = np.roots(den_s)
    real = [r.real for r in roots if abs(r.imag) <= 1e-9 * max(1.0, abs(r))]
    pairs = [r for r in roots if r.imag > 1e-9 * max(1.0, abs(r))]
    signs = [1.0 if r > 0 else -1.0 for r in real]
    zero = [r == 0.0 for r in real]
    q = [math.log(abs(r)) if r else 0.0 for r in real]
    for r in pairs:
        q += [math.log(abs(r)), -r.real / abs(r)]

    def den(z):
        out = np.ones(1)
        for i, (sg, z0) in enumerate(zip(signs, zero)):
            out = np.convolve(out, [1.0, 0.0 if z0 else -sg * _exp(z[i])])
        for j in range(len(pairs)):
            wn, zeta = _exp(z[len(real) + 2 * j]), z[len(real) + 2 * j + 1]
            out = np.convolve(out, [1.0, 2.0 * zeta * wn, wn * wn])
        return out

    return np.array(q), den


def accel_feedback(u, theta, a, v, d: int, m: int, p: int, limit: float, dt: float = DT,
                   zero: bool = False) -> AccelFeedback | None:
    """Ga of order ``p`` beside a Gth of order ``m`` that together give the logged v, if any.

    Given Ga's denominator D, the law A·v = B·w − (BC)·(a/D) is linear in A, B and the
    product BC: the polish searches D alone (its poles, :func:`_pole_params`, through
    Tustin's inverse) with the rest solved by least squares at each step (variable
    projection; Golub & Pereyra, SIAM J. Numer. Anal. 10, 1973), and C = BC/B.

    Parameters
    ----------
    u, theta, a, v : numpy.ndarray, shape (N,)
        The log's reference and θ (encoder counts), a (accelerometer counts) and v (DAC counts).
    d : int
        The alignment: row k's command from θ[k − d] and a[k − d].
    m, p : int
        Gth's and Ga's orders (0..3).
    limit : float
        The clamp, DAC counts (rows at it do not hold Gth's law). Gth's recursion is on the
        float command (module docstring: not beside the stored integer).
    dt : float
        Sample time, s (Tustin's inverse of D, for the polish).
    zero : bool
        Fit the zero a0 the loop took off a before Ga as well (a logged as the accelerometer
        read it): the law is A·v = B·w − (BC)·(a − a0)/D, a constant (BC)(1)·a0 in the
        products' least squares, then one more parameter of the polish.

    Returns
    -------
    AccelFeedback or None
        None when the products do not fit (no such law: the usual answer), do not factor, or
        the accelerometer never moved.
    """
    from scipy.optimize import least_squares  # lazy: start-up time
    from scipy.signal import lfilter  # lazy: start-up time

    alpha = lagged(a, d)
    if not np.any(alpha):
        return None
    a0 = 0.0
    w = np.zeros(v.size)
    w[d:] = u[d:] - theta[:v.size - d]
    free = np.abs(v) < limit
    with np.errstate(all="ignore"):  # wrong orders overflow on the way to being refused
        products = _arx(w, alpha, v, d, m + p, free, zero)
        factors = None if products is None else _factor(*products[:3], m, p)
        if factors is None or not all(np.all(np.isfinite(f)) for f in factors):
            return None
        d_ga = factors[3]
        if zero:  # a − a0 from here; the polish refines a0
            a0 = products[3]
            alpha = lagged(a - a0, d)
        k = np.arange(d + m + p, v.size)
        k = k[free[k]]
        target = v[k]
        known = [-v[k - 1 - j] for j in range(m)] + [w[k - i] for i in range(m + 1)]

        def inner(den_z):
            filtered = np.zeros(v.size)
            filtered[d:] = lfilter([1.0], den_z, alpha[d:])
            if not np.all(np.isfinite(filtered)):  # an unstable D on the way: refused
                return np.full(k.size, 1e30), np.zeros(2 * m + p + 2)
            x = np.column_stack(known + [-filtered[k - j] for j in range(m + p + 1)])
            sol, *_ = np.linalg.lstsq(x, target, rcond=None)
            return x @ sol - target, sol

        den_z, den_of, q = d_ga, None, np.zeros(0)
        back = to_continuous(np.ones(1), d_ga, dt, "Tustin") if p else None
        if back is not None and np.all(np.isfinite(back[1])):
            best = None
            for start in _sign_starts(back[1]):  # each parametrization keeps its real poles' signs
                q0, den_s = _pole_params(start)

                def of(q, den_s=den_s):
                    return discretize(np.ones(1), den_s(q), dt, "Tustin")[1]

                fit = least_squares(lambda q, of=of: inner(of(q))[0], q0, method="trf", jac="3-point",
                                    x_scale="jac", xtol=1e-15, ftol=1e-15, gtol=1e-15, callback=_give_up(q0.size))
                if np.all(np.isfinite(fit.x)) and (best is None or fit.cost < best[0]):
                    best = fit.cost, fit.x, of
                if den_of is None:  # the products' own poles, should no polish be finite
                    q, den_of = q0, of
            if best is not None:
                q, den_of = best[1], best[2]
                den_z = den_of(q)
        _, sol = inner(den_z)
        if not (np.all(np.isfinite(sol)) and np.all(np.isfinite(den_z))):
            return None
        a_th, b = sol[:m], sol[m:2 * m + 1]
        if b[0] == 0.0:
            return None
        # C itself (BC/B leaves a remainder): with D and B held, the law is linear in A and C
        den = np.asarray(den_z, float) / den_z[0]
        filtered = np.zeros(v.size)
        filtered[d:] = lfilter(b, den, alpha[d:])
        x = np.column_stack([-v[k - 1 - j] for j in range(m)] + [-filtered[k - j] for j in range(p + 1)])
        sol, *_ = np.linalg.lstsq(x, target - np.column_stack(known[m:]) @ b, rcond=None)
        num = sol[m:]
        if den_of is not None:  # the law itself, every factor free, from there
            n_q = q.size
            w_lags = np.column_stack(known[m:])
            v_lags = np.column_stack(known[:m]) if m else np.zeros((k.size, 0))

            def split(z):
                return (den_of(z[:n_q]), z[n_q:n_q + p + 1], z[n_q + p + 1:n_q + p + m + 2],
                        z[n_q + p + m + 2:n_q + p + 2 * m + 2], z[n_q + p + 2 * m + 2:])

            def law(z):
                dz, cz, bz, az, shift = split(z)
                xa = np.zeros(v.size)
                xa[d:] = lfilter(cz, dz, alpha[d:] - np.sum(shift))
                if not np.all(np.isfinite(xa)):
                    return np.full(k.size, 1e30)
                return w_lags @ bz - np.column_stack([xa[k - i] for i in range(m + 1)]) @ bz + v_lags @ az - target

            z0 = np.concatenate((q, num, b, a_th, [0.0] if zero else []))
            fit = least_squares(law, z0, method="trf", jac="3-point", x_scale="jac", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                                callback=_give_up(z0.size))
            if np.all(np.isfinite(fit.x)) and np.max(np.abs(fit.fun)) < np.max(np.abs(law(z0))):
                dz, num, _, _, shift = split(fit.x)
                den = np.asarray(dz, float) / dz[0]
                if zero:
                    a0 += float(np.sum(shift))
                    alpha = lagged(a - a0, d)
        if p and np.any(np.abs(np.roots(den)) >= 1.0 + 1e-9):
            return None  # an unstable Ga: not a compensator a lab ran
        return AccelFeedback(num, den, _filter(num, den, alpha, d), a0)
