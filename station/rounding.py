"""Rounding to whole counts, halves away from zero: the one definition, and its compiled twin.

The spec (``shared/spec/protocol.md``) has the station round v to the nearest integer,
halves away from zero, before sending it; the v1 firmware rounds its accelerometer
offset the same way. The simulated device, the protocol codec and the numba kernel of
:func:`station.plant.simulate.simulate` all use this module, so the model equals loop +
device to the last count. ``floor(x + 0.5)`` is not this rule: ``0.49999999999999994 + 0.5``
rounds to 1.0 in floating point, so that form sends 1 where the rule gives 0.
"""

from __future__ import annotations

import math

_WHOLE = 4503599627370496.0  # 2**52: every float at or beyond it is already whole


def half_away(x: float) -> float:
    """Nearest whole number to ``x``, halves away from zero, as a float.

    Parameters
    ----------
    x : float
        Any float; ±inf and NaN come back unchanged.

    Returns
    -------
    float
        The rounded value (−0.0 for small negatives, which equals 0.0).

    Notes
    -----
    The fraction ``|x| - floor(|x|)`` is exact and compared with 0.5, so no sum is
    rounded on the way (unlike ``floor(x + 0.5)``).
    """
    mag = abs(x)
    if not mag < _WHOLE:
        return x
    whole = float(math.floor(mag))  # exact below 2**52
    if mag - whole >= 0.5:  # exact too: no sum is rounded on the way
        whole += 1.0
    return whole if x >= 0.0 else -whole


try:
    import numba
except ImportError:  # pragma: no cover - numba is a dependency; plain Python without it
    half_away_compiled = half_away
else:
    half_away_compiled = numba.njit(cache=True, nogil=True)(half_away)
""":func:`half_away` compiled by numba, for compiled kernels (same float operations)."""


def round_half_away(x: float) -> int:
    """Nearest integer to ``x``, halves away from zero (:func:`half_away` as an int).

    Parameters
    ----------
    x : float
        Any finite float.

    Raises
    ------
    ValueError
        ``x`` is NaN.
    OverflowError
        ``x`` is infinite.
    """
    return int(half_away(x))
