"""Which controller ran a logged run: named by its header and confirmed by its data, matched,
or inferred from the data (when the header names none, or what it names does not reproduce
the logged commands).

Our logs record the controller's spec; the rig's headers print P gains, PID gains or the
compensators' z coefficients to 8 decimals. When those equal the Tustin coefficients of
the known continuous designs to the printed digits, the unrounded designs are used
(DESIGN.md: the printed Ga alone replays the accelerometer run only to 0.03 counts). A
PID header is matched against the standard discretizations, and a log that names no
controller gets one identified from u, θ and v (:mod:`station.analysis.controller_id`),
accepted only when it reproduces every logged v. A named controller is replayed over the
log first: the audit's controller row (DESIGN.md "Log audit") says whether the data confirm
or contradict it, and a contradicted header gives way to the data's law.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from station.analysis.controller_id import (PREFERRED_ALIGNMENT, TOLERANCE, IdentifiedController, at_clamps,
                                           infer_controller, variant_of)
from station.analysis.header_law import (NEAR_COUNTS, PRINTED_TOLERANCE, SAME_LAW_RTOL, completed_law, gain_words,
                                         idle_ga, named_design, same_law)
from station.analysis.law_words import ga_text
from station.analysis.glitches import GLITCH_WORDS, Glitches, isolated_misses, law_past_glitches
from station.analysis.law_rows import pins_a_law, unpinned_words
from station.analysis.pid_law import match_pid
from station.control import Compensator, DiscreteTF, OpenLoop, controller_from_spec, lead_controller, p_controller
from station.control.compensator import recursion_words
from station.control.designs import MAX_ORDER, z_problem
from station.control.rerun import ALIGNMENTS, AlignmentFit, is_closed_loop, memory, printed_commands
from station.errors import StationError
from station.logged.audit import AuditClaim
from station.logged.missing_ticks import law_before_gap, law_on_kept_rows, miss_at_gap, p_on_kept_rows
from station.logged.start import start_claims
from station.logged.units import replayable_rate
from station.runlog.printing import Printing
from station.runlog.timebase import restart_rows, row_ticks, tick_time
from station.rig import CLAMP, DT  # the rig's clamp and sample time: its compensators ran at them
from station.runlog import RunLog

def _matches_printed(printed: list[float], exact: np.ndarray) -> bool:
    return len(printed) == exact.size and bool(np.all(np.abs(np.asarray(printed) - exact) <= PRINTED_TOLERANCE))


def _rig_stage(meta: dict, key: str, design: DiscreteTF, notes: list[str]) -> tuple[DiscreteTF | None, bool]:
    """The filter printed in a rig header: the exact design when it matches, else as printed."""
    coeffs = meta.get(key)
    if not coeffs or not coeffs.get("num"):
        return None, True
    num, den = coeffs.get("num", []), coeffs.get("den", [])
    if max(len(num), len(den)) > MAX_ORDER + 1:  # before any arithmetic on them
        raise StationError(f"{key}: {z_problem(num, den)}", key=key)
    if _matches_printed(num, design.num) and _matches_printed(den, design.den):
        return design, True
    notes.append(f"{key} coefficients as printed in the header (8 decimals; not a known design)")
    try:
        tf = DiscreteTF(num, den)
    except ValueError as exc:
        raise StationError(f"header {key} num={num} den={den}: {exc}", key=key) from None
    problem = z_problem(tf.num, tf.den)  # the one check of every filter read
    if problem is not None:
        raise StationError(f"{key}: {problem}", key=key)
    return tf, False


def _header_number(meta: dict[str, Any], key: str) -> float:
    """A gain of a rig header (0 when absent); StationError naming the field when not a number."""
    value = meta.get(key, 0.0)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
        raise StationError(f"{key}: expected a number, got {value!r}", key=key)
    return float(value)


def _lab_coefficients(meta: dict[str, Any], notes: list[str]) -> dict[str, Any]:
    """``meta`` with a Gth read from ryanGT's Motor_Comp lines ``#b0=``, ``#b1=``, ``#a1=`` when it has
    none (v[i] = b0·e[i] + b1·e[i−1] − a1·v[i−1]): Gth's z⁻¹ num [b0, b1, …] and den [1, a1, …]."""
    if "Gth" in meta or "b0" not in meta:
        return meta
    num = [_header_number(meta, f"b{k}") for k in range(MAX_ORDER + 2) if f"b{k}" in meta]
    den = [1.0] + [_header_number(meta, f"a{k}") for k in range(1, MAX_ORDER + 2) if f"a{k}" in meta]
    notes.append(f"Gth read from the header's b and a lines (the lab's Motor_Comp): num {num}, den {den}")
    return {**meta, "Gth": {"num": num, "den": den}}


def rig_controller(meta: dict[str, Any], dt: float = DT) -> tuple[Compensator | OpenLoop | None, list[str]]:
    """The controller a rig log's header names.

    Parameters
    ----------
    meta : dict
        ``RunLog.meta`` of a rig log (see :func:`station.runlog.read_log`).
    dt : float
        Sample time, s.

    Returns
    -------
    controller : Compensator, OpenLoop or None
        P_control (kp) and PID_control with ki = kd = 0 -> P; Motor_Comp with Gth (and Ga)
        -> lead / lead-accel (exact designs when the printed coefficients match them);
        OL_Test -> open loop; None when the header does not say.
    notes : list of str
    """
    notes: list[str] = []
    test = str(meta.get("test", ""))
    meta = _lab_coefficients(meta, notes)
    if "Gth" in meta:
        ref = lead_controller(CLAMP, dt, accel=True)
        gth, gth_known = _rig_stage(meta, "Gth", ref.gth, notes)
        if gth is None:
            return None, [f"header has an empty Gth ({test}): controller unknown"]
        ga, ga_known = _rig_stage(meta, "Ga", ref.ga, notes)
        known = gth_known and ga_known
        name = ("lead-accel" if ga is not None else "lead") if known else "rig-printed"
        spec = {"kind": name, "name": name, "dt": dt, "limit": CLAMP, "source": "rig header",
                "gth": {"num_z": gth.num.tolist(), "den_z": gth.den.tolist()},
                "ga": None if ga is None else {"num_z": ga.num.tolist(), "den_z": ga.den.tolist()}}
        if known:
            notes.append("printed coefficients equal the Tustin designs to their 8 decimals: unrounded designs used")
        return Compensator(gth, ga, limit=CLAMP, name=name, spec=spec), notes
    if "kp" in meta:
        kp, ki, kd = (_header_number(meta, key) for key in ("kp", "ki", "kd"))
        if ki != 0.0 or kd != 0.0:  # how the rig discretized it: the data decide (identify_controller)
            return None, []
        if "ki" in meta or "kd" in meta:
            notes.append("PID_control with ki = kd = 0: P control")
        return p_controller(kp, CLAMP, dt), notes
    if "OL" in test.split("_") or test.startswith("OL"):
        return OpenLoop(limit=None), notes
    return None, notes


NO_LAW = "no law found"
"""The controller claim's data when the log names no controller and no law reproduces it."""

NOT_STATED = "not stated"
"""The controller claim's header when the log names no controller."""


class ControllerId(NamedTuple):
    """Which controller ran a log, where that came from, and its audit (:func:`identify_controller`).

    Attributes
    ----------
    controller : Compensator, OpenLoop or None
        None when no controller is known: commands not replayed, the model driven by the
        logged v.
    source : {"header", "inferred", "inferred (header contradicted)"} or None
        "header": named by the log (including a PID header matched to a standard
        discretization); "inferred": identified from the data, the log naming none;
        "inferred (header contradicted)": the log's named controller does not reproduce its
        commands and the data's law does.
    notes : list of str
        One line each on what was assumed or could not be done.
    fit : AlignmentFit or None
        The controller replayed over the log at its best alignment (None when not replayed).
    claim : AuditClaim or None
        The controller's audit row (None for a log without rows).
    alignments : tuple of int
        Every alignment at which the controller reproduces the logged v (more than one: the
        data cannot tell them apart; ``fit`` holds the preferred).
    cut : bool
        The log is a copy cut from a longer run: the law reproduces it only with its first
        rows of memory taken as logged (or the hub moved at its first row).
    judged_to : int or None
        The row where n jumps past which the law could not be judged (its memory, such as
        Ga's, is not in the log's rows): ``fit.max_abs_dv`` is over the rows before it. None:
        judged on every row.
    corrupted : Glitches or None
        Fields the law misses alone, corrupted, and the log put right (:func:`station.analysis.
        glitches.isolated_misses`; None: none): ``fit.max_abs_dv`` is over the other rows.
    """

    controller: Compensator | OpenLoop | None
    source: str | None
    notes: list[str]
    fit: AlignmentFit | None = None
    claim: AuditClaim | None = None
    alignments: tuple[int, ...] = ()
    cut: bool = False
    judged_to: int | None = None
    corrupted: Glitches | None = None


def describe_controller(controller) -> str:
    """A controller in a few words, for the audit: "open loop", "P, kp = 2", "lead Gth
    (the thesis's)", "3(s+13)/(s+20) (Tustin, 0.002 s)", with its integer recursion.

    Parameters
    ----------
    controller : Compensator, OpenLoop or None
    """
    if controller is None:
        return "none"
    if not is_closed_loop(controller):
        return "open loop"
    spec = getattr(controller, "spec", None) or {}
    name = getattr(controller, "name", "") or spec.get("kind", "")
    design = spec.get("design")
    if spec.get("kind") == "p" and isinstance(spec.get("kp"), (int, float)):
        text = f"P, kp = {spec['kp']:g}"
    elif isinstance(design, dict) and design.get("text"):
        text = f"{design['text']} ({design.get('method', '?')}, {spec.get('dt', DT):g} s)"
    elif name in ("lead", "lead-accel"):
        text = "lead Gth (the thesis's 20(s+2π·5)/(s+2π·20))" + (" with accelerometer feedback Ga"
                                                                 if name == "lead-accel" else "")
    elif spec.get("kind") == "pid":
        text = (f"PID kp = {spec.get('kp', 0):g}, ki = {spec.get('ki', 0):g}, kd = {spec.get('kd', 0):g} "
                f"({spec.get('discretization', '?')})")
    else:
        fmt = lambda c: "[" + ", ".join(f"{x:.8g}" for x in c) + "]"  # noqa: E731
        gth = controller.gth
        text = f"{name}: Gth num {fmt(gth.num)}, den {fmt(gth.den)} (z^-1)"
        if getattr(controller, "ga", None) is not None:
            text += f", Ga num {fmt(controller.ga.num)}, den {fmt(controller.ga.den)}"
    ga = getattr(controller, "ga", None)
    if ga is not None and (spec.get("kind") == "p" or isinstance(design, dict) and design.get("text")):
        text += f", with {ga_text(ga, spec.get('dt', DT))}"
    recursion = getattr(controller, "recursion", "none")
    if recursion != "none":
        text += f", {recursion_words(recursion)}"
    return text


def _how_close(dv: float, printing: Printing | None = None) -> str:
    if printing is not None:
        return (f"to {dv:.2g} counts beyond" if dv else "to") + f" its printing ({printing.text()})"
    return "exactly" if dv == 0 else f"to {dv:.2g} counts"


def log_controller(log: RunLog) -> tuple[Compensator | OpenLoop | None, list[str]]:
    """The controller that ran a log: named by its header and confirmed by its data, else
    identified from the data.

    Parameters
    ----------
    log : RunLog
        Ours (the header's ``controller`` spec) or the rig's (see :func:`rig_controller`).

    Returns
    -------
    controller : Compensator, OpenLoop or None
        None when the header names none and none reproduces the logged v
        (:func:`identify_controller`).
    notes : list of str
        What was assumed.

    Raises
    ------
    StationError
        Our header's controller spec is malformed, or a rig header's gain is not a
        number (naming the file and line).
    """
    cid = identify_controller(log)
    return cid.controller, cid.notes


def named_law(log: RunLog):
    """The law a log's header names, as given (None: no rows, a custom controller, none named,
    or a malformed header, which :func:`identify_controller` says).

    Parameters
    ----------
    log : RunLog
    """
    if not len(log) or _custom_controller(log) is not None:
        return None
    try:
        return _named_controller(log)[0]
    except StationError:
        return None


def header_reproduces(log: RunLog, skipped=None) -> bool | None:
    """Whether the law a log's header names reproduces its logged v: v = u for an open-loop
    header, :func:`header_law_dv` within the device's quantization for a closed-loop one; None
    when the header names no law (or a malformed one) or the log cannot be replayed.

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`identify_controller`.
    """
    controller = named_law(log)
    if controller is None:
        return None
    if not is_closed_loop(controller):
        u, v = (np.asarray(log.data[c], dtype=float) for c in ("u", "v"))
        return bool(np.all(np.isfinite(u)) and np.all(np.isfinite(v)) and np.max(np.abs(v - u)) <= TOLERANCE)
    dv = header_law_dv(log, skipped)
    return None if dv is None else dv <= TOLERANCE


def header_law_dv(log: RunLog, skipped=None, own_clamp: bool = False) -> float | None:
    """How near the closed-loop law a log's header names comes to its logged commands: max
    |v_replayed − v_logged| at its best alignment and recursion (:func:`variant_of`) and clamp
    (its own, or the log's largest |v|), DAC counts; None when the header names no closed-loop
    law, the log's rows are no loop's every tick (:func:`station.logged.units.replayable_rate`),
    or u, θ or v are not finite. The header's coefficients as given: no law is inferred
    (:func:`identify_controller` does that). A law whose memory is in no column (Ga's) is judged
    on the rows before n first jumps, if it does and they pin a law (v more than 0 and one level).

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        As :func:`identify_controller`.
    own_clamp : bool, optional
        At the law's own clamp only (a v of 0 and ±peak is any law's at its peak: ``pins_a_law``).
    """
    controller = named_law(log)
    data = log.data
    if (controller is None or not is_closed_loop(controller) or not replayable_rate(log)
            or not all(np.all(np.isfinite(data[c])) for c in ("u", "theta", "v"))):
        return None
    cols, best = (data["u"], data["theta"], np.where(np.isfinite(data["a"]), data["a"], 0.0), data["v"]), None
    restarts = restart_rows(data["n"])
    if restarts and memory(controller) is None and pins_a_law(cols[3][:restarts[0]]):  # Ga's state: no column
        cols = tuple(np.asarray(c, dtype=float)[:restarts[0]] for c in cols)
        skipped, restarts = None if skipped is None else np.asarray(skipped)[:restarts[0]], ()
    for law in [controller] if own_clamp else at_clamps(controller, data["v"]):
        _, fit, _ = variant_of(law, *cols, ALIGNMENTS, skipped, restarts=restarts)
        if fit is not None and (best is None or fit.max_abs_dv < best):
            best = float(fit.max_abs_dv)
    return best


def _driven(v) -> str:
    """How a model runs on the log: on its logged v, or not at all (no usable v)."""
    return "the model is driven by the logged v" if np.all(np.isfinite(v)) else "no model can run on it (no usable v)"


def _set_aside(glitch: Glitches, t, u, theta, a, v) -> tuple[str, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The words that set a log's corrupted fields aside, and its u, θ, a and v put right."""
    return (f"; but {glitch.words(v, t, u, theta, a)}: {GLITCH_WORDS}", *glitch.repaired(v))


def identify_controller(log: RunLog, skipped=None) -> ControllerId:
    """The controller that ran a log, whether the header named it or the data did, and the
    audit of the header's claim.

    The header's controller (a PID header with ki or kd != 0 matched against the standard
    discretizations, :func:`station.analysis.pid_law.match_pid`) is replayed over the
    log (:func:`station.analysis.controller_id.variant_of`: as it is, or with its recursion on
    the stored integer, or on the float with that whole count sent, when every logged v is a
    whole count). It is confirmed when it
    reproduces every logged v (to 1e-6 DAC counts; exactly for an integer recursion). When it
    does not, or the log names none, a law is identified from u, θ and v
    (:func:`station.analysis.controller_id.infer_controller`: open loop, P, linear e -> v up
    to order 3, float or integer recursion, Gth with accelerometer feedback Ga, both
    alignments, the clamp) and, when one
    reproduces every v, it is used: "inferred", or "inferred (header contradicted)". A
    header law that misses by a count or more with no law found is contradicted but kept;
    one that misses by less stays unchecked. A rig log sampled at another rate than the
    rig's 0.002 s cannot be replayed with a closed-loop controller (the rows it ran on are
    missing): one note says so and the model is driven by the logged v.

    Parameters
    ----------
    log : RunLog
    skipped : array_like of bool, optional
        Rows whose sample the station did not answer (:attr:`station.logged.LoggedRun.skipped`).

    Returns
    -------
    ControllerId

    Raises
    ------
    StationError
        As :func:`log_controller`.
    """
    custom = _custom_controller(log)
    if custom is not None:  # a Python controller of the user's: its law is not in the log
        note = (f"the log's controller is a custom Python controller ({custom}): its commands cannot be "
                f"replayed; the model is driven by the logged v")
        return ControllerId(None, None, [note], None, AuditClaim(
            "controller", f"custom Python controller {custom}", "not replayable", "unchecked", note))
    data = log.data
    ticks = None if replayable_rate(log) else row_ticks(data["n"])
    # a copy that lacks ticks between its rows: its law ran at the tick's rate, not the rows'
    dt = log.dt if ticks is None else tick_time(data["t"], data["n"], log.dt)
    controller, notes = _named_controller(log, dt)
    u, theta, v, a = data["u"], data["theta"], data["v"], data["a"]
    a = np.where(np.isfinite(a), a, 0.0)
    printing = printed_commands(v)
    if printing is not None:
        notes.append(f"v is printed to {printing.text()} (up to {np.max(printing.resolution(v)):.2g} counts off "
                     f"the value computed): a law is judged to that printing")
    # rows missing or repeated: a law replayed again from each jump of n, its memory as logged
    restarts = restart_rows(data["n"])
    pid = _header_pid(log)
    stated_d = log.meta.get("alignment") if log.format == "station" else None
    prefer = stated_d if isinstance(stated_d, int) and not isinstance(stated_d, bool) else PREFERRED_ALIGNMENT
    said = (describe_controller(controller) if controller is not None else
            f"PID kp = {pid[0]:g}, ki = {pid[1]:g}, kd = {pid[2]:g}" if pid is not None else NOT_STATED)
    kept = ticks is not None and all(np.all(np.isfinite(x)) for x in (u, theta, v))  # rows that skip ticks
    if kept and is_closed_loop(controller):
        k = law_on_kept_rows(controller, u, theta, a, v, ticks, said, dt)
        return ControllerId(k.law, "header", notes + [k.note], k.fit, k.claim, k.alignments,
                            judged_to=None if k.judged else 0)
    if kept:  # none named, an open loop or an unmatched PID: a P law the kept rows give
        stated = controller is not None or pid is not None  # an open loop (v = u) or a PID: contradicted
        k = None if controller is not None and np.max(np.abs(v - u)) <= TOLERANCE else p_on_kept_rows(
            u, theta, a, v, ticks, said, dt, stated)
        if k is not None:
            return ControllerId(k.law, "inferred (header contradicted)" if stated else "inferred", notes + [k.note],
                                k.fit, k.claim, k.alignments)
    if not replayable_rate(log) and not isinstance(controller, OpenLoop):
        notes.append(f"sampled at {log.dt:g} s, not the rig's {DT:g} s, and its rows are not every tick of a loop "
                     f"at that rate (n jumps, or no n column): closed-loop commands cannot be replayed or "
                     f"inferred (the rig's controllers ran at {DT:g} s, on rows this log may lack); {_driven(v)}")
        return ControllerId(None, None, notes, None, AuditClaim("controller", said, "not replayable", "unchecked",
                                                                notes[-1]))
    missing = [name for name in ("u", "v") + (("theta",) if is_closed_loop(controller) or controller is None
                                              else ()) if not np.all(np.isfinite(data[name]))]
    header_dv = completed = glitch = None
    aside = ""  # corrupted fields set aside, said after the controller's evidence
    # a copy cut from a longer run: a law's first rows of history are the logged ones
    cut = not missing and start_claims(theta, a, u, v, dt, False, False).at_rest is False
    if pid is not None and controller is None and not missing:
        hit, best = match_pid(*pid, u, theta, v, a, dt, CLAMP)
        gains = f"kp = {pid[0]:g}, ki = {pid[1]:g}, kd = {pid[2]:g}"
        if hit is not None:
            notes.append(f"PID header ({gains}) replayed with the {hit.law}")
            controller = hit.controller
        else:
            header_dv = best
            notes.append(f"PID header ({gains}): no standard discretization (integral by backward Euler, "
                         f"forward Euler or Tustin; derivative by backward difference) reproduces the logged v "
                         f"(best max |dv| = {best:.3g} counts)")
    elif pid is not None and missing:
        notes.append(f"PID header, but the log has no usable {', '.join(missing)}: commands not replayed")
    if controller is not None:
        if missing:  # LoggedRun.replayed names the column
            return ControllerId(controller, "header", notes, None, AuditClaim(
                "controller", said, "not replayable", "unchecked", f"the log has no usable {', '.join(missing)}"))
        used, fit, exact = variant_of(controller, u, theta, a, v, ALIGNMENTS, skipped, prefer, cut, restarts)
        if fit.max_abs_dv > TOLERANCE and not cut and getattr(controller, "history", 0):
            # a copy cut while the hub rested but the controller's memory did not
            retry = variant_of(controller, u, theta, a, v, ALIGNMENTS, skipped, prefer, True, restarts)
            if retry[1].max_abs_dv <= TOLERANCE:
                (used, fit, exact), cut = retry, True
                notes.append(_CUT_NOTE.format(used.history))
        glitch = None
        if fit.max_abs_dv > TOLERANCE and not cut:
            glitch = isolated_misses(controller, u, theta, a, v, ALIGNMENTS, skipped, restarts, slack=NEAR_COUNTS)
            if glitch is None and fit.max_abs_dv <= NEAR_COUNTS:  # a field's echo within a printing's slack
                glitch = isolated_misses(controller, u, theta, a, v, ALIGNMENTS, skipped, restarts)
        if glitch is not None:  # a corrupted field or two, not another law: set aside, said, and put right
            aside, u, theta, a, v = _set_aside(glitch, data['t'], u, theta, a, v)
            used, fit, exact = glitch.law, glitch.fit, (glitch.fit.alignment,)
        if fit.max_abs_dv <= TOLERANCE:
            at = f" at alignment {fit.alignment}" if is_closed_loop(used) else ""
            if used is not controller:
                notes.append(f"the header's controller reproduces the logged v with "
                             f"{recursion_words(used.recursion)} (the lab's software stored it)")
            pinned = not is_closed_loop(used) or pins_a_law(v)
            used = named_design(used, u, theta, v, fit.alignment, dt) if pinned else used
            return ControllerId(used, "header", notes, fit, AuditClaim(
                "controller", said, describe_controller(used) + at, "confirmed" if pinned else "unchecked",
                f"replays every logged v {_how_close(fit.max_abs_dv, printing)}{at}" + (
                    "" if pinned else f"; but {unpinned_words(v)}: the data cannot confirm this one") + aside),
                exact, cut=cut, corrupted=glitch)
        header_dv = fit.max_abs_dv
        if header_dv <= NEAR_COUNTS and not cut:  # printed coefficients a count off: the design they round
            completed = completed_law(used, u, theta, a, v, fit.alignment, dt, CLAMP, prefer, restarts)
    if missing:
        if pid is None and controller is None:
            notes.append(f"the log names no controller and has no usable {', '.join(missing)} column to "
                         f"infer one from: commands not replayed; {_driven(v)}")
        return ControllerId(None, None, notes, None, AuditClaim(
            "controller", said, "not replayable", "unchecked", f"the log has no usable {', '.join(missing)}"))
    hit = completed or infer_controller(u, theta, v, a, dt, CLAMP, prefer=prefer, cut=cut, restarts=restarts)
    if hit is None and not cut:  # a copy cut while the hub rested but the controller's memory did not
        hit = infer_controller(u, theta, v, a, dt, CLAMP, prefer=prefer, cut=True, restarts=restarts)
        if hit is not None and getattr(hit.controller, "history", 0):
            notes.append(_CUT_NOTE.format(hit.controller.history))
            cut = True
    if hit is None and not cut and not len(restarts):  # a law but for a corrupted field or two
        past = law_past_glitches(u, theta, a, v, dt, CLAMP, ALIGNMENTS, prefer)
        if past is not None:
            glitch = past[1]
            aside, u, theta, a, v = _set_aside(glitch, data['t'], u, theta, a, v)
            law = past[0].law if glitch.law is past[0].controller else describe_controller(glitch.law)
            hit = IdentifiedController(glitch.law, glitch.fit.alignment, glitch.fit.max_abs_dv, glitch.fit.v_replayed,
                                       law, past[0].design, (glitch.fit.alignment,))
    stated = controller is not None or pid is not None
    gap = None if controller is None or hit is not None else miss_at_gap(used, u, theta, a, v, data["n"], skipped)
    judged_to = None  # a law with memory in no column (Ga's) is judged before n jumps, as the header's is
    if hit is None and gap is None and not cut and (found := law_before_gap(u, theta, a, v, data["n"], skipped, dt,
                                                                            prefer)) is not None:
        hit, judged_to = found
    if hit is not None:
        fit = AlignmentFit(hit.alignment, hit.max_abs_dv, hit.v_replayed)
        at = f" at alignment {hit.alignment}" if is_closed_loop(hit.controller) else ""
        upto = "" if judged_to is None else f" before row {judged_to}, where n jumps (not judged across it)"
        data_says = f"{hit.law}{at}, reproduces every logged v {_how_close(hit.max_abs_dv, printing)}{upto}"
        idle = None if controller is None else idle_ga(controller, hit.controller, a, hit.alignment)
        if controller is not None and (hit is completed or same_law(controller, hit.controller) or idle):
            # the header holds; the data complete the rest (clamp, stored integer, digits, a Ga stored as 0)
            data_says += "" if idle is None else f"; {idle}"
            notes.append(f"the header's controller ({said}) is the data's law, completed from the data: "
                         f"{data_says}")
            return ControllerId(hit.controller, "header", notes, fit, AuditClaim(
                "controller", said, data_says, "confirmed", f"the data's law has the header's {'Gth ' if idle else ''}"
                f"coefficients (to {SAME_LAW_RTOL:g} relative); as printed it "
                f"replays v to max |dv| = {_counts(header_dv)}, completed from the data "
                f"{_how_close(hit.max_abs_dv, printing)}{at}{upto}{aside}"), hit.alignments, cut=cut,
                judged_to=judged_to, corrupted=glitch)
        if stated:
            data_says += gain_words(controller, hit.controller, "b0" in log.meta)
            notes.append(f"the header's controller ({said}) does not reproduce the logged v (max |dv| = "
                         f"{_counts(header_dv)}); the data's is used: {data_says}")
            return ControllerId(hit.controller, "inferred (header contradicted)", notes, fit, AuditClaim(
                "controller", said, data_says, "contradicted",
                f"the header's controller replays v to max |dv| = {_counts(header_dv)} at best; the data's law "
                f"reproduces every logged v {_how_close(hit.max_abs_dv, printing)}{at}{upto}{aside}"), hit.alignments,
                cut=cut, judged_to=judged_to, corrupted=glitch)
        notes.append(f"controller inferred from the data: {hit.law}, alignment {hit.alignment} "
                     f"(reproduces the logged v {_how_close(hit.max_abs_dv, printing)}{upto})")
        return ControllerId(hit.controller, "inferred", notes, fit, AuditClaim(
            "controller", said, data_says, "unchecked", f"the log names no controller; inferred from the data{aside}"),
            hit.alignments, cut=cut, judged_to=judged_to, corrupted=glitch)
    tried = ("open loop, P, linear e -> v up to order 3, on the float or the stored integer command, "
             "designs on the float with the whole count sent, Gth with accelerometer feedback Ga up to order 3 "
             "each on the float command, the thesis's Ga beside a Gth on whole counts, alignments 0 and 1")
    if not stated:
        notes.append(f"the log names no controller and none could be inferred from the data ({tried}): "
                     f"commands not replayed, model driven by the logged v")
        return ControllerId(None, None, notes, None, AuditClaim(
            "controller", said, NO_LAW, "unchecked", f"none reproduces the logged v ({tried})"))
    verdict = "contradicted" if header_dv >= 1.0 else "unchecked"
    evidence = (f"the header's controller replays v to max |dv| = {_counts(header_dv)} at best, and no law "
                f"tried ({tried}) reproduces it")
    data_says = f"not this law (max |dv| = {_counts(header_dv)}); no law found"
    if gap is not None:  # the law is judged on rows it never saw together: not a contradiction
        gap, fit = gap
        verdict = "unchecked"
        data_says = f"this law up to row {gap}, where n jumps; not judged across it"
        evidence += (f"; but it reproduces every row before row {gap}, where n jumps (rows missing or repeated): "
                     f"across the gap its inputs are not the log's ticks, so the data cannot judge it")
    if verdict == "contradicted":
        notes.append(f"{evidence}: the header's controller is used, but the data contradict it")
    return ControllerId(controller, "header" if controller is not None else None, notes,
                        None if controller is None else fit, AuditClaim(
                            "controller", said, data_says, verdict, evidence), judged_to=gap)


def _counts(dv: float) -> str:
    """A replay's largest miss in words: "3 counts", or that the replay diverged (an unstable law)."""
    return f"{dv:.3g} counts" if math.isfinite(dv) else "no finite value (its replay diverges: an unstable law)"


_CUT_NOTE = ("the law reproduces the log with its first {} row(s) of memory taken as logged: a copy cut from a "
             "longer run (the controller remembered the earlier rows)")


def _header_pid(log: RunLog) -> tuple[float, float, float] | None:
    """(kp, ki, kd) of a rig header whose PID has ki or kd != 0, else None."""
    meta = log.meta
    if log.format != "rig" or "kp" not in meta:
        return None
    try:
        kp, ki, kd = (_header_number(meta, key) for key in ("kp", "ki", "kd"))
    except StationError:
        return None
    return (kp, ki, kd) if (ki != 0.0 or kd != 0.0) else None


def _custom_controller(log: RunLog) -> str | None:
    """The name of a custom Python controller our log's header records ({"kind": "custom"}), else None."""
    spec = log.meta.get("controller") if log.format == "station" else None
    if not isinstance(spec, dict) or spec.get("kind") == "open-loop" or "gth" in spec:
        return None
    return str(spec.get("name") or spec.get("kind") or "unnamed")


def _named_controller(log: RunLog, dt: float | None = None) -> tuple[Compensator | OpenLoop | None, list[str]]:
    """The controller the log's header names (None when it names none), at ``dt`` (default the log's)."""
    if log.format == "station":
        spec = log.meta.get("controller")
        if not isinstance(spec, dict):
            return None, []
        try:
            return controller_from_spec(spec), []
        except StationError as exc:  # name the log
            raise StationError(f"{log.path}: {exc}", file=log.path, key="controller") from None
    try:
        return rig_controller(log.meta, log.dt if dt is None else dt)
    except StationError as exc:  # a header field: name the file and its line
        key = exc.key
        line = None if key is None else next((i for i, text in enumerate(log.header, 1)
                                              if text[1:].strip().startswith(key) and "=" in text), None)
        where = f"{log.path}: line {line}" if line else str(log.path)
        raise StationError(f"{where}: {exc}", file=log.path, line=line, key=key) from None
