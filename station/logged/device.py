"""What a log says about the device that ran it: its sample time and how it turned v into DAC counts."""

from __future__ import annotations

import numpy as np

from station.runlog import RunLog


def log_dt(log: RunLog) -> float:
    """The log's sample time, s: the header's ``dt``, else the median step of t (0.002 s
    when the log has fewer than two rows). Every sample time of a logged run (the
    controller's, the model's, the beam test's) comes from here.

    Parameters
    ----------
    log : RunLog
        The log.
    """
    dt = log.meta.get("dt")
    if isinstance(dt, (int, float)) and not isinstance(dt, bool) and dt > 0:
        return float(dt)
    t = log.data["t"]
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.002
    return float(round(dt, 9) or 0.002)


def command_quantization(log: RunLog) -> str:
    """How the log's device turned v into DAC counts (for :func:`station.plant.simulate`).

    Our logs name their protocol: v1 rounds (halves away from zero), legacy truncates;
    a log of ours without a protocol did not come from a device (e.g. written from a
    simulation): "none". The rig's logs were recorded with its legacy firmware:
    truncation toward zero.

    Parameters
    ----------
    log : RunLog
        The log (its header's protocol and format decide).
    """
    if log.format != "station":
        return "trunc"
    return {"v1": "round", "legacy": "trunc"}.get(log.meta.get("protocol"), "none")
