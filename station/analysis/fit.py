"""Goodness of fit of a simulated signal to a measured one (DESIGN.md "Model diagnosis")."""

from __future__ import annotations

import numpy as np


def nrmse_fit(y, yhat) -> float:
    """NRMSE fit in percent: 100 (1 - ||y - yhat|| / ||y - mean(y)||).

    100 is a perfect fit, 0 is no better than the measured mean, negative is worse.

    Parameters
    ----------
    y : array_like, shape (N,) or (N, ...)
        Measured signal (e.g. theta in encoder counts, a in accelerometer counts).
    yhat : array_like, same shape as ``y``
        Predicted signal, same units.

    Returns
    -------
    float
        The fit, percent; NaN when ``y`` is constant (the fit is undefined).

    Raises
    ------
    ValueError
        Shapes differ, arrays are empty, or either holds NaN.

    Notes
    -----
    Source: DESIGN.md "Model diagnosis contract" (fit_pct); the same as MATLAB's
    ``goodnessOfFit(yhat, y, 'NRMSE')`` times 100 and System Identification's "fit".
    """
    y = np.asarray(y, dtype=float)
    yhat = np.asarray(yhat, dtype=float)
    if y.shape != yhat.shape:
        raise ValueError(f"y and yhat must have the same shape, got {y.shape} and {yhat.shape}")
    if y.size == 0:
        raise ValueError("y and yhat are empty")
    if np.any(np.isnan(y)) or np.any(np.isnan(yhat)):
        raise ValueError("y or yhat holds NaN samples")
    denom = np.linalg.norm(y - y.mean())
    if denom == 0.0:
        return float("nan")
    return float(100.0 * (1.0 - np.linalg.norm(y - yhat) / denom))


def fit_pct(theta, theta_hat, a, a_hat, digits: int | None = None) -> dict[str, float | None]:
    """The NRMSE fits of a simulated run, as every report carries them (DESIGN.md ``fit_pct``).

    Parameters
    ----------
    theta, theta_hat : array_like, shape (N,)
        Measured and simulated θ, encoder counts.
    a, a_hat : array_like, shape (N,)
        Measured and simulated accelerometer counts.
    digits : int, optional
        Round each fit to this many decimals (default: not rounded).

    Returns
    -------
    dict
        ``{"theta": F, "accel": F}``, percent (:func:`nrmse_fit`); None where the fit is
        undefined (a constant measured signal, or one not measured: all NaN), ``-inf``
        where the simulation is not finite (it diverged).

    Raises
    ------
    ValueError
        As :func:`nrmse_fit`: shapes differ, arrays are empty, or a measured signal holds NaN.
    """
    out: dict[str, float | None] = {}
    for key, y, yhat in (("theta", theta, theta_hat), ("accel", a, a_hat)):
        if np.all(np.isnan(y)):  # not measured: a log without the column
            out[key] = None
            continue
        fit = nrmse_fit(y, yhat) if np.all(np.isfinite(yhat)) else float("-inf")
        out[key] = None if np.isnan(fit) else fit if digits is None else round(fit, digits)
    return out
