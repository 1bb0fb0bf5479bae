"""What tells apart two column rewrites a law reproduces alike (:mod:`station.logged.columns`).

A P law of gain 1 at alignment 0, v = u − θ, reads the same with θ negated as with u and v
swapped and its gain −1 (u = v + θ); only the physics tells which column is the reference and
which the command: a closed loop's angle follows its reference (:func:`tracking_error`), and the
hub's angle is what the plant makes of the command (:func:`model_miss`, the nominal model run
in closed loop by the rewrite's law; on a sweep the hub lags, and how closely θ follows u says
little).
"""

from __future__ import annotations

import numpy as np

from station.logged.simulate import nominal_theta
from station.runlog import RunLog


def tracking_error(log: RunLog) -> float:
    """RMS of u − θ over a log's finite rows, encoder counts (inf without any): how closely its
    hub follows its reference, as a closed loop's does.

    Parameters
    ----------
    log : RunLog

    Returns
    -------
    float
    """
    e = np.asarray(log.data["u"], dtype=float) - np.asarray(log.data["theta"], dtype=float)
    e = e[np.isfinite(e)]
    return float(np.sqrt(np.mean(e * e))) if e.size else np.inf


def model_miss(log: RunLog, law=None, alignment: int | None = None) -> float:
    """RMS of θ less the nominal model's θ, run in closed loop by the log's law, encoder counts
    (inf where the model cannot run it): which of two rewrites a law cannot decide puts the
    reference in u, the command in v and the hub's angle in θ (a P law of gain 1 reads the same
    with θ negated as with u and v swapped; on a sweep the hub lags, and how closely θ follows u
    says little). In closed loop, as the rig ran it: the model driven open loop by v drifts
    over a long run.

    Parameters
    ----------
    log : RunLog
    law : Compensator, OpenLoop or None
        The law the rewrite reproduces (None: the model driven by the logged v).
    alignment : int or None
        The law's alignment.
    """
    predicted = nominal_theta(log, law, alignment)
    if predicted is None:
        return np.inf
    miss = np.asarray(log.data["theta"], dtype=float) - predicted
    miss = miss[np.isfinite(miss)]
    return float(np.sqrt(np.mean(miss * miss))) if miss.size else np.inf


def tracks_better(trial: RunLog, log: RunLog) -> bool:
    """Whether a rewrite's θ follows its u more closely than as named (:func:`tracking_error`).
    Asked of u and v swapped beside a sign, where a law cannot decide: a P law of gain 1
    (v = u − θ) is the same law with u and v swapped and θ negated (u = v + θ), and only the
    tracking tells which column is the reference.

    Parameters
    ----------
    trial : RunLog
        The log rewritten.
    log : RunLog
        The log as named.
    """
    return tracking_error(trial) < tracking_error(log)
