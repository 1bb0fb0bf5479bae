"""Laws whose recursion ran on the float while the whole count it sent was logged
(:data:`station.control.compensator.SENT`): lab software that logs what it sends.

The float such a law remembers is not in the log, so no regression on the logged counts gives
its coefficients to the quantization (least squares with the counts as the history put the
thesis lead's b0 at 18.16 against 18.33, and a blind lead's pole 6 % off, past the round
number's neighbours). The law's own float run fitted to the counts (:func:`output_error`)
gives poles and zeros near enough to recognise the round numbers of a continuous design
(:func:`station.analysis.continuous_design.recognize`); with the poles fixed the remembered
float is affine in the gain, so every row bounds the gain exactly (:func:`sent_gain_interval`).
:func:`sent_designs` gives the candidates; :mod:`station.analysis.controller_id` accepts one
only when its replay gives every logged v. A law with no round numbers behind it is not
found this way.
"""

from __future__ import annotations

from collections.abc import Iterator

import numpy as np

from station.analysis.continuous_design import ContinuousDesign, recognize
from station.analysis.law_rows import LawRows
from station.control.compensator import STORED


def _clamped_loop(e, num, den, limit, d):  # pragma: no cover - compiled by numba
    x = np.zeros(e.size)
    m = num.size - 1
    for k in range(d, e.size):
        acc = 0.0
        for i in range(min(m, k) + 1):
            acc += num[i] * e[k - i]
        for j in range(1, min(m, k - d) + 1):
            acc -= den[j] * x[k - j]
        x[k] = min(max(acc, -limit), limit)
    return x


_MAX = float(np.finfo(float).max)  # numpy.nan_to_num's stand-in for an infinite bound


def _interval_loop(e, v, d, limit, edge, trunc, num, den, k_ref, has_ref):  # pragma: no cover - compiled by numba
    n_laws, n_num, n_den = num.shape[0], num.shape[1], den.shape[1]
    order = max(n_num, n_den) - 1
    lo_out, hi_out = np.empty(n_laws), np.empty(n_laws)
    for law in range(n_laws):
        alpha, beta = np.zeros(max(order, 1)), np.zeros(max(order, 1))  # x[k-1..k-order] = alpha·K + beta
        lo_k, hi_k = -np.inf, np.inf
        for k in range(d, v.size):
            g = 0.0
            for i in range(n_num):
                if k - i >= 0:
                    g += num[law, i] * e[k - i]
            acc_a, acc_b = 0.0, 0.0
            for j in range(1, n_den):
                acc_a += den[law, j] * alpha[j - 1]
                acc_b += den[law, j] * beta[j - 1]
            a_y, b_y = g - acc_a, -acc_b
            vk = v[k]
            if vk >= limit or vk <= -limit:  # y beyond the limit (less the rounding's half count)
                s = 1.0 if vk > 0 else -1.0
                lo, hi = (limit - edge, np.inf) if s > 0 else (-np.inf, -limit + edge)
                clamped = True
                if edge:  # within half a count of it, the float is remembered as it is
                    bounded = np.isfinite(lo_k) and np.isfinite(hi_k)
                    guess = k_ref[law] if has_ref else 0.5 * (lo_k + hi_k)
                    if bounded:  # numpy.clip's minimum(maximum(guess, lo), hi), NaN kept
                        ref = guess if guess != guess or guess >= lo_k else lo_k
                        ref = ref if ref != ref or ref <= hi_k else hi_k
                    else:
                        ref = k_ref[law] if has_ref else 0.0
                    beyond_lo = s * (a_y * (lo_k if bounded else ref) + b_y) >= limit
                    beyond_hi = s * (a_y * (hi_k if bounded else ref) + b_y) >= limit
                    clamped = beyond_lo if beyond_lo == beyond_hi else s * (a_y * ref + b_y) >= limit
                x_a, x_b = (0.0, s * limit) if clamped else (a_y, b_y)
            else:
                if not trunc:
                    lo, hi = vk - 0.5, vk + 0.5
                elif vk > 0:
                    lo, hi = vk, vk + 1.0
                elif vk < 0:
                    lo, hi = vk - 1.0, vk
                else:
                    lo, hi = -1.0, 1.0
                x_a, x_b = a_y, b_y
            low, high = -np.inf, np.inf
            if a_y > 0:
                low, high = (lo - b_y) / a_y, (hi - b_y) / a_y
            elif a_y < 0:
                low, high = (hi - b_y) / a_y, (lo - b_y) / a_y
            # numpy.nan_to_num's rule: NaN no bound, an infinite one the largest float
            low = -np.inf if low != low else (_MAX if low == np.inf else (-_MAX if low == -np.inf else low))
            high = np.inf if high != high else (_MAX if high == np.inf else (-_MAX if high == -np.inf else high))
            dead = (a_y == 0 and (b_y < lo or b_y > hi)) or not np.isfinite(a_y) or not np.isfinite(b_y)
            lo_k = low if low > lo_k else lo_k
            hi_k = -np.inf if dead else (high if high < hi_k else hi_k)
            for j in range(order - 1, 0, -1):
                alpha[j], beta[j] = alpha[j - 1], beta[j - 1]
            alpha[0], beta[0] = x_a, x_b
        lo_out[law], hi_out[law] = lo_k, hi_k
    return lo_out, hi_out


_COMPILED: dict = {}  # each loop compiled by numba (or plain Python without it), made on first use


def _compiled(loop):
    """``loop`` compiled by numba, once (plain Python without numba)."""
    if loop not in _COMPILED:
        try:
            import numba  # lazy: start-up time (numba compiles the loop on first use)
        except ImportError:  # pragma: no cover - numba is a dependency; plain Python without it
            _COMPILED[loop] = loop
        else:
            _COMPILED[loop] = numba.njit(cache=True, nogil=True, error_model="numpy")(loop)
    return _COMPILED[loop]


def clamped_float(e: np.ndarray, c: np.ndarray, order: int, limit: float, d: int) -> np.ndarray:
    """x[k] = sat(Σ b_i e[k-i] − Σ a_j x[k-j]) from rest at row d: what a recursion on the
    float remembers (the recursion row by row, compiled by numba: an output-error fit runs it
    thousands of times).

    Parameters
    ----------
    e : numpy.ndarray, shape (N,)
        The error, encoder counts (0 before d).
    c : numpy.ndarray, shape (2·order + 1,)
        [b_0..b_m, a_1..a_m].
    order : int
    limit : float
        The clamp, DAC counts.
    d : int
        The alignment: rows before it are 0.

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    num = np.ascontiguousarray(c[:order + 1], dtype=float)
    den = np.concatenate(([1.0], np.asarray(c[order + 1:], dtype=float)))
    return _compiled(_clamped_loop)(np.ascontiguousarray(e, dtype=float), num, den, float(limit), int(d))


def output_error(e: np.ndarray, v: np.ndarray, d: int, order: int, limit: float, c: np.ndarray,
                 stored: str) -> tuple[np.ndarray, float]:
    """The law whose own float run is closest to the middle of the floats the logged whole
    counts allow (``stored``: v + sign(v)/2 truncated, v rounded; least squares on the rows
    inside the clamp, from ``c``): least squares with the logged integers as the history
    biases the poles by their rounding (a lead's pole 6 % off, past the round number's
    neighbours), the law's own history does not.

    Parameters
    ----------
    e : numpy.ndarray, shape (N,)
        The error, encoder counts (0 before d).
    v : numpy.ndarray, shape (N,)
        The logged commands, whole DAC counts.
    d : int
        The alignment.
    order : int
    limit : float
        The clamp, DAC counts.
    c : numpy.ndarray, shape (2·order + 1,)
        The start, [b_0..b_m, a_1..a_m] (least squares on the counts).
    stored : {"trunc", "round"}
        How the command was made whole.

    Returns
    -------
    (numpy.ndarray, float)
        The law (``c`` itself when the fit fails) and its largest distance, counts, from the
        middles on the rows inside the clamp (at most 1/2 for the law that made the counts,
        its coefficients exact; inf when the fit fails).
    """
    from scipy.optimize import least_squares  # lazy: start-up time

    inside = np.abs(v[d:]) < limit
    if not np.any(inside):
        return c, np.inf
    middle = v[d:] + (0.5 * np.sign(v[d:]) if stored == "trunc" else 0.0)

    def resid(p):
        return (clamped_float(e, p, order, limit, d)[d:] - middle)[inside]

    try:
        fit = least_squares(resid, c, x_scale=np.maximum(np.abs(c), 1e-3), max_nfev=60 * c.size)
    except (ValueError, FloatingPointError):
        return c, np.inf
    if not np.all(np.isfinite(fit.x)) or not np.all(np.isfinite(fit.fun)):
        return c, np.inf
    return fit.x, float(np.max(np.abs(fit.fun)))


SENT_MISS = 2.0
"""Counts the law's own float run, fitted to the middles the logged counts allow, may stray
from them (1/2 for the exact law; its fitted coefficients' error on top) before the law is
taken as not the one that made the log."""

SENT_SLACK = 0.5
"""Counts a float law's least-squares residual on the logged whole counts may exceed its
quantization's reach by (its coefficients' bias) before the log is taken as no such law."""


def _gain_guess(c: np.ndarray, num: np.ndarray) -> np.ndarray:
    """Each unit law's gain near the fitted law ``c``, from its largest numerator coefficient
    (a ZOH law's first is 0)."""
    idx = np.argmax(np.abs(num), axis=1)
    return c[idx] / num[np.arange(num.shape[0]), idx]


def sent_designs(rows: LawRows, e: np.ndarray, v: np.ndarray, d: int, dt: float
                 ) -> Iterator[tuple[ContinuousDesign, str]]:
    """The continuous designs (and their recursion, "float-trunc" or "float-round") whose
    float run, its whole count sent, may have made the logged v: recognised from the law's
    own float run fitted to the counts, each gain the rows' exact bounds allow.

    Parameters
    ----------
    rows : LawRows
        The log's rows for one order, alignment and clamp (the logged counts as history).
    e : numpy.ndarray, shape (N,)
        The error u[k] − θ[k-d] (less Ga(a) beside an accelerometer feedback), encoder counts.
    v : numpy.ndarray, shape (N,)
        The logged commands, whole DAC counts.
    d : int
        The alignment.
    dt : float
        Sample time, s.

    Yields
    ------
    (ContinuousDesign, str)
        Truncated first; none when the counts' least-squares residual is past what whole
        counts make (a log no such law made), or the law's own run strays from them.
    """
    c = rows.least_squares("none")
    if c is None:
        return
    order = rows.order
    # the float law explains the logged integers to their quantization (and the fit's bias) or
    # is not this law: a log no law made is not searched for designs (18 s a log)
    keep = ~rows.clamped
    resid = rows.v[keep] - rows.X[keep] @ c
    reach = rows.reach(c)
    if not resid.size or np.max(np.abs(resid)) > reach + SENT_SLACK or np.sqrt(np.mean(resid ** 2)) > 0.5 * reach:
        return
    # one corrupted v as the log's largest |v|, tried as a clamp, sent a P log here for 90 s
    if np.any(rows.short_of_clamp(c, SENT_SLACK)):
        return
    first = c
    for stored in STORED:
        c, miss = output_error(e, v, d, order, rows.limit, first, stored)
        if miss > SENT_MISS:  # its own float run strays from the counts: not this law
            continue

        def interval(num, den, stored=stored, c=c):
            return sent_gain_interval(e, v, d, rows.limit, stored, num, den, _gain_guess(c, num))

        design = recognize(c[:order + 1], np.concatenate(([1.0], c[order + 1:])), dt, interval)
        if design is not None:
            yield design, f"float-{stored}"


def sent_gain_interval(e: np.ndarray, v: np.ndarray, d: int, limit: float, stored: str, num: np.ndarray,
                       den: np.ndarray, k_ref: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The gains K with which laws K·num[i]/den[i], their recursion on the clamped float and the
    whole count sent (:data:`station.control.compensator.SENT`), give every logged v.

    The float the recursion remembers is not in the log, but with the law's poles fixed it is
    affine in K, x[k] = α[k]·K + β[k], row by row (a clamped row resets it to ±limit); each
    row's Q(x[k]) = v[k] then bounds K from both sides, and the rows together give an
    interval, for every law at once. A row at ±limit is clamped for a truncated command; for
    a rounded one it may be a float within half a count of the limit: clamped where every
    gain left would clamp it, else as ``k_ref`` (within the gains left; their middle without
    it) would (the replay decides).

    Parameters
    ----------
    e : numpy.ndarray, shape (N,)
        The error u[k] − θ[k-d] (0 for k < d), encoder counts.
    v : numpy.ndarray, shape (N,)
        The logged commands, whole DAC counts.
    d : int
        The alignment.
    limit : float
        The clamp, DAC counts.
    stored : {"trunc", "round"}
        How the command was made whole.
    num, den : numpy.ndarray, shape (L, order+1)
        Unit-gain laws, ascending powers of z⁻¹, ``den[:, 0] = 1``.
    k_ref : numpy.ndarray, shape (L,), optional
        A gain near each law's (e.g. its first coefficient from least squares), for the
        rounded command's rows at the limit before any row bounds the gain.

    Returns
    -------
    lo, hi : numpy.ndarray, shape (L,)
        lo > hi where no gain does.
    """
    num = np.ascontiguousarray(np.atleast_2d(num), dtype=float)
    den = np.ascontiguousarray(np.atleast_2d(den), dtype=float)
    ref = np.zeros(num.shape[0]) if k_ref is None else np.ascontiguousarray(np.broadcast_to(k_ref, num.shape[:1]),
                                                                              dtype=float)
    return _compiled(_interval_loop)(np.ascontiguousarray(e, dtype=float), np.ascontiguousarray(v, dtype=float),
                                     int(d), float(limit), 0.0 if stored == "trunc" else 0.5, stored == "trunc",
                                     num, den, ref, k_ref is not None)
