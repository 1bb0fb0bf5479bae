"""One range per number the station takes, checked in one place.

:class:`Number` is a range (``number(low, high, ...)``) used three ways: as argparse's
``type=`` for a command-line option (it parses the text), by the ``sim://`` URL handler
for a URL option (the same text parsing), and by the file loaders for a number read from
TOML (:meth:`Number.check`). :data:`SIM_RIG` is the table of the simulated rig's numeric
settings: ``sim://?seed=``/``--seed``, ``sim://?elements=``/``--elements`` (and a model
file's ``n_elements``), and the URL-only ``noise``, ``watchdog`` and fault options - so
the range ``--help`` documents is the one the URL handler and the model loader check.

Imports nothing of the station: every layer may use it.
"""

from __future__ import annotations

import argparse
import math
import numbers


def shown(value, width: int = 40) -> str:
    """``repr(value)`` cut to ``width`` characters, for a one-line message about a value a
    file or option gave (which may be a megabyte long).

    Parameters
    ----------
    value : object
        The value.
    width : int
        The most characters shown ("..." ends a cut).
    """
    return _cut(repr(value), width)


def _cut(text: str, width: int = 40) -> str:
    if not text.isprintable():  # a control character (float() takes some as blanks): show it escaped
        text = repr(text)
    return text if len(text) <= width else text[:width - 3] + "..."


class RangeError(argparse.ArgumentTypeError, ValueError):
    """A value outside its :class:`Number` range, or not a number: argparse reports it as
    ``argument --x: MESSAGE``; other callers catch it as a ValueError.

    Parameters
    ----------
    message : str
        What was given and what was expected (the range).
    """


class Number:
    """A finite number within ``[low, high]``: argparse ``type=``, URL option or file field.

    Parameters
    ----------
    low, high : float
        Inclusive bounds (``integer``: whole numbers only).
    integer : bool
        Accept whole numbers only (returns ``int``).
    unit : str
        Unit shown in the range and the error (e.g. "s", "encoder counts").
    nonzero : bool
        Refuse 0 inside the range (e.g. a step height).
    """

    def __init__(self, low: float, high: float, integer: bool = False, unit: str = "", nonzero: bool = False):
        self.low, self.high, self.integer, self.unit, self.nonzero = low, high, integer, unit, nonzero
        self.__name__ = "integer" if integer else "number"  # argparse names the type in its errors

    def range_text(self) -> str:
        """The documented range, e.g. ``range 0.001..60 s`` or ``range 1..100, whole number``."""
        unit = f" {self.unit}" if self.unit else ""
        kind = ", whole number" if self.integer else ""
        nz = ", not 0" if self.nonzero else ""
        fmt = (lambda x: str(int(x))) if self.integer else (lambda x: f"{x:.10g}")
        return f"range {fmt(self.low)}..{fmt(self.high)}{unit}{kind}{nz}"

    def __call__(self, text: str):
        """Parse ``text`` (a command-line or URL value) and check it.

        Parameters
        ----------
        text : str
            The value as typed.

        Raises
        ------
        RangeError
            Not a number, not finite, not whole (``integer``) or out of range; the message
            says what was given and the range.
        """
        try:
            value = float(text)
        except ValueError:
            raise RangeError(f"{shown(text)} is not a number (expected {self.range_text()})") from None
        return self._within(value, _cut(text))

    def check(self, value):
        """Check a number read from a file (TOML): a bool or a string is not a number.

        Parameters
        ----------
        value : object
            As the file holds it.

        Returns
        -------
        int or float
            The value (``int`` when ``integer``).

        Raises
        ------
        RangeError
            As :meth:`__call__`.
        """
        if isinstance(value, bool) or not isinstance(value, numbers.Real):  # numpy's numbers are Real too
            raise RangeError(f"expected a number ({self.range_text()}), got {shown(value)}")
        return self._within(float(value) if not isinstance(value, numbers.Integral) else int(value), shown(value))

    def _within(self, value: float, text: str):
        if not isinstance(value, int) and not math.isfinite(value):  # (an int is finite, however large)
            raise RangeError(f"{text} is not a finite number (expected {self.range_text()})")
        if self.integer:
            if value != int(value):
                raise RangeError(f"{text} is not a whole number (expected {self.range_text()})")
            value = int(value)
        if not self.low <= value <= self.high or (self.nonzero and value == 0):
            raise RangeError(f"{text} is out of range (expected {self.range_text()})")
        return value

    def __repr__(self) -> str:
        return f"number({self.low!r}, {self.high!r}, integer={self.integer})"


def number(low: float, high: float, integer: bool = False, unit: str = "", nonzero: bool = False) -> Number:
    """A range (see :class:`Number`): ``type=`` of a numeric option, a URL option's or a file field's range.

    Parameters
    ----------
    low, high : float
        Inclusive bounds.
    integer : bool, default False
        Accept whole numbers only (returns ``int``).
    unit : str, optional
        Unit shown in the range and the error.
    nonzero : bool, default False
        Refuse 0 inside the range.
    """
    return Number(low, high, integer=integer, unit=unit, nonzero=nonzero)


TICKS = 2**32 - 1
"""Most ticks protocol v1 counts (uint32); the bound of the simulated rig's tick options."""

SIM_RIG: dict[str, Number] = {
    "seed": number(0, 2**32 - 1, integer=True),
    "elements": number(1, 100, integer=True),
    "noise": number(0.0, 100.0, unit="ADC counts"),
    "watchdog": number(1, 255, integer=True, unit="ticks"),
    "silent_after": number(0, TICKS, integer=True, unit="ticks"),
    "garbage_every": number(1, TICKS, integer=True, unit="samples"),
    "skip_tick": number(0, TICKS, integer=True, unit="ticks"),
}
"""The simulated rig's numeric settings by ``sim://`` option name: the seed of its sensor
noise, the FEM element count (a model's ``n_elements``, ``--elements``), the accelerometer
noise std, the v1 watchdog (DESIGN: 1..255 ticks) and the fault options' ticks. The URL
handler, ``--seed``/``--elements`` and the model loader check these, and no other, ranges."""

N_ELEMENTS = SIM_RIG["elements"]
"""Beam elements of a FEM model, 1..100 (a model's ``n_elements``, ``--elements``, ``sim://?elements=``)."""
