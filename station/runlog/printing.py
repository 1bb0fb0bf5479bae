"""How a log's text printed a column of floats: to a number of decimals (``%.8f``) or of
significant digits (``%.6g``, MATLAB's ``csvwrite`` at 5), decided from the values read back.

A law replayed over a log is compared with its commands to what the log's printing
allows (:func:`station.control.rerun.command_error`): a lead's float command printed to 6
significant digits is 183.255 where the law gives 183.2547182, and 1e-6 counts would call
that another law. Whole numbers say nothing of the printing and are left out.

Imports numpy only.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAX_DIGITS = 17
"""A float64 prints exactly in at most this many significant digits."""

MIN_VALUES = 10
"""Non-whole values needed to decide a printing: fewer decide none."""


def _exponent(x: np.ndarray) -> np.ndarray:
    """floor(log10 |x|) of nonzero ``x``, as float."""
    return np.floor(np.log10(np.abs(x)))


def _round_at(x: np.ndarray, step_exp: np.ndarray) -> np.ndarray:
    """``x`` rounded to a multiple of 10**step_exp, halves away from zero (as ``%f``/``%g`` print
    a value that is not a binary tie)."""
    scale = 10.0 ** -step_exp
    y = np.abs(x) * scale
    whole = np.floor(y)
    return np.copysign(whole + (y - whole >= 0.5), x) / scale


def _digits_needed(x: np.ndarray, kind: str) -> np.ndarray:
    """The fewest decimals (``kind="f"``) or significant digits (``"g"``) that give each of the
    nonzero ``x`` back: the printed text's own length."""
    need = np.full(x.shape, MAX_DIGITS, dtype=int)
    e = _exponent(x)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):  # a subnormal's step: not that printing
        for k in range(MAX_DIGITS, -1 if kind == "f" else 0, -1):
            step = -k if kind == "f" else e - k + 1
            same = np.abs(_round_at(x, step) - x) <= 4 * np.finfo(float).eps * np.abs(x)
            need = np.where(same, k, need)
    return need


@dataclass(frozen=True)
class Printing:
    """A column's printing: each value rounded to ``decimals`` decimals or ``digits``
    significant digits, whichever is coarser there (a ``%.8f`` column has decimals 8 and
    the digits its largest value needed; a ``%.6g`` column digits 6).

    Attributes
    ----------
    decimals : int
        The most decimals any value needed.
    digits : int
        The most significant digits any value needed.
    significant : bool
        Whether more values take all ``digits`` significant digits than all ``decimals``
        decimals (``%g``), for the words only.
    """

    decimals: int
    digits: int

    def step_exponent(self, x) -> np.ndarray:
        """The exponent of the last printed digit of each value.

        Parameters
        ----------
        x : array_like, shape (N,)
            Values as printed (or as computed: the same digit but at a power of ten).

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        x = np.asarray(x, dtype=float)
        with np.errstate(divide="ignore"):
            e = np.where(x != 0, _exponent(np.where(x != 0, x, 1.0)), -np.inf)
        return np.maximum(-float(self.decimals), e - self.digits + 1)

    def resolution(self, x) -> np.ndarray:
        """Half the last printed digit's unit at each value: how far the printed value may be
        from the one computed.

        Parameters
        ----------
        x : array_like, shape (N,)

        Returns
        -------
        numpy.ndarray, shape (N,)
        """
        return 0.5 * 10.0 ** self.step_exponent(x)

    significant: bool = False

    def text(self) -> str:
        """``"6 significant digits"`` or ``"8 decimals"``."""
        return f"{self.digits} significant digits" if self.significant else f"{self.decimals} decimals"


def printing_of(values, coarser_than: float = 0.0) -> Printing | None:
    """The printing a column's values show, when it rounds them coarser than a float64.

    Parameters
    ----------
    values : array_like, shape (N,)
        A column as read back from a log's text.
    coarser_than : float
        None unless some value's :meth:`Printing.resolution` exceeds this (a caller whose
        comparisons already allow that much).

    Returns
    -------
    Printing or None
        None when fewer than :data:`MIN_VALUES` finite values are not whole (integer
        commands, a column of zeros), or when every value needs 15 or more significant
        digits (printed in full: ``repr``).
    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x) & (x != np.round(x))]
    if x.size < MIN_VALUES:
        return None
    sig, dec = _digits_needed(x, "g"), _digits_needed(x, "f")
    digits, decimals = int(np.max(sig)), int(np.max(dec))
    if digits >= 15:
        return None
    printing = Printing(decimals, digits, bool(np.count_nonzero(sig == digits) > np.count_nonzero(dec == decimals)))
    return printing if float(np.max(printing.resolution(x))) > coarser_than else None
