"""Which controller made a log, from the data: where the header names none or its law misses v.

A log holds u, θ and the command v the controller produced. Candidate laws, simplest first,
each for both alignments d (DESIGN.md "Timing and log rows": v[k] = C(u[k], θ[k-d])):

- open loop, v = u;
- proportional, v = sat(kp·(u[k] - θ[k-d])), any kp;
- linear compensators e -> v of order 1 to 3 (a direct-form recursion in z^-1);
- then, where a moved and v is no whole count, the rig's two-input law: a P or linear Gth of order
  0 to 3 with accelerometer feedback Ga of order 0 to 3, θ̂_d = u − Ga(a) (DESIGN.md "Compensators";
  :mod:`station.analysis.accel_law` finds Ga, then Gth from e = u − θ − Ga(a) as any one-input law).
  Beside whole-count commands (on the stored integer, or the float with its whole count sent) only
  the thesis's Ga is tried: another Ga's coefficients are not found to the quantization.

Each at the rig's clamp (±200, or the DAC's when v exceeds it) or the log's own (a level |v| sits
at on several rows), and with the recursion as lab software ran it
(:data:`station.control.compensator.RECURSIONS`): on the float command, or, when every logged v is
a whole count, on the stored integer (truncated toward zero or rounded), the integer then being
the command: v[k] = sat(Q(Σ b_i e[k-i] - Σ a_j v[k-j])); or on the float with its whole count sent
and logged (:data:`station.control.compensator.SENT`): a header's law is checked that way
(:func:`variant_of`), and a design is inferred that way when nothing simpler reproduces the log.

Coefficients: for a float recursion, least squares over the unclamped rows (exact there: the
recursion runs on the clamped v). For an integer recursion, whose history is the logged integer
itself, reproducing every v is a set of linear inequalities (Q(x) = v ⇔ v ≤ x < v + 1 for a
truncated positive v, ...), and a linear program (scipy's HiGHS) finds the coefficients deepest
inside them. Then the numbers a person typed: a P gain with the fewest digits, a continuous
design (:func:`station.analysis.continuous_design.recognize`: Tustin, ZOH, backward or forward
Euler with round numbers) whose discretization still reproduces the log. A law is accepted only
when, run as the rig ran it (:func:`station.control.rerun.replay_commands`), it reproduces every
logged v: to ``tolerance`` (1e-6 DAC counts), the logged integer exactly for an integer
recursion. The identification claims nothing the data do not prove.

A PID header's law is matched in :mod:`station.analysis.pid_law`; a law on the float whose whole
count was logged is recognised in :mod:`station.analysis.sent_law` (:func:`_sent_design`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from threadpoolctl import threadpool_limits

from station.analysis.accel_law import AccelFeedback, accel_feedback, lagged
from station.analysis.continuous_design import ContinuousDesign
from station.analysis.law_rows import TOLERANCE, LawRows, no_dac_command, pinned_law, pins_a_law, tie_rows
from station.analysis.law_words import law_text
from station.analysis.memo import by_content
from station.analysis.sent_law import sent_designs
from station.control.compensator import SENT, STORED
from station.control import DAC_LIMIT, Compensator, DiscreteTF, OpenLoop, lead_controller  # DAC_LIMIT: the clamp assumed when v exceeds the rig's ±200
from station.control.rerun import ALIGNMENTS, AlignmentFit, detect_alignment
from station.rig import CLAMP, DT

MAX_ORDER = 3
"""Highest order of the linear compensators tried."""


@dataclass(frozen=True)
class IdentifiedController:
    """A control law that reproduces a log's commands (:func:`infer_controller`,
    :func:`match_pid`).

    Attributes
    ----------
    controller : Compensator or OpenLoop
    alignment : int
        The computational delay d it needs, samples.
    max_abs_dv : float
        max |v_replayed - v_logged| with it, DAC counts.
    v_replayed : numpy.ndarray, shape (N,)
    law : str
        One line for reports, e.g. "P, kp = 1" or "lead 3(s+13)/(s+20) (Tustin, 0.002 s),
        its recursion on the truncated integer command".
    design : ContinuousDesign or None
        The continuous design recognised behind a linear law.
    alignments : tuple of int
        Every alignment at which it reproduces the logged v (more than one: the data cannot
        tell them apart, and ``alignment`` is the preferred one).
    """

    controller: Compensator | OpenLoop
    alignment: int
    max_abs_dv: float
    v_replayed: np.ndarray
    law: str
    design: ContinuousDesign | None = None
    alignments: tuple[int, ...] = ()

    @property
    def recursion(self) -> str:
        """What the law's recursion remembers: "none", "trunc" or "round"."""
        return getattr(self.controller, "recursion", "none")


def clamps_to_try(v: np.ndarray, rig_limit: float) -> list[float]:
    """The clamps worth trying: the rig's (the DAC's when v exceeds it), then the log's own
    largest |v| (a clamp the law hit, perhaps on one row only: a law that reproduces the log
    at the first never gets to it).

    Parameters
    ----------
    v : numpy.ndarray, shape (N,)
        The logged commands, DAC counts.
    rig_limit : float
        The rig's clamp, DAC counts.

    Returns
    -------
    list of float, DAC counts
    """
    vmax = float(np.max(np.abs(v))) if v.size else 0.0
    first = rig_limit if vmax <= rig_limit else max(DAC_LIMIT, vmax)
    return [first, vmax] if 0 < vmax < first else [first]


def at_clamps(controller, v) -> list:
    """A law a header names, at its own clamp, then at the log's largest |v| where that is
    under it (a header does not state its clamp; the lab's ran at 150 as well as 200).

    Parameters
    ----------
    controller : Compensator
    v : array_like, shape (N,)
        The logged commands, DAC counts.

    Returns
    -------
    list of Compensator
    """
    peak = float(np.max(np.abs(v))) if np.size(v) else 0.0
    laws = [controller]
    if 0 < peak < (controller.limit or np.inf):
        laws.append(with_recursion(controller, controller.recursion, peak))
    return laws


def law_compensator(num, den, limit: float | None, dt: float, kind: str, extra: dict | None = None,
                    recursion: str = "none", name: str | None = None, ga=None) -> Compensator:
    """A compensator for a law found in a log: its z-law (and Ga's), clamp and recursion, its
    spec saying where it came from ("inferred from the data") and ``extra`` (a design, kp).

    Parameters
    ----------
    num, den : array_like
        Gth's z-law, ascending powers of z⁻¹.
    limit : float or None
        The clamp, DAC counts.
    dt : float
        Sample time, s.
    kind : str
        The spec's kind ("p", "linear-1", "linear-1+accel-3", "pid").
    extra : dict, optional
        More of the spec (``design``, ``kp``).
    recursion : str
        One of :data:`station.control.compensator.RECURSIONS`.
    name : str, optional
        The compensator's name (the kind without it).
    ga : (array_like, array_like), optional
        Ga's z-law (num, den).

    Returns
    -------
    Compensator

    Raises
    ------
    ValueError
        As :class:`station.control.tf.DiscreteTF` (a leading denominator of 0).
    """
    tf = DiscreteTF(num, den)
    ga_tf = None if ga is None else DiscreteTF(*ga)
    spec = {"kind": kind, "name": name or kind, "dt": dt, "limit": limit, "source": "inferred from the data",
            "gth": {"num_z": tf.num.tolist(), "den_z": tf.den.tolist()},
            "ga": None if ga_tf is None else {"num_z": ga_tf.num.tolist(), "den_z": ga_tf.den.tolist()},
            **(extra or {})}
    if recursion != "none":
        spec["recursion"] = recursion
    return Compensator(tf, ga_tf, limit=limit, name=name or kind, spec=spec, recursion=recursion)


def with_recursion(controller: Compensator, recursion: str, limit: float | None = None) -> Compensator:
    """The same compensator (fresh filters) with its recursion on ``recursion``'s command
    (and its clamp at ``limit`` when given).

    Parameters
    ----------
    controller : Compensator
    recursion : {"none", "trunc", "round", "float-trunc", "float-round"}
    limit : float, optional
        Another clamp, DAC counts.
    """
    spec = {**controller.spec, "recursion": recursion}
    if recursion == "none":
        spec.pop("recursion")
    if limit is not None:
        spec["limit"] = limit
    ga = None if controller.ga is None else DiscreteTF(controller.ga.num, controller.ga.den)
    limit = controller.limit if limit is None else limit
    return Compensator(DiscreteTF(controller.gth.num, controller.gth.den), ga, limit=limit,
                       name=controller.name, spec=spec, shaper=controller.shaper, recursion=recursion)


PREFERRED_ALIGNMENT = 1
"""The alignment chosen when several reproduce a log (the rig's later logs, protocol v1)."""


def fit_alignments(controller, u, theta, a, v, alignments=ALIGNMENTS, skipped=None,
                   prefer: int | None = PREFERRED_ALIGNMENT, primed: int = 0,
                   restarts=()) -> tuple[AlignmentFit | None, tuple[int, ...]]:
    """A controller replayed over a log at each alignment: the best fit, and every alignment
    at which it reproduces every logged v (to :data:`TOLERANCE`).

    Parameters
    ----------
    controller : Compensator or OpenLoop
    u, theta, a, v : array_like, shape (N,)
    alignments : sequence of int
    skipped : array_like of bool, optional
        The samples the station did not answer (:func:`station.control.rerun.replay_commands`).
    prefer : int or None
        The alignment chosen when several reproduce the log (a log whose θ seldom changes
        between rows cannot tell them apart); None: the first.
    primed : int
        Rows taken into the controller's history as logged (a copy cut from a longer run:
        :func:`station.control.rerun.replay_commands`).
    restarts : sequence of int
        Rows where the log's ticks jump (:func:`station.control.rerun.detect_alignment`).

    Returns
    -------
    (AlignmentFit or None, tuple of int)
        The preferred reproducing alignment's fit, else the closest (the first on a tie);
        None when no alignment was tried.
    """
    fits = [f for d in alignments if (f := detect_alignment(controller, u, theta, a, v, (d,), skipped, primed,
                                                           restarts)) is not None]
    if not fits:
        return None, ()
    exact = tuple(f.alignment for f in fits if f.max_abs_dv <= TOLERANCE)
    if len(exact) > 1 and prefer in exact:
        return next(f for f in fits if f.alignment == prefer), exact
    return min(fits, key=lambda f: f.max_abs_dv), exact


def check_law(controller, u, theta, a, v, law: str, alignments, design=None,
              prefer: int | None = PREFERRED_ALIGNMENT, primed: int = 0, restarts=()) -> IdentifiedController | None:
    """``controller`` at its best alignment (:func:`fit_alignments`), as an IdentifiedController
    named ``law``.

    Parameters
    ----------
    controller : Compensator or OpenLoop
    u, theta, a, v : array_like, shape (N,)
        The log's reference, samples and commands.
    law : str
        The law's words for reports.
    alignments : sequence of int
    design : ContinuousDesign, optional
    prefer, primed, restarts
        As :func:`fit_alignments`.

    Returns
    -------
    IdentifiedController or None
        None when no alignment was tried.
    """
    fit, exact = fit_alignments(controller, u, theta, a, v, alignments, prefer=prefer, primed=primed,
                                restarts=restarts)
    return None if fit is None else IdentifiedController(controller, *fit, law, design, exact)  # None: no alignment tried


def whole_counts(v) -> bool:
    """Whether every logged command is a whole DAC count (an integer recursion is possible).

    Parameters
    ----------
    v : array_like, shape (N,)
        The logged commands, DAC counts.
    """
    v = np.asarray(v, dtype=float)
    return bool(v.size) and bool(np.all(v == np.round(v)))


def law_variants(controller, v):
    """A law as stated, then, when every logged v is a whole count and the law has no
    recursion of its own, the same law with its recursion on the stored integer (truncated,
    rounded) and on the float with its whole count sent (:func:`with_recursion`): the forms
    lab software ran it in.

    Parameters
    ----------
    controller : Compensator or OpenLoop
    v : array_like, shape (N,), or None
        The logged commands, DAC counts; None: every form (v in a unit not yet read).

    Yields
    ------
    Compensator or OpenLoop
    """
    yield controller
    if isinstance(controller, Compensator) and getattr(controller, "recursion", "none") == "none" and (
            v is None or whole_counts(v)):
        for q in (*STORED, *SENT):
            yield with_recursion(controller, q)


def variant_of(controller, u, theta, a, v, alignments=ALIGNMENTS, skipped=None,
               prefer: int | None = PREFERRED_ALIGNMENT, cut: bool = False, restarts=()):
    """The variant of ``controller`` that reproduces a log best, its fit and every alignment
    at which it reproduces the log (:func:`fit_alignments`).

    Parameters
    ----------
    controller : Compensator or OpenLoop
    u, theta, a, v : array_like, shape (N,)
    alignments : sequence of int
    skipped : array_like of bool, optional
    prefer, restarts
        As :func:`fit_alignments` (``restarts``: rows where the log's ticks jump).
    cut : bool
        The log is a copy cut from a longer run: the law's first rows of history are taken
        as logged (:func:`fit_alignments` ``primed``).

    Returns
    -------
    (controller, AlignmentFit or None, tuple of int)
        The controller itself or, when every logged v is a whole count and it does not
        reproduce them as it is, a copy with its recursion on the stored integer
        (:func:`with_recursion`: truncated, then rounded), then on the float with its whole
        count sent (truncated, then rounded): the first that reproduces every v
        (to :data:`TOLERANCE`), else the closest; the fit is None without rows.
    """
    best = None
    for candidate in law_variants(controller, v):
        primed = getattr(candidate, "history", 0) if cut else 0
        fit, exact = fit_alignments(candidate, u, theta, a, v, alignments, skipped, prefer, primed, restarts)
        if fit is not None and (best is None or fit.max_abs_dv < best[1].max_abs_dv):
            best = (candidate, fit, exact)
        if best is not None and best[1].max_abs_dv <= TOLERANCE:
            break
    return best if best is not None else (controller, None, ())


def aligned_error(u: np.ndarray, theta: np.ndarray, d: int) -> np.ndarray:
    """The error a law saw at alignment ``d``: e[k] = u[k] − θ[k−d], 0 for k < d.

    Parameters
    ----------
    u, theta : numpy.ndarray, shape (N,)
        Reference and hub angle, encoder counts.
    d : int
        The alignment (0: v[k] from θ[k], the 2009 software; 1: from θ[k−1]).
    """
    e = np.zeros(u.size)
    e[d:] = u[d:] - theta[:u.size - d]
    return e


@by_content()  # a column check asks again of a rewrite's rewrite (the log itself)
@threadpool_limits.wrap(limits=1, user_api="blas")  # small matrices: threads on a busy machine made it 5x slower
def infer_controller(u, theta, v, a=None, dt: float = DT, rig_limit: float = CLAMP,
                     alignments=(0, 1), prefer: int | None = PREFERRED_ALIGNMENT,
                     cut: bool = False, restarts=(), accel_only: bool = False) -> IdentifiedController | None:
    """Identify the controller that produced a log's commands from u, θ and v.

    Parameters
    ----------
    u, theta, v : array_like, shape (N,)
        Logged reference (encoder counts), encoder counts and command (DAC counts).
    a : array_like, shape (N,), optional
        Accelerometer counts (the accelerometer feedback's input; passed to the replay).
    dt : float
        Sample time, s (recorded in the controller's spec; the continuous design's).
    rig_limit : float
        The clamp assumed when |v| never exceeds it (the rig's 200 DAC counts); else
        the DAC's 255 (or max |v|). The log's own clamp is tried too (:func:`clamps_to_try`).
    alignments : sequence of int
        Computational delays tried, samples.
    prefer : int or None
        The alignment chosen when the law reproduces the log at several (:func:`fit_alignments`).
    cut : bool
        The log is a copy cut from a longer run: a law of order m is fitted and judged from
        its m-th row on, its history before taken as logged.
    restarts : sequence of int
        Rows where the log's ticks jump (rows missing or repeated:
        :func:`station.runlog.timebase.restart_rows`): P and linear laws are fitted on the rows
        whose lags do not reach across a jump and replayed again from each
        (:func:`station.control.rerun.replay_commands`); the laws with accelerometer
        feedback or a sent whole count are not tried across a jump.
    accel_only : bool
        Only the laws with accelerometer feedback (on a log's first rows, before a corrupted
        field: :func:`station.analysis.glitches.law_past_glitches`).

    Returns
    -------
    IdentifiedController or None
        The simplest law (open loop, P, then linear of order 1..3; a float recursion before an integer one;
        then Gth with accelerometer feedback Ga) that reproduces every logged v (to :data:`TOLERANCE`;
        exactly for an integer recursion); None when none does, or the log lacks u, θ or v (NaN), never
        commands anything, commands nothing but 0 and one level (:func:`station.analysis.law_rows.pins_a_law`),
        or commands under one count while the hub moved (:func:`station.analysis.law_rows.no_dac_command`).
    """
    u = np.asarray(u, dtype=float)
    theta = np.asarray(theta, dtype=float)
    v = np.asarray(v, dtype=float)
    a = np.zeros_like(v) if a is None else np.asarray(a, dtype=float)
    if v.size < 8 or not all(np.all(np.isfinite(x)) for x in (u, theta, v)) or not np.any(v):
        return None
    a = np.where(np.isfinite(a), a, 0.0)

    if np.array_equal(v, u) or np.array_equal(v[1:], u[1:]) and v[0] == 0:
        ol = OpenLoop(limit=None)
        return check_law(ol, u, theta, a, v, "open loop, v = u", alignments, prefer=prefer, restarts=restarts)
    if not pins_a_law(v) or no_dac_command(v, theta):
        return None  # nothing but 0 and a clamp's level, or no DAC command: no law is pinned

    recursions = () if accel_only else ("none", *STORED) if whole_counts(v) else ("none",)  # (): no one-input law
    for order in range(MAX_ORDER + 1):
        for d in alignments:
            if d < 0:
                continue
            e = aligned_error(u, theta, d)
            for limit in clamps_to_try(v, rig_limit):
                rows = LawRows(e, v, d, order, limit, order if cut else 0, restarts)
                for recursion in recursions:
                    hit = _accepted(rows, recursion, d, (u, theta, a, v), dt, rig_limit, alignments, prefer,
                                    order if cut else 0, restarts=restarts)
                    if hit is not None:
                        return hit
    if len(restarts):  # the laws below are not tried across a jump of n
        return None
    if len(recursions) > 1 and not cut:  # the float with its whole count sent: after every law the log holds
        for order in range(1, MAX_ORDER + 1):
            for d in alignments:
                if d < 0:
                    continue
                e = aligned_error(u, theta, d)
                for limit in clamps_to_try(v, rig_limit):
                    hit = _sent_design(LawRows(e, v, d, order, limit), e, d, (u, theta, a, v), dt, rig_limit,
                                       alignments, prefer)
                    if hit is not None:
                        return hit
    if cut or not np.any(a != a[0]):
        return None
    if whole_counts(v):  # Ga is not pinned by whole counts: the thesis's, beside a law on them
        return _with_thesis_ga(u, theta, a, v, dt, rig_limit, alignments, prefer)
    return _with_accel_feedback(u, theta, a, v, dt, rig_limit, alignments, prefer)


def _accepted(rows: LawRows, recursion: str, d: int, log, dt: float, rig_limit: float, alignments, prefer,
              primed: int = 0, ga: AccelFeedback | None = None, restarts=()) -> IdentifiedController | None:
    """The law ``rows`` hold (with the accelerometer feedback ``ga`` when given), when, run as
    the rig ran it, it reproduces the log ``(u, θ, a, v)``: to :data:`TOLERANCE`, or with rows
    on a quantization boundary only (:func:`tie_rows`); else None."""
    found = pinned_law(rows, recursion, dt)
    if found is None:
        return None
    c, design = found
    if design is not None and recursion in STORED:  # a law on the other stored integer may reproduce it too
        other = next(q for q in STORED if q != recursion)
        beside = pinned_law(rows, other, dt)
        if beside is not None and beside[1] is not None:
            design = design.with_alternatives(beside[1], other)
    order = rows.order
    kind = ("p" if order == 0 else f"linear-{order}") + ("" if ga is None else f"+accel-{ga.den.size - 1}")
    extra = {"kp": float(c[0])} if order == 0 else {}
    if design is not None:
        extra["design"] = design.to_json()
    name = kind if design is None else design.text + ("" if ga is None else " with Ga")
    limit = rows.limit
    try:
        ctl = law_compensator(c[:order + 1], np.concatenate(([1.0], c[order + 1:])), limit, dt, kind, extra,
                           recursion, name, ga=None if ga is None else (ga.num, ga.den))
    except ValueError:
        return None
    law = law_text(order, c, design, dt, recursion, limit, rig_limit, ctl.ga)
    return replayed_or_tied(ctl, log, law, alignments, design, prefer, primed, restarts, rows, c, recursion, d)


def replayed_or_tied(ctl, log, law: str, alignments, design, prefer, primed: int, restarts, rows: LawRows,
                     c: np.ndarray, recursion: str, d: int) -> IdentifiedController | None:
    """A law found on a log's rows, run as the rig ran it (:func:`check_law`): accepted when it
    reproduces every logged v, or when it differs only on rows whose exact value is a quantization
    boundary, which the lab's arithmetic decided (:func:`station.analysis.law_rows.tie_rows`);
    then at every alignment of ``alignments`` where it holds so (a hub that never moves).

    Parameters
    ----------
    ctl : Compensator
    log : tuple of array_like
        (u, θ, a, v).
    law : str
        Its words (:func:`law_text`).
    alignments, design, prefer, primed, restarts
        As :func:`check_law`.
    rows : LawRows
        The log's rows at alignment ``d``.
    c : numpy.ndarray
        The law's coefficients, [b_0..b_m, a_1..a_m].
    recursion : {"none", "trunc", "round"}
    d : int
        The rows' alignment.

    Returns
    -------
    IdentifiedController or None
    """
    hit = check_law(ctl, *log, law, alignments, design, prefer, primed, restarts)
    if hit is not None and hit.max_abs_dv <= TOLERANCE:
        return hit
    ties = tie_rows(rows, c, recursion)
    if ties:
        alike = tuple(sorted({d, *(x for x in alignments if x >= 0 and _holds_at(ctl, log, rows, c, recursion, x))}))
        return IdentifiedController(ctl, d, 0.0, np.asarray(log[3], float).copy(), f"{law}, {ties} row(s) on a "
                                    f"quantization boundary as the lab's arithmetic decided them", design, alike)
    return None


def _holds_at(ctl, log, rows: LawRows, c: np.ndarray, recursion: str, d: int) -> bool:
    """Whether the law ``c`` holds at alignment ``d`` too, as :func:`replayed_or_tied` accepts it."""
    from scipy.signal import lfilter  # lazy: start-up time
    u, theta, a, _ = (np.asarray(x, float) for x in log)
    fed = 0.0 if ctl.ga is None else lfilter(ctl.ga.num, ctl.ga.den, lagged(a, d))  # Ga's, as the thesis's Ga path
    at = rows.at(aligned_error(u, theta, d) - fed, d)
    return at.reproduces(c, recursion) or tie_rows(at, c, recursion) > 0


def _sent_design(rows: LawRows, e: np.ndarray, d: int, log, dt: float, rig_limit: float, alignments,
                 prefer, ga: AccelFeedback | None = None) -> IdentifiedController | None:
    """A continuous design whose recursion ran on the float while its whole count was sent and
    logged (:func:`station.analysis.sent_law.sent_designs`), with ``ga`` beside it when given;
    accepted only when, run as the rig ran it, it gives every logged v exactly."""
    order = rows.order
    for design, recursion in sent_designs(rows, e, log[3], d, dt):
        num_z, den_z = design.discretize(dt, order)
        try:
            kind = f"linear-{order}" + ("" if ga is None else f"+accel-{ga.den.size - 1}")
            ctl = law_compensator(num_z, den_z, rows.limit, dt, kind, {"design": design.to_json()}, recursion,
                               design.text + ("" if ga is None else " with Ga"),
                               ga=None if ga is None else (ga.num, ga.den))
        except ValueError:
            continue
        law = law_text(order, np.concatenate([num_z, den_z[1:]]), design, dt, recursion, rows.limit, rig_limit,
                        ctl.ga)
        hit = check_law(ctl, *log, law, alignments, design, prefer)
        if hit is not None and hit.max_abs_dv <= TOLERANCE:
            return hit
    return None


def _with_thesis_ga(u, theta, a, v, dt: float, rig_limit: float, alignments, prefer) -> IdentifiedController | None:
    """The thesis's accelerometer feedback Ga (DESIGN.md) beside a Gth whose command was stored
    or sent as a whole count: on such a log Ga's own coefficients (not round numbers) cannot
    be found to the quantization, but the lab's software ran the thesis's. Gth of order 0 to
    3, its recursion on the stored integer, then on the float with the whole count sent
    (:func:`_sent_design`); accepted only when the replay gives every logged v."""
    from scipy.signal import lfilter  # lazy: start-up time

    thesis = lead_controller(CLAMP, dt, accel=True).ga
    log = (u, theta, a, v)
    for order in range(MAX_ORDER + 1):
        for d in alignments:
            if d < 0:
                continue
            x = lfilter(thesis.num, thesis.den, lagged(a, d))
            ga = AccelFeedback(thesis.num, thesis.den, x)
            e = aligned_error(u, theta, d) - x
            for limit in clamps_to_try(v, rig_limit):
                rows = LawRows(e, v, d, order, limit)
                for recursion in STORED:
                    hit = _accepted(rows, recursion, d, log, dt, rig_limit, alignments, prefer, ga=ga)
                    if hit is not None:
                        return hit
                if order:
                    hit = _sent_design(rows, e, d, log, dt, rig_limit, alignments, prefer, ga)
                    if hit is not None:
                        return hit
    return None


def _with_accel_feedback(u, theta, a, v, dt: float, rig_limit: float, alignments, prefer) -> IdentifiedController | None:
    """The simplest Gth with accelerometer feedback Ga (:mod:`station.analysis.accel_law`)
    that reproduces every logged v: total order m + p first, then the lower Gth order m (a
    lead and the thesis's third-order Ga before a third-order Gth and a first-order Ga)."""
    for total in range(2 * MAX_ORDER + 1):
        for order in range(max(0, total - MAX_ORDER), min(total, MAX_ORDER) + 1):
            for d in alignments:
                if d < 0:
                    continue
                for limit in clamps_to_try(v, rig_limit):
                    ga = accel_feedback(u, theta, a, v, d, order, total - order, limit, dt)
                    if ga is None:
                        continue
                    rows = LawRows(aligned_error(u, theta, d) - ga.x, v, d, order, limit)
                    hit = _accepted(rows, "none", d, (u, theta, a, v), dt, rig_limit, alignments, prefer, ga=ga)
                    if hit is not None:
                        return hit
    return None
