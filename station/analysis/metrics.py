"""Step-response metrics exactly as the thesis reports them (DESIGN.md "Step metrics").

overshoot = (max theta - u_final)/u_final, in percent; settling time = the time, from
t = 0 of the log, of the first sample after the last sample outside the band
|theta - u_final| <= max(1 % of |u_final|, 1 count); None when the last sample is outside.
With these definitions the rig logs give the thesis's experimental table exactly
(P 24.00 % / 1.250 s, lead 10.00 % / not settled, lead + accel 21.50 % / 0.608 s).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np


@dataclass(frozen=True)
class StepMetrics:
    """Overshoot (percent of the step) and settling time (s from t = 0; None: not settled)."""

    overshoot_pct: float
    settling_time_s: float | None

    def to_json(self) -> dict:
        """``{"overshoot_pct": F, "settling_time_s": F | None}``."""
        return asdict(self)


def settling_band(u_final: float) -> float:
    """Half-width of the settling band, encoder counts: max(1 % of |u_final|, 1 count)."""
    return max(0.01 * abs(u_final), 1.0)


def step_metrics(t, theta, u_final: float) -> StepMetrics:
    """Overshoot and settling time of a step response.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s, from t = 0 of the log (the step need not be at 0).
    theta : array_like, shape (N,)
        Hub angle, encoder counts.
    u_final : float
        Final value of the reference, encoder counts (the logs' last u). Non-zero; for a
        negative step the peak is the minimum of theta.

    Returns
    -------
    StepMetrics
        ``overshoot_pct = 100 (peak - u_final)/u_final`` (peak = max theta for a positive
        step); ``settling_time_s`` = t of the first sample after the last sample with
        ``|theta - u_final| > settling_band(u_final)`` (t[0] if none is outside), None when
        the last sample is outside the band.

    Raises
    ------
    ValueError
        Empty or mismatched arrays, NaN in theta, or ``u_final == 0``.

    Notes
    -----
    Source: DESIGN.md "Step metrics as the thesis reports them".
    """
    t = np.asarray(t, dtype=float)
    theta = np.asarray(theta, dtype=float)
    if t.ndim != 1 or t.shape != theta.shape or t.size == 0:
        raise ValueError(f"t and theta must be 1-D arrays of the same non-zero length, got {t.shape} and {theta.shape}")
    if np.any(np.isnan(theta)):
        raise ValueError("theta holds NaN samples")
    u_final = float(u_final)
    if u_final == 0.0 or not np.isfinite(u_final):
        raise ValueError(f"u_final must be a non-zero step size, got {u_final}")
    peak = theta.max() if u_final > 0 else theta.min()
    overshoot = 100.0 * float((peak - u_final) / u_final)
    outside = np.flatnonzero(np.abs(theta - u_final) > settling_band(u_final))
    if outside.size == 0:
        settling = float(t[0])
    elif outside[-1] == theta.size - 1:
        settling = None
    else:
        settling = float(t[outside[-1] + 1])
    return StepMetrics(overshoot_pct=overshoot, settling_time_s=settling)
