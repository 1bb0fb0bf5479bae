"""References u[k], k = 0..n-1, for closed-loop steps and open-loop tests.

u is in encoder counts for closed loop and DAC counts for open loop (v = u).
Tick k is at t = k dt (DESIGN.md "Timing and log rows").
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from station.errors import StationError
from station.rig import DEFAULT_STEP_TICK, DT
from station.runlog import read_log


def _check_n(n: int) -> int:
    if isinstance(n, bool) or int(n) != n or n < 0:
        raise ValueError(f"n must be a non-negative whole number of ticks, got {n!r}")
    return int(n)


def step_reference(amplitude: float, n: int, at_tick: int = DEFAULT_STEP_TICK) -> np.ndarray:
    """A step: u[k] = amplitude for k >= at_tick, else 0.

    Parameters
    ----------
    amplitude : float
        Step height, encoder counts (station default 100).
    n : int
        Number of ticks.
    at_tick : int
        First tick of the step (default 10, t = 0.02 s at 500 Hz).

    Returns
    -------
    numpy.ndarray, shape (n,), float
    """
    n = _check_n(n)
    u = np.zeros(n)
    u[max(int(at_tick), 0):] = amplitude
    return u


def pulse_reference(amplitude: float, n: int, start_tick: int, width_ticks: int,
                    return_tick: int | None = None) -> np.ndarray:
    """Open-loop pulse test: +amplitude for width_ticks from start_tick, optionally
    -amplitude for width_ticks from return_tick (bringing the hub back).

    The rig's OL pulse log (DESIGN.md data table) is
    ``pulse_reference(100, 1000, 20, 50, return_tick=700)``: +100 for 0.1 s from
    t = 0.04 s, -100 for 0.1 s from t = 1.4 s.

    Parameters
    ----------
    amplitude : float
        Pulse height, DAC counts.
    n : int
        Number of ticks.
    start_tick, width_ticks : int
        First tick and length of the pulse, ticks.
    return_tick : int or None
        First tick of the opposite pulse; None for a single pulse.

    Returns
    -------
    numpy.ndarray, shape (n,), float

    Raises
    ------
    ValueError
        If the pulses overlap or a tick is negative.
    """
    n = _check_n(n)
    if start_tick < 0 or width_ticks < 0 or (return_tick is not None and return_tick < 0):
        raise ValueError("pulse ticks must be non-negative")
    if return_tick is not None and return_tick < start_tick + width_ticks:
        raise ValueError(f"return pulse at tick {return_tick} overlaps the first pulse "
                         f"(ticks {start_tick}..{start_tick + width_ticks - 1})")
    u = np.zeros(n)
    u[start_tick:start_tick + width_ticks] = amplitude
    if return_tick is not None:
        u[return_tick:return_tick + width_ticks] = -amplitude
    return u


def swept_sine_reference(n: int, amplitude: float = 50.0, dt: float = DT) -> np.ndarray:
    """The swept-sine log's reference: u = trunc(amplitude sin(2 pi (t-1)^2)) for
    1 < t <= 21 s, else 0; t = k dt (DESIGN.md; chirp at 2(t-1) Hz, 0..40 Hz).

    Parameters
    ----------
    n : int
        Number of ticks (the log has 11000).
    amplitude : float
        Peak, encoder counts.
    dt : float
        Sample time, s.

    Returns
    -------
    numpy.ndarray, shape (n,), float (whole numbers)
    """
    n = _check_n(n)
    t = np.arange(n) * dt
    u = np.trunc(amplitude * np.sin(2 * np.pi * (t - 1.0) ** 2))
    u[(t <= 1.0) | (t > 21.0)] = 0.0
    return u + 0.0  # no -0.0


def file_reference(path: str | Path, column: str = "u") -> np.ndarray:
    """A reference taken from a column of a run log (ours or the rig's).

    Parameters
    ----------
    path : str or Path
        A log readable by :func:`station.runlog.read_log`.
    column : str
        Standard column name (t, n, u, v, theta, a, theta_d_hat, ...).

    Returns
    -------
    numpy.ndarray, shape (rows,), float

    Raises
    ------
    StationError
        If the log cannot be read or has no such column (or it is empty there).
    """
    log = read_log(path)
    held = [name for name, x in log.data.items() if np.asarray(x).size and not np.all(np.isnan(np.asarray(x, float)))]
    if column not in held:  # a standard column the format lacks is all NaN
        raise StationError(f"{path}: no column {column!r} with values (the log's columns: {', '.join(held) or 'none'})")
    return np.asarray(log.data[column], dtype=float).copy()
