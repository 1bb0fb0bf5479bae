"""Isolated rows no law gives: a corrupted field in a log a law otherwise reproduces.

A serial line or a log writer can corrupt one field (a digit dropped, a bit flipped): the law
then misses that row of v, or the rows its θ feeds, and reproduces every other row. Judged by its largest
miss alone, such a log "contradicts" its header, and at the other alignment the miss can be a
count smaller, so the alignment flips too. Rows the law misses alone, few and far beyond a
printing's count, and a θ whose neighbour in its place makes the law reproduce the rows it fed,
are set aside instead and said: they are not a law's.
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

from station.analysis.accel_law import arx_rows_off
from station.analysis.controller_id import (MAX_ORDER, PREFERRED_ALIGNMENT, IdentifiedController, aligned_error,
                                           clamps_to_try, infer_controller, law_variants)
from station.analysis.header_law import NEAR_COUNTS
from station.analysis.law_rows import TOLERANCE, LawRows, pins_a_law
from station.control import Compensator, OpenLoop
from station.control.rerun import (ALIGNMENTS, AlignmentFit, command_error, is_closed_loop, judged_rows, memory,
                                   pole_radius, replay_commands)
from station.rig import CLAMP, DAC_LIMIT, DT

GLITCH_WORDS = "what no law gives, as a corrupted field has it; set aside, the law reproduces every other row"
"""Why rows a law misses alone are set aside, said after them."""

MAX_GLITCH_ROWS = 3
"""Most rows a law may miss and still be the log's, each alone (a corrupted field); and at
most 1 % of the rows judged."""


def most_glitches(rows: int) -> int:
    """Most corrupted fields a log of ``rows`` rows may have set aside: :data:`MAX_GLITCH_ROWS`,
    and at most 1 % of the rows (0 below 100 rows: a short log's misses are a law's).

    Parameters
    ----------
    rows : int
        The log's rows.

    Returns
    -------
    int
        The most rows whose fields may be set aside as corrupted.
    """
    return min(MAX_GLITCH_ROWS, rows // 100)


MIN_STRETCH = 100
"""Fewest rows between corrupted fields that :func:`law_past_glitches` infers a law on."""

MIN_ACCEL_ROWS = 250
"""Fewest first rows :func:`law_past_glitches` infers a law with accelerometer feedback on (0.5 s at
the rig's rate)."""


class Glitches(NamedTuple):
    """A law that reproduces every row of a log but for a few isolated corrupted fields.

    Attributes
    ----------
    law : Compensator or OpenLoop
        The law in the form that reproduces the other rows (:func:`station.analysis.controller_id.law_variants`).
    fit : AlignmentFit
        The law at that alignment, its max |dv| over the rows not set aside, replayed on the
        log with its corrupted θ fields repaired.
    rows : tuple of int
        The rows whose v is set aside (a corrupted v, 0-based).
    theta_rows : tuple of int
        The rows whose θ was corrupted: the law reproduces every row after them with θ there
        taken from a neighbouring row.
    a_rows : tuple of int
        The rows whose a was corrupted: the law reproduces every row after them with a there
        solved from the law.
    u_rows : tuple of int
        The rows whose u was corrupted: the law reproduces every row from them with u there
        taken from a neighbouring row (the reference the loop ran on).
    u, theta, a : numpy.ndarray, shape (N,)
        The log's u, θ and a with those rows put right.
    """

    law: Compensator | OpenLoop
    fit: AlignmentFit
    rows: tuple[int, ...]
    theta_rows: tuple[int, ...]
    a_rows: tuple[int, ...]
    u_rows: tuple[int, ...]
    u: np.ndarray
    theta: np.ndarray
    a: np.ndarray

    def repaired(self, v) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The log's u, θ, a and v with the corrupted fields put right (v: the law's there).

        Parameters
        ----------
        v : array_like, shape (N,)
            The logged commands.

        Returns
        -------
        (u, theta, a, v) : numpy.ndarray, shape (N,) each
        """
        v = np.array(v, dtype=float)
        if self.rows:
            v[list(self.rows)] = self.fit.v_replayed[list(self.rows)]
        return self.u, self.theta, self.a, v

    def words(self, v, t, u, theta, a) -> str:
        """``v of row 499 at t = 0.998 s (logged 33, the law's 71)``, ``θ of row 300 at t = 0.6 s
        (logged 72, its neighbours 52 and 52)``, ``u of row 500 at t = 1 s (logged 114, its
        neighbours 50 and 50)``: each row by its index among the log's data rows, from 0, and
        its time.

        Parameters
        ----------
        v, t, u, theta, a : array_like, shape (N,)
            The logged commands (DAC counts), times (s), reference and hub angle (encoder
            counts) and accelerometer (counts), as logged.
        """
        v_hat = self.fit.v_replayed
        each = [f"v of row {k} at t = {t[k]:g} s (logged {v[k]:g}, the law's {v_hat[k]:.6g})" for k in self.rows]
        each += [f"θ of row {k} at t = {t[k]:g} s (logged {theta[k]:g}, its {neighbours_words(theta, k)})"
                 for k in self.theta_rows]
        each += [f"a of row {k} at t = {t[k]:g} s (logged {a[k]:g})" for k in self.a_rows]
        each += [f"u of row {k} at t = {t[k]:g} s (logged {u[k]:g}, its {neighbours_words(u, k)})" for k in self.u_rows]
        return ", ".join(each)


def neighbours_words(x, k: int) -> str:
    """``neighbours 52 and 52`` (or ``neighbour 50`` at the log's first or last row): a field's
    neighbouring rows, as a corrupted field is said beside them.

    Parameters
    ----------
    x : array_like, shape (N,)
        The column.
    k : int
        The field's row.

    Returns
    -------
    str
    """
    near = [f"{x[j]:g}" for j in (k - 1, k + 1) if 0 <= j < len(x)]
    return f"neighbours {near[0]} and {near[1]}" if len(near) == 2 else f"neighbour {near[0]}"


def _misses(controller, u, theta, a, v, d, skipped, restarts, rows_back,
            above: float = TOLERANCE) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The rows the law misses by more than ``above``, |dv| on every row (0 where not
    judged), and the replayed v."""
    v_hat, _ = replay_commands(controller, u, theta, a, d, skipped, v, 0, restarts)
    judged = judged_rows(v.size, d, 0, () if rows_back is None else restarts, rows_back or 0)
    err = np.where(judged, command_error(v_hat, v, seeded=tuple(restarts)), 0.0)
    return np.flatnonzero(err > above), err, v_hat


def isolated_misses(controller, u, theta, a, v, alignments=ALIGNMENTS, skipped=None,
                    restarts=(), slack: float = TOLERANCE) -> Glitches | None:
    """Corrupted fields that alone keep ``controller`` from reproducing a log: at most
    :data:`MAX_GLITCH_ROWS` (and 1 % of the rows), each a v the law misses alone (the rows
    beside it within ``slack``) by more than :data:`station.analysis.header_law.NEAR_COUNTS` (a
    law a count off is a printing's, :func:`station.analysis.header_law.completed_law`), or a θ
    whose row's neighbour, put in its place, makes the law reproduce the rows it fed (a law
    with memory carries a corrupted θ into many rows), or an a solved so, or a u so put right. Every other row
    must be within ``slack``, at the alignment where the law misses fewest, and pin the law
    (:func:`station.analysis.law_rows.pins_a_law`; not asked of an open-loop law). Of the law's
    forms (:func:`station.analysis.controller_id.law_variants`), the one nearest the other rows.
    Cheap on a law another law wrote: each form's misses must first fall in a few windows of its
    fading echo (one replay per alignment; a law without memory is gated once, its forms
    differing by a count at most), or no repair is tried.

    Parameters
    ----------
    controller : Compensator or OpenLoop
        A law replayed over the log (:func:`station.control.rerun.replay_commands`).
    u, theta, a, v : array_like, shape (N,)
        The log's reference, hub angle, accelerometer and commands, counts.
    alignments : sequence of int
    skipped : array_like of bool, optional
    restarts : sequence of int
        Rows where the log's ticks jump.
    slack : float
        The most the law may miss any other row by, DAC counts: the law's tolerance, or
        :data:`station.analysis.header_law.NEAR_COUNTS` for a header's printed coefficients,
        which :func:`station.analysis.header_law.completed_law` then completes on the
        repaired log (:meth:`Glitches.repaired`).

    Returns
    -------
    Glitches or None
        None when the law misses no row, or more than a few corrupted fields explain.
    """
    v = np.asarray(v, dtype=float)
    most = most_glitches(v.size)
    if _fading_rows(controller) == 1 and not any(
            0 < _episodes(_misses(controller, u, theta, a, v, d, skipped, restarts, memory(controller), slack)[0],
                          1) <= most for d in alignments):
        return None  # (a law with memory: each form is gated so in _isolated, before any repair)
    found = [g for law in law_variants(controller, v)
             if (g := _isolated(law, u, theta, a, v, alignments, skipped, restarts, slack)) is not None]
    return min(found, key=lambda g: g.fit.max_abs_dv, default=None)


def _isolated(controller, u, theta, a, v, alignments, skipped, restarts, slack) -> Glitches | None:
    rows_back = memory(controller)
    ranked = []
    for d in alignments:
        small, err, _ = _misses(controller, u, theta, a, v, d, skipped, restarts, rows_back)
        ranked.append((int(np.count_nonzero(err > slack)), small.size, d, np.flatnonzero(err > slack)))
    best = min(ranked, key=lambda r: r[:3], default=None)
    if best is None or not best[1]:
        return None
    d, miss = best[2], best[3]
    most = most_glitches(v.size)
    if _episodes(miss, _fading_rows(controller)) > most:
        return None  # misses spread past what a few fields' fading echoes reach: a law's, not a field's
    cols = {"u": np.array(u, dtype=float), "theta": np.array(theta, dtype=float), "a": np.array(a, dtype=float)}
    bad_v: list[int] = []
    bad: dict[str, list[int]] = {name: [] for name in cols}
    while miss.size and len(bad_v) + sum(map(len, bad.values())) < most:
        first = int(miss[0])
        fixed = _repaired(controller, cols, v, d, first, bad_v, skipped, restarts, rows_back, slack)
        onset = _onset(controller, cols, v, d, first, skipped, restarts, rows_back) if fixed is None else first
        if onset < first:  # a law with memory grows a field's echo past the slack rows after its first miss
            fixed = _repaired(controller, cols, v, d, onset, bad_v, skipped, restarts, rows_back, slack)
        if fixed is not None:
            cols, miss, column, row = fixed
            bad[column].append(row)
            continue
        if miss.size > 1 and miss[1] == first + 1:
            return None  # rows missed together: a law's miss, not a field's
        bad_v.append(first)
        miss = miss[1:]
    if miss.size or not (bad_v or any(bad.values())):
        return None
    _, err, v_hat = _misses(controller, cols["u"], cols["theta"], cols["a"], v, d, skipped, restarts, rows_back)
    kept = np.ones(v.size, bool)
    kept[bad_v] = False
    if np.any(err[bad_v] <= NEAR_COUNTS) or (is_closed_loop(controller) and not pins_a_law(v[kept])):
        return None
    return Glitches(controller, AlignmentFit(d, float(np.max(err[kept], initial=0.0)), v_hat), tuple(bad_v),
                    tuple(bad["theta"]), tuple(bad["a"]), tuple(bad["u"]), cols["u"], cols["theta"], cols["a"])


ONSET_ROWS = 50
"""Most rows before the first row a law misses by more than its slack that a field's echo may
have grown over from its first miss (:func:`_onset`)."""


def _onset(controller, cols, v, d, first, skipped, restarts, rows_back) -> int:
    """The first of the rows up to ``first`` that the law misses by more than
    :data:`~station.analysis.law_rows.TOLERANCE` without a break (at most :data:`ONSET_ROWS`
    back): where a corrupted field's echo began (an a under Ga's slow poles: 0.46, 1.7, then
    3.2 counts), the row to put right from."""
    err = _misses(controller, cols["u"], cols["theta"], cols["a"], v, d, skipped, restarts, rows_back)[1]
    onset = first
    while onset > max(0, first - ONSET_ROWS) and err[onset - 1] > TOLERANCE:
        onset -= 1
    return onset


def _fading_rows(controller) -> int:
    """Rows over which a law's recursion carries a corrupted input, until its slowest pole has
    faded it a thousandfold (1 for a law without memory)."""
    radius = pole_radius(controller)
    if radius <= 0.0:
        return 1
    if radius >= 1.0:
        return 10 ** 9  # an integrator: an echo that never fades
    return int(np.ceil(np.log(1e-3) / np.log(radius))) + 1


def _episodes(rows, reach: int) -> int:
    """How many windows of ``reach`` rows, each opened at a row not in the one before, cover ``rows``."""
    count, end = 0, -1
    for k in rows:
        if k > end:
            count, end = count + 1, int(k) + reach
    return count


def _repaired(controller, cols, v, d, first, bad_v, skipped, restarts, rows_back, slack):
    """One field put right so that the law reproduces row ``first`` and the next, missing
    fewest rows: θ of the row the law read there (``first - d``) from its neighbouring rows or
    a count between them; a there (noisy between rows) solved from the law's slope in it
    (rounded to a whole count when a is logged in whole counts); u of row ``first`` between its
    neighbouring rows (:func:`_u_guesses`). (columns, the misses left, the column, its row), or None."""
    u, theta, a = cols["u"], cols["theta"], cols["a"]
    j = first - d  # the θ and a row the law read there
    trials = []
    if 0 < j < theta.size - 1:
        low, high = sorted((theta[j - 1], theta[j + 1]))
        between = np.arange(np.ceil(low), np.floor(high) + 1) if high - low <= 8 else np.array([low, high])
        trials += [("theta", j, float(guess)) for guess in dict.fromkeys((low, high, *between)) if guess != theta[j]]
        v_hat = _misses(controller, u, theta, a, v, d, skipped, restarts, rows_back)[2]
        nudged = a.copy()
        nudged[j] += 1.0
        slope = _misses(controller, u, theta, nudged, v, d, skipped, restarts, rows_back)[2][first] - v_hat[first]
        if slope:
            guess = a[j] + (v[first] - v_hat[first]) / slope
            whole = np.all(a[np.isfinite(a)] == np.round(a[np.isfinite(a)]))
            guess = float(np.round(guess)) if whole else float(guess)
            trials += [("a", j, guess)] if guess != a[j] else []
    trials += [("u", first, guess) for guess in _u_guesses(controller, cols, v, d, first, skipped, restarts, rows_back)]
    best = None
    for column, row, guess in trials:
        trial = {**cols, column: cols[column].copy()}
        trial[column][row] = guess
        _, err, _ = _misses(controller, trial["u"], trial["theta"], trial["a"], v, d, skipped, restarts, rows_back)
        err[bad_v] = 0.0
        left = np.flatnonzero(err > slack)
        score = int(np.count_nonzero(err > TOLERANCE))
        if (not left.size or left[0] > first + 1) and (best is None or score < best[0]):
            best = (score, (trial, left, column, row))
    return None if best is None else best[1]


def _u_guesses(controller, cols, v, d, first, skipped, restarts, rows_back) -> list[float]:
    """What u of row ``first`` may have been, when the logged one lies outside its neighbours
    (a reference steps or sweeps through its rows; a value past both neighbours is a corrupted
    field's, a v corrupted under a law without memory is not read as one): the neighbours, their
    mean, every whole count between them (u in whole counts), and the u that makes the law give
    the logged v there, solved from its slope, when no further past them than the reference's
    rows lie past theirs elsewhere (its largest second difference, at least a count)."""
    u = cols["u"]
    near = [float(u[k]) for k in (first - 1, first + 1) if 0 <= k < u.size and np.isfinite(u[k])]
    if not near or min(near) <= u[first] <= max(near):
        return []
    low, high = min(near), max(near)
    # how far a row of this reference lies past its neighbours elsewhere (a sine's peak, a step)
    bend = np.abs(np.diff(u, 2))
    bend[max(first - 2, 0):first + 1] = 0.0
    reach = max(1.0, float(np.max(bend[np.isfinite(bend)], initial=0.0)))
    whole = bool(np.all(u[np.isfinite(u)] == np.round(u[np.isfinite(u)])))
    mean = float(np.mean(near))
    guesses = [float(np.round(mean)) if whole else mean, low, high]
    guesses += list(np.arange(np.ceil(low), np.floor(high) + 1)) if whole and high - low <= 8 else []
    v_hat = _misses(controller, u, cols["theta"], cols["a"], v, d, skipped, restarts, rows_back)[2]
    nudged = u.copy()
    nudged[first] += 1.0
    slope = _misses(controller, nudged, cols["theta"], cols["a"], v, d, skipped, restarts, rows_back)[2][first] - \
        v_hat[first]
    if slope:
        solved = u[first] + (v[first] - v_hat[first]) / slope
        if low - reach <= solved <= high + reach:
            guesses.append(float(np.round(solved)) if whole else float(solved))
    return [float(g) for g in dict.fromkeys(guesses) if g != u[first]]


def law_past_glitches(u, theta, a, v, dt: float = DT, rig_limit: float = CLAMP, alignments=ALIGNMENTS,
                      prefer: int | None = PREFERRED_ALIGNMENT) -> tuple[IdentifiedController, Glitches] | None:
    """The law of a log that no law reproduces whole, for a few corrupted fields: inferred on a
    stretch they left clean (between the rows a least-squares law misses, :func:`_rows_off`)
    (:func:`station.analysis.controller_id.infer_controller`, the stretch's first rows of
    history taken as logged), then accepted on the whole log only as :func:`isolated_misses`
    accepts a law (at most :data:`MAX_GLITCH_ROWS` isolated fields, every other row reproduced).
    A header-less log, or one whose header lies, with a serial glitch in it. A law with
    accelerometer feedback, whose Ga state no log holds (no stretch after a glitch, no least
    squares of one input finds it), is inferred on the log's first half or quarter and judged
    on the whole log the same way.

    Parameters
    ----------
    u, theta, a, v : array_like, shape (N,)
        The log's reference, hub angle, accelerometer and commands, counts.
    dt : float
        Sample time, s.
    rig_limit : float
        The clamp assumed where a stretch never reaches one, DAC counts.
    alignments : sequence of int
    prefer : int or None
        As :func:`station.analysis.controller_id.infer_controller`.

    Returns
    -------
    (IdentifiedController, Glitches) or None
        The law as a stretch gave it, and the fields set aside on the whole log; None when no
        stretch gives a law, or none holds on the whole log but for a few fields.
    """
    u, theta, a, v = (np.asarray(x, dtype=float) for x in (u, theta, a, v))
    tried: set[str] = set()
    for off in _rows_off(u, theta, v, alignments, rig_limit, most_glitches(v.size)):
        # the stretches between the rows missed, longest first: a law inferred on one never read them
        edges = np.concatenate(([-1], off, [v.size]))
        stretches = sorted(((int(b - a - 1), int(a + 1)) for a, b in zip(edges[:-1], edges[1:])), reverse=True)
        for length, start in stretches[:2]:
            if length < MIN_STRETCH:
                break
            piece = slice(start, start + length)
            hit = infer_controller(u[piece], theta[piece], v[piece], a[piece], dt, rig_limit, alignments, prefer,
                                   cut=start > 0)
            if hit is None or hit.law in tried:
                continue
            tried.add(hit.law)
            found = isolated_misses(hit.controller, u, theta, a, v, alignments, slack=TOLERANCE)
            if found is not None:
                return hit, found
    for end in (v.size // 2, v.size // 4) if np.any(a != a[0]) else ():
        gated = end >= MIN_ACCEL_ROWS and _arx_glitches(u, theta, a, v, end, alignments, rig_limit)
        hit = infer_controller(u[:end], theta[:end], v[:end], a[:end], dt, rig_limit, alignments, prefer,
                               accel_only=True) if gated else None
        found = None if hit is None else isolated_misses(hit.controller, u, theta, a, v, alignments, slack=TOLERANCE)
        if found is not None:
            return hit, found
    return None


def _rows_off(u, theta, v, alignments, rig_limit: float, most: int) -> list[np.ndarray]:
    """The rows a linear law with the logged v as its history misses past its whole counts'
    :meth:`~station.analysis.law_rows.LawRows.reach`, for each order, alignment and clamp where
    they fall in at most ``most`` windows of its order + 1 rows (with the logged history a
    corrupted field reaches no further): fewest first, each set once ([] for a log no law of
    these gives, or one it gives whole). Least squares twice: the second without the rows the
    first missed by far (a corrupted field pulls it)."""
    found: set[tuple[int, ...]] = set()
    # a corrupted v past the DAC's range is no clamp: the clamps of the rows within it too
    limits = dict.fromkeys(clamps_to_try(v, rig_limit) + clamps_to_try(v[np.abs(v) <= DAC_LIMIT], rig_limit))
    for order in range(MAX_ORDER + 1):
        for d in alignments:
            e = aligned_error(u, theta, d)
            for limit in limits:
                rows = LawRows(e, v, d, order, limit)
                keep = ~rows.clamped
                law = _refit(rows, keep)
                if law is None:
                    continue
                c, miss = law
                reach = rows.reach(c)
                if not np.all(np.isfinite(miss)) or not np.isfinite(reach):
                    continue
                off = np.flatnonzero(keep & (miss > reach + 0.5) | rows.short_of_clamp(c, 0.5)) + d
                if off.size and _episodes(off, order + 1) <= most:
                    found.add(tuple(off.tolist()))
    return [np.array(off) for off in sorted(found, key=len)]


def _arx_glitches(u, theta, a, v, end: int, alignments, rig_limit: float) -> bool:
    """Whether a two-input law (Gth beside Ga) fitted on the first ``end`` rows misses the whole
    log in a few windows of its order + 1 rows alone (a corrupted field's), at some order,
    alignment and clamp: the cheap gate before Ga's search on those rows."""
    for n, d, limit in itertools.product(range(1, 2 * MAX_ORDER + 1), alignments, clamps_to_try(v, rig_limit)):
        off = arx_rows_off(u, theta, a, v, d, n, limit, end) if d >= 0 else None
        if off is not None and off.size and _episodes(off, n + 1) <= most_glitches(v.size):
            return True
    return False


def _refit(rows: LawRows, keep: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Least squares on the rows ``keep``, then again without those it missed by four times
    its reach: the law and its miss |v − X c| on every row; None with too few rows or numbers
    past a float's range (no law there)."""
    fit = keep
    for again in (True, False):
        if np.count_nonzero(fit) < 4 * (2 * rows.order + 1):
            return None
        with np.errstate(all="ignore"):
            try:
                c, *_ = np.linalg.lstsq(rows.X[fit], rows.v[fit], rcond=None)
            except np.linalg.LinAlgError:
                return None
            miss = np.abs(rows.v - rows.X @ c)
            if again:
                fit = keep & (miss <= 4.0 * rows.reach(c))
    return c, miss


def glitched(found: Glitches | None) -> tuple[int, ...]:
    """The rows whose v :func:`isolated_misses` set aside (() for None).

    Parameters
    ----------
    found : Glitches or None

    Returns
    -------
    tuple of int
    """
    return () if found is None else found.rows
