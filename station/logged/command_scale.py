"""The size of a float command's unit, read by the header's law replayed on its own commands.

A command written as a float in another unit (the thesis's lead logs store the float command; a
script that wrote it in volts: 5/2048 V a count of a ±5 V 12-bit DAC) has no step to read its
unit from (:func:`station.logged.quantum.count_step`). A closed-loop law replayed on its own
past commands (:func:`station.control.rerun.replay_commands`) gives v in DAC counts whatever
unit the log wrote, so the least-squares ratio of the logged v to that replay is the unit's
size, and the replay is v in counts where it gives every logged v to its printing
(:func:`station.logged.columns.check_command_unit` reads v so).
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from station.analysis.controller_id import law_variants
from station.analysis.law_rows import TOLERANCE
from station.control.rerun import (ALIGNMENTS, command_error, is_closed_loop, judged_rows, memory,
                                   replay_commands)
from station.logged.column_zeros import theta_from_zero
from station.logged.controller import named_law
from station.logged.units import replayable_rate
from station.runlog import RunLog
from station.runlog.timebase import restart_rows


class Scaled(NamedTuple):
    """A float command read in DAC counts by the law (:func:`law_scale`).

    Attributes
    ----------
    ratio : float
        The log's v units in one DAC count.
    v : numpy.ndarray, shape (N,)
        The law's commands, DAC counts: the logged v divided by ``ratio``, to its printing.
    """

    ratio: float
    v: np.ndarray


def law_scale(log: RunLog, skipped=None) -> Scaled | None:
    """The log's v read in DAC counts by its header's law: the least-squares ratio of the
    logged v to the law replayed on its own commands, at the alignment it fits best, when that
    ratio times the replay gives every logged v to its printing (half its last digit:
    :func:`station.control.rerun.command_error`, in the unit v was written in, whose printing
    the division would lose).

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    Scaled or None
        None when the header names no closed-loop law, the rows are no loop's every tick, u, θ
        or v are not finite, the law commands nothing, the ratio is not positive (a reversed
        command is the motor's polarity, not a unit) or the law so scaled misses a logged v.
        Where n jumps (rows missing or repeated) the ratio is taken on the rows before the first
        jump, and the law replayed again from each jump with its memory the logged v in counts
        (:func:`station.control.rerun.judged_rows` are judged); a law whose memory is in no
        column (Ga's) is judged on the rows before the first jump, and past it v is the logged
        one in counts.
    """
    law = _replayable_law(log)
    if law is None:
        return None
    data = log.data
    v = np.asarray(data["v"], dtype=float)
    a = np.where(np.isfinite(data["a"]), data["a"], 0.0)
    restarts = restart_rows(data["n"])
    first = restarts[0] if restarts else v.size  # the ratio from the rows before n jumps, if it does
    rows_back = memory(law)
    for d in ALIGNMENTS:
        replayed, _ = replay_commands(law, data["u"], data["theta"], a, d, skipped)
        power = float(replayed[:first] @ replayed[:first])
        ratio = float(v[:first] @ replayed[:first]) / power if power > 0 else 0.0
        if ratio <= 0:
            continue
        if restarts and rows_back is not None:  # again from each jump, its memory the logged v in counts
            replayed, _ = replay_commands(law, data["u"], data["theta"], a, d, skipped, v / ratio, 0, restarts)
        elif restarts:  # Ga's memory is in no column: judged before the jump, v in counts past it as logged
            replayed = np.concatenate((replayed[:first], v[first:] / ratio))
        judged = judged_rows(v.size, d, 0, restarts, rows_back or 0)
        judged[first if rows_back is None else v.size:] = False
        if np.all(command_error(ratio * replayed, v, seeded=restarts)[judged] <= TOLERANCE):
            return Scaled(ratio, replayed)
    return None


COMMAND_READING_COUNTS = 1.5
"""Most DAC counts (of the law's, times its unit's size) the logged v may lie off a line through
the header's law replayed on its own commands for a rewrite to be asked of the whole audit
(:func:`law_line`): the stored integer's truncation and v's printing, loosely."""


def _replayable_law(log: RunLog):
    """The header's closed-loop law where it can be replayed on the log as logged (every tick of a
    loop, u, θ and v finite); else None."""
    law = named_law(log)
    if (law is None or not is_closed_loop(law) or not replayable_rate(log)
            or not all(np.all(np.isfinite(log.data[c])) for c in ("u", "theta", "v"))):
        return None
    return law


def law_line(log: RunLog, skipped=None) -> bool:
    """Whether the logged v lies on a line (a unit's size and a zero, any of the two) through the
    header's closed-loop law replayed on its own commands, from θ's first count where θ rests
    off 0 (:func:`station.logged.column_zeros.theta_from_zero`): a quick test of whether a
    rewrite of a log's columns leaves only the command's reading and θ's zero to find.

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`station.logged.controller.identify_controller`.

    Returns
    -------
    bool
        True when at some alignment, with the law's recursion as stated or on the stored integer
        or the whole count sent, the least-squares line gives every logged v before n first
        jumps (but at v's extremes: a clamp) within :data:`COMMAND_READING_COUNTS` of the law's
        counts; False when it does not, when the header names no closed-loop law, when u, θ
        or v is not finite, or when the law's command moves by less than a count there.
    """
    law = _replayable_law(log)
    if law is None:
        return False
    data = log.data
    zeroed = theta_from_zero(log)
    theta = (zeroed if zeroed is not None else log).data["theta"]
    v = np.asarray(data["v"], dtype=float)
    a = np.where(np.isfinite(data["a"]), data["a"], 0.0)
    restarts = restart_rows(data["n"])
    first = restarts[0] if restarts else v.size
    v = v[:first]
    inside = (v > v.min()) & (v < v.max())  # v at its extremes may be at a clamp the header does not print
    # as stated, and as lab software ran it: its recursion on the stored integer or the whole count
    # sent (a float replay of an integer lead drifts from it by up to 1/(1 - pole) counts)
    for d, form in itertools.product(ALIGNMENTS, list(law_variants(law, None))):
        replayed, _ = replay_commands(form, data["u"], theta, a, d, skipped)
        basis = np.column_stack((replayed[:first], np.ones(first)))[inside]
        if basis.shape[0] < 2 or not np.all(np.isfinite(basis)) or np.ptp(basis[:, 0]) < 1.0:
            continue  # (a law that moves its command by less than a count puts any v on a line)
        (size, zero), *_ = np.linalg.lstsq(basis, v[inside], rcond=None)
        miss = np.abs(basis @ (size, zero) - v[inside])
        if size > 0 and float(np.max(miss)) <= COMMAND_READING_COUNTS * size + 1e-9:
            return True
    return False
