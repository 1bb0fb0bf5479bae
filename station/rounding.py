"""Rounding to whole counts, halves away from zero: the one definition, and its compiled twins.

The spec (``shared/spec/protocol.md``) has the station round v to the nearest integer,
halves away from zero, before sending it; the v1 firmware rounds its accelerometer
offset the same way. The simulated sensors read by the same rule (:func:`sensor_count`:
θ to the nearest encoder count, a to whole ADC counts). The simulated device, the
protocol codec, the plant's `Sensors` and the numba kernel of
:func:`station.plant.simulate.simulate` all use this module, so the model equals loop +
device to the last count. ``floor(x + 0.5)`` is not this rule: ``0.49999999999999994 + 0.5``
rounds to 1.0 in floating point, so that form sends 1 where the rule gives 0 (and it
rounds −2.5 to −2).

Imports nothing from the station (the bottom layer); numpy, and numba when installed.
"""

from __future__ import annotations

import math

import numpy as np

_WHOLE = 4503599627370496.0  # 2**52: every float at or beyond it is already whole


# Each rule has one body, made twice: for Python with math.floor and compiled with np.floor
# (both exact; np.floor keeps a float where math.floor passes through an int, which costs
# the simulate kernel a few per cent per sample).

def _half_away_with(floor):
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
        whole = float(floor(mag))  # exact below 2**52
        whole = whole + 1.0 if mag - whole >= 0.5 else whole  # exact too: no sum is rounded on the way
        return whole if x >= 0.0 else -whole

    return half_away


def _sensor_count_with(rounding):
    def sensor_count(x: float) -> float:
        """A sensor's reading of a noise-free value: the nearest whole count, as a float.

        The encoder reports θ to the nearest count and the accelerometer's ADC a in
        whole counts (DESIGN.md "FEM plant"); both round halves away from zero, the
        station's one rule (:func:`half_away`).

        Parameters
        ----------
        x : float
            Noise-free (or noisy) output, counts.

        Returns
        -------
        float
            The whole count; a zero reading is +0.0 (a count has no sign, so −0.3 reads
            0.0, not −0.0); ±inf and NaN come back unchanged.
        """
        return rounding(x) + 0.0  # -0.0 + 0.0 is +0.0

    return sensor_count


half_away = _half_away_with(math.floor)
sensor_count = _sensor_count_with(half_away)


def sensor_counts(x) -> np.ndarray:
    """:func:`sensor_count` of every element: an array's reading, the same exact rule.

    Parameters
    ----------
    x : array_like
        Noise-free (or noisy) outputs, counts, any shape.

    Returns
    -------
    ndarray of float
        The whole counts, the shape of ``x`` (+0.0 for a zero reading; ±inf and NaN unchanged).
    """
    x = np.asarray(x, float)
    inside = np.abs(x) < _WHOLE  # False for ±inf and NaN too: they come back unchanged
    mag = np.where(inside, np.abs(x), 0.0)
    whole = np.floor(mag)
    whole = np.where(mag - whole >= 0.5, whole + 1.0, whole)  # the fraction is exact: no sum rounded
    return np.where(inside, np.copysign(whole, x), x) + 0.0


def toward_zero(x: float) -> float:
    """``x`` truncated toward zero, as a float (the lab's stored integer command).

    Parameters
    ----------
    x : float
        Any float; ±inf and NaN come back unchanged (``math.trunc`` would raise: an unstable
        filter's replay reaches them).

    Returns
    -------
    float
        The whole number toward zero.
    """
    return x if not abs(x) < _WHOLE else float(math.trunc(x))



def __getattr__(name: str):
    """``half_away_compiled`` and ``sensor_count_compiled``: :func:`half_away` and
    :func:`sensor_count` compiled by numba, for compiled kernels (the same float operations:
    np.floor and math.floor agree below 2**52). Made on first use: numba takes a second to
    import, and the protocol codec, which uses this module too, never needs it."""
    if name not in ("half_away_compiled", "sensor_count_compiled"):
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    try:
        import numba  # lazy: start-up time (numba)
    except ImportError:  # pragma: no cover - numba is a dependency; plain Python without it
        compiled = {"half_away_compiled": half_away, "sensor_count_compiled": sensor_count}
    else:
        half = numba.njit(cache=True, nogil=True)(_half_away_with(np.floor))
        compiled = {"half_away_compiled": half,
                    "sensor_count_compiled": numba.njit(cache=True, nogil=True)(_sensor_count_with(half))}
    globals().update(compiled)
    return compiled[name]


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
