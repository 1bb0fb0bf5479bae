"""Discrete transfer functions in z^-1 and Tustin discretization.

A :class:`DiscreteTF` is one direct-form (I) recursion

    y[k] = b0 x[k] + b1 x[k-1] + ... + bm x[k-m] - a1 y[k-1] - ... - an y[k-n]

with its own input and output histories. The output history holds the outputs the
caller *committed*, which lets a compensator feed its saturated command back into the
recursion (anti-windup, DESIGN.md "Compensators").

The per-sample methods use plain Python floats and lists, not numpy: they run inside
the 500 Hz real-time loop, where numpy's per-call overhead would dominate.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence

import numpy as np
from station.rig import DT


class DiscreteTF:
    """A discrete transfer function b(z^-1)/a(z^-1) with its own state.

    Parameters
    ----------
    num, den : sequence of float
        Coefficients of ascending powers of z^-1: ``num = [b0, b1, ..., bm]``,
        ``den = [a0, a1, ..., an]``. When both have the same length this is the same
        as descending powers of z (what :func:`tustin` and ``control.c2d`` return).
        Both are divided by ``a0`` so that ``den[0] == 1``.

    Attributes
    ----------
    num, den : numpy.ndarray, shape (m+1,), (n+1,)
        The normalized coefficients (read-only copies; the recursion uses its own).

    Raises
    ------
    ValueError
        If a coefficient list is empty, not finite, or ``den[0] == 0``.
    """

    __slots__ = ("_b0", "_b", "_a", "_x", "_y", "_acc", "num", "den")

    def __init__(self, num: Sequence[float], den: Sequence[float]):
        num_a = np.atleast_1d(np.asarray(num, dtype=float))
        den_a = np.atleast_1d(np.asarray(den, dtype=float))
        if num_a.ndim != 1 or den_a.ndim != 1 or num_a.size == 0 or den_a.size == 0:
            raise ValueError("num and den must be non-empty 1-D coefficient lists")
        if not (np.all(np.isfinite(num_a)) and np.all(np.isfinite(den_a))):
            raise ValueError("num and den must be finite numbers")
        if den_a[0] == 0.0:
            raise ValueError("den[0] must not be zero (the recursion would be non-causal)")
        num_a = num_a / den_a[0]
        den_a = den_a / den_a[0]
        num_a.setflags(write=False)
        den_a.setflags(write=False)
        self.num = num_a
        self.den = den_a
        self._b0 = float(num_a[0])
        self._b = [float(c) for c in num_a[1:]]
        self._a = [float(c) for c in den_a[1:]]
        self._x = [0.0] * len(self._b)
        self._y = [0.0] * len(self._a)
        self._acc = 0.0

    def reset(self) -> None:
        """Zero the input and output histories (the filter at rest)."""
        self._x = [0.0] * len(self._b)
        self._y = [0.0] * len(self._a)
        self._acc = 0.0

    def output(self, x: float) -> float:
        """The output for input ``x`` now, without changing the state.

        Parameters
        ----------
        x : float
            The input sample x[k].

        Returns
        -------
        float
            y[k] = b0 x[k] + (the contribution of the committed history).
        """
        return self._b0 * x + self._acc

    def commit(self, x: float, y: float) -> None:
        """Push input ``x`` and the output ``y`` actually used (e.g. after saturation).

        Parameters
        ----------
        x : float
            The input x[k] given to :meth:`output`.
        y : float
            The output to remember as y[k]; the saturated value for anti-windup.
        """
        xs = self._x
        ys = self._y
        if xs:
            xs.pop()
            xs.insert(0, x)
        if ys:
            ys.pop()
            ys.insert(0, y)
        acc = 0.0
        for b, xv in zip(self._b, xs):
            acc += b * xv
        for a, yv in zip(self._a, ys):
            acc -= a * yv
        self._acc = acc

    def step(self, x: float) -> float:
        """One sample without output limiting: ``y = output(x); commit(x, y)``.

        Parameters
        ----------
        x : float
            The input sample x[k].

        Returns
        -------
        float
            The output y[k].
        """
        y = self._b0 * x + self._acc
        self.commit(x, y)
        return y

    def dc_gain(self) -> float:
        """Steady-state (DC) gain.

        Returns
        -------
        float
            b(1)/a(1), i.e. sum(num)/sum(den); ``inf`` (signed) for a pole at z = 1,
            NaN for 0/0.
        """
        a1 = float(np.sum(self.den))
        b1 = float(np.sum(self.num))
        if a1 == 0.0:
            return math.copysign(math.inf, b1) if b1 else math.nan
        return b1 / a1

    def __repr__(self) -> str:
        return f"DiscreteTF(num={self.num.tolist()}, den={self.den.tolist()})"


def tustin(num_s: Sequence[float], den_s: Sequence[float], dt: float = DT) -> tuple[np.ndarray, np.ndarray]:
    """Discretize a continuous transfer function by Tustin's (bilinear) method.

    The rig's compensators are the Tustin discretizations of their continuous designs at
    dt = 0.002 s (DESIGN.md "Compensators").

    Parameters
    ----------
    num_s, den_s : sequence of float
        Coefficients of descending powers of s; proper (``len(num_s) <= len(den_s)``).
    dt : float
        Sample time, s.

    Returns
    -------
    num_z, den_z : numpy.ndarray, shape (n+1,)
        Coefficients of descending powers of z (equivalently ascending powers of z^-1,
        both of length n+1 where n = len(den_s) - 1), normalized so ``den_z[0] == 1``.

    Raises
    ------
    ValueError
        If the design is improper, not finite, or ``dt`` is not positive.
    """
    num_s = np.atleast_1d(np.asarray(num_s, dtype=float))
    den_s = np.atleast_1d(np.asarray(den_s, dtype=float))
    if not dt > 0:
        raise ValueError(f"dt must be positive, got {dt}")
    if num_s.size == 0 or den_s.size == 0 or not (np.all(np.isfinite(num_s)) and np.all(np.isfinite(den_s))):
        raise ValueError("num_s and den_s must be non-empty lists of finite numbers")
    lead = np.flatnonzero(den_s)  # (np.trim_zeros: 60 µs of a tustin called thousands of times a fit)
    if lead.size == 0:
        raise ValueError("den_s must not be all zeros")
    den_s = den_s[lead[0]:]
    if num_s.size > den_s.size:
        num_s = np.trim_zeros(num_s, "f")
        if num_s.size > den_s.size:
            raise ValueError("the continuous design is improper (numerator degree > denominator degree)")
    n = den_s.size - 1
    num_s = np.concatenate([np.zeros(n + 1 - num_s.size), num_s])
    num_z, den_z = np.zeros(n + 1), np.zeros(n + 1)
    for j, term in enumerate(_bilinear_powers(n, float(dt))):
        num_z += num_s[n - j] * term
        den_z += den_s[n - j] * term
    return num_z / den_z[0], den_z / den_z[0]


@functools.lru_cache(maxsize=32)
def _bilinear_powers(n: int, dt: float) -> tuple[np.ndarray, ...]:
    """What each power s^j (j = 0..n) becomes under s = c (z − 1)/(z + 1), c = 2/dt, times
    (z + 1)^n: c^j (z − 1)^j (z + 1)^(n − j), descending powers of z (numpy's polynomials;
    scipy.signal takes a second to import). Cached: an identification discretizes thousands of
    candidate denominators of one order (:mod:`station.analysis.accel_law`)."""
    c = 2.0 / dt
    terms = []
    for j in range(n + 1):
        term = np.polynomial.polynomial.polypow([-1.0, 1.0], j)[::-1] * c**j
        term = np.convolve(term, np.polynomial.polynomial.polypow([1.0, 1.0], n - j)[::-1])
        term.flags.writeable = False
        terms.append(term)
    return tuple(terms)
