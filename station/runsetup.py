"""How a step run is set up, before anything starts: its reference, its controller and clamp,
and the simulated rig's port (the parts :func:`station.plan.plan_step` settles a run from).
"""

from __future__ import annotations

import tempfile
import urllib.parse
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
from serial import SerialException

from station.control import (KINDS, file_reference, make_controller, pulse_reference, step_reference,
                             swept_sine_reference)
from station.control.contract import wire_limit
from station.control.designs import read_compensator_file
from station.errors import StationError
from station.inputs import exists
from station.rig import CLAMP, DEFAULT_DURATION, DT

REFERENCES = ("step", "pulse", "swept-sine")
"""Built-in reference laws; a run log's column (``FILE[:COLUMN]``) is the other kind."""
PULSE_WIDTH = 0.1
"""Width of the open-loop pulse, s (the rig's pulse test)."""
SWEPT_SINE_DURATION = 22.0
"""Default length of a swept-sine run, s: the law spans 1 < t <= 21 s (DESIGN.md)."""


def default_duration(kind: str) -> float | None:
    """A run's length when none is asked for, s: 2 s (step, pulse), 22 s (swept sine), None
    for a file reference (its own length).

    Parameters
    ----------
    kind : str
        The reference (:func:`make_reference`).

    Returns
    -------
    float or None
    """
    if kind not in REFERENCES:
        return None
    return SWEPT_SINE_DURATION if kind == "swept-sine" else DEFAULT_DURATION


def make_reference(kind: str, amplitude: float, duration: float | None, step_tick: int,
                   dt: float = DT) -> tuple[np.ndarray, dict]:
    """The reference u[k] of a test, and its description for the log header.

    Parameters
    ----------
    kind : str
        "step" (amplitude from ``step_tick`` on), "pulse" (open loop: +amplitude for
        0.1 s from ``step_tick``), "swept-sine" (u = trunc(amplitude sin(2π(t−1)²)) for
        1 < t ≤ 21 s, DESIGN.md), or ``FILE[:COLUMN]``: a column (default u) of a run log,
        ours or the rig's.
    amplitude : float
        Counts (encoder counts closed loop, DAC counts open loop); unused for a file.
    duration : float or None
        Run length, s; None: 2 s (step, pulse), 22 s (swept sine), the file's length.
    step_tick : int
        Tick of the step or pulse start.
    dt : float
        Sample time, s.

    Returns
    -------
    u : ndarray, shape (n_ticks,)
    meta : dict
        JSON-able description (kind, amplitude, ticks, file).

    Raises
    ------
    StationError
        Unknown kind, unreadable file or column, a run shorter than two samples, or a
        step tick outside the run.
    """
    if kind in REFERENCES:
        if duration is None:
            duration = default_duration(kind)
        n_ticks = int(round(duration / dt))
        if n_ticks < 2:
            raise StationError(f"--duration {duration} s is shorter than two samples of {dt} s")
        if kind != "swept-sine" and not 0 <= step_tick < n_ticks:
            raise StationError(f"step tick {step_tick} is outside the run's {n_ticks} ticks")
        if kind == "step":
            u = step_reference(amplitude, n_ticks, at_tick=step_tick)
        elif kind == "pulse":
            u = pulse_reference(amplitude, n_ticks, step_tick, int(round(PULSE_WIDTH / dt)))
        else:
            u = swept_sine_reference(n_ticks, amplitude, dt)
        return u, {"kind": kind, "amplitude": amplitude, "step_tick": step_tick, "n_ticks": n_ticks}
    path, column = _reference_file(kind)
    if not exists(path):
        raise StationError(f"reference {kind!r}: expected one of {', '.join(REFERENCES)} or FILE[:COLUMN] "
                           f"of a run log; no file {path}")
    u = file_reference(path, column or "u")
    if duration is not None:
        n_ticks = int(round(duration / dt))
        u = np.concatenate([u[:n_ticks], np.full(max(0, n_ticks - u.size), u[-1] if u.size else 0.0)])
    if u.size < 2:
        raise StationError(f"reference {kind!r}: fewer than two samples")
    return u, {"kind": "file", "file": str(path), "column": column or "u", "n_ticks": int(u.size)}


def _reference_file(kind: str) -> tuple[Path, str]:
    """``FILE[:COLUMN]`` split: the file and the column ("" for the default)."""
    if exists(kind) or ":" not in kind:  # (inputs.exists: never raises, even on a name too long)
        return Path(kind), ""
    path, _, column = kind.rpartition(":")
    return Path(path), column


def reference_path(kind: str) -> Path | None:
    """The run log a ``FILE[:COLUMN]`` reference reads (None for a built-in law).

    Parameters
    ----------
    kind : str
        The ``--reference`` value (:func:`make_reference`).
    """
    return None if kind in REFERENCES else _reference_file(kind)[0]


class ChosenController(NamedTuple):
    """The controller a run uses (:func:`choose_controller`).

    Attributes
    ----------
    controller : controller object
        ``step(u, theta, a) -> (v, theta_d_hat)``, ``reset()``, a JSON-able ``spec``.
    note : str or None
        Which clamp won when a compensator file's own ``limit`` overrides the one asked
        for (``--limit 100 is not used: c.toml sets limit = 150 (the file wins)``).
    limit : float
        The run's clamp, ±DAC counts: the controller's own (a compensator file's, an
        object's finite ``limit``), else the one asked for, else 200; never above the
        DAC's range (:func:`station.control.contract.wire_limit`). Every command is
        clamped to it before the wire, and the log header's ``limit`` records it.
    """

    controller: Any
    note: str | None
    limit: float


def choose_controller(controller, kp: float | None = None, limit: float | None = None,
                      dt: float = DT) -> ChosenController:
    """Build the run's controller; the one place where its clamp is settled.

    A compensator file's own ``limit`` wins over ``limit`` (the note says so); otherwise
    the controller clamps at ``limit`` (default 200). A controller object is used as
    given (reset), its own finite ``limit`` winning too.

    Parameters
    ----------
    controller : str, Path or controller object
        "p", "lead", "lead-accel", "open-loop", a compensator file, or an object as
        :func:`run_step` takes.
    kp : float, optional
        P gain (kind "p"; default 2).
    limit : float, optional
        The clamp asked for, ±DAC counts (None: 200, and no note).
    dt : float
        Sample time, s.

    Returns
    -------
    ChosenController
        The controller, at rest; the note; the run's clamp.

    Raises
    ------
    StationError
        An unknown kind, a bad compensator file, a bad kp or limit, a kp for another
        controller than "p".
    """
    is_object = not isinstance(controller, (str, Path))
    if kp is not None and (is_object or str(controller) != "p"):
        raise StationError(f"--kp: the P gain applies to --controller p only, not "
                           f"{'a controller object' if is_object else controller}")
    clamp = CLAMP if limit is None else limit
    if is_object:
        controller.reset()
        return ChosenController(controller, None, wire_limit(controller, clamp))
    kind = str(controller)
    note = None
    if kind in KINDS or not exists(kind):  # make_controller names what a kind may be (or refuses a folder)
        built = make_controller(kind, dt=dt, kp=2.0 if kp is None else kp, limit=clamp)
    else:
        found = read_compensator_file(kind)
        if limit is not None and found.sets_limit:
            note = f"--limit {limit:g} is not used: {kind} sets limit = {found.limit_text()} (the file wins)"
        built = found.compensator(dt, clamp)
    return ChosenController(built, note, wire_limit(built, clamp))


def log_tag(controller) -> str:
    """The controller's name in default log names: its kind, or a compensator file's stem.

    Parameters
    ----------
    controller : controller object
        Its ``spec`` names the kind (and the file).
    """
    spec = controller.spec
    if spec.get("kind") == "file" and spec.get("file"):
        return Path(spec["file"]).stem
    return str(spec.get("kind", "custom"))


def sim_port(port: str, model=None, elements=None, seed=None) -> str:
    """``port`` with the simulated rig's model, element count and seed as sim:// URL options.

    Parameters
    ----------
    port : str
        The port URL.
    model : str or Path, optional
        A built-in model's name or a model file (``sim://?model=``).
    elements, seed : int, optional
        ``sim://?elements=``, ``sim://?seed=``.

    Raises
    ------
    StationError
        One of them given for a port that is not ``sim://`` (named as its option, e.g.
        ``--model``), or for a ``sim://`` URL that sets it too (naming both: which one
        would win is not for the station to guess).
    """
    extra = {k: str(v) for k, v in (("model", model), ("elements", elements), ("seed", seed)) if v is not None}
    if not extra:
        return port
    if not port.lower().startswith("sim://"):
        raise StationError(f"--{next(iter(extra))}: only for the simulated rig (--port sim://...), not {port!r}")
    given = dict(urllib.parse.parse_qsl(urllib.parse.urlsplit(port).query, keep_blank_values=True))
    both = next((k for k in extra if k in given), None)
    if both is not None:
        raise StationError(f"--{both} {extra[both]} and --port {port}: both set the simulated "
                           f"rig's {both}; give one of them", key=both)
    query = urllib.parse.urlencode(extra)
    return port + ("&" if "?" in port else "?") + query


def run_url(port: str, model, n_elements: int | None,
            seed: int | None) -> tuple[str, tempfile.TemporaryDirectory | None]:
    """The port a run opens: :func:`sim_port`, its sim:// options checked before anything starts;
    a Model object goes to the simulated rig as a model file in a temporary folder.

    Parameters
    ----------
    port : str
        The port URL.
    model : Model, str, Path or None
        The simulated rig's model (a Model object, a built-in name or a model file).
    n_elements, seed : int or None
        The simulated rig's element count and seed.

    Returns
    -------
    url : str
    folder : tempfile.TemporaryDirectory or None
        The model file's folder: remove it once the port is open (the rig has read it).

    Raises
    ------
    StationError
        As :func:`sim_port`, or a sim:// option out of its range (named as the command line's
        option when it came from there).
    """
    folder = None
    if model is not None and not isinstance(model, (str, Path)):
        folder = tempfile.TemporaryDirectory(prefix="station-model-")
        path = Path(folder.name) / "model.toml"
        model.save(path)
        model = path
    url = sim_port(port, model, n_elements, seed)
    if url.lower().startswith("sim://"):  # the URL's options and model checked before anything starts

        # lazy: start-up time (the simulator, only for sim:// ports)
        from station.sim.protocol_sim import OptionError, parse_url

        try:
            parse_url(url)
        except SerialException as exc:
            if folder is not None:
                folder.cleanup()
            option = exc.option if isinstance(exc, OptionError) else None
            given = {"model": model, "elements": n_elements, "seed": seed}.get(option)
            if given is not None:  # an option of the command line (or run_step's argument): name it
                raise StationError(f"--{option}: {exc.detail}", key=option) from None
            raise StationError(f"--port {url}: {exc}", key="port") from None
    return url, folder




class DesignModel(NamedTuple):
    """The simulated rig's model for a compensator file that records its design model
    (:func:`design_model_note`).

    Attributes
    ----------
    model : str, Path or None
        The model the run should use (None: the port's own, tmm-fit by default).
    note : str or None
        One line to show: which model runs and why, or that it is not the design model.
    """

    model: Any
    note: str | None


def design_model_note(controller, model, port: str, n_elements: int | None = None) -> DesignModel:
    """The simulated rig's model for a run, given the compensator file's ``[design]`` record.

    The choice (docs/tuning.md "Running a tuned compensator"): on a simulated rig (``sim://``),
    a compensator file that records the model it was designed on runs on that model when no
    model is given (``--model`` or ``sim://?model=``), if it is still the same model (a
    built-in name, or the model file, its path relative to the compensator file's folder, as
    long as it exists and its sha256 matches), and the note says so; when a model is given
    and it is not the design model, that model runs and the note says so. A real port, a
    built-in controller kind or a file without a record: no note, the model as given.

    Parameters
    ----------
    controller : str, Path or controller object
        ``--controller``.
    model : str, Path or None
        ``--model`` (None: not given).
    port : str
        ``--port``.
    n_elements : int, optional
        ``--elements`` (part of the model that runs).

    Returns
    -------
    DesignModel

    Raises
    ------
    StationError
        A compensator file that cannot be read (as :func:`choose_controller`).
    """
    from station.plant.model import Model, builtin_models, load_model  # lazy: start-up time (the plant: scipy)

    if (not isinstance(controller, (str, Path)) or str(controller) in KINDS or not exists(controller)
            or not str(port).lower().startswith("sim://")):
        return DesignModel(model, None)
    record = read_compensator_file(controller).design
    if record is None:
        return DesignModel(model, None)
    given = model if model is not None else dict(urllib.parse.parse_qsl(urllib.parse.urlsplit(str(port)).query)).get(
        "model")
    designed = f"{controller} was designed on model {record.model!r}"
    if given is not None:
        try:
            served = given if isinstance(given, Model) else load_model(given, n_elements)
            ok = record.matches(served.to_toml())
        except StationError:  # a bad --model is refused where it is opened, with its own line
            return DesignModel(model, None)
        return DesignModel(model, None if ok else f"{designed}; the simulated rig runs {str(given)!r}, another model "
                                                  f"(sha256 differs)")
    path = Path(record.model)
    if not path.is_absolute():
        path = Path(controller).parent / path
    found = str(path) if path.suffix.lower() == ".toml" and exists(path) else (
        record.model if record.model in builtin_models() else None)
    if found is None:
        return DesignModel(None, f"{designed}, not a built-in model or a model file here: the simulated rig runs "
                                 f"its default, tmm-fit")
    try:
        design = load_model(found)
    except StationError as exc:
        return DesignModel(None, f"{designed}, which cannot be read ({exc}): the simulated rig runs its default, "
                                 f"tmm-fit")
    if not record.matches(design.to_toml()):
        return DesignModel(None, f"{designed}, which has changed since (sha256 differs): the simulated rig runs its "
                                 f"default, tmm-fit")
    other = "" if n_elements is None or n_elements == design.n_elements else \
        f" (with --elements {n_elements}: another model than the {design.n_elements} elements it was designed on)"
    return DesignModel(found, f"simulated rig: model {record.model}, from {controller}'s design record{other}")
