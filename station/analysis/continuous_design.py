"""The continuous design behind a discrete compensator law.

A lab designs its compensator in s (a lead 3(s+13)/(s+20); the thesis's
Gth = 20(s+2π·5)/(s+2π·20)) and discretizes it by Tustin (bilinear), ZOH (step
invariant), backward or forward Euler (Franklin, Powell & Workman, Digital Control of
Dynamic Systems, 3rd ed., ch. 6). :func:`recognize` maps an identified z-law back to s by
each method's inverse, rounds its zeros and poles to the numbers a person types (few
significant digits, in rad/s or as 2π times a frequency in Hz), discretizes each such
design again the same way and keeps the simplest whose discretization reproduces the log
with a gain of few digits (every method is linear in the gain, so the gains that reproduce
the log are an interval the caller computes); the others as simple that reproduce it too are
kept beside it (:attr:`ContinuousDesign.alternatives`): a log may not tell them apart. Coefficients in z are in ascending powers of z⁻¹, ``den[0] = 1``
(:class:`station.control.DiscreteTF`); in s in descending powers, the denominator monic.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, replace
import warnings

import numpy as np
from numpy.polynomial import polynomial as P

from station.control.tf import tustin

METHODS = ("Tustin", "ZOH", "backward Euler", "forward Euler")
"""Discretizations recognised, in the order they are preferred on a tie."""

_ALPHA = {"Tustin": 0.5, "backward Euler": 1.0, "forward Euler": 0.0}
"""The generalized bilinear transform's α of each method but ZOH: s = (z − 1)/(T(αz + 1 − α))."""

MAX_DIGITS = 5
"""Most significant digits a recognised design's numbers may have."""

MAX_ALTERNATIVES = 3
"""Most equally simple designs named beside a recognised one (:attr:`ContinuousDesign.alternatives`)."""

INFINITE_ZERO = 20.0
"""A zero beyond this many times 1/dt rad/s is a zero at infinity (Tustin puts it at z = −1)."""

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class ContinuousDesign:
    """A continuous compensator design and how it was discretized (:func:`recognize`).

    Attributes
    ----------
    num_s, den_s : tuple of float
        Descending powers of s; ``den_s[0] = 1``.
    method : str
        One of :data:`METHODS`.
    text : str
        The factored form, e.g. ``"3(s+13)/(s+20)"`` or ``"20(s+2π·5)/(s+2π·20)"``.
    digits : int
        Significant digits of its numbers (the fewer, the more surely a person typed it).
    alternatives : tuple of ContinuousDesign
        Other designs with no more digits whose discretization reproduces the log as well, at
        most :data:`MAX_ALTERNATIVES`: the log does not tell them apart (a settled step on the
        stored integer command pins a lead's pole only so far).
    more : int
        How many more such designs were found than ``alternatives`` holds.
    recursion : str
        For an alternative only: the stored integer its recursion runs on ("trunc" or
        "round") where it differs from the recognised law's ("": the same); a step on the
        stored integer may be reproduced by a truncating law and a rounding one alike.
    span : DesignSpan or None
        How far the log pins a first-order design's zero and pole, where not closely
        (:class:`station.analysis.design_doubt.DesignSpan`).
    """

    num_s: tuple[float, ...]
    den_s: tuple[float, ...]
    method: str
    text: str
    digits: int
    alternatives: tuple[ContinuousDesign, ...] = ()
    more: int = 0
    recursion: str = ""
    span: object = None

    def discretize(self, dt: float, order: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Its z-law at ``dt`` by its method (:func:`discretize`).

        Parameters
        ----------
        dt : float
            Sample time, s.
        order : int, optional
            The order to write it in: its top taps 0 past its own (a law found at that order
            with a pair cancelled, :func:`recognize`).
        """
        law = discretize(self.num_s, self.den_s, dt, self.method)
        if order is None:
            return law
        return tuple(np.pad(x, (0, max(order + 1 - x.size, 0))) for x in law)

    def describe(self) -> str:
        """One line: the factored form, num/den in s and the method."""
        fmt = lambda c: "[" + ", ".join(f"{x:.6g}" for x in c) + "]"  # noqa: E731
        return f"{self.text} (num {fmt(self.num_s)}, den {fmt(self.den_s)} in s; {self.method})"

    def to_json(self) -> dict:
        """``{"num_s", "den_s", "method", "text", "alternatives", "more_alternatives"}``,
        ``"recursion"`` where an alternative's stored integer differs from the law's, ``"span"``."""
        out = {"num_s": list(self.num_s), "den_s": list(self.den_s), "method": self.method, "text": self.text,
               "alternatives": [d.to_json() for d in self.alternatives], "more_alternatives": self.more}
        if self.recursion:
            out["recursion"] = self.recursion
        if self.span is not None:
            out["span"] = self.span.to_json()
        return out

    def with_alternatives(self, other: ContinuousDesign, recursion: str) -> ContinuousDesign:
        """This design with ``other`` (and its own alternatives), found for a law on another
        stored integer, said beside it: at most :data:`MAX_ALTERNATIVES` in all, those with no
        more digits than this one. The span is both integers' where this design has one; it is
        not taken from ``other`` alone (it would bound another integer's designs, perhaps by
        another method, under this one's name).

        Parameters
        ----------
        other : ContinuousDesign
            The design recognised for the same rows with the recursion on ``recursion``'s integer.
        recursion : str
            "trunc" or "round".

        Returns
        -------
        ContinuousDesign
        """
        found = [replace(d, alternatives=(), more=0, recursion=recursion)
                 for d in (other, *other.alternatives) if d.digits <= self.digits]
        extra = other.more if other.digits <= self.digits else 0
        pool = list(self.alternatives) + found
        span = None if self.span is None else self.span.hull(other.span)
        return replace(self, alternatives=tuple(pool[:MAX_ALTERNATIVES]), span=span,
                       more=self.more + extra + max(len(pool) - MAX_ALTERNATIVES, 0))



def _gbt(num_s, den_s, dt: float, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """s = (z − 1)/(T(αz + 1 − α)) substituted into N(s)/D(s), times (T(αz + 1 − α))^n."""
    num_s, den_s = np.trim_zeros(np.asarray(num_s, float), "f"), np.trim_zeros(np.asarray(den_s, float), "f")
    n = den_s.size - 1
    zm1 = np.array([-1.0, 1.0])                        # z − 1, ascending in z
    w = np.array([dt * (1.0 - alpha), dt * alpha])      # T(αz + 1 − α)

    def sub(c):  # c descending in s, degree <= n
        out = np.zeros(n + 1)
        for k, coef in enumerate(c[::-1]):             # coef of s^k
            term = P.polymul(P.polypow(zm1, k), P.polypow(w, n - k)) * coef
            out[:term.size] += term
        return out

    nz, dz = sub(num_s), sub(den_s)
    nz, dz = nz[::-1], dz[::-1]                         # descending in z = ascending in z^-1
    return nz / dz[0], dz / dz[0]


def discretize(num_s, den_s, dt: float, method: str) -> tuple[np.ndarray, np.ndarray]:
    """A continuous design's z-law.

    Parameters
    ----------
    num_s, den_s : array_like
        Descending powers of s; proper.
    dt : float
        Sample time, s.
    method : str
        One of :data:`METHODS`.

    Returns
    -------
    num_z, den_z : numpy.ndarray, shape (n+1,)
        Ascending powers of z⁻¹, ``den_z[0] = 1``.

    Raises
    ------
    ValueError
        An improper design, an unknown method, a design with a pole the method maps to z = ∞.
    """
    if method == "Tustin":
        return tustin(num_s, den_s, dt)
    if method == "ZOH":
        from scipy.signal import cont2discrete  # lazy: start-up time (scipy.signal), loaded when a design is recognised

        num_z, den_z, _ = cont2discrete((np.asarray(num_s, float), np.asarray(den_s, float)), dt, method="zoh")
        num_z, den_z = np.atleast_1d(np.squeeze(num_z)), np.asarray(den_z, float)
        num_z = np.concatenate([np.zeros(den_z.size - num_z.size), num_z])
        return num_z / den_z[0], den_z / den_z[0]
    if method not in _ALPHA:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    num_z, den_z = _gbt(num_s, den_s, dt, _ALPHA[method])
    if not np.all(np.isfinite(num_z)) or not np.all(np.isfinite(den_z)):
        raise ValueError(f"{method} maps this design's poles to z = infinity")
    return num_z, den_z


def to_continuous(num_z, den_z, dt: float, method: str) -> tuple[np.ndarray, np.ndarray] | None:
    """The continuous design whose ``method`` discretization is the z-law (the inverse map).

    Parameters
    ----------
    num_z, den_z : array_like
        Ascending powers of z⁻¹ (padded to one length), ``den_z[0] = 1``.
    dt : float
        Sample time, s.
    method : str
        One of :data:`METHODS`.

    Returns
    -------
    (num_s, den_s) or None
        Descending powers of s, den monic; None when no real design maps to it (a pole the
        inverse sends to s = ∞, a negative real pole under ZOH, an integrator under ZOH).
    """
    num_z, den_z = np.asarray(num_z, float), np.asarray(den_z, float)
    n = max(num_z.size, den_z.size) - 1
    num_z = np.concatenate([num_z, np.zeros(n + 1 - num_z.size)])
    den_z = np.concatenate([den_z, np.zeros(n + 1 - den_z.size)])
    if method == "ZOH":
        return _zoh_inverse(num_z, den_z, dt)
    alpha = _ALPHA[method]
    # z = (1 + (1 − α) s T)/(1 − α s T), times (1 − α s T)^n
    up, down = np.array([1.0, (1 - alpha) * dt]), np.array([1.0, -alpha * dt])  # ascending in s

    def sub(c):  # c ascending in z^-1: B(z) = sum_j c_j z^(n-j)
        out = np.zeros(n + 1)
        for j, coef in enumerate(c):
            term = P.polymul(P.polypow(up, n - j), P.polypow(down, j)) * coef
            out[:term.size] += term
        return out[::-1]  # descending in s

    ns, ds = sub(num_z), sub(den_z)
    scale = np.max(np.abs(ds))
    if not scale or abs(ds[0]) <= 1e-12 * scale:  # a pole at s = infinity: no proper design
        return None
    return ns / ds[0], ds / ds[0]


def _zoh_inverse(num_z, den_z, dt):
    from scipy.linalg import logm  # lazy: start-up time (scipy)
    from scipy.signal import BadCoefficients, ss2tf, tf2ss  # lazy: start-up time (scipy)

    if num_z.size == 1:
        return None  # a gain: no dynamics to map
    with warnings.catch_warnings():  # a fitted law's b_0 near 0: scipy strips it, and warns to stderr
        warnings.simplefilter("ignore", BadCoefficients)
        ad, bd, c, d = tf2ss(num_z, den_z)
    eig = np.linalg.eigvals(ad)
    if np.any((np.abs(eig.imag) < 1e-12) & (eig.real <= 0)):
        return None  # a negative real z-pole: no real continuous pole is sampled to it
    a = logm(ad) / dt
    if np.max(np.abs(np.imag(a))) > 1e-9 * max(1.0, np.max(np.abs(a))):
        return None
    a = np.real(a)
    m = ad - np.eye(ad.shape[0])
    if np.linalg.cond(m) > 1e12:
        return None  # an integrator (z-pole at 1)
    b = np.linalg.solve(m, a @ bd)
    ns, ds = ss2tf(a, b, c, d)
    return np.asarray(ns, float).ravel(), np.asarray(ds, float)


# --- rounding to what a person types ----------------------------------------------------

def _sig(x: float, digits: int) -> float:
    return float(f"{x:.{digits}g}")


def _roots(num_s, den_s, dt):
    """(gain, zeros, poles) with conjugate pairs as one root (imag > 0); infinite zeros dropped."""
    num = np.trim_zeros(np.asarray(num_s, float), "f")
    scale = np.max(np.abs(num)) if num.size else 0.0
    while num.size > 1 and abs(num[0]) <= 1e-13 * scale:
        num = num[1:]
    gain = float(num[0] / den_s[0]) if num.size else 0.0
    zeros = []
    for z in np.roots(num) if num.size > 1 else []:
        if abs(z) > INFINITE_ZERO / dt:
            gain *= float(-z.real)  # K(s − z) ≈ −K z where the design acts
        else:
            zeros.append(z)
    poles = list(np.roots(den_s)) if len(den_s) > 1 else []
    return gain, _paired(zeros), _paired(poles)


def _paired(roots):
    out = []
    for r in roots:
        if abs(r.imag) <= 1e-9 * max(1.0, abs(r)):
            out.append(complex(r.real, 0.0))
        elif r.imag > 0:
            out.append(complex(r))
    return out


NEIGHBOURS = (0, -1, 1)
"""Steps in the last digit tried around a rounded number: an identified law sits anywhere in
the set of laws that reproduce the log, not necessarily nearest the design a person typed."""


def _near(x: float, digits: int, steps=NEIGHBOURS) -> list[tuple[float, int]]:
    """Numbers of ``digits`` significant digits near ``x``: its rounding and the neighbours
    ``steps`` units of the last digit away (value, |step|); 0 stays 0."""
    base = _sig(x, digits)
    if base == 0.0:
        return [(0.0, 0)]
    unit = 10.0 ** (math.floor(math.log10(abs(base))) - digits + 1)
    out = []
    for k in steps:
        value = _sig(base + k * unit, digits)
        if value != 0.0 and math.copysign(1.0, value) == math.copysign(1.0, base):
            out.append((value, abs(k)))
    return out


def _forms(root: complex, digits: int, steps=NEIGHBOURS) -> list[tuple[complex, str, float, float, int, int]]:
    """A root at ``digits`` significant digits, in rad/s and as 2π times Hz, rounded and its
    neighbours: (value, the printed unit, the printed real and imaginary parts, digits,
    steps away from the rounding)."""
    out = []
    for scale, unit in ((1.0, ""), (TWO_PI, "2π·")):
        ims = _near(root.imag / scale, digits, steps) if root.imag else [(0.0, 0)]
        for re, kre in _near(root.real / scale, digits, steps):
            for im, kim in ims:
                # "2π·" counts as a digit: of two designs a log cannot tell apart, the one in
                # rad/s is preferred unless the one in Hz is rounder (20(s+2π·5)/(s+2π·20))
                out.append((complex(re * scale, im * scale), unit, re, im, digits + (unit != ""), kre + kim))
    return out


def _candidates(root: complex, max_digits: int) -> list[tuple[complex, str, float, float, int, int]]:
    """Every number of :func:`_forms` up to ``max_digits``, each value once at its fewest digits."""
    out, seen = [], set()
    for digits in range(1, max_digits + 1):
        for form in _forms(root, digits):
            if form[0] not in seen:
                seen.add(form[0])
                out.append(form)
    return out


def _factor(form) -> str:
    value, unit, re, im = form[:4]
    if im == 0.0:
        if re == 0.0:
            return "s"
        return f"(s{'+' if re < 0 else '-'}{unit}{abs(re):g})"
    a, b = -2.0 * value.real, abs(value) ** 2  # s^2 + a s + b
    return f"(s^2{'+' if a >= 0 else '-'}{abs(a):.{MAX_DIGITS}g}s+{b:.{MAX_DIGITS}g})"


def _poly(roots) -> np.ndarray:
    out = np.array([1.0])
    for r in roots:
        if r.imag == 0.0:
            out = np.convolve(out, [1.0, -r.real])
        else:
            out = np.convolve(out, [1.0, -2.0 * r.real, abs(r) ** 2])
    return out


MIXED_LIMIT = 4000
"""Most combinations of separately rounded roots tried per method at one level of digits;
beyond it every root is rounded to the same digits, without neighbours."""


def _linear_factor(r: complex, dt: float, alpha: float) -> np.ndarray:
    """(s − r)·T(αz + 1 − α) with s = (z − 1)/(T(αz + 1 − α)): a polynomial in z (descending)."""
    return np.array([1.0 - r * dt * alpha, -(1.0 + r * dt * (1.0 - alpha))], dtype=complex)


def unit_gain_law(zeros, poles, dt: float, method: str) -> tuple[np.ndarray, np.ndarray] | None:
    """The z-law of Π(s − zᵢ)/Π(s − pⱼ) (gain 1; conjugate pairs as one root with imag > 0)
    by ``method``: ascending powers of z⁻¹, one length, ``den[0] = 1``. Every method is
    linear in the design's gain, so K times this is the law of K·Π(s − zᵢ)/Π(s − pⱼ).

    Parameters
    ----------
    zeros, poles : sequence of complex
        Roots, rad/s (a complex one stands for its pair).
    dt : float
        Sample time, s.
    method : str
        One of :data:`METHODS`.

    Returns
    -------
    (num_z, den_z) or None
        None for an improper design or one the method cannot map.
    """
    full = lambda roots: [r for q in roots for r in ((q, q.conjugate()) if q.imag else (q,))]  # noqa: E731
    zs, ps = full(zeros), full(poles)
    n = len(ps)
    if len(zs) > n:
        return None
    if method == "ZOH":
        if n == 0:
            return np.ones(1), np.ones(1)
        if n == 1 and len(zs) <= 1:  # K(s − z)/(s − p) = K + K(p − z)/(s − p), sampled exactly
            p0 = ps[0].real
            e = math.exp(p0 * dt)
            zero = zs[0].real if zs else None
            if p0 == 0.0:
                return None
            if zero is None:  # 1/(s − p)
                return np.array([0.0, (e - 1.0) / p0]), np.array([1.0, -e])
            return np.array([1.0, -e + (p0 - zero) * (e - 1.0) / p0]), np.array([1.0, -e])
        try:
            nz, dz = discretize(_poly(list(zeros)), _poly(list(poles)), dt, "ZOH")
        except (ValueError, np.linalg.LinAlgError):
            return None
        return nz, dz
    alpha = _ALPHA[method]
    num = np.ones(1, dtype=complex)
    for r in zs:
        num = np.convolve(num, _linear_factor(r, dt, alpha))
    for _ in range(n - len(zs)):
        num = np.convolve(num, np.array([dt * alpha, dt * (1.0 - alpha)], dtype=complex))
    den = np.ones(1, dtype=complex)
    for r in ps:
        den = np.convolve(den, _linear_factor(r, dt, alpha))
    num, den = num.real, den.real
    if den[0] == 0.0 or not (np.all(np.isfinite(num)) and np.all(np.isfinite(den))):
        return None
    return num / den[0], den / den[0]


def nicest_between(lo: float, hi: float, max_digits: int = MAX_DIGITS) -> tuple[float, int] | None:
    """The number with the fewest significant digits in [lo, hi] (nearest the middle on a
    tie), and its digits; None when none has at most ``max_digits`` (or lo > hi); never 0.

    Parameters
    ----------
    lo, hi : float
    max_digits : int
    """
    if not (np.isfinite(lo) and np.isfinite(hi)) or lo > hi:
        return None
    mid = 0.5 * (lo + hi)
    top = max(abs(lo), abs(hi))
    if top == 0.0:
        return None
    for digits in range(1, max_digits + 1):
        unit = 10.0 ** (math.floor(math.log10(top)) - digits + 1)
        first, last = math.ceil(lo / unit), math.floor(hi / unit)
        if first > last:
            continue
        k = min(max(round(mid / unit), first), last)
        value = _sig(k * unit, digits)
        if value != 0.0 and lo <= value <= hi:
            return value, digits
        for k in range(first, last + 1):  # 0 in the middle: the next multiple
            value = _sig(k * unit, digits)
            if value != 0.0 and lo <= value <= hi:
                return value, digits
    return None


GainInterval = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]
"""``(N, D) -> (lo, hi)``: for laws K·N[i]/D[i] (rows of unit-gain z-laws, ascending powers
of z⁻¹, ``D[:, 0] = 1``), the gains K with which each reproduces the log (lo > hi: none)."""


def _combos(options, level):
    lists = [[f for f in opts if f[4] <= level] for opts in options]
    if math.prod(len(x) for x in lists) <= MIXED_LIMIT:
        combos = [c for c in itertools.product(*lists) if not c or max(f[4] for f in c) <= level]
        return sorted(combos, key=lambda c: (max((f[4] for f in c), default=0), sum(f[4] for f in c),
                                             sum(f[5] for f in c)))
    return list(itertools.product(*[[f for f in opts if f[4] == level and f[5] == 0] or opts[:1]
                                    for opts in options]))


def recognize(num_z, den_z, dt: float, gain_interval: GainInterval, methods=METHODS,
              max_digits: int = MAX_DIGITS, within=None) -> ContinuousDesign | None:
    """The simplest continuous design whose discretization reproduces a log.

    For each method, the z-law maps back to s (:func:`to_continuous`); its roots are
    rounded (rad/s or 2π·Hz, each to 1..``max_digits`` digits, the rounding and its
    neighbours in the last digit: :data:`NEIGHBOURS`); for each set of rounded roots the
    gains that reproduce the log form an interval (``gain_interval``: every method is linear
    in the gain), in which the number with the fewest digits is the design's gain.

    Parameters
    ----------
    num_z, den_z : array_like
        The identified z-law, ascending powers of z⁻¹ (order >= 1).
    dt : float
        Sample time, s.
    gain_interval : callable
        :data:`GainInterval` of the log.
    methods : sequence of str
        Discretizations tried (:data:`METHODS`).
    max_digits : int
        Most significant digits of a recognised design's numbers.
    within : dict, optional
        For a first-order design's method, the round numbers its zero and pole may be
        (:func:`station.analysis.design_doubt.round_roots`), tried after those near the fit.

    Returns
    -------
    ContinuousDesign or None
        The design whose numbers have the fewest digits (then the first method of
        ``methods``), the others of as few digits that reproduce the log as its
        ``alternatives``; None when none up to ``max_digits`` reproduces the log.
    """
    plans = []
    for method in methods:
        back = to_continuous(num_z, den_z, dt, method)
        if back is None or not (np.all(np.isfinite(back[0])) and np.all(np.isfinite(back[1]))):
            continue
        _, zeros, poles = _roots(back[0], back[1], dt)
        options = [_candidates(r, max_digits) for r in zeros + poles]
        plans.append((method, len(zeros), options, set(), []))
        within_m = (within or {}).get(method, ())
        if len(within_m) == len(options) == 2 and len(zeros) == 1 and all(within_m):
            # the round numbers the log admits anywhere, after those near the fit (the same tried set)
            plans.append((method, 1, within_m, plans[-1][3], []))
    for level in range(1, max_digits + 1):
        found = []  # every design of this level that reproduces the log, the preferred first
        for method, n_zeros, options, tried, open_ in plans:
            combos, laws = [], []
            for combo in _combos(options, level):
                key = tuple(f[0] for f in combo)
                if key in tried:
                    continue
                tried.add(key)
                law = unit_gain_law([f[0] for f in combo[:n_zeros]], [f[0] for f in combo[n_zeros:]], dt, method)
                if law is not None and law[0].size == law[1].size:
                    combos.append(combo)
                    laws.append(law)
            if laws:
                lo, hi = gain_interval(np.array([x[0] for x in laws]), np.array([x[1] for x in laws]))
                # roots tried at a lower level whose gain needs more digits (2.5(s+30)/(s+90)) come first
                open_.extend((combos[i], laws[i], float(lo[i]), float(hi[i])) for i in np.flatnonzero(lo <= hi))
            for combo, law, lo_i, hi_i in open_:
                gain = nicest_between(lo_i, hi_i, level)
                if gain is not None:
                    combo_kept, kept = _cancelled(combo, n_zeros, law, dt, method)
                    found.append(_design(gain[0], combo_kept, kept, method, max(gain[1], *(f[4] for f in combo))))
        if found:
            best = found[0]
            others = {(d.text, d.method): d for d in found[1:] if d.digits <= best.digits}
            return replace(best, alternatives=tuple(others.values())[:MAX_ALTERNATIVES],
                           more=max(len(others) - MAX_ALTERNATIVES, 0))
    return None


def _cancelled(combo, n_zeros: int, law, dt: float, method: str) -> tuple[tuple, int]:
    """A zero and a pole at one root, said without the pair where the law is then the same
    z-law with its top taps 0 (Tustin's (s + 2/dt)/(s + 2/dt): a law of one order less written
    in the rows' order); elsewhere a pair cancels in s but not in the recursion, and is kept."""
    zs, ps = list(combo[:n_zeros]), list(combo[n_zeros:])
    for z in list(zs):
        p = next((q for q in ps if q[0] == z[0]), None)
        if p is None:
            continue
        rz, rp = [f for f in zs if f is not z], [f for f in ps if f is not p]
        reduced = unit_gain_law([f[0] for f in rz], [f[0] for f in rp], dt, method)
        if reduced is not None and all(np.allclose(np.pad(r, (0, x.size - r.size)), x, rtol=1e-12, atol=1e-15)
                                       for r, x in zip(reduced, law)):
            zs, ps = rz, rp
    return tuple(zs + ps), len(zs)


def _design(k: float, combo, n_zeros: int, method: str, digits: int) -> ContinuousDesign:
    zs, ps = combo[:n_zeros], combo[n_zeros:]
    num = k * _poly([f[0] for f in zs])
    den = _poly([f[0] for f in ps])
    top, bottom = "".join(_factor(f) for f in zs), "".join(_factor(f) for f in ps)
    if len(ps) > 1:
        bottom = f"({bottom})"
    text = f"{k:g}{top}" + (f"/{bottom}" if ps else "")
    return ContinuousDesign(tuple(num.tolist()), tuple(den.tolist()), method, text, digits)
