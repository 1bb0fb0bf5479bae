"""What a log says about the device that ran it: how it turned v into DAC counts."""

from __future__ import annotations

from station.runlog import RunLog


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
