"""A whole run of the SFLR in closed (or open) loop, simulated as the rig runs it.

Timing (ARCHITECTURE.md, DESIGN.md "Timing and log rows"): at tick k the sensors latch
theta[k], a[k] from x_k; the command is v[k] = C(u[k], theta[k-d], a[k-d]) with the
alignment d (v[k] = 0 for k < d, before the first sample); then x_{k+1} = Ad x_k + Bd v[k].

:func:`simulate` is the run driver: it takes the plant's modal form
(:mod:`station.plant.modal`) and a Model's effects, and runs the station's own
compensators (exactly `Compensator` and `OpenLoop`) in the compiled sample loop of
:mod:`station.plant.kernel`; any other controller (a subclass too, whose ``step`` may
differ) runs in a Python loop over the same compiled per-sample functions, its commands
through the controller contract's guard (:func:`station.control.contract.guard_command`)
as in :func:`station.loop.run_loop`.

Imports the modal form, the kernel, the Model and the controller contract (all below it).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from station.rig import DT
from station.control.compensator import Compensator, OpenLoop
from station.control.contract import guard_command, wire_limit
from station.plant.kernel import COMMAND_QUANTIZATION, KernelEffects, ModelPlant, Stepper, device_command, effects_of
from station.plant.kernel import coefficients as _coeffs
from station.plant.kernel import run_kernel as _kernel
from station.plant.modal import sampled_form
from station.plant.model import Model
from station.rounding import sensor_count

# ModelPlant and COMMAND_QUANTIZATION live in kernel; re-exported where they were
__all__ = ["COMMAND_QUANTIZATION", "ModelPlant", "SimResult", "simulate"]


def _plant_parts(model, dt, substeps):
    """(linear form, effects, z0, dt) of a Model or a DiscretePlant."""
    if isinstance(model, Model):
        dt = DT if dt is None else float(dt)
        return model.linear_form(dt, substeps), effects_of(model, dt), None, dt
    if dt is not None and float(dt) != float(getattr(model, "dt", DT)):
        raise ValueError(f"dt={dt} differs from the plant's own dt={model.dt}")
    form = sampled_form(model)
    return form, KernelEffects(), form.vinv @ model.x.astype(complex), getattr(model, "dt", DT)


STORE_MODES = {"none": 0, "round": 1, "trunc": 2, "float-round": 3, "float-trunc": 4}
"""A compensator's recursion (:data:`station.control.compensator.RECURSIONS`) as the compiled
loop's store mode: the float, the whole count rounded half away from zero, or truncated; or
the float remembered and its whole count sent, rounded or truncated."""


def _python_loop(stepper, controller, u, d, v_open, quantize, cmd_mode, limit):
    """The kernel's sample loop in Python, for a controller object with step/reset; its
    commands guarded at ±limit as the loop guards them."""
    n = u.size
    theta, acc, v, thd = (np.zeros(n) for _ in range(4))
    controller.reset()
    for k in range(n):
        y0, y1 = stepper.outputs()
        if quantize:
            y0, y1 = sensor_count(y0), sensor_count(y1)
        theta[k], acc[k] = y0, y1
        td = u[k]
        if v_open is not None:
            vk = float(v_open[k])
        elif k < d:
            vk = 0.0
        else:
            out = controller.step(float(u[k]), float(theta[k - d]), float(acc[k - d]))
            vk = guard_command(float(out[0]), limit, k - d)
            if len(out) > 1:
                td = float(out[1])
        v[k], thd[k] = vk, td
        stepper.advance(device_command(vk, cmd_mode))
    controller.reset()
    return theta, acc, v, thd


class SimResult(NamedTuple):
    """A simulated run (:func:`simulate`), one array of shape (N,) per column.

    Named fields, still unpackable as a tuple (``t, u, v, theta, a, theta_d_hat =
    result``) and readable by column name like the dict it replaces
    (``result["theta"]``), as python-control's ``TimeResponseData``.

    Attributes
    ----------
    t : ndarray
        Time, s (k·dt).
    u : ndarray
        Reference, encoder counts (DAC counts open loop).
    v : ndarray
        The controller's command after its clamp, DAC counts.
    theta : ndarray
        Base angle, encoder counts.
    a : ndarray
        Tip acceleration, accelerometer counts.
    theta_d_hat : ndarray
        Reference after accelerometer feedback, encoder counts.
    """

    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    theta: np.ndarray
    a: np.ndarray
    theta_d_hat: np.ndarray

    def __getitem__(self, key):
        if isinstance(key, str):
            try:
                return getattr(self, key)
            except AttributeError:
                raise KeyError(key) from None
        return tuple.__getitem__(self, key)

    def __contains__(self, key) -> bool:
        return key in self._fields

    def keys(self) -> tuple[str, ...]:
        """Column names, as a dict's keys."""
        return self._fields

    def items(self):
        """(name, array) pairs, as a dict's items."""
        return self._asdict().items()

    def to_pandas(self):
        """The run as a ``pandas.DataFrame``, one column per field (pandas imported here)."""
        import pandas as pd  # lazy: start-up time (pandas)

        return pd.DataFrame(self._asdict())


def simulate(model, controller, u, alignment: int = 1, v_open=None, quantize: bool = True,
             command: str = "none", dt: float | None = None, substeps: int | None = None) -> SimResult:
    """Simulate a whole run of the plant with a compensator, as the rig runs it.

    Starts from the plant's current state (a DiscretePlant; at rest after
    ``reset()``) or at rest (a Model), and the controller's filters at rest; a
    DiscretePlant and a Compensator are not changed.

    Parameters
    ----------
    model : station.plant.model.Model or station.plant.DiscretePlant
        A Model is simulated with its effects (DESIGN.md "Model diagnosis contract"):
        the device's command quantization, then the amplifier's offset, saturation,
        dead-zone and extra delay on the command (before the first sample the device
        outputs 0 and the amplifier its offset), then motor_polarity on its output; dry
        friction (Coulomb, breakaway and Stribeck: stick-slip) and backlash inside the
        plant on a grid of ``substeps`` per sample; the sensors' faults before their
        quantization (θ·encoder_scale; accel_gain·a + accel_offset + accel_drift·t, t =
        k·dt from the run's first sample); viscous_friction, beam_damping and param:NAME
        in the linear part. A Model
        without effects gives exactly the DiscretePlant's result.
        The linear part's modal form is cached per (parameters, elements, dt, substeps).
    controller : Compensator, OpenLoop, or a `station.control.Controller`
        A Compensator / OpenLoop (exactly those types) runs compiled from its ``gth``,
        ``ga`` (DiscreteTF or None, coefficients in z⁻¹) and ``limit`` (DAC counts or
        None), a Compensator's reference ``shaper`` applied to u first
        (:meth:`station.control.shaper.ReferenceShaper.apply`, from tick d on: the same
        floats as its ``step``); OpenLoop is v = u clamped at ±limit. Any other object with ``step(u,
        theta, a) -> (v, theta_d_hat)`` and ``reset()`` (a subclass of those two as
        well, so its own ``step`` counts) runs in a Python loop with the same timing
        and quantization (reset before and after the run); each command goes through
        :func:`station.control.contract.guard_command` at
        ``wire_limit(controller)``: the controller's own finite ``limit``, at most the
        DAC's ±255, else ±255; the clamp :func:`station.loop.run_loop` gets for it from
        ``station step`` (where ``--limit``, default 200, stands in for a missing own
        limit). May be None when ``v_open`` is given.
    u : array_like, shape (N,)
        Reference per tick: encoder counts (closed loop) or DAC counts (open loop).
    alignment : int, default 1
        Computational delay d >= 0: v[k] = C(u[k], theta[k-d], a[k-d]). For k < d there
        is no sample to compute from: v[k] = 0 and the controller is not stepped, as on
        the device (v1 tick 0 outputs 0) and in :func:`station.loop.run_loop`.
    v_open : array_like, shape (N,), optional
        When given, the command applied at each tick (e.g. a log's v); the controller
        is not used and theta_d_hat = u.
    quantize : bool, default True
        Round theta and a to whole counts as the rig's sensors do (no noise added; see
        `Sensors` for a noisy accelerometer).
    command : {"none", "round", "trunc"}, default "none"
        How the device turns v into whole DAC counts before it acts on the plant:
        "round" (protocol v1, halves away from zero), "trunc" (the legacy firmware,
        toward zero), "none" (v acts unrounded). The returned v is the controller's.
    dt : float, optional
        Sample time of a Model, s (default 0.002). For a DiscretePlant, its own dt
        (another value is an error).
    substeps : int, optional
        Sub-steps per sample when the Model has friction or backlash (default
        ``station.plant.model.SUBSTEPS``).

    Returns
    -------
    SimResult
        ``t`` (s, k·dt), ``u``, ``v`` (DAC counts, the controller's, after its clamp),
        ``theta`` (encoder counts), ``a`` (accelerometer counts), ``theta_d_hat``
        (encoder counts), each shape (N,).

    Raises
    ------
    ValueError
        Negative alignment, v_open of a different length than u, an unknown
        ``command``, or a dt that is not a DiscretePlant's own.
    TypeError
        A controller that is neither a Compensator / OpenLoop nor has ``step`` and
        ``reset`` (never silently open loop).
    station.control.ControllerFault
        A controller run in Python returned NaN (as the loop's "controller-fault").

    Examples
    --------
    A 50-count step at tick 10 under the thesis's P control (kp = 2, clamp ±200) on the rig's
    model, one sample of computational delay and the commands rounded as protocol v1's device
    does:

    >>> from station.control import make_controller, step_reference
    >>> from station.plant import load_model, simulate
    >>> u = step_reference(50, 500, at_tick=10)                   # 1 s at 2 ms
    >>> run = simulate(load_model("tmm-fit"), make_controller("p"), u, command="round")
    >>> run.theta.shape, float(run.t[-1])
    ((500,), 0.998)
    >>> run.v[9:12].tolist()                                      # v = 2 (u − θ), from tick 10
    [0.0, 100.0, 100.0]
    >>> float(run.theta.max())                                    # 40 % overshoot (thesis FEM: 38.2 %)
    70.0
    """
    if command not in COMMAND_QUANTIZATION:
        raise ValueError(f"command quantization must be one of {', '.join(COMMAND_QUANTIZATION)}, got {command!r}")
    u = np.ascontiguousarray(np.asarray(u, dtype=float).ravel())
    d = int(alignment)
    if d < 0:
        raise ValueError(f"alignment must be >= 0, got {alignment}")
    use_v_open = v_open is not None
    if use_v_open:
        v_open = np.ascontiguousarray(np.asarray(v_open, dtype=float).ravel())
        if v_open.shape != u.shape:
            raise ValueError(f"v_open has {v_open.size} samples, u has {u.size}")
    # the compiled loop only for the station's own types: a subclass may override step
    compiled = type(controller) in (Compensator, OpenLoop) or (use_v_open and controller is None)
    if not compiled and not (callable(getattr(controller, "step", None))
                             and callable(getattr(controller, "reset", None))):
        raise TypeError(f"controller must be a Compensator, an OpenLoop or have step(u, theta, a) and reset(); "
                        f"got {type(controller).__name__}")
    form, fx, z0, dt = _plant_parts(model, dt, substeps)
    cmd_mode = COMMAND_QUANTIZATION[command]
    if not compiled:
        stepper = Stepper(form, fx, z0)
        theta, a, v, thd = _python_loop(stepper, controller, u, d, v_open if use_v_open else None,
                                        bool(quantize), cmd_mode, wire_limit(controller))
    else:
        gth = getattr(controller, "gth", None)
        ga = getattr(controller, "ga", None)
        limit = getattr(controller, "limit", None)
        gnum, gden = _coeffs(gth)
        anum, aden = _coeffs(ga)
        shaper = None if use_v_open else getattr(controller, "shaper", None)
        # a reference shaper is linear in u alone: shaped here, float for float as its step() would
        u_ctrl = u if shaper is None else shaper.apply(u, start=d)
        theta, a, v, thd = _kernel(
            form.lam, form.bm, form.bp, form.cm, form.co, form.gw_v, form.gw_p, form.substeps,
            np.zeros(form.lam.size, complex) if z0 is None else z0, u_ctrl, v_open if use_v_open else np.zeros(1),
            use_v_open, gth is not None, gnum, gden, anum, aden, ga is not None,
            math.inf if limit is None else float(limit), d, bool(quantize), cmd_mode,
            STORE_MODES[getattr(controller, "recursion", "none")], *fx,
        )
    return SimResult(np.arange(u.size) * dt, u, v, theta, a, thd)
