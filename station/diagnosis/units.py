"""An effect's value in words with its unit: the diagnosis's bottom floor, so the search's
progress, the rivals, the drift and the answer's prose all write a value the same way."""

from __future__ import annotations

import math


def format_quantity(x: float, unit: str) -> str:
    """An effect's value with its unit: whole samples, else 3 significant digits; "∞" when
    infinite; no unit for ratios ("1").

    Parameters
    ----------
    x : float
        The value, in ``unit``.
    unit : str
        The effect's unit (:data:`station.plant.effects.EFFECTS`).

    Returns
    -------
    str
        E.g. "12 samples", "5.31 DAC counts", "2.86" (a ratio).
    """
    if not math.isfinite(x):
        return "∞"
    s = f"{x:.0f}" if unit == "samples" else f"{x:.3g}"
    return s + ("" if unit == "1" else f" {unit}")
