"""Step-response metrics exactly as the thesis reports them (DESIGN.md "Step metrics").

overshoot = (max theta - u_final)/u_final, in percent; settling time = the time, from
t = 0 of the log, of the first sample after the last sample outside the band
|theta - u_final| <= max(1 % of |u_final|, 1 count). With these definitions the rig logs
give the thesis's experimental table exactly (P 24.00 % / 1.250 s, lead 10.00 % / not
settled, lead + accel 21.50 % / 0.608 s).

"Settled" has one definition here (:func:`settled_index`), for the thesis's 1 % band and
for :func:`step_info`'s 2 % band alike: a sample is outside the band when its distance to
the final value is strictly greater than the band's half-width; the response is settled
from the first sample after the last one outside, provided it then stays inside for at
least :data:`SETTLE_HOLD_S` (counted in whole samples, N·dt). Otherwise it is "not settled
within the run": a run still swinging at its end, whose last few samples happen to cross
the band, has not settled.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from station.rig import STEP_INFO_BAND, THESIS_BAND, THESIS_BAND_FLOOR


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
        """``{"overshoot_pct": F, "settling_thesis_s": F | None}`` (DESIGN.md's key for the 1 %
        time from t = 0, the one ``station tune --json`` uses)."""
        return {"overshoot_pct": self.overshoot_pct, "settling_thesis_s": self.settling_time_s}

    def summary(self) -> str:
        """``overshoot 10.00 %, settling (1 %) 0.608 s from t = 0`` (or "... settling (1 %) not
        settled within the run")."""
        label = settling_label(THESIS_BAND_PCT)
        settle = NOT_SETTLED if self.settling_time_s is None else f"{self.settling_time_s:.3f} s {FROM_START}"
        return f"{self.overshoot_words()}, {label} {settle}"

    def overshoot_words(self) -> str:
        """``overshoot 24.00 %``; below 0 with why: ``overshoot -92.00 % (θ never reached the step:
        its peak 8 % of it)`` (a run that ended before the response rose)."""
        text = f"overshoot {self.overshoot_pct:.2f} %"
        if self.overshoot_pct < 0:
            text += f" (θ never reached the step: its peak {100 + self.overshoot_pct:.0f} % of it)"
        return text


def settling_label(band_pct: float) -> str:
    """The one name of a settling time, with its band: ``settling (1 %)``, ``settling (2 %)``.

    Every place that prints a settling time names its band with this, so the thesis's 1 %
    time (:func:`step_metrics`) and the 2 % time (:func:`step_info`, ``station tune``) are
    never both called "settling".

    Parameters
    ----------
    band_pct : float
        The band's half-width, percent of the step (the thesis's band is 1 %, at least one
        encoder count: :func:`settling_band`).

    Returns
    -------
    str

    Examples
    --------
    >>> settling_label(1)
    'settling (1 %)'
    >>> settling_label(2.0)
    'settling (2 %)'
    """
    return f"settling ({band_pct:g} %)"


THESIS_BAND_PCT = 100 * THESIS_BAND
"""The thesis's settling band, percent of the step (at least one count: :func:`settling_band`)."""

STEP_INFO_BAND_PCT = 100 * STEP_INFO_BAND
"""The 2 % settling band, percent of the step (:func:`step_info`)."""

FROM_START = "from t = 0"
"""Where the thesis's settling (1 %) counts from, said beside every such time printed: the log's
t = 0, not the step (DESIGN.md's definition: the rig's logs step at 0.1 s, ``station step`` at
0.02 s; the 2 % time and rise and peak count from the step, :data:`AFTER_STEP`)."""

AFTER_STEP = "after the step"
"""Where :class:`StepInfo`'s times count from, said where they are printed."""

NOT_SETTLED = "not settled within the run"
"""What a report says when θ has not settled (:func:`settled_index`): outside the band at the
run's end, or back inside it for less than :data:`SETTLE_HOLD_S`."""

SETTLE_HOLD_S = 0.1
"""Least time inside the band, from the settling sample to the run's end, that counts as
settled, s (50 samples at 500 Hz: well over one period of the 18 Hz second mode, and short
against the thesis's settling times, 0.6-1.3 s into 2 s runs)."""


def settled_index(t, y, final: float, band: float, hold_s: float = SETTLE_HOLD_S) -> int | None:
    """Where a response has settled: the one definition of "settled".

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s (evenly spaced; their median step is the sample time).
    y : array_like, shape (N,)
        The response, e.g. θ in encoder counts.
    final : float
        The value it settles to, same units.
    band : float
        Half-width of the band, same units; a sample with ``|y - final| > band`` (strictly)
        is outside.
    hold_s : float
        Least time inside the band to the run's end, s, counted as whole samples (N·dt).

    Returns
    -------
    int or None
        Index of the first sample after the last sample outside the band (0 when none is
        outside); None when the last sample is outside or the response stays inside for
        less than ``hold_s`` (not settled within the run).
    """
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    outside = np.flatnonzero(np.abs(y - final) > band)
    first = 0 if outside.size == 0 else int(outside[-1]) + 1
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    need = max(1, math.ceil(hold_s / dt - 1e-9)) if dt > 0 else 1
    return first if y.size - first >= need else None


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
        The 2 % settling time (:func:`settled_index` with a band of 2 % of the step;
        None: not settled within the run).
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
        """The fields as a dict (None for what is undefined); the 2 % time as
        ``settling_2pct_s``, DESIGN.md's key (``station tune --json`` uses it too)."""
        out = asdict(self)
        out["settling_2pct_s"] = out.pop("settling_time_2pct_s")
        return out

    def summary(self, unsettled: str = NOT_SETTLED) -> str:
        """One line: rise, peak, 2 % settling (named by :func:`settling_label`), each after the
        step (:data:`AFTER_STEP`), steady-state error, saturation.

        Parameters
        ----------
        unsettled : str
            What the 2 % settling time says when θ has not settled (a report that has just
            said :data:`NOT_SETTLED` of the 1 % band says "not settled either").

        Returns
        -------
        str
        """
        f = lambda x: "n/a" if x is None else f"{x:.3f} s"  # noqa: E731
        settle = (f"{settling_label(STEP_INFO_BAND_PCT)} "
                  f"{unsettled if self.settling_time_2pct_s is None else f(self.settling_time_2pct_s)}")
        sat = "" if self.saturation_time_s is None else f"   saturated {self.saturation_time_s:.3f} s"
        return (f"{AFTER_STEP}: rise {f(self.rise_time_s)}   peak {f(self.peak_time_s)}   {settle}   "
                f"steady-state error {self.steady_state_error:.1f} counts{sat}")


def _step_response(t, theta, u_final, u_initial=0.0) -> tuple[np.ndarray, np.ndarray, float]:
    """t and θ as float arrays and the step's height as a float; ValueError when they cannot be
    a step response."""
    t = np.asarray(t, dtype=float)
    theta = np.asarray(theta, dtype=float)
    if t.ndim != 1 or t.shape != theta.shape or t.size == 0:
        raise ValueError(f"t and theta must be 1-D arrays of the same non-zero length, got {t.shape} and {theta.shape}")
    if np.any(np.isnan(theta)):
        raise ValueError("theta holds NaN samples")
    height = float(u_final) - float(u_initial)
    if height == 0.0 or not np.isfinite(height):
        raise ValueError(f"u_final must be a non-zero step size, got {float(u_final)}" if not u_initial else
                         f"u_final - u_initial must be a non-zero step size, got {u_final} - {u_initial}")
    return t, theta, height


def step_info(t, theta, u_final: float, step_time: float = 0.0, v=None, limit: float | None = None,
              u_initial: float = 0.0) -> StepInfo:
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
    u_initial : float
        The level the step starts from, encoder counts (0 but for a step from a held
        position): the figures are of θ − u_initial against the height ``u_final - u_initial``.

    Returns
    -------
    StepInfo

    Raises
    ------
    ValueError
        Mismatched or empty arrays, NaN in theta, a height zero or not finite.

    Notes
    -----
    Rise time: ``control.step_info`` (python-control) with ``RiseTimeLimits=(0.1, 0.9)``
    and ``yfinal = u_final``; peak time: the largest |θ|. The 2 % settling time is
    :func:`settled_index` (the same definition as the thesis's settling time) with a band
    of 2 % of ``|u_final|``: python-control counts a sample exactly on the band's edge as
    outside and has no hold.
    """
    import control  # lazy: start-up time (python-control)

    t, theta, height = _step_response(t, theta, u_final, u_initial)
    after = t >= step_time - 1e-12
    ts, ys = t[after] - step_time, theta[after] - u_initial  # the response from the level it steps from
    if ts.size < 2:
        raise ValueError("fewer than two samples after the step")
    reached = np.sign(height) * (ys - 0.9 * height) >= 0
    info = control.step_info(ys, timepts=ts, final_output=height) if reached.any() else None
    tail = ys[ts >= ts[-1] - 0.1]

    def value(key):
        if info is None:
            return None
        x = info[key]
        return None if not np.isfinite(x) else float(x)

    settled = settled_index(ts, ys, height, step_info_band(height))
    sat = None
    if v is not None and limit is not None and np.isfinite(limit):
        sat = time_at_clamp(v, limit, float(np.median(np.diff(t))) if t.size > 1 else 0.0)
    peak = float(ts[np.argmax(np.abs(ys))])
    return StepInfo(rise_time_s=value("RiseTime"), peak_time_s=peak,
                    settling_time_2pct_s=None if settled is None else float(ts[settled]),
                    steady_state_error=float(height - tail.mean()), saturation_time_s=sat)


def settling_band(u_final: float) -> float:
    """Half-width of the settling band, encoder counts: max(1 % of |u_final|, 1 count).

    Parameters
    ----------
    u_final : float
        The step's final value, encoder counts.

    Returns
    -------
    float
        max(:data:`station.rig.THESIS_BAND` × |u_final|, :data:`station.rig.THESIS_BAND_FLOOR`).
    """
    return max(THESIS_BAND * abs(u_final), THESIS_BAND_FLOOR)


def step_info_band(u_final: float) -> float:
    """Half-width of the 2 % settling band, encoder counts: 2 % of |u_final| (no floor).

    Parameters
    ----------
    u_final : float
        The step's final value, encoder counts.

    Returns
    -------
    float
        :data:`station.rig.STEP_INFO_BAND` × |u_final|.
    """
    return STEP_INFO_BAND * abs(u_final)


def time_at_clamp(v, limit: float, dt: float) -> float:
    """Time the command spent at the clamp: the samples with |v| ≥ ``limit``, times ``dt``.

    Parameters
    ----------
    v : array_like, shape (N,)
        Commands, DAC counts.
    limit : float
        The controller's clamp, DAC counts.
    dt : float
        Sample time, s.

    Returns
    -------
    float
        Seconds at the clamp.
    """
    return float(np.count_nonzero(np.abs(np.asarray(v, dtype=float)) >= limit) * dt)


def step_metrics(t, theta, u_final: float, u_initial: float = 0.0) -> StepMetrics:
    """Overshoot and settling time of a step response.

    Parameters
    ----------
    t : array_like, shape (N,)
        Sample times, s, from t = 0 of the log (the step need not be at 0).
    theta : array_like, shape (N,)
        Hub angle, encoder counts.
    u_final : float
        Final value of the reference, encoder counts (the logs' last u); for a step down the
        peak is the minimum of theta.
    u_initial : float
        The level the step starts from, encoder counts (0 but for a step from a held
        position); the step's height ``u_final - u_initial`` is non-zero.

    Returns
    -------
    StepMetrics
        ``overshoot_pct = 100 (peak - u_final)/(u_final - u_initial)`` (peak = max theta for
        a step up); ``settling_time_s`` = t of the first sample after the last sample with
        ``|theta - u_final| > settling_band(u_final - u_initial)`` (t[0] if none is
        outside), None when not settled within the run (:func:`settled_index`: the last
        sample outside the band, or inside for less than :data:`SETTLE_HOLD_S`).

    Raises
    ------
    ValueError
        Empty or mismatched arrays, NaN in theta, or a step of height 0.

    Notes
    -----
    Source: DESIGN.md "Step metrics as the thesis reports them".

    Examples
    --------
    A 100-count step answered by a 2 Hz ring that decays at 8 /s, in whole encoder counts:

    >>> import numpy as np
    >>> from station.analysis.metrics import step_metrics
    >>> t = np.arange(1000) * 0.002
    >>> theta = np.round(100 * (1 - np.exp(-8 * t) * np.cos(2 * np.pi * 2 * t)))
    >>> step_metrics(t, theta, 100)                               # band ±1 count
    StepMetrics(overshoot_pct=16.0, settling_time_s=0.522)
    >>> step_metrics(t, theta, 0)
    Traceback (most recent call last):
    ...
    ValueError: u_final must be a non-zero step size, got 0.0
    """
    t, theta, height = _step_response(t, theta, u_final, u_initial)
    peak = theta.max() if height > 0 else theta.min()
    overshoot = 100.0 * float((peak - u_final) / height)
    settled = settled_index(t, theta, u_final, settling_band(height))
    return StepMetrics(overshoot_pct=overshoot, settling_time_s=None if settled is None else float(t[settled]))
