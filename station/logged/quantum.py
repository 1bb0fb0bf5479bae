"""A column's quantum: whether its values are whole multiples of one size, and which size.

A converter's reading written in another unit (θ in degrees, a in m/s², v in volts) steps by its
scale; the log audit reads a column's unit from it (:mod:`station.logged.units`,
:mod:`station.logged.columns`). Imports nothing of the station.
"""

from __future__ import annotations

import numpy as np

STEP_DIVISORS = 10
"""Most counts a column's smallest change between rows may span for :func:`count_step` (a P
law's command trunc(kp·e) changes by 2 or 3 counts at kp = 2.5)."""

FIELD_COUNTS = 65536
"""Counts a sample of the rig's can span (a signed 16-bit field)."""

QUANTUM_TOLERANCE = 1e-3
"""How far a value may sit from a whole multiple of a quantum (in quanta) and still be one
(values printed to a few decimals)."""


CONVERTER_VOLTS = tuple(span / 2 ** (bits - 1) for span in (2.5, 5.0, 10.0) for bits in (8, 10, 12, 14, 16))
"""One count of a bipolar converter, volts (±2.5, ±5 or ±10 V full scale, 8 to 16 bits; the
rig's DAC count is 5/2048 V of a ±5 V 12-bit converter, DESIGN.md): sizes a command written in
volts steps by, tried where its changes cannot give one (a v only 0 and one value)."""

FLOAT_NOISE = 1e-9
"""A change between two printed values smaller than this is the float's rounding, not a change."""


def quantum_fits(x: np.ndarray, quantum: float, spare: int = 0) -> bool:
    """Whether every value of ``x`` is a whole multiple of ``quantum`` (to
    :data:`QUANTUM_TOLERANCE` of it), but at most ``spare`` of them.

    Parameters
    ----------
    x : ndarray, shape (N,)
    quantum : float
    spare : int, default 0
        Values that may be off: a column's corrupted fields, which the law then finds
        (:func:`station.analysis.glitches.most_glitches`).
    """
    return int(np.count_nonzero(~quantum_fits_each(x, quantum))) <= spare


def quantum_fits_each(x: np.ndarray, quantum: float) -> np.ndarray:
    """Which values of ``x`` are whole multiples of ``quantum`` (:func:`quantum_fits`).

    Parameters
    ----------
    x : ndarray, shape (N,)
    quantum : float

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    q = np.asarray(x, dtype=float) / quantum
    return np.abs(q - np.round(q)) <= QUANTUM_TOLERANCE


def count_step(x, spare: int = 0) -> float | None:
    """The size of one count in a column of counts written in another unit: the largest size
    every change between rows is a whole multiple of (to :data:`QUANTUM_TOLERANCE` of it), the
    smallest change or a :data:`STEP_DIVISORS`-th of it at most, refined by least squares; None
    when the column never changes, its changes have no common size (a filtered or computed
    float) or that size spans more than a 16-bit field over its range (the last digit printed).

    A converter's reading scaled into another unit steps by its scale (an accelerometer count of
    the rig's is 1/1.145 m/s², DESIGN.md's a_gain; a DAC count 5/2048 V of a ±5 V 12-bit
    converter); an offset (the thesis's lead + accelerometer log stores a as counts + 0.04)
    moves no step.

    Parameters
    ----------
    x : array_like, shape (N,)
    spare : int, default 0
        Changes that may be off the size: two for each corrupted field (into it and out of
        it), which the law then finds; the smallest ``spare`` changes do not set the size.

    Returns
    -------
    float or None
    """
    x = np.asarray(x, dtype=float)
    if x.size < 2 or not np.all(np.isfinite(x)):
        return None
    steps = np.abs(np.diff(x))
    steps = steps[steps > 1e-9 * max(1.0, float(np.max(np.abs(x))))]
    if steps.size <= spare:
        return None
    least = float(np.sort(steps)[spare])
    for k in range(1, STEP_DIVISORS + 1):  # a column whose least change spans k counts (2 or 3 of trunc(2.5 e))
        size = least / k
        if np.ptp(x) / size > FIELD_COUNTS:  # the printing's last digit
            return None
        # the size from the small changes, then each change's count from it and the size from them
        # all (least squares): a change of c counts holds c times the first size's error
        for few, tol in ((steps[steps <= (k + 1.5) * size], QUANTUM_TOLERANCE), (steps, 0.1)):
            counts = np.round(few / size)
            fits = (counts != 0) & (np.abs(few / size - counts) <= tol)
            if np.count_nonzero(~fits) > spare or not np.any(fits):
                break
            size = float(np.sum(few[fits] * counts[fits]) / np.sum(counts[fits] ** 2))
        else:
            if quantum_fits(steps, size, spare):
                return size
    return None


def in_counts(x) -> bool:
    """Whether a column is in whole counts: it changes by whole counts (or never changes),
    whatever its offset. A column that steps by whole multiples of 2 or more is counts too (an
    accelerometer of another gain read in whole counts: the gain says it, not the unit); False
    for a column that changes by fractions of a count, however small (a change within
    :data:`QUANTUM_TOLERANCE` of none, but more than :data:`FLOAT_NOISE`, is one).

    Parameters
    ----------
    x : array_like, shape (N,)
    """
    x = np.asarray(x, dtype=float)
    if x.size < 2 or not np.all(np.isfinite(x)):
        return True
    d = np.diff(x)  # a change within the tolerance of none is a fraction, not a count (volts of a 16-bit DAC)
    return quantum_fits(d, 1.0) and not np.any((np.abs(d) > FLOAT_NOISE) & (np.round(d) == 0))
