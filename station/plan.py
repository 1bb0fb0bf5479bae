"""A step test planned once: every setting settled and checked before anything starts.

:func:`plan_step` turns what a step test is asked for (``station step``'s options, or the
keywords of :func:`station.experiment.run_step` in a notebook) into a :class:`StepPlan`, and
:func:`station.experiment.run_step` runs it. The command line and Python go through the same
function, so they refuse the same things with the same one line
(:class:`station.errors.StationError`), before a port is opened or a file written:

- every number in its range (:data:`RANGES`, the command line's own);
- options that do not apply: a P gain for another controller, an amplitude with a file
  reference, a step time with a swept sine or a file;
- the step inside the run; the run within what the protocol counts
  (:func:`station.protocol.check_ticks`) and what the machine holds (memory, disk);
- the reference's peak: closed loop below the soft limit (after a compensator's reference
  shaper too), open loop within the DAC's range (the reference is the command);
- the simulated rig's options and model (:func:`station.runsetup.run_url`);
- the outputs through the one output guard (:func:`station.outputs.check_outputs`), every
  input counted: the compensator file, the reference's log and the simulated rig's model
  file (``--model FILE`` or ``sim://?model=FILE``).

The step's start is a tick, held as a tick from the plan to the log header and the metrics;
its time (``step_tick × dt``) is derived for printing and for the metrics' time axis only.
"""

from __future__ import annotations

import datetime as _dt
import shutil
import tempfile
import time
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from station.control.contract import DAC_LIMIT
from station.control.rerun import is_closed_loop
from station.control.shaper import ReferenceShaper
from station.errors import StationError
from station.inputs import exists, sim_model_file
from station.link import LinkLimits
from station.outputs import Input, Output, check_folder, check_outputs, is_device
from station.protocol import check_ticks
from station.ranges import TICKS, RangeError, number
from station.rig import DEFAULT_AMPLITUDE, DEFAULT_SOFT_LIMIT, DEFAULT_STEP_TICK, DEFAULT_TIMEOUT, DT
from station.runsetup import (REFERENCES, choose_controller, default_duration, design_model_note, log_tag,
                              make_reference, reference_path, run_url)
from station.viz import RRD_BYTES_PER_TICK

DEFAULT_PORT = "sim://"
DEFAULT_CONTROLLER = "lead"

MAX_DURATION_S = TICKS * DT
"""Longest run v1 can count (START's n_ticks is a u32), s."""
MAX_AMPLITUDE = 32767.0
"""Largest step height, counts (the legacy protocol's θ word is int16; the soft limit bounds it further)."""

RANGES = {
    "amplitude": number(-MAX_AMPLITUDE, MAX_AMPLITUDE, nonzero=True),
    "duration": number(2 * DT, MAX_DURATION_S, unit="s"),
    "step_time": number(0.0, MAX_DURATION_S, unit="s"),
    "step_tick": number(0, TICKS, integer=True, unit="ticks"),
    "kp": number(1e-3, 100.0),
    "limit": number(1, DAC_LIMIT, unit="DAC counts"),
    "soft_limit": number(1, 32767, unit="encoder counts"),
    "timeout": number(1e-3, 60.0, unit="s"),
    "baudrate": number(300, 12_000_000, integer=True),
    "dt": number(1e-5, 1.0, unit="s"),
}
"""The range of each number of a step test, by :func:`plan_step`'s keyword: ``station step``'s
options take these as their argparse types, and :func:`plan_step` checks a Python caller's
values with them (named as the options: ``--step-time``, ``--baud``)."""

OPTION_OF = {"baudrate": "--baud"}
"""The command-line option of a keyword whose name is not the option's (others: ``--`` and ``-`` for ``_``)."""

BYTES_PER_TICK_MEMORY = 200
"""Memory a run needs per tick, bytes, at its peak (the reference as floats for the loop,
latencies, the log read back for metrics and the figure), rounded up."""
BYTES_PER_TICK_DISK = 80
"""Disk a run log takes per tick, bytes (a row of our format is ~60)."""


def option_name(keyword: str) -> str:
    """How messages name a setting: its command-line option (``step_time`` -> ``--step-time``).

    Parameters
    ----------
    keyword : str
        A keyword of :func:`plan_step`.

    Returns
    -------
    str
    """
    return OPTION_OF.get(keyword, "--" + keyword.replace("_", "-"))


def figure_path(log_path: str | Path) -> Path:
    """The figure :func:`station.experiment.run_step` draws beside a run log: ``<log stem>.png``.

    Parameters
    ----------
    log_path : str or Path
        The run log.

    Returns
    -------
    Path
    """
    return Path(log_path).with_suffix(".png")


def default_log_path(tag: str, when: _dt.datetime | None = None, folder: str | Path = "runs") -> Path:
    """``runs/step-<tag>-<UTC time, ms>.tsv`` under the current directory (tag: controller
    name), with ``-2``, ``-3``... added when that name exists: names never collide.

    Parameters
    ----------
    tag : str
        The controller's name.
    when : datetime, optional
        The time in the name (default now, UTC).
    folder : str or Path, default "runs"
        Folder of the log.

    Returns
    -------
    Path
        A name that neither a log nor its figure uses yet.
    """
    when = when or _dt.datetime.now(_dt.UTC)
    stem = f"step-{tag}-{when:%Y%m%d-%H%M%S}-{when.microsecond // 1000:03d}"
    path = Path(folder) / f"{stem}.tsv"
    counter = 1
    while exists(path) or exists(figure_path(path)):
        counter += 1
        path = Path(folder) / f"{stem}-{counter}.tsv"
    return path


@dataclass(frozen=True, eq=False)
class StepPlan:
    """A step test, settled and checked, ready to run (:func:`plan_step`; run by
    :func:`station.experiment.run_step`).

    Attributes
    ----------
    url : str
        The port to open; a ``sim://`` URL carries the simulated rig's model, element
        count and seed.
    protocol : {"v1", "legacy"}
    baudrate : int or None
        None: the protocol's.
    limits : station.link.LinkLimits
        The link's fail-safe bounds (timeout, lag, misses, encoder step).
    controller : controller object
        At rest; ``step(u, theta, a)``, ``reset()``, ``spec``.
    limit : float
        The run's clamp, ±DAC counts (:func:`station.runsetup.choose_controller`).
    soft_limit : float
        |θ| beyond this many encoder counts stops the run.
    reference : str
        The reference as asked: "step", "pulse", "swept-sine" or ``FILE[:COLUMN]``.
    u : numpy.ndarray, shape (n_ticks,)
        The reference per tick, counts (encoder counts closed loop, DAC counts open loop).
    reference_meta : dict
        The log header's ``reference``.
    amplitude : float or None
        Step height, counts (None for a file reference).
    step_tick : int
        Tick of the step's (pulse's) start.
    dt : float
        Sample time, s.
    log_path : Path
        The run log.
    figure_path : Path or None
        The figure beside it (None: none is drawn).
    force : bool
        The log and its figure may replace existing files.
    lean : bool
        The loop's real-time settings (:func:`station.loop.run_loop`).
    model : str or None
        The simulated rig's model as its URL names it (a built-in name or a file; None:
        the port's default, or a real port).
    notes : tuple of str
        Which value won where two were given (a compensator file's own ``limit``).
    planning_s : float
        Time the plan took to make, s (part of the run's ``setup_s``).
    inputs : tuple of Input
        Every file the run reads (the compensator file, the reference's log, the model
        file, the caller's): no output may replace one.
    model_folder : tempfile.TemporaryDirectory or None
        The temporary folder of a Model object's file (removed with the plan).
    """

    url: str
    protocol: str
    baudrate: int | None
    limits: LinkLimits
    controller: Any
    limit: float
    soft_limit: float
    reference: str
    u: np.ndarray
    reference_meta: dict
    amplitude: float | None
    step_tick: int
    dt: float
    log_path: Path
    figure_path: Path | None
    force: bool = False
    lean: bool = True
    model: str | None = None
    notes: tuple[str, ...] = ()
    planning_s: float = 0.0
    inputs: tuple[Input, ...] = ()
    model_folder: tempfile.TemporaryDirectory | None = field(default=None, repr=False)

    @property
    def n_ticks(self) -> int:
        """Ticks of the run."""
        return int(self.u.size)

    @property
    def duration(self) -> float:
        """Length of the run, s."""
        return self.n_ticks * self.dt

    @property
    def step_time(self) -> float:
        """When the step starts, s from t = 0 of the log (``step_tick × dt``)."""
        return self.step_tick * self.dt

    @property
    def closed_step(self) -> bool:
        """A closed-loop step: the runs that have step metrics."""
        return self.reference == "step" and is_closed_loop(self.controller)

    def check_outputs(self) -> None:
        """Check the log and its figure again through the output guard (a run starts with this:
        a file may have appeared since the plan was made, or the plan already ran).

        Raises
        ------
        StationError
            As :func:`station.outputs.check_outputs`.
        """
        check_outputs([Output("the run log", self.log_path), Output("the run log's figure", self.figure_path)],
                      self.inputs, force=self.force)

    def __repr__(self) -> str:
        what = (f"{self.reference} of {self.amplitude:g} counts at tick {self.step_tick} ({self.step_time:g} s)"
                if self.amplitude is not None else f"reference {self.reference}")
        return (f"StepPlan({log_tag(self.controller)}, {what}, {self.n_ticks} ticks ({self.duration:g} s), "
                f"protocol {self.protocol} on {self.url}, clamp ±{self.limit:g}, soft limit {self.soft_limit:g}, "
                f"log {str(self.log_path)!r})")


def _check_numbers(values: dict[str, Any]) -> None:
    """Each given number in its :data:`RANGES` range; a one-line error naming its option."""
    for key, value in values.items():
        if value is None:
            continue
        try:
            RANGES[key].check(value)
        except RangeError as exc:
            raise StationError(f"{option_name(key)}: {exc}", key=key) from None


def _url_model(url: str) -> str | None:
    """The ``model`` option of a ``sim://`` URL (None without one, or for another port)."""
    return sim_model_file(url)


def _check_length(protocol: str, n_ticks: int, dt: float, what: str) -> None:
    """The run within what the protocol counts (:func:`check_ticks`), named as ``what``."""
    try:
        check_ticks(protocol, n_ticks, dt)
    except StationError as exc:
        raise StationError(f"{what}: {exc}") from None


def _check_peak(u: np.ndarray, controller, soft_limit: float, what: str, reference: str, named: str,
                dt: float) -> None:
    """Closed loop: the reference, and the shaped one, below the soft limit, every impulse of the
    shaper inside the run; open loop: within the DAC."""
    peak = float(np.max(np.abs(u))) if u.size else 0.0
    if not is_closed_loop(controller):
        if peak > DAC_LIMIT:
            raise StationError(f"{what}: open loop the reference is the command, at most {DAC_LIMIT:g} DAC counts")
        return
    kind = reference if reference in REFERENCES else "reference"
    if peak >= soft_limit:
        raise StationError(f"{what}: the {kind} would pass --soft-limit {soft_limit:g} encoder counts and stop the run")
    shaper = getattr(controller, "shaper", None)
    if isinstance(shaper, ReferenceShaper):
        moves = np.flatnonzero(u)
        last = shaper.delays[-1] if shaper.delays else 0
        if moves.size and moves[0] + last >= u.size:  # the shaped reference would never reach the reference
            raise StationError(f"--controller {named}: its reference shaper's last impulse comes {last * dt:g} s "
                               f"after the {kind} starts ({moves[0] * dt:g} s), past the run's end ({u.size * dt:g} "
                               f"s): the shaped {kind} would not reach its height within the run (a --duration "
                               f"longer than {(moves[0] + last + 1) * dt:g} s, or a shorter shaper)")
        shaped = float(np.max(np.abs(shaper.apply(u))))
        if not shaped < soft_limit:  # (NaN too)
            raise StationError(f"--controller {named}: its reference shaper takes the {kind} to {shaped:.6g} "
                               f"counts ({what}), past --soft-limit {soft_limit:g} encoder counts (the run would "
                               f"stop)")


def _check_resources(n_ticks: int, folder: Path, what: str, rrd: bool) -> None:
    """Refuse a run this machine cannot hold in memory (an .rrd recording too) or its log on disk."""
    need_mem = n_ticks * (BYTES_PER_TICK_MEMORY + RRD_BYTES_PER_TICK * rrd)
    need_disk = n_ticks * BYTES_PER_TICK_DISK
    available = _available_memory()
    if available is not None and need_mem > available:
        raise StationError(f"{what}: {n_ticks} ticks need about {need_mem / 1e9:.1f} GB of memory; "
                           f"this machine has {available / 1e9:.1f} GB available")
    existing = Path(folder)
    while not exists(existing) and existing.parent != existing:
        existing = existing.parent
    free = shutil.disk_usage(existing).free
    if need_disk > free:
        raise StationError(f"{what}: the run log would take about {need_disk / 1e9:.1f} GB; "
                           f"{existing} has {free / 1e9:.1f} GB free")


def _available_memory() -> int | None:
    """MemAvailable of /proc/meminfo, bytes (None where there is none)."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        return None
    return None


def _warn(note: str) -> None:
    warnings.warn(note, UserWarning, stacklevel=3)


def plan_step(port: str = DEFAULT_PORT, protocol: str = "v1", controller: Any = DEFAULT_CONTROLLER,
              amplitude: float | None = None, duration: float | None = None, step_time: float | None = None,
              step_tick: int | None = None, reference: str = "step", *,
              kp: float | None = None, limit: float | None = None, soft_limit: float = DEFAULT_SOFT_LIMIT,
              timeout: float = DEFAULT_TIMEOUT, limits: LinkLimits | None = None, baudrate: int | None = None,
              dt: float = DT, model=None, n_elements: int | None = None, seed: int | None = None,
              out: str | Path | None = None, out_dir: str | Path = "runs", force: bool = False,
              figure: bool = True, lean: bool = True, outputs: Sequence[Output] = (),
              inputs: Sequence[Input] = (), rrd: bool = False,
              notify: Callable[[str], None] | None = None) -> StepPlan:
    """Settle and check a step test before anything starts: the one plan of ``station step``
    and :func:`station.experiment.run_step`.

    Parameters
    ----------
    port : str
        Port path or pyserial URL; ``sim://`` is the built-in simulated rig (lockstep).
    protocol : {"v1", "legacy"}
        The device's wire protocol (``shared/spec/protocol.md``).
    controller : str, Path or controller object
        "p", "lead", "lead-accel", "open-loop", a compensator TOML file, or any object with
        ``step(u, theta, a) -> (v, theta_d_hat)``, ``reset()`` and a JSON-able ``spec``
        (:func:`station.runsetup.choose_controller`).
    amplitude : float, optional
        Step height, encoder counts (open loop: DAC counts); default 100. Not with a file
        reference.
    duration : float, optional
        Run length, s: round(duration/dt) ticks. Default: the reference's
        (:func:`station.runsetup.default_duration`; 2 s for a step).
    step_time, step_tick : optional
        When the step (pulse) starts: a time, s, rounded to the tick grid once, or the tick
        itself (one of them; default tick 10, 0.02 s). Not with a swept sine or a file.
    reference : str
        "step" (default), "pulse", "swept-sine" or ``FILE[:COLUMN]``
        (:func:`station.runsetup.make_reference`).
    kp : float, optional
        P gain of kind "p" (default 2); refused for another controller.
    limit : float, optional
        The clamp asked for, ±DAC counts (default 200; a compensator file's own wins, with a
        note).
    soft_limit : float
        Encoder soft limit, counts: passing it stops the run safely; the reference must
        stay below it.
    timeout : float
        Longest wait for one sample, s (when ``limits`` is not given).
    limits : station.link.LinkLimits, optional
        The link's fail-safe bounds; default ``LinkLimits(timeout)``. Its timeout wins.
    baudrate : int, optional
        Serial baud rate (default: the protocol's).
    dt : float
        Sample time, s (0.002: the rig's 500 Hz).
    model : Model, str or Path, optional
        The simulated rig's model (``sim://`` only): a :class:`station.plant.model.Model`
        (served as a file in a temporary folder that lives as long as the plan), a built-in
        name or a model file (``sim://?model=``).
    n_elements, seed : int, optional
        The simulated rig's element count and sensor noise seed.
    out : path, optional
        The run log; default :func:`default_log_path` in ``out_dir``.
    out_dir : path
        Folder of the default log name.
    force : bool
        An existing log (and its figure) may be replaced; an input never.
    figure : bool
        Draw ``<log stem>.png`` beside the log (:func:`figure_path`; never beside a device
        such as /dev/null).
    lean : bool
        The loop's real-time settings.
    outputs, inputs : sequence of Output, Input
        The caller's other outputs and inputs (``station step``'s ``--json``, ``--rrd``,
        ``station.toml``), checked with the run's own.
    rrd : bool
        A rerun recording is kept in memory during the run (counted in the memory check).
    notify : callable, optional
        Gets each note (which value won) as one line; default a :class:`UserWarning`.

    Returns
    -------
    StepPlan

    Raises
    ------
    StationError
        One line naming the option (as the command line spells it): a number out of range,
        an option that does not apply, a step after the run's end, a run longer than the
        protocol counts or than the machine holds, a reference past the soft limit (closed
        loop, shaped or not) or the DAC's range (open loop), a bad controller, reference,
        port or model, an output onto an input, another output or an existing file.

    Examples
    --------
    >>> from station.plan import plan_step
    >>> plan = plan_step(controller="p", amplitude=50, duration=0.5, step_time=0.1, out="/dev/null")
    >>> plan.step_tick, plan.n_ticks, plan.limit, plan.figure_path is None
    (50, 250, 200.0, True)
    >>> plan_step(controller="p", amplitude=3000, out="/dev/null")
    Traceback (most recent call last):
    ...
    station.errors.StationError: --amplitude 3000: the step would pass --soft-limit 2048 encoder counts and stop the run
    """
    started = time.perf_counter()
    _check_numbers({"amplitude": amplitude, "duration": duration, "step_time": step_time, "step_tick": step_tick,
                    "kp": kp, "limit": limit, "soft_limit": soft_limit, "timeout": timeout, "baudrate": baudrate,
                    "dt": dt})
    port = str(port)
    if "://" not in port and not exists(port):
        raise StationError(f"--port {port}: no such device; `station ports` lists this machine's serial ports "
                           f"(the simulated rig is sim://)")
    builtin = reference in REFERENCES
    if amplitude is not None and not builtin:
        raise StationError(f"--amplitude: not with a file reference ({reference}): the file's column is "
                           f"the reference")
    if step_time is not None and step_tick is not None:
        raise StationError("step_time and step_tick: give one of them")
    timing = "--step-time" if step_time is not None else "step_tick" if step_tick is not None else None
    if timing is not None and (not builtin or reference == "swept-sine"):
        raise StationError(f"{timing}: not with the {reference} reference "
                           f"({'its law starts at t = 1 s' if builtin else 'the file gives the reference'})")
    if builtin and amplitude is None:
        amplitude = DEFAULT_AMPLITUDE
    tick = (DEFAULT_STEP_TICK if timing is None else step_tick if step_tick is not None
            else int(round(step_time / dt)))

    chosen = choose_controller(controller, kp, limit, dt)
    # the controller is known and the simulated rig's model not yet served: a compensator
    # file's design model meets the rig's here (and runs when no model is given)
    design = design_model_note(controller, model, port, n_elements)
    notes = tuple(note for note in (chosen.note, design.note) if note is not None)
    model_label = "--model" if isinstance(model, (str, Path)) else "--port's model"
    if model is None and design.model is not None:
        model, model_label = design.model, "--controller's design model"

    # the run's length: known before the reference is built (a file's: once it is read)
    length = f"--duration {duration:g} s" if duration is not None else f"the {reference} reference"
    planned = default_duration(reference) if duration is None else duration
    n_ticks = None if planned is None else int(round(planned / dt))
    if n_ticks is not None:
        _check_length(protocol, n_ticks, dt, length)
        if builtin and reference != "swept-sine" and tick >= n_ticks:
            when = f"--step-time {step_time:g} s" if timing == "--step-time" else f"step tick {tick}"
            raise StationError(f"{when}: the step must start before the run ends ({n_ticks * dt:g} s)")

    for option, value in (("--out", out), ("--out-dir", out_dir)):
        if value is not None and not str(value).strip():  # Path("") is the working folder, silently
            raise StationError(f"{option}: an empty path: expected a file name" if option == "--out" else
                               f"{option}: an empty path: expected a folder")
    url, folder = run_url(port, model, n_elements, seed)  # a real port refuses the rig's options
    try:
        if out is None:  # (first: a name the file system cannot hold is refused here)
            check_folder(out_dir, "--out-dir")
        log_path = Path(out) if out is not None else default_log_path(log_tag(chosen.controller), folder=out_dir)
        figure_file = figure_path(log_path) if figure and not is_device(log_path) else None
        sim_model = _url_model(url)
        run_inputs = (Input("--controller", controller if isinstance(controller, (str, Path)) else None),
                      Input("--reference", reference_path(reference)),
                      Input(model_label, sim_model if folder is None else None), *inputs)
        log_option = "--out" if out is not None else "the run log"  # (a name made up in out_dir)
        check_outputs([Output(log_option, log_path), Output(f"the figure beside {log_option}", figure_file),
                       *outputs], run_inputs, force=force)
        if n_ticks is not None:  # before the reference takes its memory
            _check_resources(n_ticks, log_path.parent, length, rrd)
        u, reference_meta = make_reference(reference, amplitude, duration, tick, dt)
        if n_ticks is None:  # a file's length
            _check_length(protocol, u.size, dt, f"--reference {reference}")
            _check_resources(u.size, log_path.parent, f"--reference {reference}", rrd)
        named = str(controller) if isinstance(controller, (str, Path)) else "(the controller object)"
        what = f"--amplitude {amplitude:g}" if builtin else f"--reference {reference}"
        _check_peak(u, chosen.controller, soft_limit, what, reference, named, dt)
    except BaseException:
        if folder is not None:
            folder.cleanup()
        raise
    for note in notes:
        (notify or _warn)(note)
    return StepPlan(url=url, protocol=protocol, baudrate=baudrate, limits=limits or LinkLimits(timeout=timeout),
                    controller=chosen.controller, limit=chosen.limit, soft_limit=soft_limit, reference=reference,
                    u=u, reference_meta=reference_meta, amplitude=amplitude if builtin else None, step_tick=tick,
                    dt=dt, log_path=log_path, figure_path=figure_file, force=force, lean=lean, model=sim_model,
                    notes=notes, planning_s=time.perf_counter() - started, inputs=run_inputs, model_folder=folder)
