"""Which controller ran a logged run: named by its header, matched, or inferred from the data.

Our logs record the controller's spec; the rig's headers print P gains, PID gains or the
compensators' z coefficients to 8 decimals. When those equal the Tustin coefficients of
the known continuous designs to the printed digits, the unrounded designs are used
(DESIGN.md: the printed Ga alone replays the accelerometer run only to 0.03 counts). A
PID header is matched against the standard discretizations, and a log that names no
controller gets one identified from u, θ and v (:mod:`station.analysis.identify`),
accepted only when it reproduces every logged v.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from station.analysis.identify import infer_controller, match_pid
from station.control import Compensator, DiscreteTF, OpenLoop, controller_from_spec, lead_controller, p_controller
from station.control.designs import MAX_ORDER, z_problem
from station.errors import StationError
from station.runlog import RIG_DT, RunLog  # RIG_DT: the rig's sample time, its compensators ran at it

RIG_LIMIT = 200.0
"""The rig software's clamp of v, DAC counts (DESIGN.md)."""

PRINTED_TOLERANCE = 5.0001e-9
"""Largest difference between a coefficient and its 8-decimal print (half a unit in the 8th place)."""


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


def rig_controller(meta: dict[str, Any], dt: float = 0.002) -> tuple[Compensator | OpenLoop | None, list[str]]:
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
    if "Gth" in meta:
        ref = lead_controller(RIG_LIMIT, dt, accel=True)
        gth, gth_known = _rig_stage(meta, "Gth", ref.gth, notes)
        if gth is None:
            return None, [f"header has an empty Gth ({test}): controller unknown"]
        ga, ga_known = _rig_stage(meta, "Ga", ref.ga, notes)
        known = gth_known and ga_known
        name = ("lead-accel" if ga is not None else "lead") if known else "rig-printed"
        spec = {"kind": name, "name": name, "dt": dt, "limit": RIG_LIMIT, "source": "rig header",
                "gth": {"num_z": gth.num.tolist(), "den_z": gth.den.tolist()},
                "ga": None if ga is None else {"num_z": ga.num.tolist(), "den_z": ga.den.tolist()}}
        if known:
            notes.append("printed coefficients equal the Tustin designs to their 8 decimals: unrounded designs used")
        return Compensator(gth, ga, limit=RIG_LIMIT, name=name, spec=spec), notes
    if "kp" in meta:
        kp, ki, kd = (_header_number(meta, key) for key in ("kp", "ki", "kd"))
        if ki != 0.0 or kd != 0.0:  # how the rig discretized it: the data decide (identify_controller)
            return None, []
        if "ki" in meta or "kd" in meta:
            notes.append("PID_control with ki = kd = 0: P control")
        return p_controller(kp, RIG_LIMIT, dt), notes
    if "OL" in test.split("_") or test.startswith("OL"):
        return OpenLoop(limit=None), notes
    return None, notes


class ControllerId(NamedTuple):
    """Which controller ran a log and where that came from (:func:`identify_controller`).

    Attributes
    ----------
    controller : Compensator, OpenLoop or None
        None when no controller is known: commands not replayed, the model driven by the
        logged v.
    source : {"header", "inferred"} or None
        "header": named by the log (including a PID header matched to a standard
        discretization); "inferred": identified from the data.
    notes : list of str
        One line each on what was assumed or could not be done.
    """

    controller: Compensator | OpenLoop | None
    source: str | None
    notes: list[str]


def log_controller(log: RunLog) -> tuple[Compensator | OpenLoop | None, list[str]]:
    """The controller that ran a log: named by its header, else identified from the data.

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


def identify_controller(log: RunLog) -> ControllerId:
    """The controller that ran a log, and whether the header named it or the data did.

    Order: the header's controller; a PID header with ki or kd != 0 matched against the
    standard discretizations (:func:`station.analysis.identify.match_pid`); else a law
    identified from u, θ and v (:func:`station.analysis.identify.infer_controller`:
    open loop, P, linear e -> v up to order 3), accepted only when it reproduces every
    logged v to 1e-6 DAC counts. A rig log sampled at another rate than the rig's
    0.002 s cannot be replayed with a closed-loop controller (the rows it ran on are
    missing): one note says so and the model is driven by the logged v.

    Parameters
    ----------
    log : RunLog

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
        return ControllerId(None, None, [f"the log's controller is a custom Python controller ({custom}): its "
                                         f"commands cannot be replayed; the model is driven by the logged v"])
    controller, notes = _named_controller(log)
    dt = log.dt
    data = log.data
    u, theta, v, a = data["u"], data["theta"], data["v"], data["a"]
    if log.format == "rig" and abs(dt - RIG_DT) > 1e-9 and not isinstance(controller, OpenLoop):
        notes.append(f"sampled at {dt:g} s, not the rig's {RIG_DT:g} s: closed-loop commands cannot be "
                     f"replayed or inferred (the rig's controllers ran at {RIG_DT:g} s, on rows this log "
                     f"lacks); the model is driven by the logged v at {dt:g} s")
        return ControllerId(None, None, notes)
    if controller is not None:
        return ControllerId(controller, "header", notes)
    missing = [name for name in ("u", "theta", "v") if not np.all(np.isfinite(data[name]))]
    pid = _header_pid(log)
    if pid is not None and not missing:
        hit, best = match_pid(*pid, u, theta, v, a, dt, RIG_LIMIT)
        gains = f"kp = {pid[0]:g}, ki = {pid[1]:g}, kd = {pid[2]:g}"
        if hit is not None:
            notes.append(f"PID header ({gains}) replayed with the {hit.law}")
            return ControllerId(hit.controller, "header", notes)
        notes.append(f"PID header ({gains}): no standard discretization (integral by backward Euler, "
                     f"forward Euler or Tustin; derivative by backward difference) reproduces the logged v "
                     f"(best max |dv| = {best:.3g} counts)")
    elif pid is not None:
        notes.append(f"PID header, but the log has no usable {', '.join(missing)}: commands not replayed")
    if missing:
        if pid is None:
            notes.append(f"the log names no controller and has no usable {', '.join(missing)} column to "
                         f"infer one from: commands not replayed, model driven by the logged v")
        return ControllerId(None, None, notes)
    hit = infer_controller(u, theta, v, a, dt, RIG_LIMIT)
    if hit is not None:
        notes.append(f"controller inferred from the data: {hit.law}, alignment {hit.alignment} "
                     f"(reproduces the logged v to {hit.max_abs_dv:.2g} counts)")
        return ControllerId(hit.controller, "inferred", notes)
    if pid is None:
        notes.append("the log names no controller and none could be inferred from the data (open loop, "
                     "P, linear e -> v up to order 3): commands not replayed, model driven by the logged v")
    return ControllerId(None, None, notes)


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
    """The name of a custom Python controller our log's header records (a spec with
    neither coefficients nor open loop, e.g. ``{"kind": "custom"}``), else None."""
    spec = log.meta.get("controller") if log.format == "station" else None
    if not isinstance(spec, dict) or spec.get("kind") == "open-loop" or "gth" in spec:
        return None
    return str(spec.get("name") or spec.get("kind") or "unnamed")


def _named_controller(log: RunLog) -> tuple[Compensator | OpenLoop | None, list[str]]:
    """The controller the log's header names (None when it names none)."""
    if log.format == "station":
        spec = log.meta.get("controller")
        if not isinstance(spec, dict):
            return None, []
        try:
            return controller_from_spec(spec), []
        except StationError as exc:  # name the log
            raise StationError(f"{log.path}: {exc}", file=log.path, key="controller") from None
    dt = log.dt
    try:
        return rig_controller(log.meta, dt)
    except StationError as exc:  # a header field: name the file and its line
        key = exc.key
        line = None if key is None else next((i for i, text in enumerate(log.header, 1)
                                              if text[1:].strip().startswith(key) and "=" in text), None)
        where = f"{log.path}: line {line}" if line else str(log.path)
        raise StationError(f"{where}: {exc}", file=log.path, line=line, key=key) from None
