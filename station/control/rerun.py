"""Run a controller over recorded samples, and find the alignment that reproduces a log.

DESIGN.md "Timing and log rows": v[k] = C(u[k], theta[k-d], a[k-d]) with the computational
delay d (the alignment), which the rig's headers do not state: :func:`detect_alignment`
finds it from the data. Arrays in, arrays out, no log reading: the controller
identification (:mod:`station.analysis.controller_id`) and the logged-run reader
(:mod:`station.logged`) both build on it.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from station.control.compensator import OpenLoop
from station.runlog.printing import Printing, printing_of

ALIGNMENTS = (0, 1)
"""Computational delays tried, samples (the rig's 2009 logs d = 0, its later logs and protocol v1 d = 1)."""

_BLOCK = 1 << 16
"""Samples per block of :func:`replay_commands`."""


def is_closed_loop(controller: Any) -> bool:
    """Whether a controller feeds θ back: the one definition of "closed loop".

    Parameters
    ----------
    controller : Compensator, OpenLoop, an object with step/reset and ``spec``, or None
        None (no controller known) and open loop (an :class:`OpenLoop`, or a ``spec`` of
        kind "open-loop") are not closed loop; anything else is.

    Returns
    -------
    bool
    """
    if controller is None or isinstance(controller, OpenLoop):
        return False
    spec = getattr(controller, "spec", None)
    return not (isinstance(spec, dict) and spec.get("kind") == "open-loop")


def replay_commands(controller, u, theta, a, alignment: int, skipped=None, v=None,
                    primed: int = 0, restarts=()) -> tuple[np.ndarray, np.ndarray]:
    """Run a controller over logged samples: v[k] = C(u[k], theta[k-d], a[k-d]).

    Before the first sample (k < d) there is nothing to compute from: v[k] = 0 and
    theta_d_hat[k] = u[k], and the controller is not stepped (as :func:`station.loop.run_loop`
    and the device do: tick 0 outputs 0; the rig's logs start with v[0] = 0). A sample the
    station skipped (``skipped[k-d]``, our logs' :data:`station.runlog.SKIPPED` bit) was not
    answered either: the controller is not stepped on it and v[k], theta_d_hat[k] are
    those of the row before (the command the device held).

    Parameters
    ----------
    controller : Compensator or OpenLoop
        Reset before and after the run.
    u : array_like, shape (N,)
        Reference, encoder counts (DAC counts in open loop).
    theta, a : array_like, shape (N,)
        Logged encoder and accelerometer counts.
    alignment : int
        d >= 0, samples.
    skipped : array_like of bool, shape (N,), optional
        The samples the station did not answer (default: none).
    v : array_like, shape (N,), optional
        The logged commands (needed with ``primed``).
    primed : int
        The first ``primed`` rows from d on are not computed: their logged u, θ, a and v
        go into the controller's history (:meth:`station.control.compensator.Compensator.prime`),
        as a copy cut from a longer run had it; their v is the logged one. 0 (default):
        the controller starts at rest. Controllers without ``prime`` start at rest.
    restarts : sequence of int, optional
        Rows where the log's ticks jump (rows missing or repeated before them:
        :func:`station.runlog.timebase.restart_rows`). The replay starts again at each as on a
        copy cut from a longer run: its first d rows' v are the logged ones (computed from
        samples the log lacks), and the next :func:`memory` rows go into the controller's
        history as logged. Needs ``v``.

    Returns
    -------
    v, theta_d_hat : numpy.ndarray, shape (N,)
        The commands (DAC counts) and the reference after accelerometer feedback (encoder
        counts).

    Raises
    ------
    ValueError
        ``alignment`` < 0.
    """
    d = int(alignment)
    if d < 0:
        raise ValueError(f"alignment must be >= 0, got {alignment}")
    u = np.asarray(u, dtype=float)
    rows_back = memory(controller)
    restarts = () if v is None or rows_back is None else restarts
    bounds = [0, *sorted(int(r) for r in restarts if 0 < r < u.size), u.size]
    if len(bounds) > 2:
        theta, a, v = (np.asarray(x, dtype=float) for x in (theta, a, v))
        v_out, hat_out = np.zeros(u.size), u.copy()
        for i, (lo, hi) in enumerate(zip(bounds[:-1], bounds[1:])):
            part = slice(lo, hi)
            v_out[part], hat_out[part] = replay_commands(
                controller, u[part], theta[part], a[part], d, None if skipped is None else np.asarray(skipped)[part],
                v[part], primed if i == 0 else rows_back)
            if i:  # computed from samples of ticks the log lacks: the logged commands
                v_out[lo:min(lo + d, hi)] = v[lo:min(lo + d, hi)]
        return v_out, hat_out
    n = u.size
    theta = np.asarray(theta, dtype=float)
    a = np.asarray(a, dtype=float)
    v_out = np.zeros(n)
    hat_out = u.copy()  # k < d: theta_d_hat = u
    rows = np.arange(min(d, n), n)
    held = None
    if skipped is not None:
        skipped = np.asarray(skipped, dtype=bool)
        held = skipped[rows - d]
        rows = rows[~held] if held.any() else rows
    controller.reset()
    prime = getattr(controller, "prime", None)
    if primed > 0 and v is not None and prime is not None:
        logged = np.asarray(v, dtype=float)
        for k in rows[:primed].tolist():
            v_out[k], hat_out[k] = prime(float(u[k]), float(theta[k - d]), float(a[k - d]), float(logged[k]))
        rows = rows[primed:]
    step = controller.step
    # in blocks: Python floats for speed, without a list per sample of a 100 MB log at once
    for lo in range(0, rows.size, _BLOCK):
        k = rows[lo:lo + _BLOCK]
        uu, th, ac = u[k].tolist(), theta[k - d].tolist(), a[k - d].tolist()
        out = [step(x, y, z) for x, y, z in zip(uu, th, ac)]
        block = np.array(out, dtype=float).reshape(k.size, 2)
        v_out[k], hat_out[k] = block[:, 0], block[:, 1]
    controller.reset()
    if held is not None and held.any():  # skipped samples: the row before's command, held
        source = np.arange(n)
        source[min(d, n):][held] = 0
        source = np.maximum.accumulate(source)
        v_out, hat_out = v_out[source], hat_out[source]
    return v_out, hat_out


def memory(controller) -> int | None:
    """Rows of e and v a controller's recursion remembers, all of which a log holds: its
    ``history`` when it has ``prime`` and no accelerometer feedback; 0 for a law without
    memory (open loop); None when its memory is not all in the log (Ga's state is a's whole
    past, a custom controller's is its own): a replay cannot start again from logged rows.

    Parameters
    ----------
    controller : Compensator, OpenLoop or an object with step/reset

    Returns
    -------
    int or None
    """
    if isinstance(controller, OpenLoop):
        return 0
    if not callable(getattr(controller, "prime", None)) or getattr(controller, "ga", None) is not None:
        return None
    return int(getattr(controller, "history", 0))


def judged_rows(n: int, alignment: int, primed: int = 0, restarts=(), memory_rows: int = 0) -> np.ndarray:
    """The rows whose replayed command a log can judge, as a mask.

    Rows k < d were computed from samples before the log (0 on a run logged from its start,
    the earlier run's on a copy cut from one), and the ``primed`` rows after them were taken
    as logged; after each restart (:func:`replay_commands`) the same d + ``memory_rows`` rows.
    At least the last row is judged, unless the restarts leave none (every row follows a jump
    of n within d + ``memory_rows``: nothing the log holds can judge the law there).

    Parameters
    ----------
    n : int
        Rows.
    alignment : int
        d, samples.
    primed : int
        Rows primed at the start.
    restarts : sequence of int
        Rows where the replay starts again.
    memory_rows : int
        Rows primed after each restart (:func:`memory`).

    Returns
    -------
    numpy.ndarray of bool, shape (n,)
    """
    mask = np.ones(n, dtype=bool)
    d = max(int(alignment), 0)
    mask[:min(d + primed, max(n - 1, 0))] = False
    for r in restarts:
        if 0 < r < n:
            mask[r:r + d + memory_rows] = False
    if n and not mask.any() and not any(0 < r < n for r in restarts):  # a short log: its last row
        mask[-1] = True
    return mask


class AlignmentFit(NamedTuple):
    """The alignment with which a controller best reproduces logged commands (:func:`detect_alignment`).

    Attributes
    ----------
    alignment : int
        The computational delay d, samples.
    max_abs_dv : float
        max |v_replayed - v_logged| with it, DAC counts, less what the log's printing of v
        allows (:func:`command_error`; nothing for whole counts and full floats).
    v_replayed : numpy.ndarray, shape (N,)
        The replayed commands, DAC counts (as computed).
    """

    alignment: int
    max_abs_dv: float
    v_replayed: np.ndarray


_OF_V = object()  # command_error's default: v's printing decided there

COMMAND_PRINT_FLOOR = 5e-7
"""A logged v printed this finely or finer is compared as computed (half the 1e-6 counts a
law must meet: :data:`station.analysis.law_rows.TOLERANCE`; ``%.6f``, the lab's ``%0.10g``)."""


def printed_commands(v) -> Printing | None:
    """How the log printed its commands, when coarser than :data:`COMMAND_PRINT_FLOOR`
    (:func:`station.runlog.printing.printing_of`); None otherwise (whole counts, full floats,
    the lab's ``%0.10g`` of a lead's float command).

    Parameters
    ----------
    v : array_like, shape (N,)
        The logged commands, DAC counts.
    """
    return printing_of(v, COMMAND_PRINT_FLOOR)


PRINT_HISTORY = 8
"""The most last-digit halves a law's value may be from a printed v when the law's history is
the printed v too (:func:`print_allowance`): one for the row's own printing, and up to 2^3 - 1
more through a recursion of order 3 (a stable denominator's sum of |a_j| is at most
2^order - 1)."""


def print_allowance(v, printing: Printing, history: bool = False) -> np.ndarray:
    """How far a law's value may be from each printed v, DAC counts.

    Parameters
    ----------
    v : array_like, shape (N,)
        The logged commands.
    printing : Printing
        Their printing (:func:`printed_commands`).
    history : bool
        False: a law replayed on its own values, whose only error is the row's printing
        (half its last digit, and a float's rounding); True: a law whose history is the
        printed v (:class:`station.analysis.law_rows.LawRows`), :data:`PRINT_HISTORY` halves of
        the coarsest last digit among the row and the three before it.

    Returns
    -------
    numpy.ndarray, shape (N,)
    """
    v = np.asarray(v, dtype=float)
    res = printing.resolution(v)
    if not history:
        return res * (1.0 + 1e-9) + 4.0 * np.finfo(float).eps * np.abs(v)
    back = res.copy()
    for j in range(1, 4):
        back[j:] = np.maximum(back[j:], res[:-j])
    return PRINT_HISTORY * back


SEEDED_ROWS = 100
"""Rows after a replay takes its memory from the printed v (a cut copy's first rows, a jump of
n) over which the printed memory's error is allowed to die out (:data:`PRINT_HISTORY`)."""


def command_error(v_replayed, v, printing=_OF_V, seeded=()) -> np.ndarray:
    """|v_replayed - v|, less what the log's printing of v allows (:func:`printed_commands`:
    a float command written to 6 significant digits is 183.255 where the law gives
    183.2547182: half its last digit is allowed, :func:`print_allowance`; nothing for whole
    counts and full floats).

    Parameters
    ----------
    v_replayed, v : array_like, shape (N,)
        The replayed and the logged commands, DAC counts.
    printing : Printing or None, optional
        v's printing when already decided (None: printed in full); by default
        :func:`printed_commands`.
    seeded : sequence of int
        Rows where the replay took its memory from the printed v: for :data:`SEEDED_ROWS`
        from each, the history's allowance (:func:`print_allowance`).

    Returns
    -------
    numpy.ndarray, shape (N,)
        0 where the replay is within the printing; inf where it left the finite numbers and
        the log did not (NaN only where the log's own v is).
    """
    v = np.asarray(v, dtype=float)
    replayed = np.asarray(v_replayed, dtype=float)
    err = np.abs(replayed - v)
    err[np.isfinite(v) & ~np.isfinite(replayed)] = np.inf  # a replay that diverged (an unstable law): no match, not NaN
    if printing is _OF_V:
        printing = printed_commands(v)
    if printing is None:
        return err
    allowed = print_allowance(v, printing)
    if len(seeded):
        near = np.zeros(v.size, dtype=bool)
        for r in seeded:
            near[max(int(r), 0):int(r) + SEEDED_ROWS] = True
        allowed = np.where(near, print_allowance(v, printing, history=True), allowed)
    return np.maximum(err - allowed, 0.0)


def detect_alignment(controller, u, theta, a, v, alignments=ALIGNMENTS, skipped=None,
                     primed: int = 0, restarts=()) -> AlignmentFit:
    """The computational delay d with which ``controller`` best reproduces the logged
    commands ``v`` (DESIGN.md: headers do not say; the data do).

    Parameters
    ----------
    controller : Compensator or OpenLoop
    u, theta, a, v : array_like, shape (N,), N >= 1
        The log's reference, samples and commands.
    alignments : sequence of int
        The delays tried, samples (default :data:`ALIGNMENTS`).
    skipped : array_like of bool, shape (N,), optional
        The samples the station did not answer (:func:`replay_commands`).
    primed : int
        Rows from d on taken into the controller's history as logged and not judged
        (:func:`replay_commands`: a copy cut from a longer run).
    restarts : sequence of int
        Rows where the log's ticks jump: the replay starts again there
        (:func:`replay_commands`), and the rows it takes as logged are not judged.

    Returns
    -------
    AlignmentFit
        The best alignment (the first tried on a tie), its max |dv| over the rows judged
        (:func:`judged_rows`) and the replayed v; unpacks as ``(d, max_abs_dv, v_replayed)``.
    """
    v = np.asarray(v, dtype=float)
    printing = printed_commands(v)
    best = None
    for d in alignments:
        v_hat, _ = replay_commands(controller, u, theta, a, d, skipped, v, primed, restarts)
        rows_back = memory(controller)
        judged = judged_rows(v.size, d, primed, () if rows_back is None else restarts, rows_back or 0)
        seeded = (d + primed,) * bool(primed) + tuple(restarts)
        # no row judged (every row follows a jump of n within d): this alignment cannot be told
        err = float(np.max(command_error(v_hat, v, printing, seeded)[judged])) if judged.any() else math.inf
        if best is None or err < best.max_abs_dv:
            best = AlignmentFit(d, err, v_hat)
    return best


def pole_radius(controller) -> float:
    """The largest |pole| of a controller's filters (its Gth and Ga), 0 for one without memory
    (a P law, an open loop): at 1 or more its recursion does not fade.

    Parameters
    ----------
    controller : Compensator, OpenLoop or an object with ``gth`` / ``ga`` DiscreteTFs

    Returns
    -------
    float
    """
    dens = [np.asarray(tf.den, dtype=float) for tf in (getattr(controller, "gth", None), getattr(controller, "ga", None))
            if tf is not None and len(tf.den) > 1]
    return max((float(np.max(np.abs(np.roots(den)))) for den in dens), default=0.0)
