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
    """Overshoot (percent of the step) and settling time (s from t = 0; None: not settled).

    Attributes
    ----------
    overshoot_pct : float
        Overshoot, percent of the step.
    settling_time_s : float or None
        Settling time, s from t = 0; None: not settled.
    """

    overshoot_pct: float
    settling_time_s: float | None

    def to_json(self) -> dict:
        """``{"overshoot_pct": F, "settling_time_s": F | None}``."""
        return asdict(self)

    def summary(self) -> str:
        """``overshoot 10.00 %, settling 0.608 s`` (or "not settled within the run")."""
        settle = NOT_SETTLED if self.settling_time_s is None else f"settling {self.settling_time_s:.3f} s"
        return f"overshoot {self.overshoot_pct:.2f} %, {settle}"


NOT_SETTLED = "not settled within the run"
"""What a report says when θ is still outside the settling band at the run's end."""


@dataclass(frozen=True)
class StepInfo:
    """The usual step-response figures beside the thesis's (python-control ``step_info`` on the logged θ).

    Times are s after the step (not from t = 0 of the log).

    Attributes
    ----------
    rise_time_s : float or None
        10 % to 90 % of the step (None when θ never reached 90 %).
    peak_time_s : float or None
        Time of the largest |θ|.
    settling_time_2pct_s : float or None
        python-control's 2 % settling time (None: not settled within the run).
    steady_state_error : float
        Step − mean θ over the run's last 0.1 s, encoder counts.
    saturation_time_s : float or None
        Time the command spent at the controller's clamp (None when the limit or v is
        unknown).
    """

    rise_time_s: float | None
    peak_time_s: float | None
    settling_time_2pct_s: float | None
    steady_state_error: float
    saturation_time_s: float | None

    def to_json(self) -> dict:
        """The fields as a dict (None for what is undefined)."""
        return asdict(self)

    def summary(self) -> str:
        """One line: rise, peak, 2 % settling, steady-state error, saturation."""
        f = lambda x: "n/a" if x is None else f"{x:.3f} s"  # noqa: E731
        settle = (f"2 % band: {NOT_SETTLED}" if self.settling_time_2pct_s is None
                  else f"2 % settling {f(self.settling_time_2pct_s)}")
        sat = "" if self.saturation_time_s is None else f"   saturated {self.saturation_time_s:.3f} s"
        return (f"rise {f(self.rise_time_s)}   peak {f(self.peak_time_s)}   {settle}   "
                f"steady-state error {self.steady_state_error:.1f} counts{sat}")


def step_info(t, theta, u_final: float, step_time: float = 0.0, v=None, limit: float | None = None) -> StepInfo:
    """Rise time, peak time, 2 % settling time, steady-state error and time in saturation.

    Parameters
    ----------
    t, theta : array_like, shape (N,)
        Sample times (s) and hub angle (encoder counts) of the log.
    u_final : float
        Step height, encoder counts (non-zero).
    step_time : float
        When the step starts, s (the samples before it are left out).
    v : array_like, shape (N,), optional
        Commands, DAC counts (for the time in saturation).
    limit : float, optional
        The controller's clamp, DAC counts.

    Returns
    -------
    StepInfo

    Raises
    ------
    ValueError
        Mismatched or empty arrays, NaN in theta, ``u_final`` zero or not finite.

    Notes
    -----
    Source: ``control.step_info`` (python-control) with ``SettlingTimeThreshold=0.02``,
    ``RiseTimeLimits=(0.1, 0.9)`` and ``yfinal = u_final``.
    """
    import control

    t = np.asarray(t, dtype=float)
    theta = np.asarray(theta, dtype=float)
    if t.ndim != 1 or t.shape != theta.shape or t.size == 0:
        raise ValueError(f"t and theta must be 1-D arrays of the same non-zero length, got {t.shape} and {theta.shape}")
    if np.any(np.isnan(theta)):
        raise ValueError("theta holds NaN samples")
    if u_final == 0.0 or not np.isfinite(u_final):
        raise ValueError(f"u_final must be a non-zero step size, got {u_final}")
    after = t >= step_time - 1e-12
    ts, ys = t[after] - step_time, theta[after]
    if ts.size < 2:
        raise ValueError("fewer than two samples after the step")
    reached = np.sign(u_final) * (ys - 0.9 * u_final) >= 0
    info = control.step_info(ys, timepts=ts, final_output=float(u_final)) if reached.any() else None
    tail = ys[ts >= ts[-1] - 0.1]

    def value(key):
        if info is None:
            return None
        x = info[key]
        return None if not np.isfinite(x) else float(x)

    sat = None
    if v is not None and limit is not None and np.isfinite(limit):
        v = np.asarray(v, dtype=float)
        dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
        sat = float(np.count_nonzero(np.abs(v) >= limit) * dt)
    peak = float(ts[np.argmax(np.abs(ys))])
    return StepInfo(rise_time_s=value("RiseTime"), peak_time_s=peak,
                    settling_time_2pct_s=value("SettlingTime"),
                    steady_state_error=float(u_final - tail.mean()), saturation_time_s=sat)


def settling_band(u_final: float) -> float:
    """Half-width of the settling band, encoder counts: max(1 % of |u_final|, 1 count).

    Parameters
    ----------
    u_final : float
        The step's final value, encoder counts.
    """
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
