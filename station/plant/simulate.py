"""Fast whole-run simulation of the SFLR in closed (or open) loop, as the rig runs it.

The plant is stepped in its modal (diagonal) form z_{k+1} = Λ z_k + b_m v[k],
y_k = Re(C_m z_k) (an exact similarity transform of the ZOH model, O(n) per sample
instead of O(n²)), and the sample loop, with the compensator's recursions, saturation
and encoder quantization, runs in a numba-compiled kernel. Without numba the same
kernel runs as plain Python (same results, about 1000x slower).

Timing (ARCHITECTURE.md, DESIGN.md "Timing and log rows"): at tick k the sensors latch
theta[k], a[k] from x_k; the command is v[k] = C(u[k], theta[k-d], a[k-d]) with the
alignment d (v[k] = 0 for k < d, before the first sample); then x_{k+1} = Ad x_k + Bd v[k].

Effects of a :class:`station.plant.model.Model` (DESIGN.md "Model diagnosis contract"):
the command goes through the device's quantization, the amplifier's saturation,
dead-zone and extra delay; Coulomb friction (Karnopp stick-slip) and backlash act inside
the plant on a sub-step grid dt/M of the same exact ZOH (friction through the command's
channel, backlash as a torque pair on motor and base); accel_gain scales a before its
quantization. `ModelPlant` steps the same arithmetic tick by tick for the simulated device.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from station import DT

try:  # compiled kernel when numba is installed; plain Python otherwise
    import numba
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None

from station.rounding import half_away, half_away_compiled


def _commit(num, den, xs, ys, x, y):  # pragma: no cover - compiled by numba
    """Push input x and output y into a direct-form I history; return the next
    output's history term sum(num[i] x[k+1-i]) - sum(den[i] y[k+1-i]) (i >= 1),
    summed in the order of station.control.DiscreteTF."""
    for i in range(xs.shape[0] - 1, 0, -1):
        xs[i] = xs[i - 1]
    if xs.shape[0] > 0:
        xs[0] = x
    for i in range(ys.shape[0] - 1, 0, -1):
        ys[i] = ys[i - 1]
    if ys.shape[0] > 0:
        ys[0] = y
    acc = 0.0
    for i in range(xs.shape[0]):
        acc += num[i + 1] * xs[i]
    for i in range(ys.shape[0]):
        acc -= den[i + 1] * ys[i]
    return acc


def _outputs(z, cm, accel_gain):  # pragma: no cover - compiled by numba
    """Noise-free (theta, a) at modal state z: Re(cm @ z), a scaled by accel_gain."""
    y0 = 0.0
    y1 = 0.0
    for i in range(z.shape[0]):
        y0 += (cm[0, i] * z[i]).real
        y1 += (cm[1, i] * z[i]).real
    return y0, y1 * accel_gain


def _amplifier(vk, saturation, deadzone):  # pragma: no cover - compiled by numba
    """The amplifier's saturation then dead-zone (DESIGN.md order), DAC counts."""
    if vk > saturation:
        vk = saturation
    elif vk < -saturation:
        vk = -saturation
    if deadzone > 0.0:
        if vk > deadzone:
            vk = vk - deadzone
        elif vk < -deadzone:
            vk = vk + deadzone
        else:
            vk = 0.0
    return vk


def _advance(z, vk, lam, bm, bp, co, gw_v, gw_p, substeps, v_c, half_gap, k_d, c_d):  # pragma: no cover
    """One sample with the torque command vk (DAC counts) held: z in place.

    substeps == 0: the linear ZOH step z <- lam z + bm vk. Else ``substeps`` steps of the
    sub-step grid, each with the backlash torque pair T and the Coulomb friction f
    (counts, through the command's channel) held over the step: T = k_d·(δ − dz(δ)) +
    c_d·δ'·[|δ| <= half_gap] cancels what the drive spring/damper would transmit inside
    the gap; friction slides at v_c·sign(ω_m) while ω_m keeps its sign over the step, else
    (Karnopp) takes the value that stops the motor at the step's end when that is within
    ±v_c (stick), else ±v_c against the motion (break-away).
    """
    n = z.shape[0]
    if substeps == 0:
        for i in range(n):
            z[i] = lam[i] * z[i] + bm[i] * vk
        return
    for _ in range(substeps):
        dl = 0.0
        ddl = 0.0
        wm = 0.0
        wf = 0.0
        if half_gap > 0.0:
            for i in range(n):
                dl += (co[0, i] * z[i]).real
                ddl += (co[1, i] * z[i]).real
        if v_c > 0.0:
            for i in range(n):
                wm += (co[2, i] * z[i]).real
                wf += (co[3, i] * z[i]).real
        t = 0.0
        if half_gap > 0.0:
            if dl > half_gap:
                t = k_d * half_gap
            elif dl < -half_gap:
                t = -k_d * half_gap
            else:
                t = k_d * dl + c_d * ddl
        f = 0.0
        if v_c > 0.0:
            w_free = wf + gw_v * vk + gw_p * t  # ω_m at the step's end without friction
            sliding = False
            if wm != 0.0:
                sg = 1.0 if wm > 0.0 else -1.0
                if (w_free - gw_v * v_c * sg) * sg > 0.0:
                    f = v_c * sg
                    sliding = True
            if not sliding:
                f = w_free / gw_v
                if f > v_c:
                    f = v_c
                elif f < -v_c:
                    f = -v_c
        ue = vk - f
        for i in range(n):
            z[i] = lam[i] * z[i] + bm[i] * ue + bp[i] * t


def _loop(lam, bm, bp, cm, co, gw_v, gw_p, substeps, z0, u, v_open, use_v_open, closed, gnum, gden, anum, aden,
          use_ga, limit, d, quantize, cmd_mode, saturation, deadzone, delay, accel_gain, v_c, half_gap, k_d,
          c_d):  # pragma: no cover - compiled by numba
    n = u.shape[0]
    theta = np.zeros(n)
    acc = np.zeros(n)
    v = np.zeros(n)
    thd = np.zeros(n)
    z = z0.copy()
    gx = np.zeros(gnum.shape[0] - 1)  # Gth input history (newest first)
    gy = np.zeros(gden.shape[0] - 1)  # Gth output history: the saturated v
    ax = np.zeros(anum.shape[0] - 1)  # Ga input history
    ay = np.zeros(aden.shape[0] - 1)  # Ga output history
    fifo = np.zeros(max(delay, 1))  # the amplifier's extra delay, samples
    head = 0
    g_acc = 0.0
    a_acc = 0.0
    for k in range(n):
        y0, y1 = _outputs(z, cm, accel_gain)
        if quantize:
            y0 = math.floor(y0 + 0.5)
            y1 = math.floor(y1 + 0.5)
        theta[k] = y0
        acc[k] = y1
        j = k - d
        uk = u[k]
        td = uk
        e = 0.0
        if use_v_open:
            vk = v_open[k]
        elif k < d:
            vk = 0.0  # no sample yet: the device outputs 0 (v1 tick 0), the filters stay at rest
        else:
            if closed:
                if use_ga:
                    g = anum[0] * acc[j] + a_acc
                    a_acc = _commit(anum, aden, ax, ay, acc[j], g)
                    td = uk - g
                e = td - theta[j]
                vk = gnum[0] * e + g_acc
            else:
                vk = uk
            if vk > limit:
                vk = limit
            elif vk < -limit:
                vk = -limit
            if closed:
                g_acc = _commit(gnum, gden, gx, gy, e, vk)
        v[k] = vk
        thd[k] = td
        # what the device applies: whole DAC counts (the controller keeps the unrounded v)
        if cmd_mode == 1:
            vk = _half_away(vk)
        elif cmd_mode == 2:
            vk = float(math.trunc(vk))
        vk = _amplifier(vk, saturation, deadzone)
        if delay > 0:
            out = fifo[head]
            fifo[head] = vk
            head = (head + 1) % delay
            vk = out
        _advance(z, vk, lam, bm, bp, co, gw_v, gw_p, substeps, v_c, half_gap, k_d, c_d)
    return theta, acc, v, thd


_half_away = half_away  # the device's command rounding (station.rounding), compiled below

if numba is not None:
    _half_away = half_away_compiled
    _commit = numba.njit(cache=True, nogil=True)(_commit)
    _outputs = numba.njit(cache=True, nogil=True)(_outputs)
    _amplifier = numba.njit(cache=True, nogil=True)(_amplifier)
    _advance = numba.njit(cache=True, nogil=True)(_advance)
    _kernel = numba.njit(cache=True, nogil=True)(_loop)
else:  # pragma: no cover
    _kernel = _loop

def _coeffs(tf) -> tuple[np.ndarray, np.ndarray]:
    if tf is None:
        return np.zeros(1), np.ones(1)
    num = np.asarray(tf.num, dtype=float)
    den = np.asarray(tf.den, dtype=float)
    if den[0] != 1.0:
        num, den = num / den[0], den / den[0]
    return np.ascontiguousarray(num), np.ascontiguousarray(den)


COMMAND_QUANTIZATION = {"none": 0, "round": 1, "trunc": 2}
"""How a device turns the station's v into DAC counts: v1 rounds (halves away from zero),
the rig's legacy firmware truncates toward zero (spec/protocol.md)."""


class _Effects(NamedTuple):
    """A model's amplifier, output and in-plant effects as the kernel takes them."""

    saturation: float = math.inf  # DAC counts
    deadzone: float = 0.0  # DAC counts
    delay: int = 0  # samples
    accel_gain: float = 1.0
    v_c: float = 0.0  # Coulomb friction, DAC counts
    half_gap: float = 0.0  # backlash / 2, rad
    k_d: float = 0.0  # drive spring N·m/rad and damper N·m·s/rad of the linear part (backlash)
    c_d: float = 0.0


def _effects_of(model) -> _Effects:
    fx = model.effect_dict()
    p = model.linear_params()
    return _Effects(saturation=float(fx.get("saturation", math.inf)), deadzone=float(fx.get("deadzone", 0.0)),
                    delay=int(fx.get("delay", 0)), accel_gain=float(fx.get("accel_gain", 1.0)),
                    v_c=float(fx.get("coulomb_friction", 0.0)), half_gap=float(fx.get("backlash", 0.0)) / 2.0 / p.H,
                    k_d=p.drive_k, c_d=p.drive_c)


def _device_command(vk: float, cmd_mode: int) -> float:
    # the kernel's command quantization, for the Python loop (same float operations)
    if cmd_mode == 1:
        return half_away(vk)
    if cmd_mode == 2:
        return float(math.trunc(vk))
    return vk


class _Stepper:
    """A linear form plus effects, stepped one sample at a time with the kernel's own functions."""

    def __init__(self, form, fx: _Effects, z0=None) -> None:
        self._form = form
        self._fx = fx
        self._z0 = np.zeros(form.lam.size, complex) if z0 is None else np.asarray(z0, complex).copy()
        self.reset()
        # compile (or load) the kernel's functions now, not on a real-time device's first tick
        self.outputs()
        _amplifier(0.0, fx.saturation, fx.deadzone)
        _advance(self.z.copy(), 0.0, form.lam, form.bm, form.bp, form.co, form.gw_v, form.gw_p, form.substeps,
                 fx.v_c, fx.half_gap, fx.k_d, fx.c_d)

    def reset(self) -> None:
        """Back to the initial state (at rest for a model), the amplifier's delay line empty."""
        self.z = self._z0.copy()
        self._fifo = [0.0] * self._fx.delay
        self._head = 0

    def outputs(self) -> tuple[float, float]:
        """Noise-free (theta, a): encoder counts, accelerometer counts (accel_gain applied)."""
        y0, y1 = _outputs(self.z, self._form.cm, self._fx.accel_gain)
        return float(y0), float(y1)

    def advance(self, v: float) -> None:
        """One sample with the device's command v (DAC counts, already quantized by the
        device) through the amplifier's saturation, dead-zone and delay into the plant."""
        fx, f = self._fx, self._form
        vk = _amplifier(float(v), fx.saturation, fx.deadzone)
        if fx.delay > 0:
            vk, self._fifo[self._head] = self._fifo[self._head], vk
            self._head = (self._head + 1) % fx.delay
        _advance(self.z, vk, f.lam, f.bm, f.bp, f.co, f.gw_v, f.gw_p, f.substeps, fx.v_c, fx.half_gap, fx.k_d, fx.c_d)


class ModelPlant(_Stepper):
    """A :class:`station.plant.model.Model` stepped tick by tick, effects included.

    The interface of `DiscretePlant` that the simulated device uses (``reset``,
    ``outputs``, ``advance``); ``advance`` takes the command the device applies (after
    its own quantization and clamp) and passes it through the amplifier's saturation,
    dead-zone and delay; friction and backlash act inside the plant on the sub-step
    grid; ``outputs`` applies accel_gain. Sample for sample equal to :func:`simulate`
    with the same model (the same compiled functions do the arithmetic).

    Parameters
    ----------
    model : Model
    dt : float, default 0.002
        Sample time, s.
    substeps : int, optional
        Sub-steps per sample with friction or backlash (default ``model.SUBSTEPS``).

    Attributes
    ----------
    model, dt, n_elements
        As given.
    params : Params
        The model's nominal parameter set.
    """

    def __init__(self, model, dt: float = DT, substeps: int | None = None) -> None:
        self.model = model
        self.dt = float(dt)
        self.n_elements = model.n_elements
        self.params = model.params
        super().__init__(model.linear_form(self.dt, substeps), _effects_of(model))


def _plant_parts(plant, dt, substeps):
    """(linear form, effects, z0, dt) of a Model or a DiscretePlant."""
    from station.plant.model import LinearForm, Model

    if isinstance(plant, Model):
        dt = DT if dt is None else float(dt)
        return plant.linear_form(dt, substeps), _effects_of(plant), None, dt
    if dt is not None and float(dt) != float(getattr(plant, "dt", DT)):
        raise ValueError(f"dt={dt} differs from the plant's own dt={plant.dt}")
    lam, bm, cm, vinv = plant.modal_form()
    n = lam.size
    form = LinearForm(lam, bm, np.zeros(n, complex), np.ascontiguousarray(cm), np.zeros((4, n), complex), vinv,
                      0.0, 0.0, 0)
    return form, _Effects(), vinv @ plant.x.astype(complex), getattr(plant, "dt", DT)


def _python_loop(stepper, controller, u, d, v_open, quantize, cmd_mode):
    """The kernel's sample loop in Python, for a controller object with step/reset."""
    n = u.size
    theta, acc, v, thd = (np.zeros(n) for _ in range(4))
    controller.reset()
    for k in range(n):
        y0, y1 = stepper.outputs()
        if quantize:
            y0, y1 = math.floor(y0 + 0.5), math.floor(y1 + 0.5)
        theta[k], acc[k] = y0, y1
        td = u[k]
        if v_open is not None:
            vk = float(v_open[k])
        elif k < d:
            vk = 0.0
        else:
            out = controller.step(float(u[k]), float(theta[k - d]), float(acc[k - d]))
            vk = float(out[0])
            if len(out) > 1:
                td = float(out[1])
        v[k], thd[k] = vk, td
        stepper.advance(_device_command(vk, cmd_mode))
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
        import pandas as pd

        return pd.DataFrame(self._asdict())


def simulate(plant, controller, u, alignment: int = 1, v_open=None, quantize: bool = True,
             command: str = "none", dt: float | None = None, substeps: int | None = None) -> dict:
    """Simulate a whole run of the plant with a compensator, as the rig runs it.

    Starts from the plant's current state (a DiscretePlant; at rest after
    ``plant.reset()``) or at rest (a Model), and the controller's filters at rest; a
    DiscretePlant and a Compensator are not changed.

    Parameters
    ----------
    plant : station.plant.model.Model or station.plant.DiscretePlant
        A Model is simulated with its effects (DESIGN.md "Model diagnosis contract"):
        the device's command quantization, then the amplifier's saturation, dead-zone
        and extra delay on the command; Coulomb friction (stick-slip) and backlash
        inside the plant on a grid of ``substeps`` per sample; accel_gain on the
        accelerometer before its quantization; beam_damping and param:NAME in the
        linear part. A Model without effects gives exactly the DiscretePlant's result.
        The linear part's modal form is cached per (parameters, elements, dt, substeps).
    controller : Compensator, OpenLoop, or an object with ``step`` and ``reset``
        Compensator / OpenLoop run compiled from their ``gth``, ``ga`` (DiscreteTF or
        None, coefficients in z⁻¹) and ``limit`` (DAC counts or None); OpenLoop is
        v = u clamped at ±limit. Any other object with ``step(u, theta, a) -> (v,
        theta_d_hat)`` and ``reset()`` runs in a Python loop with the same timing and
        quantization (reset before and after the run). May be None when ``v_open`` is
        given.
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
    """
    from station.control import Compensator, OpenLoop

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
    compiled = isinstance(controller, (Compensator, OpenLoop)) or (use_v_open and controller is None)
    if not compiled and not (callable(getattr(controller, "step", None))
                             and callable(getattr(controller, "reset", None))):
        raise TypeError(f"controller must be a Compensator, an OpenLoop or have step(u, theta, a) and reset(); "
                        f"got {type(controller).__name__}")
    form, fx, z0, dt = _plant_parts(plant, dt, substeps)
    cmd_mode = COMMAND_QUANTIZATION[command]
    if not compiled:
        stepper = _Stepper(form, fx, z0)
        theta, a, v, thd = _python_loop(stepper, controller, u, d, v_open if use_v_open else None,
                                        bool(quantize), cmd_mode)
    else:
        gth = getattr(controller, "gth", None)
        ga = getattr(controller, "ga", None)
        limit = getattr(controller, "limit", None)
        gnum, gden = _coeffs(gth)
        anum, aden = _coeffs(ga)
        theta, a, v, thd = _kernel(
            form.lam, form.bm, form.bp, form.cm, form.co, form.gw_v, form.gw_p, form.substeps,
            np.zeros(form.lam.size, complex) if z0 is None else z0, u, v_open if use_v_open else np.zeros(1),
            use_v_open, gth is not None, gnum, gden, anum, aden, ga is not None,
            math.inf if limit is None else float(limit), d, bool(quantize), cmd_mode,
            fx.saturation, fx.deadzone, fx.delay, fx.accel_gain, fx.v_c, fx.half_gap, fx.k_d, fx.c_d,
        )
    return SimResult(np.arange(u.size) * dt, u, v, theta, a, thd)
