"""Reference shapers: the reference the controller sees is a sum of delayed, scaled copies of u.

A shaper (input shaping, Singer & Seering 1990) is a train of impulses at times t_i with
amplitudes A_i (Σ A_i = 1, so a step still ends at its height): the controller's reference
at tick k is

    r[k] = Σ_i A_i · u[k − n_i],   n_i = round(t_i / dt)

with u = 0 before the controller's first step (the filter starts at rest, as Gth and Ga
do). A compensator file holds it as ``[shaper] times = [...] (s), amplitudes = [...]``
(DESIGN.md "Designing a compensator on a model"); its times are rounded to the sample grid
(whole samples: a shaper acts once per tick). The sum runs in the impulses' order,
``0.0 + A_0 u[k − n_0] + A_1 u[k − n_1] + ...``, by :meth:`ReferenceShaper.step` (the
real-time loop, replay) and :meth:`ReferenceShaper.apply` (the compiled simulation's whole
reference at once) alike, so both give the same floats.

:func:`zv_shaper` and :func:`zvd_shaper` are the standard zero-vibration shapers for a
mode of natural frequency f and damping ratio ζ (Singer & Seering, "Preshaping command
inputs to reduce system vibration", J. Dyn. Sys. Meas. Control 112, 1990): with the damped
period T_d = 1/(f √(1 − ζ²)) and K = exp(−ζπ/√(1 − ζ²)),
ZV: t = [0, T_d/2], A = [1, K]/(1 + K); ZVD: t = [0, T_d/2, T_d], A = [1, 2K, K²]/(1 + K)².

Imports only :mod:`station.errors`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from station.errors import StationError
from station.rig import DT

SUM_TOLERANCE = 1e-6
"""How far Σ amplitudes may be from 1 (a file's printed digits), absolute."""

MAX_IMPULSES = 16
"""Most impulses a shaper may have."""

MAX_TIME_S = 10.0
"""Latest impulse time, s (a shaper delays the reference by at most this)."""


class ShaperTimes(NamedTuple):
    """Impulse times and amplitudes as a compensator file gives them (:func:`check_shaper`).

    Attributes
    ----------
    times : tuple of float
        Impulse times, s, increasing, the first ≥ 0.
    amplitudes : tuple of float
        Their amplitudes, summing to 1.
    """

    times: tuple[float, ...]
    amplitudes: tuple[float, ...]


class ReferenceShaper:
    """A reference shaper on the sample grid: r[k] = Σ A_i u[k − n_i], at rest before the first step.

    Parameters
    ----------
    delays : sequence of int
        n_i, samples, ≥ 0 and increasing.
    amplitudes : sequence of float
        A_i, finite, same length as ``delays``.
    dt : float
        Sample time, s (the spec records t_i = n_i·dt).

    Attributes
    ----------
    delays : tuple of int
    amplitudes : tuple of float
    dt : float
    spec : dict
        ``{"times": [s], "amplitudes": [...], "delays": [samples]}`` for log headers
        (:func:`shaper_from_spec` rebuilds it).

    Raises
    ------
    ValueError
        Mismatched lengths, no impulse, a negative or non-increasing delay, a non-finite amplitude.
    """

    def __init__(self, delays: Sequence[int], amplitudes: Sequence[float], dt: float = DT):
        delays = tuple(int(n) for n in delays)
        amplitudes = tuple(float(a) for a in amplitudes)
        if not delays or len(delays) != len(amplitudes):
            raise ValueError(f"a shaper needs as many delays as amplitudes (at least one), got "
                             f"{len(delays)} and {len(amplitudes)}")
        if delays[0] < 0 or any(b <= a for a, b in zip(delays, delays[1:])):
            raise ValueError(f"shaper delays must be >= 0 and increasing, got {list(delays)}")
        if not all(math.isfinite(a) for a in amplitudes):
            raise ValueError(f"shaper amplitudes must be finite, got {list(amplitudes)}")
        self.delays = delays
        self.amplitudes = amplitudes
        self.dt = float(dt)
        self._pairs = tuple(zip(delays, amplitudes))
        self._history = [0.0] * (delays[-1] + 1)  # u[k], u[k-1], ... newest first
        self.spec = {"times": [n * self.dt for n in delays], "amplitudes": list(amplitudes), "delays": list(delays)}

    def reset(self) -> None:
        """Forget the reference's history (at rest)."""
        self._history = [0.0] * (self.delays[-1] + 1)

    def step(self, u: float) -> float:
        """The shaped reference for this tick, ``u`` being this tick's reference.

        Parameters
        ----------
        u : float
            The reference u[k], encoder counts.

        Returns
        -------
        float
            r[k] = Σ A_i u[k − n_i] (u before the first step counted as 0).
        """
        hist = self._history
        hist.pop()
        hist.insert(0, u)
        r = 0.0
        for n, a in self._pairs:
            r += a * hist[n]
        return r

    def apply(self, u, start: int = 0) -> np.ndarray:
        """The shaped reference of a whole run, as :meth:`step` gives it tick by tick from ``start``.

        Parameters
        ----------
        u : array_like, shape (N,)
            The reference per tick.
        start : int
            The first tick the controller is stepped on (the alignment d): u before it counts
            as 0; r[k] = u[k] for k < start (those ticks have no command).

        Returns
        -------
        numpy.ndarray, shape (N,)
            Equal, float for float, to ``[step(u[k]) for k in range(start, N)]`` after a reset.
        """
        u = np.asarray(u, dtype=float)
        seen = u.copy()
        seen[:start] = 0.0
        r = np.zeros(u.size)
        for n, a in self._pairs:
            if n < u.size:
                r[n:] += a * seen[:u.size - n]
        r[:start] = u[:start]
        return r

    def __repr__(self) -> str:
        return f"ReferenceShaper(delays={list(self.delays)}, amplitudes={list(self.amplitudes)}, dt={self.dt})"


def check_shaper(times: Any, amplitudes: Any, where: str = "[shaper]") -> ShaperTimes:
    """Check a shaper's times and amplitudes as a file or a caller gives them.

    Parameters
    ----------
    times : list of float
        Impulse times, s: finite, the first ≥ 0, increasing, at most :data:`MAX_TIME_S`.
    amplitudes : list of float
        Their amplitudes: finite, as many as ``times`` (1..:data:`MAX_IMPULSES`), summing to
        1 within :data:`SUM_TOLERANCE`.
    where : str
        Prefix of the messages (e.g. ``c.toml: [shaper]``).

    Returns
    -------
    ShaperTimes

    Raises
    ------
    StationError
        One line naming ``where`` and the field (``times``, ``times[i]``, ``amplitudes``...).
    """
    out = []
    for field, value in (("times", times), ("amplitudes", amplitudes)):
        if not isinstance(value, (list, tuple)) or not 1 <= len(value) <= MAX_IMPULSES:
            raise StationError(f"{where}.{field}: expected a list of 1 to {MAX_IMPULSES} numbers, got {value!r}")
        for i, x in enumerate(value):
            if isinstance(x, bool) or not isinstance(x, (int, float)) or not math.isfinite(x):
                raise StationError(f"{where}.{field}[{i}]: expected a finite number, got {x!r}")
        out.append(tuple(float(x) for x in value))
    t, a = out
    if len(t) != len(a):
        raise StationError(f"{where}.amplitudes: {len(a)} amplitudes for {len(t)} times (expected one per time)")
    if t[0] < 0:
        raise StationError(f"{where}.times[0]: expected a time >= 0 s, got {t[0]:g}")
    for i in range(1, len(t)):
        if t[i] <= t[i - 1]:
            raise StationError(f"{where}.times[{i}]: expected increasing times, got {t[i]:g} after {t[i - 1]:g}")
    if t[-1] > MAX_TIME_S:
        raise StationError(f"{where}.times[{len(t) - 1}]: {t[-1]:g} s is later than {MAX_TIME_S:g} s")
    total = math.fsum(a)
    if abs(total - 1.0) > SUM_TOLERANCE:
        raise StationError(f"{where}.amplitudes: expected a sum of 1 (a step keeps its height), got {total:.9g}")
    return ShaperTimes(t, a)


def make_shaper(times: Sequence[float], amplitudes: Sequence[float], dt: float = DT,
                where: str = "[shaper]") -> ReferenceShaper:
    """A :class:`ReferenceShaper` from times in seconds, each rounded to the nearest sample.

    Parameters
    ----------
    times : sequence of float
        Impulse times, s (:func:`check_shaper`).
    amplitudes : sequence of float
        Their amplitudes, summing to 1.
    dt : float
        Sample time, s: n_i = round(t_i/dt).
    where : str
        Prefix of the messages.

    Raises
    ------
    StationError
        As :func:`check_shaper`, and two times that round to the same sample.
    """
    t, a = check_shaper(list(times), list(amplitudes), where)
    delays = [int(round(x / dt)) for x in t]
    for i in range(1, len(delays)):
        if delays[i] == delays[i - 1]:
            raise StationError(f"{where}.times[{i}]: {t[i]:g} s and {t[i - 1]:g} s fall on the same sample "
                               f"of {dt:g} s (times are rounded to whole samples)")
    return ReferenceShaper(delays, a, dt)


def shaper_from_spec(spec: dict, dt: float = DT) -> ReferenceShaper:
    """Rebuild a shaper from its ``spec`` (a log header's ``controller.shaper``).

    Parameters
    ----------
    spec : dict
        ``{"delays": [samples], "amplitudes": [...], ...}`` as :class:`ReferenceShaper` writes it.
    dt : float
        The controller's sample time, s.

    Raises
    ------
    KeyError, TypeError, ValueError
        A missing or bad field (the caller names the log).
    """
    return ReferenceShaper(spec["delays"], spec["amplitudes"], dt)


def _mode(f_hz: float, zeta: float) -> tuple[float, float]:
    if not (math.isfinite(f_hz) and f_hz > 0):
        raise ValueError(f"mode frequency must be a positive number of Hz, got {f_hz}")
    if not (math.isfinite(zeta) and 0 <= zeta < 1):
        raise ValueError(f"damping ratio must be in [0, 1), got {zeta}")
    root = math.sqrt(1.0 - zeta * zeta)
    return 1.0 / (f_hz * root), math.exp(-zeta * math.pi / root)


def zv_shaper(f_hz: float, zeta: float) -> ShaperTimes:
    """The zero-vibration (ZV) shaper of a mode (Singer & Seering 1990).

    Parameters
    ----------
    f_hz : float
        The mode's undamped natural frequency, Hz.
    zeta : float
        Its damping ratio, 0 ≤ ζ < 1.

    Returns
    -------
    ShaperTimes
        t = [0, T_d/2], A = [1, K]/(1 + K), T_d = 1/(f √(1 − ζ²)), K = exp(−ζπ/√(1 − ζ²)).

    Raises
    ------
    ValueError
        A frequency that is not positive, a damping ratio outside [0, 1).
    """
    td, k = _mode(f_hz, zeta)
    return ShaperTimes((0.0, td / 2), (1 / (1 + k), k / (1 + k)))


def zvd_shaper(f_hz: float, zeta: float) -> ShaperTimes:
    """The zero-vibration-and-derivative (ZVD) shaper of a mode (Singer & Seering 1990).

    Parameters
    ----------
    f_hz : float
        The mode's undamped natural frequency, Hz.
    zeta : float
        Its damping ratio, 0 ≤ ζ < 1.

    Returns
    -------
    ShaperTimes
        t = [0, T_d/2, T_d], A = [1, 2K, K²]/(1 + K)²: less sensitive to an error in f than ZV,
        at twice its delay.

    Raises
    ------
    ValueError
        A frequency that is not positive, a damping ratio outside [0, 1).
    """
    td, k = _mode(f_hz, zeta)
    s = (1 + k) ** 2
    return ShaperTimes((0.0, td / 2, td), (1 / s, 2 * k / s, k * k / s))


__all__ = ["MAX_IMPULSES", "MAX_TIME_S", "SUM_TOLERANCE", "ReferenceShaper", "ShaperTimes", "check_shaper",
           "make_shaper", "shaper_from_spec", "zv_shaper", "zvd_shaper"]
