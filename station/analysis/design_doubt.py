"""What a log leaves open about a recognised design: the equally simple designs that
reproduce it as well (:func:`alternatives_phrase`), and how far its commands pin a
first-order design's zero and pole at all (:class:`DesignSpan`, :func:`design_span`).

A step or a slow sine on the stored integer command often pins a lead only to a family: on
the lab's session with a 26-count sine, every gain-1 Tustin lead with a zero of 6–13 rad/s and
a pole of 30–64 rad/s reproduces every logged integer. The simplest of them is named, and the
span says how far the data pin it, so a reader does not take the name for the data's answer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from station.analysis.continuous_design import _ALPHA, TWO_PI
from station.control.compensator import on_integer

WITHIN = 20
"""Most round numbers of one decade and one count of digits :func:`round_roots` gives; a span
wider than that at those digits pins no number of them."""

def alternatives_phrase(alternatives, method: str, more: int = 0) -> str:
    """What is said after a recognised design that its log does not single out:
    ``" or A or B (ZOH) or C (on the rounded integer) (the log reproduced by each; 2 more as
    simple)"``, empty without alternatives. One text on one integer is said once, with every
    method that gives it (``"D (ZOH or forward Euler)"``).

    Parameters
    ----------
    alternatives : sequence of (str, str, str)
        Each alternative's factored form, method and stored integer
        (:attr:`~station.analysis.continuous_design.ContinuousDesign.alternatives`' ``text``,
        ``method`` and ``recursion``, or their JSON's; "" where the law's).
    method : str
        The recognised design's method: an alternative's is said where it differs.
    more : int
        How many more were found (``ContinuousDesign.more``).

    Returns
    -------
    str
    """
    if not alternatives:
        return ""
    methods: dict[tuple[str, str], list[str]] = {}  # one text on one integer is said once, its methods joined
    for text, m, recursion in alternatives:
        seen = methods.setdefault((text, recursion), [])
        seen += [m] if m not in seen else []
    texts = []
    for (text, recursion), ms in methods.items():
        how = [" or ".join(ms)] if ms != [method] else []
        how += [on_integer(recursion)] if recursion else []
        texts.append(text + (f" ({', '.join(how)})" if how else ""))
    tail = f"; {more} more as simple" if more else ""
    return f" or {' or '.join(texts)} (the log reproduced by each{tail})"


@dataclass(frozen=True)
class DesignSpan:
    """The zeros and poles of every first-order design K(s + z)/(s + p) whose discretization
    reproduces a log (:func:`design_span`): its commands pin z and p no closer.

    Attributes
    ----------
    zero, pole : tuple of float
        (lowest, highest) z and p, rad/s. The bounds of each alone: not every pair inside both
        reproduces the log (z/p is pinned closer than either).
    """

    zero: tuple[float, float]
    pole: tuple[float, float]

    def hull(self, other: DesignSpan | None) -> DesignSpan:
        """The span of both (a law on either stored integer).

        Parameters
        ----------
        other : DesignSpan or None
        """
        if other is None:
            return self
        return DesignSpan((min(self.zero[0], other.zero[0]), max(self.zero[1], other.zero[1])),
                          (min(self.pole[0], other.pole[0]), max(self.pole[1], other.pole[1])))

    def holds(self, zero: float, pole: float, rtol: float = 1e-9) -> bool:
        """Whether a design with this zero and pole (rad/s) lies in the span.

        Parameters
        ----------
        zero, pole : float
            rad/s.
        rtol : float
            Relative slack at the ends.
        """
        inside = lambda x, lo, hi: lo - rtol * abs(lo) <= x <= hi + rtol * abs(hi)  # noqa: E731
        return inside(zero, *self.zero) and inside(pole, *self.pole)

    def wide(self, zero: float, pole: float) -> bool:
        """Whether the span leaves the named zero or pole open: it holds another number with
        as few significant digits, or two where the named has one (a zero of 17 in 15.2–18.5
        rad/s: 16 and 18 as well; a pole of 70 in 67.5–72: 68 and more; 12 in 11.8–12.1: no
        other).

        Parameters
        ----------
        zero, pole : float
            The named design's, rad/s.
        """
        return _another(zero, self.zero) or _another(pole, self.pole)

    def to_json(self) -> dict:
        """``{"zero_rad_s": [lo, hi], "pole_rad_s": [lo, hi]}``."""
        return {"zero_rad_s": list(self.zero), "pole_rad_s": list(self.pole)}

    @classmethod
    def from_json(cls, doc: dict) -> DesignSpan:
        """The span :meth:`to_json` wrote.

        Parameters
        ----------
        doc : dict
            ``{"zero_rad_s": [lo, hi], "pole_rad_s": [lo, hi]}``.
        """
        return cls(tuple(doc["zero_rad_s"]), tuple(doc["pole_rad_s"]))


def _another(x: float, span: tuple[float, float]) -> bool:
    """Whether ``span`` holds a number other than ``x`` with as few significant digits as
    ``x``, and at least two (a person types 68 rad/s as readily as 70)."""
    if not (x > 0 and math.isfinite(x)):
        return span[1] > span[0]
    digits = max(2, next((d for d in range(1, 16) if float(f"{x:.{d}g}") == x), 15))
    unit = 10.0 ** (math.floor(math.log10(x)) - digits + 1)
    first, last = max(math.ceil(span[0] / unit), 1), math.floor(span[1] / unit)
    return last - first >= 1 or (last == first and abs(first * unit - x) > 0.5 * unit)


def span_phrase(design: dict) -> str:
    """``"; the log pins it only to a zero in 6.21–13.4 rad/s and a pole in 30.1–64.2 rad/s
    (...)"``, each end rounded outwards to 3 digits, where the design's span leaves its zero or
    pole open (:meth:`DesignSpan.wide`); empty otherwise.

    Parameters
    ----------
    design : dict
        A first-order design's JSON (:meth:`~station.analysis.continuous_design.ContinuousDesign.to_json`):
        its ``num_s``, ``den_s`` and ``span``.
    """
    span = (design or {}).get("span")
    num, den = (design or {}).get("num_s", ()), (design or {}).get("den_s", ())
    if not span or len(num) != 2 or len(den) != 2 or not num[0]:
        return ""
    span = DesignSpan.from_json(span)
    if not span.wide(num[1] / num[0], den[1]):
        return ""
    return (f"; the log pins it only to a zero in {_outward(span.zero)} rad/s and a pole in {_outward(span.pole)} rad/s"
            " (each alone, over every design that reproduces it)")


def _outward(pair) -> str:
    """lo–hi to 3 significant digits, lo rounded down and hi up."""
    def sig(x: float, up: bool) -> float:
        if x == 0 or not math.isfinite(x):
            return x
        q = 10.0 ** (math.floor(math.log10(abs(x))) - 2)
        return (math.ceil if up else math.floor)(x / q) * q
    return f"{sig(pair[0], False):.3g}–{sig(pair[1], True):.3g}"


def round_roots(span: tuple[float, float], max_digits: int,
                near: float | None = None) -> list[tuple[complex, str, float, float, int, int]]:
    """The roots −x for the round numbers x in a root's span (rad/s, or 2π times Hz), as
    ``continuous_design._forms`` gives them (value, unit, printed real and imaginary parts,
    digits, steps 0), for :func:`~station.analysis.continuous_design.recognize` to try: every
    design whose roots a log admits, not only those near one fit.

    Parameters
    ----------
    span : (float, float)
        Lowest and highest x, rad/s (:attr:`DesignSpan.zero` or :attr:`DesignSpan.pole`).
    max_digits : int
        Most significant digits.
    near : float, optional
        The fit's root, rad/s: the numbers nearest it (by ratio) first, so that of a family's
        equally simple designs the one nearest the fit is named; else lowest first.

    Returns
    -------
    list of tuple
    """
    lo, hi = span
    out = []
    if not (0.0 < hi and math.isfinite(hi) and math.isfinite(lo)):
        return out
    for scale, unit in ((1.0, ""), (TWO_PI, "2π·")):
        a, b = max(lo, 0.0) / scale, hi / scale
        top = math.floor(math.log10(b))
        for digits in range(1, max_digits + 1):
            for decade in range(top - 2 if a <= 0 else math.floor(math.log10(a)), top + 1):
                step = 10.0 ** (decade - digits + 1)
                first = max(math.ceil(a / step - 1e-9), 10 ** (digits - 1))  # an end that is round: inside
                last = min(math.floor(b / step + 1e-9), 10 ** digits - 1)
                if last - first + 1 > WITHIN:
                    continue
                for k in range(first, last + 1):
                    x = float(f"{k * step:.{digits}g}")
                    out.append((complex(-x * scale, 0.0), unit, -x, 0.0, digits + (unit != ""), 0))
    if near is not None and near > 0.0:  # recognize's combos keep this order among equally simple ones
        out.sort(key=lambda f: abs(math.log(-f[0].real / near)))
    return out


def design_span(X: np.ndarray, lo: np.ndarray, hi: np.ndarray, dt: float, method: str,
                box: float) -> DesignSpan | None:
    """The span of a first-order design over every law c = [b0, b1, a1] with lo <= X c <= hi
    (a log's rows, :class:`station.analysis.law_rows.LawRows`): four linear programs. The pole's
    z-root is −a1 (min and max a1); the zero's, −b1/b0, is linear-fractional in c and is
    minimised and maximised as a linear program by the Charnes–Cooper transformation
    (y = tc, t b0 = ±1; Boyd & Vandenberghe, Convex Optimization, 4.3.2).

    Parameters
    ----------
    X : numpy.ndarray, shape (rows, 3)
        The rows' regressors [e[k], e[k−1], −v[k−1]].
    lo, hi : numpy.ndarray, shape (rows,)
        Each row's interval of x (±inf where open).
    dt : float
        Sample time, s.
    method : str
        The design's discretization: Tustin, backward or forward Euler (the others: None).
    box : float
        Bound on |c|: a span that reaches it is not pinned, and None is returned.

    Returns
    -------
    DesignSpan or None
        None where the rows admit no law, b0 changes sign among them, an end reaches ``box``,
        or a root maps across the method's singular point.
    """
    from scipy.optimize import linprog  # lazy: start-up time (scipy.optimize), loaded when a design is recognised

    if method not in _ALPHA or X.ndim != 2 or X.shape[1] != 3:
        return None
    up, low = np.isfinite(hi), np.isfinite(lo)
    a_c = np.vstack([X[up], -X[low]])
    b_c = np.concatenate([hi[up], -lo[low]])
    ends = []
    for sign in (1.0, -1.0):  # a1 least, then most
        res = linprog([0.0, 0.0, sign], A_ub=a_c, b_ub=b_c, bounds=[(-box, box)] * 3, method="highs")
        if res.status != 0 or np.max(np.abs(res.x)) >= 0.99 * box:
            return None
        ends.append(-res.x[2])
    b0 = []
    for s in (1.0, -1.0):  # which sign b0 keeps over the rows' laws (a lead's: its gain's)
        res = linprog([-s, 0.0, 0.0], A_ub=a_c, b_ub=b_c, bounds=[(-box, box)] * 3, method="highs")
        if res.status != 0:
            return None
        b0.append(s * res.x[0])
    if -b0[1] <= 0 <= b0[0]:
        return None  # b0 can be 0: the zero is not pinned
    s = 1.0 if -b0[1] > 0 else -1.0
    # y = t c with t b0 = s (t > 0): lo t <= X y <= hi t, |y| <= box t; −b1/b0 = −s y1
    a_y = np.vstack([np.column_stack([X[up], -hi[up]]), np.column_stack([-X[low], lo[low]]),
                     np.column_stack([np.eye(3), -box * np.ones(3)]), np.column_stack([-np.eye(3), -box * np.ones(3)])])
    zeros = []
    for sense in (1.0, -1.0):
        res = linprog([0.0, -s * sense, 0.0, 0.0], A_ub=a_y, b_ub=np.zeros(a_y.shape[0]),
                      A_eq=[[1.0, 0.0, 0.0, 0.0]], b_eq=[s], bounds=[(None, None)] * 3 + [(0.0, None)],
                      method="highs")
        if res.status != 0 or res.x[3] <= 0 or np.max(np.abs(res.x[:3] / res.x[3])) >= 0.99 * box:
            return None
        zeros.append(-s * res.x[1])
    alpha = _ALPHA[method]
    roots = []
    for pair in (zeros, ends):
        w = [dt * (alpha * r + 1.0 - alpha) for r in pair]
        if min(w) <= 0:
            return None  # across the map's pole (Tustin's z = −1)
        # a root within 1e-4 rad/s of 0 is 0 (an integrator's, z = 1, the rows' boundary slack off)
        s_roots = sorted(0.0 if abs(x) < 1e-4 else x for x in ((1.0 - r) / wi for r, wi in zip(pair, w)))
        roots.append((float(s_roots[0]), float(s_roots[1])))
    return DesignSpan(*roots)
